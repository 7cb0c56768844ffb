"""Spectrum → linear sRGB weights for the thin-film BSDF, from colour-science tables.

The renderer carries RGB; wavelengths exist only inside the thin-film BSDF, which must turn a
reflectance spectrum R(λ) into the RGB reflectance a D65-lit surface would show. The mapping is

    XYZ = ∫ R(λ) D65(λ) (x̄, ȳ, z̄)(λ) dλ / ∫ D65(λ) ȳ(λ) dλ,      rgb = M_sRGB · XYZ,

which is linear in R, so it collapses to per-wavelength weight vectors w(λ) = M (x̄, ȳ, z̄) D65 / ∫D65ȳ
with rgb = ∫ R(λ) w(λ) dλ. D65 is sRGB's white, so a perfect mirror (R ≡ 1) must come out as
(1, 1, 1). The CIE 1931 2° observer and CIE D65 integrate to xy within 1e-4 of sRGB's nominal white,
so every discretisation below is renormalised per channel to make white exactly white; that
diagonal correction is far below what a viewer can see.

Tables come from colour-science (never typed by hand) and are cached; all wavelengths in nm.
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np

LAMBDA_MIN_NM = 360.0
LAMBDA_MAX_NM = 830.0
TABLE_STEP_NM = 1.0

# The seed's wavelengths, used directly as the R, G and B channels in the "rgb3" mode.
RGB3_WAVELENGTHS_NM = (650.0, 510.0, 475.0)


@lru_cache(maxsize=1)
def _cie_tables() -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(λ grid at 1 nm over [360, 830], x̄ȳz̄ (n, 3), D65 (n,), XYZ→linear-sRGB matrix), float64."""
    import colour

    shape = colour.SpectralShape(LAMBDA_MIN_NM, LAMBDA_MAX_NM, TABLE_STEP_NM)
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(shape)
    d65 = colour.SDS_ILLUMINANTS["D65"].copy().align(shape)
    lam = np.asarray(shape.wavelengths, dtype=np.float64)
    matrix = np.asarray(colour.RGB_COLOURSPACES["sRGB"].matrix_XYZ_to_RGB, dtype=np.float64)
    return lam, np.asarray(cmfs.values, np.float64), np.asarray(d65.values, np.float64), matrix


def _unnormalised_rgb_density(wavelengths_nm: np.ndarray) -> np.ndarray:
    """M (x̄, ȳ, z̄)(λ) D65(λ) at arbitrary λ (linear interpolation of the 1 nm tables; 0 outside)."""
    lam, cmfs, d65, matrix = _cie_tables()
    wl = np.asarray(wavelengths_nm, dtype=np.float64)
    xyz = np.stack([np.interp(wl, lam, cmfs[:, c] * d65, left=0.0, right=0.0) for c in range(3)], axis=-1)
    return xyz @ matrix.T


def spectrum_to_rgb_weights(wavelengths_nm: np.ndarray, quadrature_weights_nm: np.ndarray | None = None) -> np.ndarray:
    """Per-wavelength linear-sRGB weights w_i (shape (n, 3)) with rgb = Σ_i R(λ_i) w_i.

    ``quadrature_weights_nm`` are the dλ each sample stands for (default: equal weights, as for
    stratum midpoints). The weights include the quadrature and are renormalised so that
    Σ_i w_i = (1, 1, 1) exactly: R ≡ 1 gives white for this set of wavelengths, whatever n is.
    """
    wl = np.atleast_1d(np.asarray(wavelengths_nm, dtype=np.float64))
    q = np.ones_like(wl) if quadrature_weights_nm is None else np.broadcast_to(
        np.asarray(quadrature_weights_nm, dtype=np.float64), wl.shape)
    w = _unnormalised_rgb_density(wl) * q[:, None]
    total = w.sum(axis=0)
    if np.any(total <= 0.0):
        raise ValueError("these wavelengths cannot represent white: some sRGB channel gets no weight")
    return w / total


def rgb_weight_table() -> tuple[np.ndarray, float, float]:
    """(w (n, 3) float32 in 1/nm, λ of the first entry, step) on the 1 nm grid over [360, 830].

    This is a density: rgb = ∫ R(λ) w(λ) dλ. It is normalised so that the integral of its
    piecewise-linear interpolant (the trapezoid sum) is exactly (1, 1, 1). A kernel that jitters
    one wavelength λ_i = 360 + (i + u) Δ in each of N strata of width Δ = 470/N, looks w up by
    linear interpolation and sums R(λ_i) w(λ_i) Δ is therefore an unbiased estimator of rgb: for
    R ≡ 1 its expectation over u ~ U[0, 1) is exactly white (one sample is white within the
    stratification error, about 1e-3 at N = 32).
    """
    lam, _, _, _ = _cie_tables()
    w = _unnormalised_rgb_density(lam)
    trapezoid = TABLE_STEP_NM * (w.sum(axis=0) - 0.5 * (w[0] + w[-1]))
    return (w / trapezoid).astype(np.float32), float(lam[0]), TABLE_STEP_NM


