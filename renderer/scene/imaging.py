"""``Camera``, ``Film`` and ``PixelFilter`` parameters read as pbrt-v4 reads them (its cameras.cpp,
film.cpp and filters.cpp): names, defaults and checks, into plain description values. pbrt-v3's
film parameters that pbrt-v4's ``--upgrade`` rewrites (``scale`` -> ``iso`` = 100 x scale,
``maxsampleluminance`` -> ``maxcomponentvalue``) are accepted with a warning."""
from __future__ import annotations

import math
from typing import Callable

from renderer.errors import Location, RenderError, SceneError
import numpy as np

from renderer.scene.description import CameraDesc, FilmDesc, FilterDesc
from renderer.scene.params import ParamSet
from renderer.settings import check_resolution

#: Bounds on the imaging ratio's factors, far beyond any camera: with both at their limit the
#: ratio is 1e13, so a sane radiance stays far inside float32.
MAX_ISO = 1e9
MAX_EXPOSURE_TIME = 1e6
#: pbrt-v4's filters and their default radius (both axes).
FILTER_RADIUS = {"box": 0.5, "gaussian": 1.5, "mitchell": 2.0, "sinc": 4.0, "triangle": 2.0}


def read_camera(name: str, p: ParamSet, world_from_camera: np.ndarray, loc: Location) -> CameraDesc:
    """The perspective, orthographic or spherical camera; the shutter interval is the exposure time
    of pbrt's imaging ratio."""
    fov = p.float("fov", 90.0) if name == "perspective" else 90.0
    if not 0.0 < fov < 180.0:
        raise SceneError(f'Camera: "fov" must be between 0 and 180 degrees, got {fov}', p.get("fov").loc)
    frame = p.float("frameaspectratio")
    if frame is not None and not frame > 0.0:
        raise SceneError(f'Camera: "frameaspectratio" must be > 0, got {frame}', loc)
    window = p.floats("screenwindow")
    if window is not None and (len(window) != 4 or window[0] >= window[1] or window[2] >= window[3]):
        raise SceneError('Camera: "screenwindow" needs 4 values x0 < x1, y0 < y1', p.params["screenwindow"].loc)
    lens_radius = p.float("lensradius", 0.0, min=0.0)
    focal_distance = p.float("focaldistance", 1e6)
    if focal_distance <= 0.0:
        raise SceneError(f'Camera: "focaldistance" must be > 0, got {focal_distance}', loc)
    exposure = abs(p.float("shutterclose", 1.0) - p.float("shutteropen", 0.0))   # pbrt swaps them if reversed
    if exposure <= 0.0:
        raise SceneError("Camera: the shutter times imply that the shutter does not open (a black image)", loc)
    if exposure > MAX_EXPOSURE_TIME:
        raise SceneError(f"Camera: an exposure (shutterclose - shutteropen) of {exposure:g} s is beyond "
                         f"{MAX_EXPOSURE_TIME:g} s: the image would overflow", loc)
    projection = "spherical equirectangular" if name == "environment" else name    # pbrt-v3's name for it
    if name == "spherical":
        mapping = p.string("mapping", "equalarea")
        if mapping not in ("equalarea", "equirectangular"):
            raise SceneError(f'Camera "spherical": mapping must be "equalarea" or "equirectangular", got '
                             f'"{mapping}"', p.params["mapping"].loc)
        projection = f"spherical {mapping}"
    return CameraDesc(world_from_camera, fov, lens_radius, focal_distance, exposure, projection, frame,
                      None if window is None else tuple(float(v) for v in window))


def read_film(p: ParamSet, loc: Location, warn: Callable[[Location, str], None]) -> FilmDesc:
    film = FilmDesc(p.int("xresolution", 1280, min=1), p.int("yresolution", 720, min=1),
                    p.string("filename", "pbrt.exr"))
    try:
        check_resolution(film.width, film.height)
    except RenderError as e:
        raise SceneError(f"Film: {e}", loc) from None
    film.iso = p.float("iso", 100.0, min=0.0, max=MAX_ISO)
    legacy = p.get("scale")
    if legacy is not None:
        film.iso = 100.0 * p.float("scale", min=0.0, max=MAX_ISO / 100.0)
        warn(legacy.loc, 'Film: "scale" is pbrt-v3\'s; read as pbrt-v4\'s --upgrade does, "iso" = 100 x scale')
    film.max_component_value = p.float("maxcomponentvalue", float("inf"), min=0.0)
    legacy = p.get("maxsampleluminance")
    if legacy is not None:
        film.max_component_value = p.float("maxsampleluminance", min=0.0)
        warn(legacy.loc, 'Film: "maxsampleluminance" is pbrt-v3\'s; read as "maxcomponentvalue"')
    film.white_balance = p.float("whitebalance", 0.0, min=0.0)
    sensor = p.string("sensor", "cie1931")
    if sensor != "cie1931":
        warn(p.params["sensor"].loc, f'Film: sensor "{sensor}" is not implemented; the cie1931 sensor is used '
                                     '(with pbrt\'s white balance for a camera sensor, 6500 K unless given)')
        film.white_balance = film.white_balance or 6500.0
    if film.white_balance and not 1000.0 <= film.white_balance <= 100_000.0:
        raise SceneError(f'Film: "whitebalance" must be 0 (none) or a temperature between 1000 and 100000 K, '
                         f"got {film.white_balance}", p.params["whitebalance"].loc)
    film.crop_window = _bounds(p, "cropwindow", "float", loc)
    bounds = _bounds(p, "pixelbounds", "integer", loc)
    film.pixel_bounds = None if bounds is None else tuple(int(v) for v in bounds)
    if film.crop_window is not None and film.pixel_bounds is not None:
        warn(loc, "Film: both pixel bounds and a crop window are given; the crop window is used (as pbrt-v4)")
        film.pixel_bounds = None
    try:
        film_region(film, film.width, film.height)
    except RenderError as e:
        raise SceneError(f"Film: {e}", loc) from None
    p.float("diagonal", 35.0, min=0.0)          # only the realistic camera reads it
    p.bool("savefp16")                          # output precision: EXRs are always written as float32
    return film


