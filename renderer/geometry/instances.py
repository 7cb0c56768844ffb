"""Instanced triangle meshes on the device: one ``wp.Mesh`` per unique mesh and a top-level
``wp.Bvh`` over instance bounds, so 100k sand grains cost one mesh plus 100k matrices."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import warp as wp


@wp.struct
class Geometry:
    tlas: wp.uint64                          # wp.Bvh over instance world bounds
    mesh_ids: wp.array(dtype=wp.uint64)      # per unique mesh
    mesh_normal_offset: wp.array(dtype=int)  # into normals, -1 if the mesh has none
    mesh_uv_offset: wp.array(dtype=int)      # into uvs, -1 if none
    normals: wp.array(dtype=wp.vec3)
    uvs: wp.array(dtype=wp.vec2)
    inst_mesh: wp.array(dtype=int)
    inst_shape: wp.array(dtype=int)          # index of the ShapeDesc (material, light, orientation)
    inst_to_world: wp.array(dtype=wp.mat44)
    inst_to_object: wp.array(dtype=wp.mat44)


@dataclass
class GeometryData:
    """Host-side owner of every Warp object the :class:`Geometry` struct points into: a struct
    holds raw ids, so the meshes and BVH must stay referenced here for as long as it is used."""

    struct: Geometry
    meshes: list = field(default_factory=list)
    arrays: list = field(default_factory=list)
    tlas: object = None


def build_geometry(meshes: list[tuple[np.ndarray, np.ndarray, np.ndarray | None, np.ndarray | None]],
                   inst_mesh: np.ndarray, inst_shape: np.ndarray, inst_to_world: np.ndarray,
                   device: str) -> GeometryData:
    """Upload meshes (positions, indices, normals|None, uvs|None) and instances (mesh index,
    shape index, (K, 4, 4) object-to-world) to ``device``."""
    data = GeometryData(struct=Geometry())
    normals, uvs, n_off, uv_off = [], [], [], []
    n_count = uv_count = 0
    mesh_lo, mesh_hi = [], []
    for pos, idx, nrm, uv in meshes:
        pos = np.ascontiguousarray(pos, dtype=np.float32)
        m = wp.Mesh(points=wp.array(pos, dtype=wp.vec3, device=device),
                    indices=wp.array(np.ascontiguousarray(idx, dtype=np.int32).reshape(-1), dtype=int, device=device))
        data.meshes.append(m)
        mesh_lo.append(pos.min(axis=0))
        mesh_hi.append(pos.max(axis=0))
        n_off.append(n_count if nrm is not None else -1)
        if nrm is not None:
            normals.append(np.asarray(nrm, dtype=np.float32))
            n_count += len(nrm)
        uv_off.append(uv_count if uv is not None else -1)
        if uv is not None:
            uvs.append(np.asarray(uv, dtype=np.float32))
            uv_count += len(uv)
    to_world = np.ascontiguousarray(inst_to_world, dtype=np.float32).reshape(-1, 4, 4)
    to_object = np.linalg.inv(to_world.astype(np.float64)).astype(np.float32)
    lo, hi = instance_bounds(np.array(mesh_lo), np.array(mesh_hi), np.asarray(inst_mesh), to_world)

    def arr(a, dtype, empty_shape):
        a = np.concatenate(a) if a else np.zeros(empty_shape, dtype=np.float32)
        w = wp.array(a, dtype=dtype, device=device)
        data.arrays.append(w)
        return w

    s = data.struct
    s.mesh_ids = wp.array(np.array([m.id for m in data.meshes], dtype=np.uint64), dtype=wp.uint64, device=device)
    s.mesh_normal_offset = wp.array(np.array(n_off, dtype=np.int32), dtype=int, device=device)
    s.mesh_uv_offset = wp.array(np.array(uv_off, dtype=np.int32), dtype=int, device=device)
    s.normals = arr(normals, wp.vec3, (1, 3))
    s.uvs = arr(uvs, wp.vec2, (1, 2))
    s.inst_mesh = wp.array(np.asarray(inst_mesh, dtype=np.int32), dtype=int, device=device)
    s.inst_shape = wp.array(np.asarray(inst_shape, dtype=np.int32), dtype=int, device=device)
    s.inst_to_world = wp.array(to_world, dtype=wp.mat44, device=device)
    s.inst_to_object = wp.array(to_object, dtype=wp.mat44, device=device)
    data.arrays += [s.mesh_ids, s.mesh_normal_offset, s.mesh_uv_offset, s.inst_mesh, s.inst_shape,
                    s.inst_to_world, s.inst_to_object]
    lo_a = wp.array(lo, dtype=wp.vec3, device=device)
    hi_a = wp.array(hi, dtype=wp.vec3, device=device)
    data.arrays += [lo_a, hi_a]
    data.tlas = wp.Bvh(lo_a, hi_a)
    s.tlas = data.tlas.id
    return data


def instance_bounds(mesh_lo: np.ndarray, mesh_hi: np.ndarray, inst_mesh: np.ndarray,
                     to_world: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """World bounds of each instance: the 8 transformed corners of its mesh's box, slightly padded
    so rays grazing a flat mesh still enter its box."""
    lo, hi = mesh_lo[inst_mesh], mesh_hi[inst_mesh]
    corners = np.stack([np.where(np.array([(c >> k) & 1 for k in range(3)], dtype=bool), hi, lo)
                        for c in range(8)], axis=1)                       # (K, 8, 3)
    w = np.einsum("kij,kcj->kci", to_world[:, :3, :3].astype(np.float64), corners) + to_world[:, None, :3, 3]
    wlo, whi = w.min(axis=1), w.max(axis=1)
    pad = 1e-6 * np.maximum(np.abs(wlo), np.abs(whi)).max(axis=1, keepdims=True) + 1e-7 * (whi - wlo).max(axis=1, keepdims=True) + 1e-9
    return (wlo - pad).astype(np.float32), (whi + pad).astype(np.float32)
