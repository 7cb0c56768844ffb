"""Low-discrepancy point sets on the device: Sobol points from generator matrices (uploaded from
``lowdiscrepancy_tables``), radical inverses in prime bases (Halton), with the randomisations pbrt-v4
offers for each, and Morton codes (ZSobol orders pixels along a Z curve)."""
from __future__ import annotations

import warp as wp

from renderer.sampling.scramble import OWEN, PERMUTE_DIGITS, hash2, hash3, permutation_element, scramble

#: The largest float32 below 1: samples are in [0, 1), and sums that round up are clamped to this.
ONE_MINUS_EPSILON = wp.constant(0.99999994)
#: Below this a further base-b digit no longer changes a float32 in [0, 1).
_FLOAT32_ULP = wp.constant(5.9604645e-08)


@wp.func
def sobol_bits(matrices: wp.array(dtype=wp.uint32), dim: int, a: wp.uint32) -> wp.uint32:
    """Sobol point ``a`` of dimension ``dim`` as a 32-bit fraction: the XOR of the generator
    columns of a's set bits."""
    v = wp.uint32(0)
    j = dim * 32
    while a != wp.uint32(0):
        if (a & wp.uint32(1)) != wp.uint32(0):
            v = v ^ matrices[j]
        a = a >> wp.uint32(1)
        j += 1
    return v


@wp.func
def sobol_bits_bytes(tables: wp.array(dtype=wp.uint32), dim: int, a: wp.uint32) -> wp.uint32:
    """The same bits as ``sobol_bits``, looked up a byte of ``a`` at a time in
    ``sobol_byte_tables``: four loads instead of a branch per bit. Used for the two dimensions
    zsobol and paddedsobol draw (1.5x faster zsobol passes); the sobol sampler's 1024 dimensions
    would make 4 MB of tables, measured slower than the loop."""
    j = dim * 1024
    return (tables[j + int(a & wp.uint32(255))] ^ tables[j + 256 + int((a >> wp.uint32(8)) & wp.uint32(255))]
            ^ tables[j + 512 + int((a >> wp.uint32(16)) & wp.uint32(255))] ^ tables[j + 768 + int(a >> wp.uint32(24))])


@wp.func
def sobol_sample(matrices: wp.array(dtype=wp.uint32), dim: int, a: wp.uint32, mode: int,
                 seed: wp.uint32) -> wp.uint32:
    return scramble(sobol_bits(matrices, dim, a), mode, seed)


@wp.func
def sobol_sample_bytes(tables: wp.array(dtype=wp.uint32), dim: int, a: wp.uint32, mode: int,
                       seed: wp.uint32) -> wp.uint32:
    return scramble(sobol_bits_bytes(tables, dim, a), mode, seed)


@wp.func
def radical_inverse(base: int, a: wp.int64) -> float:
    """The base-b digits of ``a`` mirrored about the radix point (the Halton coordinate)."""
    b = wp.int64(base)
    inv = wp.float64(1.0) / wp.float64(base)
    scale = wp.float64(1.0)
    r = wp.float64(0.0)
    while a > wp.int64(0):
        nxt = a / b
        scale = scale * inv
        r = r + wp.float64(a - nxt * b) * scale
        a = nxt
    return wp.min(float(r), ONE_MINUS_EPSILON)


@wp.func
def scrambled_radical_inverse(base: int, base_index: int, a: wp.int64, mode: int, seed: wp.uint32) -> float:
    """A radical inverse whose digits are permuted: one random permutation per digit position
    (``permutedigits``) or one per digit prefix (``owen``), both from hashes of the seed. Digits
    continue past a's leading zeros until float32 precision, since permuted zeros are not zero."""
    b = wp.int64(base)
    inv = wp.float64(1.0) / wp.float64(base)
    scale = wp.float64(1.0)
    r = wp.float64(0.0)
    prefix = wp.uint32(0)      # the scrambled digits so far, as a hash chain (Owen's nesting)
    k = int(0)
    while scale > wp.float64(_FLOAT32_ULP):
        nxt = a / b
        digit = wp.uint32(a - nxt * b)
        h = hash3(seed, wp.uint32(base_index), wp.uint32(k))
        if mode == OWEN:
            h = hash2(prefix, h)
        if mode == PERMUTE_DIGITS or mode == OWEN:
            digit = permutation_element(digit, wp.uint32(base), h)
        prefix = hash2(prefix, digit + wp.uint32(1))
        scale = scale * inv
        r = r + wp.float64(digit) * scale
        a = nxt
        k += 1
    return wp.min(float(r), ONE_MINUS_EPSILON)


@wp.func
def spread_bits(x: wp.uint32) -> wp.uint32:
    """Bits of a 16-bit integer moved to the even positions (half of a 2D Morton code)."""
    x = x & wp.uint32(0x0000FFFF)
    x = (x | (x << wp.uint32(8))) & wp.uint32(0x00FF00FF)
    x = (x | (x << wp.uint32(4))) & wp.uint32(0x0F0F0F0F)
    x = (x | (x << wp.uint32(2))) & wp.uint32(0x33333333)
    x = (x | (x << wp.uint32(1))) & wp.uint32(0x55555555)
    return x


@wp.func
def morton2(x: int, y: int) -> wp.uint32:
    return spread_bits(wp.uint32(x)) | (spread_bits(wp.uint32(y)) << wp.uint32(1))
