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
* ``layered`` true: every interreflection between the coating (kind FILM) and that Lambertian base, by
  pbrt-v4's layered random walk (:mod:`.layered`; no medium between them), of ``maxdepth`` and ``nsamples``.
* ``tint`` (clear substrate): Beer–Lambert in a thin parallel slab, tint being the transmittance
  of one pass at normal incidence; each vertex charges tint^(1/(2|cos θ|)) for each of wo and wi
  that lies inside, so a pass in and out pays tint^(1/cos θ) and the BSDF stays reciprocal.
* ``roughness`` (pbrt's ``uroughness``/``vroughness``/``remaproughness``, as ``dielectric``): the
  delta lobes become GGX microfacet lobes sampled by visible normals, each facet carrying the
  coating, so R and T are the coating's spectral Fresnel at the half-vector (reflection and
  refraction alike); the opaque substrate's lobe keeps the coating at the macroscopic normal.
"""
from __future__ import annotations

from functools import lru_cache
from typing import Any

import numpy as np
import warp as wp

from renderer.errors import Location, SceneError
from renderer.materials.bsdf import (BSDF, DIFFUSE, GLOSSY, REFLECTION, SPECULAR, TRANSMISSION, BSDFEval,
                                     BSDFSample, delta_sample, failed_sample, reflect_z, refract, same_hemisphere,
                                     sampled, signed_z)
from renderer.materials.coating import (BOTH_SIDES, Coating, coating_eval, coating_rgb, coating_rgb_inlined,
                                       coating_sample, glossy_reflection)
from renderer.materials.coating_energy import coating_ms_eval, coating_ms_sample, mean_reflectance
from renderer.materials.energy import mirror_lost, mirror_multiple
from renderer.materials.coating_table import coating_table
from renderer.materials.layer_interfaces import FILM, LAMBERT, Interface
from renderer.materials.layered import SLAB_PARAMS, Slab, make_slab, walk, walk_alone, walk_flags
from renderer.materials.microfacet import (ROUGHNESS_PARAMS, ggx_sample_visible, is_smooth, resolve_roughness,
                                           roughness_to_alpha)
from renderer.materials.stack import STACK_PARAMS, resolve_stack, stack_rows
from renderer.parameters import Parameter, Parameters
from renderer.sampling.warps import cosine_hemisphere
from renderer.vecmath import INV_PI, max3, mean3

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
    Parameter("tint", "rgb", 1.0, 0.0, 1.0, texture=True,
              doc="clear substrate: internal transmittance of one pass through the lens at normal incidence"),
    Parameter("reflectance", "rgb", 0.0, 0.0, 1.0, texture=True,
              doc="albedo of an opaque substrate's Lambertian base"),
    Parameter("layered", "bool", False, doc="opaque substrate: every interreflection between film and base "
              "(pbrt-v4's layered random walk) instead of one pass"),
    *(p for p in SLAB_PARAMS if p.name in ("maxdepth", "nsamples")),
    *STACK_PARAMS,
    *ROUGHNESS_PARAMS,
    Parameter("multiscatter", "bool", True, doc="rough coatings: count the bounces between microfacets (energy "
              "compensation coloured by the coating, docs/thinfilm.md)"),
    Parameter("thinslab", "bool", False, doc="a face of a thin closed slab (a lens): shadow rays cross it with its "
              "T and half a pass of the tint (docs/thinfilm.md, \"Shadows through thin lenses\")"),
)
SLOT = PARAMS.slots
FLAG = PARAMS.flags


def resolve(values: dict[str, Any], loc: Location | None) -> tuple[dict[str, Any], int]:
    """Refraction needs a substrate light can cross: no absorption and no diffuse base; the
    layered walk needs a clear substrate over its base, which it cannot refract out of. A stack
    (see :mod:`renderer.materials.stack`) replaces eta_film and derives its total thickness."""
    if values.get("transmission") and (values.get("k_inner", 0.0) > 0.0 or "reflectance" in values):
        raise SceneError('thinfilm: "transmission" needs a clear substrate (no "k_inner", no "reflectance")', loc)
    if "tint" in values and not values.get("transmission"):
        raise SceneError('thinfilm: "tint" colours a clear substrate, which needs "transmission" true', loc)
    if values.get("layered") and (values.get("transmission") or values.get("k_inner", 0.0) > 0.0):
        raise SceneError('thinfilm: "layered" puts a Lambertian base under a clear substrate: it excludes '
                         '"transmission" and "k_inner"', loc)
    if values.get("thinslab") and (not values.get("transmission") or values.get("layered") or "displacement" in values
                                   or any(values.get(n, 0.0) for n in ("roughness", "uroughness", "vroughness"))):
        raise SceneError('thinfilm: "thinslab" is a smooth clear face: it needs "transmission" true and no '
                         '"layered", roughness or displacement', loc)
    walk = [n for n in ("maxdepth", "nsamples") if n in values]
    if walk and not values.get("layered"):
        raise SceneError(f'thinfilm: {" and ".join(walk)} belong to the layered walk: it needs "layered" true', loc)
    flags = walk_flags(values) if values.get("layered") else 0
    return resolve_roughness(resolve_stack(values, loc)), flags


def layer_rows(values: dict[str, Any], loc: Location | None) -> np.ndarray:
    """This material's rows of the scene's layer table (none without a stack)."""
    return stack_rows(values, loc)


def table_rows(values: dict[str, Any], loc: Location | None, thin_film: str) -> tuple[np.ndarray, str]:
    """The coating's baked RGB (R, T) table in the thin-film mode ``table`` (:mod:`.coating_table`)."""
    return coating_table(values, PARAMS, loc, thin_film, bool(values.get("transmission") or values.get("layered")))


