"""Warps from the unit square to disks and directions, each with its density."""
from __future__ import annotations

import warp as wp

from renderer.vecmath import PI


@wp.func
def concentric_disk(u: wp.vec2) -> wp.vec2:
    """Shirley–Chiu concentric map: area preserving and low distortion, used for lens sampling."""
    ox = 2.0 * u[0] - 1.0
    oy = 2.0 * u[1] - 1.0
    if ox == 0.0 and oy == 0.0:
        return wp.vec2(0.0, 0.0)
    r = float(0.0)
    theta = float(0.0)
    if wp.abs(ox) > wp.abs(oy):
        r = ox
        theta = (PI / 4.0) * (oy / ox)
    else:
        r = oy
        theta = PI / 2.0 - (PI / 4.0) * (ox / oy)
    return wp.vec2(r * wp.cos(theta), r * wp.sin(theta))


@wp.func
def cosine_hemisphere(u: wp.vec2) -> wp.vec3:
    """Cosine-weighted direction about +z (Malley's method); pdf = cos θ / π."""
    d = concentric_disk(u)
    z = wp.sqrt(wp.max(0.0, 1.0 - d[0] * d[0] - d[1] * d[1]))
    return wp.vec3(d[0], d[1], z)


@wp.func
def uniform_sphere(u: wp.vec2) -> wp.vec3:
    """Uniform direction on the unit sphere; pdf = 1 / 4π."""
    z = 1.0 - 2.0 * u[0]
    r = wp.sqrt(wp.max(0.0, 1.0 - z * z))
    phi = 2.0 * PI * u[1]
    return wp.vec3(r * wp.cos(phi), r * wp.sin(phi), z)


@wp.func
def uniform_cone(u: wp.vec2, cos_max: float) -> wp.vec3:
    """Uniform direction in a cone about +z of half-angle acos(cos_max); pdf = 1 / (2π(1 - cos_max))."""
    cos_t = 1.0 - u[0] * (1.0 - cos_max)
    sin_t = wp.sqrt(wp.max(0.0, 1.0 - cos_t * cos_t))
    phi = 2.0 * PI * u[1]
    return wp.vec3(sin_t * wp.cos(phi), sin_t * wp.sin(phi), cos_t)
