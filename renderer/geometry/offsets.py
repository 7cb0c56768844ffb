"""Where a spawned ray starts: off the surface by the hit point's own float32 error."""
from __future__ import annotations

import warp as wp

from renderer.geometry.intersect import Surface
from renderer.vecmath import max_abs


@wp.func
def offset_origin(s: Surface, w: wp.vec3) -> wp.vec3:
    """Move a spawned ray's origin off the surface along the geometric normal, on the side of
    ``w``. The distance scales with the float32 error of the hit point, which grows with the
    magnitude of the triangle's vertices (pbrt's bound Σ b_i |p_i|, with a safety factor for the
    intersector's barycentrics), so 0.3 mm grains and 1 km dunes both escape self-intersection
    without light leaking through either."""
    eps = 1.0e-7 + 4.0e-6 * wp.max(s.err, max_abs(s.p))
    if wp.dot(w, s.ng) < 0.0:
        eps = -eps
    return s.p + s.ng * eps


@wp.func
def ray_epsilon(p: wp.vec3) -> float:
    """The same relative tolerance, for shortening shadow rays towards a point on a light."""
    return 1.0e-7 + 8.0e-6 * max_abs(p)
