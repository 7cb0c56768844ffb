"""pbrt's ``conductor``: a metal with complex index eta + i k (or an artist ``reflectance``),
smooth (a mirror) or rough (GGX). Two-sided."""
from __future__ import annotations

from typing import Any

import warp as wp

from renderer.errors import Location
from renderer.materials.bsdf import (BSDF, FIRST_DERIVED_FLAG, GLOSSY, REFLECTION, SPECULAR, BSDFEval, BSDFSample,
                                     delta_sample, failed_sample, reflect_z, same_hemisphere, sampled, signed_z)
from renderer.materials.microfacet import (ROUGHNESS_PARAMS, ggx_D, ggx_G, ggx_sample_visible, ggx_visible_pdf,
                                           is_smooth, resolve_roughness, roughness_to_alpha)
from renderer.optics.fresnel import fresnel_conductor
from renderer.parameters import Parameter, Parameters

NAME = "conductor"

# pbrt-v4's default conductor is copper; these are copper's eta and k averaged over the
# sRGB primaries' wavelength bands (the values pbrt-v3 and Mitsuba use for "Cu").
COPPER_ETA = (0.200438, 0.924033, 1.102212)
COPPER_K = (3.912949, 2.452848, 2.142188)

PARAMS = Parameters(
    Parameter("eta", "rgb", COPPER_ETA, 0.0, texture=True, doc="real part of the complex index (default: copper)"),
    Parameter("k", "rgb", COPPER_K, 0.0, texture=True, doc="imaginary part of the complex index (default: copper)"),
    *ROUGHNESS_PARAMS,
    Parameter("reflectance", "rgb", None, 0.0, 0.9999, texture=True,
              doc="artist reflectance at normal incidence; replaces eta and k when given"),
)
SLOT = PARAMS.slots
FLAG = PARAMS.flags
#: Derived flag: ``reflectance`` was given, so it replaces eta and k.
ARTIST = wp.constant(FIRST_DERIVED_FLAG)


def resolve(values: dict[str, Any], loc: Location | None) -> tuple[dict[str, Any], int]:
    return resolve_roughness(values), ARTIST if "reflectance" in values else 0


@wp.func
def _alpha(b: BSDF) -> wp.vec2:
    return roughness_to_alpha(wp.vec2(b.p[SLOT.uroughness][0], b.p[SLOT.vroughness][0]),
                              (b.flags & FLAG.remaproughness) != 0)


@wp.func
def _fresnel(b: BSDF, cos_i: float) -> wp.vec3:
    eta = b.p[SLOT.eta]
    k = b.p[SLOT.k]
    if (b.flags & ARTIST) != 0:
        # pbrt-v4: an artist reflectance r maps to eta = 1, k = 2 sqrt(r) / sqrt(1 - r)
        r = b.p[SLOT.reflectance]
        eta = wp.vec3(1.0)
        k = wp.vec3(2.0 * wp.sqrt(r[0]) / wp.sqrt(1.0 - r[0]), 2.0 * wp.sqrt(r[1]) / wp.sqrt(1.0 - r[1]),
                    2.0 * wp.sqrt(r[2]) / wp.sqrt(1.0 - r[2]))
    return fresnel_conductor(cos_i, eta, k)


@wp.func
def eval_pdf(b: BSDF, wo: wp.vec3, wi: wp.vec3) -> BSDFEval:
    e = BSDFEval()
    alpha = _alpha(b)
    if is_smooth(alpha) or not same_hemisphere(wo, wi):
        return e
    sgn = wp.where(wo[2] < 0.0, -1.0, 1.0)
    o = signed_z(wo, sgn)
    i = signed_z(wi, sgn)
    wm = wp.normalize(o + i)
    e.f = _fresnel(b, wp.dot(o, wm)) * (ggx_D(wm, alpha) * ggx_G(o, i, alpha) / (4.0 * o[2] * i[2]))
    e.pdf = ggx_visible_pdf(o, wm, alpha) / (4.0 * wp.abs(wp.dot(o, wm)))
    return e


@wp.func
def sample(b: BSDF, wo: wp.vec3, u: wp.vec3) -> BSDFSample:
    alpha = _alpha(b)
    if is_smooth(alpha):
        return delta_sample(reflect_z(wo), _fresnel(b, wo[2]), 1.0, REFLECTION | SPECULAR)
    sgn = wp.where(wo[2] < 0.0, -1.0, 1.0)
    o = signed_z(wo, sgn)
    wm = ggx_sample_visible(o, alpha, wp.vec2(u[0], u[1]))
    i = wm * (2.0 * wp.dot(o, wm)) - o
    if i[2] <= 0.0:
        return failed_sample()
    wi = signed_z(i, sgn)
    return sampled(wo, wi, eval_pdf(b, wo, wi), GLOSSY)
