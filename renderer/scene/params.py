"""pbrt-style typed parameter lists (``"float fov" [45]``) and typed look-ups with located errors."""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from renderer.errors import Location, SceneError

#: Parameter types of the pbrt-v4 format that this renderer understands.
PARAM_TYPES = {
    "integer", "float", "point2", "vector2", "point3", "vector3", "normal3", "normal",
    "point", "vector", "rgb", "spectrum", "blackbody", "bool", "string", "texture",
}


@dataclass
class Param:
    """One ``"type name" [values]`` entry as written in the file."""

    type: str
    name: str
    values: list[Any]
    loc: Location
    used: bool = False


@dataclass
class ParamSet:
    """The parameters of one directive. Look-ups mark entries used so leftovers can be warned about."""

    params: dict[str, Param] = field(default_factory=dict)
    loc: Location | None = None
    shadowed: list[Param] = field(default_factory=list)

    def add(self, p: Param) -> None:
        """A name given twice: the last one wins, as in pbrt-v4 (its dictionary looks names up
        from the end and does not report the shadowed one); the earlier one is kept for a warning."""
        old = self.params.pop(p.name, None)
        if old is not None:
            self.shadowed.append(old)
        self.params[p.name] = p

    def __contains__(self, name: str) -> bool:
        return name in self.params

    def get(self, name: str) -> Param | None:
        p = self.params.get(name)
        if p is not None:
            p.used = True
        return p

    def _one(self, name: str, types: tuple[str, ...], n: int) -> Param | None:
        p = self.get(name)
        if p is None:
            return None
        if p.type not in types:
            raise SceneError(f'parameter "{name}" must be of type {" or ".join(types)}, not {p.type}', p.loc)
        if len(p.values) != n:
            raise SceneError(f'parameter "{name}" needs {n} value(s), got {len(p.values)}', p.loc)
        return p

    def float(self, name: str, default: float | None = None, *, min: float | None = None,
              max: float | None = None) -> float | None:
        """A number; a ``spectrum`` (a dielectric's ``"spectrum eta" "glass-BK7"``) gives its
        luminance-weighted mean (:mod:`renderer.color.named_spectra`)."""
        q = self.params.get(name)
        if q is not None and q.type == "spectrum":
            from renderer.color.named_spectra import spectrum_mean

            q.used = True
            v = float(q.values[0]) if len(q.values) == 1 and not isinstance(q.values[0], str) \
                else spectrum_mean(self._spectrum(q))
            return self._bounded(name, v, min, max, q.loc)
        p = self._one(name, ("float", "integer"), 1)
        if p is None:
            return default
        return self._bounded(name, float(p.values[0]), min, max, p.loc)

    def _spectrum(self, p: Param) -> np.ndarray:
        from renderer.color.named_spectra import spectrum

        base = Path(p.loc.file).parent if p.loc else Path(".")
        return spectrum(p.values, base, f'parameter "{p.name}"', p.loc)

    @staticmethod
    def _bounded(name: str, v: float, min: float | None, max: float | None, loc: Location) -> float:
        """``v`` checked finite and within [min, max]."""
        if not math.isfinite(v):
            raise SceneError(f'parameter "{name}" must be finite, got {v}', loc)
        if min is not None and v < min:
            raise SceneError(f'parameter "{name}" must be >= {min}, got {v}', loc)
        if max is not None and v > max:
            raise SceneError(f'parameter "{name}" must be <= {max}, got {v}', loc)
        return v

    def int(self, name: str, default: int | None = None, *, min: int | None = None) -> int | None:
        p = self._one(name, ("integer",), 1)
        if p is None:
            return default
        v = int(p.values[0])
        if min is not None and v < min:
            raise SceneError(f'parameter "{name}" must be >= {min}, got {v}', p.loc)
        return v

    def bool(self, name: str, default: bool | None = None) -> bool | None:
        p = self._one(name, ("bool",), 1)
        return default if p is None else bool(p.values[0])

    def string(self, name: str, default: str | None = None) -> str | None:
        p = self._one(name, ("string",), 1)
        return default if p is None else str(p.values[0])

    def texture(self, name: str) -> str | None:
        p = self._one(name, ("texture",), 1)
        return None if p is None else str(p.values[0])

    def floats(self, name: str, types: tuple[str, ...] = ("float",)) -> np.ndarray | None:
        """All values of an array parameter as float64, or None when absent."""
        p = self.get(name)
        if p is None:
            return None
        if p.type not in types:
            raise SceneError(f'parameter "{name}" must be of type {" or ".join(types)}, not {p.type}', p.loc)
        a = np.asarray(p.values, dtype=np.float64)
        if not np.all(np.isfinite(a)):
            raise SceneError(f'parameter "{name}" contains NaN or infinite values', p.loc)
        return a

    def ints(self, name: str) -> np.ndarray | None:
        p = self.get(name)
        if p is None:
            return None
        if p.type != "integer":
            raise SceneError(f'parameter "{name}" must be of type integer, not {p.type}', p.loc)
        return np.asarray(p.values, dtype=np.int64)

    def unused(self) -> list[Param]:
        """Parameters nobody looked up: the caller warns about them (file:line)."""
        return [p for p in self.params.values() if not p.used]

    def rgb(self, name: str, default: Any = None) -> np.ndarray | None:
        """A colour parameter as linear sRGB: ``rgb``, ``blackbody`` (luminance 1, as pbrt-v4) or a
        ``spectrum`` (constant, sampled, named or a file: :mod:`renderer.color.named_spectra`)."""
        p = self.get(name)
        if p is None:
            return None if default is None else np.asarray(default, dtype=np.float64) * np.ones(3)
        if p.type == "rgb":
            if len(p.values) != 3:
                raise SceneError(f'parameter "{name}" needs 3 values, got {len(p.values)}', p.loc)
            v = np.asarray(p.values, dtype=np.float64)
        elif p.type == "blackbody":
            if len(p.values) != 1 or not 0 < float(p.values[0]) < 1e6:
                raise SceneError(f'parameter "{name}": blackbody needs one temperature between 0 and 1e6 kelvin',
                                 p.loc)
            from renderer.color.rgb import blackbody_rgb

            v = blackbody_rgb(float(p.values[0]))
        elif p.type == "spectrum" and len(p.values) == 1 and not isinstance(p.values[0], str):
            v = np.full(3, float(p.values[0]))
        elif p.type == "spectrum":
            from renderer.color.named_spectra import spectrum_rgb

            v = spectrum_rgb(self._spectrum(p))
        elif p.type in ("float",) and len(p.values) == 1:
            v = np.full(3, float(p.values[0]))
        else:
            raise SceneError(f'parameter "{name}": only rgb, blackbody and spectrum values are '
                             f'supported (got {p.type} {p.values[:4]})', p.loc)
        if not np.all(np.isfinite(v)):
            raise SceneError(f'parameter "{name}" contains NaN or infinite values', p.loc)
        return v

    def spectrum_samples(self, name: str) -> np.ndarray | None:
        """The (N, 2) samples of a parameter given as a non-constant spectrum (named, inline or a
        file), else None: what a material that works per wavelength reads beside its RGB."""
        p = self.get(name)
        if p is None or p.type != "spectrum" or (len(p.values) == 1 and not isinstance(p.values[0], str)):
            return None
        return self._spectrum(p)

    def rgb_or_texture(self, name: str, default: Any = None) -> np.ndarray | str | None:
        """A colour that may also name a texture (returned as the texture's name)."""
        p = self.params.get(name)
        if p is not None and p.type == "texture":
            return self.texture(name)
        return self.rgb(name, default)

    def float_or_texture(self, name: str, default: float | None = None, **limits: float) -> float | str | None:
        """A float that may also name a float texture (returned as the texture's name)."""
        p = self.params.get(name)
        if p is not None and p.type == "texture":
            return self.texture(name)
        return self.float(name, default, **limits)