def walks(values: dict[str, Any]) -> bool:
    """Whether this material takes the layered random walk (``"bool layered"``)."""
    return bool(PARAMS.value(values, "layered"))


@wp.func
def _transmissive(b: BSDF) -> bool:
    return (b.flags & FLAG.transmission) != 0


@wp.func
def _layered(b: BSDF) -> bool:
    return (b.flags & FLAG.layered) != 0


@wp.func
def film_coating(b: BSDF) -> Coating:
    """The coating of this material's parameters (see :mod:`renderer.materials.coating`); the
    substrate is crossed with ``transmission`` and under the layered walk."""
    c = Coating()
    c.n_outer = b.p[SLOT.eta_outer][0]
    c.n_film = b.p[SLOT.eta_film][0]
    c.n_inner = wp.vec2(b.p[SLOT.eta_inner][0], b.p[SLOT.k_inner][0])
    c.d = wp.max(b.p[SLOT.thickness][0] + b.p[SLOT.thicknessscale][0] * b.p[SLOT.thicknessmap][0], 0.0)
    c.total = b.p[SLOT.thickness][0]
    c.clear = _transmissive(b) or _layered(b)
    c.balanced = c.clear       # many crossings (a clear substrate, the layered walk): see coating.py
    c.layers = b.layers
    c.layer_first = b.layer_first
    c.layer_count = b.layer_count
    c.spectral_n = b.spectral_n
    c.wavelength_u = b.wavelength_u
    c.spectral = b.spectral
    c.table_first = b.table_first
    return c


@wp.func
def coating_RT(b: BSDF, cos_w: float):
    """RGB (R, T) of the coating for light arriving at cosine cos_w to its normal (negative: from
    the substrate side): :func:`renderer.materials.coating.coating_rgb`."""
    return coating_rgb(film_coating(b), cos_w)


@wp.func
def film_reflect_transmit(b: BSDF, w: wp.vec3):
    """RGB (R, T) of the coating for light arriving along w (see :func:`coating_RT`)."""
    return coating_RT(b, w[2])


@wp.func
def _tinted(b: BSDF, v: wp.vec3, wo: wp.vec3, wi: wp.vec3) -> wp.vec3:
    """v times the tinted substrate's internal transmittance charged at this vertex: tint^x with
    x = Σ 1/(2 |cos θ|) over wo and wi where they lie inside (see docs/thinfilm.md)."""
    tint = b.p[SLOT.tint]
    if tint == wp.vec3(1.0):
        return v
    x = float(0.0)
    if wo[2] < 0.0:
        x += 0.5 / wp.max(-wo[2], 1.0e-6)
    if wi[2] < 0.0:
        x += 0.5 / wp.max(-wi[2], 1.0e-6)
    if x == 0.0:
        return v
    tint = wp.min(wp.max(tint, wp.vec3(0.0)), wp.vec3(1.0))
    return wp.cw_mul(v, wp.vec3(wp.pow(tint[0], x), wp.pow(tint[1], x), wp.pow(tint[2], x)))


