"""pbrt-v4's ``coateddiffuse``: a dielectric coat (smooth or rough) over a Lambertian base, with
a slab of medium between them, evaluated by the layered random walk (:mod:`.layered`)."""
from __future__ import annotations

from typing import Any

import warp as wp

from renderer.errors import Location
from renderer.materials.bsdf import BSDF, BSDFEval, BSDFSample
from renderer.materials.coating import Coating
from renderer.materials.layer_interfaces import DIELECTRIC, LAMBERT, Interface
from renderer.materials.layered import SLAB_PARAMS, Slab, make_slab, walk, walk_flags
from renderer.materials.microfacet import REMAP_ROUGHNESS, resolve_roughness, roughness_params, roughness_to_alpha
from renderer.parameters import Parameter, Parameters

NAME = "coateddiffuse"
PARAMS = Parameters(
    Parameter("reflectance", "rgb", 0.5, 0.0, 1.0, texture=True, doc="albedo of the diffuse base"),
    *roughness_params(),
    Parameter("eta", "float", 1.5, 1.0e-3, doc="index of refraction of the coat"),
    *SLAB_PARAMS,
    REMAP_ROUGHNESS,
)
SLOT = PARAMS.slots
FLAG = PARAMS.flags


def resolve(values: dict[str, Any], loc: Location | None) -> tuple[dict[str, Any], int]:
    return resolve_roughness(values), walk_flags(values)


@wp.func
def _slab(b: BSDF) -> Slab:
    top = Interface()
    top.kind = DIELECTRIC
    top.eta = wp.vec3(b.p[SLOT.eta][0])
    top.alpha = roughness_to_alpha(wp.vec2(b.p[SLOT.uroughness][0], b.p[SLOT.vroughness][0]),
                                   (b.flags & FLAG.remaproughness) != 0)
    base = Interface()
    base.kind = LAMBERT
    base.albedo = b.p[SLOT.reflectance]
    return make_slab(top, base, Coating(), b.p[SLOT.thickness][0], b.p[SLOT.albedo], b.p[SLOT.g][0], b.flags,
                     b.wavelength_u)


_walk_eval_pdf, _walk_sample = walk(DIELECTRIC, LAMBERT)


@wp.func
def eval_pdf(b: BSDF, wo: wp.vec3, wi: wp.vec3) -> BSDFEval:
    return _walk_eval_pdf(_slab(b), wo, wi)


@wp.func
def sample(b: BSDF, wo: wp.vec3, u: wp.vec3) -> BSDFSample:
    return _walk_sample(_slab(b), wo, u)
