"""Energy compensation (``multiscatter``) of a rough coating: the light that bounces between coated
microfacets, which single scattering drops, put back as Kulla and Conty's lobe, coloured by the
coating and sized by the coating's own loss.

Clear substrate. For a lossless coating (R + T = 1 at every facet) the single-scattering albedo seen
at cosine μ from side A (relative index e) is, per RGB channel,
    E_coat(μ) = E_d(μ) + ∫ ρ(c) (1 − F(c)) (G2(wo, wr) − G2(wo, wt)) / G1(wo) dP(m),
    ρ = (R − F) / (1 − F) = 1 − T / (1 − F),
E_d the bare dielectric's albedo, F its Fresnel term, c = wo·m the facet cosine, P the visible
normals. ρ, the coating's transmittance relative to the bare interface's, stays smooth through the
critical angle (both vanish there like the refracted wave's normal wavenumber), where R − F has a
kink. Interpolating ρ linearly between FACET_NODES nodes c_j turns the integral into
Σ_j ρ(c_j) K_j(μ, α, e), K tabulated with the bare 1 − F inside (:mod:`.energy`), so the loss
L(μ) = 1 − E_coat(μ) follows the coating's R wherever it changes with the angle (a mirror stack's
band edge as well as a film's slow colour shift). The nodes are uniform in the facet's cosine on
the rarer side (the refracted cosine when light arrives from the denser one), so both sides read
the coating at the same configurations and the denser side's narrow cone outside total internal
reflection gets every node; node 0 (grazing on the rarer side, where ρ is 0/0) continues node 1. The cosine mean L̄ = 2∫L μ dμ comes from
K̄_j, the exact mean of K_j, so the lobe returns exactly L(μo):
reflection (1 − x_A) L_A(μo) L_A(μi) / (π L̄_A), transmission G e L_A(μo) L_B(μi) / (π L̄_A L̄_B), with
x_A = G e / L̄_A and the symmetric G from the outside: the bare interface's transmitted share x
re-weighted by the coating's hemispherical R̄ and T̄ against the bare F̄, times L̄_out / e, clipped so
that x ≤ 1 inside; hence η_A² f(A→B) = η_B² f(B→A), and a 0 nm coating (ρ = 0) is the bare
dielectric's compensation. Each evaluation reads the coating at the FACET_NODES − 1 non-grazing
nodes from both sides, and from wi's side again where wi is not on wo's. Equal media (e = 1) are not
compensated. The hemispherical means R̄, T̄, F̄ weigh the outside nodes as cosines, which they are
unless the outside is the denser medium.

Opaque substrate: :func:`mean_reflectance` is the F̄ of Kulla and Conty's reflection lobe.
"""
from __future__ import annotations

import warp as wp

from renderer.materials.bsdf import BSDFEval, BSDFSample, failed_sample, refract, sampled, GLOSSY
from renderer.materials.coating import BOTH_SIDES, Coating, coating_eval, coating_rgb, coating_sample
from renderer.materials.energy import (FACET_NODES, MEAN_NODES, FacetVector, dielectric_albedo,
                                       dielectric_albedo_mean, dielectric_transmit_share, effective_alpha,
                                       extra_direction, facet_weights, facet_weights_mean, mixed_pdf,
                                       node_cosine)
from renderer.materials.microfacet import ggx_sample_visible, is_smooth
from renderer.optics.fresnel import fresnel_dielectric
from renderer.vecmath import INV_PI, mean3


@wp.func
def mean_reflectance(c: Coating) -> wp.vec3:
    """R̄ = 2∫R(μ) μ dμ per channel from the outside (midpoint rule in μ²): what an opaque rough
    coating's compensation lobe reflects per bounce (Kulla–Conty's F̄)."""
    r = wp.vec3(0.0)
    for j in range(MEAN_NODES):
        rj, tj = coating_rgb(c, wp.sqrt((float(j) + 0.5) / float(MEAN_NODES)))
        r += rj
    return r / float(MEAN_NODES)


@wp.struct
class FacetShift:
    """ρ(c_j) = (R − F) / (1 − F) at the facet-cosine nodes, per channel, seen from one side."""
    r: FacetVector
    g: FacetVector
    b: FacetVector


