"""pbrt-v3's ``disney`` material, a documented extension: Burley's principled BSDF (SIGGRAPH 2012
and 2015 course notes) with pbrt-v3's parameter names, defaults and alpha mapping.

Lobes, in the local shading frame (see docs/disney.md for the formulas and their sources):

* diffuse group (cosine-sampled): Burley's Fresnel-shaped diffuse (1 − F_o/2)(1 − F_i/2) c/π, or for
  ``thin`` sheets its blend with the Hanrahan–Krueger-style flattened "fake subsurface" lobe by
  ``flatness``; retro-reflection; sheen. All weighted by (1 − metallic)(1 − spectrans).
* specular: anisotropic GGX reflection (visible normals), Fresnel = dielectric (tinted towards the
  base colour by ``speculartint``, as Mitsuba 3) blended with Schlick on the base colour by ``metallic``.
* clearcoat: GTR1 with a fixed GGX masking of alpha 0.25, Schlick F0 = 0.04, weight clearcoat/4.
* specular transmission, weight (1 − metallic) spectrans: solid surfaces are the rough dielectric
  (:mod:`dielectric`, Walter 2007) with the refracted part tinted by sqrt(colour) per crossing;
  ``thin`` sheets let light through without bending (a GGX reflection mirrored through the sheet,
  with Burley 2015's roughness scaled by (0.65 eta − 0.35)), tinted by the colour once.
* diffuse transmission (``thin`` only): Lambertian, the share difftrans/2 of the diffuse weight.

Solid (non-thin) surfaces bound an object: hit from the inside only the dielectric interface exists.
Thin sheets are two-sided. With a non-zero ``scatterdistance`` on a solid surface the diffuse base
is not part of the BSDF: :mod:`renderer.subsurface` carries that light through the object instead,
and marks the exit point (flag EXIT) where the BSDF becomes the exit lobe (1 − F_i/2)/π.
An extension: a film or stack over that body, named as on ``subsurface`` (flag FILM, :mod:`.disney_film`).

Sampling picks one lobe by the lobe weights at wo; ``eval_pdf``'s density is the one-sample MIS
mixture Σ p_lobe pdf_lobe and ``sample`` returns f|cos θi|/pdf with that mixture.
"""
from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
import warp as wp

from renderer.errors import Location, SceneError
from renderer.materials import dielectric
from renderer.materials.bsdf import (BSDF, DIFFUSE, FIRST_DERIVED_FLAG, GLOSSY, REFLECTION, TRANSMISSION, BSDFEval,
                                     BSDFSample, failed_sample, sampled, signed_z)
from renderer.materials.film_body import FILM_PARAMS, has_film, resolve_film
from renderer.materials.microfacet import ggx_D, ggx_G, ggx_G1, ggx_sample_visible, ggx_visible_pdf, gtr1_D, gtr1_sample
from renderer.optics.fresnel import fresnel_dielectric
from renderer.parameters import Parameter, Parameters, TextureRef
from renderer.materials.stack import stack_rows
from renderer.sampling.warps import cosine_hemisphere
from renderer.vecmath import INV_PI, luminance, max3

