"""Rays that pass through cut-outs: pbrt-v4's shape ``alpha`` (a float texture or constant; 0 is a
hole, fractional alpha keeps a hit with that probability, decided by a hash of the ray) and the
``interface`` material (an invisible boundary, alpha 0 everywhere).

Warp's mesh query has no any-hit filter, so a rejected hit is stepped over: the ray is traced again
from just past it (offset along the geometric normal by the hit point's own error bound), at most
MAX_SKIPS times. Each trace is a whole ``intersect`` that has returned before the next starts, so
no two traversals share a stack on CUDA. Kernels only call these when the scene has cut-outs
(``Features.alpha``); other scenes keep the plain queries."""
from __future__ import annotations

from typing import NamedTuple

import warp as wp

from renderer.device.scene import Features, Scene
from renderer.geometry.intersect import Hit, intersect, occluded, surface_at
from renderer.geometry.offsets import offset_origin
from renderer.integrators.thin_slab import transmittance_query
from renderer.sampling.scramble import hash_point_direction, to_unit
from renderer.textures import texture_eval

#: Rejected hits one ray steps over before it takes the next hit as it is.
MAX_SKIPS = 64


@wp.func
def trace(scene: Scene, o: wp.vec3, d: wp.vec3, t_max: float) -> Hit:
    """The closest hit within (0, t_max) that alpha keeps; t is measured from ``o``."""
    travelled = float(0.0)
    hit = Hit()
    for k in range(MAX_SKIPS + 1):     # one call site: the traversal is inlined once
        hit = intersect(scene.geo, o, d, t_max - travelled)
        if k == MAX_SKIPS:
            break
        if hit.inst < 0:
            return hit
        shape = scene.geo.inst_shape[hit.inst]
        tid = scene.shape_alpha[shape]
        if tid < 0:
            break
        s = surface_at(scene.geo, hit, scene.shape_flip[shape] != 0)
        a = texture_eval(scene.tex, tid, s.uv, s.p, s.ng)[0]
        if a >= 1.0:
            break
        if a > 0.0:
            if to_unit(hash_point_direction(o, d)) <= a:      # pbrt: skipped when u > a
                break
        step = offset_origin(s, d)
        travelled += wp.dot(step - o, d)
        o = step
    hit.t = hit.t + travelled
    return hit


@wp.func
def blocked(scene: Scene, o: wp.vec3, d: wp.vec3, t_max: float) -> bool:
    """Whether a hit that alpha keeps lies along the ray before t_max (shadow rays)."""
    return trace(scene, o, d, t_max).inst >= 0


@wp.func(inline=True)
def _closest(scene: Scene, o: wp.vec3, d: wp.vec3, t_max: float) -> Hit:
    return intersect(scene.geo, o, d, t_max)


@wp.func(inline=True)
def _occluded(scene: Scene, o: wp.vec3, d: wp.vec3, t_max: float) -> bool:
    return occluded(scene.geo, o, d, t_max)


class RayQueries(NamedTuple):
    closest: wp.Function        # (scene, o, d, t_max) -> Hit
    blocked: wp.Function        # (scene, o, d, t_max) -> bool
    transmitted: wp.Function    # (scene, o, d, t_max) -> vec3 through thin slabs (Features.thin_slabs)


def ray_queries(features: Features) -> RayQueries:
    """The closest-hit and shadow queries a kernel of this feature set uses: alpha-aware ones only
    when the scene has cut-outs; kernels call ``transmitted`` instead of ``blocked`` only when it
    has thin slabs (renderer.integrators.thin_slab)."""
    closest, shadow = (trace, blocked) if features.alpha else (_closest, _occluded)
    return RayQueries(closest, shadow, transmittance_query(closest, features.alpha))
