"""A thin film or multilayer stack over the Disney material's subsurface body (flag FILM): the film's
per-wavelength R and T, integrated to RGB by :mod:`renderer.materials.coating`, take the place of
the bare boundary's dielectric Fresnel F(eta) and 1 − F(eta), Disney's ``eta`` being the body's index:

* the specular lobe's dielectric Fresnel (the untinted share of Burley's specular blend) becomes
  the film's R at the microfacet, so the film's colour shows where the surface mirrors the sky;
* Burley's entry and exit factors (1 − F_o/2) and (1 − F_i/2), shapes fitted to a bare boundary,
  are each multiplied by what the film changes in the light crossing there, T_coat(cos) / (1 − F(cos));
* the exit balance k of :mod:`renderer.materials.film_body` (what the body returns of the light the
  film keeps inside), with the base colour as the body's effective albedo, is charged at the entry.

The lobe-selection probabilities stay the bare material's, so a film changes values, never
densities: sample() picks as the plain material does and reweights by the coated value. A 0 nm film,
or one of the body's own index, is the plain material to float rounding (its R and T are the bare
Fresnel's). The glass lobe (``spectrans``) keeps its bare dielectric: the film coats the body the
subsurface step carries. docs/thinfilm.md measures the coupling against a volumetric reference.

Compiled only into kernels of scenes where some Disney material has a film
(``Features.coated_disney``): the plain Disney kernels carry no Coating.
"""
from __future__ import annotations

from functools import lru_cache
from typing import Any

import warp as wp

from renderer.materials import disney
from renderer.materials.bsdf import BSDF, BSDFEval, BSDFSample, signed_z
from renderer.materials.coating import Coating, coating_rgb
from renderer.materials.film_body import body_coating, exit_balance
from renderer.materials.microfacet import ggx_D, ggx_G
from renderer.optics.fresnel import fresnel_dielectric

SLOT = disney.SLOT


@wp.func
def disney_coating(b: BSDF, eta: float) -> Coating:
    """Vacuum | the film (thickness + thicknessscale · thicknessmap nm) or stack | the body of index eta."""
    d = b.p[SLOT.thickness][0] + b.p[SLOT.thicknessscale][0] * b.p[SLOT.thicknessmap][0]
    return body_coating(b, b.p[SLOT.eta_film][0], eta, d, b.p[SLOT.thickness][0])


@wp.func
def transmission_ratio(c: Coating, eta: float, cos_w: float) -> wp.vec3:
    """T_coat / (1 − F) from outside at cosine cos_w > 0: how the film changes the light crossing there."""
    r, t = coating_rgb(c, cos_w)
    bare = 1.0 - fresnel_dielectric(cos_w, eta)
    return wp.where(bare > 0.0, t / wp.max(bare, 1.0e-30), wp.vec3(0.0))


@wp.func
def film_change(P: disney.Params, c: Coating, o: wp.vec3, i: wp.vec3, f: wp.vec3) -> wp.vec3:
    """The plain value f (o, i brought above the surface as the plain material does) with the film:
    the exit lobe times T_coat / (1 − F) at i; above a solid, the specular lobe's dielectric Fresnel
    replaced by the film's R at the half-vector."""
    if o[2] <= 0.0 or i[2] <= 0.0:
        return f
    if P.exit:
        return wp.cw_mul(f, transmission_ratio(c, P.eta, i[2]))
    h = wp.normalize(o + i)
    cos_d = wp.dot(o, h)
    r, t = coating_rgb(c, cos_d)
    share = P.dw * (1.0 - P.spec_tint) * ggx_D(h, P.alpha) * ggx_G(o, i, P.alpha) / (4.0 * o[2] * i[2])
    return f + (r - wp.vec3(fresnel_dielectric(cos_d, P.eta))) * share


@wp.func
def coated_eval_pdf(b: BSDF, wo: wp.vec3, wi: wp.vec3) -> BSDFEval:
    ev = disney.eval_pdf(b, wo, wi)
    P = disney.seen_from(b, wo)
    if P.thin:
        return ev
    ev.f = film_change(P, disney_coating(b, P.eta), P.o, signed_z(wi, P.sgn), ev.f)
    return ev


@wp.func
def coated_sample(b: BSDF, wo: wp.vec3, u: wp.vec3) -> BSDFSample:
    """The plain material's choice (same density), weighted by the coated value."""
    s = disney.sample(b, wo, u)
    if s.pdf > 0.0:
        s.weight = coated_eval_pdf(b, wo, s.wi).f * (wp.abs(s.wi[2]) / s.pdf)
    return s


@wp.func
def entry_factor(b: BSDF, cos_o: float) -> wp.vec3:
    """What the subsurface route's weight gains at the entry: T_coat / (1 − F) at cos_o times the exit
    balance k for the base colour's albedo (1 without a film)."""
    if (b.flags & disney.FILM) == 0:
        return wp.vec3(1.0)
    P = disney.load_params(b)
    c = disney_coating(b, P.eta)
    return wp.cw_mul(transmission_ratio(c, P.eta, cos_o), exit_balance(c, P.eta, P.c))


@lru_cache(maxsize=None)
def _lobes(coated: bool) -> tuple[wp.Function, wp.Function]:
    if not coated:
        return disney.eval_pdf, disney.sample

    @wp.func
    def eval_pdf(b: BSDF, wo: wp.vec3, wi: wp.vec3) -> BSDFEval:
        if (b.flags & disney.FILM) != 0:
            return coated_eval_pdf(b, wo, wi)
        return disney.eval_pdf(b, wo, wi)

    @wp.func
    def sample(b: BSDF, wo: wp.vec3, u: wp.vec3) -> BSDFSample:
        if (b.flags & disney.FILM) != 0:
            return coated_sample(b, wo, u)
        return disney.sample(b, wo, u)

    return eval_pdf, sample


#: Every lobe, film or not: what the tests call directly.
eval_pdf, sample = _lobes(True)


def specialised(features: Any) -> tuple[wp.Function, wp.Function]:
    """Disney's ``eval_pdf`` and ``sample``: the plain functions unless some Disney material has a film."""
    return _lobes(features.coated_disney)
