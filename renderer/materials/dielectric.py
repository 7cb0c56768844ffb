"""pbrt's ``dielectric``: glass-like interface with Fresnel-weighted reflection and refraction,
smooth (delta lobes) or rough (GGX, Walter et al. 2007). ``eta`` is the inside over the outside
index; the surface normal points outside. Radiance is scaled by 1/eta'^2 on refraction.

An ``eta`` read from a spectrum that is not constant (``"spectrum eta" "glass-F11"``) is
dispersive: the material's eta(λ) is uploaded as a table (:mod:`renderer.optics.dispersion`),
and in scenes with one the integrator gives each path a wavelength at its first dispersive
interface and passes eta(λ) in through :func:`dispersed`. Elsewhere (the AOV kernel) eta is the
spectrum's luminance-weighted mean."""
from __future__ import annotations

from typing import Any

import numpy as np
import warp as wp

from renderer.errors import Location
from renderer.materials.bsdf import (BSDF, GLOSSY, REFLECTION, SPECULAR, TRANSMISSION, BSDFEval, BSDFSample,
                                     delta_sample, failed_sample, reflect_z, refract, sampled)
from renderer.materials.energy import (dielectric_lost, dielectric_multiple, dielectric_transmit_share, extra_direction,
                                       mixed_pdf)
from renderer.materials.microfacet import (ROUGHNESS_PARAMS, ggx_D, ggx_G, ggx_sample_visible, ggx_visible_pdf,
                                           half_vector, is_smooth, resolve_roughness, roughness_to_alpha)
from renderer.optics.dispersion import eta_at, eta_rows, is_dispersive
from renderer.optics.fresnel import fresnel_dielectric
from renderer.parameters import Parameter, Parameters

NAME = "dielectric"
PARAMS = Parameters(
    Parameter("eta", "float", 1.5, 1.0e-3, texture=True, doc="index of refraction, inside over outside"),
    *ROUGHNESS_PARAMS,
    Parameter("multiscatter", "bool", False, doc="count the bounces between microfacets (energy compensation, "
              "docs/materials.md); off: pbrt-v4's single scattering"),
)
SLOT = PARAMS.slots
FLAG = PARAMS.flags


def resolve(values: dict[str, Any], loc: Location | None) -> tuple[dict[str, Any], int]:
    return resolve_roughness(values), 0


def disperses(values: dict[str, Any]) -> bool:
    """Whether this dielectric's eta varies with the wavelength."""
    return is_dispersive(PARAMS.value(values, "eta"))


def table_rows(values: dict[str, Any], loc: Location | None, thin_film: str) -> tuple[np.ndarray, str]:
    """A dispersive dielectric's eta(λ) rows; none otherwise."""
    if not disperses(values):
        return np.zeros((0, 4), np.float32), ""
    return eta_rows(PARAMS.value(values, "eta")), ""


@wp.func
def dispersed(b: BSDF, lambda_nm: float) -> BSDF:
    """b with the eta of its dispersive table (b.table_first > 0) at wavelength lambda_nm."""
    out = b
    eta = eta_at(b.layers, b.table_first, lambda_nm)
    out.p[SLOT.eta, 0] = eta
    out.p[SLOT.eta, 1] = eta
    out.p[SLOT.eta, 2] = eta
    return out


@wp.func
def _alpha(b: BSDF) -> wp.vec2:
    return roughness_to_alpha(wp.vec2(b.p[SLOT.uroughness][0], b.p[SLOT.vroughness][0]),
                              (b.flags & FLAG.remaproughness) != 0)


@wp.func
def _choice(F: float, sides: int) -> wp.vec2:
    """The probabilities of choosing reflection and transmission (pbrt's pr, pt normalised) when
    ``sides`` (REFLECTION | TRANSMISSION, or one of them) may be sampled."""
    if sides == REFLECTION:
        return wp.vec2(wp.where(F > 0.0, 1.0, 0.0), 0.0)
    if sides == TRANSMISSION:
        return wp.vec2(0.0, wp.where(F < 1.0, 1.0, 0.0))
    return wp.vec2(F, 1.0 - F)


@wp.func
def _reflects(F: float, sides: int, u: float) -> bool:
    if sides == REFLECTION | TRANSMISSION:
        return u < F
    return sides == REFLECTION


