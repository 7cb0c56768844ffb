"""Randomisations of low-discrepancy points, on 32-bit fixed-point values: a random XOR of all
digits (``permutedigits`` in base 2), Owen's nested scrambling with a hash per prefix
(``owen``), the Laine–Karras style hash that approximates it in a few multiplies (``fastowen``),
and Kensler's hashed permutation of 0..n-1 (for strata, sample orders and base-b digits)."""
from __future__ import annotations

import warp as wp

from renderer.sampling.rng import hash_u32

#: Randomisation codes shared by the samplers (``SamplerSpec.randomization`` names them).
NONE = wp.constant(0)
PERMUTE_DIGITS = wp.constant(1)
FAST_OWEN = wp.constant(2)
OWEN = wp.constant(3)
CODES = {"none": 0, "permutedigits": 1, "fastowen": 2, "owen": 3}

_ONE = wp.constant(wp.uint32(1))


@wp.func
def hash2(a: wp.uint32, b: wp.uint32) -> wp.uint32:
    """A hash of two words; order matters, so (dimension, seed) and (seed, dimension) differ."""
    return hash_u32(a ^ hash_u32(b + wp.uint32(0x9E3779B9)))


@wp.func
def hash3(a: wp.uint32, b: wp.uint32, c: wp.uint32) -> wp.uint32:
    return hash_u32(a ^ hash2(b, c))


@wp.func
def _word(x: float, scale: float) -> wp.uint32:
    """The low 32 bits of a coordinate at resolution 1/scale (nearby values differ in them)."""
    return wp.uint32(wp.int64(wp.floor(x * scale)) & wp.int64(0xFFFFFFFF))


@wp.func
def hash_point_direction(p: wp.vec3, d: wp.vec3) -> wp.uint32:
    """A hash of a point (at 2^-20 resolution) and a unit direction (2^-24): pbrt-v4's HashFloat
    of a ray, for choices that must be a function of the ray alone (alpha, the mix material)."""
    a = hash3(_word(p[0], 1048576.0), _word(p[1], 1048576.0), _word(p[2], 1048576.0))
    return hash2(a, hash3(_word(d[0], 16777216.0), _word(d[1], 16777216.0), _word(d[2], 16777216.0)))


@wp.func
def to_unit(v: wp.uint32) -> float:
    """A 32-bit fixed-point fraction as a float32 strictly below 1 (its top 24 bits)."""
    return float(v >> wp.uint32(8)) * (1.0 / 16777216.0)


@wp.func
def reverse_bits(v: wp.uint32) -> wp.uint32:
    v = ((v >> wp.uint32(1)) & wp.uint32(0x55555555)) | ((v & wp.uint32(0x55555555)) << wp.uint32(1))
    v = ((v >> wp.uint32(2)) & wp.uint32(0x33333333)) | ((v & wp.uint32(0x33333333)) << wp.uint32(2))
    v = ((v >> wp.uint32(4)) & wp.uint32(0x0F0F0F0F)) | ((v & wp.uint32(0x0F0F0F0F)) << wp.uint32(4))
    v = ((v >> wp.uint32(8)) & wp.uint32(0x00FF00FF)) | ((v & wp.uint32(0x00FF00FF)) << wp.uint32(8))
    return (v >> wp.uint32(16)) | (v << wp.uint32(16))


@wp.func
def owen_scramble(v: wp.uint32, seed: wp.uint32) -> wp.uint32:
    """Flip each bit by a hash of the bits above it (and the seed): a nested uniform scramble."""
    if (seed & _ONE) != wp.uint32(0):
        v = v ^ (_ONE << wp.uint32(31))
    for b in range(1, 32):
        mask = wp.uint32(0xFFFFFFFF) << wp.uint32(32 - b)
        if (hash_u32((v & mask) ^ seed) & (_ONE << wp.uint32(b))) != wp.uint32(0):
            v = v ^ (_ONE << wp.uint32(31 - b))
    return v


@wp.func
def fast_owen_scramble(v: wp.uint32, seed: wp.uint32) -> wp.uint32:
    """Laine and Karras's observation: on bit-reversed values, x ^= x * even only changes a bit
    from the bits below it, i.e. (reversed) above it, which is Owen's nesting; mixing the seed in
    between gives a cheap, good approximation of a random Owen scramble."""
    v = reverse_bits(v)
    v = v ^ (v * wp.uint32(0x3D20ADEA))
    v = v + seed
    v = v * ((seed >> wp.uint32(16)) | _ONE)
    v = v ^ (v * wp.uint32(0x05526C56))
    v = v ^ (v * wp.uint32(0x53A22864))
    return reverse_bits(v)


@wp.func
def scramble(v: wp.uint32, mode: int, seed: wp.uint32) -> wp.uint32:
    """Apply one of the randomisation codes above to a base-2 fixed-point value."""
    if mode == PERMUTE_DIGITS:
        return v ^ seed
    if mode == FAST_OWEN:
        return fast_owen_scramble(v, seed)
    if mode == OWEN:
        return owen_scramble(v, seed)
    return v


@wp.func
def permutation_element(i: wp.uint32, n: wp.uint32, seed: wp.uint32) -> wp.uint32:
    """Element i of a permutation of 0..n-1 chosen by ``seed`` (Kensler 2013, "Correlated
    multi-jittered sampling"): an invertible hash on the next power of two, cycle-walked into [0, n)."""
    w = n - _ONE
    w = w | (w >> wp.uint32(1))
    w = w | (w >> wp.uint32(2))
    w = w | (w >> wp.uint32(4))
    w = w | (w >> wp.uint32(8))
    w = w | (w >> wp.uint32(16))
    p = seed
    while True:
        i = i ^ p
        i = i * wp.uint32(0xE170893D)
        i = i ^ (p >> wp.uint32(16))
        i = i ^ ((i & w) >> wp.uint32(4))
        i = i ^ (p >> wp.uint32(8))
        i = i * wp.uint32(0x0929EB3F)
        i = i ^ (p >> wp.uint32(23))
        i = i ^ ((i & w) >> wp.uint32(1))
        i = i * (_ONE | (p >> wp.uint32(27)))
        i = i * wp.uint32(0x6935FA69)
        i = i ^ ((i & w) >> wp.uint32(11))
        i = i * wp.uint32(0x74DCB303)
        i = i ^ ((i & w) >> wp.uint32(2))
        i = i * wp.uint32(0x9E501CC3)
        i = i ^ ((i & w) >> wp.uint32(2))
        i = i * wp.uint32(0xC860A3DF)
        i = i & w
        i = i ^ (i >> wp.uint32(5))
        if i < n:
            break
    return (i + p) % n
