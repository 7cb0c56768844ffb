"""``MakeNamedMedium`` parameters -> :class:`MediumDesc`, with pbrt-v4's names, defaults and
checks, each error naming the file and line. Grids are checked against the memory budget from
their declared size before any array is made of them."""
from __future__ import annotations

from pathlib import Path
from typing import Callable

import numpy as np

from renderer.device.machine import machine_memory
from renderer.errors import Location, SceneError, UnsupportedError
from renderer.media.description import KINDS, MediumDesc
from renderer.materials.subsurface import NAMED_MEDIA as MEASURED    # pbrt-v4's measured media, shared
from renderer.scene.params import ParamSet

#: float32 copies of a grid held at the peak of an upload (host array, device volume, its build)
GRID_COPIES = 3
#: pbrt-v4's CIE_Y_integral, the luminance of its normalised illuminant spectra. Its lights and its
#: homogeneous and uniformgrid media divide an RGB ``Le`` by it (SpectrumToPhotometric), so
#: rgb (1, 1, 1) is radiance 1; its rgbgrid medium does not, so there an ``Le`` of (1, 1, 1) is
#: this much brighter. We follow pbrt-v4 (measured: tests/media/test_pbrt_media.py).
RGBGRID_LE_SCALE = 106.856895


def read_medium(kind: str, name: str, params: ParamSet, ctm: np.ndarray, loc: Location,
                warn: Callable[[Location, str], None], memory_limit: int | None = None) -> MediumDesc:
    if kind not in KINDS:
        raise SceneError(f'MakeNamedMedium "{name}": unknown medium type "{kind}" (pbrt-v4 knows '
                         f'{", ".join(KINDS)})', loc)
    m = MediumDesc(kind=kind, name=name, loc=loc, medium_to_world=np.asarray(ctm, np.float64).copy())
    limit = machine_memory() if memory_limit is None else memory_limit
    m.g = params.float("g", 0.0, min=-0.999, max=0.999)     # |g| = 1 is a delta, which HG cannot sample
    if kind != "homogeneous":
        p0, p1 = _point(params, "p0", (0.0, 0.0, 0.0)), _point(params, "p1", (1.0, 1.0, 1.0))
        m.p0, m.p1 = np.minimum(p0, p1), np.maximum(p0, p1)
        if np.any(m.p1 - m.p0 <= 0.0):
            raise SceneError(f'MakeNamedMedium "{name}": the bounds p0 {p0} .. p1 {p1} enclose no volume', loc)
    if kind == "rgbgrid":
        _read_rgb_grid(m, params, loc, limit)
        return m
    scale = params.float("scale", 1.0, min=0.0)
    sigma_a, sigma_s = _preset(params, loc, warn) if kind == "homogeneous" else (None, None)
    m.sigma_a = scale * (sigma_a if sigma_a is not None else _coefficient(params, "sigma_a"))
    m.sigma_s = scale * (sigma_s if sigma_s is not None else _coefficient(params, "sigma_s"))
    if kind == "homogeneous":
        m.Le = _emission(params) * params.float("Lescale", 1.0, min=0.0)
    elif kind == "uniformgrid":
        _read_density_grid(m, params, loc, limit)
    elif kind == "cloud":
        m.cloud = (params.float("density", 1.0, min=0.0), params.float("wispiness", 1.0, min=0.0),
                   params.float("frequency", 5.0, min=0.0))
    else:
        _read_nanovdb(m, params, loc, limit)
    return m


def _point(params: ParamSet, name: str, default: tuple[float, float, float]) -> np.ndarray:
    v = params.floats(name, ("point3", "point"))
    if v is None:
        return np.asarray(default, np.float64)
    if len(v) != 3:
        raise SceneError(f'parameter "{name}" needs 3 values, got {len(v)}', params.get(name).loc)
    return v


def _coefficient(params: ParamSet, name: str) -> np.ndarray:
    """sigma_a or sigma_s: a colour (rgb, spectrum, blackbody), 1 by default as in pbrt-v4."""
    v = params.rgb(name, 1.0)
    if np.any(v < 0.0):
        raise SceneError(f'parameter "{name}" must not be negative, got {v.tolist()}', params.get(name).loc)
    return v


def _emission(params: ParamSet) -> np.ndarray:
    """``Le`` as pbrt-v4 normalises an illuminant: an rgb value is the radiance it names, a
    blackbody has luminance 1 (renderer.scene.params.ParamSet.rgb)."""
    v = params.rgb("Le", 0.0)
    if np.any(v < 0.0):
        raise SceneError(f'parameter "Le" must not be negative, got {v.tolist()}', params.get("Le").loc)
    return v


def _preset(params: ParamSet, loc: Location, warn: Callable[[Location, str], None]
            ) -> tuple[np.ndarray | None, np.ndarray | None]:
    """A measured medium's coefficients (mm^-1, pbrt-v4's table); an unknown name warns, as pbrt's does."""
    preset = params.string("preset", "")
    if not preset:
        return None, None
    if preset not in MEASURED:
        warn(params.get("preset").loc, f'medium preset "{preset}" not found; sigma_a and sigma_s are used')
        return None, None
    s, a = MEASURED[preset]
    return np.asarray(a, np.float64), np.asarray(s, np.float64)