@wp.func
def dielectric_eval(eta: float, alpha: wp.vec2, wo: wp.vec3, wi: wp.vec3, sides: int, radiance: bool) -> BSDFEval:
    """The rough dielectric lobes at (wo, wi); the density is that of ``dielectric_sample`` with the
    same ``sides``. ``radiance`` false is pbrt's importance transport: no 1/eta'^2 on refraction."""
    ev = BSDFEval()
    if eta == 1.0 or is_smooth(alpha):
        return ev
    h = half_vector(wo, wi, eta)
    if h[3] == 0.0:
        return ev
    wm = wp.vec3(h[0], h[1], h[2])
    etap = h[3]
    F = fresnel_dielectric(wp.dot(wo, wm), eta)
    P = _choice(F, sides)
    D = ggx_D(wm, alpha)
    G = ggx_G(wo, wi, alpha)
    vis = ggx_visible_pdf(wo, wm, alpha)
    if wo[2] * wi[2] > 0.0:
        ev.f = wp.vec3(D * G * F / wp.abs(4.0 * wi[2] * wo[2]))
        ev.pdf = vis / (4.0 * wp.abs(wp.dot(wo, wm))) * P[0]
        return ev
    denom = wp.dot(wi, wm) + wp.dot(wo, wm) / etap
    denom2 = denom * denom
    ft = D * (1.0 - F) * G * wp.abs(wp.dot(wi, wm) * wp.dot(wo, wm) / (denom2 * wi[2] * wo[2]))
    if radiance:
        ft = ft / (etap * etap)
    ev.f = wp.vec3(ft)
    ev.pdf = vis * wp.abs(wp.dot(wi, wm)) / denom2 * P[1]
    return ev


@wp.func
def smooth_sample(eta: float, wo: wp.vec3, u: float, sides: int, radiance: bool) -> BSDFSample:
    """The smooth interface's delta reflection or refraction (only from ``sides``), chosen by Fresnel."""
    R = fresnel_dielectric(wo[2], eta)
    P = _choice(R, sides)
    if _reflects(R, sides, u):
        if P[0] == 0.0:
            return failed_sample()
        return delta_sample(reflect_z(wo), wp.vec3(R / P[0]), P[0], REFLECTION | SPECULAR)
    t = refract(wo, wp.vec3(0.0, 0.0, 1.0), eta)
    if t[3] == 0.0 or P[1] == 0.0:
        return failed_sample()
    w = (1.0 - R) / P[1]
    if radiance:
        w = w / (t[3] * t[3])
    s = delta_sample(wp.vec3(t[0], t[1], t[2]), wp.vec3(w), P[1], TRANSMISSION | SPECULAR)
    s.eta = t[3]
    return s


@wp.func
def dielectric_sample(eta: float, alpha: wp.vec2, wo: wp.vec3, u: wp.vec3, sides: int, radiance: bool) -> BSDFSample:
    """A reflected or refracted direction (only from ``sides``), smooth or rough; see dielectric_eval."""
    if eta == 1.0 or is_smooth(alpha):
        return smooth_sample(eta, wo, u[2], sides, radiance)
    wm = ggx_sample_visible(wo, alpha, wp.vec2(u[0], u[1]))
    R = fresnel_dielectric(wp.dot(wo, wm), eta)
    wi = wp.vec3(0.0)
    eta_t = float(0.0)
    if _reflects(R, sides, u[2]):
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
        eta_t = t[3]
    s = sampled(wo, wi, dielectric_eval(eta, alpha, wo, wi, sides, radiance), GLOSSY)
    s.eta = eta_t
    return s


@wp.func
def dielectric_ms_eval(eta: float, alpha: wp.vec2, wo: wp.vec3, wi: wp.vec3, radiance: bool,
                       rows: wp.array(dtype=wp.vec4)) -> BSDFEval:
    """Both lobes plus the energy-compensation lobe (:mod:`.energy`); the density is that of
    ``dielectric_ms_sample``: the extra lobe with probability 1 − E(μo), split into reflection and
    transmission by its own shares, each cosine distributed."""
    ev = dielectric_eval(eta, alpha, wo, wi, REFLECTION | TRANSMISSION, radiance)
    if eta == 1.0 or is_smooth(alpha) or wo[2] == 0.0 or wi[2] == 0.0:
        return ev
    e = wp.where(wo[2] > 0.0, eta, 1.0 / eta)
    transmit = wo[2] * wi[2] < 0.0
    p_ms = dielectric_lost(rows, alpha, e, wp.abs(wo[2]))
    x = dielectric_transmit_share(rows, alpha, e)
    f = dielectric_multiple(rows, alpha, e, wp.abs(wo[2]), wp.abs(wi[2]), transmit)
    if transmit and radiance:
        f = f / (e * e)
    ev.f = ev.f + wp.vec3(f)
    ev.pdf = mixed_pdf(ev.pdf, p_ms, x, transmit, wi)
    return ev


