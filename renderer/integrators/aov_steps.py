"""The AOV pass in steps, for GPUs: the one-kernel pass (:mod:`renderer.integrators.aov`) holds every
material's BSDF sampling in one thread, too much for a GPU's registers, so here (the wavefront's
design) per sample ``aov_hits`` finds each pixel's first surface, adds its shading normal and depth
and queues the pixel by its material's shader; in scenes with bump maps ``aov_bump`` (the
wavefront's bump step) gives the pixels whose material has one their bump-mapped shading frame and
normal, so ``aov_hits`` holds no texture program for it (with the cut-outs' and the mixes' as well,
the every-feature ``aov_hits`` had a 1,136 B frame; 880 B without it: docs/gpu.md); one
``aov_<kind>`` per shader (``shaders``: thin films that walk apart) samples the BSDF and adds the
clamped weight; ``aov_guides`` writes the guides and the ids. The host launches the samples in
order, so each pixel's sums are added in the one-kernel order, with the same functions: the same
bits (tested on the CPU)."""
from __future__ import annotations

import dataclasses
from functools import lru_cache

import warp as wp

from renderer.camera import generate_ray
from renderer.device.scene import DeviceScene, Features, Scene
from renderer.geometry.intersect import Hit, surface_at
from renderer.integrators.aov_sample import aov_functions, camera_depth, camera_sample, pixel_ids, write_guides
from renderer.integrators.shader_queues import Shader, queue_chooser, queues_of_kinds, shader_features, shaders
from renderer.integrators.wavefront import step_kernel
from renderer.sampling.frames import Frame


@wp.struct
class AovSteps:
    """Per pixel of a launch: the sums over its samples, and its current sample's first hit."""

    a: wp.array(dtype=wp.vec3)              # the albedo samples' sum
    n: wp.array(dtype=wp.vec3)              # the shading normals' sum
    z: wp.array(dtype=float)                # the depths' sum
    hits: wp.array(dtype=int)               # samples that hit a surface
    hit: wp.array(dtype=Hit)
    material: wp.array(dtype=int)
    frame: wp.array(dtype=Frame)
    d: wp.array(dtype=wp.vec3)
    rng: wp.array(dtype=wp.uint32)
    queue: wp.array2d(dtype=int)            # per shader, pixel indices; then the bump step's (bump maps)
    queued: wp.array(dtype=int)
    queue_of_kind: wp.array(dtype=int)


def aov_steps(n: int, shader_names: list[str], bump: bool, device: str) -> AovSteps:
    """Buffers for ``n`` pixels, the shaders named (``aov_<kind>[_walk]``, in queue order) and with
    ``bump`` the bump step's queue (the last)."""
    st = AovSteps()
    for name, dtype in (("a", wp.vec3), ("n", wp.vec3), ("z", float), ("hits", int), ("hit", Hit),
                        ("material", int), ("frame", Frame), ("d", wp.vec3), ("rng", wp.uint32)):
        setattr(st, name, wp.zeros(n, dtype=dtype, device=device))
    st.queue = wp.zeros((len(shader_names) + bump, n), dtype=int, device=device)
    st.queued = wp.zeros(len(shader_names) + bump, dtype=int, device=device)
    st.queue_of_kind = wp.array(queues_of_kinds(shader_names, first=0), dtype=int, device=device)
    return st


@lru_cache(maxsize=None)
def aov_hits_kernel(features: Features) -> wp.Kernel:
    # no BSDF here (the shaders' kernels), nor bump maps (the bump step's)
    f = aov_functions(dataclasses.replace(features, materials=(), bump=False))
    shader_queue = queue_chooser(features, first=0)
    bump = features.bump
    bumps = len(shaders(features))          # the bump step's queue

    def aov_hits(scene: Scene, seed: int, k: int, row_offset: int, st: AovSteps):
        i = wp.tid()
        cs = camera_sample(scene, seed, k, row_offset * scene.cam.width + i)
        hit = f.closest(scene, cs.o, cs.d, 1.0e30)
        if hit.inst >= 0:
            s = surface_at(scene.geo, hit, scene.shape_flip[scene.geo.inst_shape[hit.inst]] != 0)
            m = f.material(scene, hit, s, cs.d)
            st.hits[i] = st.hits[i] + 1
            st.z[i] = st.z[i] + camera_depth(scene, hit.t, cs.d)
            st.hit[i] = hit
            st.material[i] = m
            st.d[i] = cs.d
            st.rng[i] = cs.rng
            q = shader_queue(scene, st.queue_of_kind, m)
            st.queue[q, wp.atomic_add(st.queued, q, 1)] = i
            if wp.static(bump):
                if scene.mat.bump[m] >= 0:      # its frame and normal from the bump step
                    st.queue[bumps, wp.atomic_add(st.queued, bumps, 1)] = i
                    return
            frame = f.shading_frame(scene, m, s)
            st.n[i] = st.n[i] + frame.n
            st.frame[i] = frame

    return step_kernel(aov_hits)


