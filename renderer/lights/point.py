"""pbrt-v4's ``point`` light: radiant intensity ``I`` (rgb or blackbody) in every direction from
the point ``from``, falling off as 1/r². A delta light: only light sampling can find it.

``power`` is pbrt-v4's: when > 0 it multiplies ``scale`` by power / 4π, the intensity that emits
that power. As in pbrt-v4 a blackbody ``I`` has luminance 1 first; an rgb ``I`` keeps its own
magnitude (pbrt-v4 normalises only the colour space's illuminant).
"""
from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np
import warp as wp

from renderer.lights.sample import LightSample
from renderer.lights.table import LightEntry, Lights, Row, colour_parameters, scaled_colour
from renderer.parameters import Parameter, Parameters

if TYPE_CHECKING:
    from renderer.scene.description import LightDesc

NAME = "point"
DIRECTIVE = "LightSource"
PARAMS = Parameters(
    *colour_parameters("I", "radiant intensity"),
    Parameter("power", "float", -1.0, doc="if > 0, the emitted power (pbrt-v4): it rescales I"),
    Parameter("from", "point3", (0.0, 0.0, 0.0), doc="position"),
)
ROW = Row(vecs=("position",))
V = ROW.V


def position(values: dict[str, Any], light_to_world: np.ndarray) -> np.ndarray:
    """The world-space position of ``from`` (the light space's origin for lights without one)."""
    p = np.asarray(light_to_world, np.float64) @ np.append(np.asarray(values.get("from", (0.0, 0.0, 0.0)), np.float64), 1.0)
    return p[:3] / p[3]


def intensity(values: dict[str, Any], power_per_intensity: float) -> np.ndarray:
    """I times scale, and times power / k_e when a power is given (k_e: the power emitted per unit
    of intensity, 4π for a point light)."""
    return scaled_colour(values, "I", power_factor(values, power_per_intensity))


def power_factor(values: dict[str, Any], power_per_unit: float) -> float:
    """pbrt-v4's ``power`` > 0: the factor power / k_e on ``scale``, k_e being what the light emits
    at scale 1 (1 without a power, 0 for a light that emits nothing at scale 1)."""
    if values["power"] <= 0:
        return 1.0
    return values["power"] / power_per_unit if power_per_unit > 0 else 0.0


def entry(light: LightDesc, tris: np.ndarray | None) -> LightEntry:
    return LightEntry(L=intensity(light.values, 4.0 * math.pi),
                      vecs={"position": position(light.values, light.light_to_world)})


@wp.func
def sample(lights: Lights, i: int, p: wp.vec3, u: wp.vec2) -> LightSample:
    s = LightSample()
    s.delta = True
    d = lights.v[i, V.position] - p
    dist = wp.length(d)
    if dist <= 0.0:
        s.pdf = 0.0
        return s
    s.wi = d / dist
    s.dist = dist
    s.L = lights.L[i] / (dist * dist)
    s.pdf = 1.0
    return s
