"""The seed's ``thinfilm`` (an extension; pbrt has no such material): a smooth interface coated
with one thin dielectric film, or a multilayer stack, whose interference colours the specular
reflection.

Layers, from the side the normal points to: outer medium ``eta_outer`` | film ``eta_film``,
``thickness`` nm | substrate ``eta_inner`` + i ``k_inner``. A stack (``layer_eta`` and friends,
:mod:`renderer.materials.stack`) replaces the film by its layers, read from the scene's layer
table. Reflectance R and transmittance T come from :mod:`renderer.optics` (Airy summation for one
film, Rouard's recursion for a stack; s and p averaged), converted to RGB either at
the seed's three wavelengths (``rgb3``) or by integrating N jittered wavelengths against the CIE
observer (``spectral:N``, the render option). Lobes:

* R: a delta mirror lobe.
* T (``transmission`` true): a delta refraction into a clear substrate, radiance scaled by 1/eta'²
  as in ``dielectric``. Hits from the back swap the outer and inner media; total internal
  reflection comes out of the optics (T = 0, R = 1).
* Opaque substrate (``transmission`` false, the default): two-sided. What the film does not
  reflect enters the substrate; a Lambertian substrate of albedo ``reflectance`` (default 0:
  everything is absorbed, like a metal or black glass) sends it back out. Its lobe is
  f = reflectance (1 − R(wo)) (1 − R(wi)) / π: light must cross the film on the way in and on
  the way out, which keeps it reciprocal and energy conserving (R + (1 − R)·reflectance ≤ 1);
  light the film reflects back down into the substrate is dropped (a slight darkening).
* ``roughness`` (pbrt's ``uroughness``/``vroughness``/``remaproughness``, as ``dielectric``): the
  delta lobes become GGX microfacet lobes sampled by visible normals, each facet carrying the
  coating, so R and T are the coating's spectral Fresnel at the half-vector (reflection and
  refraction alike); the opaque substrate's lobe keeps the coating at the macroscopic normal.
"""
from __future__ import annotations

from typing import Any

import numpy as np
import warp as wp

from renderer.errors import Location, SceneError
from renderer.materials.bsdf import (BSDF, DIFFUSE, GLOSSY, REFLECTION, SPECULAR, TRANSMISSION, BSDFEval,
                                     BSDFSample, delta_sample, failed_sample, reflect_z, refract, same_hemisphere,
                                     sampled, signed_z)
from renderer.materials.microfacet import (ROUGHNESS_PARAMS, ggx_D, ggx_G, ggx_sample_visible, ggx_visible_pdf,
                                           half_vector, is_smooth, resolve_roughness, roughness_to_alpha)
from renderer.materials.stack import STACK_PARAMS, resolve_stack, stack_rows
from renderer.optics.multilayer import multilayer_rgb3, multilayer_rgb_sampled
from renderer.optics.thin_film import thin_film_rgb3, thin_film_rgb_sampled
from renderer.parameters import Parameter, Parameters
from renderer.sampling.warps import cosine_hemisphere
from renderer.vecmath import INV_PI, max3

NAME = "thinfilm"
PARAMS = Parameters(
    Parameter("eta_outer", "float", 1.0, 1.0e-3, texture=True, doc="index of the medium the normal points to"),
    Parameter("eta_film", "float", 1.55, 1.0e-3, texture=True, doc="index of the film"),
    Parameter("eta_inner", "float", 1.66, 1.0e-3, texture=True, doc="real index of the substrate"),
    Parameter("k_inner", "float", 0.0, 0.0, doc="imaginary index of the substrate (a metal)"),
    Parameter("thickness", "float", 500.0, 0.0, texture=True, doc="film thickness (nm); a stack's is its total"),
    Parameter("thicknessmap", "float", 0.0, texture=True, doc="added to the thickness, times thicknessscale (nm)"),
    Parameter("thicknessscale", "float", 1.0, doc="factor of thicknessmap"),
    Parameter("transmission", "bool", False, doc="a clear substrate refracts what the film transmits"),
    Parameter("reflectance", "rgb", 0.0, 0.0, 1.0, texture=True,
              doc="albedo of an opaque substrate's Lambertian base"),
    *STACK_PARAMS,
    *ROUGHNESS_PARAMS,
)
SLOT = PARAMS.slots
FLAG = PARAMS.flags


