"""pbrt-v4's layered BSDF (``LayeredBxDF``): a top interface over an opaque base, with a slab of
homogeneous medium between them, evaluated by a random walk between the two.

The slab has optical ``thickness`` (unit extinction, so Tr = exp(-thickness / |cos θ|)), single
scattering ``albedo`` and a Henyey–Greenstein phase function of asymmetry ``g``. The material is
two-sided: a ``wo`` below the surface is mirrored above it first.

* ``layered_f``: pbrt's estimator of f(wo, wi). Light refracts in through the top along a sampled
  direction from wo, walks between the interfaces (and scatters in the medium when albedo > 0),
  and at every vertex connects to a direction sampled through the top from wi (next-event
  estimation), MIS-weighted against the walk's own continuation through the top.
* ``layered_sample``: the walk itself, returning where it leaves through the top. Its density
  has no closed form, so ``pdf`` is ``layered_pdf``'s estimate, as pbrt's "pdfIsProportional".
* ``layered_pdf``: pbrt's approximate density (top reflection plus one transmit-reflect-transmit
  bounce, mixed with 10 % uniform): for MIS weights only, it need not be the exact density.

Estimates are stochastic but deterministic: each call seeds its own RNG from a hash of its
directions and of the BSDF's per-sample ``wavelength_u``, so the same seed renders the same image
and two samples of one pixel use independent walks.

Interfaces are of a small integer kind (:mod:`.layer_interfaces`: Warp has no function pointers).
Each material walks between a top and a bottom of fixed kinds, so :func:`walk` builds its functions
from the two kinds' entries of ``INTERFACES`` and nothing branches on a kind at run time: a kernel compiles the lobes
of the kinds its materials walk between, not of every kind. FILM is a thin film
or multilayer stack (``thinfilm``'s coating, :mod:`.coating`) whose Fresnel term is an RGB R and T
per direction: smooth, it reflects with probability mean(R) / (mean R + mean T); rough, it is the
GGX pair with those R and T at the half-vector.

On a GPU (docs/gpu.md, "The layered walk's kernels"): the slab carries one coating, not one per
interface (only a FILM top or a CONDUCTOR base has one); the sample's density is estimated after
the walk, not inside it; and the three estimators are inlined (``inline=True``) into their callers:
out of line, each copied the slab into the stack frame and stacked its own frame on its caller's.
"""
from __future__ import annotations

from functools import lru_cache
from typing import Any

import warp as wp

from renderer.materials.bsdf import (BSDF, DIFFUSE, FIRST_DERIVED_FLAG, GLOSSY, REFLECTION, SPECULAR,
                                     TRANSMISSION, BSDFEval, BSDFSample, failed_sample)
from renderer.materials.coating import Coating
from renderer.materials.layer_interfaces import INTERFACES, LAMBERT, Interface
from renderer.materials.phase import hg_phase, hg_sample
from renderer.parameters import Parameter
from renderer.sampling.mis import power_heuristic
from renderer.sampling.rng import hash_u32
from renderer.vecmath import PI, max3

BOTH = wp.constant(REFLECTION | TRANSMISSION)
#: Smallest slab thickness (pbrt: the smallest normal float), so a thickness of 0 stays defined.
MIN_THICKNESS = wp.constant(1.17549435e-38)


#: pbrt-v4's parameters of the slab and of its random walk, shared by the coated materials.
SLAB_PARAMS = (
    Parameter("thickness", "float", 0.01, 0.0, texture=True, doc="slab thickness, in mean free paths"),
    Parameter("albedo", "rgb", 0.0, 0.0, 1.0, texture=True, doc="single-scattering albedo of the slab's medium"),
    Parameter("g", "float", 0.0, -1.0, 1.0, texture=True, doc="Henyey–Greenstein asymmetry of the medium"),
    Parameter("maxdepth", "int", 10, 0, 255, doc="most scattering events of one random walk"),
    Parameter("nsamples", "int", 1, 1, 63, doc="random walks averaged per evaluation"),
)
#: The walk's two integers travel in the derived flag bits: max depth at bit 16, samples at bit 24.
_DEPTH_SHIFT = FIRST_DERIVED_FLAG.bit_length() - 1
_SAMPLES_SHIFT = _DEPTH_SHIFT + 8
#: The first derived flag bit a coated material may use for itself, above the walk's.
FIRST_FREE_FLAG = 1 << (_SAMPLES_SHIFT + 6)


