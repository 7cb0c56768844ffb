"""Energy compensation for rough GGX interfaces (``"bool multiscatter"``): the light that bounces
between microfacets before it leaves, which single scattering drops.

Kulla and Conty's (2017) additional lobe, from tables our own Monte Carlo computed
(:mod:`.energy_build`, committed as ``data/energy_tables.npz``):

* Reflection only (``conductor``, an opaque ``thinfilm``): with E(μ) the directional albedo of a
  GGX mirror of Fresnel 1 and Ē = 2∫E μ dμ,
  f_ms = F_ms (1 − E(μo)) (1 − E(μi)) / (π (1 − Ē)),  F_ms = F̄² Ē / (1 − F̄ (1 − Ē)),
  F̄ = 2∫F μ dμ per channel from the material's own Fresnel. For F = 1 the albedo is exactly 1.
* A dielectric of relative index e (seen from side A, the side of wo; B is the other side, of
  index 1/e) loses 1 − E_A(μo) of its energy (E_A: reflected plus transmitted single-scattering
  albedo, without the 1/e² radiance scaling). The lobe puts a fraction 1 − x_A of it back as
  reflection, (1 − x_A)(1 − E_A(μo))(1 − E_A(μi)) / (π(1 − Ē_A)), and x_A as transmission,
  g e (1 − E_A(μo))(1 − E_B(μi)) / (π(1 − Ē_A)(1 − Ē_B)), with x_A = g e / (1 − Ē_A). The stored g
  is even in ln e, which makes η_A² f(A→B) = η_B² f(B→A) (reciprocity of refraction) hold for any
  interpolated value; g is set from the outside (e > 1) so that the multiply scattered light
  splits between reflection and transmission as the single scattering does on average
  (x = T̄_ss / Ē), clipped where the inside could not take it (x ≤ 1 on both sides).

Energy is exact for the tables: E is piecewise linear in μ and Ē is its exact cosine-weighted
integral at every node, and both are interpolated multilinearly in (alpha, ln e), so
∫(1 − E(μi)) μi dωi / π = 1 − Ē at any alpha and e. The tables' own error against the lobes is
their Monte Carlo and interpolation error (see docs/materials.md, "Energy").

A coating (``thinfilm`` over a clear substrate) changes which facets reflect: its reflectance R(c) at
the facet cosine c = wo·m differs from the bare interface's F(c). The table K_j(μ, α, e) =
∫ h_j(c) (1 − F(c)) (G2(wo, wr) − G2(wo, wt)) / G1(wo) dP(m) (the visible-normal distribution P, the
reflected and refracted directions wr and wt, h_j the hat functions on FACET_NODES uniform nodes in
the cosine on the rarer side, u = c for e ≥ 1 and the refracted cosine for e < 1, so that from the
denser side the nodes spread over the narrow cone outside total internal reflection)
makes the coating's single-scattering albedo E_coat(μ) = E_d(μ) + Σ_j ρ(c_j) K_j(μ), ρ = (R − F)/(1 − F),
exact for R + T = 1 up to the linear interpolation of ρ between the nodes (:mod:`.coating_energy`).

Anisotropic alpha uses sqrt(αx αy); alpha above 1 uses the alpha = 1 row; e is clamped to
[1/E_MAX, E_MAX]. The tables sit in the scene's layer table from row ENERGY_FIRST on, present
only when a material of the scene has ``multiscatter`` on (:func:`rows`).
"""
from __future__ import annotations

from functools import lru_cache
from pathlib import Path

import numpy as np
import warp as wp

from renderer.materials.bsdf import signed_z
from renderer.sampling.warps import cosine_hemisphere
from renderer.vecmath import INV_PI

TABLE_PATH = Path(__file__).parent / "data" / "energy_tables.npz"
N_MU = 32        # cos θ, uniform on [0, 1]
N_ALPHA = 32     # alpha, uniform on [0, 1]
N_ETA = 33       # s = ln e / ln E_MAX, uniform on [-1, 1] (odd: e = 1 is a node)
E_MAX = 3.0
#: Nodes of the midpoint rule in μ² that averages a Fresnel term over the hemisphere.
MEAN_NODES = wp.constant(8)

