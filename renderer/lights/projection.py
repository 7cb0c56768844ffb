"""pbrt-v4's ``projection`` light: a point light at the light space's origin projecting an RGB image
along its +z through a perspective frustum, like a slide projector. ``fov`` (degrees) spans the
image's shorter side; the image is upright with light-space +y up, and each direction takes the
nearest pixel's colour times ``scale`` (an rgb image keeps its own magnitude); none falls outside.
``power`` > 0 rescales ``scale`` as pbrt-v4 does, by power / (A × the image's mean of luminance ×
cos³θ at pixel centres), A being the image's area on the plane z = 1. A delta light.
"""
from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import warp as wp

from renderer.color.rgb import luminance
from renderer.errors import Location, SceneError
from renderer.lights import point
from renderer.lights.images import read_light_image, resolved
from renderer.lights.sample import LightSample
from renderer.lights.table import LightEntry, Lights, Row
from renderer.parameters import Parameter, Parameters

if TYPE_CHECKING:
    from renderer.scene.description import LightDesc

NAME = "projection"
DIRECTIVE = "LightSource"
PARAMS = Parameters(
    Parameter("scale", "float", 1.0, lo=0.0, doc="multiplies the image"),
    Parameter("power", "float", -1.0, doc="if > 0, the emitted power (pbrt-v4): it rescales scale"),
    Parameter("fov", "float", 90.0, lo=1e-3, hi=179.0, doc="field of view across the image's shorter side, degrees"),
    Parameter("filename", "string", doc="the projected image (R, G, B)"),
)
ROW = Row(floats=("tan_half", "x_max", "y_max"), ints=("width", "height"), vecs=point.ROW.names["vecs"])
F, K = ROW.F, ROW.K
#: pbrt-v4's near plane: directions closer to the light's z = 0 plane than this are dark.
HITHER = 1e-3
#: pbrt-v4 flips the light's y so that the image's first row is at the top.
FLIP_Y = np.diag([1.0, -1.0, 1.0])


def check(given: dict[str, Any], light_to_world: np.ndarray, loc: Location | None,
          base_dir: Path | None) -> dict[str, Any]:
    if "filename" not in given:
        raise SceneError('LightSource "projection" needs a "filename" (pbrt-v4 refuses it too)', loc)
    return resolved(given, loc, base_dir, "projection image")


def screen(width: int, height: int, fov: float) -> tuple[float, float, float]:
    """tan(fov / 2) and the half-extents of pbrt-v4's screen window (the shorter side spans ±1)."""
    aspect = width / height
    x_max, y_max = (aspect, 1.0) if aspect > 1 else (1.0, 1.0 / aspect)
    return math.tan(math.radians(fov) / 2.0), x_max, y_max


def power_per_scale(rgb: np.ndarray, fov: float) -> float:
    """What pbrt-v4 takes for the power at scale 1: A × mean over pixels of luminance × cos³θ at
    the pixel centre (cos³θ: the solid angle per unit area of the z = 1 plane)."""
    h, w = rgb.shape[:2]
    t, x_max, y_max = screen(w, h, fov)
    sx = -x_max + 2.0 * x_max * (np.arange(w) + 0.5) / w
    sy = -y_max + 2.0 * y_max * (np.arange(h) + 0.5) / h
    X, Y = np.meshgrid(sx * t, sy * t)
    cos3 = (1.0 + X * X + Y * Y) ** -1.5
    area = 4.0 * t * t * max(w / h, h / w)
    return float(area * (luminance(rgb.astype(np.float64)) * cos3).mean())


def entry(light: LightDesc, tris: np.ndarray | None) -> LightEntry:
    v = light.values
    image = read_light_image(v, light.loc, "projection image")
    if image.shape[2] < 3:
        raise SceneError("projection image must have R, G and B channels (pbrt-v4)", light.loc)
    rgb = np.ascontiguousarray(image[..., :3])
    h, w = rgb.shape[:2]
    t, x_max, y_max = screen(w, h, v["fov"])
    factor = point.power_factor(v, power_per_scale(rgb, v["fov"]))
    R = np.asarray(light.light_to_world, np.float64)[:3, :3] @ FLIP_Y
    return LightEntry(L=np.full(3, v["scale"] * factor), floats={"tan_half": t, "x_max": x_max, "y_max": y_max},
                      ints={"width": w, "height": h}, vecs={"position": point.position(v, light.light_to_world)},
                      to_world=R, to_light=np.linalg.inv(R), v_data=rgb.reshape(-1, 3))


@wp.func
def _slide(lights: Lights, i: int, w: wp.vec3) -> wp.vec3:
    """The image's colour towards light-space direction w (black outside the frustum)."""
    if w[2] < HITHER:
        return wp.vec3(0.0)
    t = lights.f[i, F.tan_half]
    xm = lights.f[i, F.x_max]
    ym = lights.f[i, F.y_max]
    sx = w[0] / (w[2] * t)
    sy = w[1] / (w[2] * t)
    if sx < -xm or sx > xm or sy < -ym or sy > ym:
        return wp.vec3(0.0)
    wdt = lights.k[i, K.width]
    hgt = lights.k[i, K.height]
    x = wp.clamp(int((sx + xm) / (2.0 * xm) * float(wdt)), 0, wdt - 1)
    y = wp.clamp(int((sy + ym) / (2.0 * ym) * float(hgt)), 0, hgt - 1)
    return lights.v_pool[lights.v_start[i] + y * wdt + x]


@wp.func
def sample(lights: Lights, i: int, p: wp.vec3, u: wp.vec2) -> LightSample:
    s = point.sample(lights, i, p, u)
    if s.pdf > 0.0:
        s.L = wp.cw_mul(s.L, _slide(lights, i, wp.normalize(lights.to_light[i] * (-s.wi))))
    return s
