"""A kernel that writes a sampler's numbers for every pixel, as the integrator would draw them
(dimensions 0-1 through ``get_pixel_2d``, then pairs through ``get_2d``, an odd last one through
``get_1d``): what tests and plots inspect."""
from __future__ import annotations

from functools import lru_cache

import warp as wp

from renderer.device.kernel_options import KERNEL_OPTIONS
from renderer.sampling.samplers import SamplerParams, get_1d, get_2d, get_pixel_2d, start_sample


@lru_cache(maxsize=None)
def points_kernel() -> wp.Kernel:
    @wp.kernel(module="unique", module_options=KERNEL_OPTIONS)
    def points(p: SamplerParams, seed: int, sample_index: int, width: int, dims: int,
               out: wp.array2d(dtype=float)):
        pixel = wp.tid()
        s = start_sample(p, seed, pixel, pixel % width, pixel / width, sample_index)
        u = get_pixel_2d(p, s)
        out[pixel, 0] = u[0]
        if dims > 1:
            out[pixel, 1] = u[1]
        d = int(2)
        while d < dims:
            if d + 1 < dims:
                v = get_2d(p, s, d)
                out[pixel, d] = v[0]
                out[pixel, d + 1] = v[1]
            else:
                out[pixel, d] = get_1d(p, s, d)
            d += 2
    return points