def resolve(values: dict[str, Any], loc: Location | None) -> tuple[dict[str, Any], int]:
    """Refraction needs a substrate light can cross: no absorption and no diffuse base. A stack
    (see :mod:`renderer.materials.stack`) replaces eta_film and derives its total thickness."""
    if values.get("transmission") and (values.get("k_inner", 0.0) > 0.0 or "reflectance" in values):
        raise SceneError('thinfilm: "transmission" needs a clear substrate (no "k_inner", no "reflectance")', loc)
    return resolve_roughness(resolve_stack(values, loc)), 0


def layer_rows(values: dict[str, Any], loc: Location | None) -> np.ndarray:
    """This material's rows of the scene's layer table (none without a stack)."""
    return stack_rows(values, loc)


@wp.func
def _transmissive(b: BSDF) -> bool:
    return (b.flags & FLAG.transmission) != 0


@wp.func
def film_reflect_transmit(b: BSDF, w: wp.vec3):
    """RGB (R, T) of the coating for light arriving along w (see :func:`coating_RT`)."""
    return coating_RT(b, w[2])


@wp.func
def coating_RT(b: BSDF, cos_w: float):
    """RGB (R, T) of the coating for light arriving at cosine cos_w to its normal (negative: from
    the substrate side), each clipped to [0, 1]: a film colour outside the sRGB gamut has a negative
    channel, which a path's throughput must not carry. Rough lobes pass the cosine to the
    microfacet normal.

    R + T is not clipped. With rgb3 it is 1 to float precision for lossless media; with
    spectral:N it is the jittered estimate of white, 1 ± 1e-3 at N = 32 and exactly 1 on average,
    so clipping the sum would bias every image darker (about 0.3 % in a glass-sphere furnace)."""
    n0 = b.p[SLOT.eta_outer][0]
    n2 = wp.vec2(b.p[SLOT.eta_inner][0], b.p[SLOT.k_inner][0])
    if cos_w < 0.0 and _transmissive(b):
        n0 = b.p[SLOT.eta_inner][0]
        n2 = wp.vec2(b.p[SLOT.eta_outer][0], 0.0)
    n1 = wp.vec2(b.p[SLOT.eta_film][0], 0.0)
    d = wp.max(b.p[SLOT.thickness][0] + b.p[SLOT.thicknessscale][0] * b.p[SLOT.thicknessmap][0], 0.0)
    cos0 = wp.abs(cos_w)
    r = wp.vec3(0.0)
    t = wp.vec3(0.0)
    if b.layer_count > 0:
        # a stack: d is its mapped total thickness, which scales every layer alike
        total = b.p[SLOT.thickness][0]
        scale = wp.where(total > 0.0, d / total, 1.0)
        back = cos_w < 0.0 and _transmissive(b)
        if b.spectral_n > 0:
            r, t = multilayer_rgb_sampled(cos0, n0, n2, b.layers, b.layer_first, b.layer_count, back, scale,
                                          b.spectral_n, b.wavelength_u, b.spectral)
        else:
            r, t = multilayer_rgb3(cos0, n0, n2, b.layers, b.layer_first, b.layer_count, back, scale)
    elif b.spectral_n > 0:
        r, t = thin_film_rgb_sampled(cos0, n0, n1, n2, d, b.spectral_n, b.wavelength_u, b.spectral)
    else:
        r, t = thin_film_rgb3(cos0, n0, n1, n2, d)
    r = wp.min(wp.max(r, wp.vec3(0.0)), wp.vec3(1.0))
    t = wp.min(wp.max(t, wp.vec3(0.0)), wp.vec3(1.0))
    if not _transmissive(b):
        t = wp.vec3(0.0)
    return r, t


@wp.func
def _mean(v: wp.vec3) -> float:
    return (v[0] + v[1] + v[2]) / 3.0


@wp.func
def _base_lobe(b: BSDF, r_o: wp.vec3) -> wp.vec3:
    """reflectance (1 − R(wo)): the substrate's share before the exit through the film."""
    return wp.cw_mul(b.p[SLOT.reflectance], wp.vec3(1.0) - r_o)


@wp.func
def eval_pdf(b: BSDF, wo: wp.vec3, wi: wp.vec3) -> BSDFEval:
    """The substrate lobe (the delta lobes have no value or density here): f from the film at wo
    and at wi, the density its selection probability in ``sample`` times cos/π. The film at wo
    is evaluated once for both."""
    alpha = _alpha(b)
    if not is_smooth(alpha):
        return _rough_eval_pdf(b, wo, wi, alpha)
    e = BSDFEval()
    if _transmissive(b) or max3(b.p[SLOT.reflectance]) <= 0.0 or not same_hemisphere(wo, wi):
        return e
    r_o, t_o = film_reflect_transmit(b, wo)
    r_i, t_i = film_reflect_transmit(b, wi)
    base = _base_lobe(b, r_o)
    e.f = wp.cw_mul(base, wp.vec3(1.0) - r_i) * INV_PI
    p_base = _mean(base)
    total = _mean(r_o) + _mean(t_o) + p_base
    if total > 0.0:
        e.pdf = p_base / total * wp.abs(wi[2]) * INV_PI
    return e


