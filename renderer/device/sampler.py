"""Upload a :class:`SamplerSpec` as the :class:`SamplerParams` the integrator reads: the Sobol
matrices, primes and permutations it needs (from ``lowdiscrepancy_tables``) and the per-image
constants (grid sizes, Halton scales and their multiplicative inverses)."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import warp as wp

from renderer.errors import RenderError
from renderer.sampling.lowdiscrepancy_tables import (four_way_permutations, primes, sobol_byte_tables, sobol_matrices,
                                                     sobol_pixel_inverse)
from renderer.sampling.sampler_spec import SamplerSpec
from renderer.sampling.samplers import KINDS, SamplerParams
from renderer.sampling.scramble import CODES

#: Dimensions with their own Sobol matrix (the ``sobol`` sampler) or prime (``halton``), as in pbrt-v4.
SOBOL_DIMENSIONS = 1024
HALTON_DIMENSIONS = 1000
#: pbrt-v4's limit on the pixels a Halton pattern spans before it repeats.
HALTON_MAX_RESOLUTION = 128
#: Dimensions ``zsobol``, ``paddedsobol`` and ``stratified`` cover: all of them (each has its own hash).
ALL_DIMENSIONS = 1 << 30


def _ceil_log2(n: int) -> int:
    return max(0, (n - 1).bit_length())


@dataclass
class DeviceSampler:
    params: SamplerParams
    keep: list = field(default_factory=list)    # the arrays the struct points into


def _halton(p: SamplerParams, width: int, height: int) -> None:
    scales, exps = [], []
    for base, res in ((2, width), (3, height)):
        scale, e = 1, 0
        while scale < min(res, HALTON_MAX_RESOLUTION):
            scale, e = scale * base, e + 1
        scales.append(scale)
        exps.append(e)
    p.halton_scale = wp.vec2i(*scales)
    p.halton_exp = wp.vec2i(*exps)
    inv = (pow(scales[1], -1, scales[0]) if scales[0] > 1 else 0, pow(scales[0], -1, scales[1]) if scales[1] > 1 else 0)
    p.halton_inv = wp.vec2i(*inv)


def upload_sampler(spec: SamplerSpec, width: int, height: int, device: str) -> DeviceSampler:
    """The device form of ``spec`` for a ``width`` x ``height`` film; refuses a pattern whose
    indices would not fit the 32-bit Sobol generator matrices."""
    p = SamplerParams()
    p.kind = KINDS[spec.name]
    p.randomize = CODES[spec.randomization]
    p.spp = spec.pixel_samples
    p.log2_spp = _ceil_log2(spec.pixel_samples)
    res_log2 = _ceil_log2(max(width, height))
    p.res_log2 = res_log2
    p.base4_digits = res_log2 + (p.log2_spp + 1) // 2
    p.xsamples = spec.xsamples if spec.name == "stratified" else 1
    p.jitter = int(spec.jitter)
    p.n_dims = {"sobol": SOBOL_DIMENSIONS, "halton": HALTON_DIMENSIONS}.get(spec.name, ALL_DIMENSIONS)
    if spec.name in ("sobol", "zsobol") and 2 * res_log2 + p.log2_spp > 32:
        raise RenderError(f"the {spec.name} sampler indexes {width}x{height} pixels x {spec.pixel_samples} samples "
                          "with more than 32 bits; use fewer pixel samples or the paddedsobol sampler")
    _halton(p, width, height)
    n_matrix_dims = SOBOL_DIMENSIONS if spec.name == "sobol" else 2
    keep = [wp.array(sobol_matrices(n_matrix_dims).ravel(), dtype=wp.uint32, device=device),
            wp.array(sobol_byte_tables(sobol_matrices(2)).ravel(), dtype=wp.uint32, device=device),
            wp.array(sobol_pixel_inverse(res_log2 if spec.name == "sobol" else 0), dtype=wp.uint32, device=device),
            wp.array(four_way_permutations().ravel(), dtype=int, device=device),
            wp.array(primes(HALTON_DIMENSIONS if spec.name == "halton" else 2), dtype=int, device=device)]
    p.matrices, p.byte_tables, p.pixel_inverse, p.perms, p.primes = keep
    return DeviceSampler(p, keep)


def sample_points(spec: SamplerSpec, width: int, height: int, seed: int, samples: int, dims: int,
                  device: str = "cpu") -> np.ndarray:
    """(samples, height, width, dims) of the sampler's numbers, dimension pairs drawn as 2D points
    (film first): what the integrator sees, for tests and plots."""
    from renderer.sampling.sample_kernel import points_kernel

    if spec.name == "independent":
        raise ValueError("the independent sampler draws in the integrator, in order, not by dimension")
    ds = upload_sampler(spec, width, height, device)
    out = wp.zeros((samples, height * width, dims), dtype=float, device=device)
    for k in range(samples):
        wp.launch(points_kernel(), dim=width * height, inputs=[ds.params, seed, k, width, dims, out[k]], device=device)
    return out.numpy().reshape(samples, height, width, dims)
