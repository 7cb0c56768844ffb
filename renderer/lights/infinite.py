"""pbrt-v4's ``infinite`` light: constant radiance ``L``, or an environment image (square: pbrt-v4's
equal-area octahedral map; 2:1: latitude-longitude), importance sampled with a piecewise-constant
2D distribution over the image. ``scale`` multiplies either. ``illuminance`` > 0 (lux) rescales it
as pbrt-v4 does: constant ``L`` by E / π (the illuminance of uniform unit radiance on an upward
patch; an rgb ``L`` keeps its own magnitude); an image by E / k, where k is pbrt-v4's sum over the
pixels above the horizon of luminance × cos θ × 2π / pixel count, which is half the map's true
upward illuminance (so a map ends up twice as bright as a constant ``L`` of the same illuminance,
as in pbrt-v4). ``portal`` (four corners of a rectangle, world space) makes it pbrt-v4's portal
light: the map (or a constant ``L``) is seen, and sampled, only through that window (portal.py).
"""
from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import warp as wp

from renderer.color.rgb import luminance
from renderer.errors import Location, SceneError
from renderer.lights import portal
from renderer.lights.images import read_light_image, resolved, rgb_of
from renderer.lights.sample import LightEval, LightSample
from renderer.lights.table import LightEntry, Lights, Row, colour_parameters, scaled_colour
from renderer.parameters import Parameter, Parameters
from renderer.sampling.distribution import distribution_2d, sample_cdf
from renderer.sampling.equal_area import equal_area_sphere_to_square, equal_area_square_to_sphere
from renderer.sampling.warps import uniform_sphere
from renderer.vecmath import PI

if TYPE_CHECKING:
    from renderer.scene.description import LightDesc

NAME = "infinite"
DIRECTIVE = "LightSource"
PARAMS = Parameters(
    *colour_parameters("L", "constant radiance (not with filename)"),
    Parameter("filename", "string", doc="environment image: square = equal-area, 2:1 = lat-long"),
    Parameter("illuminance", "float", -1.0, doc="if > 0, the illuminance (lux) on an upward patch (pbrt-v4)"),
    Parameter("portal", "points3", doc="4 world-space corners of a rectangle: light enters only through it (pbrt-v4)"),
)

MAP_CONSTANT = 0
MAP_EQUAL_AREA = 1
MAP_LATLONG = 2
MAP_PORTAL = 3                  # an equal-area map (or L) rectified over a portal's directions
#: channels: 0 when the pixels are float RGB in the vector pool, 1 or 3 when they are 8-bit codes
#: in the code pool; lut: where the 256 values of those codes sit in the light's float data
ROW = Row(ints=("mapping", "width", "height", "channels", "lut"))
K = ROW.K


def check(given: dict[str, Any], light_to_world: np.ndarray, loc: Location | None,
          base_dir: Path | None) -> dict[str, Any]:
    """Refuse L with filename (pbrt-v4 does too) and resolve the image against the scene file."""
    if "filename" in given and "L" in given:
        raise SceneError('LightSource "infinite": give either "L" or "filename", not both', loc)
    if "filename" in given:
        given = resolved(given, loc, base_dir, "environment image")
    if "portal" in given:
        if len(given["portal"]) != 12:
            raise SceneError(f'LightSource "infinite": "portal" needs 4 points, got {len(given["portal"]) / 3:g}', loc)
        portal.frame(np.asarray(given["portal"]), loc)
    return given


def _mapping(image: np.ndarray, loc: Location | None) -> int:
    h, w = image.shape[:2]
    if w == h:
        return MAP_EQUAL_AREA
    if w == 2 * h:
        return MAP_LATLONG
    raise SceneError(f"environment image must be square (equal-area) or 2:1 (lat-long), got {w}x{h}", loc)


class CodeRows:
    """An 8-bit map's linear RGB, decoded one row at a time: ``rows[y]`` is row y (float32 (w, 3)),
    ``rows[y0:y1]`` a band; ``shape`` is (h, w, 3). Nothing image-sized is ever decoded."""

    def __init__(self, codes: np.ndarray, values: np.ndarray):
        self.codes, self.values = codes, values
        self.shape = (*codes.shape[:2], 3)

    def __getitem__(self, rows) -> np.ndarray:
        v = self.values[self.codes[rows]]
        return v if v.shape[-1] == 3 else np.repeat(v, 3, axis=-1)