NAME = "disney"
PARAMS = Parameters(
    Parameter("color", "rgb", 0.5, 0.0, 1.0, texture=True, doc="base colour"),
    Parameter("metallic", "float", 0.0, 0.0, 1.0, texture=True, doc="blend from dielectric to metal"),
    Parameter("eta", "float", 1.5, 1.0e-3, texture=True, doc="index of refraction (specular and transmission)"),
    Parameter("roughness", "float", 0.5, 0.0, 1.0, texture=True, doc="alpha = roughness²"),
    Parameter("speculartint", "float", 0.0, 0.0, 1.0, texture=True, doc="tints the dielectric specular"),
    Parameter("anisotropic", "float", 0.0, 0.0, 1.0, texture=True, doc="aspect of the specular lobe along u"),
    Parameter("sheen", "float", 0.0, 0.0, texture=True, doc="grazing retro-reflective sheen"),
    Parameter("sheentint", "float", 0.5, 0.0, 1.0, texture=True, doc="tints the sheen"),
    Parameter("clearcoat", "float", 0.0, 0.0, 1.0, texture=True, doc="weight of the GTR1 clear coat"),
    Parameter("clearcoatgloss", "float", 1.0, 0.0, 1.0, texture=True, doc="gloss of the clear coat"),
    Parameter("spectrans", "float", 0.0, 0.0, 1.0, texture=True, doc="specular transmission"),
    Parameter("scatterdistance", "rgb", 0.0, 0.0, texture=True,
              doc="mean free path of subsurface scattering (solids; 0: none)"),
    Parameter("thin", "bool", False, doc="a two-sided thin sheet instead of a solid's boundary"),
    Parameter("flatness", "float", 0.0, 0.0, 1.0, texture=True, doc="thin sheets: the flattened diffuse share"),
    Parameter("difftrans", "float", 1.0, 0.0, 2.0, texture=True, doc="thin sheets: diffuse transmission"),
    *(dataclasses.replace(p, default=None) if p.name == "thicknessmap" else p for p in FILM_PARAMS),
    shared={"eta_film": "flatness", "thicknessscale": "difftrans"},
)
SLOT = PARAMS.slots
FLAG = PARAMS.flags
#: Set by the subsurface step where light leaves the object: only the exit lobe.
EXIT = wp.constant(FIRST_DERIVED_FLAG)
FILM = wp.constant(FIRST_DERIVED_FLAG << 1)     # a film or stack coats the subsurface body (.disney_film)
#: Lower bound of the GGX alphas (pbrt-v3): roughness 0 is a very sharp lobe, never a delta.
ALPHA_MIN = wp.constant(1.0e-3)
#: Burley's clearcoat masking uses GGX with this fixed alpha.
CLEARCOAT_MASKING_ALPHA = wp.constant(0.25)

vec5 = wp.types.vector(length=5, dtype=wp.float32)


def has_subsurface(values: dict[str, Any]) -> bool:
    """Whether a material needs the integrator's subsurface step: a solid surface whose
    ``scatterdistance`` is a texture or a non-zero constant."""
    if values.get("thin", False):
        return False
    v = values.get("scatterdistance")
    return isinstance(v, TextureRef) or (v is not None and bool(np.any(np.asarray(v) > 0.0)))


def resolve(values: dict[str, Any], loc: Location | None) -> tuple[dict[str, Any], int]:
    """A film coats a solid's subsurface body (else refused, as are the thin sheets' parameters whose
    slots it takes); it claims those slots with its ``eta_film`` and ``thicknessscale``."""
    owner = f'material "{NAME}"'
    v = resolve_film(values, owner, loc)        # refuses a stack's parameters without its layers
    if not has_film(values):
        return values, 0
    if not has_subsurface(values):
        raise SceneError(f'{owner}: a film ("thickness", "thicknessmap" or "layer_eta") coats a subsurface body: '
                         'it needs a solid ("thin" false) with a non-zero "scatterdistance"', loc)
    if any(n in values for n in PARAMS.shared.values()):
        raise SceneError(f'{owner}: flatness and difftrans (thin sheets) cannot be given with a film', loc)
    return v | {n: PARAMS.value(v, n) for n in PARAMS.shared}, FILM


def layer_rows(values: dict[str, Any], loc: Location | None) -> np.ndarray:
    return stack_rows(values, loc, f'material "{NAME}"')     # a film's stack (no rows without one)


