"""The interfaces a layered BSDF walks between (:mod:`.layered`), one small integer kind each
(Warp has no function pointers): for every kind its f and density restricted to the sides the
walk asks for, its sampling, and whether it is a delta interface. A walk between a top and a
bottom of fixed kinds takes their two entries of ``INTERFACES``, so nothing branches on a kind at
run time."""
from __future__ import annotations

import warp as wp

from renderer.materials.bsdf import REFLECTION, BSDFEval, BSDFSample, failed_sample
from renderer.materials.coating import Coating, coating_eval, coating_sample, smooth_coating_sample
from renderer.materials.conductor import conductor_eval, conductor_sample
from renderer.materials.dielectric import dielectric_eval, dielectric_sample
from renderer.materials.diffuse import lambert_eval, lambert_sample
from renderer.materials.microfacet import is_smooth

#: Interface kinds.
DIELECTRIC = wp.constant(0)   # eta (eta[0]) over alpha: pbrt's DielectricBxDF
LAMBERT = wp.constant(1)      # albedo: pbrt's DiffuseBxDF
CONDUCTOR = wp.constant(2)    # eta + i k over alpha: pbrt's ConductorBxDF
FILM = wp.constant(3)         # coat on a substrate of relative index eta[0], over alpha


@wp.struct
class Interface:
    kind: int
    eta: wp.vec3        # DIELECTRIC: eta[0], inside over outside; CONDUCTOR: eta relative to the slab
    k: wp.vec3          # CONDUCTOR
    alpha: wp.vec2      # DIELECTRIC, CONDUCTOR, FILM: GGX roughness
    albedo: wp.vec3     # LAMBERT


# Interfaces, one kind at a time: each material's walk has a fixed top and bottom kind
# (:func:`walk`), so a kernel compiles only the lobes of the kinds it walks between. Each takes the
# slab's one coating ``c`` beside its interface: a FILM's (its substrate must be clear), or a
# CONDUCTOR's spectral Fresnel table at c.layers[c.table_first] (0: the per-channel formula).


@wp.func
def _dielectric_eval(s: Interface, c: Coating, wo: wp.vec3, wi: wp.vec3, sides: int, radiance: bool) -> BSDFEval:
    return dielectric_eval(s.eta[0], s.alpha, wo, wi, sides, radiance)


@wp.func
def _dielectric_sample(s: Interface, c: Coating, wo: wp.vec3, u: wp.vec3, sides: int, radiance: bool) -> BSDFSample:
    return dielectric_sample(s.eta[0], s.alpha, wo, u, sides, radiance)


@wp.func
def _dielectric_specular(s: Interface) -> bool:
    return s.eta[0] == 1.0 or is_smooth(s.alpha)


@wp.func
def _film_eval(s: Interface, c: Coating, wo: wp.vec3, wi: wp.vec3, sides: int, radiance: bool) -> BSDFEval:
    return coating_eval(c, s.eta[0], s.alpha, wo, wi, sides, radiance)


@wp.func
def _film_sample(s: Interface, c: Coating, wo: wp.vec3, u: wp.vec3, sides: int, radiance: bool) -> BSDFSample:
    return coating_sample(c, s.eta[0], s.alpha, wo, u, sides, radiance)


@wp.func
def _rough_specular(s: Interface) -> bool:
    return is_smooth(s.alpha)


@wp.func
def _smooth_film_eval(s: Interface, c: Coating, wo: wp.vec3, wi: wp.vec3, sides: int, radiance: bool) -> BSDFEval:
    """A smooth coating's lobes are deltas: no value (``coating_eval`` at alpha 0)."""
    return BSDFEval()


@wp.func
def _smooth_film_sample(s: Interface, c: Coating, wo: wp.vec3, u: wp.vec3, sides: int, radiance: bool) -> BSDFSample:
    return smooth_coating_sample(c, s.eta[0], wo, u[2], sides, radiance)


@wp.func
def _specular(s: Interface) -> bool:
    return True


@wp.func
def _lambert_eval(s: Interface, c: Coating, wo: wp.vec3, wi: wp.vec3, sides: int, radiance: bool) -> BSDFEval:
    if (sides & REFLECTION) == 0:
        return BSDFEval()
    return lambert_eval(s.albedo, wo, wi)


@wp.func
def _lambert_sample(s: Interface, c: Coating, wo: wp.vec3, u: wp.vec3, sides: int, radiance: bool) -> BSDFSample:
    if (sides & REFLECTION) == 0:
        return failed_sample()
    return lambert_sample(s.albedo, wo, u)


@wp.func
def _diffuse(s: Interface) -> bool:
    return False


@wp.func
def _conductor_eval(s: Interface, c: Coating, wo: wp.vec3, wi: wp.vec3, sides: int, radiance: bool) -> BSDFEval:
    if (sides & REFLECTION) == 0:
        return BSDFEval()
    return conductor_eval(s.eta, s.k, s.alpha, wo, wi, c.layers, c.table_first)


@wp.func
def _conductor_sample(s: Interface, c: Coating, wo: wp.vec3, u: wp.vec3, sides: int, radiance: bool) -> BSDFSample:
    if (sides & REFLECTION) == 0:
        return failed_sample()
    return conductor_sample(s.eta, s.k, s.alpha, wo, u, c.layers, c.table_first)


#: Per (kind, smooth) the interface's f and density restricted to ``sides`` (pbrt's
#: BxDFReflTransFlags), its sampling, and whether it is a delta interface (which next-event
#: estimation cannot reach, so the walk skips that). ``smooth``: every such interface of the
#: kernel's materials has alpha 0 (a FILM of a smooth thinfilm).
INTERFACES = {
    (DIELECTRIC, False): (_dielectric_eval, _dielectric_sample, _dielectric_specular),
    (FILM, False): (_film_eval, _film_sample, _rough_specular),
    (FILM, True): (_smooth_film_eval, _smooth_film_sample, _specular),
    (LAMBERT, False): (_lambert_eval, _lambert_sample, _diffuse),
    (CONDUCTOR, False): (_conductor_eval, _conductor_sample, _rough_specular),
}
