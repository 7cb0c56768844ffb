"""Ray casting against instanced triangle meshes: one ``wp.Mesh`` per unique mesh, a top-level
``wp.Bvh`` over instance bounds, and the reconstruction of a hit into a surface point.

The top-level loop calls ``mesh_query_ray`` (its own traversal), never a second ``bvh_query``
loop, so the two traversals do not share a stack on CUDA.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import warp as wp

from renderer.sampling import max3


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


@wp.struct
class Hit:
    t: float
    inst: int                                # -1 on a miss
    face: int
    u: float
    v: float


@wp.struct
class Surface:
    """A hit turned into shading data, all in world space."""

    p: wp.vec3
    ng: wp.vec3                              # geometric normal (winding order, orientation applied)
    ns: wp.vec3                              # interpolated shading normal, same side as ng
    uv: wp.vec2
    dpdu: wp.vec3
    dpdv: wp.vec3
    shape: int
    area: float                              # world-space area of the hit triangle
    err: float                               # Σ b_i |p_i|: the scale of the float32 error in p


@wp.func
def intersect(geo: Geometry, o: wp.vec3, d: wp.vec3, t_max: float) -> Hit:
    """Closest hit along a unit-direction ray within (0, t_max); t is a world distance because
    the object-space direction keeps the world direction's scale."""
    hit = Hit()
    hit.t = t_max
    hit.inst = -1
    query = wp.bvh_query_ray(geo.tlas, o, d)
    i = int(0)
    while wp.bvh_query_next(query, i, hit.t):
        m = geo.inst_to_object[i]
        ol = wp.transform_point(m, o)
        dl = wp.transform_vector(m, d)
        q = wp.mesh_query_ray(geo.mesh_ids[geo.inst_mesh[i]], ol, dl, hit.t)
        if q.result and q.t < hit.t:
            hit.t = q.t
            hit.inst = i
            hit.face = q.face
            hit.u = q.u
            hit.v = q.v
    return hit


@wp.func
def occluded(geo: Geometry, o: wp.vec3, d: wp.vec3, t_max: float) -> bool:
    """Whether anything lies along the ray before t_max (shadow rays: any hit will do)."""
    query = wp.bvh_query_ray(geo.tlas, o, d)
    i = int(0)
    while wp.bvh_query_next(query, i, t_max):
        m = geo.inst_to_object[i]
        if wp.mesh_query_ray_anyhit(geo.mesh_ids[geo.inst_mesh[i]], wp.transform_point(m, o),
                                    wp.transform_vector(m, d), t_max):
            return True
    return False


