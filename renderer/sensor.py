"""pbrt-v4's default ``cie1931`` pixel sensor on an RGB renderer: what the film does to radiance.

pbrt's sensor records XYZ times the imaging ratio (exposure time x ISO / 100), clamps each
sample so its largest component is at most ``maxcomponentvalue``, and writes
RGB = RGB_from_XYZ · W · sensor, where W white-balances (von Kries in Bradford's LMS) from the
CIE daylight illuminant of the given temperature (a blackbody below 4000 K, as pbrt) to the
output white, D65. Here radiance is linear sRGB, so the clamp scales L by
min(1, limit / max(XYZ(L) x ratio)) per sample on the device, and the ratio and W are applied to
the finished mean on the host (both are linear, so the order does not matter). Colour science
(illuminant spectra, CMFs, the Bradford transform) comes from colour-science."""
from __future__ import annotations

from functools import lru_cache

import numpy as np
import warp as wp

from renderer.scene.description import CameraDesc, FilmDesc
from renderer.vecmath import max3


@wp.struct
class Sensor:
    xyz_from_rgb: wp.mat33             # linear sRGB to XYZ; set (and read) only when limit is finite
    limit: float                       # maxcomponentvalue / imaging ratio, in XYZ of radiance; inf: none


@wp.func
def film_value(s: Sensor, L: wp.vec3, weight: float) -> wp.vec3d:
    """What one sample adds to its pixel: clamped as pbrt's film clamps, times the filter weight."""
    if s.limit < 3.0e38:
        m = max3(s.xyz_from_rgb * L)
        if m > s.limit:
            L = L * (s.limit / m)
    L = L * weight
    return wp.vec3d(wp.float64(L[0]), wp.float64(L[1]), wp.float64(L[2]))


def imaging_ratio(film: FilmDesc, camera: CameraDesc) -> float:
    return camera.exposure_time * film.iso / 100.0


def _srgb():
    import colour

    return colour.RGB_COLOURSPACES["sRGB"]


def build_sensor(film: FilmDesc, camera: CameraDesc) -> Sensor:
    s = Sensor()
    ratio = imaging_ratio(film, camera)
    limit = film.max_component_value / ratio if ratio > 0.0 else float("inf")
    s.limit = float(min(limit, 3.4e38))
    if s.limit < 3.0e38:     # film_value reads the matrix only under a finite clamp; without one
        # colour-science is not imported at all (0.3 CPU-s of every render)
        s.xyz_from_rgb = wp.mat33(*np.asarray(_srgb().matrix_RGB_to_XYZ, dtype=np.float32).ravel())
    return s


@lru_cache(maxsize=32)
def white_balance(temperature_k: float) -> np.ndarray:
    """pbrt's white-balance matrix in linear sRGB: Bradford von Kries from the illuminant's white
    (CIE D series at the temperature, corrected by 1.4388/1.4380 as pbrt; a blackbody below
    4000 K) to D65."""
    import colour

    cct = temperature_k * 1.4388 / 1.4380
    shape = colour.SpectralShape(360, 830, 1)
    if cct < 4000.0:
        sd = colour.sd_blackbody(cct, shape)
    else:
        sd = colour.sd_CIE_illuminant_D_series(colour.temperature.CCT_to_xy_CIE_D(cct)).copy().align(shape)
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(shape)
    src = colour.sd_to_XYZ(sd, cmfs=cmfs, method="Integration")
    d65 = colour.sd_to_XYZ(colour.SDS_ILLUMINANTS["D65"].copy().align(shape), cmfs=cmfs, method="Integration")
    w = colour.adaptation.matrix_chromatic_adaptation_VonKries(src / src[1], d65 / d65[1], transform="Bradford")
    cs = _srgb()
    return np.asarray(cs.matrix_XYZ_to_RGB @ w @ cs.matrix_RGB_to_XYZ, dtype=np.float64)


def sensor_output(image: np.ndarray, film: FilmDesc, camera: CameraDesc) -> np.ndarray:
    """The film's mean radiance as pbrt writes it: times the imaging ratio, white-balanced. With
    pbrt's defaults (ratio 1, no white balance) the image is returned unchanged."""
    ratio = imaging_ratio(film, camera)
    if film.white_balance:
        image = image @ (ratio * white_balance(float(film.white_balance))).T.astype(np.float32)
    elif ratio != 1.0:
        image = image * np.float32(ratio)
    return image.astype(np.float32, copy=False)
