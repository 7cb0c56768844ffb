"""The path-tracing megakernel: one thread per pixel, a bounded path loop, next-event estimation
with MIS against BSDF sampling, and Russian roulette.

``integrator_kernel(features, independent)`` builds (once per distinct :class:`Features`) a kernel
that only contains the material types, light types and bump mapping the scene uses, so a
diffuse-only scene compiles and runs the same code however many materials the renderer learns.
With ``independent`` the path draws its numbers in order from one RNG stream (the independent
sampler); otherwise every use asks the scene's sampler for its own dimension in the order
``renderer.sampling.samplers`` documents. The steps of the loop live in
:mod:`renderer.integrators.vertex`, shared with the wavefront integrator; the light sample's shadow
ray is traced here, at once, after the vertex is shaded. With media (``Features.media``, pbrt-v4's
``volpath``) the loop also tracks the path through the medium it is in, crosses ``interface``
surfaces and weighs light by the channels' mean density (:mod:`renderer.integrators.media_path`).
"""
from __future__ import annotations

from functools import lru_cache

import warp as wp

from renderer.device.kernel_options import KERNEL_OPTIONS
from renderer.device.scene import Features, Scene
from renderer.geometry.intersect import surface_at
from renderer.geometry.offsets import offset_origin
from renderer.integrators.media_path import crossed, is_interface, media_functions, scattered_path, start_medium
from renderer.integrators.subsurface import Exit
from renderer.integrators.vertex import path_functions, scatter_function
from renderer.integrators.visibility import ray_queries
from renderer.media.tracking import ABSORBED, SCATTERED, delta_track
from renderer.vecmath import max3, mean3
from renderer.sampling.samplers import SamplerParams


@lru_cache(maxsize=None)
def integrator_kernel(features: Features, independent: bool = False) -> wp.Kernel:
    start, arrive, record = path_functions(features, independent)
    scatter = scatter_function(features, independent)
    closest, blocked, transmitted = ray_queries(features)
    thin_slabs = features.thin_slabs
    media = features.media
    in_medium = media_functions(features)

    @wp.kernel(module="unique", module_options=KERNEL_OPTIONS)
    def integrate(scene: Scene, smp: SamplerParams, seed: int, sample_index: int, row_offset: int, max_depth: int,
                  rr_depth: int,
                  film: wp.array(dtype=wp.vec3d), bad_samples: wp.array(dtype=int),
                  ray_count: wp.array(dtype=wp.int64)):
        pixel = row_offset * scene.cam.width + wp.tid()
        begun = start(scene, smp, seed, sample_index, pixel)
        ps = begun.sample
        st = begun.path
        if wp.static(media):
            ms = start_medium(scene, seed, sample_index, pixel)
        rr_mean = float(1.0)            # the channels' mean path density (media; 1 without)
        while True:
            hit = closest(scene, st.o, st.d, 1.0e30)
            st.rays = st.rays + 1
            if wp.static(media):
                # the next event in the medium before the surface (renderer.media.tracking)
                if ms.medium >= 0:
                    t_hit = float(1.0e30)
                    if hit.inst >= 0:
                        t_hit = hit.t
                    tr = delta_track(scene.media[0], ms.medium, st.o, st.d, t_hit, ms.c, ms.rng, st.beta, ms.r_u,
                                     st.L, st.depth < max_depth)
                    ms.rng = tr.rng
                    st.beta = tr.beta
                    ms.r_u = tr.r_u
                    st.L = tr.L
                    if tr.event == ABSORBED:
                        break
                    if tr.event == SCATTERED:
                        if st.depth >= max_depth:
                            break
                        st.depth = st.depth + 1
                        sm = in_medium.scatter(scene, tr.p, -st.d, ms.medium, ms.c, ms.rng, st.beta, ms.r_u)
                        ms.rng = sm.rng
                        st = scattered_path(st, tr.p, sm)
                        continue
                rr_mean = mean3(ms.r_u)
                beta = st.beta
                st.beta = beta / rr_mean       # light found now is weighted over the channels' mean
            ar = arrive(scene, st, hit, max_depth)
            st = ar.path
            if wp.static(media):
                st.beta = beta
                if hit.inst >= 0:
                    shape = scene.geo.inst_shape[hit.inst]
                    if is_interface(scene, shape):      # a boundary between media: cross it, no bounce
                        s = surface_at(scene.geo, hit, scene.shape_flip[shape] != 0)
                        ms.medium = crossed(scene, shape, s.ng, st.d, ms.medium)
                        st.o = offset_origin(s, st.d)
                        continue
            if not ar.shade:
                break
            sc = scatter(scene, smp, ps, st, hit, ar.s, ar.m, rr_depth, rr_mean, Exit())
            st = sc.path
            if sc.shadow.on:
                st.rays = st.rays + 1
                if wp.static(media):
                    # transmittance through media and interfaces (renderer.integrators.media_path)
                    shape = scene.geo.inst_shape[hit.inst]
                    tm = in_medium.shadow(scene, sc.shadow.o, sc.shadow.d, sc.shadow.t_max,
                                          crossed(scene, shape, sc.ng, sc.shadow.d, ms.medium), ms.c, ms.rng)
                    ms.rng = tm.rng
                    if max3(tm.T) > 0.0:
                        st.L = st.L + wp.cw_mul(sc.shadow.L, tm.T) / mean3(wp.cw_mul(ms.r_u, tm.r))
                elif wp.static(thin_slabs):     # through thin lenses (renderer.integrators.thin_slab)
                    st.L = st.L + wp.cw_mul(sc.shadow.L, transmitted(scene, sc.shadow.o, sc.shadow.d,
                                                                     sc.shadow.t_max))
                elif not blocked(scene, sc.shadow.o, sc.shadow.d, sc.shadow.t_max):
                    st.L = st.L + sc.shadow.L
            if not sc.alive:
                break
            if wp.static(media):
                ms.medium = crossed(scene, scene.geo.inst_shape[hit.inst], sc.ng, st.d, ms.medium)
        record(scene, st, pixel, film, bad_samples, ray_count)

    return integrate
