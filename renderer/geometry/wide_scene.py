"""The two-level wide BVH on the device: a 4-wide tree over instance boxes (top level) and one
4-wide tree per unique mesh (bottom level), all bottom trees in one node array, with each leaf's
triangles stored in leaf order so a leaf reads consecutive vertices. Experimental, not used by
the renderer (docs/traversal.md)."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import warp as wp

from renderer.geometry.instances import instance_bounds
from renderer.geometry.wide_bvh import STACK_SIZE, WIDTH, WideTree, build_wide

vec_w = wp.types.vector(length=WIDTH, dtype=float)
vec_wi = wp.types.vector(length=WIDTH, dtype=wp.int32)


@wp.struct
class WideNode:
    """Four children: their boxes as six float4 rows (one per axis and side) and their codes."""

    lox: vec_w
    loy: vec_w
    loz: vec_w
    hix: vec_w
    hiy: vec_w
    hiz: vec_w
    child: vec_wi


@wp.struct
class WideBvh:
    tlas: wp.array(dtype=WideNode)
    tlas_root: int                           # -1 when no instance has a triangle
    tlas_inst: wp.array(dtype=int)           # instance index of each top-level leaf entry
    nodes: wp.array(dtype=WideNode)          # every mesh's bottom-level nodes, codes absolute
    mesh_root: wp.array(dtype=int)           # per unique mesh, -1 for a mesh without triangles
    tri_a: wp.array(dtype=wp.vec3)           # triangle vertices in leaf order (object space)
    tri_b: wp.array(dtype=wp.vec3)
    tri_c: wp.array(dtype=wp.vec3)
    tri_face: wp.array(dtype=int)            # the triangle's index in its mesh


@dataclass
class WideBvhData:
    """Host owner of the arrays a :class:`WideBvh` points into."""

    struct: WideBvh
    arrays: list = field(default_factory=list)


def _pack(tree: WideTree, node_base: int, prim_base: int) -> np.ndarray:
    """The tree's rows as a structured array matching :class:`WideNode`, with inner-node codes
    moved by ``node_base`` and leaf starts by ``prim_base``."""
    rows = np.zeros(len(tree.child), dtype=WideNode.numpy_dtype())
    for k, name in enumerate(("lox", "loy", "loz")):
        rows[name] = tree.lo[:, k, :]
    for k, name in enumerate(("hix", "hiy", "hiz")):
        rows[name] = tree.hi[:, k, :]
    c = tree.child.astype(np.int64)
    rows["child"] = np.where(c >= 0, c + node_base, c - 16 * prim_base)
    return rows


def build_wide_bvh(meshes: list[tuple[np.ndarray, np.ndarray]], inst_mesh: np.ndarray,
                   inst_to_world: np.ndarray, device: str) -> WideBvhData:
    """Upload the two-level tree for meshes (positions, (F, 3) indices) and instances (mesh
    index, (K, 4, 4) object-to-world). Instances of meshes without triangles are left out of the
    top level."""
    rows, roots, tri, faces = [], [], [], []
    n_nodes = n_prims = 0
    for pos, idx in meshes:
        idx = np.asarray(idx, dtype=np.int64).reshape(-1, 3)
        if not len(idx):
            roots.append(-1)
            continue
        v = np.asarray(pos, dtype=np.float32)[idx]                        # (F, 3, 3)
        tree = build_wide(v.min(axis=1), v.max(axis=1))
        rows.append(_pack(tree, n_nodes, n_prims))
        roots.append(n_nodes)
        tri.append(v[tree.order])
        faces.append(tree.order)
        n_nodes += len(tree.child)
        n_prims += len(tree.order)
    inst_mesh = np.asarray(inst_mesh, dtype=np.int64)
    live = np.flatnonzero(np.array(roots, dtype=np.int64)[inst_mesh] >= 0) if len(inst_mesh) else np.zeros(0, np.int64)
    data = WideBvhData(struct=WideBvh())
    s = data.struct

    def up(a, dtype):
        w = wp.array(a, dtype=dtype, device=device)
        data.arrays.append(w)
        return w

    empty_node = np.zeros(1, dtype=WideNode.numpy_dtype())
    if len(live):
        live_mesh = inst_mesh[live]
        used = np.unique(live_mesh)
        m_lo = np.zeros((len(meshes), 3), np.float32)
        m_hi = np.zeros((len(meshes), 3), np.float32)
        for m in used:
            p = np.asarray(meshes[m][0], dtype=np.float32)
            m_lo[m], m_hi[m] = p.min(axis=0), p.max(axis=0)
        to_world = np.asarray(inst_to_world, dtype=np.float32).reshape(-1, 4, 4)[live]
        top = build_wide(*instance_bounds(m_lo, m_hi, live_mesh, to_world))
        s.tlas = up(_pack(top, 0, 0), WideNode)
        s.tlas_inst = up(live[top.order].astype(np.int32), int)
        s.tlas_root = 0
    else:
        s.tlas, s.tlas_inst, s.tlas_root = up(empty_node, WideNode), up(np.zeros(1, np.int32), int), -1
    s.nodes = up(np.concatenate(rows) if rows else empty_node, WideNode)
    s.mesh_root = up(np.array(roots, dtype=np.int32), int)
    t = np.concatenate(tri) if tri else np.zeros((1, 3, 3), dtype=np.float32)
    s.tri_a, s.tri_b, s.tri_c = (up(np.ascontiguousarray(t[:, k]), wp.vec3) for k in range(3))
    s.tri_face = up(np.concatenate(faces).astype(np.int32) if faces else np.zeros(1, np.int32), int)
    return data


__all__ = ["STACK_SIZE", "WideBvh", "WideBvhData", "WideNode", "build_wide_bvh"]
