"""pbrt-v4's ``goniometric`` light: a point light at the light space's origin whose radiant intensity
is ``I`` (rgb or blackbody) times ``scale`` times a square image over directions in pbrt-v4's
equal-area octahedral layout, looked up at the nearest pixel. The image's one value per pixel is
the average of its R, G and B (or its single channel), as pbrt-v4 reduces it. pbrt-v4 swaps the
light space's y and z before the map: the map's pole (its +z) is the light's +y. ``power`` > 0
rescales ``scale`` by power / (4π × the image's mean), so the light emits that power. Without a
``filename`` pbrt-v4 builds an unusable light from an empty image (a warning); we refuse it.
A delta light: only light sampling finds it.
"""
from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import warp as wp

from renderer.errors import Location, SceneError
from renderer.lights import point
from renderer.lights.images import read_light_image, resolved
from renderer.lights.sample import LightSample
from renderer.lights.table import LightEntry, Lights, Row, colour_parameters, scaled_colour
from renderer.parameters import Parameter, Parameters
from renderer.sampling.equal_area import equal_area_sphere_to_square

if TYPE_CHECKING:
    from renderer.scene.description import LightDesc

NAME = "goniometric"
DIRECTIVE = "LightSource"
PARAMS = Parameters(
    *colour_parameters("I", "radiant intensity, times the image's value"),
    Parameter("power", "float", -1.0, doc="if > 0, the emitted power (pbrt-v4): it rescales scale"),
    Parameter("filename", "string", doc="square equal-area image of relative intensity over directions"),
)
# the position sits where point.sample reads it
ROW = Row(ints=("size",), vecs=point.ROW.names["vecs"])
K = ROW.K
#: pbrt-v4's light-space y/z swap before the equal-area map (a symmetric permutation).
SWAP_YZ = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]])


def check(given: dict[str, Any], light_to_world: np.ndarray, loc: Location | None,
          base_dir: Path | None) -> dict[str, Any]:
    if "filename" not in given:
        raise SceneError('LightSource "goniometric" needs a "filename" (pbrt-v4 renders it from an empty image)', loc)
    return resolved(given, loc, base_dir, "goniometric image")


def diagram(values: dict[str, Any], loc: Location | None) -> np.ndarray:
    """The (N, N) relative intensities: the mean of R, G, B (or the one channel) per pixel."""
    image = read_light_image(values, loc, "goniometric image")
    h, w, c = image.shape
    if w != h:
        raise SceneError(f"goniometric image must be square (equal-area), got {w}x{h}", loc)
    if c == 2 or c > 4:
        raise SceneError(f"goniometric image needs R, G, B or one channel, got {c} channels", loc)
    return image[..., :3].mean(axis=2) if c >= 3 else image[..., 0]


def entry(light: LightDesc, tris: np.ndarray | None) -> LightEntry:
    v = light.values
    y = diagram(v, light.loc)
    R = np.asarray(light.light_to_world, np.float64)[:3, :3] @ SWAP_YZ
    factor = point.power_factor(v, 4.0 * math.pi * float(y.mean(dtype=np.float64)))
    return LightEntry(L=scaled_colour(v, "I", factor), ints={"size": y.shape[0]},
                      vecs={"position": point.position(v, light.light_to_world)},
                      to_world=R, to_light=np.linalg.inv(R), f_data=y.ravel())


@wp.func
def sample(lights: Lights, i: int, p: wp.vec3, u: wp.vec2) -> LightSample:
    s = point.sample(lights, i, p, u)
    if s.pdf > 0.0:
        uv = equal_area_sphere_to_square(wp.normalize(lights.to_light[i] * (-s.wi)))
        n = lights.k[i, K.size]
        x = wp.clamp(int(uv[0] * float(n)), 0, n - 1)
        y = wp.clamp(int(uv[1] * float(n)), 0, n - 1)
        s.L = s.L * lights.f_pool[lights.f_start[i] + y * n + x]
    return s