@wp.func
def _shift_total(s: FacetShift, k: FacetVector) -> wp.vec3:
    return wp.vec3(wp.dot(s.r, k), wp.dot(s.g, k), wp.dot(s.b, k))


@wp.func
def _loss(rows: wp.array(dtype=wp.vec4), s: FacetShift, mu: float, a: float, e: float) -> wp.vec3:
    """L(μ) = 1 − E_coat(μ) per channel, seen from the side of relative index e."""
    e_coat = wp.vec3(dielectric_albedo(rows, mu, a, e)) + _shift_total(s, facet_weights(rows, mu, a, e))
    return wp.max(wp.vec3(1.0) - e_coat, wp.vec3(0.0))


@wp.func
def _mean_loss(rows: wp.array(dtype=wp.vec4), s: FacetShift, a: float, e: float) -> wp.vec3:
    """L̄ = 2∫L μ dμ (L̄ ≥ 0 wherever L is, up to the clip)."""
    e_coat = wp.vec3(dielectric_albedo_mean(rows, a, e)) + _shift_total(s, facet_weights_mean(rows, a, e))
    return wp.max(wp.vec3(1.0) - e_coat, wp.vec3(0.0))


@wp.func
def _node_weight(j: int) -> float:
    """2∫h_j(μ) μ dμ of the hat function of node j: the nodes' weights in a hemispherical mean."""
    h = 1.0 / float(FACET_NODES - 1)
    if j == 0:
        return h * h / 3.0
    if j == FACET_NODES - 1:
        return (1.0 - h) * h + 2.0 * h * h / 3.0
    return 2.0 * float(j) * h * h


@wp.func
def _relative_shift(r: wp.vec3, f: float) -> wp.vec3:
    """ρ = (R − F) / (1 − F) at a node (0 where nothing refracts)."""
    if f >= 1.0 - 1.0e-6:
        return wp.vec3(0.0)
    return (r - wp.vec3(f)) / (1.0 - f)


@wp.func
def _safe_div(a: wp.vec3, b: wp.vec3) -> wp.vec3:
    return wp.vec3(wp.where(b[0] > 1.0e-6, a[0] / b[0], 0.0), wp.where(b[1] > 1.0e-6, a[1] / b[1], 0.0),
                   wp.where(b[2] > 1.0e-6, a[2] / b[2], 0.0))


@wp.struct
class CoatSide:
    """The coating at the nodes seen from one side: ρ, and the node-weighted sums of R, T and F that
    give the hemispherical means (used from the outside only)."""
    shift: FacetShift
    r: wp.vec3
    t: wp.vec3
    f: float


@wp.func
def coat_side(c: Coating, eta: float, outside: bool) -> CoatSide:
    """The coating at the FACET_NODES − 1 non-grazing nodes from the outside (relative index eta) or
    the inside (1/eta); node 0 (grazing: R = F = 1, T = 0 from either side) continues node 1.

    One side at a time: the lobe keeps one side's 36 values at most across the coating's calls, and
    takes the other side's again where wi is on it (docs/gpu.md, "The thin film's nodes")."""
    e = wp.where(outside, eta, 1.0 / eta)
    n_r = FacetVector()
    n_g = FacetVector()
    n_b = FacetVector()
    w0 = _node_weight(0)
    r_sum = wp.vec3(w0)
    t_sum = wp.vec3(0.0)
    f_sum = w0
    for jj in range(FACET_NODES - 1):
        j = FACET_NODES - 1 - jj
        u = float(j) / float(FACET_NODES - 1)
        cj = node_cosine(u, e)
        rj, tj = coating_rgb(c, wp.where(outside, cj, -cj))
        fj = fresnel_dielectric(cj, e)
        w = _node_weight(j)
        r_sum += rj * w
        t_sum += tj * w
        f_sum += fj * w
        rho = _relative_shift(rj, fj)
        n_r[j] = rho[0]
        n_g[j] = rho[1]
        n_b[j] = rho[2]
    n_r[0] = n_r[1]
    n_g[0] = n_g[1]
    n_b[0] = n_b[1]
    s = CoatSide()
    s.shift.r = n_r
    s.shift.g = n_g
    s.shift.b = n_b
    s.r = r_sum
    s.t = t_sum
    s.f = f_sum
    return s


