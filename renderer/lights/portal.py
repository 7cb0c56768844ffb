"""pbrt-v4's portal on the ``infinite`` light (PortalImageInfiniteLight): a rectangle (``portal``,
four world-space corners) through which the environment enters, such as a window. As in pbrt-v4
the equal-area map is resampled once (bilinearly, with its octahedral wrap) into a "rectified"
image over the portal's directions, (u, v) = ((α + π/2) / π, (β + π/2) / π) with α, β the angles
of a direction from the portal's normal in its two side planes. A ray leaving the scene sees the
map only if its direction goes through the portal from where it left (the portal's (u, v) bounds
from that point); every other escaping ray sees black, as in pbrt-v4. Light sampling draws (u, v)
uniformly within those bounds, so every sample goes through the window (pbrt-v4 weights them by
the image within the bounds; both are unbiased, ours is noisier for a small bright sun).
"""
from __future__ import annotations

import numpy as np
import warp as wp

from renderer.errors import Location, SceneError
from renderer.lights.sample import LightEval, LightSample
from renderer.lights.table import Lights
from renderer.sampling.equal_area import sphere_to_square
from renderer.vecmath import PI


def frame(corners: np.ndarray, loc: Location | None) -> np.ndarray:
    """Rows x, y, z of pbrt-v4's portal frame (Frame::FromXY(p3 - p0, p1 - p0)); the corners must
    make a rectangle (pbrt-v4 reports the same test as an error)."""
    p = np.asarray(corners, np.float64).reshape(4, 3)
    unit = lambda v: v / np.linalg.norm(v) if np.linalg.norm(v) > 0 else v
    p01, p12, p32, p03 = unit(p[1] - p[0]), unit(p[2] - p[1]), unit(p[2] - p[3]), unit(p[3] - p[0])
    if (abs(p01 @ p32 - 1) > 1e-3 or abs(p12 @ p03 - 1) > 1e-3
            or max(abs(p01 @ p12), abs(p12 @ p32), abs(p32 @ p03), abs(p03 @ p01)) > 1e-3):
        raise SceneError('LightSource "infinite": "portal" must be the 4 corners of a rectangle, in order', loc)
    return np.stack([p03, p01, np.cross(p03, p01)])


def _directions(n: int, portal_frame: np.ndarray) -> np.ndarray:
    """World directions of the rectified image's pixel centres, (n, n, 3)."""
    c = (np.arange(n) + 0.5) / n
    a, b = np.meshgrid(np.tan(-np.pi / 2 + c * np.pi), np.tan(-np.pi / 2 + c * np.pi))
    local = np.stack([a, b, np.ones_like(a)], -1)
    local /= np.linalg.norm(local, axis=-1, keepdims=True)
    return local @ portal_frame


