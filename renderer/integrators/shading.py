"""The shading step every kernel shares: a hit's material parameters from their textures, the
bump-mapped shading frame, and the material dispatch, written once for the path and AOV kernels.

``shading_functions(features)`` builds (once per feature set) the Warp functions that switch over
exactly the material types a scene uses, each with only the lobes its materials can reach
(:func:`renderer.materials.hooks`), so a kernel calls ``eval_pdf``/``sample`` once per vertex
instead of looping over the registry itself."""
from __future__ import annotations

from functools import lru_cache
from typing import NamedTuple

import warp as wp

from renderer.device.scene import Features, Scene
from renderer.geometry.intersect import Surface
from renderer.color.rgb_weights import RgbWeightTable
from renderer.materials import Materials, dispatch_table, hooks
from renderer.materials.bsdf import BSDF, MAX_SLOTS, BSDFEval, BSDFSample, Slots
from renderer.sampling.frames import Frame, frame_from_tangent
from renderer.textures import Textures, texture_eval

#: Finite-difference step in texture space for bump mapping (pbrt's fallback without ray differentials).
BUMP_DELTA = 0.0005


@wp.func(inline=True)
def _with_row(p: Slots, j: int, v: wp.vec3) -> Slots:
    """``p`` with row ``j`` set to ``v``, each row written at a constant index: ``p[j]`` with the
    loop's runtime ``j`` put the whole 16x3 matrix in local memory (192 B of every shading kernel's
    frame); so the rows live in registers, and those no material of the kernel reads vanish. Spelled
    out: a loop Warp unrolls needs a ``wp.static`` of its variable, which makes the kernel's hash
    depend on what the process compiled before (tests/integrators/test_kernel_cache_keys.py)."""
    q = p
    if j == 0:
        q[0] = v
    if j == 1:
        q[1] = v
    if j == 2:
        q[2] = v
    if j == 3:
        q[3] = v
    if j == 4:
        q[4] = v
    if j == 5:
        q[5] = v
    if j == 6:
        q[6] = v
    if j == 7:
        q[7] = v
    if j == 8:
        q[8] = v
    if j == 9:
        q[9] = v
    if j == 10:
        q[10] = v
    if j == 11:
        q[11] = v
    if j == 12:
        q[12] = v
    if j == 13:
        q[13] = v
    if j == 14:
        q[14] = v
    if j == 15:
        q[15] = v
    return q


assert MAX_SLOTS == 16, "_with_row spells out one line per slot"


@wp.func(inline=True)
def load_bsdf(mat: Materials, tex: Textures, spectral: RgbWeightTable, spectral_n: int, m: int,
              s: Surface) -> BSDF:
    """Evaluate a material's parameter textures at the surface point (its uv, or for pbrt's
    spherical, cylindrical and planar mappings its world position; directionmix reads its normal)
    into the rows of ``BSDF.p``. Takes only the
    tables it reads: a CPU call copies struct arguments, and the whole ``Scene`` is 2 kB."""
    p = Slots()
    for j in range(MAX_SLOTS):
        tid = mat.slots[m, j]
        if tid >= 0:
            v = texture_eval(tex, tid, s.uv, s.p, s.ng)
            if wp.isfinite(v):          # a NaN stays NaN: its sample is dropped and counted, not hidden
                r = mat.bounds[m, j]    # the parameter's declared range, as pbrt clamps textures
                v = wp.vec3(wp.clamp(v[0], r[0], r[1]), wp.clamp(v[1], r[0], r[1]), wp.clamp(v[2], r[0], r[1]))
            p = _with_row(p, j, v)
    b = BSDF()
    b.kind = mat.kind[m]
    b.p = p
    b.flags = mat.flags[m]
    b.spectral = spectral
    b.spectral_n = spectral_n
    b.layers = mat.layers
    b.layer_first = mat.layer_first[m]
    b.layer_count = mat.layer_count[m]
    b.table_first = mat.table_first[m]
    return b


@wp.func
def bump_normal(scene: Scene, tid: int, s: Surface, ns: wp.vec3) -> wp.vec3:
    """Shading normal perturbed by a float displacement texture (pbrt's bump mapping, without the
    dn/du term): the displaced surface's tangents cross to the new normal. The offsets move both
    uv and the point (along dp/du, dp/dv), so every texture mapping sees them. The three lookups
    share one loop body: one copy of the texture program in the kernel instead of three."""
    uv = s.uv
    du = BUMP_DELTA
    dv = BUMP_DELTA
    d = float(0.0)
    d_u = float(0.0)
    d_v = float(0.0)
    for k in range(3):
        at = uv
        p = s.p
        if k == 1:
            at = wp.vec2(uv[0] + du, uv[1])
            p = s.p + s.dpdu * du
        elif k == 2:
            at = wp.vec2(uv[0], uv[1] + dv)
            p = s.p + s.dpdv * dv
        h = texture_eval(scene.tex, tid, at, p, s.ng)[0]
        if k == 0:
            d = h
        elif k == 1:
            d_u = h
        else:
            d_v = h
    su = s.dpdu + ns * ((d_u - d) / du)
    sv = s.dpdv + ns * ((d_v - d) / dv)
    n = wp.cross(su, sv)
    ln = wp.length(n)
    if ln <= 0.0:
        return ns
    n = n / ln
    if wp.dot(n, ns) < 0.0:
        n = -n
    return n


class Shading(NamedTuple):
    """The per-vertex shading functions of one feature set (each a ``wp.func``)."""

    frame: wp.Function      # (scene, material, surface) -> Frame: bump-mapped shading frame
    eval_pdf: wp.Function   # (bsdf, wo, wi) -> BSDFEval, local directions
    sample: wp.Function     # (bsdf, wo, u) -> BSDFSample


@lru_cache(maxsize=None)
def shading_functions(features: Features) -> Shading:
    mods, kinds = dispatch_table(features.materials)
    kinds = tuple(kinds)
    has_bump = features.bump

    @wp.func(inline=True)
    def shading_frame(scene: Scene, m: int, s: Surface) -> Frame:
        ns = s.ns
        if wp.static(has_bump):
            bt = scene.mat.bump[m]
            if bt >= 0:
                ns = bump_normal(scene, bt, s, ns)
        return frame_from_tangent(ns, s.dpdu)

    pairs = [hooks(m, features) for m in mods]   # each material's lobes that the scene can reach
    return Shading(shading_frame, _switch(tuple(e for e, _ in pairs), kinds, BSDFEval),
                   _switch(tuple(s for _, s in pairs), kinds, BSDFSample))


@lru_cache(maxsize=None)
def _switch(hooks: tuple[wp.Function, ...], kinds: tuple[int, ...], result: type) -> wp.Function:
    """``f(b, wo, x)``: the hook of material kind ``b.kind`` (``result()`` for none), as a chain of
    one function per kind, each naming its kind and the next link by values known when it is
    declared (a loop reading ``wp.static(kinds[j])`` would make Warp generate the kernel's code
    in every process just to hash it: renderer/integrators/emission.py)."""
    if not hooks:
        @wp.func
        def none(b: BSDF, wo: wp.vec3, x: wp.vec3):
            return result()

        return none
    hook, kind, rest = hooks[0], kinds[0], _switch(hooks[1:], kinds[1:], result)

    @wp.func
    def one(b: BSDF, wo: wp.vec3, x: wp.vec3):
        if b.kind == wp.static(kind):
            return wp.static(hook)(b, wo, x)
        return wp.static(rest)(b, wo, x)

    return one
