"""Closest-hit and any-hit traversal of the two-level wide BVH.

Correct on CUDA by construction: no recursion, and each level keeps its own fixed-size local
stack (the builder refuses a tree that could overflow it), so the bottom-level walk inside a
top-level leaf never touches the top level's entries. Triangles are tested with the watertight
algorithm of Woop, Benthin and Wald (JCGT 2013), with the ray's shear computed once per instance
rather than per triangle; barycentrics weight the vertices as (u, v, 1 - u - v), as Warp's do.

Experimental, not used by the renderer: benchmarks/traversal.py measures it against Warp's
queries and docs/traversal.md records why the renderer keeps those.
"""
from __future__ import annotations

import warp as wp

from renderer.geometry.intersect import Hit
from renderer.geometry.wide_scene import STACK_SIZE, WIDTH, WideBvh, WideNode, vec_w

_stack_i = wp.types.vector(length=STACK_SIZE, dtype=wp.int32)
_stack_f = wp.types.vector(length=STACK_SIZE, dtype=float)
_MISS = 3.0e38
# 1 + 2 gamma(3): widening the slab exit keeps a ray grazing a box from missing it to rounding
_ROBUST = 1.0000004


@wp.struct
class ObjectRay:
    """A ray in a mesh's object space with what every box and triangle test reuses."""

    o: wp.vec3
    inv: wp.vec3                             # 1 / d, with zero components nudged to 1e-30
    # Woop's shear as three rows: p - o maps to (x - sx z, y - sy z, sz z) in the axes where z is
    # d's dominant one, so d becomes (0, 0, 1); rows (not indices) keep the vertices in registers
    mx: wp.vec3
    my: wp.vec3
    mz: wp.vec3


@wp.func
def unit(k: int) -> wp.vec3:
    return wp.vec3(wp.where(k == 0, 1.0, 0.0), wp.where(k == 1, 1.0, 0.0), wp.where(k == 2, 1.0, 0.0))


@wp.func
def object_ray(o: wp.vec3, d: wp.vec3) -> ObjectRay:
    r = ObjectRay()
    r.o = o
    r.inv = wp.vec3(1.0 / wp.where(d[0] == 0.0, 1.0e-30, d[0]), 1.0 / wp.where(d[1] == 0.0, 1.0e-30, d[1]),
                    1.0 / wp.where(d[2] == 0.0, 1.0e-30, d[2]))
    ax = wp.abs(d[0])
    ay = wp.abs(d[1])
    az = wp.abs(d[2])
    kz = int(2)
    if ax > ay and ax > az:
        kz = 0
    elif ay > az:
        kz = 1
    kx = (kz + 1) % 3
    ky = (kx + 1) % 3
    if d[kz] < 0.0:
        tmp = kx
        kx = ky
        ky = tmp
    sz = 1.0 / d[kz]
    r.mx = unit(kx) - unit(kz) * (d[kx] * sz)
    r.my = unit(ky) - unit(kz) * (d[ky] * sz)
    r.mz = unit(kz) * sz
    return r


@wp.func
def entry_distances(n: WideNode, r: ObjectRay, t_max: float) -> vec_w:
    """The four children's slab entry distances, _MISS where a child's box is missed or lies
    beyond ``t_max`` (empty slots have inverted boxes, so they always miss)."""
    ox = vec_w(r.o[0])
    oy = vec_w(r.o[1])
    oz = vec_w(r.o[2])
    nx = (wp.where(r.inv[0] < 0.0, n.hix, n.lox) - ox) * r.inv[0]
    fx = (wp.where(r.inv[0] < 0.0, n.lox, n.hix) - ox) * r.inv[0]
    ny = (wp.where(r.inv[1] < 0.0, n.hiy, n.loy) - oy) * r.inv[1]
    fy = (wp.where(r.inv[1] < 0.0, n.loy, n.hiy) - oy) * r.inv[1]
    nz = (wp.where(r.inv[2] < 0.0, n.hiz, n.loz) - oz) * r.inv[2]
    fz = (wp.where(r.inv[2] < 0.0, n.loz, n.hiz) - oz) * r.inv[2]
    t_in = wp.max(wp.max(nx, ny), wp.max(nz, vec_w(0.0)))
    t_out = wp.min(wp.min(wp.min(fx, fy), fz) * _ROBUST, vec_w(t_max))
    out = vec_w(_MISS)
    for k in range(WIDTH):
        if t_in[k] <= t_out[k]:
            out[k] = t_in[k]
    return out


@wp.func
def triangle(r: ObjectRay, a: wp.vec3, b: wp.vec3, c: wp.vec3) -> wp.vec3:
    """(t, u, v) of the watertight ray-triangle test, t = _MISS on a miss or behind the origin.
    Edge functions that round to zero are recomputed in float64, so a ray through a shared edge
    or vertex hits at least one of the triangles around it."""
    pa = a - r.o
    pb = b - r.o
    pc = c - r.o
    ax = wp.dot(r.mx, pa)
    ay = wp.dot(r.my, pa)
    bx = wp.dot(r.mx, pb)
    by = wp.dot(r.my, pb)
    cx = wp.dot(r.mx, pc)
    cy = wp.dot(r.my, pc)
    eu = cx * by - cy * bx
    ev = ax * cy - ay * cx
    ew = bx * ay - by * ax
    if eu == 0.0 or ev == 0.0 or ew == 0.0:
        eu = float(wp.float64(cx) * wp.float64(by) - wp.float64(cy) * wp.float64(bx))
        ev = float(wp.float64(ax) * wp.float64(cy) - wp.float64(ay) * wp.float64(cx))
        ew = float(wp.float64(bx) * wp.float64(ay) - wp.float64(by) * wp.float64(ax))
    miss = wp.vec3(_MISS, 0.0, 0.0)
    if (eu < 0.0 or ev < 0.0 or ew < 0.0) and (eu > 0.0 or ev > 0.0 or ew > 0.0):
        return miss
    det = eu + ev + ew
    if det == 0.0:
        return miss
    tt = eu * wp.dot(r.mz, pa) + ev * wp.dot(r.mz, pb) + ew * wp.dot(r.mz, pc)
    if (tt < 0.0 and det > 0.0) or (tt > 0.0 and det < 0.0):
        return miss
    inv = 1.0 / det
    return wp.vec3(tt * inv, eu * inv, ev * inv)


