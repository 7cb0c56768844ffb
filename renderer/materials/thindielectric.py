"""pbrt-v4's ``thindielectric``: a dielectric sheet too thin to refract (a window pane, a soap
film without its colours). Light either reflects or passes straight through; the reflectance sums
the sheet's infinitely many internal bounces, R' = R + T² R / (1 − R²) with R the single-interface
Fresnel reflectance, and T' = 1 − R'. Both lobes are delta; two-sided, no radiance scaling (light
leaves into the medium it came from)."""
from __future__ import annotations

import warp as wp

from renderer.materials.bsdf import (BSDF, REFLECTION, SPECULAR, TRANSMISSION, BSDFEval, BSDFSample, delta_sample,
                                     reflect_z)
from renderer.optics.fresnel import fresnel_dielectric
from renderer.parameters import Parameter, Parameters

NAME = "thindielectric"
PARAMS = Parameters(
    Parameter("eta", "float", 1.5, 1.0e-3, texture=True, doc="index of refraction of the sheet"),
)
SLOT = PARAMS.slots


@wp.func
def sheet_reflectance(cos_o: float, eta: float) -> float:
    """The sheet's reflectance with all internal bounces: R + T² R / (1 − R²)."""
    r = fresnel_dielectric(wp.abs(cos_o), eta)
    if r < 1.0:
        t = 1.0 - r
        r = r + t * t * r / (1.0 - r * r)
    return r


@wp.func
def eval_pdf(b: BSDF, wo: wp.vec3, wi: wp.vec3) -> BSDFEval:
    """Only delta lobes: nothing to evaluate for a given pair of directions."""
    return BSDFEval()


@wp.func
def sample(b: BSDF, wo: wp.vec3, u: wp.vec3) -> BSDFSample:
    """Reflect with probability R', else pass straight through: each weight is then exactly 1."""
    r = sheet_reflectance(wo[2], b.p[SLOT.eta][0])
    if u[2] < r:
        return delta_sample(reflect_z(wo), wp.vec3(1.0), r, REFLECTION | SPECULAR)
    s = delta_sample(-wo, wp.vec3(1.0), 1.0 - r, TRANSMISSION | SPECULAR)
    s.eta = 1.0
    return s
