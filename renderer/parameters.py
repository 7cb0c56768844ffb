"""Named plugin parameters: a material or a light declares each of its parameters once (name, type,
default, range, whether a texture may drive it) and everything else follows from that one
declaration: reading them from a pbrt parameter list or from Python keyword values, range checks
with the file and line, the "unused parameter" warning (whatever the declaration did not read),
the device layout (one texture slot per float/rgb parameter, one bit per bool) and the docs table.

Device code reads parameters by name through the generated classes: ``b.p[SLOT.roughness]`` and
``b.flags & FLAG.transmission`` (Warp resolves class attributes to constants at compile time).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Iterable

import numpy as np

from renderer.color.named_spectra import SpectralFloat, SpectralRGB
from renderer.errors import Location, SceneError

if TYPE_CHECKING:   # only annotations: importing the scene package here would make import order matter
    from renderer.scene.params import ParamSet

#: Parameter types: "float" and "rgb" may be textures and get a device slot; "bool" gets a flag
#: bit; "int", "string", "strings" (a list of names, e.g. a mix's materials), "point3" (a position,
#: e.g. a light's "from"), "floats" (a list of any length, e.g. a stack's per-layer values) and
#: "points3" (a list of points: a portal's corners) are host-side only (they shape the table, not
#: the per-hit value).
TYPES = ("float", "rgb", "bool", "int", "string", "strings", "point3", "floats", "points3")


@dataclass(frozen=True)
class TextureRef:
    """A parameter bound to a named texture instead of a constant."""

    name: str


@dataclass(frozen=True)
class Parameter:
    name: str
    type: str
    default: Any = None                  # None: no default (optional, absent unless given)
    lo: float | None = None
    hi: float | None = None
    texture: bool = False                # a float or spectrum texture may drive it
    doc: str = ""

    def __post_init__(self) -> None:
        if self.type not in TYPES:
            raise ValueError(f"parameter {self.name!r}: unknown type {self.type!r}")
        if self.texture and self.type not in ("float", "rgb"):
            raise ValueError(f"parameter {self.name!r}: only float and rgb parameters can be textures")

    def check(self, value: Any, owner: str, loc: Location | None) -> Any:
        """A Python value of this parameter, converted and range-checked (TextureRef passes)."""
        if isinstance(value, TextureRef):
            if not self.texture:
                raise SceneError(f'{owner}: parameter "{self.name}" cannot be a texture', loc)
            return value
        if self.type == "bool":
            if not isinstance(value, (bool, np.bool_)):
                raise SceneError(f'{owner}: parameter "{self.name}" must be true or false, got {value!r}', loc)
            return bool(value)
        if self.type == "string":
            if not isinstance(value, str):
                raise SceneError(f'{owner}: parameter "{self.name}" must be a string, got {value!r}', loc)
            return value
        if self.type == "strings":
            if isinstance(value, str) or not all(isinstance(v, str) for v in value):
                raise SceneError(f'{owner}: parameter "{self.name}" must be a list of strings, got {value!r}', loc)
            return tuple(value)
        try:
            a = np.asarray(value, dtype=np.float64)
        except (TypeError, ValueError):
            raise SceneError(f'{owner}: parameter "{self.name}" must be a number, got {value!r}', loc) from None
        if self.type == "rgb":
            if a.size not in (1, 3):
                raise SceneError(f'{owner}: parameter "{self.name}" needs 1 or 3 values, got {a.size}', loc)
            a = np.broadcast_to(a.ravel(), (3,)) if a.size == 1 else a.ravel()
        elif self.type == "floats":
            if a.size == 0:
                raise SceneError(f'{owner}: parameter "{self.name}" needs at least one value', loc)
            a = a.ravel()
        elif self.type == "points3":
            if a.size == 0 or a.size % 3:
                raise SceneError(f'{owner}: parameter "{self.name}" needs points (3 values each), got {a.size} values', loc)
            a = a.ravel()
        elif self.type == "point3":
            if a.size != 3:
                raise SceneError(f'{owner}: parameter "{self.name}" needs 3 values (one point), got {a.size}', loc)
            a = a.ravel()
        elif a.size != 1:
            raise SceneError(f'{owner}: parameter "{self.name}" needs one value, got {a.size}', loc)
        if not np.all(np.isfinite(a)):
            raise SceneError(f'{owner}: parameter "{self.name}" must be finite, got {a.tolist()}', loc)
        if (self.lo is not None and np.any(a < self.lo)) or (self.hi is not None and np.any(a > self.hi)):
            lo = "-inf" if self.lo is None else self.lo
            hi = "inf" if self.hi is None else self.hi
            raise SceneError(f'{owner}: parameter "{self.name}" = {a.tolist()} is outside [{lo}, {hi}]', loc)
        if self.type == "int":
            if float(a.ravel()[0]) != math.floor(float(a.ravel()[0])):
                raise SceneError(f'{owner}: parameter "{self.name}" must be an integer, got {value!r}', loc)
            return int(a.ravel()[0])
        if isinstance(value, SpectralRGB) and self.type == "rgb":
            return SpectralRGB((float(x) for x in a), value.samples)     # the spectrum travels with its RGB
        if isinstance(value, SpectralFloat) and self.type == "float":
            return SpectralFloat(float(a.ravel()[0]), value.samples)     # and with its float
        return tuple(float(x) for x in a) if self.type in ("rgb", "point3", "floats", "points3") else float(a.ravel()[0])

    def read(self, ps: ParamSet, owner: str) -> Any:
        """This parameter's value from a pbrt parameter list, or None when it is absent."""
        p = ps.params.get(self.name)
        if p is None:
            return None
        loc = p.loc
        if p.type == "texture":
            if not self.texture:
                raise SceneError(f'{owner}: parameter "{self.name}" cannot be a texture', loc)
            return TextureRef(ps.texture(self.name))
        if self.type == "float":
            v = ps.float(self.name)
            samples = ps.spectrum_samples(self.name)
            if samples is not None:
                v = SpectralFloat(v, samples)
        elif self.type == "rgb":
            v = tuple(ps.rgb(self.name))
            samples = ps.spectrum_samples(self.name)
            if samples is not None:
                v = SpectralRGB(v, samples)
        elif self.type == "bool":
            v = ps.bool(self.name)
        elif self.type == "int":
            v = ps.int(self.name)
        elif self.type in ("point3", "points3"):
            v = ps.floats(self.name, ("point3", "point"))
        elif self.type == "floats":
            v = ps.floats(self.name)
        elif self.type == "strings":
            if p.type != "string":
                raise SceneError(f'{owner}: parameter "{self.name}" must be of type string, not {p.type}', loc)
            v = tuple(ps.get(self.name).values)
        else:
            v = ps.string(self.name)
        return self.check(v, owner, loc)


