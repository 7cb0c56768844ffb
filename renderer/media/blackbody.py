"""The emission of a grid medium's ``temperature``: pbrt-v4's BlackbodySpectrum (Planck's law
normalised to 1 at its peak wavelength, not to luminance 1 as a light's ``blackbody`` is) in this
renderer's RGB, as pbrt-v4's film sees it (the spectrum integrated against the CIE 1931 matching
functions, then XYZ to linear sRGB), tabulated over log temperature and built with colour-science."""
from __future__ import annotations

from functools import lru_cache

import numpy as np

#: the table's temperature range (kelvin); pbrt emits nothing at or below 100 K
T_MIN, T_MAX, SIZE = 100.0, 100_000.0, 512


@lru_cache(maxsize=1)
def blackbody_table() -> np.ndarray:
    """(SIZE, 3) float32 linear sRGB at temperatures T_MIN * (T_MAX / T_MIN) ** (i / (SIZE - 1))."""
    import colour

    lam = np.arange(360.0, 831.0) * 1e-9
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(colour.SpectralShape(360, 830, 1))
    xyz_bar = np.asarray(cmfs.values)
    temps = T_MIN * (T_MAX / T_MIN) ** (np.arange(SIZE) / (SIZE - 1))
    c, h, kb = 299792458.0, 6.62606957e-34, 1.3806488e-23
    out = np.zeros((SIZE, 3))
    for i, t in enumerate(temps):
        def planck(lm: np.ndarray) -> np.ndarray:
            return 2 * h * c * c / (lm ** 5 * (np.exp((h * c) / (lm * kb * t)) - 1))
        b = planck(lam) / planck(np.array(2.8977721e-3 / t))
        xyz = b @ xyz_bar                                         # 1 nm steps: the integral in nm
        out[i] = colour.XYZ_to_RGB(xyz, colour.RGB_COLOURSPACES["sRGB"], illuminant=None,
                                   chromatic_adaptation_transform=None)
    return np.maximum(out, 0.0).astype(np.float32)