#: The tables' first row in the layer table (row 0 is the table's dummy row).
ENERGY_FIRST = wp.constant(1)
_OFF_C = 0
_OFF_CAVG = _OFF_C + N_ALPHA * N_MU
_OFF_D = _OFF_CAVG + N_ALPHA
_OFF_DAVG = _OFF_D + N_ETA * N_ALPHA * N_MU
_OFF_G = _OFF_DAVG + N_ETA * N_ALPHA
_OFF_T0 = _OFF_G + (N_ETA // 2 + 1) * N_ALPHA
#: Nodes of the coating's facet cosine c (uniform on [0, 1], a multiple of 4: a node vector is whole rows).
N_FACET = 12
_OFF_K = _OFF_T0 + N_ETA * N_ALPHA * N_MU
_OFF_KAVG = _OFF_K + N_ETA * N_ALPHA * N_MU * N_FACET
_SIZE = _OFF_KAVG + N_ETA * N_ALPHA * N_FACET
OFF_C, OFF_CAVG, OFF_D, OFF_DAVG, OFF_G, OFF_T0, OFF_K, OFF_KAVG = (
    wp.constant(v) for v in (_OFF_C, _OFF_CAVG, _OFF_D, _OFF_DAVG, _OFF_G, _OFF_T0, _OFF_K, _OFF_KAVG))
FACET_NODES = wp.constant(N_FACET)
#: A value per facet-cosine node.
FacetVector = wp.types.vector(length=N_FACET, dtype=float)
LOG_E_MAX = wp.constant(float(np.log(E_MAX)))


def cosine_mean(e: np.ndarray) -> np.ndarray:
    """2∫E(μ) μ dμ of E piecewise linear on the uniform μ grid (last axis), exactly."""
    mu = np.linspace(0.0, 1.0, e.shape[-1])
    a, b = mu[:-1], mu[1:]
    h = b - a
    return 2.0 * (h / 6.0 * (e[..., :-1] * (2 * a + b) + e[..., 1:] * (a + 2 * b))).sum(axis=-1)


@lru_cache(maxsize=1)
def table_values() -> np.ndarray:
    """The flat float table the device reads (conductor E, Ē, dielectric E, Ē, g, refraction E, the facet
    weights K and their cosine means), float32."""
    t = np.load(TABLE_PATH)
    ec = t["conductor"].astype(np.float64)                   # (alpha, mu)
    ed = (t["dielectric_r"] + t["dielectric_t"]).astype(np.float64)    # (eta, alpha, mu)
    eavg_c = cosine_mean(ec)
    eavg_d = cosine_mean(ed)
    tavg_d = cosine_mean(t["dielectric_t"].astype(np.float64))
    e = np.exp(np.linspace(-1.0, 1.0, N_ETA) * np.log(E_MAX))
    half = N_ETA // 2
    out_, in_ = slice(half, None), slice(half, None, -1)     # e >= 1 and its mirror 1/e, from e = 1 up
    loss_out, loss_in = 1.0 - eavg_d[out_], 1.0 - eavg_d[in_]
    x_out = np.divide(tavg_d[out_], eavg_d[out_], out=np.zeros_like(loss_out), where=eavg_d[out_] > 0)
    g = x_out * loss_out / e[out_, None]
    g = np.minimum(g, np.maximum(loss_in, 0.0) * e[out_, None])   # x_in = g / (e_in (1 - Ē_in)) ≤ 1
    k = t["facet_split"].astype(np.float64)                  # (eta, alpha, mu, node)
    kavg = cosine_mean(np.moveaxis(k, -2, -1))               # (eta, alpha, node)
    flat = np.concatenate([ec.ravel(), eavg_c, ed.ravel(), eavg_d.ravel(), g.ravel(), t["refraction"].ravel(),
                           k.ravel(), kavg.ravel()])
    assert flat.size == _SIZE
    return flat.astype(np.float32)


def rows() -> np.ndarray:
    """The tables as layer-table rows (n, 4), to be placed at row ENERGY_FIRST."""
    flat = table_values()
    pad = np.zeros((-flat.size) % 4, np.float32)
    return np.concatenate([flat, pad]).reshape(-1, 4)


@wp.func
def _at(layers: wp.array(dtype=wp.vec4), i: int) -> float:
    r = i / 4
    return layers[ENERGY_FIRST + r][i - 4 * r]


@wp.func
def _cell(x: float, n: int) -> wp.vec2:
    """Grid cell (index, fraction) of x in [0, 1] on n uniform nodes."""
    t = wp.clamp(x, 0.0, 1.0) * float(n - 1)
    i = wp.min(int(t), n - 2)
    return wp.vec2(float(i), t - float(i))


@wp.func
def effective_alpha(alpha: wp.vec2) -> float:
    return wp.sqrt(wp.max(alpha[0], 0.0) * wp.max(alpha[1], 0.0))


@wp.func
def _bilinear(layers: wp.array(dtype=wp.vec4), base: int, a: wp.vec2, m: wp.vec2) -> float:
    """A (alpha, mu) plane at base: rows alpha, columns mu."""
    ia = int(a[0])
    im = int(m[0])
    i00 = base + ia * N_MU + im
    lo = _at(layers, i00) * (1.0 - m[1]) + _at(layers, i00 + 1) * m[1]
    hi = _at(layers, i00 + N_MU) * (1.0 - m[1]) + _at(layers, i00 + N_MU + 1) * m[1]
    return lo * (1.0 - a[1]) + hi * a[1]


@wp.func
def _line(layers: wp.array(dtype=wp.vec4), base: int, a: wp.vec2) -> float:
    ia = int(a[0])
    return _at(layers, base + ia) * (1.0 - a[1]) + _at(layers, base + ia + 1) * a[1]


@wp.func
def _eta_cell(e: float) -> wp.vec2:
    return _cell(0.5 * (wp.log(wp.max(e, 1.0e-6)) / LOG_E_MAX + 1.0), N_ETA)


@wp.func
def mirror_albedo(layers: wp.array(dtype=wp.vec4), mu: float, alpha: float) -> float:
    """E(μ): the single-scattering albedo of a GGX mirror of Fresnel 1."""
    return _bilinear(layers, OFF_C, _cell(alpha, N_ALPHA), _cell(mu, N_MU))


@wp.func
def mirror_albedo_mean(layers: wp.array(dtype=wp.vec4), alpha: float) -> float:
    return _line(layers, OFF_CAVG, _cell(alpha, N_ALPHA))


@wp.func
def dielectric_albedo(layers: wp.array(dtype=wp.vec4), mu: float, alpha: float, e: float) -> float:
    """E(μ) of a rough dielectric of relative index e seen from the side of incidence."""
    return _trilinear(layers, OFF_D, mu, alpha, e)


@wp.func
def refraction_albedo(layers: wp.array(dtype=wp.vec4), mu: float, alpha: float, e: float) -> float:
    """The transmitted albedo of the same interface with Fresnel 0: every facet refracts."""
    return _trilinear(layers, OFF_T0, mu, alpha, e)


@wp.func
def _trilinear(layers: wp.array(dtype=wp.vec4), first: int, mu: float, alpha: float, e: float) -> float:
    s = _eta_cell(e)
    base = first + int(s[0]) * N_ALPHA * N_MU
    a = _cell(alpha, N_ALPHA)
    m = _cell(mu, N_MU)
    lo = _bilinear(layers, base, a, m)
    hi = _bilinear(layers, base + N_ALPHA * N_MU, a, m)
    return lo * (1.0 - s[1]) + hi * s[1]


@wp.func
def dielectric_albedo_mean(layers: wp.array(dtype=wp.vec4), alpha: float, e: float) -> float:
    s = _eta_cell(e)
    a = _cell(alpha, N_ALPHA)
    base = OFF_DAVG + int(s[0]) * N_ALPHA
    return _line(layers, base, a) * (1.0 - s[1]) + _line(layers, base + N_ALPHA, a) * s[1]


@wp.func
def _facet_row(layers: wp.array(dtype=wp.vec4), at: int) -> FacetVector:
    """The node vector whose first float is at (a multiple of 4)."""
    v = FacetVector()
    first = ENERGY_FIRST + at / 4
    for r in range(FACET_NODES / 4):
        q = layers[first + r]
        for j in range(4):
            v[4 * r + j] = q[j]
    return v


@wp.func
def node_coordinate(c: float, e: float) -> float:
    """u: the facet's cosine on the rarer side of the interface, where the nodes are uniform: c itself
    for e ≥ 1, the refracted cosine for e < 1 (0 under total internal reflection)."""
    if e >= 1.0:
        return c
    return wp.sqrt(wp.max(0.0, 1.0 - (1.0 - c * c) / (e * e)))


@wp.func
def node_cosine(u: float, e: float) -> float:
    """The facet cosine c on the side of relative index e whose node coordinate is u."""
    if e >= 1.0:
        return u
    return wp.sqrt(wp.max(0.0, 1.0 - e * e * (1.0 - u * u)))


@wp.func
def facet_weights(layers: wp.array(dtype=wp.vec4), mu: float, alpha: float, e: float) -> FacetVector:
    """K_j(μ, α, e): how much the coating's (R − F)/(1 − F) at node j adds to its albedo seen at cosine mu."""
    s = _eta_cell(e)
    a = _cell(alpha, N_ALPHA)
    m = _cell(mu, N_MU)
    out = FacetVector()
    for corner in range(8):
        ds = corner & 1
        da = (corner >> 1) & 1
        dm = (corner >> 2) & 1
        w = wp.where(ds == 1, s[1], 1.0 - s[1]) * wp.where(da == 1, a[1], 1.0 - a[1]) * wp.where(dm == 1, m[1],
                                                                                               1.0 - m[1])
        node = ((int(s[0]) + ds) * N_ALPHA + int(a[0]) + da) * N_MU + int(m[0]) + dm
        out = out + _facet_row(layers, OFF_K + node * FACET_NODES) * w
    return out


@wp.func
def facet_weights_mean(layers: wp.array(dtype=wp.vec4), alpha: float, e: float) -> FacetVector:
    """K̄_j = 2∫K_j(μ) μ dμ, exactly for K piecewise linear in μ."""
    s = _eta_cell(e)
    a = _cell(alpha, N_ALPHA)
    out = FacetVector()
    for corner in range(4):
        ds = corner & 1
        da = (corner >> 1) & 1
        w = wp.where(ds == 1, s[1], 1.0 - s[1]) * wp.where(da == 1, a[1], 1.0 - a[1])
        node = (int(s[0]) + ds) * N_ALPHA + int(a[0]) + da
        out = out + _facet_row(layers, OFF_KAVG + node * FACET_NODES) * w
    return out


@wp.func
def _split(layers: wp.array(dtype=wp.vec4), alpha: float, e: float) -> float:
    """g(alpha, |ln e|): the stored transmission share, even in ln e."""
    s = _cell(wp.abs(wp.log(wp.max(e, 1.0e-6))) / LOG_E_MAX, N_ETA // 2 + 1)
    a = _cell(alpha, N_ALPHA)
    base = OFF_G + int(s[0]) * N_ALPHA
    return _line(layers, base, a) * (1.0 - s[1]) + _line(layers, base + N_ALPHA, a) * s[1]


@wp.func
def _series(fbar: float, eavg: float) -> float:
    """F_ms: the bounces after the first, each reflecting fbar and escaping with Ē."""
    return fbar * fbar * eavg / (1.0 - fbar * (1.0 - eavg))


@wp.func
def mirror_multiple(layers: wp.array(dtype=wp.vec4), alpha: wp.vec2, mu_o: float, mu_i: float, fbar: wp.vec3) -> wp.vec3:
    """Kulla–Conty's reflection lobe f_ms (without the cosine) for hemispherical Fresnel means fbar."""
    a = effective_alpha(alpha)
    eavg = mirror_albedo_mean(layers, a)
    loss = 1.0 - eavg
    if loss <= 1.0e-6:
        return wp.vec3(0.0)
    lobe = (1.0 - mirror_albedo(layers, mu_o, a)) * (1.0 - mirror_albedo(layers, mu_i, a)) * INV_PI / loss
    return wp.vec3(_series(fbar[0], eavg), _series(fbar[1], eavg), _series(fbar[2], eavg)) * lobe


@wp.func
def mirror_lost(layers: wp.array(dtype=wp.vec4), alpha: wp.vec2, mu_o: float) -> float:
    """1 − E(μo): what single scattering loses, the probability of sampling the extra lobe."""
    return wp.clamp(1.0 - mirror_albedo(layers, mu_o, effective_alpha(alpha)), 0.0, 1.0)


@wp.func
def dielectric_lost(layers: wp.array(dtype=wp.vec4), alpha: wp.vec2, e: float, mu_o: float) -> float:
    """1 − E_A(μo) of a dielectric seen from the side of index ratio e."""
    return wp.clamp(1.0 - dielectric_albedo(layers, mu_o, effective_alpha(alpha), e), 0.0, 1.0)


@wp.func
def dielectric_transmit_share(layers: wp.array(dtype=wp.vec4), alpha: wp.vec2, e: float) -> float:
    """x_A: the share of the lost energy the lobe transmits, seen from the side of index ratio e."""
    a = effective_alpha(alpha)
    loss = 1.0 - dielectric_albedo_mean(layers, a, e)
    if loss <= 1.0e-6:
        return 0.0
    return wp.clamp(_split(layers, a, e) * e / loss, 0.0, 1.0)


@wp.func
def dielectric_multiple(layers: wp.array(dtype=wp.vec4), alpha: wp.vec2, e: float, mu_o: float, mu_i: float,
                        transmit: bool) -> float:
    """The dielectric's extra lobe (without the cosine, without the 1/e² of radiance) for wo on the
    side of index ratio e: the reflected part, or the transmitted one."""
    a = effective_alpha(alpha)
    loss_a = 1.0 - dielectric_albedo_mean(layers, a, e)
    if loss_a <= 1.0e-6:
        return 0.0
    lost_o = 1.0 - dielectric_albedo(layers, mu_o, a, e)
    if not transmit:
        x = wp.clamp(_split(layers, a, e) * e / loss_a, 0.0, 1.0)
        return (1.0 - x) * lost_o * (1.0 - dielectric_albedo(layers, mu_i, a, e)) * INV_PI / loss_a
    loss_b = 1.0 - dielectric_albedo_mean(layers, a, 1.0 / e)
    if loss_b <= 1.0e-6:
        return 0.0
    return (_split(layers, a, e) * e * lost_o * (1.0 - dielectric_albedo(layers, mu_i, a, 1.0 / e)) * INV_PI
            / (loss_a * loss_b))


@wp.func
def mixed_pdf(pdf_single: float, p_ms: float, p_t: float, transmit: bool, wi: wp.vec3) -> float:
    """The density of a sampler that draws the single-scattering lobes with probability 1 − p_ms and
    otherwise a cosine-distributed direction, transmitted with probability p_t."""
    return (1.0 - p_ms) * pdf_single + p_ms * wp.where(transmit, p_t, 1.0 - p_t) * wp.abs(wi[2]) * INV_PI


@wp.func
def extra_direction(wo: wp.vec3, u: wp.vec3, p_ms: float, p_t: float, e: float) -> wp.vec4:
    """A direction of the compensation lobe when u[2] < p_ms (xyz; w: e when it crosses, else 0),
    cosine distributed, on the other side with probability p_t; w = −1 when the single-scattering
    lobes are to be sampled instead (with u[2] rescaled by the caller)."""
    if u[2] >= p_ms:
        return wp.vec4(0.0, 0.0, 0.0, -1.0)
    wi = cosine_hemisphere(wp.vec2(u[0], u[1]))
    up = wp.where(wo[2] > 0.0, 1.0, -1.0)
    if u[2] < p_ms * p_t:
        wi = signed_z(wi, -up)
        return wp.vec4(wi[0], wi[1], wi[2], e)
    wi = signed_z(wi, up)
    return wp.vec4(wi[0], wi[1], wi[2], 0.0)
