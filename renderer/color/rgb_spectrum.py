"""pbrt-v4's RGB to spectrum upsampling, for the few constant colours that need a spectrum: Jakob and
Hanika's (2019) smooth spectra s(λ) = 1/2 + x / (2 sqrt(1 + x²)), x a quadratic in λ, whose colour
(CIE 1931 under D65, linear sRGB: the convention of :mod:`renderer.color.spectral`) is the given RGB.

pbrt-v4 interpolates a precomputed 64³ table of these fits; here the one fit needed is solved
directly (Gauss-Newton on the three coefficients, in λ normalised to [0, 1] over [360, 830] nm).
``unbounded`` is pbrt-v4's RGBUnboundedSpectrum (scattering coefficients: 2 max(rgb) times the
spectrum of rgb / (2 max(rgb))), ``albedo`` its RGBAlbedoSpectrum (reflectances in [0, 1]).
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np

from renderer.color.spectral import LAMBDA_MAX_NM, LAMBDA_MIN_NM, spectrum_to_rgb_weights

_GRID = np.arange(LAMBDA_MIN_NM, LAMBDA_MAX_NM + 1.0, 1.0)
#: A fit whose colour misses its target by more than this is not used.
TOLERANCE = 1e-5


def sigmoid(c: np.ndarray, lam: np.ndarray) -> np.ndarray:
    """The spectrum of coefficients c = (c0, c1, c2) at λ (nm)."""
    t = (np.asarray(lam, np.float64) - LAMBDA_MIN_NM) / (LAMBDA_MAX_NM - LAMBDA_MIN_NM)
    x = c[0] * t * t + c[1] * t + c[2]
    return 0.5 + x / (2.0 * np.sqrt(1.0 + x * x))


@lru_cache(maxsize=256)
def fit(target: tuple[float, float, float]) -> tuple[np.ndarray, float]:
    """Coefficients whose spectrum has colour ``target`` (each in (0, 1)), and the colour's miss."""
    w = spectrum_to_rgb_weights(_GRID)
    goal = np.asarray(target, np.float64)

    def miss(c: np.ndarray) -> np.ndarray:
        return sigmoid(c, _GRID) @ w - goal

    c = np.zeros(3)
    r = miss(c)
    for _ in range(200):
        if np.abs(r).max() < 1e-9:
            break
        J = np.stack([(miss(c + d) - miss(c - d)) / 2e-6 for d in np.eye(3) * 1e-6], 1)
        step = np.linalg.lstsq(J, -r, rcond=None)[0]
        k = 1.0
        while k > 1e-4 and np.abs(miss(c + k * step)).max() >= np.abs(r).max():
            k *= 0.5
        if k <= 1e-4:
            break
        c = c + k * step
        r = miss(c)
    return c, float(np.abs(r).max())


def unbounded(rgb) -> tuple[np.ndarray, float, float]:
    """(coefficients, scale, miss) of pbrt-v4's RGBUnboundedSpectrum: value = scale * sigmoid."""
    rgb = np.asarray(rgb, np.float64)
    m = float(rgb.max())
    if m <= 0.0:
        return np.zeros(3), 0.0, 0.0
    c, miss = fit(tuple(float(x) for x in rgb / (2.0 * m)))
    return c, 2.0 * m, miss * 2.0 * m


def albedo(rgb) -> tuple[np.ndarray, float, float]:
    """(coefficients, 1, miss) of pbrt-v4's RGBAlbedoSpectrum for a reflectance in [0, 1]."""
    rgb = np.clip(np.asarray(rgb, np.float64), 1e-4, 1.0 - 1e-4)
    c, miss = fit(tuple(float(x) for x in rgb))
    return c, 1.0, miss
