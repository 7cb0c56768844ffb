"""The anisotropic Trowbridge–Reitz (GGX) microfacet distribution with visible-normal sampling
(Heitz 2018), shared by the rough conductor and rough dielectric, with their shared roughness
parameters."""
from __future__ import annotations

from typing import Any

import warp as wp

from renderer.parameters import Parameter
from renderer.vecmath import PI


def roughness_params(prefix: str = "") -> tuple[Parameter, ...]:
    """pbrt-v4's three roughness parameters, optionally prefixed (``interface.``, ``conductor.``)."""
    return (
        Parameter(f"{prefix}roughness", "float", 0.0, 0.0, texture=True,
                  doc=f"shorthand for {prefix}uroughness = {prefix}vroughness"),
        Parameter(f"{prefix}uroughness", "float", None, 0.0, texture=True,
                  doc=f"roughness along u (default: {prefix}roughness)"),
        Parameter(f"{prefix}vroughness", "float", None, 0.0, texture=True,
                  doc=f"roughness along v (default: {prefix}roughness)"),
    )


REMAP_ROUGHNESS = Parameter("remaproughness", "bool", True,
                            doc="alpha = sqrt(roughness) when true (else roughness is alpha)")
#: pbrt-v4's roughness parameters of ``conductor`` and ``dielectric``.
ROUGHNESS_PARAMS = (*roughness_params(), REMAP_ROUGHNESS)


def resolve_roughness(values: dict[str, Any], prefix: str = "") -> dict[str, Any]:
    """pbrt's ``roughness`` shorthand: the value of uroughness and vroughness where those are not given."""
    r = values.get(f"{prefix}roughness", 0.0)
    return {f"{prefix}uroughness": r, f"{prefix}vroughness": r} | values


@wp.func
def ggx_D(wm: wp.vec3, alpha: wp.vec2) -> float:
    cos2 = wm[2] * wm[2]
    if cos2 <= 0.0:
        return 0.0
    x = wm[0] / alpha[0]
    y = wm[1] / alpha[1]
    e = x * x + y * y + cos2
    return 1.0 / (PI * alpha[0] * alpha[1] * e * e)


@wp.func
def ggx_lambda(w: wp.vec3, alpha: wp.vec2) -> float:
    cos2 = w[2] * w[2]
    if cos2 <= 0.0:
        return 1.0e30
    t2 = (alpha[0] * alpha[0] * w[0] * w[0] + alpha[1] * alpha[1] * w[1] * w[1]) / cos2
    return 0.5 * (wp.sqrt(1.0 + t2) - 1.0)


@wp.func
def ggx_G1(w: wp.vec3, alpha: wp.vec2) -> float:
    return 1.0 / (1.0 + ggx_lambda(w, alpha))


@wp.func
def ggx_G(wo: wp.vec3, wi: wp.vec3, alpha: wp.vec2) -> float:
    """Height-correlated masking-shadowing."""
    return 1.0 / (1.0 + ggx_lambda(wo, alpha) + ggx_lambda(wi, alpha))


@wp.func
def ggx_visible_pdf(w: wp.vec3, wm: wp.vec3, alpha: wp.vec2) -> float:
    """Density of visible normals wm seen from w (either side): G1(w) |w·wm| D(wm) / |cos θ_w|."""
    cw = wp.abs(w[2])
    if cw == 0.0:
        return 0.0
    return ggx_G1(w, alpha) * wp.abs(wp.dot(w, wm)) * ggx_D(wm, alpha) / cw


@wp.func
def ggx_sample_visible(w: wp.vec3, alpha: wp.vec2, u: wp.vec2) -> wp.vec3:
    """A microfacet normal (on the +z side) distributed by visible area as seen from w."""
    if w[2] < 0.0:
        w = -w
    wh = wp.normalize(wp.vec3(alpha[0] * w[0], alpha[1] * w[1], w[2]))
    t1 = wp.vec3(1.0, 0.0, 0.0)
    if wh[2] < 0.99999:
        t1 = wp.normalize(wp.cross(wp.vec3(0.0, 0.0, 1.0), wh))
    t2 = wp.cross(wh, t1)
    r = wp.sqrt(u[0])
    phi = 2.0 * PI * u[1]
    p0 = r * wp.cos(phi)
    p1 = r * wp.sin(phi)
    h = wp.sqrt(wp.max(0.0, 1.0 - p0 * p0))
    s = 0.5 * (1.0 + wh[2])
    p1 = (1.0 - s) * h + s * p1
    p2 = wp.sqrt(wp.max(0.0, 1.0 - p0 * p0 - p1 * p1))
    nh = t1 * p0 + t2 * p1 + wh * p2
    return wp.normalize(wp.vec3(alpha[0] * nh[0], alpha[1] * nh[1], wp.max(1.0e-6, nh[2])))


@wp.func
def half_vector(wo: wp.vec3, wi: wp.vec3, eta: float) -> wp.vec4:
    """Generalised half vector of a reflection or refraction (xyz, on the +z side) and eta' (w), for
    eta = inside over outside index; w = 0 when undefined (a side mismatch or a degenerate pair)."""
    co = wo[2]
    ci = wi[2]
    etap = 1.0
    if co * ci <= 0.0:
        etap = wp.where(co > 0.0, eta, 1.0 / eta)
    wm = wi * etap + wo
    if ci == 0.0 or co == 0.0 or wp.length_sq(wm) == 0.0:
        return wp.vec4(0.0)
    wm = wp.normalize(wm)
    if wm[2] < 0.0:
        wm = -wm
    if wp.dot(wm, wi) * ci < 0.0 or wp.dot(wm, wo) * co < 0.0:
        return wp.vec4(0.0)
    return wp.vec4(wm[0], wm[1], wm[2], etap)


@wp.func
def is_smooth(alpha: wp.vec2) -> bool:
    """Below this roughness the lobe is treated as a perfect mirror (as pbrt does)."""
    return wp.max(alpha[0], alpha[1]) < 1.0e-3


@wp.func
def roughness_to_alpha(r: wp.vec2, remap: bool) -> wp.vec2:
    """pbrt-v4's remapping: alpha = sqrt(roughness) when ``remaproughness`` is true."""
    if remap:
        return wp.vec2(wp.sqrt(wp.max(r[0], 0.0)), wp.sqrt(wp.max(r[1], 0.0)))
    return r


@wp.func
def gtr1_D(cos_h: float, alpha: float) -> float:
    """Burley's GTR1 ("generalised Trowbridge–Reitz", γ = 1) distribution of the clearcoat: a
    longer tail than GGX, normalised so that ∫ D cos θh dω = 1 (needs alpha < 1)."""
    if cos_h <= 0.0:
        return 0.0
    a2 = alpha * alpha
    return (a2 - 1.0) / (PI * wp.log(a2) * (1.0 + (a2 - 1.0) * cos_h * cos_h))


@wp.func
def gtr1_sample(alpha: float, u: wp.vec2) -> wp.vec3:
    """A normal distributed as D(wm) cos θm (inverting GTR1's closed-form CDF); pdf = gtr1_D · cos θm."""
    a2 = alpha * alpha
    cos2 = (1.0 - wp.pow(a2, 1.0 - u[0])) / (1.0 - a2)
    cos_t = wp.sqrt(wp.clamp(cos2, 0.0, 1.0))
    sin_t = wp.sqrt(wp.max(0.0, 1.0 - cos_t * cos_t))
    phi = 2.0 * PI * u[1]
    return wp.vec3(sin_t * wp.cos(phi), sin_t * wp.sin(phi), cos_t)
