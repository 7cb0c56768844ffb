"""The path-tracing megakernel: one thread per pixel, a bounded path loop, next-event estimation
with MIS against BSDF sampling, and Russian roulette.

``integrator_kernel(features, independent)`` builds (once per distinct :class:`Features`) a kernel
that only contains the material types, light types and bump mapping the scene uses, so a
diffuse-only scene compiles and runs the same code however many materials the renderer learns.
With ``independent`` the path draws its numbers in order from one RNG stream (the independent
sampler); otherwise every use asks the scene's sampler for its own dimension in the order
``renderer.sampling.samplers`` documents. The steps of the loop live in
:mod:`renderer.integrators.vertex`, shared with the wavefront integrator; the light sample's shadow
ray is traced here, at once, after the vertex is shaded.
"""
from __future__ import annotations

from functools import lru_cache

import warp as wp

from renderer.device.kernel_options import KERNEL_OPTIONS
from renderer.device.scene import Features, Scene
from renderer.integrators.vertex import path_functions, scatter_function
from renderer.integrators.visibility import ray_queries
from renderer.sampling.samplers import SamplerParams


@lru_cache(maxsize=None)
def integrator_kernel(features: Features, independent: bool = False) -> wp.Kernel:
    start, arrive, record = path_functions(features, independent)
    scatter = scatter_function(features, independent)
    closest, blocked = ray_queries(features)

    @wp.kernel(module="unique", module_options=KERNEL_OPTIONS)
    def integrate(scene: Scene, smp: SamplerParams, seed: int, sample_index: int, row_offset: int, max_depth: int,
                  rr_depth: int,
                  film: wp.array(dtype=wp.vec3d), bad_samples: wp.array(dtype=int),
                  ray_count: wp.array(dtype=wp.int64)):
        pixel = row_offset * scene.cam.width + wp.tid()
        begun = start(scene, smp, seed, sample_index, pixel)
        ps = begun.sample
        st = begun.path
        while True:
            hit = closest(scene, st.o, st.d, 1.0e30)
            st.rays = st.rays + 1
            ar = arrive(scene, st, hit, max_depth)
            st = ar.path
            if not ar.shade:
                break
            sc = scatter(scene, smp, ps, st, hit, ar.s, ar.m, rr_depth)
            st = sc.path
            if sc.shadow.on:
                st.rays = st.rays + 1
                if not blocked(scene, sc.shadow.o, sc.shadow.d, sc.shadow.t_max):
                    st.L = st.L + sc.shadow.L
            if not sc.alive:
                break
        record(scene, st, pixel, film, bad_samples, ray_count)

    return integrate
