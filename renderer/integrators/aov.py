"""Arbitrary output variables at the first visible surface: albedo, shading normal and depth,
the guides a denoiser needs, and the material and instance ids (as pbrt-v4's gbuffer film gives)
so figures and tests can pick out a region of the picture. Rendered after the beauty passes by a
kernel of their own (the CPU's) or, where the render runs the wavefront (GPUs), in steps
(renderer.integrators.aov_steps): the same numbers.

The ids are those of the surface seen through the pixel's centre (not averaged: an id is a label),
-1 where the centre sees no surface: the material's index in the scene description's materials,
and the instance's index in the flattened instance list (file order).

Albedo is the material's directional albedo seen from the camera, estimated as the mean
throughput weight of its own BSDF samples, so every material (present or future) defines it
without extra code; specular-only surfaces report their Fresnel-weighted reflectance."""
from __future__ import annotations

from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from functools import lru_cache

import numpy as np
import warp as wp

from renderer.camera import generate_ray
from renderer.device.kernel_options import KERNEL_OPTIONS
from renderer.device.scene import DeviceScene, Features, Scene
from renderer.geometry.intersect import surface_at
from renderer.integrators.aov_sample import aov_functions, camera_depth, camera_sample, pixel_ids, write_guides
from renderer.integrators.aov_steps import launch_aov_steps

AOV_NAMES = ("albedo", "normal", "depth", "material", "instance")
#: Channel names per AOV in the EXR (layer.channel, as OpenEXR's multi-layer convention).
AOV_CHANNELS = {"albedo": ("R", "G", "B"), "normal": ("X", "Y", "Z"), "depth": ("Z",), "material": ("id",),
                "instance": ("id",)}


@lru_cache(maxsize=None)
def aov_kernel(features: Features) -> wp.Kernel:
    """The AOV pass in one kernel (the CPU's): every sample of a pixel in one thread."""
    f = aov_functions(features)

    @wp.kernel(module="unique", module_options=KERNEL_OPTIONS)
    def first_hit(scene: Scene, seed: int, n_samples: int, row_offset: int, albedo: wp.array(dtype=wp.vec3),
                  normal: wp.array(dtype=wp.vec3), depth: wp.array(dtype=float), material: wp.array(dtype=float),
                  instance: wp.array(dtype=float)):
        width = scene.cam.width
        pixel = row_offset * width + wp.tid()
        centre = generate_ray(scene.cam, float(pixel % width) + 0.5, float(pixel // width) + 0.5, wp.vec2(0.5, 0.5))
        pixel_ids(scene, f.closest(scene, centre.o, centre.d, 1.0e30), pixel, material, instance)
        a = wp.vec3(0.0)
        n = wp.vec3(0.0)
        z = float(0.0)
        hits = int(0)
        for k in range(n_samples):
            cs = camera_sample(scene, seed, k, pixel)
            hit = f.closest(scene, cs.o, cs.d, 1.0e30)
            if hit.inst >= 0:
                s = surface_at(scene.geo, hit, scene.shape_flip[scene.geo.inst_shape[hit.inst]] != 0)
                m = f.material(scene, hit, s, cs.d)
                frame = f.shading_frame(scene, m, s)
                a = a + f.albedo(scene, m, s, frame, cs.d, cs.rng)
                n = n + frame.n
                hits += 1
                z = z + camera_depth(scene, hit.t, cs.d)
        write_guides(pixel, a, n, z, hits, n_samples, albedo, normal, depth)

    return first_hit


def render_aovs(ds: DeviceScene, seed: int, n_samples: int = 16, chunks: Sequence[tuple[int, int]] = (),
                threads: int = 1, steps: bool = False) -> dict[str, np.ndarray]:
    """Albedo (H, W, 3) in [0, 1] (box-filtered over ``n_samples``, 0 for the background), unit
    shading normal (H, W, 3) and camera-space depth (H, W, 1) averaged over the samples that hit
    (both 0 where nothing is hit), and the material and instance ids (H, W, 1) at pixel centres
    (-1: nothing), exact as float32 up to 2^24. ``chunks`` (first row, rows) are launched from
    ``threads`` threads, as the render's passes are (the CPU device runs a launch on one core); each
    pixel's numbers depend on the pixel alone, so the AOVs are the same however the rows are cut.
    ``steps``: the pass in steps (renderer.integrators.aov_steps, what the wavefront launches: GPUs),
    the same numbers."""
    W, H, dev = ds.width, ds.height, ds.device
    out = {"albedo": wp.zeros(W * H, dtype=wp.vec3, device=dev), "normal": wp.zeros(W * H, dtype=wp.vec3, device=dev),
           "depth": wp.zeros(W * H, dtype=float, device=dev), "material": wp.zeros(W * H, dtype=float, device=dev),
           "instance": wp.zeros(W * H, dtype=float, device=dev)}
    kernel = None if steps else aov_kernel(ds.features)

    def launch(chunk: tuple[int, int]) -> None:
        first, rows = chunk
        if steps:
            launch_aov_steps(ds, seed, n_samples, first, rows, out)
        else:
            wp.launch(kernel, dim=rows * W, inputs=[ds.struct, seed, n_samples, first, *out.values()], device=dev)
        wp.synchronize_device(dev)

    with ThreadPoolExecutor(max_workers=max(1, threads)) as pool:
        list(pool.map(launch, chunks or [(0, H)]))
    return {k: v.numpy().reshape(H, W, -1) for k, v in out.items()}
