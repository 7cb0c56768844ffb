"""Random numbers as a pure function of (seed, sample index, pixel, dimension).

The state is seeded from the first three and the dimension is the order of draws along a path.
Passes are therefore independent and films add, which is what progressive rendering and resume
rely on. Warp passes an RNG state to a ``wp.func`` by value: draw with ``wp.randf(rng)`` in the
kernel itself, never through a helper that would return the same numbers on every call."""
from __future__ import annotations

import warp as wp


_HASH_M1 = wp.constant(wp.uint32(0x7FEB352D))


_HASH_M2 = wp.constant(wp.uint32(0x846CA68B))


_GOLDEN = wp.constant(wp.uint32(0x9E3779B9))


@wp.func
def hash_u32(x: wp.uint32) -> wp.uint32:
    """A 32-bit integer finaliser (lowbias32), so nearby seeds give unrelated streams."""
    x = x ^ (x >> wp.uint32(16))
    x = x * _HASH_M1
    x = x ^ (x >> wp.uint32(15))
    x = x * _HASH_M2
    x = x ^ (x >> wp.uint32(16))
    return x


@wp.func
def sample_rng(seed: int, sample_index: int, pixel: int) -> wp.uint32:
    """The RNG state for one (seed, sample, pixel); draws from it are the path's dimensions."""
    key = hash_u32(wp.uint32(seed) ^ hash_u32(wp.uint32(sample_index) + _GOLDEN))
    return wp.rand_init(wp.int32(key), pixel)
