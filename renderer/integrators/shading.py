"""The shading step every kernel shares: a hit's material parameters from their textures, and the
bump-mapped shading normal."""
from __future__ import annotations

import warp as wp

from renderer.device.scene import Scene
from renderer.materials.bsdf import BSDF, MAX_SLOTS, Slots
from renderer.textures import texture_eval


#: Finite-difference step in texture space for bump mapping (pbrt's fallback without ray differentials).
BUMP_DELTA = 0.0005


@wp.func
def load_bsdf(scene: Scene, m: int, uv: wp.vec2) -> BSDF:
    """Evaluate a material's parameter textures at uv into the rows of ``BSDF.p``."""
    p = Slots()
    for j in range(MAX_SLOTS):
        tid = scene.mat.slots[m, j]
        if tid >= 0:
            v = texture_eval(scene.tex, tid, uv)
            p[j, 0] = v[0]
            p[j, 1] = v[1]
            p[j, 2] = v[2]
    b = BSDF()
    b.kind = scene.mat.kind[m]
    b.p = p
    b.spectral = scene.spectral
    b.spectral_n = scene.spectral_n
    return b


@wp.func
def bump_normal(scene: Scene, tid: int, uv: wp.vec2, ns: wp.vec3, dpdu: wp.vec3, dpdv: wp.vec3) -> wp.vec3:
    """Shading normal perturbed by a float displacement texture (pbrt's bump mapping, without the
    dn/du term): the displaced surface's tangents cross to the new normal."""
    d = texture_eval(scene.tex, tid, uv)[0]
    du = BUMP_DELTA
    dv = BUMP_DELTA
    d_u = texture_eval(scene.tex, tid, wp.vec2(uv[0] + du, uv[1]))[0]
    d_v = texture_eval(scene.tex, tid, wp.vec2(uv[0], uv[1] + dv))[0]
    su = dpdu + ns * ((d_u - d) / du)
    sv = dpdv + ns * ((d_v - d) / dv)
    n = wp.cross(su, sv)
    ln = wp.length(n)
    if ln <= 0.0:
        return ns
    n = n / ln
    if wp.dot(n, ns) < 0.0:
        n = -n
    return n
