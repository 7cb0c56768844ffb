"""Closest-hit distances for batches of rays from numpy, through the renderer's own intersector.

Used by the asset generator (is a grain visible from the camera?) and by tests that compare the
BVH against brute force, for Warp's BVH (what the renderer uses) and for the experimental wide BVH.
"""
from __future__ import annotations

import numpy as np
import warp as wp

from renderer.device.runtime import init_warp
from renderer.geometry.instances import Geometry, build_geometry
from renderer.geometry.intersect import intersect, occluded
from renderer.geometry.wide_scene import WideBvh, build_wide_bvh
from renderer.geometry.wide_traverse import wide_intersect, wide_occluded

wp.set_module_options({"enable_backward": False})   # nothing differentiates these kernels


@wp.kernel
def _cast(geo: Geometry, origins: wp.array(dtype=wp.vec3), dirs: wp.array(dtype=wp.vec3), t_max: float,
          t_out: wp.array(dtype=float), inst_out: wp.array(dtype=int), face_out: wp.array(dtype=int)):
    i = wp.tid()
    h = intersect(geo, origins[i], dirs[i], t_max)
    t_out[i] = wp.where(h.inst >= 0, h.t, 1.0e38)
    inst_out[i] = h.inst
    face_out[i] = wp.where(h.inst >= 0, h.face, -1)


@wp.kernel
def _cast_wide(inst_mesh: wp.array(dtype=int), to_object: wp.array(dtype=wp.mat44), bvh: WideBvh, origins: wp.array(dtype=wp.vec3), dirs: wp.array(dtype=wp.vec3),
               t_max: float, t_out: wp.array(dtype=float), inst_out: wp.array(dtype=int),
               face_out: wp.array(dtype=int)):
    i = wp.tid()
    h = wide_intersect(bvh, inst_mesh, to_object, origins[i], dirs[i], t_max)
    t_out[i] = wp.where(h.inst >= 0, h.t, 1.0e38)
    inst_out[i] = h.inst
    face_out[i] = wp.where(h.inst >= 0, h.face, -1)


@wp.kernel
def _occluded(geo: Geometry, origins: wp.array(dtype=wp.vec3), dirs: wp.array(dtype=wp.vec3), t_max: float,
              out: wp.array(dtype=int)):
    i = wp.tid()
    out[i] = wp.where(occluded(geo, origins[i], dirs[i], t_max), 1, 0)


@wp.kernel
def _occluded_wide(inst_mesh: wp.array(dtype=int), to_object: wp.array(dtype=wp.mat44), bvh: WideBvh, origins: wp.array(dtype=wp.vec3), dirs: wp.array(dtype=wp.vec3),
                   t_max: float, out: wp.array(dtype=int)):
    i = wp.tid()
    out[i] = wp.where(wide_occluded(bvh, inst_mesh, to_object, origins[i], dirs[i], t_max), 1, 0)


def _upload(meshes, inst_mesh, inst_to_world, origins, directions, traversal: str, device: str):
    """The rays, and the kernel inputs that describe the scene: Warp's geometry struct, or for
    ``traversal="wide"`` the instance arrays and the wide BVH (which, unlike ``wp.Mesh``, also
    takes meshes without triangles)."""
    if traversal not in ("warp", "wide"):
        raise ValueError(f'traversal must be "warp" or "wide", not {traversal!r}')
    init_warp()
    o = wp.array(np.ascontiguousarray(origins, dtype=np.float32), dtype=wp.vec3, device=device)
    d = wp.array(np.ascontiguousarray(directions, dtype=np.float32), dtype=wp.vec3, device=device)
    if traversal == "warp":
        data = build_geometry([(v, f, None, None) for v, f in meshes], np.asarray(inst_mesh),
                              np.zeros(len(inst_mesh), dtype=np.int32), inst_to_world, device)
        return [data.struct], data, o, d
    wide = build_wide_bvh(meshes, inst_mesh, inst_to_world, device)
    to_world = np.asarray(inst_to_world, dtype=np.float32).reshape(-1, 4, 4)
    im = wp.array(np.asarray(inst_mesh, dtype=np.int32), dtype=int, device=device)
    to_object = wp.array(np.linalg.inv(to_world.astype(np.float64)).astype(np.float32), dtype=wp.mat44, device=device)
    return [im, to_object, wide.struct], wide, o, d


def cast_rays_instanced(meshes: list[tuple[np.ndarray, np.ndarray]], inst_mesh: np.ndarray,
                        inst_to_world: np.ndarray, origins: np.ndarray, directions: np.ndarray,
                        max_t: float = np.inf, device: str = "cpu",
                        traversal: str = "warp") -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(t, instance, face) of the closest hit of each ray against instanced meshes; t = inf,
    instance = face = -1 where a ray misses. Directions must be unit length."""
    scene, _owner, o, d = _upload(meshes, inst_mesh, inst_to_world, origins, directions, traversal, device)
    n = len(origins)
    t = wp.empty(n, dtype=float, device=device)
    inst = wp.empty(n, dtype=int, device=device)
    face = wp.empty(n, dtype=int, device=device)
    tm = float(min(max_t, 1e38))
    kernel = _cast if traversal == "warp" else _cast_wide
    wp.launch(kernel, dim=n, inputs=[*scene, o, d, tm, t, inst, face], device=device)
    t_np = t.numpy()
    t_np[t_np >= 1e38] = np.inf
    return t_np, inst.numpy(), face.numpy()


def occluded_rays_instanced(meshes: list[tuple[np.ndarray, np.ndarray]], inst_mesh: np.ndarray,
                            inst_to_world: np.ndarray, origins: np.ndarray, directions: np.ndarray,
                            max_t: float, device: str = "cpu", traversal: str = "warp") -> np.ndarray:
    """Whether each ray meets anything before ``max_t`` (the shadow-ray query)."""
    scene, _owner, o, d = _upload(meshes, inst_mesh, inst_to_world, origins, directions, traversal, device)
    out = wp.empty(len(origins), dtype=int, device=device)
    tm = float(min(max_t, 1e38))
    kernel = _occluded if traversal == "warp" else _occluded_wide
    wp.launch(kernel, dim=len(origins), inputs=[*scene, o, d, tm, out], device=device)
    return out.numpy().astype(bool)


def cast_rays(vertices: np.ndarray, faces: np.ndarray, origins: np.ndarray, directions: np.ndarray,
              max_t: float = np.inf, device: str = "cpu") -> np.ndarray:
    """Closest-hit distance of each unit-direction ray against one mesh; inf where it misses."""
    t, _, _ = cast_rays_instanced([(vertices, faces)], np.zeros(1, dtype=np.int32), np.eye(4)[None],
                                  origins, directions, max_t, device)
    return t
