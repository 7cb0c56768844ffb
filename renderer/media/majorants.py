"""Majorant grids: per cell of a coarse grid over a medium's bounds, an upper bound of sigma_t =
sigma_a + sigma_s, per RGB channel. Delta and ratio tracking sample free flights against it, so a
tight bound wastes few null collisions and a loose one stays unbiased. The bound of a cell is
the largest grid sample whose trilinear support reaches into it (pbrt-v4's SampledGrid::MaxValue),
so it bounds the interpolated field everywhere in the cell."""
from __future__ import annotations

import numpy as np

from renderer.media.description import MediumDesc

#: cells per axis of a grid medium's majorant grid (pbrt-v4 uses 16^3 too)
RESOLUTION = 16


def _axis_max(a: np.ndarray, axis: int, cells: int) -> np.ndarray:
    """Along ``axis`` (n samples over [0, 1]), the max over each of ``cells`` equal cells of the
    samples that trilinear interpolation inside the cell reads."""
    n = a.shape[axis]
    out = []
    for c in range(cells):
        lo = max(int(np.floor(c / cells * n - 0.5)), 0)
        hi = min(int(np.floor((c + 1) / cells * n - 0.5)) + 1, n - 1)
        out.append(np.take(a, range(lo, hi + 1), axis=axis).max(axis=axis))
    return np.stack(out, axis=axis)


def grid_max(grid: np.ndarray, cells: int = RESOLUTION) -> np.ndarray:
    """(cells, cells, cells[, 3]) maxima of a (nz, ny, nx[, 3]) grid, indexed [z, y, x] as the grid."""
    m = grid
    for axis in range(3):
        m = _axis_max(m, axis, cells)
    return m


def majorants(m: MediumDesc) -> tuple[tuple[int, int, int], np.ndarray]:
    """The majorant grid's resolution (x, y, z) and its (nz*ny*nx, 3) float32 sigma_t bounds, x fastest."""
    sigma_t = np.asarray(m.sigma_a + m.sigma_s, np.float64)
    if m.kind == "uniformgrid":
        cells = grid_max(m.density)[..., None] * sigma_t
    elif m.kind == "rgbgrid":
        parts = [grid_max(g) if g is not None else np.full((RESOLUTION,) * 3 + (3,), s, np.float32)
                 for g, s in ((m.rgb_sigma_a, m.sigma_a), (m.rgb_sigma_s, m.sigma_s))]
        cells = parts[0] + parts[1]
    else:       # homogeneous; a cloud's density is at most 1
        cells = sigma_t.reshape(1, 1, 1, 3)
    res = (cells.shape[2], cells.shape[1], cells.shape[0])
    return res, np.ascontiguousarray(cells.reshape(-1, 3), dtype=np.float32)
