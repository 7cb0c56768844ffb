"""Light a path finds by leaving the scene or by hitting an emitter, MIS-weighted against next-event
estimation, specialised to the light kinds a scene has.

Each factory returns a chain of ``wp.func``s, one per light kind, each naming its kind, its light
module's function and the next link through ``wp.static`` of a value known when it is declared.
A loop over the kinds reading ``wp.static(kinds[j])`` would depend on the loop variable, which
Warp can only resolve by generating the whole kernel's code before it can hash it, in every
process, even when the compiled kernel is already cached (0.7 CPU-s for the path kernel).
"""
from __future__ import annotations

from functools import lru_cache
from types import ModuleType

import warp as wp

from renderer.lights.sample import LightEval
from renderer.lights.table import Lights
from renderer.sampling.mis import power_heuristic
from renderer.vecmath import max3


@wp.func
def emission(beta: wp.vec3, ev: LightEval, sel: float, prev_pdf: float, prev_specular: bool, mis: bool) -> wp.vec3:
    """Light a path finds on a light, MIS-weighted against next-event estimation (which could have
    sampled it unless the bounce that led here was specular)."""
    w = float(1.0)
    if mis:
        if not prev_specular:
            w = power_heuristic(prev_pdf, ev.pdf * sel)
    return wp.cw_mul(beta, ev.L) * w


@lru_cache(maxsize=None)
def escaped_adder(mods: tuple[ModuleType, ...], ids: tuple[int, ...], mis: bool) -> wp.Function:
    """``add_escaped(lights, o, d, beta, sel, prev_pdf, prev_specular, L)``: ``L`` plus what every
    light of the kinds ``mods`` gives a ray leaving the scene, kind by kind, then light by light."""
    if not mods:
        @wp.func
        def add_nothing(lights: Lights, o: wp.vec3, d: wp.vec3, beta: wp.vec3, sel: float, prev_pdf: float,
                        prev_specular: bool, L: wp.vec3) -> wp.vec3:
            return L

        return add_nothing
    escaped, kind, rest = mods[0].escaped, ids[0], escaped_adder(mods[1:], ids[1:], mis)

    @wp.func(inline=True)
    def add_escaped(lights: Lights, o: wp.vec3, d: wp.vec3, beta: wp.vec3, sel: float, prev_pdf: float,
                    prev_specular: bool, L: wp.vec3) -> wp.vec3:
        acc = L
        for i in range(lights.count):
            if lights.kind[i] == wp.static(kind):
                ev = wp.static(escaped)(lights, i, o, d)
                if max3(ev.L) > 0.0:
                    acc = acc + emission(beta, ev, sel, prev_pdf, prev_specular, wp.static(mis))
        return wp.static(rest)(lights, o, d, beta, sel, prev_pdf, prev_specular, acc)

    return add_escaped


@lru_cache(maxsize=None)
def emitted_adder(mods: tuple[ModuleType, ...], ids: tuple[int, ...], mis: bool) -> wp.Function:
    """``add_emitted(lights, li, prev_p, p, ng, wo, beta, sel, prev_pdf, prev_specular, L)``: ``L``
    plus the light of emitter ``li`` (one of the kinds ``mods``) seen at ``p`` from ``prev_p``."""
    if not mods:
        @wp.func
        def add_nothing(lights: Lights, li: int, prev_p: wp.vec3, p: wp.vec3, ng: wp.vec3, wo: wp.vec3,
                        beta: wp.vec3, sel: float, prev_pdf: float, prev_specular: bool, L: wp.vec3) -> wp.vec3:
            return L

        return add_nothing
    emitted, kind, rest = mods[0].emitted, ids[0], emitted_adder(mods[1:], ids[1:], mis)

    @wp.func(inline=True)
    def add_emitted(lights: Lights, li: int, prev_p: wp.vec3, p: wp.vec3, ng: wp.vec3, wo: wp.vec3,
                    beta: wp.vec3, sel: float, prev_pdf: float, prev_specular: bool, L: wp.vec3) -> wp.vec3:
        if lights.kind[li] == wp.static(kind):
            ev = wp.static(emitted)(lights, li, prev_p, p, ng, wo)
            return L + emission(beta, ev, sel, prev_pdf, prev_specular, wp.static(mis))
        return wp.static(rest)(lights, li, prev_p, p, ng, wo, beta, sel, prev_pdf, prev_specular, L)

    return add_emitted
