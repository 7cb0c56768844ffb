"""Light through thin coated lenses: shadow rays that cross the faces of a thin closed slab (a
``thinfilm`` with ``transmission`` and ``"bool thinslab" true``) instead of stopping at them.

A shadow ray from x towards a light meets the slab's two faces; it carries
T(θ) = T_front(θ) · tint^(1/cos θ_t) · T_back(θ), each face's coating transmittance at the angle the
light meets it (inside: θ_t, from Snell's law) times half a pass of the tint
(:func:`renderer.materials.thinfilm.slab_face`). The ray goes on straight: a parallel
slab shifts light sideways by t·sin(θ − θ_t)/cos θ_t but does not turn it. Interreflections
between the faces are left out of the shadow ray (a few per cent of T at most for R ≈ 4-10 %); BSDF
sampling still finds them.

Nothing is counted twice: where BSDF sampling can reach the same light (a soft sun, an area light,
an environment), the path that refracts through the slab's faces keeps the density, the
specularity and the position of the vertex it left (``crosses_thin_slab`` in
:func:`renderer.integrators.vertex.scatter_function`), so the light it finds after the slab is
MIS-weighted against the shadow ray's sample, which carried the same T. Only a refraction through
such a face is a pass-through event; a reflection at it is a vertex as before.

Each face is its own ``intersect`` that returns before the next begins (no nested traversals on
CUDA). Kernels call this only when the scene has such faces (``Features.thin_slabs``).
"""
from __future__ import annotations

from functools import lru_cache

import warp as wp

from renderer.device.scene import Scene
from renderer.geometry.intersect import surface_at
from renderer.geometry.offsets import offset_origin
from renderer.integrators.shading import load_bsdf
from renderer.materials import Materials, kind_id, thinfilm
from renderer.materials.bsdf import TRANSMISSION
from renderer.sampling.scramble import hash_point_direction, to_unit
from renderer.vecmath import max3

#: Slab faces one shadow ray crosses before it counts as blocked (eight lenses in a row).
MAX_FACES = 16

THINFILM = wp.constant(kind_id(thinfilm.NAME))
THIN_SLAB = wp.constant(thinfilm.FLAG.thinslab)


@wp.func
def is_thin_slab(mat: Materials, m: int) -> bool:
    """Whether material m is a face of a thin slab that shadow rays cross."""
    return mat.kind[m] == THINFILM and (mat.flags[m] & THIN_SLAB) != 0


@wp.func
def crosses_thin_slab(mat: Materials, m: int, sampled_flags: int) -> bool:
    """Whether a BSDF sample of material m refracted through a thin slab's face: a pass-through
    event that keeps the MIS bookkeeping of the vertex before it (module docstring)."""
    return (sampled_flags & TRANSMISSION) != 0 and is_thin_slab(mat, m)


#: What lies along a shadow ray (:func:`crossing`).
CLEAR, BLOCKED, SLABS_ONLY = 0, 1, 2


@wp.func
def crossing(scene: Scene, o: wp.vec3, d: wp.vec3, t_max: float) -> int:
    """What lies along the ray, by any-hit queries in any order: CLEAR nothing, BLOCKED something
    opaque (the ray is blocked whatever else it crosses), SLABS_ONLY thin slabs' faces only. Most
    shadow rays end here at the cost of the plain any-hit query; only rays past a lens go on to
    trace its faces (the wavefront traces those in a kernel of their own)."""
    query = wp.bvh_query_ray(scene.geo.tlas, o, d)
    i = int(0)
    found = int(CLEAR)
    while wp.bvh_query_next(query, i, t_max):
        m = scene.geo.inst_to_object[i]
        if wp.mesh_query_ray_anyhit(scene.geo.mesh_ids[scene.geo.inst_mesh[i]], wp.transform_point(m, o),
                                    wp.transform_vector(m, d), t_max):
            if not is_thin_slab(scene.mat, scene.shape_material[scene.geo.inst_shape[i]]):
                return BLOCKED
            found = SLABS_ONLY
    return found


@lru_cache(maxsize=None)
def face_walk(closest: wp.Function, own_kernel: bool = False) -> wp.Function:
    """``through_faces(scene, o, d, t_max) -> vec3``: the ray traced hit by hit (``closest``, the
    kernel's closest-hit query), the product of the thin slabs' faces' transmittances it crosses,
    0 at any other hit or past MAX_FACES faces. ``own_kernel``: the walk is its kernel's only work
    (the wavefront's lens step), so the coating's optics are inlined into it."""
    face_transmittance = thinfilm.slab_face(own_kernel)

    @wp.func
    def through_faces(scene: Scene, o: wp.vec3, d: wp.vec3, t_max: float) -> wp.vec3:
        T = wp.vec3(1.0)
        travelled = float(0.0)
        for _k in range(MAX_FACES):
            hit = wp.static(closest)(scene, o, d, t_max - travelled)
            if hit.inst < 0:
                return T
            shape = scene.geo.inst_shape[hit.inst]
            m = scene.shape_material[shape]
            if not is_thin_slab(scene.mat, m):
                return wp.vec3(0.0)
            s = surface_at(scene.geo, hit, scene.shape_flip[shape] != 0)
            b = load_bsdf(scene.mat, scene.tex, scene.spectral, scene.spectral_n, m, s)
            b.wavelength_u = to_unit(hash_point_direction(s.p, d))   # spectral:N: this face's jitter
            T = wp.cw_mul(T, wp.static(face_transmittance)(b, wp.dot(d, s.ns)))
            if max3(T) <= 0.0:
                return T
            step = offset_origin(s, d)
            travelled += wp.dot(step - o, d)
            o = step
        return wp.vec3(0.0)

    return through_faces


@wp.func
def crossing_transmittance(c: int) -> wp.vec3:
    """The transmittance of a ray that ``crossing`` found CLEAR (1) or BLOCKED (0)."""
    if c == BLOCKED:
        return wp.vec3(0.0)
    return wp.vec3(1.0)


@lru_cache(maxsize=None)
def transmittance_query(closest: wp.Function, alpha: bool) -> wp.Function:
    """``transmitted(scene, o, d, t_max) -> vec3``: what reaches ``o`` along ``d`` from t_max,
    through thin slabs' faces (0 at any other hit); ``closest`` is the kernel's closest-hit query.
    Without alpha cut-outs an any-hit pass first tells blocked and clear rays apart (``crossing``);
    with them, every ray walks its hits, as alpha needs."""
    through_faces = face_walk(closest)

    @wp.func
    def transmitted(scene: Scene, o: wp.vec3, d: wp.vec3, t_max: float) -> wp.vec3:
        if wp.static(not alpha):
            c = crossing(scene, o, d, t_max)
            if c != SLABS_ONLY:
                return crossing_transmittance(c)
        return wp.static(through_faces)(scene, o, d, t_max)

    return transmitted
