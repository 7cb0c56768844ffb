"""pbrt-v4's samplers on the device: each sample is a pure function of (seed, sample index, pixel,
dimension), so passes stay independent, resume is bit-exact and passes could be split over machines.

The integrator asks for dimensions by number in this fixed order (pbrt's Get1D/Get2D/GetPixel2D
order, so each 2D use gets a well-stratified pair); see ``DIM_*`` below:

    0-1  film position in the pixel        2-3  lens
    then per bounce, from 4 + 9 * depth:
    +0 light choice, +1-2 light position, +3-4 BSDF direction, +5 BSDF lobe choice,
    +6 Russian roulette, +7 wavelength (thin film), +8 subsurface walk seed

Dimensions beyond what a sampler covers come from a hashed independent stream. ``independent``
itself draws in the integrator (the same stream as before samplers existed); the others:

- ``stratified``: the pass picks a stratum by a hashed permutation of the pixel's samples (one
  permutation per dimension), jittered inside it.
- ``halton``: one Halton sequence over the image; pixel (x, y) owns the indices whose base-2 and
  base-3 radical inverses fall in it, found with the Chinese remainder theorem; dimension d > 1 is
  the radical inverse in the d-th prime, randomised by digit permutations or Owen scrambling.
- ``sobol``: one Sobol sequence over a 2^m x 2^m grid; the index of the pixel's k-th sample solves
  a GF(2) system (``sobol_pixel_inverse``); dimension d uses Sobol dimension d, scrambled.
- ``paddedsobol``: per pixel and dimension a random permutation of the pixel's sample order into
  Sobol dimensions 0 (1D) or 0-1 (2D), each scrambled by its own hash.
- ``zsobol`` (Ahmed and Wonka 2020): the pixel's Morton code followed by the sample index is a
  Sobol index whose base-4 digits are permuted by a hash of the digits above them and the
  dimension, so neighbouring pixels get decorrelated but well-distributed points.

Samples past the pattern size (``SamplerSpec.pixel_samples``) start another block, randomised
with a fresh seed (and, for the deterministic pixel dimensions of halton/sobol, a random shift)."""
from __future__ import annotations

import warp as wp

from renderer.sampling.lowdiscrepancy import (ONE_MINUS_EPSILON, morton2, radical_inverse, scrambled_radical_inverse, sobol_bits,
                                              sobol_sample, sobol_sample_bytes)
from renderer.sampling.rng import hash_u32
from renderer.sampling.scramble import NONE, hash2, hash3, permutation_element, to_unit

DIM_FILM = wp.constant(0)
DIM_LENS = wp.constant(2)
DIM_BOUNCE = wp.constant(4)
DIMS_PER_BOUNCE = wp.constant(9)
#: Offsets inside a bounce's block of dimensions.
LIGHT_CHOICE, LIGHT, BSDF, LOBE, ROULETTE, WAVELENGTH, SUBSURFACE = (wp.constant(k) for k in (0, 1, 3, 5, 6, 7, 8))

#: Sampler codes in ``SamplerParams.kind``.
KINDS = {"independent": 0, "stratified": 1, "halton": 2, "sobol": 3, "paddedsobol": 4, "zsobol": 5}
STRATIFIED, HALTON, SOBOL, PADDED_SOBOL = (wp.constant(KINDS[k]) for k in ("stratified", "halton", "sobol",
                                                                             "paddedsobol"))


@wp.struct
class SamplerParams:
    kind: int
    randomize: int          # a code of renderer.sampling.scramble
    spp: int                # the pattern size
    log2_spp: int           # zsobol: ceil(log2 spp)
    base4_digits: int       # zsobol: base-4 digits of the Morton index with the sample bits
    res_log2: int           # sobol: the 2^m x 2^m grid the sequence is spread over
    xsamples: int           # stratified
    jitter: int
    n_dims: int             # dimensions the sampler covers; beyond them, hashed random numbers
    halton_scale: wp.vec2i  # 2^j and 3^k covering (at most) 128 pixels across and down
    halton_exp: wp.vec2i
    halton_inv: wp.vec2i    # multiplicative inverses for the Chinese remainder theorem
    matrices: wp.array(dtype=wp.uint32)       # sobol: generator matrices, 32 columns per dimension
    byte_tables: wp.array(dtype=wp.uint32)    # zsobol, paddedsobol: dimensions 0-1 as byte tables (4 x 256 each)
    pixel_inverse: wp.array(dtype=wp.uint32)  # sobol: columns of the pixel -> index GF(2) inverse
    perms: wp.array(dtype=int)                # zsobol: the 24 permutations of four digits
    primes: wp.array(dtype=int)               # halton: the base of each dimension


