"""Random numbers and the warps from the unit square to directions, shared by every kernel.

Random numbers are a pure function of (seed, sample index, pixel, dimension): the state is
seeded from the first three and the dimension is the order of draws along a path. Passes are
therefore independent and films add, which is what progressive rendering and resume rely on.
"""
from __future__ import annotations

import warp as wp

PI = wp.constant(3.14159265358979323846)
INV_PI = wp.constant(0.31830988618379067154)


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


@wp.func
def rand2(state: wp.uint32) -> wp.vec2:
    """Two uniforms from ``state``. CAUTION: Warp passes scalars to a ``wp.func`` by value, so the
    caller's state does NOT advance: two calls return the same pair. Inline
    ``wp.vec2(wp.randf(rng), wp.randf(rng))`` in kernels instead."""
    a = wp.randf(state)
    b = wp.randf(state)
    return wp.vec2(a, b)


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


@wp.func
def power_heuristic(pdf_a: float, pdf_b: float) -> float:
    """Veach's power heuristic (β = 2) weight for the strategy with density ``pdf_a``."""
    a = pdf_a * pdf_a
    b = pdf_b * pdf_b
    if a + b <= 0.0:
        return 0.0
    if a > 1.0e30:
        return 1.0
    return a / (a + b)


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


@wp.func
def max3(v: wp.vec3) -> float:
    return wp.max(v[0], wp.max(v[1], v[2]))


@wp.func
def luminance(c: wp.vec3) -> float:
    return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
