"""pbrt-v4's ``spot`` light: a point light at ``from`` shining towards ``to``, full intensity
``I`` within ``coneangle - conedeltaangle`` of the axis, none beyond ``coneangle`` (degrees), and
pbrt-v4's smoothstep in cos θ between. ``power`` > 0 sets the emitted power as in pbrt-v4.
"""
from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import warp as wp

from renderer.errors import Location, SceneError
from renderer.lights import point
from renderer.lights.sample import LightSample
from renderer.lights.table import LightEntry, Lights, Row
from renderer.parameters import Parameter, Parameters

if TYPE_CHECKING:
    from renderer.scene.description import LightDesc

NAME = "spot"
DIRECTIVE = "LightSource"
PARAMS = Parameters(
    *point.PARAMS,
    Parameter("to", "point3", (0.0, 0.0, 1.0), doc="a point on the axis"),
    Parameter("coneangle", "float", 30.0, lo=0.0, hi=180.0, doc="half-angle where the light ends, degrees"),
    Parameter("conedeltaangle", "float", 5.0, lo=0.0, hi=180.0, doc="width of the falloff inside it, degrees"),
)
# the position sits where point.sample reads it
ROW = Row(floats=("cos_falloff_start", "cos_falloff_end"), vecs=point.ROW.names["vecs"])
F = ROW.F


def _axis(values: dict[str, Any]) -> np.ndarray:
    return np.asarray(values["to"], np.float64) - np.asarray(values["from"], np.float64)


def check(given: dict[str, Any], light_to_world: np.ndarray, loc: Location | None,
          base_dir: Path | None) -> dict[str, Any]:
    if not np.linalg.norm(_axis({p.name: PARAMS.value(given, p.name) for p in PARAMS})) > 0.0:
        raise SceneError('LightSource "spot": "from" and "to" give no direction', loc)
    return given


def _light_from_world(values: dict[str, Any], light_to_world: np.ndarray) -> np.ndarray:
    """Directions from world space into the spot's frame, whose +z is the axis (pbrt-v4:
    Frame::FromZ of to - from, after the CTM)."""
    z = _axis(values) / np.linalg.norm(_axis(values))
    x = np.cross(z, [1.0, 0.0, 0.0] if abs(z[0]) < 0.9 else [0.0, 1.0, 0.0])
    x /= np.linalg.norm(x)
    frame = np.stack([x, np.cross(z, x), z])
    return frame @ np.linalg.inv(np.asarray(light_to_world, np.float64)[:3, :3])


def entry(light: LightDesc, tris: np.ndarray | None) -> LightEntry:
    v = light.values
    cos_end = math.cos(math.radians(v["coneangle"]))
    cos_start = math.cos(math.radians(v["coneangle"] - v["conedeltaangle"]))
    k_e = 2.0 * math.pi * ((1.0 - cos_start) + (cos_start - cos_end) / 2.0)
    to_light = _light_from_world(v, light.light_to_world)
    return LightEntry(L=point.intensity(v, k_e), floats={"cos_falloff_start": cos_start, "cos_falloff_end": cos_end},
                      vecs={"position": point.position(v, light.light_to_world)},
                      to_world=np.linalg.inv(to_light), to_light=to_light)


@wp.func
def _smoothstep(x: float, a: float, b: float) -> float:
    """pbrt-v4's SmoothStep: 0 below a, 1 above b, a step where a == b."""
    if a == b:
        if x < a:
            return 0.0
        return 1.0
    t = wp.clamp((x - a) / (b - a), 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


@wp.func
def sample(lights: Lights, i: int, p: wp.vec3, u: wp.vec2) -> LightSample:
    s = point.sample(lights, i, p, u)
    if s.pdf > 0.0:
        cos_t = wp.normalize(lights.to_light[i] * (-s.wi))[2]
        s.L = s.L * _smoothstep(cos_t, lights.f[i, F.cos_falloff_end], lights.f[i, F.cos_falloff_start])
    return s