@wp.func
def sample(b: BSDF, wo: wp.vec3, u: wp.vec3) -> BSDFSample:
    """Pick the mirror, the refraction or the substrate in proportion to their mean RGB albedo."""
    alpha = _alpha(b)
    if not is_smooth(alpha):
        return _rough_sample(b, wo, u, alpha)
    r, t = film_reflect_transmit(b, wo)
    base = _base_lobe(b, r)
    p_r = _mean(r)
    p_t = _mean(t)
    total = p_r + p_t + _mean(base)
    if total <= 0.0:
        return failed_sample()
    p_r = p_r / total
    p_t = p_t / total
    if u[2] < p_r:
        return delta_sample(reflect_z(wo), r / p_r, p_r, REFLECTION | SPECULAR)
    if u[2] < p_r + p_t:
        refr = refract(wo, wp.vec3(0.0, 0.0, 1.0), b.p[SLOT.eta_inner][0] / b.p[SLOT.eta_outer][0])
        if refr[3] == 0.0:
            return failed_sample()
        s = delta_sample(wp.vec3(refr[0], refr[1], refr[2]), t / (p_t * refr[3] * refr[3]), p_t,
                         TRANSMISSION | SPECULAR)
        s.eta = refr[3]
        return s
    wi = cosine_hemisphere(wp.vec2(u[0], u[1]))
    if wo[2] < 0.0:
        wi = wp.vec3(wi[0], wi[1], -wi[2])
    p_base = _mean(base) / total
    s = BSDFSample()
    s.pdf = p_base * wp.abs(wi[2]) * INV_PI
    if s.pdf <= 0.0:
        return failed_sample()
    r_i, t_i = film_reflect_transmit(b, wi)
    s.wi = wi
    s.weight = wp.cw_mul(base, wp.vec3(1.0) - r_i) / p_base
    s.flags = REFLECTION | DIFFUSE
    return s


# ---------------------------------------------------------------------------------------------
# Rough coatings: GGX microfacets (as ``dielectric``) whose facets are coated, so the coating's
# R and T are taken at the microfacet normal: a glossy surface is iridescent too.


@wp.func
def _alpha(b: BSDF) -> wp.vec2:
    return roughness_to_alpha(wp.vec2(b.p[SLOT.uroughness][0], b.p[SLOT.vroughness][0]),
                              (b.flags & FLAG.remaproughness) != 0)


@wp.func
def _eta(b: BSDF) -> float:
    return b.p[SLOT.eta_inner][0] / b.p[SLOT.eta_outer][0]


@wp.func
def _glossy_reflection(wo: wp.vec3, wi: wp.vec3, wm: wp.vec3, r: wp.vec3, alpha: wp.vec2) -> BSDFEval:
    """D G R / (4 |cos θo cos θi|) and the visible-normal density of wi (no lobe choice)."""
    e = BSDFEval()
    e.f = r * (ggx_D(wm, alpha) * ggx_G(wo, wi, alpha) / wp.abs(4.0 * wi[2] * wo[2]))
    e.pdf = ggx_visible_pdf(wo, wm, alpha) / (4.0 * wp.abs(wp.dot(wo, wm)))
    return e


@wp.func
def _rough_clear_eval_pdf(b: BSDF, wo: wp.vec3, wi: wp.vec3, alpha: wp.vec2) -> BSDFEval:
    """A rough coated clear substrate: Walter et al.'s BSDF with the coating's RGB R and T in
    place of F and 1 − F; reflection or refraction picked by their mean at the facet."""
    e = BSDFEval()
    h = half_vector(wo, wi, _eta(b))
    if h[3] == 0.0:
        return e
    wm = wp.vec3(h[0], h[1], h[2])
    etap = h[3]
    r, t = coating_RT(b, wp.dot(wo, wm))
    total = _mean(r) + _mean(t)
    if total <= 0.0:
        return e
    if wo[2] * wi[2] > 0.0:
        e = _glossy_reflection(wo, wi, wm, r, alpha)
        e.pdf = e.pdf * _mean(r) / total
        return e
    denom = wp.dot(wi, wm) + wp.dot(wo, wm) / etap
    denom2 = denom * denom
    g = ggx_D(wm, alpha) * ggx_G(wo, wi, alpha) * wp.abs(wp.dot(wi, wm) * wp.dot(wo, wm) / (denom2 * wi[2] * wo[2]))
    e.f = t * (g / (etap * etap))
    e.pdf = ggx_visible_pdf(wo, wm, alpha) * wp.abs(wp.dot(wi, wm)) / denom2 * _mean(t) / total
    return e


