"""Arbitrary output variables at the first visible surface: albedo, shading normal and depth,
the guides a denoiser needs, and the material and instance ids (as pbrt-v4's gbuffer film gives)
so figures and tests can pick out a region of the picture. Rendered by their own small kernel
after the beauty passes.

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
from renderer.integrators.media_path import media_functions
from renderer.integrators.shading import load_bsdf, shading_functions
from renderer.integrators.visibility import ray_queries
from renderer.materials.selection import choose_material
from renderer.sampling.frames import to_local
from renderer.sampling.rng import sample_rng

AOV_NAMES = ("albedo", "normal", "depth", "material", "instance")
#: Channel names per AOV in the EXR (layer.channel, as OpenEXR's multi-layer convention).
AOV_CHANNELS = {"albedo": ("R", "G", "B"), "normal": ("X", "Y", "Z"), "depth": ("Z",), "material": ("id",),
                "instance": ("id",)}


@lru_cache(maxsize=None)
def aov_kernel(features: Features) -> wp.Kernel:
    shading_frame, _, sample_bsdf = shading_functions(features)
    # in scenes with media, interface surfaces are hit (the path crosses them); the AOVs look through
    closest = media_functions(features).surface if features.media else ray_queries(features).closest
    mixes = features.mix

    @wp.kernel(module="unique", module_options=KERNEL_OPTIONS)
    def first_hit(scene: Scene, seed: int, n_samples: int, row_offset: int, albedo: wp.array(dtype=wp.vec3),
                  normal: wp.array(dtype=wp.vec3), depth: wp.array(dtype=float), material: wp.array(dtype=float),
                  instance: wp.array(dtype=float)):
        width = scene.cam.width
        pixel = row_offset * width + wp.tid()
        px = pixel % width
        py = pixel // width
        centre = generate_ray(scene.cam, float(px) + 0.5, float(py) + 0.5, wp.vec2(0.5, 0.5))
        seen = closest(scene, centre.o, centre.d, 1.0e30)
        material[pixel] = -1.0
        instance[pixel] = -1.0
        if seen.inst >= 0:
            material[pixel] = float(scene.shape_material[scene.geo.inst_shape[seen.inst]])   # a mix's own id
            instance[pixel] = float(seen.inst)
        a = wp.vec3(0.0)
        n = wp.vec3(0.0)
        z = float(0.0)
        hits = int(0)
        for k in range(n_samples):
            rng = sample_rng(seed ^ 0x5A5A5A5, k, pixel)
            jit = wp.vec2(wp.randf(rng), wp.randf(rng))  # drawn inline: Warp passes rng by value
            ray = generate_ray(scene.cam, float(px) + jit[0], float(py) + jit[1],
                               wp.vec2(wp.randf(rng), wp.randf(rng)))
            hit = closest(scene, ray.o, ray.d, 1.0e30)
            if hit.inst >= 0:
                shape = scene.geo.inst_shape[hit.inst]
                s = surface_at(scene.geo, hit, scene.shape_flip[shape] != 0)
                m = scene.shape_material[shape]
                if wp.static(mixes):
                    m = choose_material(scene.mat.kind, scene.mat.mix, scene.tex, m, s, -ray.d)
                b = load_bsdf(scene.mat, scene.tex, scene.spectral, scene.spectral_n, m, s)
                b.wavelength_u = wp.randf(rng)
                frame = shading_frame(scene, m, s)
                wo_l = to_local(frame, -ray.d)
                bs = sample_bsdf(b, wo_l, wp.vec3(wp.randf(rng), wp.randf(rng), wp.randf(rng)))
                if bs.pdf > 0.0 and wp.isfinite(bs.weight):
                    a = a + wp.vec3(wp.clamp(bs.weight[0], 0.0, 1.0), wp.clamp(bs.weight[1], 0.0, 1.0),
                                    wp.clamp(bs.weight[2], 0.0, 1.0))
                n = n + frame.n
                hits += 1
                # depth as pbrt's: distance along the camera's z axis
                cw = scene.cam.to_world
                fwd = wp.normalize(wp.vec3(cw[0, 2], cw[1, 2], cw[2, 2]))
                z = z + hit.t * wp.dot(ray.d, fwd)
        inv = 1.0 / float(wp.max(n_samples, 1))
        albedo[pixel] = a * inv
        ln = wp.length(n)
        if ln > 0.0:
            n = n / ln
        normal[pixel] = n
        depth[pixel] = z / float(wp.max(hits, 1))

    return first_hit


def render_aovs(ds: DeviceScene, seed: int, n_samples: int = 16,
                chunks: Sequence[tuple[int, int]] = (), threads: int = 1) -> dict[str, np.ndarray]:
    """Albedo (H, W, 3) in [0, 1] (box-filtered over ``n_samples``, 0 for the background), unit
    shading normal (H, W, 3) and camera-space depth (H, W, 1) averaged over the samples that hit
    (both 0 where nothing is hit), and the material and instance ids (H, W, 1) at pixel centres
    (-1: nothing), exact as float32 up to 2^24. ``chunks`` (first row, rows) are launched from
    ``threads`` threads, as the render's passes are (the CPU device runs a launch on one core); each
    pixel's numbers depend on the pixel alone, so the AOVs are the same however the rows are cut."""
    W, H, dev = ds.width, ds.height, ds.device
    out = {"albedo": wp.zeros(W * H, dtype=wp.vec3, device=dev), "normal": wp.zeros(W * H, dtype=wp.vec3, device=dev),
           "depth": wp.zeros(W * H, dtype=float, device=dev), "material": wp.zeros(W * H, dtype=float, device=dev),
           "instance": wp.zeros(W * H, dtype=float, device=dev)}
    kernel = aov_kernel(ds.features)

    def launch(chunk: tuple[int, int]) -> None:
        first, rows = chunk
        wp.launch(kernel, dim=rows * W, inputs=[ds.struct, seed, n_samples, first, *out.values()], device=dev)
        wp.synchronize_device(dev)

    with ThreadPoolExecutor(max_workers=max(1, threads)) as pool:
        list(pool.map(launch, chunks or [(0, H)]))
    return {k: v.numpy().reshape(H, W, -1) for k, v in out.items()}