class _MaxChannel:
    """The sampling function's rows (the largest channel of each pixel), for distribution_2d."""

    def __init__(self, rgb):
        self.rgb, self.shape = rgb, rgb.shape[:2]

    def __getitem__(self, y: int) -> np.ndarray:
        return self.rgb[y].max(axis=-1)


def distribution_function(rgb, mapping: int) -> tuple[object, np.ndarray | None]:
    """The function the map is importance sampled by, as (max channel, per-row weight): sin θ for
    lat-long (the solid angle of a row), none for the equal-area square. ``rgb`` is a float
    (h, w, 3) array or :class:`CodeRows`; the max channel is taken a row at a time."""
    h = rgb.shape[0]
    weight = np.sin(np.pi * (np.arange(h) + 0.5) / h) if mapping == MAP_LATLONG else None
    return _MaxChannel(rgb), weight


#: Rows per band when a whole-map sum is taken a band at a time
_BAND = 256


def pbrt_illuminance(rgb, mapping: int) -> float:
    """pbrt-v4's illuminance of a map (ImageInfiniteLight with ``illuminance``): luminance × cos θ
    over the pixel centres above the horizon (+z of the map's frame), times half a pixel's solid
    angle (2π / pixel count for the equal-area square, which is what pbrt-v4 computes). Computed a
    band of rows at a time into one float64 vector of the upper pixels' terms, summed once, so the
    sum is the one a whole-map computation gives, bit for bit."""
    h, w = rgb.shape[:2]
    terms, used = np.empty(0), 0
    for y0 in range(0, h, _BAND):
        y1 = min(h, y0 + _BAND)
        u, v = np.meshgrid((np.arange(w) + 0.5) / w, (np.arange(y0, y1) + 0.5) / h)
        if mapping == MAP_EQUAL_AREA:
            from renderer.sampling.equal_area import square_to_sphere
            cos_t = square_to_sphere(np.stack([u, v], -1).reshape(-1, 2))[:, 2].reshape(u.shape)
            half_pixel = np.broadcast_to(2.0 * np.pi / (w * h), u.shape)
        else:                                   # lat-long: a pixel's solid angle varies with its row
            cos_t = np.cos(np.pi * v)
            half_pixel = 0.5 * (2.0 * np.pi / w) * (np.pi / h) * np.sin(np.pi * v)
        up = cos_t > 0
        term = luminance(np.asarray(rgb[y0:y1], dtype=np.float64))[up] * cos_t[up] * half_pixel[up]
        if used + term.size > terms.size:
            terms = np.resize(terms, max(2 * terms.size, used + term.size))
        terms[used:used + term.size] = term
        used += term.size
    return float(terms[:used].sum())


def _decoded_map(light: LightDesc) -> tuple[np.ndarray | CodeRows, int]:
    """The map's pixels: 8-bit codes with their sRGB values (a file's one or three channels, kept
    8-bit), or linear float RGB; and its mapping."""
    from renderer.io.images import code_values

    stored = read_light_image(light.values, light.loc, "environment image", stored=True)
    mapping = _mapping(stored, light.loc)
    if stored.dtype == np.uint8:
        return CodeRows(stored, code_values(srgb=True)), mapping
    return np.ascontiguousarray(rgb_of(stored)), mapping