def _octahedral_pixels(x: np.ndarray, y: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """pbrt-v4's OctahedralSphere wrap of pixel coordinates (RemapPixelCoords)."""
    x, y = x.copy(), y.copy()
    lo, hi = x < 0, x >= n
    x[lo], y[lo] = -x[lo], n - 1 - y[lo]
    x[hi], y[hi] = 2 * n - 1 - x[hi], n - 1 - y[hi]
    lo, hi = y < 0, y >= n
    x[lo], y[lo] = n - 1 - x[lo], -y[lo]
    x[hi], y[hi] = n - 1 - x[hi], 2 * n - 1 - y[hi]
    return np.clip(x, 0, n - 1), np.clip(y, 0, n - 1)


def rectified(rgb: np.ndarray, light_from_world: np.ndarray, portal_frame: np.ndarray) -> np.ndarray:
    """The equal-area map (n, n, 3) resampled over the portal's (u, v), bilinearly as pbrt-v4."""
    n = rgb.shape[0]
    w = _directions(n, portal_frame) @ np.asarray(light_from_world, np.float64).T
    w /= np.linalg.norm(w, axis=-1, keepdims=True)
    uv = sphere_to_square(w.reshape(-1, 3).astype(np.float32)).astype(np.float64)
    x, y = uv[:, 0] * n - 0.5, uv[:, 1] * n - 0.5
    xi, yi = np.floor(x).astype(np.int64), np.floor(y).astype(np.int64)
    dx, dy = (x - xi)[:, None], (y - yi)[:, None]

    def at(px: np.ndarray, py: np.ndarray) -> np.ndarray:
        qx, qy = _octahedral_pixels(px, py, n)
        return rgb[qy, qx]

    out = ((1 - dx) * (1 - dy) * at(xi, yi) + dx * (1 - dy) * at(xi + 1, yi)
           + (1 - dx) * dy * at(xi, yi + 1) + dx * dy * at(xi + 1, yi + 1))
    return out.reshape(n, n, 3).astype(np.float32)


# ---- device ---------------------------------------------------------------------------------------

@wp.func
def _uv(w: wp.vec3) -> wp.vec2:
    """A portal-frame direction's rectified (u, v) (w.z > 0)."""
    return wp.vec2(wp.clamp((wp.atan2(w[0], w[2]) + PI / 2.0) / PI, 0.0, 1.0),
                   wp.clamp((wp.atan2(w[1], w[2]) + PI / 2.0) / PI, 0.0, 1.0))


@wp.func
def _dw_duv(w: wp.vec3) -> float:
    """Solid angle per unit of (u, v) at portal-frame direction w (pbrt-v4's duv_dw)."""
    return PI * PI * (1.0 - w[0] * w[0]) * (1.0 - w[1] * w[1]) / w[2]


@wp.func
def _bounds(lights: Lights, i: int, p: wp.vec3, n: int) -> wp.vec4:
    """The (u, v) rectangle the portal covers seen from p: (u0, v0, u1, v1); u1 < u0 when p is
    behind the portal's plane."""
    c = lights.v_start[i] + n * n
    a = wp.normalize(lights.to_light[i] * wp.normalize(lights.v_pool[c] - p))
    b = wp.normalize(lights.to_light[i] * wp.normalize(lights.v_pool[c + 1] - p))
    if a[2] <= 0.0 or b[2] <= 0.0:
        return wp.vec4(1.0, 1.0, 0.0, 0.0)
    ua = _uv(a)
    ub = _uv(b)
    return wp.vec4(wp.min(ua[0], ub[0]), wp.min(ua[1], ub[1]), wp.max(ua[0], ub[0]), wp.max(ua[1], ub[1]))


@wp.func
def _lookup(lights: Lights, i: int, uv: wp.vec2, n: int) -> wp.vec3:
    x = wp.clamp(int(uv[0] * float(n)), 0, n - 1)
    y = wp.clamp(int(uv[1] * float(n)), 0, n - 1)
    return wp.cw_mul(lights.L[i], lights.v_pool[lights.v_start[i] + y * n + x])


@wp.func
def escaped(lights: Lights, i: int, n: int, p: wp.vec3, d: wp.vec3) -> LightEval:
    """What a ray leaving the scene from p along d sees: the map through the portal, else nothing."""
    ev = LightEval()
    w = wp.normalize(lights.to_light[i] * d)
    b = _bounds(lights, i, p, n)
    if w[2] <= 0.0 or b[2] <= b[0] or b[3] <= b[1]:
        return ev
    uv = _uv(w)
    if uv[0] < b[0] or uv[0] > b[2] or uv[1] < b[1] or uv[1] > b[3]:
        return ev
    ev.L = _lookup(lights, i, uv, n)
    ev.pdf = 1.0 / ((b[2] - b[0]) * (b[3] - b[1]) * _dw_duv(w))
    return ev


@wp.func
def sample(lights: Lights, i: int, n: int, p: wp.vec3, u: wp.vec2) -> LightSample:
    """A direction through the portal from p, uniform in its (u, v) bounds."""
    s = LightSample()
    s.delta = False
    s.dist = 1.0e30
    b = _bounds(lights, i, p, n)
    if b[2] <= b[0] or b[3] <= b[1]:
        return s
    uv = wp.vec2(b[0] + u[0] * (b[2] - b[0]), b[1] + u[1] * (b[3] - b[1]))
    w = wp.normalize(wp.vec3(wp.tan(-PI / 2.0 + uv[0] * PI), wp.tan(-PI / 2.0 + uv[1] * PI), 1.0))
    s.wi = wp.normalize(lights.to_world[i] * w)
    s.L = _lookup(lights, i, uv, n)
    s.pdf = 1.0 / ((b[2] - b[0]) * (b[3] - b[1]) * _dw_duv(w))
    return s
