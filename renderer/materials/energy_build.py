"""Builds the energy-compensation tables of :mod:`renderer.materials.energy` by Monte Carlo over
the renderer's own single-scattering GGX lobes, and writes ``data/energy_tables.npz``.

``python -m renderer.materials.energy_build`` (about a minute per core on the Warp CPU device).
The tables hold, for the grids of :mod:`.energy` (cos θ uniform on [0, 1], alpha uniform on
[0, 1], the relative index e = exp(s ln E_MAX) with s uniform on [-1, 1]):

* ``conductor``: E(μ, α), the directional albedo of a GGX mirror whose Fresnel is 1;
* ``dielectric_r`` and ``dielectric_t``: the reflected and transmitted parts of the directional
  albedo of a rough dielectric of relative index e seen from the side the light arrives from,
  without the 1/e² radiance scaling (what energy conservation is about);
* ``refraction``: the transmitted albedo of the same interface with Fresnel 0 (every facet
  refracts), which with ``conductor`` describes a coating whose reflectance differs from F;
* ``facet_split``: K_j(μ, α, e), the same difference (reflected minus refracted G2/G1) times the
  bare transmittance 1 − F, resolved by the facet's cosine in the rarer medium (c = wo·m, or the
  refracted cosine when e < 1) onto hat functions on N_FACET uniform nodes (:mod:`.energy`), with
  FACET_STRATA² strata per entry.

Each entry is the mean over a jittered stratified grid of visible normals (Heitz 2018) of the
expected sample weight: F G2/G1 for the reflection and (1 − F) G2/G1 for the refraction, with the
same Warp functions (``ggx_sample_visible``, ``fresnel_dielectric``, ``refract``, ``ggx_G``) the
materials evaluate, so the tables complement exactly the lobes the renderer draws.
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np
import warp as wp

from renderer.materials.bsdf import refract
from renderer.materials.energy import E_MAX, N_ALPHA, N_ETA, N_FACET, N_MU, TABLE_PATH, FacetVector, node_coordinate
from renderer.materials.microfacet import ggx_G, ggx_G1, ggx_sample_visible
from renderer.optics.fresnel import fresnel_dielectric

#: Visible normals per entry: a STRATA x STRATA jittered grid.
STRATA = 96
#: Visible normals per entry of ``facet_split``: a FACET_STRATA x FACET_STRATA jittered grid.
FACET_STRATA = 160
#: The grazing node μ = 0 is evaluated at this cosine (G1 vanishes at 0).
MU_GRAZING = 2.0e-3


@wp.kernel
def _albedo(mus: wp.array(dtype=float), alphas: wp.array(dtype=float), etas: wp.array(dtype=float), strata: int,
            seed: int, out: wp.array(dtype=wp.vec3, ndim=3)):
    """out[e, a, m] = (reflected, transmitted, transmitted with F = 0) directional albedo; eta 0
    means a mirror of F = 1."""
    ie, ia, im = wp.tid()
    mu = mus[im]
    alpha = wp.vec2(alphas[ia], alphas[ia])
    eta = etas[ie]
    wo = wp.vec3(wp.sqrt(1.0 - mu * mu), 0.0, mu)
    rng = wp.rand_init(seed, (ie * 4096 + ia) * 4096 + im)
    g1 = ggx_G1(wo, alpha)
    acc_r = float(0.0)
    acc_t = float(0.0)
    acc_t0 = float(0.0)
    inv = 1.0 / float(strata)
    for k in range(strata * strata):
        u = wp.vec2((float(k % strata) + wp.randf(rng)) * inv, (float(k / strata) + wp.randf(rng)) * inv)
        wm = ggx_sample_visible(wo, alpha, u)
        F = float(1.0)
        if eta > 0.0:
            F = fresnel_dielectric(wp.dot(wo, wm), eta)
        wr = wm * (2.0 * wp.dot(wo, wm)) - wo
        if wr[2] > 0.0:
            acc_r += F * ggx_G(wo, wr, alpha) / g1
        if eta > 0.0 and F < 1.0:
            t = refract(wo, wm, eta)
            wt = wp.vec3(t[0], t[1], t[2])
            if t[3] != 0.0 and wt[2] < 0.0:
                g = ggx_G(wo, wt, alpha) / g1
                acc_t += (1.0 - F) * g
                acc_t0 += g
    n = float(strata * strata)
    out[ie, ia, im] = wp.vec3(acc_r / n, acc_t / n, acc_t0 / n)


@wp.func
def facet_masking(wo: wp.vec3, wm: wp.vec3, alpha: wp.vec2, eta: float, g1: float) -> wp.vec2:
    """G2(wo, wr)/G1(wo) and G2(wo, wt)/G1(wo) of facet wm's mirror and refracted directions (wo
    above, relative index eta), 0 where that direction lands on the wrong side or refraction fails:
    a visible facet's chance to send each out unshadowed."""
    c = wp.dot(wo, wm)
    out = wp.vec2(0.0)
    wr = wm * (2.0 * c) - wo
    if wr[2] > 0.0:
        out[0] = ggx_G(wo, wr, alpha) / g1
    t = refract(wo, wm, eta)
    wt = wp.vec3(t[0], t[1], t[2])
    if t[3] != 0.0 and wt[2] < 0.0:
        out[1] = ggx_G(wo, wt, alpha) / g1
    return out


