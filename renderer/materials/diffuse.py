"""pbrt's ``diffuse``: a Lambertian reflector, two-sided."""
from __future__ import annotations

import warp as wp

from renderer.materials.bsdf import BSDF, BSDFSample, failed_sample, same_hemisphere
from renderer.vecmath import INV_PI
from renderer.sampling.warps import cosine_hemisphere

NAME = "diffuse"


def slots(s) -> list[int]:
    return [s.rgb("reflectance", 0.5, lo=0.0, hi=1.0)]


@wp.func
def eval(b: BSDF, wo: wp.vec3, wi: wp.vec3) -> wp.vec3:
    if not same_hemisphere(wo, wi):
        return wp.vec3(0.0)
    return b.p[0] * INV_PI


@wp.func
def pdf(b: BSDF, wo: wp.vec3, wi: wp.vec3) -> float:
    if not same_hemisphere(wo, wi):
        return 0.0
    return wp.abs(wi[2]) * INV_PI


@wp.func
def sample(b: BSDF, wo: wp.vec3, u: wp.vec3) -> BSDFSample:
    wi = cosine_hemisphere(wp.vec2(u[0], u[1]))
    if wo[2] < 0.0:
        wi = wp.vec3(wi[0], wi[1], -wi[2])
    s = BSDFSample()
    s.wi = wi
    s.pdf = wp.abs(wi[2]) * INV_PI
    if s.pdf <= 0.0:
        return failed_sample()
    s.weight = b.p[0]
    s.specular = False
    return s