@wp.func
def _specular_share(b: BSDF, r_o: wp.vec3, base: wp.vec3) -> float:
    """Probability of the glossy lobe over an opaque substrate: the coating's mean R at the
    macroscopic normal against the substrate's share (it depends on wo only)."""
    total = _mean(r_o) + _mean(base)
    return wp.where(total > 0.0, _mean(r_o) / total, 0.0)


@wp.func
def _rough_opaque_eval_pdf(b: BSDF, wo: wp.vec3, wi: wp.vec3, alpha: wp.vec2) -> BSDFEval:
    """A rough coated opaque substrate (two-sided): the glossy coating lobe plus the smooth case's
    substrate lobe, which keeps the film's R and T at the macroscopic normal (an approximation:
    the coating's glossy albedo and 1 − R there need not sum to exactly 1)."""
    e = BSDFEval()
    if not same_hemisphere(wo, wi):
        return e
    sgn = wp.where(wo[2] < 0.0, -1.0, 1.0)
    o = signed_z(wo, sgn)
    i = signed_z(wi, sgn)
    r_o, t_o = coating_RT(b, o[2])
    base = _base_lobe(b, r_o)
    p_spec = _specular_share(b, r_o, base)
    wm = wp.normalize(o + i)
    r_m, t_m = coating_RT(b, wp.dot(o, wm))
    e = _glossy_reflection(o, i, wm, r_m, alpha)
    e.pdf = e.pdf * p_spec
    if max3(b.p[SLOT.reflectance]) > 0.0:
        r_i, t_i = coating_RT(b, i[2])
        e.f = e.f + wp.cw_mul(base, wp.vec3(1.0) - r_i) * INV_PI
        e.pdf = e.pdf + (1.0 - p_spec) * i[2] * INV_PI
    return e


@wp.func
def _rough_eval_pdf(b: BSDF, wo: wp.vec3, wi: wp.vec3, alpha: wp.vec2) -> BSDFEval:
    if _transmissive(b):
        return _rough_clear_eval_pdf(b, wo, wi, alpha)
    return _rough_opaque_eval_pdf(b, wo, wi, alpha)


@wp.func
def _rough_sample(b: BSDF, wo: wp.vec3, u: wp.vec3, alpha: wp.vec2) -> BSDFSample:
    """A visible microfacet normal, then reflection or refraction by the coating's mean R and T
    there (clear substrate), or the glossy lobe or the substrate by their shares (opaque)."""
    if _transmissive(b):
        wm = ggx_sample_visible(wo, alpha, wp.vec2(u[0], u[1]))
        r, t = coating_RT(b, wp.dot(wo, wm))
        total = _mean(r) + _mean(t)
        if total <= 0.0:
            return failed_sample()
        if u[2] * total < _mean(r):
            wi = wm * (2.0 * wp.dot(wo, wm)) - wo
            if wi[2] * wo[2] <= 0.0:
                return failed_sample()
            return sampled(wo, wi, _rough_clear_eval_pdf(b, wo, wi, alpha), GLOSSY)
        refr = refract(wo, wm, _eta(b))
        wt = wp.vec3(refr[0], refr[1], refr[2])
        if refr[3] == 0.0 or wt[2] * wo[2] >= 0.0:
            return failed_sample()
        s = sampled(wo, wt, _rough_clear_eval_pdf(b, wo, wt, alpha), GLOSSY)
        s.eta = refr[3]
        return s
    sgn = wp.where(wo[2] < 0.0, -1.0, 1.0)
    o = signed_z(wo, sgn)
    r_o, t_o = coating_RT(b, o[2])
    base = _base_lobe(b, r_o)
    if _mean(r_o) + _mean(base) <= 0.0:
        return failed_sample()
    lobe = DIFFUSE
    i = cosine_hemisphere(wp.vec2(u[0], u[1]))
    if u[2] < _specular_share(b, r_o, base):
        wm = ggx_sample_visible(o, alpha, wp.vec2(u[0], u[1]))
        i = wm * (2.0 * wp.dot(o, wm)) - o
        lobe = GLOSSY
        if i[2] <= 0.0:
            return failed_sample()
    wi = signed_z(i, sgn)
    return sampled(wo, wi, _rough_opaque_eval_pdf(b, wo, wi, alpha), lobe)
