"""Closest-hit and any-hit queries against the instanced scene, and the reconstruction of a hit
into a surface point.

The top-level loop calls ``mesh_query_ray`` (its own traversal), never a second ``bvh_query``
loop, so the two traversals do not share a stack on CUDA."""
from __future__ import annotations

import warp as wp

from renderer.geometry.instances import Geometry
from renderer.vecmath import max_abs


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
    err: float                               # Σ b_i |p_i|: the scale of the float32 error in p


@wp.func(inline=True)
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


@wp.func(inline=True)
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


@wp.func(inline=True)
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
    s.err = b0 * max_abs(p0) + b1 * max_abs(p1) + b2 * max_abs(p2)
    e1 = p1 - p0
    e2 = p2 - p0
    c = wp.cross(e1, e2)
    la = wp.length(c)
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
    return s
