"""What light sampling returns, and next-event estimation's light choice, specialised to the kinds
of light a scene has: one light is picked uniformly and its own module samples a direction.

Densities are in solid angle. A kind's ``sample``, ``escaped`` and ``emitted`` give the density of
that light's own sampling; the selection probability is applied here (``sample_light``) and by the
integrator for lights it hits, so MIS weights compare like with like.
"""
from __future__ import annotations

from functools import lru_cache
from types import ModuleType

import warp as wp

from renderer.lights.table import Lights


@wp.struct
class LightSample:
    wi: wp.vec3
    L: wp.vec3
    pdf: float                             # solid angle; sample_light includes the selection probability
    dist: float                            # distance to the sampled point (1e30 for lights at infinity)
    delta: bool                            # a delta light: no MIS, BSDF sampling cannot hit it


@wp.struct
class LightEval:
    """Radiance a ray finds on a light (by escaping, or by hitting an emitter) and the density
    with which that light's own sampling would have chosen the ray (selection excluded)."""

    L: wp.vec3
    pdf: float


@lru_cache(maxsize=None)
def light_sampler(modules: tuple[ModuleType, ...], ids: tuple[int, ...]) -> wp.Function:
    """A device function ``sample_light(lights, p, u_select, u)`` that picks one light uniformly
    with ``u_select`` and calls its module's ``sample``; only ``modules`` are compiled in."""
    pick = _switch(tuple(m.sample for m in modules), ids)

    @wp.func(inline=True)
    def sample_light(lights: Lights, p: wp.vec3, u_select: float, u: wp.vec2) -> LightSample:
        n = lights.count
        i = wp.min(int(u_select * float(n)), n - 1)
        sel = 1.0 / float(n)
        k = lights.kind[i]
        s = pick(lights, k, i, p, u)
        s.pdf = s.pdf * sel
        return s

    return sample_light


@lru_cache(maxsize=None)
def _switch(hooks: tuple[wp.Function, ...], ids: tuple[int, ...]) -> wp.Function:
    """``f(lights, kind, i, p, u)``: the ``sample`` of light kind ``kind`` (an empty sample for
    none), one function per kind, each naming its kind and the next by values known when it is
    declared (why: renderer/integrators/emission.py)."""
    if not hooks:
        @wp.func
        def none(lights: Lights, k: int, i: int, p: wp.vec3, u: wp.vec2) -> LightSample:
            return LightSample()

        return none
    hook, kind, rest = hooks[0], ids[0], _switch(hooks[1:], ids[1:])

    @wp.func
    def one(lights: Lights, k: int, i: int, p: wp.vec3, u: wp.vec2) -> LightSample:
        if k == wp.static(kind):
            return wp.static(hook)(lights, i, p, u)
        return wp.static(rest)(lights, k, i, p, u)

    return one