def entry(light: LightDesc, tris: np.ndarray | None) -> LightEntry:
    """The row: mapping and size, the light frame, and the pixels and CDFs in the pools."""
    v = light.values
    R = np.asarray(light.light_to_world, dtype=np.float64)[:3, :3]
    E = v["illuminance"]
    e = LightEntry(L=scaled_colour(v, "L", E / np.pi if E > 0 else 1.0),
                   ints={"mapping": MAP_CONSTANT, "width": 1, "height": 1, "channels": 0, "lut": 0},
                   to_world=R, to_light=np.linalg.inv(R), escapes=True)
    if v["filename"] is None and v["portal"] is None:
        return e
    if v["filename"] is None:       # L through a portal: pbrt-v4 makes a 1x1 map of it
        rgb, mapping = np.asarray(v["L"], np.float32).reshape(1, 1, 3), MAP_EQUAL_AREA
    else:
        rgb, mapping = _decoded_map(light)
    k = pbrt_illuminance(rgb, mapping) if E > 0 else 1.0
    factor = (E / k if k > 0 else 0.0) if E > 0 else 1.0
    e.L = np.full(3, v["scale"] * factor)
    if v["portal"] is not None:
        rgb = rgb[:] if isinstance(rgb, CodeRows) else rgb      # the portal rectifies float pixels
        return _portal_entry(e, rgb, mapping, np.asarray(v["portal"]).reshape(4, 3), light.loc)
    h, w = rgb.shape[:2]
    lut = 0 if not isinstance(rgb, CodeRows) else h * (w + 1) + h + 1
    e.f_data = np.empty(h * (w + 1) + h + 1 + (256 if lut else 0), np.float32)   # CDFs [, code values]
    _, marg, _ = distribution_2d(*distribution_function(rgb, mapping), out=e.f_data[:h * (w + 1)].reshape(h, w + 1))
    e.f_data[h * (w + 1):h * (w + 1) + h + 1] = marg
    if isinstance(rgb, CodeRows):
        e.f_data[lut:] = rgb.values
        e.c_data = rgb.codes.reshape(-1)
    else:
        e.v_data = rgb.reshape(-1, 3)
    e.ints = {"mapping": mapping, "width": w, "height": h,
              "channels": rgb.codes.shape[2] if isinstance(rgb, CodeRows) else 0, "lut": lut}
    return e


def _portal_entry(e: LightEntry, rgb: np.ndarray, mapping: int, corners: np.ndarray,
                  loc: Location | None) -> LightEntry:
    """The portal light's row: the rectified image and two opposite corners in the vector pool,
    the portal's frame as the light frame."""
    if mapping != MAP_EQUAL_AREA:
        raise SceneError('LightSource "infinite": a "portal" needs a square equal-area map (as pbrt-v4)', loc)
    f = portal.frame(corners, loc)
    n = rgb.shape[0]
    rect = portal.rectified(rgb, e.to_light, f)
    e.ints = {"mapping": MAP_PORTAL, "width": n, "height": n, "channels": 0, "lut": 0}
    e.to_world, e.to_light = f.T, f
    e.v_data = np.concatenate([rect.reshape(-1, 3), corners[[0, 2]]]).astype(np.float32)
    return e


# ---- device ---------------------------------------------------------------------------------------

@wp.func
def _uv(mapping: int, w_light: wp.vec3) -> wp.vec2:
    if mapping == MAP_EQUAL_AREA:
        return equal_area_sphere_to_square(w_light)
    theta = wp.acos(wp.clamp(w_light[2], -1.0, 1.0))
    phi = wp.atan2(w_light[1], w_light[0])
    if phi < 0.0:
        phi = phi + 2.0 * PI
    return wp.vec2(phi / (2.0 * PI), theta / PI)


@wp.func
def _jacobian(mapping: int, w_light: wp.vec3) -> float:
    """Solid angle per unit of (u, v): 4π for the equal-area map, 2π² sin θ for lat-long."""
    if mapping == MAP_EQUAL_AREA:
        return 4.0 * PI
    return 2.0 * PI * PI * wp.sqrt(wp.max(0.0, 1.0 - w_light[2] * w_light[2]))


@wp.func
def _pixel(lights: Lights, i: int, w_light: wp.vec3) -> wp.vec2i:
    """The image pixel (x, y) that direction w_light (in the light's frame) falls in."""
    uv = _uv(lights.k[i, K.mapping], w_light)
    wdt = lights.k[i, K.width]
    hgt = lights.k[i, K.height]
    return wp.vec2i(wp.clamp(int(uv[0] * float(wdt)), 0, wdt - 1), wp.clamp(int(uv[1] * float(hgt)), 0, hgt - 1))


