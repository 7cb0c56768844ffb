"""Piecewise-constant 1D and 2D distributions: built in numpy, sampled in kernels by binary search."""
from __future__ import annotations

import numpy as np
import warp as wp


def cdf_1d(f: np.ndarray) -> tuple[np.ndarray, float]:
    """Normalised CDF (n + 1 entries) of a non-negative piecewise-constant function on [0, 1] and
    its integral. An all-zero function becomes uniform so sampling never divides by zero."""
    f = np.asarray(f, dtype=np.float64)
    n = len(f)
    integral = float(f.sum() / n)
    cdf = np.concatenate([[0.0], np.cumsum(f) / n])
    cdf = cdf / integral if integral > 0 else np.linspace(0.0, 1.0, n + 1)
    cdf[-1] = 1.0
    return cdf.astype(np.float32), integral


def distribution_2d(f: np.ndarray, row_weight: np.ndarray | None = None,
                    out: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, float]:
    """(conditional CDFs (h, w + 1), marginal CDF (h + 1), integral) for f (times ``row_weight``
    per row, in float64) over [0, 1]², rows along v and columns along u. Rows are weighted one at
    a time, so a 16k map never needs a float64 copy of itself; ``f`` may be anything with a
    ``shape`` whose ``f[y]`` is row y (an 8-bit map decoded a row at a time), and ``out`` a
    float32 (h, w + 1) array to write the conditional CDFs into (a view of a light's pool data)."""
    h, w = f.shape
    cond = np.empty((h, w + 1), dtype=np.float32) if out is None else out
    row_int = np.empty(h)
    for y in range(h):
        row = f[y].astype(np.float64)
        cond[y], row_int[y] = cdf_1d(row if row_weight is None else row * row_weight[y])
    marg, integral = cdf_1d(row_int)
    return cond, marg, integral


@wp.func
def find_interval(cdf: wp.array(dtype=float), start: int, n: int, u: float) -> int:
    """The largest i in [0, n) with cdf[start + i] <= u (cdf has n + 1 entries from ``start``)."""
    lo = int(0)
    hi = n
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if cdf[start + mid] <= u:
            lo = mid
        else:
            hi = mid
    return lo


@wp.func
def sample_cdf(cdf: wp.array(dtype=float), start: int, n: int, u: float) -> wp.vec2:
    """Continuous sample in [0, 1) of a piecewise-constant CDF: (x, cell index)."""
    i = find_interval(cdf, start, n, u)
    c0 = cdf[start + i]
    width = cdf[start + i + 1] - c0
    du = float(0.5)
    if width > 0.0:
        du = (u - c0) / width
    x = (float(i) + wp.clamp(du, 0.0, 0.99999)) / float(n)
    return wp.vec2(x, float(i))
