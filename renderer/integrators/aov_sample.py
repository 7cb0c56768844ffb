"""What the AOV pass computes per pixel and per sample (renderer.integrators.aov), shared by its
one-kernel form and its steps (renderer.integrators.aov_steps), so both add the same numbers."""
from __future__ import annotations

from functools import lru_cache
from typing import NamedTuple

import warp as wp

from renderer.camera import generate_ray
from renderer.device.scene import Features, Scene
from renderer.geometry.intersect import Hit, Surface
from renderer.integrators.media_path import media_functions
from renderer.integrators.shading import load_bsdf, shading_functions
from renderer.integrators.visibility import ray_queries
from renderer.materials.selection import choose_material
from renderer.sampling.frames import Frame, to_local
from renderer.sampling.rng import sample_rng


@wp.struct
class CameraSample:
    """One jittered camera ray of the AOV pass and the random stream it continues."""

    o: wp.vec3
    d: wp.vec3
    rng: wp.uint32


@wp.func
def camera_sample(scene: Scene, seed: int, k: int, pixel: int) -> CameraSample:
    """Sample k of the pixel: its own stream (not the render's), a jittered ray through the lens."""
    width = scene.cam.width
    rng = sample_rng(seed ^ 0x5A5A5A5, k, pixel)
    jit = wp.vec2(wp.randf(rng), wp.randf(rng))  # drawn inline: Warp passes rng by value
    ray = generate_ray(scene.cam, float(pixel % width) + jit[0], float(pixel // width) + jit[1],
                       wp.vec2(wp.randf(rng), wp.randf(rng)))
    out = CameraSample()
    out.o = ray.o
    out.d = ray.d
    out.rng = rng
    return out


@wp.func
def camera_depth(scene: Scene, t: float, d: wp.vec3) -> float:
    """Depth as pbrt's: the distance t along d measured along the camera's z axis."""
    cw = scene.cam.to_world
    return t * wp.dot(d, wp.normalize(wp.vec3(cw[0, 2], cw[1, 2], cw[2, 2])))


@wp.func
def pixel_ids(scene: Scene, seen: Hit, pixel: int, material: wp.array(dtype=float),
              instance: wp.array(dtype=float)):
    """The material (a mix's own id) and instance of the surface the pixel's centre sees, -1 none."""
    material[pixel] = -1.0
    instance[pixel] = -1.0
    if seen.inst >= 0:
        material[pixel] = float(scene.shape_material[scene.geo.inst_shape[seen.inst]])
        instance[pixel] = float(seen.inst)


@wp.func
def write_guides(pixel: int, a: wp.vec3, n: wp.vec3, z: float, hits: int, n_samples: int,
                 albedo: wp.array(dtype=wp.vec3), normal: wp.array(dtype=wp.vec3), depth: wp.array(dtype=float)):
    """The sums over the pixel's samples as the guides: mean albedo, unit normal, mean depth of hits."""
    albedo[pixel] = a * (1.0 / float(wp.max(n_samples, 1)))
    ln = wp.length(n)
    if ln > 0.0:
        n = n / ln
    normal[pixel] = n
    depth[pixel] = z / float(wp.max(hits, 1))


class AovFunctions(NamedTuple):
    closest: wp.Function        # (scene, o, d, t_max) -> Hit: the first surface (media: through interfaces)
    material: wp.Function       # (scene, hit, s, d) -> int: the material seen, mixes resolved
    shading_frame: wp.Function  # (scene, m, s) -> Frame
    albedo: wp.Function         # (scene, m, s, frame, d, rng) -> vec3: one BSDF sample's clamped weight


@lru_cache(maxsize=None)
def aov_functions(features: Features) -> AovFunctions:
    """The AOV pass's steps for a scene of ``features`` (a step kernel narrows ``materials``)."""
    shading_frame, _, sample_bsdf = shading_functions(features)
    # in scenes with media, interface surfaces are hit (the path crosses them); the AOVs look through
    closest = media_functions(features).surface if features.media else ray_queries(features).closest
    mixes = features.mix

    @wp.func
    def material_seen(scene: Scene, hit: Hit, s: Surface, d: wp.vec3) -> int:
        m = scene.shape_material[scene.geo.inst_shape[hit.inst]]
        if wp.static(mixes):
            m = choose_material(scene.mat.kind, scene.mat.mix, scene.tex, m, s, -d)
        return m

    @wp.func
    def albedo(scene: Scene, m: int, s: Surface, frame: Frame, d: wp.vec3, rng: wp.uint32) -> wp.vec3:
        b = load_bsdf(scene.mat, scene.tex, scene.spectral, scene.spectral_n, m, s)
        state = rng
        b.wavelength_u = wp.randf(state)
        bs = sample_bsdf(b, to_local(frame, -d), wp.vec3(wp.randf(state), wp.randf(state), wp.randf(state)))
        if bs.pdf > 0.0 and wp.isfinite(bs.weight):
            return wp.vec3(wp.clamp(bs.weight[0], 0.0, 1.0), wp.clamp(bs.weight[1], 0.0, 1.0),
                           wp.clamp(bs.weight[2], 0.0, 1.0))
        return wp.vec3(0.0)

    return AovFunctions(closest, material_seen, shading_frame, albedo)
