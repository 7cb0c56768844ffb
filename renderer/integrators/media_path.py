"""What pbrt-v4's ``volpath`` adds to the path loop, for kernels of scenes with media
(``Features.media``): the medium a path is in, crossing medium boundaries, shadow rays'
transmittance through media and ``interface`` surfaces, and scattering at a point of a medium
(next-event estimation with the phase function, then a phase-sampled direction), and the first
surface that is not an interface (the AOVs').

Weights: a path samples distances with one colour channel (renderer.media.tracking); ``beta``
is its throughput over that channel's density and ``r_u`` the channels' densities over it, so a
contribution is divided by mean(r_u) (for a shadow ray, by the mean of r_u times the ratio
tracking's own ratios). Between light sampling and phase or BSDF sampling the directions are
MIS-weighted by the power heuristic, as in the path kernel; transmittance multiplies both
strategies, so the two weights still sum to one for every path.

A dispersed path (one wavelength, renderer.optics.dispersion) meets media in RGB: its throughput
is already RGB (the wavelength's colour weight), and media scale it channel by channel."""
from __future__ import annotations

from functools import lru_cache
from typing import NamedTuple

import warp as wp

from renderer.device.scene import Features, Scene
from renderer.geometry.intersect import Hit, surface_at
from renderer.geometry.offsets import offset_origin, ray_epsilon
from renderer.integrators.path_state import MediumState, PathState
from renderer.integrators.visibility import ray_queries
from renderer.lights import dispatch
from renderer.lights.sample import light_sampler
from renderer.materials.phase import hg_phase, hg_sample
from renderer.materials.selection import INTERFACE_KIND
from renderer.media.tracking import Transmitted, ratio_track
from renderer.sampling.mis import power_heuristic
from renderer.sampling.rng import sample_rng
from renderer.vecmath import max3, mean3

#: interface surfaces one shadow ray crosses before it counts as blocked
MAX_CROSSINGS = 64
INTERFACE = wp.constant(INTERFACE_KIND)
#: the tracking stream's seed offset: not the independent sampler's stream
_STREAM = 0x2545F491


@wp.func
def start_medium(scene: Scene, seed: int, sample_index: int, pixel: int) -> MediumState:
    """A camera path in the camera's medium, with a channel chosen uniformly."""
    ms = MediumState()
    ms.medium = scene.camera_medium
    ms.r_u = wp.vec3(1.0)
    state = sample_rng(seed + _STREAM, sample_index, pixel)
    ms.c = wp.min(int(wp.randf(state) * 3.0), 2)
    ms.rng = state
    return ms


@wp.func
def crossed(scene: Scene, shape: int, ng: wp.vec3, w: wp.vec3, medium: int) -> int:
    """The medium a ray leaving a point of ``shape`` in direction w travels in: the side of w of
    the shape's MediumInterface when it separates two media, else the medium it was in."""
    mi = scene.shape_media[shape]
    if mi[0] == mi[1]:
        return medium
    if wp.dot(w, ng) > 0.0:
        return mi[1]
    return mi[0]


@wp.func
def is_interface(scene: Scene, shape: int) -> bool:
    return scene.mat.kind[scene.shape_material[shape]] == INTERFACE


@wp.struct
class Scattered:
    L: wp.vec3            # next-event estimation's light
    wi: wp.vec3           # the phase-sampled direction
    pdf: float
    rng: wp.uint32


@wp.func
def scattered_path(st: PathState, p: wp.vec3, sm: Scattered) -> PathState:
    """The path after a real scattering at p: its light sample added (one more ray), its next ray
    from p along the phase-sampled direction, whose density MIS weighs what that ray finds."""
    out = st
    out.L = st.L + sm.L
    out.rays = st.rays + 1
    out.prev_pdf = sm.pdf
    out.prev_specular = False
    out.prev_p = p
    out.o = p
    out.d = sm.wi
    return out


class MediaFunctions(NamedTuple):
    shadow: wp.Function     # (scene, o, d, t_max, medium, c, rng) -> Transmitted
    scatter: wp.Function    # (scene, p, wo, medium, c, rng, beta, r_u) -> Scattered
    surface: wp.Function    # (scene, o, d, t_max) -> Hit: the first surface that is not an interface