def walk_flags(values: dict[str, Any]) -> int:
    """The derived flag bits that carry ``maxdepth`` and ``nsamples`` to the device."""
    defaults = {p.name: p.default for p in SLAB_PARAMS}
    depth = values.get("maxdepth", defaults["maxdepth"])
    samples = values.get("nsamples", defaults["nsamples"])
    return (depth << _DEPTH_SHIFT) | (samples << _SAMPLES_SHIFT)


@wp.struct
class Slab:
    top: Interface
    bottom: Interface
    coat: Coating       # the coating of the interface that has one (layer_interfaces): only one does
    thickness: float
    albedo: wp.vec3
    g: float
    max_depth: int
    n_samples: int
    seed: float         # per-sample random number mixed into each estimate's RNG


@wp.func
def make_slab(top: Interface, bottom: Interface, coat: Coating, thickness: float, albedo: wp.vec3, g: float,
              flags: int, seed: float) -> Slab:
    """A slab from a material's evaluated parameters; ``flags`` carry the walk's integers (walk_flags)."""
    L = Slab()
    L.top = top
    L.bottom = bottom
    L.coat = coat
    L.thickness = thickness
    L.albedo = wp.min(wp.max(albedo, wp.vec3(0.0)), wp.vec3(1.0))
    L.g = wp.clamp(g, -1.0, 1.0)
    L.max_depth = (flags >> wp.static(_DEPTH_SHIFT)) & 255
    L.n_samples = (flags >> wp.static(_SAMPLES_SHIFT)) & 63
    L.seed = seed
    return L


@wp.func
def _ok(bs: BSDFSample) -> bool:
    return bs.pdf > 0.0 and max3(bs.weight) > 0.0 and bs.wi[2] != 0.0


@wp.func
def _tr(dz: float, w: wp.vec3) -> float:
    """Transmittance over a height dz along w (unit extinction)."""
    if wp.abs(dz) <= MIN_THICKNESS:
        return 1.0
    return wp.exp(-wp.abs(dz / w[2]))


@wp.func
def _quantised(x: float) -> wp.uint32:
    return wp.uint32(wp.int32(wp.clamp(x, -1.0, 1.0) * 8388608.0))


@wp.func
def walk_rng(a: wp.vec3, c: wp.vec3, seed: float) -> wp.uint32:
    """An RNG state that is a hash of two vectors and the per-sample seed (pbrt: Hash(wo), Hash(wi))."""
    h = hash_u32(_quantised(a[0]) ^ wp.uint32(0x68E31DA4))
    h = hash_u32(h ^ _quantised(a[1]))
    h = hash_u32(h ^ _quantised(a[2]))
    h = hash_u32(h ^ _quantised(c[0]))
    h = hash_u32(h ^ _quantised(c[1]))
    h = hash_u32(h ^ _quantised(c[2]))
    h = hash_u32(h ^ wp.uint32(wp.int32(wp.clamp(seed, 0.0, 1.0) * 16777216.0)))
    return wp.rand_init(wp.int32(h))


@wp.func
def _up(wo: wp.vec3) -> float:
    """Two-sided: the sign that brings wo above the surface."""
    return wp.where(wo[2] < 0.0, -1.0, 1.0)


@wp.func
def _walk_flags(L: Slab, specular: bool) -> int:
    """pbrt's flags of a path through the layers: specular only if every vertex was; else diffuse
    when the base or the medium is, glossy otherwise."""
    if specular:
        return REFLECTION | SPECULAR
    if L.bottom.kind == LAMBERT or max3(L.albedo) > 0.0:
        return REFLECTION | DIFFUSE
    return REFLECTION | GLOSSY