@wp.struct
class Params:
    c: wp.vec3
    tint: wp.vec3          # the base colour's hue at luminance 1
    sheen: wp.vec3         # sheen colour times its weight and the diffuse weight
    metallic: float
    eta: float
    roughness: float
    alpha: wp.vec2
    alpha_t: wp.vec2       # thin sheets' transmission alphas (Burley 2015, fig. 15)
    spec_tint: float
    clearcoat: float
    cc_alpha: float
    dw: float              # diffuse weight (1 - metallic)(1 - spectrans)
    gw: float              # glass weight (1 - metallic) spectrans
    flatness: float
    dt: float              # share of the thin diffuse that is transmitted: difftrans / 2
    thin: bool
    sss: bool              # the diffuse base is carried by subsurface scattering instead
    exit: bool             # this is a subsurface exit point: only the exit lobe
    sgn: float             # -1 where a two-sided case is seen from below (see _two_sided), else 1
    o: wp.vec3             # wo with its z times sgn


@wp.func
def _alphas(r: float, aspect: float) -> wp.vec2:
    r2 = r * r
    return wp.vec2(wp.max(ALPHA_MIN, r2 / aspect), wp.max(ALPHA_MIN, r2 * aspect))


@wp.func
def load_params(b: BSDF) -> Params:
    P = Params()
    c = b.p[SLOT.color]
    c = wp.vec3(wp.clamp(c[0], 0.0, 1.0), wp.clamp(c[1], 0.0, 1.0), wp.clamp(c[2], 0.0, 1.0))
    lum = luminance(c)
    P.c = c
    P.tint = wp.where(lum > 0.0, c / wp.max(lum, 1.0e-8), wp.vec3(1.0))
    m = b.p[SLOT.metallic][0]
    st = b.p[SLOT.spectrans][0]
    P.metallic = m
    P.dw = (1.0 - m) * (1.0 - st)
    P.gw = (1.0 - m) * st
    eta = b.p[SLOT.eta][0]
    if wp.abs(eta - 1.0) < 1.0e-3:
        eta = 1.001  # an index-matched interface has no microfacet transmission to sample
    P.eta = eta
    r = b.p[SLOT.roughness][0]
    P.roughness = r
    aspect = wp.sqrt(1.0 - 0.9 * b.p[SLOT.anisotropic][0])
    P.alpha = _alphas(r, aspect)
    P.alpha_t = _alphas((0.65 * eta - 0.35) * r, aspect)
    P.spec_tint = b.p[SLOT.speculartint][0]
    st_tint = b.p[SLOT.sheentint][0]
    P.sheen = (wp.vec3(1.0 - st_tint) + P.tint * st_tint) * (P.dw * b.p[SLOT.sheen][0])
    P.clearcoat = b.p[SLOT.clearcoat][0]
    P.cc_alpha = 0.1 + (0.001 - 0.1) * b.p[SLOT.clearcoatgloss][0]
    P.flatness = b.p[SLOT.flatness][0]
    P.dt = 0.5 * b.p[SLOT.difftrans][0]
    P.thin = (b.flags & FLAG.thin) != 0
    P.sss = (not P.thin) and max3(b.p[SLOT.scatterdistance]) > 0.0
    P.exit = (b.flags & EXIT) != 0
    return P


@wp.func
def schlick_weight(cos_t: float) -> float:
    m = wp.clamp(1.0 - cos_t, 0.0, 1.0)
    m2 = m * m
    return m2 * m2 * m


@wp.func
def _schlick(r0: wp.vec3, cos_t: float) -> wp.vec3:
    return r0 + (wp.vec3(1.0) - r0) * schlick_weight(cos_t)


@wp.func
def _specular_fresnel(P: Params, cos_t: float) -> wp.vec3:
    """Mitsuba 3's principled blend: the dielectric part tinted by speculartint, the metallic part
    Schlick on the base colour; thin sheets add their glass reflection (solids get it from the
    dielectric lobe)."""
    fd = fresnel_dielectric(cos_t, P.eta)
    r0 = (P.eta - 1.0) / (P.eta + 1.0)
    nonmetal = wp.vec3(fd * (1.0 - P.spec_tint)) + _schlick(P.tint * (r0 * r0), cos_t) * P.spec_tint
    F = nonmetal * P.dw + _schlick(P.c, cos_t) * P.metallic
    if P.thin:
        F = F + wp.vec3(P.gw * fd)
    return F