@wp.struct
class PixelSample:
    """Where one path's samples come from; made once per (pixel, sample index) by ``start_sample``."""

    seed: wp.uint32      # the render seed, re-hashed for every block of ``spp`` samples
    pixel: int
    px: int
    py: int
    index: int           # the sample's index inside its block
    block: int
    global_index: wp.int64   # halton / sobol: the index in the image-wide sequence
    morton: wp.uint32        # zsobol: Morton code of the pixel, then the sample index


@wp.func
def _inverse_radical_inverse(x: int, base: int, digits: int) -> wp.int64:
    r = wp.int64(0)
    for _ in range(digits):
        r = r * wp.int64(base) + wp.int64(x % base)
        x = x / base
    return r


@wp.func(inline=True)
def start_sample(p: SamplerParams, seed: int, pixel: int, px: int, py: int, sample_index: int) -> PixelSample:
    s = PixelSample()
    s.block = sample_index / p.spp
    s.index = sample_index - s.block * p.spp
    s.seed = wp.uint32(seed)
    if s.block > 0:
        s.seed = hash2(wp.uint32(seed), wp.uint32(s.block))
    s.pixel = pixel
    s.px = px
    s.py = py
    if p.kind == HALTON:
        stride = p.halton_scale[0] * p.halton_scale[1]
        h = wp.int64(0)
        if stride > 1:
            for i in range(2):
                c = px % 128
                if i == 1:
                    c = py % 128
                off = _inverse_radical_inverse(c, 2 + i, p.halton_exp[i])
                h = h + off * wp.int64(stride / p.halton_scale[i]) * wp.int64(p.halton_inv[i])
            h = h % wp.int64(stride)
        s.global_index = h + wp.int64(s.index) * wp.int64(stride)
    elif p.kind == SOBOL:
        m = p.res_log2
        hi = wp.uint32(s.index) << wp.uint32(2 * m)
        b = wp.uint32(0)
        if m > 0:
            tx = sobol_bits(p.matrices, 0, hi) >> wp.uint32(32 - m)
            ty = sobol_bits(p.matrices, 1, hi) >> wp.uint32(32 - m)
            target = (wp.uint32(px) ^ tx) | ((wp.uint32(py) ^ ty) << wp.uint32(m))
            for j in range(2 * m):
                if ((target >> wp.uint32(j)) & wp.uint32(1)) != wp.uint32(0):
                    b = b ^ p.pixel_inverse[j]
        s.global_index = wp.int64(hi | b)
    else:
        s.morton = (morton2(px, py) << wp.uint32(p.log2_spp)) | wp.uint32(s.index)
    return s


@wp.func
def hashed_bits(s: PixelSample, dim: int) -> wp.uint32:
    """32 independent random bits for (seed, block, pixel, sample, dimension)."""
    return hash3(hash2(s.seed, wp.uint32(dim) + wp.uint32(0x68E31DA4)), wp.uint32(s.pixel), wp.uint32(s.index))


@wp.func
def _hashed(s: PixelSample, dim: int) -> float:
    return to_unit(hashed_bits(s, dim))


@wp.func
def _zsobol_index(p: SamplerParams, s: PixelSample, dim: int) -> wp.uint32:
    """The Morton index with each base-4 digit permuted by a hash of the digits above it."""
    odd = p.log2_spp & 1
    salt = hash2(wp.uint32(dim) * wp.uint32(0x55555555), s.seed)
    idx = wp.uint32(0)
    k = p.base4_digits - 1
    while k >= odd:
        shift = wp.uint32(2 * k - odd)
        digit = int((s.morton >> shift) & wp.uint32(3))
        higher = s.morton >> (shift + wp.uint32(2))
        perm = int((hash_u32(higher ^ salt) >> wp.uint32(24)) % wp.uint32(24))
        idx = idx | (wp.uint32(p.perms[perm * 4 + digit]) << shift)
        k -= 1
    if odd == 1:
        idx = idx | ((s.morton & wp.uint32(1)) ^ (hash_u32((s.morton >> wp.uint32(1)) ^ salt) & wp.uint32(1)))
    return idx


@wp.func
def _stratum(p: SamplerParams, s: PixelSample, dim: int) -> int:
    return int(permutation_element(wp.uint32(s.index), wp.uint32(p.spp),
                                   hash3(wp.uint32(s.pixel), wp.uint32(dim), s.seed)))


@wp.func
def _jitter(p: SamplerParams, s: PixelSample, dim: int) -> float:
    if p.jitter != 0:
        return _hashed(s, dim)
    return 0.5