@lru_cache(maxsize=None)
def slab_face(inlined: bool) -> wp.Function:
    """``slab_face_transmittance(b, cos_d) -> vec3`` with the coating's optics out of line (as every
    other caller has them), or ``inlined`` for the lens step, whose only call it is."""
    rgb = coating_rgb_inlined if inlined else coating_rgb

    @wp.func
    def slab_face_transmittance(b: BSDF, cos_d: float) -> wp.vec3:
        """What this face of a thin slab passes of light that crosses it without turning (a shadow ray
        at cosine cos_d to the normal; light comes from the side it points to): the coating's T from
        that side (inside: at the angle Snell's law gives) and half a pass of the tint there, as the
        refraction lobe charges it. The 1/η² of entering and η² of leaving cancel over the slab."""
        eta = _eta(b)
        sin2_in = (1.0 - cos_d * cos_d) / (eta * eta)
        if sin2_in >= 1.0:
            return wp.vec3(0.0)
        cos_in = wp.sqrt(1.0 - sin2_in)
        r, t = wp.static(rgb)(film_coating(b), wp.where(cos_d > 0.0, cos_d, -cos_in))
        return _tinted(b, t, wp.vec3(0.0, 0.0, 1.0), wp.vec3(0.0, 0.0, -cos_in))

    return slab_face_transmittance


@wp.func
def _slab(b: BSDF) -> Slab:
    """The walk's slab: the coating over the Lambertian base right under its clear substrate (thickness 0)."""
    top = Interface()
    top.kind = FILM
    top.eta = wp.vec3(_eta(b))
    top.alpha = _alpha(b)
    base = Interface()
    base.kind = LAMBERT
    base.albedo = b.p[SLOT.reflectance]
    return make_slab(top, base, film_coating(b), 0.0, wp.vec3(0.0), 0.0, b.flags, b.wavelength_u)


@wp.func
def _base_lobe(b: BSDF, r_o: wp.vec3) -> wp.vec3:
    """reflectance (1 − R(wo)): the substrate's share before the exit through the film."""
    return wp.cw_mul(b.p[SLOT.reflectance], wp.vec3(1.0) - r_o)


@wp.func
def _smooth_eval_pdf(b: BSDF, wo: wp.vec3, wi: wp.vec3) -> BSDFEval:
    """The substrate lobe (the delta lobes have no value or density here): f from the film at wo
    and at wi, the density its selection probability in ``sample`` times cos/π. The film at wo
    is evaluated once for both."""
    ev = BSDFEval()
    if _transmissive(b) or max3(b.p[SLOT.reflectance]) <= 0.0 or not same_hemisphere(wo, wi):
        return ev
    r_o, t_o = film_reflect_transmit(b, wo)
    r_i, t_i = film_reflect_transmit(b, wi)
    base = _base_lobe(b, r_o)
    ev.f = wp.cw_mul(base, wp.vec3(1.0) - r_i) * INV_PI
    p_base = mean3(base)
    total = mean3(r_o) + mean3(t_o) + p_base
    if total > 0.0:
        ev.pdf = p_base / total * wp.abs(wi[2]) * INV_PI
    return ev


@wp.func
def _smooth_sample(b: BSDF, wo: wp.vec3, u: wp.vec3) -> BSDFSample:
    """Pick the mirror, the refraction or the substrate in proportion to their mean RGB albedo."""
    r, t = film_reflect_transmit(b, wo)
    base = _base_lobe(b, r)
    p_r = mean3(r)
    p_t = mean3(t)
    total = p_r + p_t + mean3(base)
    if total <= 0.0:
        return failed_sample()
    p_r = p_r / total
    p_t = p_t / total
    if u[2] < p_r:
        return delta_sample(reflect_z(wo), _tinted(b, r / p_r, wo, reflect_z(wo)), p_r, REFLECTION | SPECULAR)
    if u[2] < p_r + p_t:
        refr = refract(wo, wp.vec3(0.0, 0.0, 1.0), b.p[SLOT.eta_inner][0] / b.p[SLOT.eta_outer][0])
        if refr[3] == 0.0:
            return failed_sample()
        wt = wp.vec3(refr[0], refr[1], refr[2])
        s = delta_sample(wt, _tinted(b, t / (p_t * refr[3] * refr[3]), wo, wt), p_t, TRANSMISSION | SPECULAR)
        s.eta = refr[3]
        return s
    wi = cosine_hemisphere(wp.vec2(u[0], u[1]))
    if wo[2] < 0.0:
        wi = wp.vec3(wi[0], wi[1], -wi[2])
    p_base = mean3(base) / total
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
def _multiscatters(b: BSDF) -> bool:
    return (b.flags & FLAG.multiscatter) != 0