@wp.func
def _reflection(P: Params, o: wp.vec3, i: wp.vec3) -> wp.vec3:
    """The reflection lobes for o, i both above the surface."""
    h = o + i
    if wp.length_sq(h) == 0.0:
        return wp.vec3(0.0)
    h = wp.normalize(h)
    cos_d = wp.dot(i, h)
    f = wp.vec3(0.0)
    if P.dw > 0.0:
        Fo = schlick_weight(o[2])
        Fi = schlick_weight(i[2])
        Rr = 2.0 * P.roughness * cos_d * cos_d
        base = float(0.0)
        if not P.sss:
            base = (1.0 - 0.5 * Fo) * (1.0 - 0.5 * Fi)
            if P.thin:
                fss90 = 0.5 * Rr
                fss = (1.0 + (fss90 - 1.0) * Fo) * (1.0 + (fss90 - 1.0) * Fi)
                flat = 1.25 * (fss * (1.0 / (o[2] + i[2]) - 0.5) + 0.5)
                base = ((1.0 - P.flatness) * base + P.flatness * flat) * (1.0 - P.dt)
        retro = Rr * (Fo + Fi + Fo * Fi * (Rr - 1.0))
        f = P.c * (P.dw * INV_PI * (base + retro)) + P.sheen * schlick_weight(cos_d)
    inv_cos = 1.0 / (4.0 * o[2] * i[2])
    f = f + _specular_fresnel(P, wp.dot(o, h)) * (ggx_D(h, P.alpha) * ggx_G(o, i, P.alpha) * inv_cos)
    if P.clearcoat > 0.0:
        a = wp.vec2(CLEARCOAT_MASKING_ALPHA, CLEARCOAT_MASKING_ALPHA)
        Fcc = 0.04 + 0.96 * schlick_weight(wp.dot(o, h))
        cc = 0.25 * P.clearcoat * Fcc * gtr1_D(h[2], P.cc_alpha) * ggx_G1(o, a) * ggx_G1(i, a) * inv_cos
        f = f + wp.vec3(cc)
    return f


@wp.func
def _thin_transmission(P: Params, o: wp.vec3, i: wp.vec3) -> wp.vec3:
    """Through a thin sheet (o above, i below): Lambertian diffuse transmission plus the specular
    transmission, a GGX reflection mirrored to the other side (the sheet does not bend rays)."""
    f = P.c * (P.dw * P.dt * INV_PI)
    if P.gw > 0.0:
        j = wp.vec3(i[0], i[1], -i[2])
        h = wp.normalize(o + j)
        F = fresnel_dielectric(wp.dot(o, h), P.eta)
        f = f + P.c * (P.gw * (1.0 - F) * ggx_D(h, P.alpha_t) * ggx_G(o, j, P.alpha_t) / (4.0 * o[2] * j[2]))
    return f


@wp.func
def _exit_lobe(i: wp.vec3) -> wp.vec3:
    """Where subsurface light leaves: Burley's exit factor (1 - F_i/2)/π, so that a vanishing
    scatter distance gives back exactly the diffuse lobe the subsurface step replaced."""
    return wp.vec3((1.0 - 0.5 * schlick_weight(wp.abs(i[2]))) * INV_PI)


@wp.func
def _weights(P: Params, wo: wp.vec3) -> vec5:
    """Unnormalised lobe-selection weights (diffuse group, specular, clearcoat, specular
    transmission, diffuse transmission): rough estimates of each lobe's albedo at wo."""
    if P.exit:
        return vec5(1.0, 0.0, 0.0, 0.0, 0.0)
    if not P.thin and wo[2] < 0.0:
        return vec5(0.0, 0.0, 0.0, P.gw, 0.0)  # inside a solid: only the dielectric interface
    cos_o = wp.abs(wo[2])
    lum = luminance(P.c)
    k = float(1.0)
    if P.thin:
        k = 1.0 - P.dt
    if P.sss:
        k = 0.5 * P.roughness  # only the retro-reflection stays
    fd = fresnel_dielectric(cos_o, P.eta)
    glass = fd + (1.0 - fd) * luminance(wp.vec3(wp.sqrt(P.c[0]), wp.sqrt(P.c[1]), wp.sqrt(P.c[2])))
    dt = float(0.0)
    if P.thin:
        glass = (1.0 - fd) * lum
        dt = P.dw * P.dt * lum
    return vec5(P.dw * lum * k + luminance(P.sheen), luminance(_specular_fresnel(P, cos_o)),
                0.25 * P.clearcoat, P.gw * glass, dt)