def _cumulative_rgb_weight(wavelengths_nm: np.ndarray) -> np.ndarray:
    """∫ from 360 nm to λ of the table's piecewise-linear w, exactly (quadratic inside a cell)."""
    w, lambda_min, step = rgb_weight_table()
    w = w.astype(np.float64)
    cells = step * 0.5 * (w[1:] + w[:-1])
    nodes = np.concatenate([np.zeros((1, 3)), np.cumsum(cells, axis=0)])
    x = np.clip((np.asarray(wavelengths_nm, np.float64) - lambda_min) / step, 0.0, len(w) - 1.0)
    k = np.minimum(np.floor(x).astype(int), len(w) - 2)
    t = (x - k)[:, None]
    return nodes[k] + step * (w[k] * t + 0.5 * (w[k + 1] - w[k]) * t * t)


#: More wavelengths than the 1 nm table has cannot add accuracy, only time.
MAX_SPECTRAL_SAMPLES = 1024


#: Wavelengths per evaluation of ``table`` for the materials a table cannot describe.
TABLE_FALLBACK_SAMPLES = 32


def parse_mode(mode: str) -> tuple[str, int]:
    """The one parser of thin-film colour modes: ``rgb3`` → ("rgb3", 0), ``spectral:N`` →
    ("spectral", N) with 1 <= N <= MAX_SPECTRAL_SAMPLES, ``reference`` → ("reference", 0),
    ``table`` / ``table:N`` → ("table", N): per-material tables over the angle baked from the
    1 nm reference (:mod:`renderer.optics.angular_table`), spectral:N (default 32) where a
    material's coating is textured and no table describes it."""
    if mode in ("rgb3", "reference"):
        return mode, 0
    if mode == "table":
        return mode, TABLE_FALLBACK_SAMPLES
    name, _, count = mode.partition(":")
    if name in ("spectral", "table") and count.isdigit() and 1 <= int(count) <= MAX_SPECTRAL_SAMPLES:
        return name, int(count)
    raise ValueError(f"unknown thin-film mode {mode!r}: use 'rgb3', 'spectral:N' (1 <= N <= "
                     f"{MAX_SPECTRAL_SAMPLES}), 'table', 'table:N' or 'reference'")


def mode_wavelengths(mode: str) -> tuple[np.ndarray, np.ndarray, float]:
    """(wavelengths (n,), RGB weights (n, 3), band width in nm each sample stands for) of a mode.

    Modes: ``"rgb3"`` (the seed: R(650), R(510), R(475) used directly as R, G, B; monochromatic,
    band 0), ``"spectral:N"`` (N equal strata of [360, 830]: the sample sits at the midpoint, its
    weight is the colour-matching integral over the whole stratum, band = stratum width),
    ``"reference"`` (every nm of [360, 830] with trapezoid weights, band 1 nm).
    The band is how wide a slice of spectrum one sample represents; the thin-film code returns the
    band average of R there, so Σ R̄_i ∫_stratum w is exact whenever R or w is flat across a
    stratum, and thick films converge instead of aliasing. Stratum integrals (not w at the
    midpoint) also keep few strata usable: 4 midpoint values of the sRGB blue weight sum to < 0.
    """
    span = LAMBDA_MAX_NM - LAMBDA_MIN_NM
    if mode == "rgb3":
        return np.asarray(RGB3_WAVELENGTHS_NM), np.eye(3), 0.0
    if mode == "reference":
        lam, _, _, _ = _cie_tables()
        q = np.full_like(lam, TABLE_STEP_NM)
        q[[0, -1]] *= 0.5
        return lam, spectrum_to_rgb_weights(lam, q), TABLE_STEP_NM
    kind, n = parse_mode(mode)
    if kind == "table":
        raise ValueError("the thin-film mode 'table' is a render mode: its tables are the 'reference' quadrature")
    step = span / n
    edges = LAMBDA_MIN_NM + np.arange(n + 1) * step
    cumulative = _cumulative_rgb_weight(edges)
    weights = np.diff(cumulative, axis=0)
    return 0.5 * (edges[:-1] + edges[1:]), weights / weights.sum(axis=0), step
