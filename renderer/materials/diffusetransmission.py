"""pbrt-v4's ``diffusetransmission``: a Lambertian surface that also scatters diffusely through
itself (leaves, paper, a lamp shade): f = reflectance / π on the side light came from and
transmittance / π on the other. Sampling picks the side in proportion to the two colours' largest
components, as pbrt does, then a cosine-distributed direction on it. ``scale`` multiplies both;
they are clamped to [0, 1] like pbrt."""
from __future__ import annotations

import warp as wp

from renderer.materials.bsdf import (BSDF, DIFFUSE, BSDFEval, BSDFSample, failed_sample, same_hemisphere, sampled)
from renderer.parameters import Parameter, Parameters
from renderer.sampling.warps import cosine_hemisphere
from renderer.vecmath import INV_PI, max3

NAME = "diffusetransmission"
PARAMS = Parameters(
    Parameter("reflectance", "rgb", 0.25, 0.0, 1.0, texture=True, doc="albedo of the diffuse reflection"),
    Parameter("transmittance", "rgb", 0.25, 0.0, 1.0, texture=True, doc="albedo of the diffuse transmission"),
    Parameter("scale", "float", 1.0, 0.0, doc="multiplies both (the products are clamped to 1)"),
)
SLOT = PARAMS.slots


@wp.func
def _colour(b: BSDF, slot: int) -> wp.vec3:
    """A colour parameter times ``scale``, clamped to [0, 1]."""
    k = b.p[SLOT.scale][0]
    c = b.p[slot] * k
    return wp.min(wp.max(c, wp.vec3(0.0)), wp.vec3(1.0))


@wp.func
def _reflect_probability(r: wp.vec3, t: wp.vec3) -> float:
    """pbrt's choice between the sides: by the colours' largest components."""
    total = max3(r) + max3(t)
    if total <= 0.0:
        return 0.0
    return max3(r) / total


@wp.func
def eval_pdf(b: BSDF, wo: wp.vec3, wi: wp.vec3) -> BSDFEval:
    r = _colour(b, SLOT.reflectance)
    t = _colour(b, SLOT.transmittance)
    pr = _reflect_probability(r, t)
    ev = BSDFEval()
    if max3(r) + max3(t) <= 0.0 or wi[2] == 0.0 or wo[2] == 0.0:
        return ev
    if same_hemisphere(wo, wi):
        ev.f = r * INV_PI
        ev.pdf = pr * wp.abs(wi[2]) * INV_PI
    else:
        ev.f = t * INV_PI
        ev.pdf = (1.0 - pr) * wp.abs(wi[2]) * INV_PI
    return ev


@wp.func
def sample(b: BSDF, wo: wp.vec3, u: wp.vec3) -> BSDFSample:
    r = _colour(b, SLOT.reflectance)
    t = _colour(b, SLOT.transmittance)
    if max3(r) + max3(t) <= 0.0:
        return failed_sample()
    wi = cosine_hemisphere(wp.vec2(u[0], u[1]))
    below = wo[2] < 0.0
    if u[2] >= _reflect_probability(r, t):
        below = not below
    if below:
        wi = wp.vec3(wi[0], wi[1], -wi[2])
    return sampled(wo, wi, eval_pdf(b, wo, wi), DIFFUSE)
