"""pbrt-v4's procedural textures on the device: Perlin noise, FBm and turbulence, and the textures
built from them (fbm, wrinkled, windy, marble, and the dots pattern), with pbrt's own permutation
table (``data/pbrt_noise.json``, extracted from pbrt-v4's source by ``data/make_pbrt_noise.py``).

pbrt fades out octaves finer than a pixel's footprint (from ray differentials); we have no ray
differentials, so every octave is summed: pbrt's result for a footprint under 2^-(octaves+1)."""
from __future__ import annotations

import json
from functools import lru_cache
from pathlib import Path

import numpy as np
import warp as wp

_Spline = wp.types.matrix(shape=(9, 3), dtype=float)
#: marble's colour spline: pbrt-v4's nine cubic Bézier control points (six segments), times 1.5
MARBLE_COLORS = wp.constant(_Spline(.58, .58, .6, .58, .58, .6, .58, .58, .6, .5, .5, .5, .6, .59, .58,
                                    .58, .58, .6, .58, .58, .6, .2, .2, .33, .58, .58, .6))


@lru_cache(maxsize=1)
def permutation() -> np.ndarray:
    """pbrt's NoisePerm: 512 ints, a permutation of 0..255 written twice."""
    data = json.loads((Path(__file__).parent / "data" / "pbrt_noise.json").read_text())
    return np.asarray(data["perm"], dtype=np.int32)


@wp.func
def _grad(perm: wp.array(dtype=int), x: int, y: int, z: int, dx: float, dy: float, dz: float) -> float:
    h = perm[perm[perm[x] + y] + z] & 15
    u = wp.where(h < 8 or h == 12 or h == 13, dx, dy)
    v = wp.where(h < 4 or h == 12 or h == 13, dy, dz)
    return wp.where((h & 1) != 0, -u, u) + wp.where((h & 2) != 0, -v, v)


@wp.func
def _weight(t: float) -> float:
    t3 = t * t * t
    return 6.0 * t3 * t * t - 15.0 * t3 * t + 10.0 * t3


@wp.func
def _lerp(t: float, a: float, b: float) -> float:
    return (1.0 - t) * a + t * b


@wp.func
def noise(perm: wp.array(dtype=int), p: wp.vec3) -> float:
    """pbrt-v4's Perlin noise: gradients from the permutation at the 8 lattice corners, blended by
    the quintic weight; zero at every lattice point, roughly within [-1, 1]."""
    big = float(1 << 30)
    x = wp.mod(p[0], big)
    y = wp.mod(p[1], big)
    z = wp.mod(p[2], big)
    fx = wp.floor(x)
    fy = wp.floor(y)
    fz = wp.floor(z)
    dx = x - fx
    dy = y - fy
    dz = z - fz
    ix = int(fx) & 255
    iy = int(fy) & 255
    iz = int(fz) & 255
    w000 = _grad(perm, ix, iy, iz, dx, dy, dz)
    w100 = _grad(perm, ix + 1, iy, iz, dx - 1.0, dy, dz)
    w010 = _grad(perm, ix, iy + 1, iz, dx, dy - 1.0, dz)
    w110 = _grad(perm, ix + 1, iy + 1, iz, dx - 1.0, dy - 1.0, dz)
    w001 = _grad(perm, ix, iy, iz + 1, dx, dy, dz - 1.0)
    w101 = _grad(perm, ix + 1, iy, iz + 1, dx - 1.0, dy, dz - 1.0)
    w011 = _grad(perm, ix, iy + 1, iz + 1, dx, dy - 1.0, dz - 1.0)
    w111 = _grad(perm, ix + 1, iy + 1, iz + 1, dx - 1.0, dy - 1.0, dz - 1.0)
    wx = _weight(dx)
    wy = _weight(dy)
    wz = _weight(dz)
    y0 = _lerp(wy, _lerp(wx, w000, w100), _lerp(wx, w010, w110))
    y1 = _lerp(wy, _lerp(wx, w001, w101), _lerp(wx, w011, w111))
    return _lerp(wz, y0, y1)


