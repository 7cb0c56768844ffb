"""The subsurface material's lobes one at a time, for the sampling-against-evaluation harness: its
(eval_pdf, sample) with a derived flag set, as the subsurface step sets it (EXIT: the exit lobe;
SURFACE: the entry's reflection alone)."""
from __future__ import annotations

import warp as wp

from renderer.materials import subsurface as sss
from renderer.materials.bsdf import BSDF, BSDFEval, BSDFSample


def with_flag(flag: int) -> tuple[wp.Function, wp.Function]:
    """The material's (eval_pdf, sample) with ``flag`` set."""

    @wp.func
    def flagged_eval(b: BSDF, wo: wp.vec3, wi: wp.vec3) -> BSDFEval:
        c = b
        c.flags = b.flags | flag
        return sss.eval_pdf(c, wo, wi)

    @wp.func
    def flagged_sample(b: BSDF, wo: wp.vec3, u: wp.vec3) -> BSDFSample:
        c = b
        c.flags = b.flags | flag
        return sss.sample(c, wo, u)

    return flagged_eval, flagged_sample


#: the exit lobe and the entry's reflection, each alone
LOBES = {"exit": with_flag(sss.EXIT), "surface": with_flag(sss.SURFACE)}