@wp.func
def leaf_range(code: int) -> wp.vec2i:
    v = -code - 1
    start = v >> 4
    return wp.vec2i(start, start + (v & 15) + 1)


@wp.func
def instance_ray(to_object: wp.mat44, o: wp.vec3, d: wp.vec3) -> ObjectRay:
    """The world ray in an instance's object space; its direction keeps the world scale, so
    distances along it stay world distances."""
    return object_ray(wp.transform_point(to_object, o), wp.transform_vector(to_object, d))


def _walk(top: bool, any_hit: bool, mesh_walk=None):
    """One level's walk. Children are pushed far to near, so the nearest is walked first (for
    shadow rays too: measured 1.0-1.2x faster than pushing them as they come), and an entry
    farther than the best hit so far is dropped on pop; ``any_hit`` ends the walk at the first
    hit (shadow rays). A top-level leaf
    holds instances, each walked by ``mesh_walk`` (with its own stack) along ``r`` in object
    space; a bottom-level leaf holds triangles. ``o``, ``d`` (the world ray) serve the top level.
    The bottom level never takes the instance branch, but Warp resolves every ``wp.static`` when the
    function is declared (else it regenerates the code to hash it in each process), so there that
    branch names ``leaf_range``: a resolvable function in a branch that is never compiled."""
    descend = mesh_walk if mesh_walk is not None else leaf_range

    @wp.func
    def walk(bvh: WideBvh, inst_mesh: wp.array(dtype=int), inst_to_object: wp.array(dtype=wp.mat44),
             root: int, o: wp.vec3, d: wp.vec3, r: ObjectRay, t_max: float) -> Hit:
        best = Hit()
        best.t = t_max
        best.inst = -1
        best.face = -1
        stack = _stack_i()
        dist = _stack_f()
        stack[0] = root
        dist[0] = 0.0
        sp = int(1)
        while sp > 0:
            sp -= 1
            code = stack[sp]
            if dist[sp] >= best.t:
                continue
            if code >= 0:
                node = bvh.tlas[code] if wp.static(top) else bvh.nodes[code]
                tn = entry_distances(node, r, best.t)
                base = sp
                for k in range(WIDTH):
                    e = tn[k]
                    if e < best.t:
                        pos = sp
                        while pos > base and dist[pos - 1] < e:
                            stack[pos] = stack[pos - 1]
                            dist[pos] = dist[pos - 1]
                            pos -= 1
                        stack[pos] = node.child[k]
                        dist[pos] = e
                        sp += 1
            else:
                span = leaf_range(code)
                for p in range(span[0], span[1]):
                    if wp.static(top):
                        i = bvh.tlas_inst[p]
                        h = wp.static(descend)(bvh, inst_mesh, inst_to_object, bvh.mesh_root[inst_mesh[i]],
                                                 o, d, instance_ray(inst_to_object[i], o, d), best.t)
                        if h.face >= 0:
                            best = h
                            best.inst = i
                            if wp.static(any_hit):
                                return best
                    else:
                        h3 = triangle(r, bvh.tri_a[p], bvh.tri_b[p], bvh.tri_c[p])
                        if h3[0] < best.t:
                            best.t = h3[0]
                            best.u = h3[1]
                            best.v = h3[2]
                            best.face = bvh.tri_face[p]
                            if wp.static(any_hit):
                                return best
        return best

    return walk


_scene_closest = _walk(True, False, _walk(False, False))
_scene_any = _walk(True, True, _walk(False, True))


@wp.func
def wide_intersect(bvh: WideBvh, inst_mesh: wp.array(dtype=int), inst_to_object: wp.array(dtype=wp.mat44),
                   o: wp.vec3, d: wp.vec3, t_max: float) -> Hit:
    """Closest hit within (0, t_max) over every instance; the same record as ``intersect``."""
    if bvh.tlas_root < 0:
        miss = Hit()
        miss.t = t_max
        miss.inst = -1
        return miss
    return _scene_closest(bvh, inst_mesh, inst_to_object, bvh.tlas_root, o, d, object_ray(o, d), t_max)


@wp.func
def wide_occluded(bvh: WideBvh, inst_mesh: wp.array(dtype=int), inst_to_object: wp.array(dtype=wp.mat44),
                  o: wp.vec3, d: wp.vec3, t_max: float) -> bool:
    """Whether anything lies along the ray before ``t_max`` (shadow rays)."""
    if bvh.tlas_root < 0:
        return False
    return _scene_any(bvh, inst_mesh, inst_to_object, bvh.tlas_root, o, d, object_ray(o, d), t_max).face >= 0