@wp.func
def _eta(b: BSDF) -> float:
    return b.p[SLOT.eta_inner][0] / b.p[SLOT.eta_outer][0]


@wp.func
def _specular_share(b: BSDF, r_o: wp.vec3, base: wp.vec3) -> float:
    """Probability of the glossy lobe over an opaque substrate: the coating's mean R at the
    macroscopic normal against the substrate's share (it depends on wo only)."""
    total = mean3(r_o) + mean3(base)
    return wp.where(total > 0.0, mean3(r_o) / total, 0.0)


@lru_cache(maxsize=None)
def _rough_lobes(multiscatter: bool) -> tuple[wp.Function, wp.Function]:
    """The rough coating's ``eval_pdf`` and ``sample`` (with ``alpha``), with the compensation lobe
    compiled in only where ``multiscatter`` says some material of the kernel's scene can use it."""

    @wp.func
    def opaque_eval_pdf(b: BSDF, wo: wp.vec3, wi: wp.vec3, alpha: wp.vec2) -> BSDFEval:
        """A rough coated opaque substrate (two-sided): the glossy coating lobe plus the smooth case's
        substrate lobe, which keeps the film's R and T at the macroscopic normal (an approximation:
        the coating's glossy albedo and 1 − R there need not sum to exactly 1)."""
        ev = BSDFEval()
        if not same_hemisphere(wo, wi):
            return ev
        sgn = wp.where(wo[2] < 0.0, -1.0, 1.0)
        o = signed_z(wo, sgn)
        i = signed_z(wi, sgn)
        r_o, t_o = coating_RT(b, o[2])
        base = _base_lobe(b, r_o)
        p_spec = _specular_share(b, r_o, base)
        wm = wp.normalize(o + i)
        r_m, t_m = coating_RT(b, wp.dot(o, wm))
        ev = glossy_reflection(o, i, wm, r_m, alpha)
        if wp.static(multiscatter):
            if _multiscatters(b):
                # Kulla–Conty's lobe with F̄ the coating's mean R: the glossy part then sums to the coating's albedo
                p_ms = mirror_lost(b.layers, alpha, o[2])
                ev.f = ev.f + mirror_multiple(b.layers, alpha, o[2], i[2], mean_reflectance(film_coating(b)))
                ev.pdf = (1.0 - p_ms) * ev.pdf + p_ms * i[2] * INV_PI
        ev.pdf = ev.pdf * p_spec
        if max3(b.p[SLOT.reflectance]) > 0.0:
            r_i, t_i = coating_RT(b, i[2])
            ev.f = ev.f + wp.cw_mul(base, wp.vec3(1.0) - r_i) * INV_PI
            ev.pdf = ev.pdf + (1.0 - p_spec) * i[2] * INV_PI
        return ev

    @wp.func
    def rough_eval_pdf(b: BSDF, wo: wp.vec3, wi: wp.vec3, alpha: wp.vec2) -> BSDFEval:
        if _transmissive(b):
            if wp.static(multiscatter):
                if _multiscatters(b):
                    ms = coating_ms_eval(film_coating(b), _eta(b), alpha, wo, wi, True, b.layers)
                    ms.f = _tinted(b, ms.f, wo, wi)
                    return ms
            ev = coating_eval(film_coating(b), _eta(b), alpha, wo, wi, BOTH_SIDES, True)
            ev.f = _tinted(b, ev.f, wo, wi)
            return ev
        return wp.static(opaque_eval_pdf)(b, wo, wi, alpha)

    @wp.func
    def rough_sample(b: BSDF, wo: wp.vec3, u: wp.vec3, alpha: wp.vec2) -> BSDFSample:
        """A visible microfacet normal, then reflection or refraction by the coating's mean R and T
        there (clear substrate), or the glossy lobe or the substrate by their shares (opaque)."""
        if _transmissive(b):
            if wp.static(multiscatter):
                if _multiscatters(b):
                    ms = coating_ms_sample(film_coating(b), _eta(b), alpha, wo, u, True, b.layers)
                    ms.weight = _tinted(b, ms.weight, wo, ms.wi)
                    return ms
            s = coating_sample(film_coating(b), _eta(b), alpha, wo, u, BOTH_SIDES, True)
            s.weight = _tinted(b, s.weight, wo, s.wi)
            return s
        sgn = wp.where(wo[2] < 0.0, -1.0, 1.0)
        o = signed_z(wo, sgn)
        r_o, t_o = coating_RT(b, o[2])
        base = _base_lobe(b, r_o)
        if mean3(r_o) + mean3(base) <= 0.0:
            return failed_sample()
        lobe = DIFFUSE
        i = cosine_hemisphere(wp.vec2(u[0], u[1]))
        p_spec = _specular_share(b, r_o, base)
        if u[2] < p_spec:
            lobe = GLOSSY
            # the compensation lobe is cosine distributed, like the base: i stays as drawn
            glossy = True
            if wp.static(multiscatter):
                glossy = not _multiscatters(b) or u[2] >= p_spec * mirror_lost(b.layers, alpha, o[2])
            if glossy:
                wm = ggx_sample_visible(o, alpha, wp.vec2(u[0], u[1]))
                i = wm * (2.0 * wp.dot(o, wm)) - o
                if i[2] <= 0.0:
                    return failed_sample()
        wi = signed_z(i, sgn)
        return sampled(wo, wi, wp.static(opaque_eval_pdf)(b, wo, wi, alpha), lobe)

    return rough_eval_pdf, rough_sample


