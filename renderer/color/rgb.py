"""Colour facts from colour-science: blackbody emission and the sRGB encoding. RGB is linear sRGB."""
from __future__ import annotations

from functools import lru_cache

import numpy as np


@lru_cache(maxsize=64)
def blackbody_rgb(temperature_k: float) -> np.ndarray:
    """Linear sRGB of a blackbody emitter, normalised to luminance Y = 1 as pbrt-v4 normalises lights.
    Below about 1900 K the colour lies outside the sRGB gamut (blue < 0); that component is clipped
    to 0, since an RGB renderer cannot emit negative light."""
    import colour

    if not 0 < temperature_k < 1e6:
        raise ValueError(f"blackbody temperature must be between 0 and 1e6 K, got {temperature_k} K")
    shape = colour.SpectralShape(360, 830, 1)
    sd = colour.sd_blackbody(float(temperature_k), shape)
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(shape)
    xyz = colour.sd_to_XYZ(sd, cmfs=cmfs, method="Integration")
    xyz = xyz / xyz[1]
    rgb = colour.XYZ_to_RGB(xyz, colour.RGB_COLOURSPACES["sRGB"], illuminant=None,
                            chromatic_adaptation_transform=None)
    return np.maximum(np.asarray(rgb, dtype=np.float64), 0.0)


def linear_to_srgb(x: np.ndarray) -> np.ndarray:
    """The sRGB transfer function (IEC 61966-2-1) applied to linear values clipped to [0, 1]."""
    import colour

    return np.asarray(colour.cctf_encoding(np.clip(x, 0.0, 1.0), function="sRGB"), dtype=np.float32)


def srgb_to_linear(x: np.ndarray) -> np.ndarray:
    """Inverse of :func:`linear_to_srgb` for 8-bit image textures with sRGB encoding."""
    import colour

    return np.asarray(colour.cctf_decoding(np.asarray(x, dtype=np.float64), function="sRGB"), dtype=np.float32)


def luminance(rgb: np.ndarray) -> np.ndarray:
    """Relative luminance Y of linear sRGB (the Y row of the sRGB-to-XYZ matrix)."""
    return rgb[..., 0] * 0.2126 + rgb[..., 1] * 0.7152 + rgb[..., 2] * 0.0722