@wp.func
def radiance(lights: Lights, i: int, d: wp.vec3) -> wp.vec3:
    """Radiance arriving along -d (d points away from the scene)."""
    if lights.k[i, K.mapping] == MAP_CONSTANT:
        return lights.L[i]
    xy = _pixel(lights, i, wp.normalize(lights.to_light[i] * d))
    at = xy[1] * lights.k[i, K.width] + xy[0]
    channels = lights.k[i, K.channels]
    if channels == 0:
        return wp.cw_mul(lights.L[i], lights.v_pool[lights.v_start[i] + at])
    lut = lights.f_start[i] + lights.k[i, K.lut]        # an 8-bit map: its codes' values
    c = lights.c_start[i] + at * channels
    if channels == 1:
        return lights.L[i] * lights.f_pool[lut + int(lights.c_pool[c])]
    return wp.cw_mul(lights.L[i], wp.vec3(lights.f_pool[lut + int(lights.c_pool[c])],
                                          lights.f_pool[lut + int(lights.c_pool[c + 1])],
                                          lights.f_pool[lut + int(lights.c_pool[c + 2])]))


@wp.func
def pdf(lights: Lights, i: int, d: wp.vec3) -> float:
    """Solid-angle density of sampling direction d (selection excluded)."""
    mapping = lights.k[i, K.mapping]
    if mapping == MAP_CONSTANT:
        return 1.0 / (4.0 * PI)
    w = wp.normalize(lights.to_light[i] * d)
    jac = _jacobian(mapping, w)
    if jac <= 0.0:
        return 0.0
    xy = _pixel(lights, i, w)
    x = xy[0]
    y = xy[1]
    wdt = lights.k[i, K.width]
    hgt = lights.k[i, K.height]
    cond = lights.f_start[i] + y * (wdt + 1)
    marg = lights.f_start[i] + hgt * (wdt + 1)
    f = (lights.f_pool[cond + x + 1] - lights.f_pool[cond + x]) * float(wdt)
    fy = (lights.f_pool[marg + y + 1] - lights.f_pool[marg + y]) * float(hgt)
    return f * fy / jac


@wp.func
def escaped(lights: Lights, i: int, p: wp.vec3, d: wp.vec3) -> LightEval:
    if lights.k[i, K.mapping] == MAP_PORTAL:
        return portal.escaped(lights, i, lights.k[i, K.width], p, d)
    ev = LightEval()
    ev.L = radiance(lights, i, d)
    ev.pdf = pdf(lights, i, d)
    return ev


@wp.func
def sample(lights: Lights, i: int, p: wp.vec3, u: wp.vec2) -> LightSample:
    s = LightSample()
    s.delta = False
    s.dist = 1.0e30
    mapping = lights.k[i, K.mapping]
    if mapping == MAP_PORTAL:
        return portal.sample(lights, i, lights.k[i, K.width], p, u)
    if mapping == MAP_CONSTANT:
        # the constant sky has no preferred direction
        s.wi = uniform_sphere(u)
        s.L = lights.L[i]
        s.pdf = 1.0 / (4.0 * PI)
        return s
    wdt = lights.k[i, K.width]
    hgt = lights.k[i, K.height]
    vy = sample_cdf(lights.f_pool, lights.f_start[i] + hgt * (wdt + 1), hgt, u[1])
    y = int(vy[1])
    ux = sample_cdf(lights.f_pool, lights.f_start[i] + y * (wdt + 1), wdt, u[0])
    uv = wp.vec2(ux[0], vy[0])
    w = wp.vec3(0.0)
    if mapping == MAP_EQUAL_AREA:
        w = equal_area_square_to_sphere(uv)
    else:
        theta = uv[1] * PI
        phi = uv[0] * 2.0 * PI
        w = wp.vec3(wp.sin(theta) * wp.cos(phi), wp.sin(theta) * wp.sin(phi), wp.cos(theta))
    s.wi = wp.normalize(lights.to_world[i] * w)
    s.L = radiance(lights, i, s.wi)
    s.pdf = pdf(lights, i, s.wi)
    return s