@wp.kernel
def _facet_split(mus: wp.array(dtype=float), alphas: wp.array(dtype=float), etas: wp.array(dtype=float), strata: int,
                 seed: int, out: wp.array(dtype=FacetVector, ndim=3)):
    """out[e, a, m][j] = the mean of h_j(c) (1 − F(c)) (G2(wo, wr) − G2(wo, wt)) / G1(wo) over visible normals
    m, c = wo·m, h_j on the cosine in the rarer medium (:func:`.energy.node_coordinate`)."""
    ie, ia, im = wp.tid()
    mu = mus[im]
    alpha = wp.vec2(alphas[ia], alphas[ia])
    eta = etas[ie]
    wo = wp.vec3(wp.sqrt(1.0 - mu * mu), 0.0, mu)
    rng = wp.rand_init(seed, (ie * 4096 + ia) * 4096 + im)
    g1 = ggx_G1(wo, alpha)
    acc = FacetVector()
    inv = 1.0 / float(strata)
    for k in range(strata * strata):
        u = wp.vec2((float(k % strata) + wp.randf(rng)) * inv, (float(k / strata) + wp.randf(rng)) * inv)
        wm = ggx_sample_visible(wo, alpha, u)
        c = wp.dot(wo, wm)
        gs = facet_masking(wo, wm, alpha, eta, g1)
        g = (gs[0] - gs[1]) * (1.0 - fresnel_dielectric(c, eta))
        x = wp.clamp(node_coordinate(c, eta), 0.0, 1.0) * float(N_FACET - 1)
        j = wp.min(int(x), N_FACET - 2)
        f = x - float(j)
        acc[j] = acc[j] + g * (1.0 - f)
        acc[j + 1] = acc[j + 1] + g * f
    out[ie, ia, im] = acc / float(strata * strata)


def build(strata: int = STRATA, seed: int = 1) -> dict[str, np.ndarray]:
    """The tables on the grids of :mod:`.energy`; α = 0 (a smooth lobe, never compensated) is 1.
    The node e = 1 is the limit of rough facets between nearly equal media (F = 0, the
    straight-through refraction shadowed by G2/G1), which interpolation towards e = 1 needs;
    the materials themselves treat e = 1 as no interface."""
    wp.init()
    mus = np.linspace(0.0, 1.0, N_MU)
    mus[0] = MU_GRAZING
    alphas = np.linspace(0.0, 1.0, N_ALPHA)
    alphas[0] = alphas[1] * 1.0e-2          # the kernel needs alpha > 0; overwritten with 1 below
    s = np.linspace(-1.0, 1.0, N_ETA)
    etas = np.concatenate([[0.0], np.exp(s * np.log(E_MAX))])
    etas[1 + N_ETA // 2] = 1.0
    out = wp.zeros((len(etas), N_ALPHA, N_MU), dtype=wp.vec3, device="cpu")
    args = [wp.array(a.astype(np.float32), dtype=float, device="cpu") for a in (mus, alphas, etas)]
    wp.launch(_albedo, dim=out.shape, inputs=[*args, strata, seed, out], device="cpu")
    o = out.numpy().astype(np.float64)
    r, t, t0 = o[..., 0], o[..., 1], o[..., 2]
    r[:, 0, :], t[:, 0, :], t0[:, 0, :] = 1.0, 0.0, 1.0
    return {"facet_split": facet_split(mus, alphas, etas[1:], seed), "conductor": r[0].astype(np.float32), "dielectric_r": r[1:].astype(np.float32),
            "dielectric_t": t[1:].astype(np.float32), "refraction": t0[1:].astype(np.float32),
            "strata": np.int32(strata), "seed": np.int32(seed)}


def facet_split(mus: np.ndarray, alphas: np.ndarray, etas: np.ndarray, seed: int,
                strata: int = FACET_STRATA) -> np.ndarray:
    """K (eta, alpha, mu, node), float32; the smooth row alpha = 0 is 0 (every facet is the normal)."""
    out = wp.zeros((len(etas), N_ALPHA, N_MU), dtype=FacetVector, device="cpu")
    args = [wp.array(a.astype(np.float32), dtype=float, device="cpu") for a in (mus, alphas, etas)]
    wp.launch(_facet_split, dim=out.shape, inputs=[*args, strata, seed, out], device="cpu")
    k = out.numpy().astype(np.float64)
    k[:, 0] = 0.0
    return k.astype(np.float32)


def main() -> None:
    t0 = time.perf_counter()
    tables = build()
    np.savez_compressed(TABLE_PATH, **tables)
    e = tables["dielectric_r"] + tables["dielectric_t"]
    print(f"wrote {TABLE_PATH} in {time.perf_counter() - t0:.0f} s: conductor E in "
          f"[{tables['conductor'].min():.3f}, {tables['conductor'].max():.3f}], dielectric E in "
          f"[{e.min():.3f}, {e.max():.3f}]", file=sys.stderr)


if __name__ == "__main__":
    main()
