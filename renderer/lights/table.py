"""The device light table, the same for every kind of light: one row per light (its kind, its
colour, a few named floats, ints and vectors, a rotation each way) and two shared pools (floats and
vectors) for what a light needs in bulk: an environment map's pixels and CDFs, an area light's
triangles and their CDF; and a pool of bytes, where an 8-bit environment map stays 8-bit.

A light module names its row entries once with :class:`Row`; device code reads them as constants,
``lights.f[i, F.cos_max]``, and the module's host ``entry`` fills them by the same names.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import warp as wp

from renderer.device.pools import pooled
from renderer.errors import RenderError
from renderer.parameters import Parameter


@wp.struct
class Lights:
    count: int
    kind: wp.array(dtype=int)              # registry id of each light (renderer.lights.kind_id)
    L: wp.array(dtype=wp.vec3)             # radiance, intensity or irradiance (per kind), scale applied
    f: wp.array2d(dtype=float)             # (count, widest row) named floats of each light's kind
    k: wp.array2d(dtype=int)               # named ints
    v: wp.array2d(dtype=wp.vec3)           # named vectors
    to_world: wp.array(dtype=wp.mat33)     # light-to-world rotation (identity where unused)
    to_light: wp.array(dtype=wp.mat33)     # its inverse
    f_start: wp.array(dtype=int)           # where each light's data begins in the float pool
    v_start: wp.array(dtype=int)           # and in the vector pool
    f_pool: wp.array(dtype=float)
    v_pool: wp.array(dtype=wp.vec3)
    c_start: wp.array(dtype=int)           # where each light's 8-bit codes begin in the code pool
    c_pool: wp.array(dtype=wp.uint8)       # 8-bit environment maps as stored (see infinite.py)


def colour_parameters(name: str, doc: str) -> tuple[Parameter, Parameter]:
    """The two parameters every pbrt-v4 light has: its colour ``name`` (rgb, or a blackbody of
    luminance 1 as in pbrt-v4) and the ``scale`` that multiplies it, neither negative: negative
    light would subtract from the image (and break light sampling's densities)."""
    return (Parameter(name, "rgb", (1.0, 1.0, 1.0), lo=0.0, doc=doc),
            Parameter("scale", "float", 1.0, lo=0.0, doc=f"multiplies {name}"))


def scaled_colour(values: dict[str, Any], name: str, factor: float = 1.0) -> np.ndarray:
    """The colour ``name`` times ``scale`` (and a light's own ``factor``), as its row holds it."""
    return np.asarray(values[name], np.float64) * (values["scale"] * factor)


class Row:
    """The names of a kind's row entries. ``F``, ``K`` and ``V`` are classes whose attributes are
    the column of each name, which Warp reads as compile-time constants."""

    def __init__(self, floats: tuple[str, ...] = (), ints: tuple[str, ...] = (), vecs: tuple[str, ...] = ()):
        self.names = {"floats": tuple(floats), "ints": tuple(ints), "vecs": tuple(vecs)}
        self.F = type("F", (), {n: i for i, n in enumerate(floats)})
        self.K = type("K", (), {n: i for i, n in enumerate(ints)})
        self.V = type("V", (), {n: i for i, n in enumerate(vecs)})


@dataclass
class LightEntry:
    """One light's row, as its module's host ``entry`` builds it."""

    L: Any                                        # (3,) colour, scale applied
    floats: dict[str, float] = field(default_factory=dict)
    ints: dict[str, int] = field(default_factory=dict)
    vecs: dict[str, Any] = field(default_factory=dict)
    to_world: np.ndarray = field(default_factory=lambda: np.eye(3))
    to_light: np.ndarray = field(default_factory=lambda: np.eye(3))
    f_data: np.ndarray = field(default_factory=lambda: np.zeros(0, np.float32))
    v_data: np.ndarray = field(default_factory=lambda: np.zeros((0, 3), np.float32))
    c_data: np.ndarray = field(default_factory=lambda: np.zeros(0, np.uint8))
    escapes: bool = False                         # a ray leaving the scene can see it (env map, soft sun)


def _placed(values: dict[str, Any], names: tuple[str, ...], width: int) -> list:
    """The values in column order, padded to ``width``."""
    return [values[n] for n in names] + [0] * (width - len(names))


@dataclass
class LightTable:
    """Host-side list of light rows; ``upload`` turns it into the :class:`Lights` struct. Kinds
    are registry ids with their row layouts, so the table itself knows no kind of light."""

    kinds: list[int] = field(default_factory=list)
    rows: list[Row] = field(default_factory=list)
    entries: list[LightEntry] = field(default_factory=list)

    def add(self, kind: int, row: Row, entry: LightEntry) -> int:
        for what, given in (("floats", entry.floats), ("ints", entry.ints), ("vecs", entry.vecs)):
            if set(given) != set(row.names[what]):   # a bug in the light module, not in the scene
                raise ValueError(f"light kind {kind}: {what} {sorted(given)} do not match its Row "
                                 f"{sorted(row.names[what])}")
        self.kinds.append(kind)
        self.rows.append(row)
        self.entries.append(entry)
        return len(self.entries) - 1

    def upload(self, device: str) -> tuple[Lights, list]:
        n = len(self.entries)
        widths = {w: max([len(r.names[w]) for r in self.rows] + [1]) for w in ("floats", "ints", "vecs")}
        f = np.zeros((max(n, 1), widths["floats"]), np.float32)
        k = np.zeros((max(n, 1), widths["ints"]), np.int32)
        v = np.zeros((max(n, 1), widths["vecs"], 3), np.float32)
        L = np.zeros((max(n, 1), 3), np.float32)
        to_world = np.tile(np.eye(3, dtype=np.float32), (max(n, 1), 1, 1))
        to_light = to_world.copy()
        f_start, v_start, c_start = (np.zeros(max(n, 1), np.int32) for _ in range(3))
        f_pool, v_pool, c_pool = [], [], []
        f_used, v_used, c_used = 0, 0, 0
        for i, (kind, row, e) in enumerate(zip(self.kinds, self.rows, self.entries)):
            f[i] = _placed(e.floats, row.names["floats"], widths["floats"])
            k[i] = _placed(e.ints, row.names["ints"], widths["ints"])
            v[i] = [np.asarray(x, np.float32) * np.ones(3, np.float32)
                    for x in _placed(e.vecs, row.names["vecs"], widths["vecs"])]
            L[i] = np.asarray(e.L, dtype=np.float32)
            to_world[i], to_light[i] = e.to_world, e.to_light
            f_start[i], v_start[i], c_start[i] = f_used, v_used, c_used
            f_pool.append(np.asarray(e.f_data, np.float32).ravel())
            v_pool.append(np.asarray(e.v_data, np.float32).reshape(-1, 3))
            c_pool.append(np.asarray(e.c_data, np.uint8).ravel())
            f_used += f_pool[-1].size
            v_used += len(v_pool[-1])
            c_used += c_pool[-1].size
        if max(f_used, c_used) >= 2**31:      # device code indexes the pools with 32-bit integers
            raise RenderError(f"the lights' data ({max(f_used, c_used)} entries) is more than 2^31; "
                              "use smaller environment images")
        arr = lambda a, dt: wp.array(a, dtype=dt, device=device)
        S = Lights()
        S.count = n
        S.kind = arr(np.asarray(self.kinds or [0], np.int32), int)
        S.L = arr(L, wp.vec3)
        S.f, S.k, S.v = arr(f, float), arr(k, int), arr(v, wp.vec3)
        S.to_world, S.to_light = arr(to_world, wp.mat33), arr(to_light, wp.mat33)
        S.f_start, S.v_start, S.c_start = arr(f_start, int), arr(v_start, int), arr(c_start, int)
        S.f_pool = pooled(f_pool, np.zeros(1, np.float32), float, device)
        S.v_pool = pooled(v_pool, np.zeros((1, 3), np.float32), wp.vec3, device)
        S.c_pool = pooled(c_pool, np.zeros(1, np.uint8), wp.uint8, device)
        keep = [S.kind, S.L, S.f, S.k, S.v, S.to_world, S.to_light, S.f_start, S.v_start, S.f_pool, S.v_pool,
                S.c_start, S.c_pool]
        return S, keep
