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


@wp.func
def sampled_white(table: RgbWeightTable, n_samples: int, u_jitter: float) -> wp.vec3:
    """What the stratified jittered estimator of the spectral BSDFs (thin_film_rgb_sampled)
    returns for a spectrum ≡ 1 at this jitter: white (1, 1, 1) only in expectation. Dividing a
    spectral estimate by it makes a flat spectrum come out exact, sample by sample."""
    step = table.step * float(table.w.shape[0] - 1) / float(n_samples)
    s = wp.vec3(0.0)
    for i in range(n_samples):
        s += rgb_weight(table, table.lambda_min + (float(i) + u_jitter) * step) * step
    return s
