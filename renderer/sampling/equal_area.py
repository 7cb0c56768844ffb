"""Clarberg's octahedral equal-area map between [0,1]² and the unit sphere (pbrt-v4's layout for
environment images), on the device and, through the same functions, on numpy arrays."""
from __future__ import annotations

import numpy as np
import warp as wp

from renderer.device.runtime import init_warp
from renderer.vecmath import PI

wp.set_module_options({"enable_backward": False})   # nothing differentiates these kernels


@wp.func
def equal_area_square_to_sphere(p: wp.vec2) -> wp.vec3:
    """Clarberg's octahedral equal-area map of [0,1]² onto the sphere (pbrt-v4's layout)."""
    u = 2.0 * p[0] - 1.0
    v = 2.0 * p[1] - 1.0
    up = wp.abs(u)
    vp = wp.abs(v)
    sd = 1.0 - (up + vp)
    d = wp.abs(sd)
    r = 1.0 - d
    phi = PI / 4.0
    if r > 0.0:
        phi = ((vp - up) / r + 1.0) * PI / 4.0
    z = wp.where(sd >= 0.0, 1.0 - r * r, -(1.0 - r * r))
    cp = wp.where(u >= 0.0, wp.abs(wp.cos(phi)), -wp.abs(wp.cos(phi)))
    sp = wp.where(v >= 0.0, wp.abs(wp.sin(phi)), -wp.abs(wp.sin(phi)))
    s = r * wp.sqrt(wp.max(0.0, 2.0 - r * r))
    return wp.vec3(cp * s, sp * s, z)


@wp.func
def equal_area_sphere_to_square(d: wp.vec3) -> wp.vec2:
    x = wp.abs(d[0])
    y = wp.abs(d[1])
    z = wp.abs(d[2])
    r = wp.sqrt(wp.max(0.0, 1.0 - z))
    a = wp.max(x, y)
    b = wp.min(x, y)
    if a > 0.0:
        b = b / a
    else:
        b = 0.0
    phi = wp.atan(b) * 2.0 / PI
    if x < y:
        phi = 1.0 - phi
    v = phi * r
    u = r - v
    if d[2] < 0.0:
        t = u
        u = 1.0 - v
        v = 1.0 - t
    u = wp.where(d[0] >= 0.0, u, -u)
    v = wp.where(d[1] >= 0.0, v, -v)
    return wp.vec2(0.5 * (u + 1.0), 0.5 * (v + 1.0))


@wp.kernel
def _to_sphere(uv: wp.array(dtype=wp.vec2), out: wp.array(dtype=wp.vec3)):
    i = wp.tid()
    out[i] = equal_area_square_to_sphere(uv[i])


@wp.kernel
def _to_square(d: wp.array(dtype=wp.vec3), out: wp.array(dtype=wp.vec2)):
    i = wp.tid()
    out[i] = equal_area_sphere_to_square(d[i])


def _launch(kernel, x: np.ndarray, n_in: int, in_type, n_out: int, out_type) -> np.ndarray:
    init_warp()
    x = np.asarray(x, dtype=np.float32)
    flat = np.ascontiguousarray(x.reshape(-1, n_in))
    out = wp.empty(len(flat), dtype=out_type, device="cpu")
    wp.launch(kernel, dim=len(flat), inputs=[wp.array(flat, dtype=in_type, device="cpu"), out], device="cpu")
    return out.numpy().reshape(x.shape[:-1] + (n_out,))


def square_to_sphere(uv: np.ndarray) -> np.ndarray:
    """Unit directions (..., 3) for points (..., 2) of the unit square (float32)."""
    return _launch(_to_sphere, uv, 2, wp.vec2, 3, wp.vec3)


def sphere_to_square(d: np.ndarray) -> np.ndarray:
    """Points (..., 2) of the unit square for unit directions (..., 3) (float32)."""
    return _launch(_to_square, d, 3, wp.vec3, 2, wp.vec2)
