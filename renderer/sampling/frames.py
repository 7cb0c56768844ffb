"""Orthonormal shading frames and the change of basis into and out of them."""
from __future__ import annotations

import warp as wp


@wp.struct
class Frame:
    """An orthonormal basis (s, t, n): local z is the normal."""

    s: wp.vec3
    t: wp.vec3
    n: wp.vec3


@wp.func
def frame_from_normal(n: wp.vec3) -> Frame:
    """Duff et al.'s branchless orthonormal basis: continuous and stable for every unit normal."""
    sign = wp.where(n[2] >= 0.0, 1.0, -1.0)
    a = -1.0 / (sign + n[2])
    b = n[0] * n[1] * a
    f = Frame()
    f.s = wp.vec3(1.0 + sign * n[0] * n[0] * a, sign * b, -sign * n[0])
    f.t = wp.vec3(b, sign + n[1] * n[1] * a, -n[1])
    f.n = n
    return f


@wp.func
def frame_from_tangent(n: wp.vec3, dpdu: wp.vec3) -> Frame:
    """A frame whose s axis follows the surface's u direction (for anisotropic roughness)."""
    s = dpdu - n * wp.dot(n, dpdu)
    ls = wp.length(s)
    if ls < 1.0e-12:
        return frame_from_normal(n)
    f = Frame()
    f.s = s / ls
    f.t = wp.cross(n, f.s)
    f.n = n
    return f


@wp.func
def to_local(f: Frame, v: wp.vec3) -> wp.vec3:
    return wp.vec3(wp.dot(v, f.s), wp.dot(v, f.t), wp.dot(v, f.n))


@wp.func
def to_world(f: Frame, v: wp.vec3) -> wp.vec3:
    return f.s * v[0] + f.t * v[1] + f.n * v[2]