@wp.struct
class CoatEnergy:
    """What the compensation lobe of a clear coating needs for one wo (see above)."""
    e: float              # relative index from wo's side
    side: float           # 1: wo outside, -1: inside
    shift_a: FacetShift   # ρ from wo's side (the other side's is taken again where wi is on it)
    l_o: wp.vec3          # L_A(μo)
    mean_a: wp.vec3       # L̄_A
    mean_b: wp.vec3       # L̄_B
    share: wp.vec3        # G, symmetric
    p_ms: float           # probability of sampling the lobe
    p_t: float            # and of transmitting, given the lobe


@wp.func
def coat_energy(c: Coating, eta: float, alpha: wp.vec2, wo: wp.vec3, rows: wp.array(dtype=wp.vec4)) -> CoatEnergy:
    a = effective_alpha(alpha)
    q = CoatEnergy()
    outside = wo[2] > 0.0
    q.side = wp.where(outside, 1.0, -1.0)
    q.e = wp.where(outside, eta, 1.0 / eta)
    # the other side first, reduced to its mean loss before wo's side is read
    other = coat_side(c, eta, not outside)
    q.mean_b = _mean_loss(rows, other.shift, a, wp.where(outside, 1.0 / eta, eta))
    own = coat_side(c, eta, outside)
    q.shift_a = own.shift
    q.mean_a = _mean_loss(rows, own.shift, a, q.e)
    x = dielectric_transmit_share(rows, alpha, eta)
    r_out = wp.where(outside, own.r, other.r)
    t_out = wp.where(outside, own.t, other.t)
    f_out = wp.where(outside, own.f, other.f)
    l_out = wp.where(outside, q.mean_a, q.mean_b)
    l_in = wp.where(outside, q.mean_b, q.mean_a)
    refl = r_out * ((1.0 - x) / wp.max(f_out, 1.0e-6))
    tran = t_out * (x / wp.max(1.0 - f_out, 1.0e-6))
    q.share = wp.min(wp.cw_mul(_safe_div(tran, refl + tran), l_out) / eta, l_in * eta)
    q.l_o = _loss(rows, q.shift_a, wp.abs(wo[2]), a, q.e)
    q.p_ms = wp.clamp(mean3(q.l_o), 0.0, 1.0)
    if mean3(q.l_o) > 0.0:
        x_a = wp.min(_safe_div(q.share * q.e, q.mean_a), wp.vec3(1.0))
        q.p_t = wp.clamp(mean3(wp.cw_mul(x_a, q.l_o)) / mean3(q.l_o), 0.0, 1.0)
    return q


@wp.func
def coat_multiple(q: CoatEnergy, c: Coating, eta: float, alpha: wp.vec2, wi: wp.vec3,
                  rows: wp.array(dtype=wp.vec4)) -> wp.vec3:
    """The compensation lobe at wi (without the cosine and without the 1/e² of radiance)."""
    a = effective_alpha(alpha)
    if wi[2] * q.side < 0.0:
        shift_b = coat_side(c, eta, q.side < 0.0).shift
        l_i = _loss(rows, shift_b, wp.abs(wi[2]), a, 1.0 / q.e)
        return _safe_div(wp.cw_mul(q.share * (q.e * INV_PI), wp.cw_mul(q.l_o, l_i)), wp.cw_mul(q.mean_a, q.mean_b))
    l_i = _loss(rows, q.shift_a, wp.abs(wi[2]), a, q.e)
    x_a = wp.min(_safe_div(q.share * q.e, q.mean_a), wp.vec3(1.0))
    return _safe_div(wp.cw_mul(wp.vec3(1.0) - x_a, wp.cw_mul(q.l_o, l_i)) * INV_PI, q.mean_a)