@wp.func
def _probabilities(P: Params, wo: wp.vec3) -> vec5:
    w = _weights(P, wo)
    total = w[0] + w[1] + w[2] + w[3] + w[4]
    if total <= 0.0:
        return vec5(0.0)
    return w / total


@wp.func
def _two_sided(P: Params, wo: wp.vec3) -> float:
    """Thin sheets and exit points are symmetric: evaluate them with wo mirrored above."""
    if (P.thin or P.exit) and wo[2] < 0.0:
        return -1.0
    return 1.0


@wp.func
def _value(P: Params, wo: wp.vec3, wi: wp.vec3, o: wp.vec3, i: wp.vec3, glass: BSDFEval) -> wp.vec3:
    """f, with o and i the directions brought above the surface for two-sided cases."""
    if o[2] <= 0.0 and (P.thin or P.exit):
        return wp.vec3(0.0)
    if P.exit:
        return wp.where(i[2] > 0.0, _exit_lobe(i), wp.vec3(0.0))
    if P.thin:
        if i[2] > 0.0:
            return _reflection(P, o, i)
        if i[2] < 0.0:
            return _thin_transmission(P, o, i)
        return wp.vec3(0.0)
    f = wp.vec3(0.0)
    if o[2] > 0.0 and i[2] > 0.0:
        f = _reflection(P, o, i)
    if P.gw > 0.0:
        g = glass.f
        if wo[2] * wi[2] < 0.0:
            g = wp.cw_mul(g, wp.vec3(wp.sqrt(P.c[0]), wp.sqrt(P.c[1]), wp.sqrt(P.c[2])))
        f = f + g * P.gw
    return f


@wp.func
def _ggx_reflection_pdf(weight: float, o: wp.vec3, h: wp.vec3, alpha: wp.vec2) -> float:
    """weight times the density of reflecting o about a visible GGX normal h."""
    return weight * ggx_visible_pdf(o, h, alpha) / (4.0 * wp.abs(wp.dot(o, h)))


@wp.func
def _density(P: Params, p: vec5, o: wp.vec3, i: wp.vec3, glass: BSDFEval) -> float:
    """The lobe mixture's density for lobe probabilities p."""
    result = float(0.0)
    if o[2] > 0.0 and i[2] > 0.0:
        result = p[0] * i[2] * INV_PI
        h = wp.normalize(o + i)
        if p[1] > 0.0:
            result += _ggx_reflection_pdf(p[1], o, h, P.alpha)
        if p[2] > 0.0:
            result += p[2] * gtr1_D(h[2], P.cc_alpha) * h[2] / (4.0 * wp.abs(wp.dot(o, h)))
    if p[3] > 0.0:
        if P.thin:
            if o[2] > 0.0 and i[2] < 0.0:
                j = wp.vec3(i[0], i[1], -i[2])
                result += _ggx_reflection_pdf(p[3], o, wp.normalize(o + j), P.alpha_t)
        else:
            result += p[3] * glass.pdf
    if p[4] > 0.0 and o[2] > 0.0 and i[2] < 0.0:
        result += p[4] * (-i[2]) * INV_PI
    return result


@wp.func
def seen_from(b: BSDF, wo: wp.vec3) -> Params:
    """The parameters, with wo brought above the surface where the case is two-sided."""
    P = load_params(b)
    P.sgn = _two_sided(P, wo)
    P.o = signed_z(wo, P.sgn)
    return P