@lru_cache(maxsize=None)
def walk(top: int, bottom: int, top_smooth: bool = False) -> tuple[wp.Function, wp.Function]:
    """The random walk between a ``top`` and a ``bottom`` interface of these kinds (``top_smooth``:
    every top of the kernel's materials of this kind has alpha 0): ``(eval_pdf(L, wo, wi) ->
    BSDFEval, sample(L, wo, u) -> BSDFSample)`` of a :class:`Slab`, as a material's ``eval_pdf``
    and ``sample``."""
    top_f, top_sample, top_delta = INTERFACES[(top, top_smooth)]
    base_f, base_sample, base_delta = INTERFACES[(bottom, False)]

    @wp.func
    def exit_pdf(L: Slab, wi: wp.vec3, w: wp.vec3) -> float:
        """The density with which the exit strategy (a direction sampled through the top from wi)
        picks the inside direction w: the MIS partner of a walk vertex that continues along w. pbrt
        uses the top's density of wi given -w here instead, a different measure, so its weights do
        not sum to 1 and its f runs some 5-10 % above its own sampling for rough coats."""
        return wp.static(top_f)(L.top, L.coat, wi, -w, TRANSMISSION, False).pdf

    @wp.func(inline=True)
    def layered_f(L: Slab, wo_in: wp.vec3, wi_in: wp.vec3) -> wp.vec3:
        """pbrt's stochastic estimate of f(wo, wi) (see the module docstring), for an opaque base:
        light leaves through the top, so wi below wo's side gives 0."""
        sgn = _up(wo_in)
        wo = wo_in * sgn
        wi = wi_in * sgn
        if wi[2] <= 0.0 or wo[2] == 0.0:
            return wp.vec3(0.0)
        thick = wp.max(L.thickness, MIN_THICKNESS)
        n = wp.max(L.n_samples, 1)
        top_specular = wp.static(top_delta)(L.top)
        base_specular = wp.static(base_delta)(L.bottom)
        scatters = max3(L.albedo) > 0.0
        f = wp.static(top_f)(L.top, L.coat, wo, wi, BOTH, True).f * float(n)
        rng = walk_rng(wo, wi, L.seed)
        for _s in range(n):
            wos = wp.static(top_sample)(L.top, L.coat, wo,
                                        wp.vec3(wp.randf(rng), wp.randf(rng), wp.randf(rng)), TRANSMISSION, True)
            wis = wp.static(top_sample)(L.top, L.coat, wi,
                                        wp.vec3(wp.randf(rng), wp.randf(rng), wp.randf(rng)), TRANSMISSION, False)
            if _ok(wos) and _ok(wis):
                beta = wos.weight
                z = thick
                w = wos.wi
                wis_f = wis.weight / wp.abs(wis.wi[2])      # f / pdf of the exit direction, without its cosine
                for depth in range(L.max_depth):
                    if depth > 3 and max3(beta) < 0.25:
                        q = wp.max(0.0, 1.0 - max3(beta))
                        if wp.randf(rng) < q:
                            break
                        beta = beta / (1.0 - q)
                    if not scatters:
                        z = wp.where(z == thick, 0.0, thick)
                        beta = beta * _tr(thick, w)
                    else:
                        dz = -wp.log(1.0 - wp.min(wp.randf(rng), 0.99999994)) * wp.abs(w[2])
                        zp = wp.where(w[2] > 0.0, z + dz, z - dz)
                        if zp == z:
                            continue
                        if zp > 0.0 and zp < thick:
                            # a scattering event in the slab: connect to the exit direction, then scatter
                            wt = float(1.0)
                            if not top_specular:
                                wt = power_heuristic(wis.pdf, hg_phase(-w, -wis.wi, L.g))
                            f += wp.cw_mul(wp.cw_mul(beta, L.albedo), wis_f) * (hg_phase(-w, -wis.wi, L.g) * wt
                                                                                * _tr(zp - thick, wis.wi))
                            wn = hg_sample(-w, L.g, wp.vec2(wp.randf(rng), wp.randf(rng)))
                            if wn[2] == 0.0:
                                continue
                            p_phase = hg_phase(-w, wn, L.g)
                            beta = wp.cw_mul(beta, L.albedo)
                            w = wn
                            z = zp
                            if w[2] > 0.0 and not top_specular:
                                ex = wp.static(top_f)(L.top, L.coat, -w, wi, TRANSMISSION, True)
                                if max3(ex.f) > 0.0:
                                    wt = power_heuristic(p_phase, wp.static(exit_pdf)(L, wi, w))
                                    f += wp.cw_mul(beta, ex.f) * (_tr(zp - thick, w) * wt)
                            continue
                        z = wp.clamp(zp, 0.0, thick)
                    if z == thick:
                        # internal reflection at the top
                        bs = wp.static(top_sample)(L.top, L.coat, -w,
                                                   wp.vec3(wp.randf(rng), wp.randf(rng), wp.randf(rng)),
                                                   REFLECTION, True)
                        if not _ok(bs):
                            break
                        beta = wp.cw_mul(beta, bs.weight)
                        w = bs.wi
                    else:
                        # the base: connect to the exit direction, then reflect
                        if not base_specular:
                            eb = wp.static(base_f)(L.bottom, L.coat, -w, -wis.wi, BOTH, True)
                            wt = float(1.0)
                            if not top_specular:
                                wt = power_heuristic(wis.pdf, eb.pdf)
                            f += wp.cw_mul(wp.cw_mul(beta, eb.f), wis.weight) * (wt * _tr(thick, wis.wi))
                        bs = wp.static(base_sample)(L.bottom, L.coat, -w,
                                                    wp.vec3(wp.randf(rng), wp.randf(rng), wp.randf(rng)),
                                                    REFLECTION, True)
                        if not _ok(bs):
                            break
                        beta = wp.cw_mul(beta, bs.weight)
                        w = bs.wi
                        if not top_specular:
                            ex = wp.static(top_f)(L.top, L.coat, -w, wi, TRANSMISSION, True)
                            if max3(ex.f) > 0.0:
                                wt = float(1.0)
                                if not base_specular:
                                    wt = power_heuristic(bs.pdf, wp.static(exit_pdf)(L, wi, w))
                                f += wp.cw_mul(beta, ex.f) * (_tr(thick, bs.wi) * wt)
        return f / float(n)

    @wp.func(inline=True)
    def layered_pdf(L: Slab, wo_in: wp.vec3, wi_in: wp.vec3) -> float:
        """pbrt's approximate density of ``layered_sample`` at wi: the top's reflection lobe plus one
        transmit-reflect-transmit bounce (MIS-combined when both interfaces are rough), mixed with a
        uniform density (10 %). wi below wo's side gets only the uniform part."""
        sgn = _up(wo_in)
        wo = wo_in * sgn
        wi = wi_in * sgn
        n = wp.max(L.n_samples, 1)
        total = float(0.0)
        if wo[2] * wi[2] > 0.0:
            total = wp.static(top_f)(L.top, L.coat, wo, wi, REFLECTION, True).pdf * float(n)
            top_specular = wp.static(top_delta)(L.top)
            base_specular = wp.static(base_delta)(L.bottom)
            rng = walk_rng(wi, wo, L.seed)
            for _s in range(n):
                wos = wp.static(top_sample)(L.top, L.coat, wo,
                                            wp.vec3(wp.randf(rng), wp.randf(rng), wp.randf(rng)), TRANSMISSION, True)
                wis = wp.static(top_sample)(L.top, L.coat, wi,
                                            wp.vec3(wp.randf(rng), wp.randf(rng), wp.randf(rng)), TRANSMISSION, False)
                if wos.pdf > 0.0 and max3(wos.weight) > 0.0 and wis.pdf > 0.0 and max3(wis.weight) > 0.0:
                    if top_specular:
                        total += wp.static(base_f)(L.bottom, L.coat, -wos.wi, -wis.wi, BOTH, True).pdf
                    else:
                        rs = wp.static(base_sample)(L.bottom, L.coat, -wos.wi,
                                                    wp.vec3(wp.randf(rng), wp.randf(rng), wp.randf(rng)), BOTH, True)
                        if rs.pdf > 0.0 and max3(rs.weight) > 0.0:
                            if base_specular:
                                total += wp.static(top_f)(L.top, L.coat, -rs.wi, wi, BOTH, True).pdf
                            else:
                                p_r = wp.static(base_f)(L.bottom, L.coat, -wos.wi, -wis.wi, BOTH, True).pdf
                                total += power_heuristic(wis.pdf, p_r) * p_r
                                p_t = wp.static(top_f)(L.top, L.coat, -rs.wi, wi, BOTH, True).pdf
                                total += power_heuristic(rs.pdf, p_t) * p_t
        return 0.1 / (4.0 * PI) + 0.9 * total / float(n)

    @wp.func(inline=True)
    def walk_out(L: Slab, wo_in: wp.vec3, u: wp.vec3) -> BSDFSample:
        """pbrt's random walk: reflect off the top, or refract in and walk until the path leaves
        through the top (or is absorbed, ends by roulette or reaches max_depth: a failed sample).
        A sample that is not specular has no density yet (see ``layered_sample``)."""
        sgn = _up(wo_in)
        wo = wo_in * sgn
        bs = wp.static(top_sample)(L.top, L.coat, wo, u, BOTH, True)
        if not _ok(bs):
            return failed_sample()
        if bs.wi[2] > 0.0:
            bs.wi = bs.wi * sgn
            return bs
        thick = wp.max(L.thickness, MIN_THICKNESS)
        scatters = max3(L.albedo) > 0.0
        specular = (bs.flags & SPECULAR) != 0
        beta = bs.weight
        w = bs.wi
        z = thick
        rng = walk_rng(wo, u, L.seed)
        for depth in range(L.max_depth):
            if depth > 3 and max3(beta) < 0.25:
                q = wp.max(0.0, 1.0 - max3(beta))
                if wp.randf(rng) < q:
                    return failed_sample()
                beta = beta / (1.0 - q)
            if w[2] == 0.0:
                return failed_sample()
            at_boundary = True
            if scatters:
                dz = -wp.log(1.0 - wp.min(wp.randf(rng), 0.99999994)) * wp.abs(w[2])
                zp = wp.where(w[2] > 0.0, z + dz, z - dz)
                if zp == z:
                    return failed_sample()
                if zp > 0.0 and zp < thick:
                    wn = hg_sample(-w, L.g, wp.vec2(wp.randf(rng), wp.randf(rng)))
                    if wn[2] == 0.0:
                        return failed_sample()
                    beta = wp.cw_mul(beta, L.albedo)
                    specular = False
                    w = wn
                    z = zp
                    at_boundary = False
                else:
                    z = wp.clamp(zp, 0.0, thick)
            else:
                z = wp.where(z == thick, 0.0, thick)
                beta = beta * _tr(thick, w)
            if at_boundary:
                u3 = wp.vec3(wp.randf(rng), wp.randf(rng), wp.randf(rng))
                s = BSDFSample()
                if z == thick:
                    s = wp.static(top_sample)(L.top, L.coat, -w, u3, BOTH, True)
                else:
                    s = wp.static(base_sample)(L.bottom, L.coat, -w, u3, BOTH, True)
                if not _ok(s):
                    return failed_sample()
                beta = wp.cw_mul(beta, s.weight)
                specular = specular and (s.flags & SPECULAR) != 0
                w = s.wi
                if (s.flags & TRANSMISSION) != 0:
                    out = BSDFSample()
                    out.wi = w * sgn
                    out.weight = beta
                    out.flags = _walk_flags(L, specular)
                    out.pdf = 1.0
                    return out
        return failed_sample()

    @wp.func
    def layered_sample(L: Slab, wo_in: wp.vec3, u: wp.vec3) -> BSDFSample:
        """The walk's sample with ``layered_pdf``'s density when it is not specular, estimated after
        the walk rather than inside it: on a GPU the two then do not nest on the stack."""
        s = wp.static(walk_out)(L, wo_in, u)
        if s.pdf > 0.0 and (s.flags & SPECULAR) == 0:
            s.pdf = wp.static(layered_pdf)(L, wo_in, s.wi)
        return s

    @wp.func
    def layered_eval_pdf(L: Slab, wo: wp.vec3, wi: wp.vec3) -> BSDFEval:
        """f and pdf together, as a material's ``eval_pdf`` (two independent estimates)."""
        ev = BSDFEval()
        ev.f = wp.static(layered_f)(L, wo, wi)
        ev.pdf = wp.static(layered_pdf)(L, wo, wi)
        return ev

    return layered_eval_pdf, layered_sample


@lru_cache(maxsize=None)
def walk_alone(slab: wp.Function, top: int, bottom: int, top_smooth: bool = False) -> tuple[wp.Function, wp.Function]:
    """A material's ``eval_pdf(b, wo, wi)`` and ``sample(b, wo, u)`` that are the walk alone, on the
    slab ``slab(b)`` its parameters give: for a kernel none of whose materials take another lobe."""
    walk_eval_pdf, walk_sample = walk(top, bottom, top_smooth)

    @wp.func
    def eval_pdf(b: BSDF, wo: wp.vec3, wi: wp.vec3) -> BSDFEval:
        return wp.static(walk_eval_pdf)(wp.static(slab)(b), wo, wi)

    @wp.func
    def sample(b: BSDF, wo: wp.vec3, u: wp.vec3) -> BSDFSample:
        return wp.static(walk_sample)(wp.static(slab)(b), wo, u)

    return eval_pdf, sample
