"""pbrt-v4's ``distant`` light: irradiance ``L`` (rgb or blackbody) arriving from the direction
``from - to``. Our extension ``angularradius`` (degrees) spreads it uniformly over a cone of that
half-angle, a soft-shadowed sun (0.27 for the real one) that BSDF sampling can also hit.
"""
from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import warp as wp

from renderer.errors import Location, SceneError
from renderer.lights.sample import LightEval, LightSample
from renderer.lights.table import LightEntry, Lights, Row, colour_parameters, scaled_colour
from renderer.parameters import Parameter, Parameters
from renderer.sampling.frames import frame_from_normal, to_world
from renderer.sampling.warps import uniform_cone
from renderer.vecmath import PI

if TYPE_CHECKING:
    from renderer.scene.description import LightDesc

NAME = "distant"
DIRECTIVE = "LightSource"
PARAMS = Parameters(
    *colour_parameters("L", "irradiance on a surface facing the light"),
    Parameter("illuminance", "float", -1.0, doc="if > 0, multiplies scale (pbrt-v4; L keeps its own magnitude)"),
    Parameter("from", "point3", (0.0, 0.0, 0.0), doc="the light shines from here towards to"),
    Parameter("to", "point3", (0.0, 0.0, 1.0)),
    Parameter("angularradius", "float", 0.0, lo=0.0, hi=90.0, doc="extension: half-angle of a soft sun, degrees"),
)
ROW = Row(floats=("cos_max",), vecs=("direction",))
F, V = ROW.F, ROW.V


def _direction(values: dict[str, Any], light_to_world: np.ndarray) -> np.ndarray:
    """World-space vector from the scene towards the light (not normalised)."""
    return np.asarray(light_to_world, np.float64)[:3, :3] @ (np.asarray(values["from"]) - np.asarray(values["to"]))


def check(given: dict[str, Any], light_to_world: np.ndarray, loc: Location | None,
          base_dir: Path | None) -> dict[str, Any]:
    full = {p.name: PARAMS.value(given, p.name) for p in PARAMS}
    if not np.linalg.norm(_direction(full, light_to_world)) > 0.0:
        raise SceneError('LightSource "distant": "from" and "to" give no direction', loc)
    return given


def entry(light: LightDesc, tris: np.ndarray | None) -> LightEntry:
    v = light.values
    w = _direction(v, light.light_to_world)
    cos_max = float(np.cos(np.radians(v["angularradius"])))
    return LightEntry(L=scaled_colour(v, "L", v["illuminance"] if v["illuminance"] > 0 else 1.0),
                      floats={"cos_max": cos_max},
                      vecs={"direction": w / np.linalg.norm(w)}, escapes=cos_max < 1.0)


# ---- device ---------------------------------------------------------------------------------------

@wp.func
def _cone_solid_angle(cos_max: float) -> float:
    return 2.0 * PI * (1.0 - cos_max)


@wp.func
def escaped(lights: Lights, i: int, p: wp.vec3, d: wp.vec3) -> LightEval:
    """A soft sun seen along d: its irradiance spread evenly over the cone (zero outside, and for
    a delta light)."""
    ev = LightEval()
    cm = lights.f[i, F.cos_max]
    if cm >= 1.0 or wp.dot(d, lights.v[i, V.direction]) < cm:
        return ev
    ev.L = lights.L[i] / _cone_solid_angle(cm)
    ev.pdf = 1.0 / _cone_solid_angle(cm)
    return ev


@wp.func
def sample(lights: Lights, i: int, p: wp.vec3, u: wp.vec2) -> LightSample:
    s = LightSample()
    cm = lights.f[i, F.cos_max]
    s.dist = 1.0e30
    if cm >= 1.0:
        s.wi = lights.v[i, V.direction]
        s.L = lights.L[i]
        s.pdf = 1.0
        s.delta = True
    else:
        s.wi = to_world(frame_from_normal(lights.v[i, V.direction]), uniform_cone(u, cm))
        s.L = lights.L[i] / _cone_solid_angle(cm)
        s.pdf = 1.0 / _cone_solid_angle(cm)
        s.delta = False
    return s