@lru_cache(maxsize=None)
def media_functions(features: Features) -> MediaFunctions:
    closest = ray_queries(features).closest
    sample_light = light_sampler(*dispatch(features.lights, "sample"))
    light_sampling = features.nee and len(features.lights) > 0

    @wp.func
    def shadow(scene: Scene, o: wp.vec3, d: wp.vec3, t_max: float, medium: int, c: int,
               rng: wp.uint32) -> Transmitted:
        """Transmittance from o to o + t_max d: ratio tracking through each medium on the way,
        crossing interface surfaces (changing medium), 0 at any other surface."""
        res = Transmitted()
        res.T = wp.vec3(1.0)
        res.r = wp.vec3(1.0)
        res.rng = rng
        m = medium
        origin = o
        travelled = float(0.0)
        for _k in range(MAX_CROSSINGS):
            left = t_max - travelled
            hit = closest(scene, origin, d, left)
            seg = left
            if hit.inst >= 0:
                seg = hit.t
            if m >= 0:
                res = ratio_track(scene.media[0], m, origin, d, seg, c, res.rng, res.T, res.r)
                if max3(res.T) <= 0.0:
                    return res
            if hit.inst < 0:
                return res
            shape = scene.geo.inst_shape[hit.inst]
            if not is_interface(scene, shape):
                break
            s = surface_at(scene.geo, hit, scene.shape_flip[shape] != 0)
            m = crossed(scene, shape, s.ng, d, m)
            step = offset_origin(s, d)
            travelled += wp.dot(step - origin, d)
            origin = step
        res.T = wp.vec3(0.0)
        return res

    @wp.func
    def scatter(scene: Scene, p: wp.vec3, wo: wp.vec3, medium: int, c: int, rng: wp.uint32, beta: wp.vec3,
                r_u: wp.vec3) -> Scattered:
        """At a real scattering in ``medium``: one light sample (phase function, transmittance,
        MIS against phase sampling), then a direction sampled from the phase function."""
        res = Scattered()
        res.L = wp.vec3(0.0)
        g = scene.media[0].g[medium]
        state = rng
        if wp.static(light_sampling):
            u_sel = wp.randf(state)
            u_light = wp.vec2(wp.randf(state), wp.randf(state))
            if scene.lights.count > 0:
                ls = sample_light(scene.lights, p, u_sel, u_light)
                if ls.pdf > 0.0 and max3(ls.L) > 0.0:
                    f = hg_phase(wo, ls.wi, g)
                    t_max = ls.dist * (1.0 - 1.0e-4) - ray_epsilon(p)
                    tm = shadow(scene, p, ls.wi, t_max, medium, c, state)
                    state = tm.rng
                    if max3(tm.T) > 0.0:
                        w = float(1.0)
                        if not ls.delta:
                            w = power_heuristic(ls.pdf, f)
                        res.L = wp.cw_mul(wp.cw_mul(beta, ls.L), tm.T) * (f * w / (ls.pdf * mean3(
                            wp.cw_mul(r_u, tm.r))))
        res.wi = hg_sample(wo, g, wp.vec2(wp.randf(state), wp.randf(state)))
        res.pdf = hg_phase(wo, res.wi, g)
        res.rng = state
        return res

    @wp.func
    def surface(scene: Scene, o: wp.vec3, d: wp.vec3, t_max: float) -> Hit:
        """The closest hit that is not an interface (what the AOVs show; t from o)."""
        origin = o
        travelled = float(0.0)
        hit = Hit()
        for k in range(MAX_CROSSINGS + 1):     # one call site: the query is inlined once
            hit = closest(scene, origin, d, t_max - travelled)
            if hit.inst < 0 or k == MAX_CROSSINGS:
                break
            shape = scene.geo.inst_shape[hit.inst]
            if not is_interface(scene, shape):
                break
            s = surface_at(scene.geo, hit, scene.shape_flip[shape] != 0)
            step = offset_origin(s, d)
            travelled += wp.dot(step - origin, d)
            origin = step
        hit.t = hit.t + travelled
        return hit

    return MediaFunctions(shadow, scatter, surface)