@wp.func
def dielectric_ms_sample(eta: float, alpha: wp.vec2, wo: wp.vec3, u: wp.vec3, radiance: bool,
                         rows: wp.array(dtype=wp.vec4)) -> BSDFSample:
    """``dielectric_sample``, or with probability 1 − E(μo) a cosine-distributed reflection or
    transmission (u[2] is split between the two choices); weighted by the whole of ``dielectric_ms_eval``."""
    if eta == 1.0 or is_smooth(alpha) or wo[2] == 0.0:
        return dielectric_sample(eta, alpha, wo, u, REFLECTION | TRANSMISSION, radiance)
    e = wp.where(wo[2] > 0.0, eta, 1.0 / eta)
    p_ms = dielectric_lost(rows, alpha, e, wp.abs(wo[2]))
    d = extra_direction(wo, u, p_ms, dielectric_transmit_share(rows, alpha, e), e)
    wi = wp.vec3(d[0], d[1], d[2])
    eta_t = d[3]
    if d[3] < 0.0:
        s = dielectric_sample(eta, alpha, wo, wp.vec3(u[0], u[1], (u[2] - p_ms) / (1.0 - p_ms)),
                              REFLECTION | TRANSMISSION, radiance)
        if s.pdf <= 0.0:
            return s
        wi = s.wi
        eta_t = s.eta
    out = sampled(wo, wi, dielectric_ms_eval(eta, alpha, wo, wi, radiance, rows), GLOSSY)
    out.eta = eta_t
    return out


@wp.func
def eval_pdf(b: BSDF, wo: wp.vec3, wi: wp.vec3) -> BSDFEval:
    if (b.flags & FLAG.multiscatter) != 0:
        return dielectric_ms_eval(b.p[SLOT.eta][0], _alpha(b), wo, wi, True, b.layers)
    return dielectric_eval(b.p[SLOT.eta][0], _alpha(b), wo, wi, REFLECTION | TRANSMISSION, True)


@wp.func
def sample(b: BSDF, wo: wp.vec3, u: wp.vec3) -> BSDFSample:
    if (b.flags & FLAG.multiscatter) != 0:
        return dielectric_ms_sample(b.p[SLOT.eta][0], _alpha(b), wo, u, True, b.layers)
    return dielectric_sample(b.p[SLOT.eta][0], _alpha(b), wo, u, REFLECTION | TRANSMISSION, True)


# Kernels compile only the lobes their scene's dielectrics can reach (renderer.materials.hooks):
# the functions above handle every case and are what the tests and other materials call.


@wp.func
def single_eval_pdf(b: BSDF, wo: wp.vec3, wi: wp.vec3) -> BSDFEval:
    """``eval_pdf`` where no dielectric counts the bounces between microfacets."""
    return dielectric_eval(b.p[SLOT.eta][0], _alpha(b), wo, wi, REFLECTION | TRANSMISSION, True)


@wp.func
def single_sample(b: BSDF, wo: wp.vec3, u: wp.vec3) -> BSDFSample:
    """``sample`` where no dielectric counts the bounces between microfacets."""
    return dielectric_sample(b.p[SLOT.eta][0], _alpha(b), wo, u, REFLECTION | TRANSMISSION, True)


@wp.func
def smooth_eval_pdf(b: BSDF, wo: wp.vec3, wi: wp.vec3) -> BSDFEval:
    """``eval_pdf`` where every dielectric is smooth: delta lobes only, no value anywhere."""
    return BSDFEval()


@wp.func
def smooth_only_sample(b: BSDF, wo: wp.vec3, u: wp.vec3) -> BSDFSample:
    """``sample`` where every dielectric is smooth."""
    return smooth_sample(b.p[SLOT.eta][0], wo, u[2], REFLECTION | TRANSMISSION, True)


#: The lobes of a kernel where every dielectric is smooth, and where none counts the bounces between
#: microfacets (picked by :func:`renderer.materials.hooks`).
SMOOTH_LOBES = (smooth_eval_pdf, smooth_only_sample)
SINGLE_LOBES = (single_eval_pdf, single_sample)
