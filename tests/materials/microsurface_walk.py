"""An independent reference for rough conductors: Heitz et al.'s stochastic microsurface random walk
(2016), in numpy, over a GGX surface with a uniform height distribution.

A path enters from above, meets the microsurface at a height drawn from the Smith model, reflects
on a visible microfacet (drawn with Dupuy and Benyoub's spherical caps, valid for directions below
the horizon too, which a walk needs), and repeats until it leaves. Its weight is the product of the
facets' Fresnel terms, so the mean weight is the directional albedo with every order of scattering.
The walk's first order alone is single scattering with height-correlated masking-shadowing, the
model the renderer's lobes use, which makes it a check of the walk itself.

Nothing here shares code with the renderer: it is what the energy-compensation tables are tested
against (tests/materials/test_multiscatter.py)."""
from __future__ import annotations

import numpy as np


def _lambda(w: np.ndarray, alpha: float) -> np.ndarray:
    """Smith's Λ for GGX of a direction travelling along ``w``, signed as the walk needs it:
    Λ(w) for w.z > 0 and -1 - Λ(-w) for w.z < 0."""
    z = np.clip(w[:, 2], -1.0, 1.0)
    t2 = alpha * alpha * np.maximum(1.0 - z * z, 0.0) / np.maximum(z * z, 1e-300)
    up = 0.5 * (np.sqrt(1.0 + t2) - 1.0)
    return np.where(z > 0.0, up, -1.0 - up)


def _next_height(w: np.ndarray, h: np.ndarray, u: np.ndarray, alpha: float) -> np.ndarray:
    """The height of the next intersection along ``w`` from height ``h`` (heights uniform on
    [-1, 1], so C1(h) = (h + 1) / 2), or inf where the path leaves the surface."""
    c1 = np.clip(0.5 * (h + 1.0), 0.0, 1.0)
    lam = _lambda(w, alpha)
    up = w[:, 2] > 0.0
    leaves = up & (u > 1.0 - c1 ** lam)
    c1_next = c1 / (1.0 - u) ** (1.0 / lam)
    out = np.clip(2.0 * c1_next - 1.0, -1.0, 1.0)
    return np.where(leaves, np.inf, out)


def _visible_normal(wi: np.ndarray, alpha: float, u1: np.ndarray, u2: np.ndarray) -> np.ndarray:
    """A GGX normal distributed as the normals visible from ``wi`` (any hemisphere): in the
    stretched configuration m = normalize(wi + c), c uniform on the cap of the unit sphere where
    (wi + c).z > 0."""
    s = np.stack([alpha * wi[:, 0], alpha * wi[:, 1], wi[:, 2]], axis=1)
    s /= np.linalg.norm(s, axis=1, keepdims=True)
    phi = 2.0 * np.pi * u1
    z = (1.0 - u2) * (1.0 + s[:, 2]) - s[:, 2]
    r = np.sqrt(np.clip(1.0 - z * z, 0.0, 1.0))
    m = s + np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)
    m = np.stack([alpha * m[:, 0], alpha * m[:, 1], np.maximum(m[:, 2], 0.0)], axis=1)
    return m / np.linalg.norm(m, axis=1, keepdims=True)


def conductor_fresnel(cos_i: np.ndarray, eta: np.ndarray, k: np.ndarray) -> np.ndarray:
    """Unpolarised reflectance (n, 3) of a conductor of relative index eta + i k, from the complex
    Fresnel amplitudes."""
    n = np.asarray(eta, dtype=np.complex128) + 1j * np.asarray(k, dtype=np.float64)
    c = np.clip(np.abs(cos_i), 0.0, 1.0)[:, None]
    ct = np.sqrt(1.0 - (1.0 - c * c) / (n * n))
    rs = (c - n * ct) / (c + n * ct)
    rp = (n * c - ct) / (n * c + ct)
    return 0.5 * (np.abs(rs) ** 2 + np.abs(rp) ** 2)


def conductor_albedo(mu: float, alpha: float, eta, k, n: int = 400_000, seed: int = 1,
                     max_order: int = 200) -> dict[str, np.ndarray]:
    """Directional albedo (RGB) of a rough conductor seen at cos θ = ``mu`` (isotropic GGX
    ``alpha``), by the walk: ``total`` over every order, ``single`` the first order alone, and
    their standard errors."""
    with np.errstate(over="ignore", divide="ignore"):   # heights at the bounds give 0 ** -x and x ** inf
        return _walk(mu, alpha, eta, k, n, np.random.default_rng(seed), max_order)


def _walk(mu: float, alpha: float, eta, k, n: int, rng: np.random.Generator, max_order: int) -> dict[str, np.ndarray]:
    w = np.tile([-np.sqrt(1.0 - mu * mu), 0.0, -mu], (n, 1))      # travelling down onto the surface
    h = np.full(n, 2.0)                                             # above the highest microfacet
    weight = np.ones((n, 3))
    total = np.zeros((n, 3))
    single = np.zeros((n, 3))
    alive = np.arange(n)
    for order in range(max_order):
        h_next = _next_height(w[alive], h[alive], rng.random(len(alive)), alpha)
        out = np.isinf(h_next)
        total[alive[out]] = weight[alive[out]]
        if order == 1:
            single[alive[out]] = weight[alive[out]]
        alive, h_next = alive[~out], h_next[~out]
        if len(alive) == 0:
            break
        wi = -w[alive]
        m = _visible_normal(wi, alpha, rng.random(len(alive)), rng.random(len(alive)))
        cos_im = np.sum(wi * m, axis=1)
        weight[alive] *= conductor_fresnel(cos_im, eta, k)
        w[alive] = -wi + 2.0 * cos_im[:, None] * m
        h[alive] = h_next
    return {"total": total.mean(axis=0), "total_stderr": total.std(axis=0) / np.sqrt(n),
            "single": single.mean(axis=0), "single_stderr": single.std(axis=0) / np.sqrt(n)}