def _dims(params: ParamSet, name: str, loc: Location, n_grids: int, channels: int, limit: int
          ) -> tuple[int, int, int]:
    """nx, ny, nz, refused when the grids they declare would not fit in memory (before any is made)."""
    nx, ny, nz = (params.int(k, 1, min=1) for k in ("nx", "ny", "nz"))
    need = nx * ny * nz * channels * 4 * n_grids * GRID_COPIES
    if need > limit:
        raise SceneError(f'MakeNamedMedium "{name}": a {nx}x{ny}x{nz} grid needs about {need / 2**30:.1f} GiB, '
                         f'more than the {limit / 2**30:.1f} GiB limit', loc)
    return nx, ny, nz


def _grid(params: ParamSet, key: str, dims: tuple[int, int, int], what: str, channels: int = 1
          ) -> np.ndarray | None:
    """A grid parameter as a (nz, ny, nx[, 3]) float32 array, its length checked against the
    dimensions and its values against NaN and negatives."""
    p = params.params.get(key)
    if p is None:
        return None
    values = params.floats(key, ("rgb",) if channels == 3 else ("float",))
    nx, ny, nz = dims
    if len(values) != nx * ny * nz * channels:
        per = " rgb triples" if channels == 3 else " values"
        raise SceneError(f'{what}: "{key}" has {len(values) // channels}{per}; expected nx*ny*nz = '
                         f'{nx}*{ny}*{nz} = {nx * ny * nz}', p.loc)
    if np.any(values < 0.0):
        i = int(np.argmax(values < 0.0))
        raise SceneError(f'{what}: "{key}" must not be negative (value {i // channels} is {values[i]})', p.loc)
    shape = (nz, ny, nx, 3) if channels == 3 else (nz, ny, nx)
    return values.astype(np.float32).reshape(shape)


def _read_density_grid(m: MediumDesc, params: ParamSet, loc: Location, limit: int) -> None:
    what = f'uniformgrid medium "{m.name}"'
    if "density" not in params:
        raise SceneError(f'{what}: no "density" values', loc)
    dims = _dims(params, m.name, loc, 1 + ("Lescale" in params) + ("temperature" in params), 1, limit)
    m.density = _grid(params, "density", dims, what)
    m.temperature = _grid(params, "temperature", dims, what)
    if m.temperature is not None and "Le" in params:
        raise SceneError(f'{what}: both "Le" and "temperature" are given (pbrt-v4 takes one)', params.get("Le").loc)
    m.temperature_offset = params.float("temperatureoffset", params.float("temperaturecutoff", 0.0))
    m.temperature_scale = params.float("temperaturescale", 1.0, min=0.0)
    le = _emission(params)
    scale = params.params.get("Lescale")
    if scale is not None and len(scale.values) == 1 and np.prod(dims) != 1:
        raise SceneError(f'{what}: "Lescale" must give nx*ny*nz = {int(np.prod(dims))} values (a grid), '
                         f'as pbrt-v4 reads it', scale.loc)
    m.le_scale_grid = _grid(params, "Lescale", dims, what)
    m.Le = le


def _read_rgb_grid(m: MediumDesc, params: ParamSet, loc: Location, limit: int) -> None:
    what = f'rgbgrid medium "{m.name}"'
    given = [k for k in ("sigma_a", "sigma_s", "Le") if k in params]
    if "sigma_a" not in given and "sigma_s" not in given:
        raise SceneError(f'{what}: needs "sigma_a" and/or "sigma_s" grids', loc)
    if "Le" in given and "sigma_a" not in given:
        raise SceneError(f'{what}: "Le" needs "sigma_a" (emission is sigma_a * Le)', params.get("Le").loc)
    dims = _dims(params, m.name, loc, len(given), 3, limit)
    scale = params.float("scale", 1.0, min=0.0)
    sa, ss, le = (_grid(params, k, dims, what, 3) for k in ("sigma_a", "sigma_s", "Le"))
    m.rgb_sigma_a = None if sa is None else sa * np.float32(scale)
    m.rgb_sigma_s = None if ss is None else ss * np.float32(scale)
    m.rgb_Le = None if le is None else le * np.float32(params.float("Lescale", 1.0, min=0.0) * RGBGRID_LE_SCALE)
    m.sigma_a = m.sigma_s = np.full(3, scale)      # the factor of a grid that is not given (1 x scale)
    m.Le = np.zeros(3)


def _read_nanovdb(m: MediumDesc, params: ParamSet, loc: Location, limit: int) -> None:
    what = f'nanovdb medium "{m.name}"'
    fname = params.string("filename", "")
    if not fname:
        raise SceneError(f'{what}: "filename" is required', loc)
    path = Path(loc.file).parent / fname if loc else Path(fname)
    if not path.is_file():
        raise SceneError(f'{what}: no file {path}', params.get("filename").loc)
    if path.stat().st_size * GRID_COPIES > limit:
        raise SceneError(f'{what}: {path} ({path.stat().st_size / 2**30:.1f} GiB) does not fit in the '
                         f'{limit / 2**30:.1f} GiB limit', params.get("filename").loc)
    m.filename = path
    m.grid_name = params.string("gridname", "density")