@lru_cache(maxsize=None)
def aov_bump_kernel(features: Features) -> wp.Kernel:
    """The bump step (scenes with bump maps, after ``aov_hits``): the bump-mapped shading frame of
    the pixels whose material has a bump map, its normal added, the frame kept for the shaders."""
    shading_frame = aov_functions(dataclasses.replace(features, materials=())).shading_frame
    bumps = len(shaders(features))

    def aov_bump(scene: Scene, st: AovSteps):
        i = st.queue[bumps, wp.tid()]
        hit = st.hit[i]
        s = surface_at(scene.geo, hit, scene.shape_flip[scene.geo.inst_shape[hit.inst]] != 0)
        frame = shading_frame(scene, st.material[i], s)
        st.n[i] = st.n[i] + frame.n
        st.frame[i] = frame

    return step_kernel(aov_bump)


@lru_cache(maxsize=None)
def aov_shader_kernel(features: Features, shader: Shader, queue: int) -> wp.Kernel:
    albedo = aov_functions(dataclasses.replace(shader_features(features, shader), materials=(shader.kind,))).albedo

    def aov_shade(scene: Scene, st: AovSteps):
        i = st.queue[queue, wp.tid()]
        hit = st.hit[i]
        s = surface_at(scene.geo, hit, scene.shape_flip[scene.geo.inst_shape[hit.inst]] != 0)
        st.a[i] = st.a[i] + albedo(scene, st.material[i], s, st.frame[i], st.d[i], st.rng[i])

    return step_kernel(aov_shade)


@lru_cache(maxsize=None)
def aov_guides_kernel(features: Features) -> wp.Kernel:
    closest = aov_functions(dataclasses.replace(features, materials=())).closest

    def aov_guides(scene: Scene, n_samples: int, row_offset: int, st: AovSteps, albedo: wp.array(dtype=wp.vec3),
                   normal: wp.array(dtype=wp.vec3), depth: wp.array(dtype=float), material: wp.array(dtype=float),
                   instance: wp.array(dtype=float)):
        i = wp.tid()
        width = scene.cam.width
        pixel = row_offset * width + i
        centre = generate_ray(scene.cam, float(pixel % width) + 0.5, float(pixel // width) + 0.5, wp.vec2(0.5, 0.5))
        pixel_ids(scene, closest(scene, centre.o, centre.d, 1.0e30), pixel, material, instance)
        write_guides(pixel, st.a[i], st.n[i], st.z[i], st.hits[i], n_samples, albedo, normal, depth)

    return step_kernel(aov_guides)


def aov_step_kernels(features: Features) -> dict[str, wp.Kernel]:
    """By name, in launch order: the AOV pass's kernels for a scene of ``features``."""
    kernels = {"aov_hits": aov_hits_kernel(features)}
    if features.bump:
        kernels["aov_bump"] = aov_bump_kernel(features)
    for q, shader in enumerate(shaders(features)):
        kernels["aov_" + shader.name.removeprefix("shade_")] = aov_shader_kernel(features, shader, q)
    kernels["aov_guides"] = aov_guides_kernel(features)
    return kernels


def launch_aov_steps(ds: DeviceScene, seed: int, n_samples: int, first_row: int, rows: int,
                     out: dict[str, wp.array]) -> None:
    """The AOVs of rows ``first_row ...`` into ``out`` (render_aovs' arrays), sample by sample."""
    kernels, dev = aov_step_kernels(ds.features), ds.device
    shading = {name: k for name, k in kernels.items() if name not in ("aov_hits", "aov_bump", "aov_guides")}
    n = rows * ds.width
    bump = "aov_bump" in kernels
    st = aov_steps(n, list(shading), bump, dev)
    for k in range(n_samples):
        st.queued.zero_()
        wp.launch(kernels["aov_hits"], dim=n, inputs=[ds.struct, seed, k, first_row, st], device=dev)
        queued = st.queued.numpy()
        if bump and queued[-1] > 0:     # the frames the shaders read
            wp.launch(kernels["aov_bump"], dim=int(queued[-1]), inputs=[ds.struct, st], device=dev)
        for kernel, count in zip(shading.values(), queued):
            if count > 0:
                wp.launch(kernel, dim=int(count), inputs=[ds.struct, st], device=dev)
    wp.launch(kernels["aov_guides"], dim=n, inputs=[ds.struct, n_samples, first_row, st, *out.values()], device=dev)
