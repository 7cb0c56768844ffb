"""pbrt-v4's spectral parameter values — named spectra (``"spectrum eta" "metal-Au-eta"``,
``"glass-BK7"``), inline samples (``"spectrum k" [300 1.2 800 3.1]``) and ``.spd`` files of
(wavelength, value) pairs — as the RGB or single value this renderer carries.

A spectrum becomes RGB by its projection onto the CIE 1931 observer under D65, normalised so a
constant spectrum c gives (c, c, c) (sRGB's white is D65), then linear sRGB; a float parameter
(a dielectric's eta) takes the same projection's Y, the luminance-weighted mean. This is how RGB
renderers (Mitsuba's ``*_rgb`` variants, pbrt-v3) use spectral data. A colour parameter read
from a spectrum is a :class:`SpectralRGB` and a float one a :class:`SpectralFloat`, which keep
the samples, so a material can evaluate its optics per wavelength: ``conductor`` bakes its
spectral Fresnel term into a table, ``dielectric`` refracts with eta(λ) (dispersion; see
docs/pbrt-v4.md for the measured agreement with pbrt-v4). The named tables
are pbrt-v4's own (``data/pbrt_spectra.json``, extracted by ``data/make_pbrt_spectra.py``)."""
from __future__ import annotations

import json
import math
from functools import lru_cache
from pathlib import Path

import numpy as np

from renderer.errors import Location, SceneError

DATA = Path(__file__).parent / "data" / "pbrt_spectra.json"
#: The most (wavelength, value) pairs an inline or file spectrum may hold.
MAX_SAMPLES = 100_000
_GRID = np.arange(360.0, 831.0)          # nm, where the observer is tabulated


@lru_cache(maxsize=1)
def named() -> dict[str, np.ndarray]:
    """pbrt-v4's named spectra: name -> (N, 2) array of (wavelength nm, value)."""
    return {k: np.asarray(v, dtype=np.float64) for k, v in json.loads(DATA.read_text())["spectra"].items()}


@lru_cache(maxsize=1)
def _observer() -> tuple[np.ndarray, np.ndarray]:
    """(CIE 1931 x̄ȳz̄ times D65 on the 1 nm grid, normalised to Y = 1 for a unit spectrum; the XYZ
    to linear sRGB matrix)."""
    import colour

    shape = colour.SpectralShape(360, 830, 1)
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(shape).values
    d65 = colour.SDS_ILLUMINANTS["D65"].copy().align(shape).values
    w = cmfs * d65[:, None]
    return w / w[:, 1].sum(), np.asarray(colour.RGB_COLOURSPACES["sRGB"].matrix_XYZ_to_RGB)


def _pairs(values: list, where: str, loc: Location | None) -> np.ndarray:
    if len(values) < 2 or len(values) % 2 or len(values) > 2 * MAX_SAMPLES:
        raise SceneError(f"{where}: a sampled spectrum needs (wavelength, value) pairs, got {len(values)} numbers",
                         loc)
    s = np.asarray(values, dtype=np.float64).reshape(-1, 2)
    if not np.all(np.isfinite(s)) or np.any(np.diff(s[:, 0]) <= 0) or s[0, 0] <= 0:
        raise SceneError(f"{where}: spectrum wavelengths must be positive and increasing, values finite", loc)
    return s


def _read_spd(path: Path, where: str, loc: Location | None) -> np.ndarray:
    """An .spd file: whitespace-separated (wavelength, value) pairs; '#' starts a comment."""
    if not path.is_file():
        raise SceneError(f'{where}: "{path.name}" is neither one of pbrt-v4\'s named spectra '
                         f'({", ".join(sorted(named()))}) nor a spectrum file', loc)
    if path.stat().st_size > 64 * MAX_SAMPLES:
        raise SceneError(f"{where}: spectrum file {path} is larger than {64 * MAX_SAMPLES} bytes", loc)
    words = " ".join(line.split("#")[0] for line in path.read_text(errors="replace").splitlines()).split()
    try:
        numbers = [float(w) for w in words]
    except ValueError:
        raise SceneError(f"{where}: spectrum file {path} holds something other than numbers", loc) from None
    return _pairs(numbers, f"{where} ({path})", loc)


def spectrum(values: list, base_dir: Path, where: str, loc: Location | None) -> np.ndarray:
    """The (N, 2) samples a spectrum parameter's values mean: one name or file, or inline pairs."""
    if len(values) == 1 and isinstance(values[0], str):
        table = named().get(values[0])
        return table if table is not None else _read_spd(base_dir / values[0], where, loc)
    if any(isinstance(v, str) for v in values):
        raise SceneError(f"{where}: a spectrum is one name or file, or numbers", loc)
    return _pairs(list(values), where, loc)


def _xyz(samples: np.ndarray) -> np.ndarray:
    w, _ = _observer()
    v = np.interp(_GRID, samples[:, 0], samples[:, 1])     # held constant beyond the measured range
    return v @ w


class _Sampled:
    """The spectrum a parameter's value was read from, kept beside the value itself."""

    samples: np.ndarray
    _plain: type          # the builtin type of the value (what pickling rebuilds it from)

    def __reduce__(self):
        return type(self), (self._plain(self), self.samples)

    def on_grid(self, wavelengths_nm: np.ndarray) -> np.ndarray:
        """The spectrum at these wavelengths (held constant beyond its measured range, as the projection)."""
        return np.interp(np.asarray(wavelengths_nm, np.float64), self.samples[:, 0], self.samples[:, 1])


class SpectralRGB(_Sampled, tuple):
    """A colour parameter's RGB projection that keeps the spectrum it came from, for a material
    that evaluates its optics per wavelength (a conductor's Fresnel term: :mod:`renderer.materials.conductor`).
    Everything else sees the plain RGB tuple."""

    def __new__(cls, rgb, samples: np.ndarray) -> "SpectralRGB":
        self = super().__new__(cls, rgb)
        self.samples = np.asarray(samples, np.float64)
        return self

    _plain = tuple


class SpectralFloat(_Sampled, float):
    """A float parameter's luminance-weighted mean that keeps the spectrum it came from (a
    dielectric's dispersive eta: :mod:`renderer.optics.dispersion`). Everything else sees the float."""

    def __new__(cls, value: float, samples: np.ndarray) -> "SpectralFloat":
        self = super().__new__(cls, value)
        self.samples = np.asarray(samples, np.float64)
        return self

    _plain = float


def spectrum_rgb(samples: np.ndarray) -> np.ndarray:
    """Linear sRGB of a spectrum (a constant c maps to (c, c, c)); a component the projection
    makes negative (a spectrum outside the sRGB gamut) is clipped to 0."""
    _, m = _observer()
    return np.maximum(m @ _xyz(samples), 0.0)


def spectrum_mean(samples: np.ndarray) -> float:
    """The luminance-weighted mean of a spectrum: one value for a float parameter."""
    y = float(_xyz(samples)[1])
    if not math.isfinite(y):
        raise ValueError("spectrum has no finite mean")
    return y
