"""Which sample indices a film holds, as sorted disjoint half-open ranges ``[(start, stop), ...]``.

A one-process render fills ``[0, spp)`` in order; a cluster render finishes ranges in any order, so
its checkpoint may have holes. Films add exactly (:mod:`renderer.device.film`), so a render may
fill the holes in any order and still equal an uninterrupted one."""
from __future__ import annotations

from collections.abc import Iterator

import numpy as np

Ranges = list[tuple[int, int]]


def add_range(ranges: Ranges, start: int, stop: int) -> Ranges:
    """``ranges`` with ``[start, stop)`` added, touching ranges merged; overlaps are a bug upstream."""
    out: Ranges = []
    for a, b in sorted([*ranges, (start, stop)]):
        if out and a < out[-1][1]:
            raise ValueError(f"sample range [{a}, {b}) overlaps [{out[-1][0]}, {out[-1][1]}), already in the film")
        if out and a == out[-1][1]:
            out[-1] = (out[-1][0], b)
        else:
            out.append((a, b))
    return out


def count(ranges: Ranges) -> int:
    return sum(b - a for a, b in ranges)


def missing(ranges: Ranges, spp: int) -> Ranges:
    """The ranges below ``spp`` that are not yet in the film, in sample order."""
    out: Ranges = []
    at = 0
    for a, b in [*ranges, (spp, spp)]:
        if min(a, spp) > at:
            out.append((at, min(a, spp)))
        at = max(at, b)
    return out


def samples(ranges: Ranges) -> Iterator[int]:
    for a, b in ranges:
        yield from range(a, b)


def to_array(ranges: Ranges) -> np.ndarray:
    return np.array(ranges, dtype=np.int64).reshape(-1, 2)


def from_array(a: np.ndarray) -> Ranges:
    """Ranges from a checkpoint's (K, 2) array, checked to be sorted, disjoint and non-empty."""
    a = np.asarray(a)
    if a.ndim != 2 or a.shape[1] != 2 or a.dtype.kind not in "iu":
        raise ValueError(f"sample ranges must be a (K, 2) integer array, got {a.dtype} {a.shape}")
    out: Ranges = []
    for start, stop in a.tolist():
        if not 0 <= start < stop or (out and start < out[-1][1]):
            raise ValueError(f"sample ranges are not sorted, disjoint and non-empty at [{start}, {stop})")
        out = add_range(out, start, stop)
    return out
