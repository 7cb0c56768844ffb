"""Small device math every kernel shares: π, a few vector reductions, and a vector's component at
an index known only at run time."""
from __future__ import annotations

from typing import Any

import warp as wp


PI = wp.constant(3.14159265358979323846)


INV_PI = wp.constant(0.31830988618379067154)


@wp.func
def max3(v: wp.vec3) -> float:
    return wp.max(v[0], wp.max(v[1], v[2]))


@wp.func
def mean3(v: wp.vec3) -> float:
    return (v[0] + v[1] + v[2]) / 3.0


@wp.func
def luminance(c: wp.vec3) -> float:
    return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]


@wp.func
def max_abs(p: wp.vec3) -> float:
    return max3(wp.vec3(wp.abs(p[0]), wp.abs(p[1]), wp.abs(p[2])))


@wp.func
def component(v: Any, i: int):
    """``v[i]`` for an index known only at run time (a colour channel, an axis), read without
    indexing: CUDA keeps a vector indexed at run time in the stack frame, not in registers."""
    return wp.where(i == 0, v[0], wp.where(i == 1, v[1], v[2]))


@wp.func
def added(v: Any, i: int, x: Any):
    """``v`` with ``x`` added to component ``i`` (known only at run time), each write at a constant
    index (``component``'s reason)."""
    out = v
    if i == 0:
        out[0] = v[0] + x
    elif i == 1:
        out[1] = v[1] + x
    else:
        out[2] = v[2] + x
    return out


@wp.func
def with_component(v: wp.vec3, i: int, x: float) -> wp.vec3:
    """v with component i (a run-time index) set to x, by selects (see ``component``)."""
    return wp.vec3(wp.where(i == 0, x, v[0]), wp.where(i == 1, x, v[1]), wp.where(i == 2, x, v[2]))
