"""``lights.pbrt``: the generated sky as an ``infinite`` light plus the matching sun as a
``distant`` light with the sun's 0.27 degree disc, both multiplied by ``scale``, so a scene can
``Include`` the lighting that the ``sky`` generator's manifest describes.

``scale`` is one factor for sky and sun: the scene's exposure, since the sky is in kcd/m^2.
``sun``: ``rgb`` takes the sun's RGB irradiance from ``sky.json``; ``blackbody`` writes
``"blackbody L" [temperature]`` scaled to the same illuminance. The distant light's ``L`` is
irradiance at normal incidence (as in pbrt), so it takes ``sun.rgb_irradiance``, not the disc's
radiance.
"""
from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path

from assets_gen.core import Generator, Job, Params, param, reading, require


@dataclass(frozen=True)
class SkyLightsParams(Params):
    sky: str = param("assets/sky", "output folder of the `sky` generator", path=True)
    scale: float = param(1.0, "exposure factor for sky and sun (the sky map is in kcd/m^2)")
    layout: str = param("latlong", "which sky map the infinite light reads", choices=("latlong", "equalarea"))
    sun: str = param("rgb", "the sun's emission: RGB irradiance or a scaled blackbody", choices=("rgb", "blackbody"))
    temperature: float = param(5800.0, "blackbody sun temperature, K")

    def validate(self) -> None:
        meta = Path(self.sky) / "sky.json"
        require(meta.is_file(), f"{meta} not found (build the sky entry first)")
        require(self.scale > 0, "scale must be positive")
        require(self.layout in ("latlong", "equalarea"), "layout must be latlong or equalarea")
        require(self.sun in ("rgb", "blackbody"), "sun must be rgb or blackbody")
        require(1000 <= self.temperature <= 40000, "temperature must be 1000..40000 K")
        env = Path(self.sky) / _map_name(self.layout)
        require(env.is_file(), f"{env} not found (the sky entry's layout must include {self.layout})")


def _map_name(layout: str) -> str:
    return "sky_latlong.exr" if layout == "latlong" else "sky_equalarea.exr"


def _fmt(v: float) -> str:
    return f"{float(v):.6g}"


def write(job: Job) -> list[str]:
    p = job.params
    with reading(Path(p.sky) / "sky.json", "sky description"):
        meta = json.loads((Path(p.sky) / "sky.json").read_text())["params"]
        sun = meta["sun"]
        d = [float(c) for c in sun["direction_world_y_up"]]
        placed = meta.get("solar_position", meta)           # the sun's angles, given or from a date
        when = [float(placed["elevation_deg"]), float(placed["azimuth_deg"]), float(meta["turbidity"])]
        radius = _fmt(float(sun.get("angular_radius_deg", 0.27)))
        strength = ([float(v) * p.scale for v in sun["rgb_irradiance"]] if p.sun == "rgb"
                    else float(sun["normal_illuminance_lux"]) / 1000.0)   # klx
    env = Path(p.sky) / _map_name(p.layout)
    env_rel = os.path.relpath(env.resolve(), job.out_dir.resolve()).replace(os.sep, "/")
    lines = [
        f"# Written by `assets-gen recipe` (sky-lights) from {(Path(job.given.sky) / 'sky.json').as_posix()}: "
        "do not edit.",
        f"# Sun elevation {_fmt(when[0])} deg, azimuth {_fmt(when[1])} deg, turbidity {_fmt(when[2])};",
        f"# sky and sun share the exposure scale {_fmt(p.scale)} (the map is in kcd/m^2).",
        "AttributeBegin",
        "  Rotate -90 1 0 0   # the sky's light frame is +z up; this scene is +y up",
        f'  LightSource "infinite" "string filename" ["{env_rel}"] "float scale" [{_fmt(p.scale)}]',
        "AttributeEnd",
    ]
    sun_line = (f'LightSource "distant" "point3 from" [{_fmt(d[0])} {_fmt(d[1])} {_fmt(d[2])}] '
                f'"point3 to" [0 0 0]')
    if p.sun == "rgb":
        lines.append(f'{sun_line}\n    "rgb L" [{" ".join(_fmt(v) for v in strength)}] '
                     f'"float angularradius" [{radius}]')
    else:   # a blackbody L is normalised to luminance 1: scale carries the illuminance (klx)
        lines.append(f'{sun_line}\n    "blackbody L" [{_fmt(p.temperature)}] "float scale" [{_fmt(strength * p.scale)}] '
                     f'"float angularradius" [{radius}]')
    (job.stage / "lights.pbrt").write_text("\n".join(lines) + "\n")
    return ["lights.pbrt"]


GENERATOR = Generator("sky-lights", "lights.pbrt: the generated sky as an infinite light and the sun as a distant one",
                      SkyLightsParams, write, __doc__)
