"""Band-limited noise that terrain and maps share, so a mesh vertex and a map texel at the same
place read the same value whatever their sampling."""
from __future__ import annotations

import math
from typing import Callable

import numpy as np
from scipy import ndimage

#: Mean variance of a random lattice smoothed by a cubic B-spline, per axis (integral of B^2).
_BSPLINE_VARIANCE = 151.0 / 315.0


def smooth_noise(rng: np.random.Generator, lo: tuple[float, float], hi: tuple[float, float],
                 feature_size: float) -> Callable[[np.ndarray, np.ndarray], np.ndarray]:
    """Zero-mean, roughly unit-variance noise with features about ``feature_size`` across over the
    box [lo, hi]. It is a cubic B-spline through a random lattice, so it can be evaluated at any
    point: a mesh vertex and a map texel at the same place read the same value whatever the
    sampling resolution (ripples as geometry and as a map then agree)."""
    shape = tuple(int(math.ceil((h - l) / feature_size)) + 4 for l, h in zip(lo, hi))
    lattice = rng.standard_normal(shape) / _BSPLINE_VARIANCE

    def field_at(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        a, b = np.broadcast_arrays(np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64))
        coords = np.stack([(a - lo[0]) / feature_size + 1.5, (b - lo[1]) / feature_size + 1.5])
        out = ndimage.map_coordinates(lattice, coords.reshape(2, -1), order=3, prefilter=False,
                                      mode="nearest")
        return out.reshape(a.shape)

    return field_at
