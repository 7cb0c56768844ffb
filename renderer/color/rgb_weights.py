"""Spectrum → linear sRGB on the device: the colour-matching table the spectral BSDFs integrate with."""
from __future__ import annotations

import warp as wp

from renderer.color import spectral


@wp.struct
class RgbWeightTable:
    """w(λ) in 1/nm on a regular grid (see :func:`renderer.spectral.rgb_weight_table`)."""
    w: wp.array(dtype=wp.vec3)
    lambda_min: float
    step: float


def make_rgb_weight_table(device: str | None = None) -> RgbWeightTable:
    """Upload the colour-matching table. The caller keeps the returned struct alive while kernels use it."""
    w, lambda_min, step = spectral.rgb_weight_table()
    table = RgbWeightTable()
    table.w = wp.array(w, dtype=wp.vec3, device=device)
    table.lambda_min = lambda_min
    table.step = step
    return table


@wp.func
def rgb_weight(table: RgbWeightTable, lambda_nm: float) -> wp.vec3:
    x = (lambda_nm - table.lambda_min) / table.step
    last = table.w.shape[0] - 1
    i = wp.clamp(int(wp.floor(x)), 0, last - 1)
    t = wp.clamp(x - float(i), 0.0, 1.0)
    return (1.0 - t) * table.w[i] + t * table.w[i + 1]