@wp.func(inline=True)
def get_1d(p: SamplerParams, s: PixelSample, dim: int) -> float:
    """Dimension ``dim`` of the path's sample."""
    if dim >= p.n_dims:
        return _hashed(s, dim)
    if p.kind == STRATIFIED:
        return wp.min((float(_stratum(p, s, dim)) + _jitter(p, s, dim)) / float(p.spp), ONE_MINUS_EPSILON)
    if p.kind == HALTON:
        if p.randomize == NONE:
            return radical_inverse(p.primes[dim], s.global_index)
        return scrambled_radical_inverse(p.primes[dim], dim, s.global_index, p.randomize, s.seed)
    seed = hash2(wp.uint32(dim), s.seed)
    if p.kind == SOBOL:
        return to_unit(sobol_sample(p.matrices, dim, wp.uint32(s.global_index), p.randomize, seed))
    if p.kind == PADDED_SOBOL:
        h = hash3(wp.uint32(s.pixel), wp.uint32(dim), s.seed)
        i = permutation_element(wp.uint32(s.index), wp.uint32(p.spp), h)
        return to_unit(sobol_sample_bytes(p.byte_tables, 0, i, p.randomize, hash2(h, seed)))
    return to_unit(sobol_sample_bytes(p.byte_tables, 0, _zsobol_index(p, s, dim), p.randomize, seed))


@wp.func(inline=True)
def get_2d(p: SamplerParams, s: PixelSample, dim: int) -> wp.vec2:
    """Dimensions ``dim`` and ``dim + 1``, drawn as one 2D point so their strata pair up."""
    if dim + 1 >= p.n_dims:
        return wp.vec2(_hashed(s, dim), _hashed(s, dim + 1))
    if p.kind == STRATIFIED:
        k = _stratum(p, s, dim)
        ys = p.spp / p.xsamples
        return wp.vec2(wp.min((float(k % p.xsamples) + _jitter(p, s, dim)) / float(p.xsamples), ONE_MINUS_EPSILON),
                       wp.min((float(k / p.xsamples) + _jitter(p, s, dim + 1)) / float(ys), ONE_MINUS_EPSILON))
    if p.kind == HALTON or p.kind == SOBOL:
        return wp.vec2(get_1d(p, s, dim), get_1d(p, s, dim + 1))
    sx = hash2(wp.uint32(dim), s.seed)
    sy = hash3(wp.uint32(dim), s.seed, wp.uint32(0x2545F491))
    i = wp.uint32(0)
    if p.kind == PADDED_SOBOL:
        h = hash3(wp.uint32(s.pixel), wp.uint32(dim), s.seed)
        i = permutation_element(wp.uint32(s.index), wp.uint32(p.spp), h)
        sx = hash2(h, sx)
        sy = hash2(h, sy)
    else:
        i = _zsobol_index(p, s, dim)
    return wp.vec2(to_unit(sobol_sample_bytes(p.byte_tables, 0, i, p.randomize, sx)),
                   to_unit(sobol_sample_bytes(p.byte_tables, 1, i, p.randomize, sy)))


@wp.func
def _shifted(u: wp.vec2, s: PixelSample) -> wp.vec2:
    """Blocks after the first move halton/sobol's unrandomised pixel points by a random torus shift."""
    if s.block == 0:
        return u
    v = u + wp.vec2(_hashed(s, -1), _hashed(s, -2))
    return wp.vec2(v[0] - wp.floor(v[0]), v[1] - wp.floor(v[1]))


@wp.func(inline=True)
def get_pixel_2d(p: SamplerParams, s: PixelSample) -> wp.vec2:
    """The film position inside the pixel (dimensions 0-1)."""
    if p.kind == HALTON:
        u = wp.vec2(radical_inverse(2, s.global_index >> wp.int64(p.halton_exp[0])),
                    radical_inverse(3, s.global_index / wp.int64(p.halton_scale[1])))
        return _shifted(u, s)
    if p.kind == SOBOL:
        scale = wp.float64(float(1 << p.res_log2)) / wp.float64(4294967296.0)
        g = wp.uint32(s.global_index)
        u = wp.vec2(float(wp.float64(sobol_bits(p.matrices, 0, g)) * scale - wp.float64(s.px)),
                    float(wp.float64(sobol_bits(p.matrices, 1, g)) * scale - wp.float64(s.py)))
        u = wp.vec2(wp.min(u[0], ONE_MINUS_EPSILON), wp.min(u[1], ONE_MINUS_EPSILON))
        return _shifted(u, s)
    return get_2d(p, s, DIM_FILM)
