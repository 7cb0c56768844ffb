"""pbrt's ``diffuse``: a Lambertian reflector, two-sided."""
from __future__ import annotations

import warp as wp

from renderer.materials.bsdf import BSDF, DIFFUSE, REFLECTION, BSDFEval, BSDFSample, failed_sample, same_hemisphere
from renderer.parameters import Parameter, Parameters
from renderer.sampling.warps import cosine_hemisphere
from renderer.vecmath import INV_PI

NAME = "diffuse"
PARAMS = Parameters(
    Parameter("reflectance", "rgb", 0.5, 0.0, 1.0, texture=True, doc="albedo"),
)
SLOT = PARAMS.slots


@wp.func
def lambert_eval(r: wp.vec3, wo: wp.vec3, wi: wp.vec3) -> BSDFEval:
    """A two-sided Lambertian lobe of albedo r, cosine-sampled."""
    ev = BSDFEval()
    if same_hemisphere(wo, wi):
        ev.f = r * INV_PI
        ev.pdf = wp.abs(wi[2]) * INV_PI
    return ev


@wp.func
def lambert_sample(r: wp.vec3, wo: wp.vec3, u: wp.vec3) -> BSDFSample:
    wi = cosine_hemisphere(wp.vec2(u[0], u[1]))
    if wo[2] < 0.0:
        wi = wp.vec3(wi[0], wi[1], -wi[2])
    s = BSDFSample()
    s.wi = wi
    s.pdf = wp.abs(wi[2]) * INV_PI
    if s.pdf <= 0.0:
        return failed_sample()
    s.weight = r
    s.flags = REFLECTION | DIFFUSE
    return s


@wp.func
def eval_pdf(b: BSDF, wo: wp.vec3, wi: wp.vec3) -> BSDFEval:
    return lambert_eval(b.p[SLOT.reflectance], wo, wi)


@wp.func
def sample(b: BSDF, wo: wp.vec3, u: wp.vec3) -> BSDFSample:
    return lambert_sample(b.p[SLOT.reflectance], wo, u)
