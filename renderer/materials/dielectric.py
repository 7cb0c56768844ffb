"""pbrt's ``dielectric``: glass-like interface with Fresnel-weighted reflection and refraction,
smooth (delta lobes) or rough (GGX, Walter et al. 2007). ``eta`` is the inside over the outside
index; the surface normal points outside. Radiance is scaled by 1/eta'^2 on refraction."""
from __future__ import annotations

import warp as wp

from renderer.materials.bsdf import BSDF, BSDFSample, failed_sample, reflect_z, refract
from renderer.optics.fresnel import fresnel_dielectric
from renderer.materials.microfacet import (ggx_D, ggx_G, ggx_sample_visible, ggx_visible_pdf, is_smooth,
                                           roughness_to_alpha)

NAME = "dielectric"


def slots(s) -> list[int]:
    rough = s.params.float_or_texture("roughness", 0.0, min=0.0) if "roughness" in s.params else 0.0
    return [
        s.float("eta", 1.5, lo=1.0e-3),
        s.float("uroughness", rough, lo=0.0),
        s.float("vroughness", rough, lo=0.0),
        s.const(1.0 if s.params.bool("remaproughness", True) else 0.0),
    ]


@wp.func
def _alpha(b: BSDF) -> wp.vec2:
    return roughness_to_alpha(wp.vec2(b.p[1][0], b.p[2][0]), b.p[3][0])


@wp.func
def _half_vector(wo: wp.vec3, wi: wp.vec3, eta: float) -> wp.vec4:
    """Generalised half vector (xyz, on the +z side) and eta' (w); w = 0 when undefined."""
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
def eval(b: BSDF, wo: wp.vec3, wi: wp.vec3) -> wp.vec3:
    eta = b.p[0][0]
    alpha = _alpha(b)
    if eta == 1.0 or is_smooth(alpha):
        return wp.vec3(0.0)
    h = _half_vector(wo, wi, eta)
    if h[3] == 0.0:
        return wp.vec3(0.0)
    wm = wp.vec3(h[0], h[1], h[2])
    etap = h[3]
    F = fresnel_dielectric(wp.dot(wo, wm), eta)
    D = ggx_D(wm, alpha)
    G = ggx_G(wo, wi, alpha)
    if wo[2] * wi[2] > 0.0:
        return wp.vec3(D * G * F / wp.abs(4.0 * wi[2] * wo[2]))
    denom = wp.dot(wi, wm) + wp.dot(wo, wm) / etap
    denom = denom * denom * wi[2] * wo[2]
    ft = D * (1.0 - F) * G * wp.abs(wp.dot(wi, wm) * wp.dot(wo, wm) / denom)
    return wp.vec3(ft / (etap * etap))


@wp.func
def pdf(b: BSDF, wo: wp.vec3, wi: wp.vec3) -> float:
    eta = b.p[0][0]
    alpha = _alpha(b)
    if eta == 1.0 or is_smooth(alpha):
        return 0.0
    h = _half_vector(wo, wi, eta)
    if h[3] == 0.0:
        return 0.0
    wm = wp.vec3(h[0], h[1], h[2])
    R = fresnel_dielectric(wp.dot(wo, wm), eta)
    vis = ggx_visible_pdf(wo, wm, alpha)
    if wo[2] * wi[2] > 0.0:
        return vis / (4.0 * wp.abs(wp.dot(wo, wm))) * R
    denom = wp.dot(wi, wm) + wp.dot(wo, wm) / h[3]
    return vis * wp.abs(wp.dot(wi, wm)) / (denom * denom) * (1.0 - R)


@wp.func
def sample(b: BSDF, wo: wp.vec3, u: wp.vec3) -> BSDFSample:
    eta = b.p[0][0]
    alpha = _alpha(b)
    s = BSDFSample()
    if eta == 1.0 or is_smooth(alpha):
        R = fresnel_dielectric(wo[2], eta)
        if u[2] < R:
            s.wi = reflect_z(wo)
            s.weight = wp.vec3(1.0)
            s.pdf = R
        else:
            t = refract(wo, wp.vec3(0.0, 0.0, 1.0), eta)
            if t[3] == 0.0:
                return failed_sample()
            s.wi = wp.vec3(t[0], t[1], t[2])
            s.weight = wp.vec3(1.0 / (t[3] * t[3]))
            s.pdf = 1.0 - R
            s.eta = t[3]
        s.specular = True
        return s
    wm = ggx_sample_visible(wo, alpha, wp.vec2(u[0], u[1]))
    R = fresnel_dielectric(wp.dot(wo, wm), eta)
    wi = wp.vec3(0.0)
    if u[2] < R:
        wi = wm * (2.0 * wp.dot(wo, wm)) - wo
        if wi[2] * wo[2] <= 0.0:
            return failed_sample()
    else:
        t = refract(wo, wm, eta)
        if t[3] == 0.0:
            return failed_sample()
        wi = wp.vec3(t[0], t[1], t[2])
        if wi[2] * wo[2] >= 0.0:
            return failed_sample()
        s.eta = t[3]
    s.wi = wi
    s.pdf = pdf(b, wo, wi)
    if s.pdf <= 0.0:
        return failed_sample()
    s.weight = eval(b, wo, wi) * (wp.abs(wi[2]) / s.pdf)
    s.specular = False
    return s
