"""The thin-film mode ``table`` for ``thinfilm``: which coatings a baked table over the angle can
describe, and their rows (:mod:`renderer.optics.angular_table`).

A table is baked for the material's constant coating: its indices, its thickness (with a constant
``thicknessmap``) and its layers. Where one of those is a texture, the coating differs from hit to
hit and one table cannot describe it; the material then keeps the per-hit evaluation at
``spectral:N`` (``table:N``; ``table`` means N = 32) and the render warns once. A third table
axis over a thickness map's range was considered and left out: a texture's range is known only
for image maps, a 200-layer table already takes ~2 s to bake per side, and a map would multiply
that by the axis' resolution, where spectral:32 handles a mapped stack without any bake.

Rows: the front side's table (light arriving from the outer medium), then for a clear substrate
(``transmission`` or ``layered``) the back side's (from the substrate, the stack reversed).
"""
from __future__ import annotations

from typing import Any

import numpy as np

from renderer.color.spectral import parse_mode
from renderer.errors import Location
from renderer.materials.stack import has_stack, stack_rows
from renderer.optics.angular_table import stack_table
from renderer.parameters import Parameters, TextureRef

#: The parameters that shape the coating's optics; none may be a texture for a table.
COATING_PARAMS = ("eta_outer", "eta_film", "eta_inner", "k_inner", "thickness", "thicknessmap", "thicknessscale")


def coating_layers(values: dict[str, Any], params: Parameters, loc: Location | None) -> np.ndarray:
    """The coating's layer rows (Cauchy A, B, k, thickness nm), outer side first, thickness map
    applied as the device applies it: one film of ``thickness`` + scale × map, or a stack scaled
    by its mapped over its unmapped total."""
    v = {name: float(params.value(values, name)) for name in COATING_PARAMS}
    d = max(v["thickness"] + v["thicknessscale"] * v["thicknessmap"], 0.0)
    if not has_stack(values):
        return np.array([[v["eta_film"], 0.0, 0.0, d]], np.float32)
    rows = stack_rows(values, loc).astype(np.float64)
    total = float(np.float32(v["thickness"]))
    rows[:, 3] *= d / total if total > 0.0 else 1.0
    return rows.astype(np.float32)


def coating_table(values: dict[str, Any], params: Parameters, loc: Location | None, thin_film: str,
                  clear: bool) -> tuple[np.ndarray, str]:
    """(rows, warning) of the coating's table in the mode ``thin_film``: no rows outside the
    table mode, and none with a warning where a texture drives the coating."""
    kind, n = parse_mode(thin_film)
    if kind != "table":
        return np.zeros((0, 4), np.float32), ""
    textured = [name for name in COATING_PARAMS if isinstance(values.get(name), TextureRef)]
    if textured:
        return np.zeros((0, 4), np.float32), (f'thinfilm: {", ".join(textured)} given by a texture, so no table '
                                              f'describes this coating: it is evaluated at spectral:{n}')
    layers = coating_layers(values, params, loc)
    n_outer = float(params.value(values, "eta_outer"))
    n_inner = complex(float(params.value(values, "eta_inner")), float(params.value(values, "k_inner")))
    tables = [stack_table(n_outer, n_inner, layers)]
    if clear:
        tables.append(stack_table(n_inner.real, complex(n_outer, 0.0), layers[::-1]))
    return np.concatenate(tables), ""
