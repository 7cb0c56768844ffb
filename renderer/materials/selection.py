"""Materials that are not a BSDF: pbrt-v4's ``mix``, which at each hit picks one of two named
materials (the second with probability ``amount``, decided by a hash of the hit point and the
outgoing direction, so one hit sees one whole material: a stochastic selection, not a blend of the
two BSDFs), and ``interface``, which has no surface at all: rays pass through it as through an
alpha-0 cut-out (:mod:`renderer.integrators.visibility`).

The choice is made once per hit before the shading step, so a mix costs one texture look-up and a
kernel needs no BSDF code for it."""
from __future__ import annotations

import warp as wp

from renderer.geometry.intersect import Surface
from renderer.parameters import Parameter, Parameters
from renderer.sampling.scramble import hash3, hash_point_direction, to_unit
from renderer.textures import Textures, texture_eval

MIX = "mix"
INTERFACE = "interface"
PARAMS = {
    MIX: Parameters(
        Parameter("materials", "strings", None, doc="the two named materials it chooses between"),
        Parameter("amount", "float", 0.5, texture=True,
                  doc="probability of the second material (≤ 0: always the first, ≥ 1: always the second)"),
    ),
    INTERFACE: Parameters(),
}
#: device kind ids (the registry's materials are 0, 1, ...)
MIX_KIND = -2
INTERFACE_KIND = -3
#: mixes of mixes followed per hit (deeper chains and cycles are refused at upload)
MAX_DEPTH = 8


@wp.func
def choose_material(kind: wp.array(dtype=int), mix: wp.array(dtype=wp.vec3i), tex: Textures, m: int, s: Surface,
                    wo: wp.vec3) -> int:
    """The material a hit on material ``m`` shades with: ``m`` itself unless it is a mix, whose
    choice (pbrt-v4's MixMaterial::ChooseMaterial) is followed through mixes of mixes."""
    for _k in range(MAX_DEPTH):
        if kind[m] != MIX_KIND:
            return m
        c = mix[m]                                # (first, second, amount texture)
        amount = texture_eval(tex, c[2], s.uv, s.p, s.ng)[0]
        if amount <= 0.0:
            m = c[0]
        elif amount >= 1.0:
            m = c[1]
        else:
            u = to_unit(hash3(hash_point_direction(s.p, wo), wp.uint32(c[0]), wp.uint32(c[1])))
            m = wp.where(amount < u, c[0], c[1])
    return m