@wp.func
def surface_at(geo: Geometry, hit: Hit, flip: bool) -> Surface:
    """Position, normals, UVs and UV tangents at a hit. Warp's barycentrics weight the triangle's
    vertices as (u, v, 1 - u - v). ``flip`` reverses the orientation (pbrt's ReverseOrientation)."""
    inst = hit.inst
    mi = geo.inst_mesh[inst]
    mesh = wp.mesh_get(geo.mesh_ids[mi])
    i0 = mesh.indices[hit.face * 3 + 0]
    i1 = mesh.indices[hit.face * 3 + 1]
    i2 = mesh.indices[hit.face * 3 + 2]
    m = geo.inst_to_world[inst]
    p0 = wp.transform_point(m, mesh.points[i0])
    p1 = wp.transform_point(m, mesh.points[i1])
    p2 = wp.transform_point(m, mesh.points[i2])
    b0 = hit.u
    b1 = hit.v
    b2 = 1.0 - b0 - b1
    s = Surface()
    s.p = p0 * b0 + p1 * b1 + p2 * b2
    s.err = b0 * _max_abs(p0) + b1 * _max_abs(p1) + b2 * _max_abs(p2)
    e1 = p1 - p0
    e2 = p2 - p0
    c = wp.cross(e1, e2)
    la = wp.length(c)
    s.area = 0.5 * la
    ng = wp.vec3(0.0, 0.0, 1.0)
    if la > 0.0:
        ng = c / la
    if flip:
        ng = -ng
    s.ng = ng
    s.ns = ng
    no = geo.mesh_normal_offset[mi]
    if no >= 0:
        # normals transform with the inverse transpose: n_world = (M^-1)^T n_obj
        nobj = geo.normals[no + i0] * b0 + geo.normals[no + i1] * b1 + geo.normals[no + i2] * b2
        w2o = geo.inst_to_object[inst]
        nw = wp.vec3(w2o[0, 0] * nobj[0] + w2o[1, 0] * nobj[1] + w2o[2, 0] * nobj[2],
                     w2o[0, 1] * nobj[0] + w2o[1, 1] * nobj[1] + w2o[2, 1] * nobj[2],
                     w2o[0, 2] * nobj[0] + w2o[1, 2] * nobj[1] + w2o[2, 2] * nobj[2])
        ln = wp.length(nw)
        if ln > 0.0:
            nw = nw / ln
            if wp.dot(nw, ng) < 0.0:
                nw = -nw
            s.ns = nw
    uo = geo.mesh_uv_offset[mi]
    uv0 = wp.vec2(0.0, 0.0)
    uv1 = wp.vec2(1.0, 0.0)
    uv2 = wp.vec2(1.0, 1.0)
    if uo >= 0:
        uv0 = geo.uvs[uo + i0]
        uv1 = geo.uvs[uo + i1]
        uv2 = geo.uvs[uo + i2]
    s.uv = uv0 * b0 + uv1 * b1 + uv2 * b2
    # dp/du, dp/dv from the triangle's UV parameterisation (pbrt's construction)
    du02 = uv0 - uv2
    du12 = uv1 - uv2
    det = du02[0] * du12[1] - du02[1] * du12[0]
    dp02 = p0 - p2
    dp12 = p1 - p2
    if wp.abs(det) > 1.0e-12:
        inv = 1.0 / det
        s.dpdu = (dp02 * du12[1] - dp12 * du02[1]) * inv
        s.dpdv = (dp12 * du02[0] - dp02 * du12[0]) * inv
    if wp.abs(det) <= 1.0e-12 or wp.length(wp.cross(s.dpdu, s.dpdv)) == 0.0:
        t = wp.normalize(wp.where(wp.abs(ng[0]) > 0.9, wp.vec3(0.0, 1.0, 0.0), wp.vec3(1.0, 0.0, 0.0)))
        s.dpdu = wp.normalize(wp.cross(t, ng))
        s.dpdv = wp.cross(ng, s.dpdu)
    s.shape = geo.inst_shape[inst]
    return s


@wp.func
def _max_abs(p: wp.vec3) -> float:
    return max3(wp.vec3(wp.abs(p[0]), wp.abs(p[1]), wp.abs(p[2])))


@wp.func
def offset_origin(s: Surface, w: wp.vec3) -> wp.vec3:
    """Move a spawned ray's origin off the surface along the geometric normal, on the side of
    ``w``. The distance scales with the float32 error of the hit point, which grows with the
    magnitude of the triangle's vertices (pbrt's bound Σ b_i |p_i|, with a safety factor for the
    intersector's barycentrics), so 0.3 mm grains and 1 km dunes both escape self-intersection
    without light leaking through either."""
    eps = 1.0e-7 + 4.0e-6 * wp.max(s.err, _max_abs(s.p))
    if wp.dot(w, s.ng) < 0.0:
        eps = -eps
    return s.p + s.ng * eps


@wp.func
def ray_epsilon(p: wp.vec3) -> float:
    """The same relative tolerance, for shortening shadow rays towards a point on a light."""
    return 1.0e-7 + 8.0e-6 * _max_abs(p)


@dataclass
class GeometryData:
    """Host-side owner of every Warp object the :class:`Geometry` struct points into: a struct
    holds raw ids, so the meshes and BVH must stay referenced here for as long as it is used."""

    struct: Geometry
    meshes: list = field(default_factory=list)
    arrays: list = field(default_factory=list)
    tlas: object = None
    bounds: tuple[np.ndarray, np.ndarray] | None = None


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
    lo, hi = _instance_bounds(np.array(mesh_lo), np.array(mesh_hi), np.asarray(inst_mesh), to_world)
    data.bounds = (lo, hi)

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


def _instance_bounds(mesh_lo: np.ndarray, mesh_hi: np.ndarray, inst_mesh: np.ndarray,
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