@wp.func
def coating_ms_eval(c: Coating, eta: float, alpha: wp.vec2, wo: wp.vec3, wi: wp.vec3, radiance: bool,
                    rows: wp.array(dtype=wp.vec4)) -> BSDFEval:
    """:func:`coating_eval` (both sides) plus the compensation lobe (see above); the density is that
    of :func:`coating_ms_sample`. The single-scattering part is evaluated first, so that only its
    value crosses the nodes' calls of :func:`coat_energy` rather than the nodes' values the coating's
    call at wi (docs/gpu.md, "The thin film's nodes")."""
    ev = coating_eval(c, eta, alpha, wo, wi, BOTH_SIDES, radiance)
    if eta == 1.0 or is_smooth(alpha) or wo[2] == 0.0 or wi[2] == 0.0:
        return ev
    return _with_multiple(ev, coat_energy(c, eta, alpha, wo, rows), c, eta, alpha, wo, wi, radiance, rows)


@wp.func
def _with_multiple(single: BSDFEval, q: CoatEnergy, c: Coating, eta: float, alpha: wp.vec2, wo: wp.vec3,
                   wi: wp.vec3, radiance: bool, rows: wp.array(dtype=wp.vec4)) -> BSDFEval:
    """Single scattering (``single``, :func:`coating_eval` at wo and wi) plus the lobe, for a wo whose
    CoatEnergy q is known."""
    ev = single
    transmit = wo[2] * wi[2] < 0.0
    f = coat_multiple(q, c, eta, alpha, wi, rows)
    if transmit and radiance:
        f = f / (q.e * q.e)
    ev.f = ev.f + f
    ev.pdf = mixed_pdf(ev.pdf, q.p_ms, q.p_t, transmit, wi)
    return ev


@wp.func
def coating_ms_sample(c: Coating, eta: float, alpha: wp.vec2, wo: wp.vec3, u: wp.vec3, radiance: bool,
                      rows: wp.array(dtype=wp.vec4)) -> BSDFSample:
    """:func:`coating_sample` (both sides), or with probability mean L(μo) a cosine-distributed
    reflection or transmission; weighted by :func:`coating_ms_eval` (its wo terms computed once).

    The coating's calls are ordered so that the nodes' values cross none of them: the single-scattering
    facet (a visible normal, as :func:`coating_sample` draws it) and its coating come before
    :func:`coat_energy` (whether or not that lobe is then chosen), the compensation lobe at wi is
    reduced before the coating at wi is evaluated, and that evaluation serves both the single-scattering
    sample's check (:func:`coating_sample` fails where its density is 0) and the weight."""
    if eta == 1.0 or is_smooth(alpha) or wo[2] == 0.0:
        return coating_sample(c, eta, alpha, wo, u, BOTH_SIDES, radiance)
    wm = ggx_sample_visible(wo, alpha, wp.vec2(u[0], u[1]))
    r_m, t_m = coating_rgb(c, wp.dot(wo, wm))
    mean_r = mean3(r_m)
    mean_t = mean3(t_m)
    q = coat_energy(c, eta, alpha, wo, rows)
    d = extra_direction(wo, u, q.p_ms, q.p_t, q.e)
    wi = wp.vec3(d[0], d[1], d[2])
    eta_t = d[3]
    single = d[3] < 0.0
    if single:
        # coating_sample's rough lobes with u[2] rescaled: reflection or refraction by the mean R and T at wm
        if mean_r + mean_t <= 0.0:
            return failed_sample()
        if (u[2] - q.p_ms) / (1.0 - q.p_ms) * (mean_r + mean_t) < mean_r:
            wi = wm * (2.0 * wp.dot(wo, wm)) - wo
            if wi[2] * wo[2] <= 0.0:
                return failed_sample()
            eta_t = 0.0
        else:
            refr = refract(wo, wm, eta)
            wi = wp.vec3(refr[0], refr[1], refr[2])
            if refr[3] == 0.0 or wi[2] * wo[2] >= 0.0:
                return failed_sample()
            eta_t = refr[3]
    if wi[2] == 0.0:
        return failed_sample()
    transmit = wo[2] * wi[2] < 0.0
    f = coat_multiple(q, c, eta, alpha, wi, rows)
    if transmit and radiance:
        f = f / (q.e * q.e)
    ev = coating_eval(c, eta, alpha, wo, wi, BOTH_SIDES, radiance)
    if single and ev.pdf <= 0.0:
        return failed_sample()
    ev.f = ev.f + f
    ev.pdf = mixed_pdf(ev.pdf, q.p_ms, q.p_t, transmit, wi)
    out = sampled(wo, wi, ev, GLOSSY)
    out.eta = eta_t
    return out
