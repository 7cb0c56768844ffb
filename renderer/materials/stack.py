"""A multilayer stack as material parameters: what ``thinfilm`` accepts instead of one film, and
how it becomes rows of the scene's layer table (:func:`renderer.optics.multilayer.multilayer_RT`).

A stack is a unit cell of layers, listed from the outer medium down (``layer_eta`` with optional
``layer_k``, ``layer_cauchyb`` and ``layer_thickness``, each of one value or one per layer),
repeated ``repeat`` times; the substrate is ``eta_inner`` + i ``k_inner`` as for one film. A
relative thickness disorder ``layer_disorder`` (σ, per layer of the cell or one for all) multiplies
each of the repeated layers by 1 + σ·N(0, 1), clipped at 0, drawn from ``seed``: nacre's platelets
are not all alike, and their spread is what turns a narrow-band Bragg mirror into a many-hued sheen.

The stack's ``thickness`` is derived: the total of its layers, so a thickness map adds nanometres
to the whole stack exactly as it does to one film, spread over the layers in proportion to their
thicknesses (for one layer the two are the same formula).

The layer table is one array of rows for the whole scene; a material knows its first row and row
count (``Materials.layer_first``, ``layer_count``); the BSDF reaches it as ``b.layers``, the way
the colour-matching table reaches it as ``b.spectral``.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from renderer.errors import Location, SceneError
from renderer.parameters import Parameter

#: Most rows one material may put in the layer table: cost grows linearly (benchmarks/thin_film_modes.py).
MAX_LAYERS = 2000

STACK_PARAMS = (
    Parameter("layer_eta", "floats", None, 1.0e-3, doc="a stack instead of one film: each layer's index "
              "(Cauchy A), outer side first"),
    Parameter("layer_k", "floats", None, 0.0, doc="each layer's imaginary index (one value: all)"),
    Parameter("layer_cauchyb", "floats", None, doc="each layer's Cauchy B (µm²): n = A + B/λ²"),
    Parameter("layer_thickness", "floats", None, 0.0, doc="each layer's thickness (nm)"),
    Parameter("repeat", "int", 1, 1.0, float(MAX_LAYERS), doc="the layers above are a unit cell repeated this "
              "often"),
    Parameter("layer_disorder", "floats", None, 0.0, doc="relative σ of each repeated layer's thickness"),
    Parameter("seed", "int", 0, 0.0, doc="the disorder's random seed"),
)
_LAYER_NAMES = tuple(p.name for p in STACK_PARAMS)
_PER_LAYER = ("layer_cauchyb", "layer_k", "layer_thickness", "layer_disorder")   # row order after A


def has_stack(values: dict[str, Any]) -> bool:
    return values.get("layer_eta") is not None


def _per_layer(values: dict[str, Any], name: str, n: int, loc: Location | None, owner: str) -> np.ndarray:
    v = values.get(name)
    if v is None:
        return np.zeros(n)
    a = np.asarray(v, np.float64)
    if a.size not in (1, n):
        raise SceneError(f'{owner}: "{name}" needs 1 or {n} values (one per layer of "layer_eta"), got {a.size}',
                         loc)
    return np.broadcast_to(a, (n,))


def stack_rows(values: dict[str, Any], loc: Location | None = None, owner: str = "thinfilm") -> np.ndarray:
    """The stack's rows (n, 4) float32: (Cauchy A, Cauchy B, k, thickness nm), outer side first,
    repeats and disorder applied; (0, 4) without a stack. ``owner`` names the material in errors."""
    if not has_stack(values):
        return np.zeros((0, 4), np.float32)
    eta = np.asarray(values["layer_eta"], np.float64)
    n = eta.size
    if values.get("layer_thickness") is None:
        raise SceneError(f'{owner}: a stack ("layer_eta") needs "layer_thickness"', loc)
    cell = np.stack([eta, *(_per_layer(values, name, n, loc, owner) for name in _PER_LAYER)], axis=-1)
    repeat = int(values.get("repeat", 1))
    if n * repeat > MAX_LAYERS:
        raise SceneError(f"{owner}: {n} layers x repeat {repeat} = {n * repeat} layers, more than {MAX_LAYERS}", loc)
    rows = np.tile(cell, (repeat, 1))
    sigma = rows[:, 4]
    if np.any(sigma > 0.0):
        rng = np.random.default_rng(int(values.get("seed", 0)))
        rows[:, 3] *= np.maximum(1.0 + sigma * rng.standard_normal(len(rows)), 0.0)
    return rows[:, :4].astype(np.float32)


def resolve_stack(values: dict[str, Any], loc: Location | None, owner: str = "thinfilm") -> dict[str, Any]:
    """Checks a stack against the single-film parameters and derives its total ``thickness``."""
    if not has_stack(values):
        given = sorted(n for n in _LAYER_NAMES if n in values)
        if given:
            raise SceneError(f'{owner}: {", ".join(given)} describe a stack, which needs "layer_eta"', loc)
        return values
    clash = sorted(n for n in ("eta_film", "thickness") if n in values)
    if clash:
        raise SceneError(f'{owner}: {" and ".join(clash)} belong to one film; a stack ("layer_eta") gives '
                         'its layers instead', loc)
    rows = stack_rows(values, loc, owner)
    return values | {"thickness": float(rows[:, 3].astype(np.float64).sum())}
