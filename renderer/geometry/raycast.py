"""Closest-hit distances for batches of rays from numpy, through the renderer's own intersector.

Used by the asset generator (is a grain visible from the camera?) and by tests that compare the
BVH against brute force.
"""
from __future__ import annotations

import numpy as np
import warp as wp

from renderer.device.runtime import init_warp
from renderer.geometry.instances import Geometry, build_geometry
from renderer.geometry.intersect import intersect

wp.set_module_options({"enable_backward": False})   # nothing differentiates these kernels


@wp.kernel
def _cast(geo: Geometry, origins: wp.array(dtype=wp.vec3), dirs: wp.array(dtype=wp.vec3), t_max: float,
          t_out: wp.array(dtype=float), inst_out: wp.array(dtype=int), face_out: wp.array(dtype=int)):
    i = wp.tid()
    h = intersect(geo, origins[i], dirs[i], t_max)
    t_out[i] = wp.where(h.inst >= 0, h.t, 1.0e38)
    inst_out[i] = h.inst
    face_out[i] = wp.where(h.inst >= 0, h.face, -1)


def _upload(meshes, inst_mesh, inst_to_world, origins, directions, device: str):
    """The rays, and Warp's geometry struct of the instanced meshes (kept alive by the returned owner)."""
    init_warp()
    o = wp.array(np.ascontiguousarray(origins, dtype=np.float32), dtype=wp.vec3, device=device)
    d = wp.array(np.ascontiguousarray(directions, dtype=np.float32), dtype=wp.vec3, device=device)
    data = build_geometry([(v, f, None, None) for v, f in meshes], np.asarray(inst_mesh),
                          np.zeros(len(inst_mesh), dtype=np.int32), inst_to_world, device)
    return data.struct, data, o, d


def cast_rays_instanced(meshes: list[tuple[np.ndarray, np.ndarray]], inst_mesh: np.ndarray,
                        inst_to_world: np.ndarray, origins: np.ndarray, directions: np.ndarray,
                        max_t: float = np.inf, device: str = "cpu") -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(t, instance, face) of the closest hit of each ray against instanced meshes; t = inf,
    instance = face = -1 where a ray misses. Directions must be unit length."""
    scene, _owner, o, d = _upload(meshes, inst_mesh, inst_to_world, origins, directions, device)
    n = len(origins)
    t = wp.empty(n, dtype=float, device=device)
    inst = wp.empty(n, dtype=int, device=device)
    face = wp.empty(n, dtype=int, device=device)
    tm = float(min(max_t, 1e38))
    wp.launch(_cast, dim=n, inputs=[scene, o, d, tm, t, inst, face], device=device)
    t_np = t.numpy()
    t_np[t_np >= 1e38] = np.inf
    return t_np, inst.numpy(), face.numpy()


def cast_rays(vertices: np.ndarray, faces: np.ndarray, origins: np.ndarray, directions: np.ndarray,
              max_t: float = np.inf, device: str = "cpu") -> np.ndarray:
    """Closest-hit distance of each unit-direction ray against one mesh; inf where it misses."""
    t, _, _ = cast_rays_instanced([(vertices, faces)], np.zeros(1, dtype=np.int32), np.eye(4)[None],
                                  origins, directions, max_t, device)
    return t