@wp.func
def fbm(perm: wp.array(dtype=int), p: wp.vec3, omega: float, octaves: int) -> float:
    """Σ omega^i noise(1.99^i p) over every octave (pbrt's FBm at a vanishing footprint)."""
    total = float(0.0)
    lam = float(1.0)
    o = float(1.0)
    for _i in range(octaves):
        total += o * noise(perm, lam * p)
        lam *= 1.99
        o *= omega
    return total


@wp.func
def turbulence(perm: wp.array(dtype=int), p: wp.vec3, omega: float, octaves: int) -> float:
    """Σ omega^i |noise(1.99^i p)|, plus pbrt's 0.2 omega^octaves for the clamped partial octave
    (its Turbulence at a vanishing footprint)."""
    total = float(0.0)
    lam = float(1.0)
    o = float(1.0)
    for _i in range(octaves):
        total += o * wp.abs(noise(perm, lam * p))
        lam *= 1.99
        o *= omega
    return total + o * 0.2


@wp.func
def windy(perm: wp.array(dtype=int), p: wp.vec3) -> float:
    """pbrt's windy waves: |FBm(0.1 p, 1/2, 3)| (wind strength) times FBm(p, 1/2, 6) (wave height)."""
    return wp.abs(fbm(perm, 0.1 * p, 0.5, 3)) * fbm(perm, p, 0.5, 6)


@wp.func
def _bezier(a: wp.vec3, b: wp.vec3, c: wp.vec3, d: wp.vec3, t: float) -> wp.vec3:
    ab = wp.lerp(a, b, t)
    bc = wp.lerp(b, c, t)
    cd = wp.lerp(c, d, t)
    return wp.lerp(wp.lerp(ab, bc, t), wp.lerp(bc, cd, t), t)


@wp.func
def marble(perm: wp.array(dtype=int), p: wp.vec3, omega: float, octaves: int, scale: float,
           variation: float) -> wp.vec3:
    """pbrt's marble: the sine of y + variation FBm(scale p) picks a point on a cubic Bézier colour
    spline (MARBLE_COLORS, six segments), times 1.5."""
    q = p * scale
    t = 0.5 + 0.5 * wp.sin(q[1] + variation * fbm(perm, q, omega, octaves))
    first = wp.min(int(wp.floor(t * 6.0)), 5)
    t = t * 6.0 - float(first)
    c = MARBLE_COLORS
    # the segment's four control points, each read at a constant row: indexing the spline with
    # ``first`` put a copy of it in local memory (108 B of the frame of every kernel with textures)
    a = c[0]
    b = c[1]
    d = c[2]
    e = c[3]
    if first == 1:
        a, b, d, e = c[1], c[2], c[3], c[4]
    elif first == 2:
        a, b, d, e = c[2], c[3], c[4], c[5]
    elif first == 3:
        a, b, d, e = c[3], c[4], c[5], c[6]
    elif first == 4:
        a, b, d, e = c[4], c[5], c[6], c[7]
    elif first == 5:
        a, b, d, e = c[5], c[6], c[7], c[8]
    return 1.5 * _bezier(a, b, d, e, t)


@wp.func
def inside_polka_dot(perm: wp.array(dtype=int), st: wp.vec2) -> bool:
    """pbrt's dots: a cell (centred on integer st) holds a dot of radius 0.35 where noise at its
    centre is positive, shifted within the cell by two more noise values."""
    s_cell = wp.floor(st[0] + 0.5)
    t_cell = wp.floor(st[1] + 0.5)
    if noise(perm, wp.vec3(s_cell + 0.5, t_cell + 0.5, 0.5)) > 0.0:
        radius = 0.35
        shift = 0.5 - radius
        sc = s_cell + shift * noise(perm, wp.vec3(s_cell + 1.5, t_cell + 2.8, 0.5))
        tc = t_cell + shift * noise(perm, wp.vec3(s_cell + 4.5, t_cell + 9.8, 0.5))
        ds = st[0] - sc
        dt = st[1] - tc
        return ds * ds + dt * dt < radius * radius
    return False
