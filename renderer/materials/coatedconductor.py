"""pbrt-v4's ``coatedconductor``: a dielectric coat (smooth or rough) over a conductor base (smooth
or rough; complex index or artist ``reflectance``), with a slab of medium between them, evaluated
by the layered random walk (:mod:`.layered`). The conductor's index is relative to the coat's.

A spectral ``conductor.eta`` or ``conductor.k`` (pbrt-v4's named ``metal-*`` spectra, inline
samples, ``.spd``) gives the base the conductor's spectral Fresnel table
(:func:`.conductor.spectral_fresnel_rows`), baked for the index relative to the coat."""
from __future__ import annotations

from typing import Any

import numpy as np
import warp as wp

from renderer.errors import Location, SceneError
from renderer.materials.bsdf import BSDF, BSDFEval, BSDFSample
from renderer.materials.coating import Coating
from renderer.materials.conductor import COPPER_ETA, COPPER_K, artist_k, spectral_fresnel_rows
from renderer.materials.layer_interfaces import CONDUCTOR, DIELECTRIC, Interface
from renderer.materials.layered import FIRST_FREE_FLAG, SLAB_PARAMS, Slab, make_slab, walk, walk_flags
from renderer.materials.microfacet import REMAP_ROUGHNESS, resolve_roughness, roughness_params, roughness_to_alpha
from renderer.parameters import Parameter, Parameters

NAME = "coatedconductor"
PARAMS = Parameters(
    *roughness_params("interface."),
    Parameter("interface.eta", "float", 1.5, 1.0e-3, doc="index of refraction of the coat"),
    *SLAB_PARAMS,
    Parameter("conductor.eta", "rgb", COPPER_ETA, 0.0, texture=True, doc="real part of the base's index (copper)"),
    Parameter("conductor.k", "rgb", COPPER_K, 0.0, texture=True, doc="imaginary part of the base's index (copper)"),
    *roughness_params("conductor."),
    Parameter("reflectance", "rgb", None, 0.0, 0.9999, texture=True,
              doc="artist reflectance of the base at normal incidence; replaces conductor.eta and conductor.k"),
    REMAP_ROUGHNESS,
)
SLOT = PARAMS.slots
FLAG = PARAMS.flags
#: Derived flag: ``reflectance`` was given, so it replaces the conductor's eta and k.
ARTIST = wp.constant(FIRST_FREE_FLAG)
_IU = wp.constant(getattr(SLOT, "interface.uroughness"))
_IV = wp.constant(getattr(SLOT, "interface.vroughness"))
_IETA = wp.constant(getattr(SLOT, "interface.eta"))
_CU = wp.constant(getattr(SLOT, "conductor.uroughness"))
_CV = wp.constant(getattr(SLOT, "conductor.vroughness"))
_CETA = wp.constant(getattr(SLOT, "conductor.eta"))
_CK = wp.constant(getattr(SLOT, "conductor.k"))


def resolve(values: dict[str, Any], loc: Location | None) -> tuple[dict[str, Any], int]:
    """pbrt's rule: ``reflectance`` or the complex index, not both."""
    artist = "reflectance" in values
    if artist and ("conductor.eta" in values or "conductor.k" in values):
        raise SceneError('coatedconductor: give either "reflectance" or "conductor.eta" and "conductor.k", '
                         'not both', loc)
    v = resolve_roughness(resolve_roughness(values, "interface."), "conductor.")
    return v, walk_flags(values) | (ARTIST if artist else 0)


def table_rows(values: dict[str, Any], loc: Location | None, thin_film: str) -> tuple[np.ndarray, str]:
    """The base's spectral Fresnel table (relative to the coat) when its eta or k is a spectrum."""
    if "reflectance" in values:
        return np.zeros((0, 4), np.float32), ""
    rows, warning = spectral_fresnel_rows(PARAMS.value(values, "conductor.eta"), PARAMS.value(values, "conductor.k"),
                                          float(PARAMS.value(values, "interface.eta")))
    return rows, f"coatedconductor: {warning}" if warning else ""


@wp.func
def _slab(b: BSDF) -> Slab:
    remap = (b.flags & FLAG.remaproughness) != 0
    ieta = b.p[_IETA][0]
    top = Interface()
    top.kind = DIELECTRIC
    top.eta = wp.vec3(ieta)
    top.alpha = roughness_to_alpha(wp.vec2(b.p[_IU][0], b.p[_IV][0]), remap)
    base = Interface()
    table = Coating()       # the base's spectral Fresnel table, if any
    base.kind = CONDUCTOR
    base.alpha = roughness_to_alpha(wp.vec2(b.p[_CU][0], b.p[_CV][0]), remap)
    if (b.flags & ARTIST) != 0:
        base.eta = wp.vec3(1.0 / ieta)
        base.k = artist_k(b.p[SLOT.reflectance]) / ieta
    else:
        base.eta = b.p[_CETA] / ieta
        base.k = b.p[_CK] / ieta
        table.layers = b.layers
        table.table_first = b.table_first
    return make_slab(top, base, table, b.p[SLOT.thickness][0], b.p[SLOT.albedo], b.p[SLOT.g][0], b.flags,
                     b.wavelength_u)


_walk_eval_pdf, _walk_sample = walk(DIELECTRIC, CONDUCTOR)


@wp.func
def eval_pdf(b: BSDF, wo: wp.vec3, wi: wp.vec3) -> BSDFEval:
    return _walk_eval_pdf(_slab(b), wo, wi)


@wp.func
def sample(b: BSDF, wo: wp.vec3, u: wp.vec3) -> BSDFSample:
    return _walk_sample(_slab(b), wo, u)
