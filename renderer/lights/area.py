"""pbrt-v4's ``diffuse`` area light (``AreaLightSource "diffuse"``): the shapes that follow emit
radiance ``L`` from their front side (both with ``twosided``). Sampled by area, triangles chosen
in proportion to their area, so every instance of an emissive shape is one light.

``power`` > 0 is pbrt-v4's: it multiplies ``scale`` by power / (π × area × 2 if two-sided) for the
area of one pbrt-v4 shape, so that shape emits that power (an rgb ``L`` keeps its own magnitude, a
blackbody has luminance 1). For a sphere, disk or cylinder that is its exact area in object space
(pbrt-v4's Shape::Area ignores the transform's scale); in a triangle or bilinear mesh pbrt-v4
makes every triangle or patch a light of that power, which we reproduce with the mean triangle or
patch area (exact for equal ones, such as a quad's two triangles; with unequal ones pbrt-v4's
radiance differs per triangle).
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import warp as wp

from renderer.lights import point
from renderer.lights.sample import LightEval, LightSample
from renderer.lights.table import LightEntry, Lights, Row, colour_parameters, scaled_colour
from renderer.parameters import Parameter, Parameters
from renderer.sampling.distribution import sample_cdf

if TYPE_CHECKING:
    from renderer.scene.description import LightDesc

NAME = "diffuse"
DIRECTIVE = "AreaLightSource"
PARAMS = Parameters(
    *colour_parameters("L", "emitted radiance"),
    Parameter("twosided", "bool", False, doc="emit from both sides, not only along the normal"),
    Parameter("power", "float", -1.0, doc="if > 0, the power (W) each pbrt-v4 shape emits: it rescales scale"),
)
ROW = Row(floats=("area",), ints=("triangles", "two_sided"))
F, K = ROW.F, ROW.K


def entry(light: LightDesc, tris: np.ndarray | None, shape_area: float | None = None) -> LightEntry | None:
    """``tris``: (T, 3, 3) world-space triangles with outward winding; ``shape_area``: the area of
    one of pbrt-v4's shapes (above; None: the mean triangle's). Triangles without area are never
    sampled; a shape with no area at all is no light (None)."""
    areas = 0.5 * np.linalg.norm(np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0]), axis=1)
    total = float(areas.sum())
    keep = areas > 0
    tris, areas = tris[keep], areas[keep]
    if total <= 0 or len(tris) == 0:
        return None
    cdf = np.concatenate([[0.0], np.cumsum(areas) / total]).astype(np.float32)
    cdf[-1] = 1.0
    v = light.values
    k_e = np.pi * (2.0 if v["twosided"] else 1.0) * (total / len(areas) if shape_area is None else shape_area)
    return LightEntry(L=scaled_colour(v, "L", point.power_factor(v, k_e)), floats={"area": total},
                      ints={"triangles": len(tris), "two_sided": int(v["twosided"])},
                      f_data=cdf, v_data=np.asarray(tris, dtype=np.float32).reshape(-1, 3))


# ---- device ---------------------------------------------------------------------------------------

@wp.func
def _pdf(lights: Lights, i: int, p_ref: wp.vec3, p_light: wp.vec3, n_light: wp.vec3) -> float:
    """Solid-angle density at p_ref of area-sampling light i at p_light."""
    d = p_light - p_ref
    dist2 = wp.dot(d, d)
    c = wp.abs(wp.dot(n_light, d)) / wp.sqrt(dist2)
    if c <= 0.0:
        return 0.0
    return dist2 / (c * lights.f[i, F.area])


@wp.func
def _radiance(lights: Lights, i: int, n_light: wp.vec3, w_out: wp.vec3) -> wp.vec3:
    """Radiance leaving the light with normal n_light in direction w_out."""
    if lights.k[i, K.two_sided] == 0 and wp.dot(n_light, w_out) <= 0.0:
        return wp.vec3(0.0)
    return lights.L[i]


@wp.func
def emitted(lights: Lights, i: int, p_ref: wp.vec3, p: wp.vec3, n: wp.vec3, w_out: wp.vec3) -> LightEval:
    """What a ray from p_ref finds on this light at p (normal n), leaving towards w_out."""
    ev = LightEval()
    ev.L = _radiance(lights, i, n, w_out)
    ev.pdf = _pdf(lights, i, p_ref, p, n)
    return ev


@wp.func
def sample(lights: Lights, i: int, p: wp.vec3, u: wp.vec2) -> LightSample:
    cnt = lights.k[i, K.triangles]
    tv = sample_cdf(lights.f_pool, lights.f_start[i], cnt, u[0])
    t = lights.v_start[i] + 3 * int(tv[1])
    # reuse the remainder of u[0] within the chosen triangle's CDF cell
    u0 = tv[0] * float(cnt) - tv[1]
    su = wp.sqrt(wp.clamp(u0, 0.0, 1.0))
    b0 = 1.0 - su
    b1 = u[1] * su
    a = lights.v_pool[t]
    b = lights.v_pool[t + 1]
    c = lights.v_pool[t + 2]
    q = a * b0 + b * b1 + c * (1.0 - b0 - b1)
    nl = wp.normalize(wp.cross(b - a, c - a))
    d = q - p
    dist = wp.length(d)
    s = LightSample()
    s.delta = False
    if dist <= 0.0:
        s.pdf = 0.0
        return s
    s.wi = d / dist
    s.dist = dist
    s.L = _radiance(lights, i, nl, -s.wi)
    s.pdf = _pdf(lights, i, p, q, nl)
    return s