@wp.func
def eval_pdf(b: BSDF, wo: wp.vec3, wi: wp.vec3) -> BSDFEval:
    P = seen_from(b, wo)
    i = signed_z(wi, P.sgn)
    glass = BSDFEval()
    if P.gw > 0.0 and not P.thin and not P.exit:
        glass = dielectric.dielectric_eval(P.eta, P.alpha, wo, wi, REFLECTION | TRANSMISSION, True)
    ev = BSDFEval()
    ev.f = _value(P, wo, wi, P.o, i, glass)
    ev.pdf = _density(P, _probabilities(P, wo), P.o, i, glass)
    return ev


@wp.func
def _reflect(o: wp.vec3, h: wp.vec3) -> wp.vec3:
    return h * (2.0 * wp.dot(o, h)) - o


@wp.func
def sample(b: BSDF, wo: wp.vec3, u: wp.vec3) -> BSDFSample:
    P = seen_from(b, wo)
    p = _probabilities(P, wo)
    o = P.o
    sgn = P.sgn
    u2 = wp.vec2(u[0], u[1])
    x = u[2]
    i = wp.vec3(0.0)
    lobe = GLOSSY
    if x < p[0]:
        i = cosine_hemisphere(u2)
        lobe = DIFFUSE
    elif x < p[0] + p[1]:
        i = _reflect(o, ggx_sample_visible(o, P.alpha, u2))
    elif x < p[0] + p[1] + p[2]:
        i = _reflect(o, gtr1_sample(P.cc_alpha, u2))
    elif x < p[0] + p[1] + p[2] + p[3]:
        if P.thin:
            j = _reflect(o, ggx_sample_visible(o, P.alpha_t, u2))
            if j[2] <= 0.0:
                return failed_sample()
            i = wp.vec3(j[0], j[1], -j[2])
        else:
            # reuse the lobe-selection number, rescaled, for the dielectric's reflect/refract choice
            v = wp.clamp((x - p[0] - p[1] - p[2]) / p[3], 0.0, 0.999999)
            g = dielectric.dielectric_sample(P.eta, P.alpha, wo, wp.vec3(u[0], u[1], v), REFLECTION | TRANSMISSION,
                                             True)
            if g.pdf <= 0.0:
                return failed_sample()
            i = signed_z(g.wi, sgn)
    else:
        i = cosine_hemisphere(u2)
        i = wp.vec3(i[0], i[1], -i[2])
        lobe = DIFFUSE
    if i[2] == 0.0 or (x < p[0] + p[1] + p[2] and i[2] < 0.0):
        return failed_sample()  # a reflection lobe's sample below the surface: its density excludes it
    wi = signed_z(i, sgn)
    s = sampled(wo, wi, eval_pdf(b, wo, wi), lobe)
    if not P.thin and wo[2] * wi[2] < 0.0:
        s.eta = wp.where(wo[2] > 0.0, P.eta, 1.0 / P.eta)
    return s


@wp.struct
class SubsurfaceLobe:
    """What the subsurface step needs to know about the material at the entry point."""

    albedo: wp.vec3        # the diffusion profile's albedo A: the base colour
    mfp: wp.vec3           # mean free path (scatterdistance); 0 where there is no subsurface
    entry: float           # diffuse weight times Burley's entry factor (1 - F_o/2)
    prob: float            # how often to take the subsurface route instead of the surface lobes


@wp.func
def subsurface_lobe(b: BSDF, cos_o: float) -> SubsurfaceLobe:
    P = load_params(b)
    s = SubsurfaceLobe()
    if not P.sss or P.exit or cos_o <= 0.0:
        return s
    s.albedo = P.c
    s.mfp = b.p[SLOT.scatterdistance]
    s.entry = P.dw * (1.0 - 0.5 * schlick_weight(cos_o))
    w = _weights(P, wp.vec3(0.0, 0.0, cos_o))
    sss = s.entry * luminance(P.c)
    s.prob = wp.clamp(sss / wp.max(sss + w[0] + w[1] + w[2] + w[3] + w[4], 1.0e-8), 0.02, 0.98)
    return s
