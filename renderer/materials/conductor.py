"""pbrt's ``conductor``: a metal with complex index eta + i k (or an artist ``reflectance``),
smooth (a mirror) or rough (GGX). Two-sided."""
from __future__ import annotations

import warp as wp

from renderer.materials.bsdf import BSDF, BSDFSample, failed_sample, reflect_z, same_hemisphere
from renderer.optics.fresnel import fresnel_conductor
from renderer.materials.microfacet import (ggx_D, ggx_G, ggx_sample_visible, ggx_visible_pdf, is_smooth,
                                           roughness_to_alpha)

NAME = "conductor"

# pbrt-v4's default conductor is copper; these are copper's eta and k averaged over the
# sRGB primaries' wavelength bands (the values pbrt-v3 and Mitsuba use for "Cu").
COPPER_ETA = (0.200438, 0.924033, 1.102212)
COPPER_K = (3.912949, 2.452848, 2.142188)


def slots(s) -> list[int]:
    refl = s.params.params.get("reflectance")
    rough = s.params.float_or_texture("roughness", 0.0, min=0.0) if "roughness" in s.params else 0.0
    return [
        s.rgb("eta", COPPER_ETA, lo=0.0),
        s.rgb("k", COPPER_K, lo=0.0),
        s.float("uroughness", rough, lo=0.0),
        s.float("vroughness", rough, lo=0.0),
        s.const(1.0 if s.params.bool("remaproughness", True) else 0.0),
        s.rgb("reflectance", 0.0, lo=0.0, hi=0.9999) if refl is not None else s.const(0.0),
        s.const(1.0 if refl is not None else 0.0),
    ]


@wp.func
def _alpha(b: BSDF) -> wp.vec2:
    return roughness_to_alpha(wp.vec2(b.p[2][0], b.p[3][0]), b.p[4][0])


@wp.func
def _fresnel(b: BSDF, cos_i: float) -> wp.vec3:
    eta = b.p[0]
    k = b.p[1]
    if b.p[6][0] > 0.5:
        # pbrt-v4: an artist reflectance r maps to eta = 1, k = 2 sqrt(r) / sqrt(1 - r)
        r = b.p[5]
        eta = wp.vec3(1.0)
        k = wp.vec3(2.0 * wp.sqrt(r[0]) / wp.sqrt(1.0 - r[0]), 2.0 * wp.sqrt(r[1]) / wp.sqrt(1.0 - r[1]),
                    2.0 * wp.sqrt(r[2]) / wp.sqrt(1.0 - r[2]))
    return fresnel_conductor(cos_i, eta, k)


@wp.func
def _up(w: wp.vec3, sgn: float) -> wp.vec3:
    return wp.vec3(w[0], w[1], w[2] * sgn)


@wp.func
def eval(b: BSDF, wo: wp.vec3, wi: wp.vec3) -> wp.vec3:
    alpha = _alpha(b)
    if is_smooth(alpha) or not same_hemisphere(wo, wi):
        return wp.vec3(0.0)
    sgn = wp.where(wo[2] < 0.0, -1.0, 1.0)
    o = _up(wo, sgn)
    i = _up(wi, sgn)
    wm = wp.normalize(o + i)
    return _fresnel(b, wp.dot(o, wm)) * (ggx_D(wm, alpha) * ggx_G(o, i, alpha) / (4.0 * o[2] * i[2]))


@wp.func
def pdf(b: BSDF, wo: wp.vec3, wi: wp.vec3) -> float:
    alpha = _alpha(b)
    if is_smooth(alpha) or not same_hemisphere(wo, wi):
        return 0.0
    sgn = wp.where(wo[2] < 0.0, -1.0, 1.0)
    o = _up(wo, sgn)
    wm = wp.normalize(o + _up(wi, sgn))
    return ggx_visible_pdf(o, wm, alpha) / (4.0 * wp.abs(wp.dot(o, wm)))


@wp.func
def sample(b: BSDF, wo: wp.vec3, u: wp.vec3) -> BSDFSample:
    alpha = _alpha(b)
    s = BSDFSample()
    if is_smooth(alpha):
        s.wi = reflect_z(wo)
        s.weight = _fresnel(b, wo[2])
        s.pdf = 1.0
        s.specular = True
        return s
    sgn = wp.where(wo[2] < 0.0, -1.0, 1.0)
    o = _up(wo, sgn)
    wm = ggx_sample_visible(o, alpha, wp.vec2(u[0], u[1]))
    i = wm * (2.0 * wp.dot(o, wm)) - o
    if i[2] <= 0.0:
        return failed_sample()
    s.wi = _up(i, sgn)
    s.pdf = pdf(b, wo, s.wi)
    if s.pdf <= 0.0:
        return failed_sample()
    s.weight = eval(b, wo, s.wi) * (wp.abs(i[2]) / s.pdf)
    s.specular = False
    return s