@lru_cache(maxsize=None)
def _lobes(rough: bool, multiscatter: bool, layered: bool) -> tuple[wp.Function, wp.Function]:
    """``eval_pdf`` and ``sample`` compiling only what a kernel's thin films can reach: the GGX lobes
    (``rough``), their compensation (``multiscatter``), the layered walk (``layered``)."""
    rough_eval_pdf, rough_sample = _rough_lobes(multiscatter)
    walk_eval_pdf, walk_sample = walk(FILM, LAMBERT, not rough)   # the coating over its Lambertian base

    @wp.func
    def eval_pdf(b: BSDF, wo: wp.vec3, wi: wp.vec3) -> BSDFEval:
        """The layered walk's estimate, the rough lobes, or the smooth coating's substrate lobe."""
        if wp.static(layered):
            if _layered(b):
                return wp.static(walk_eval_pdf)(_slab(b), wo, wi)
        if wp.static(rough):
            alpha = _alpha(b)
            if not is_smooth(alpha):
                return wp.static(rough_eval_pdf)(b, wo, wi, alpha)
        return _smooth_eval_pdf(b, wo, wi)

    @wp.func
    def sample(b: BSDF, wo: wp.vec3, u: wp.vec3) -> BSDFSample:
        """The layered walk, the rough lobes, or the smooth coating's mirror, refraction or substrate."""
        if wp.static(layered):
            if _layered(b):
                return wp.static(walk_sample)(_slab(b), wo, u)
        if wp.static(rough):
            alpha = _alpha(b)
            if not is_smooth(alpha):
                return wp.static(rough_sample)(b, wo, u, alpha)
        return _smooth_sample(b, wo, u)

    return eval_pdf, sample


#: Every lobe: what the tests and other code call directly.
eval_pdf, sample = _lobes(True, True, True)


def specialised(features: Any) -> tuple[wp.Function, wp.Function]:
    """``eval_pdf`` and ``sample`` with only the lobes a kernel of ``features`` can reach (all films walk: the walk)."""
    if features.layered and not features.unlayered:
        return walk_alone(_slab, FILM, LAMBERT, NAME in features.smooth)
    return _lobes(NAME not in features.smooth, features.multiscatter, features.layered)
