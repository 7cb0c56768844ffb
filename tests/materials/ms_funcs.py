"""The lobes of ``dielectric`` and a clear rough ``thinfilm`` without the 1/η'² radiance scaling of
refraction, as (eval_pdf, sample) pairs for :func:`bsdf_harness.bsdf_moments`: the albedo of a
lossless interface is then exactly 1 from either side (energy, not radiance, is conserved)."""
from __future__ import annotations

import warp as wp

from renderer.materials import dielectric, thinfilm
from renderer.materials.bsdf import BSDF, REFLECTION, TRANSMISSION, BSDFEval, BSDFSample
from renderer.materials.coating import BOTH_SIDES, coating_eval, coating_sample
from renderer.materials.coating_energy import coating_ms_eval, coating_ms_sample


@wp.func
def _eta(b: BSDF) -> float:
    return b.p[dielectric.SLOT.eta][0]


@wp.func
def glass_ms_eval(b: BSDF, wo: wp.vec3, wi: wp.vec3) -> BSDFEval:
    return dielectric.dielectric_ms_eval(_eta(b), dielectric._alpha(b), wo, wi, False, b.layers)


@wp.func
def glass_ms_sample(b: BSDF, wo: wp.vec3, u: wp.vec3) -> BSDFSample:
    return dielectric.dielectric_ms_sample(_eta(b), dielectric._alpha(b), wo, u, False, b.layers)


@wp.func
def glass_ss_eval(b: BSDF, wo: wp.vec3, wi: wp.vec3) -> BSDFEval:
    return dielectric.dielectric_eval(_eta(b), dielectric._alpha(b), wo, wi, REFLECTION | TRANSMISSION, False)


@wp.func
def glass_ss_sample(b: BSDF, wo: wp.vec3, u: wp.vec3) -> BSDFSample:
    return dielectric.dielectric_sample(_eta(b), dielectric._alpha(b), wo, u, REFLECTION | TRANSMISSION, False)


@wp.func
def film_ms_eval(b: BSDF, wo: wp.vec3, wi: wp.vec3) -> BSDFEval:
    return coating_ms_eval(thinfilm.film_coating(b), thinfilm._eta(b), thinfilm._alpha(b), wo, wi, False, b.layers)


@wp.func
def film_ms_sample(b: BSDF, wo: wp.vec3, u: wp.vec3) -> BSDFSample:
    return coating_ms_sample(thinfilm.film_coating(b), thinfilm._eta(b), thinfilm._alpha(b), wo, u, False, b.layers)


@wp.func
def film_ss_eval(b: BSDF, wo: wp.vec3, wi: wp.vec3) -> BSDFEval:
    return coating_eval(thinfilm.film_coating(b), thinfilm._eta(b), thinfilm._alpha(b), wo, wi, BOTH_SIDES, False)


@wp.func
def film_ss_sample(b: BSDF, wo: wp.vec3, u: wp.vec3) -> BSDFSample:
    return coating_sample(thinfilm.film_coating(b), thinfilm._eta(b), thinfilm._alpha(b), wo, u, BOTH_SIDES, False)


GLASS_MS = (glass_ms_eval, glass_ms_sample)
GLASS_SS = (glass_ss_eval, glass_ss_sample)
FILM_MS = (film_ms_eval, film_ms_sample)
FILM_SS = (film_ss_eval, film_ss_sample)