class Parameters:
    """A plugin's declared parameters, in declaration order (which is also the slot order)."""

    def __init__(self, *params: Parameter, shared: dict[str, str] | None = None):
        """``shared`` maps a parameter to the one whose slot it takes: two parameters of modes that
        exclude each other (a thin sheet's and a coated solid's) sharing a slot; the sharer fills it
        where the material's resolved values hold it (:meth:`slot_layout`)."""
        self.by_name = {p.name: p for p in params}
        if len(self.by_name) != len(params):
            raise ValueError("a parameter is declared twice")
        self.shared = dict(shared or {})
        slotted = [p.name for p in params if p.type in ("float", "rgb") and p.name not in self.shared]
        flagged = [p.name for p in params if p.type == "bool"]
        index = {n: i for i, n in enumerate(slotted)}
        for sharer, owner in self.shared.items():
            if self.by_name[sharer].type not in ("float", "rgb") or owner not in index:
                raise ValueError(f"parameter {sharer!r} cannot share the slot of {owner!r}")
            index[sharer] = index[owner]
        #: slot index per float/rgb parameter, as class attributes Warp can read in device code
        self.slots = type("Slots", (), index)
        #: bit per bool parameter
        self.flags = type("Flags", (), {n: 1 << i for i, n in enumerate(flagged)})
        self.slot_names = tuple(slotted)
        self.flag_names = tuple(flagged)

    def __iter__(self):
        return iter(self.by_name.values())

    def from_pbrt(self, ps: ParamSet, owner: str) -> dict[str, Any]:
        """Every declared parameter present in ``ps``, typed and range-checked; the rest of ``ps``
        stays unread, for the caller to warn about (``ps.unused()``)."""
        out = {}
        for p in self:
            v = p.read(ps, owner)
            if v is not None:
                out[p.name] = v
        return out

    def from_python(self, values: dict[str, Any], owner: str, loc: Location | None = None) -> dict[str, Any]:
        """Keyword values given in Python: unknown names are an error (a typo must not vanish)."""
        unknown = sorted(set(values) - set(self.by_name))
        if unknown:
            raise SceneError(f'{owner}: unknown parameter(s) {", ".join(unknown)} '
                             f'(known: {", ".join(self.by_name)})', loc)
        return {k: self.by_name[k].check(v, owner, loc) for k, v in values.items() if v is not None}

    def value(self, values: dict[str, Any], name: str) -> Any:
        """A parameter's given value, else its declared default."""
        v = values.get(name)
        return self.by_name[name].default if v is None else v

    def slot_layout(self, values: dict[str, Any]) -> list[tuple[Parameter, Any]]:
        """Per slot its parameter and value (given or default): a shared slot's sharer where
        ``values`` holds it, else its owner."""
        out = []
        for name in self.slot_names:
            sharers = [s for s, o in self.shared.items() if o == name and s in values]
            chosen = sharers[0] if sharers else name
            out.append((self.by_name[chosen], self.value(values, chosen)))
        return out

    def docs_table(self) -> str:
        """A Markdown table of the parameters (for README and docs)."""
        rows = ["| parameter | type | default | range | texture | meaning |", "|---|---|---|---|---|---|"]
        for p in self:
            rng = "" if p.lo is None and p.hi is None else f"[{_fmt(p.lo)}, {_fmt(p.hi)}]"
            rows.append(f"| `{p.name}` | {p.type} | {_fmt(p.default)} | {rng} | {'yes' if p.texture else ''} | "
                        f"{p.doc} |")
        return "\n".join(rows)


def _fmt(x: Any) -> str:
    if x is None:
        return "–"
    if isinstance(x, Iterable) and not isinstance(x, str):
        return "(" + ", ".join(_fmt(v) for v in x) + ")"
    return str(x).lower() if isinstance(x, bool) else f"{x:g}" if isinstance(x, float) else str(x)
