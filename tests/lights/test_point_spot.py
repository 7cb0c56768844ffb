"""pbrt-v4's point and spot lights against the inverse-square law: a diffuse plane of albedo 1 at
distance h below a light of intensity I has radiance I cos θ / (π r²) = I h / (π r³), times the
spot's smoothstep falloff; "from", the CTM, "scale" and "power" place and scale the light as
pbrt-v4 does."""
from __future__ import annotations

import math

import numpy as np
import pytest

import renderer
from renderer.lights import light
from renderer.materials import material
from renderer.scene.description import MeshDesc
from renderer.scene.transform import translate
from scenes_py import look_at, single_object_scene

H = 1.0          # the light's height above the plane
EYE = 3.0        # the camera's height, looking straight down
FOV = 40.0
RES = 16
SPP = 256


def _plane_radius(n: int = 32) -> np.ndarray:
    """(RES, RES, n²) distance from the axis of the plane points that n x n subsamples of each
    pixel see."""
    t = math.tan(math.radians(FOV) / 2)
    sub = (np.arange(n) + 0.5) / n
    x = (np.arange(RES)[:, None] + sub[None, :]).ravel() / RES * 2 * t - t     # screen coordinate, pixel-major
    sx, sy = np.meshgrid(x, x, indexing="xy")
    r = EYE * np.hypot(sx, sy)                                                 # (RES n, RES n)
    return r.reshape(RES, n, RES, n).transpose(0, 2, 1, 3).reshape(RES, RES, n * n)


def _assert_matches(img: np.ndarray, sub: np.ndarray) -> None:
    """Each pixel against its expectation (the mean over its subsamples), within 5 standard errors
    of the pixel jitter (the only noise here) plus 1%."""
    expected = sub.mean(axis=2)
    tol = 5 * sub.std(axis=2) / math.sqrt(SPP) + 0.01 * expected + 1e-6
    bad = np.abs(img[..., 1] - expected) > tol
    assert not bad.any(), (img[..., 1][bad], expected[bad], tol[bad])
    np.testing.assert_array_equal(img[..., 0], img[..., 2])              # a grey light stays grey


def _render(lamp) -> np.ndarray:
    plane = MeshDesc(positions=np.array([[-9, -9, 0], [9, -9, 0], [9, 9, 0], [-9, 9, 0]], np.float32),
                     indices=np.array([[0, 1, 2], [0, 2, 3]], np.int32))
    desc = single_object_scene(material("diffuse", reflectance=(1.0, 1.0, 1.0)), mesh=plane, res=RES, fov=FOV)
    desc.camera.camera_to_world = look_at((0, 0, EYE), (0, 0, 0), (0, 1, 0))
    desc.lights = [lamp]
    desc.integrator.max_depth = 1
    return renderer.render(desc, spp=SPP)


def _smoothstep(x, a, b):
    t = np.clip((x - a) / (b - a), 0.0, 1.0)
    return t * t * (3 - 2 * t)


@pytest.mark.parametrize("lamp", [
    light("point", I=(2.0, 2.0, 2.0), from_=(0.0, 0.0, H)),
    light("point", translate(np.array([0.25, -0.5, 0.0])), I=1.0, scale=2.0, from_=(-0.25, 0.5, H)),
    light("point", I=(1.0, 1.0, 1.0), power=8 * math.pi, from_=(0.0, 0.0, H)),     # power / 4π = 2
], ids=["I", "ctm-scale", "power"])
def test_point_light_irradiance_is_inverse_square(lamp):
    img = _render(lamp)
    r = _plane_radius()
    _assert_matches(img, 2.0 * H / (math.pi * (r * r + H * H) ** 1.5))


def test_spot_light_falls_off_as_pbrt_smoothstep():
    """Within 20° the spot is the point light, beyond 30° it is dark, between it follows pbrt-v4's
    smoothstep in cos θ; with power, k_e = 2π((1 - cos 20°) + (cos 20° - cos 30°) / 2)."""
    c_end, c_start = math.cos(math.radians(30)), math.cos(math.radians(20))
    k_e = 2 * math.pi * ((1 - c_start) + (c_start - c_end) / 2)
    lamp = light("spot", I=(1.0, 1.0, 1.0), power=2.0 * k_e, from_=(0, 0, H), to=(0, 0, 0), coneangle=30.0,
                 conedeltaangle=10.0)
    img = _render(lamp)
    r = _plane_radius()
    d = np.sqrt(r * r + H * H)
    _assert_matches(img, 2.0 * H / (math.pi * d ** 3) * _smoothstep(H / d, c_end, c_start))
    assert img[0, 0, 1] == 0.0 and img[RES // 2, RES // 2, 1] > 0.5     # the corners lie outside the cone