def film_region(film: FilmDesc, width: int, height: int) -> tuple[int, int, int, int]:
    """The pixels rendered, (x0, x1, y0, y1) with the ends exclusive, at resolution width x height:
    pbrt-v4's rule, a crop window's corners at ceil(resolution x fraction), pixel bounds clipped to
    the image. Empty is an error."""
    if film.crop_window is not None:
        x0, x1, y0, y1 = film.crop_window
        b = (math.ceil(width * x0), math.ceil(width * x1), math.ceil(height * y0), math.ceil(height * y1))
    elif film.pixel_bounds is not None:
        x0, x1, y0, y1 = film.pixel_bounds
        b = (max(x0, 0), min(x1, width), max(y0, 0), min(y1, height))
    else:
        return 0, width, 0, height
    if b[1] <= b[0] or b[3] <= b[2]:
        raise RenderError(f"the crop window or pixel bounds select no pixels of the {width}x{height} image "
                          f"(x {b[0]}..{b[1]}, y {b[2]}..{b[3]})")
    return b


def _bounds(p: ParamSet, name: str, kind: str, loc: Location) -> tuple | None:
    values = p.floats(name, (kind,))
    if values is None:
        return None
    if len(values) != 4:
        raise SceneError(f'Film: "{name}" needs 4 values (x0 x1 y0 y1), got {len(values)}', p.params[name].loc)
    if kind == "float":         # pbrt sorts each pair and clamps to [0, 1]
        x0, x1, y0, y1 = (min(max(float(v), 0.0), 1.0) for v in values)
        return min(x0, x1), max(x0, x1), min(y0, y1), max(y0, y1)
    return tuple(float(v) for v in values)


def read_filter(kind: str, p: ParamSet, loc: Location, warn: Callable[[Location, str], None]) -> FilterDesc:
    """pbrt-v4's five filters with its parameter names and defaults."""
    r = FILTER_RADIUS[kind]
    for v3, v4 in (("xwidth", "xradius"), ("ywidth", "yradius")):      # pbrt-v3's names, as --upgrade renames
        if v3 in p and v4 not in p:
            p.params[v4] = p.params.pop(v3)
            warn(p.params[v4].loc, f'PixelFilter: "{v3}" is pbrt-v3\'s; read as "{v4}"')
    radius = (p.float("xradius", r), p.float("yradius", r))
    if not all(0.0 < v <= 16.0 for v in radius):
        raise SceneError(f'PixelFilter "{kind}": radii must be in (0, 16], got {radius}', loc)
    f = FilterDesc(kind, radius)
    if kind == "gaussian":
        alpha = p.float("alpha") if "sigma" not in p else None              # pbrt-v3's falloff
        if alpha is not None:
            if not alpha > 0.0:
                raise SceneError(f'PixelFilter "gaussian": "alpha" must be > 0, got {alpha}', loc)
            warn(p.params["alpha"].loc, 'PixelFilter: "alpha" is pbrt-v3\'s; read as "sigma" = 1 / sqrt(2 alpha)')
        f.sigma = p.float("sigma", 0.5) if alpha is None else 1.0 / math.sqrt(2.0 * alpha)
        if f.sigma <= 0.0:
            raise SceneError(f'PixelFilter "gaussian": "sigma" must be > 0, got {f.sigma}', loc)
    elif kind == "mitchell":
        f.b, f.c = p.float("B", 1.0 / 3.0), p.float("C", 1.0 / 3.0)
    elif kind == "sinc":
        f.tau = p.float("tau", 3.0)
        if f.tau <= 0.0:
            raise SceneError(f'PixelFilter "sinc": "tau" must be > 0, got {f.tau}', loc)
    return f
