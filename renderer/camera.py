"""pbrt's ``perspective`` camera with a thin lens: fov on the shorter image axis, raster +x to
the right and +y down, camera space looking down +z with +y up."""
from __future__ import annotations

import math

import numpy as np
import warp as wp

from renderer.sampling.warps import concentric_disk
from renderer.scene.description import CameraDesc


@wp.struct
class Camera:
    to_world: wp.mat44
    screen: wp.vec4           # (x min, x max, y min, y max) of the screen window times tan(fov/2)
    lens_radius: float
    focal_distance: float
    width: int
    height: int


@wp.struct
class Ray:
    o: wp.vec3
    d: wp.vec3


@wp.func
def generate_ray(cam: Camera, px: float, py: float, u_lens: wp.vec2) -> Ray:
    """The world-space ray through raster point (px, py), refocused through a point on the lens."""
    sx = cam.screen[0] + (cam.screen[1] - cam.screen[0]) * (px / float(cam.width))
    sy = cam.screen[3] - (cam.screen[3] - cam.screen[2]) * (py / float(cam.height))
    d = wp.normalize(wp.vec3(sx, sy, 1.0))
    o = wp.vec3(0.0)
    if cam.lens_radius > 0.0:
        lens = concentric_disk(u_lens) * cam.lens_radius
        focus = d * (cam.focal_distance / d[2])
        o = wp.vec3(lens[0], lens[1], 0.0)
        d = wp.normalize(focus - o)
    r = Ray()
    r.o = wp.transform_point(cam.to_world, o)
    r.d = wp.normalize(wp.transform_vector(cam.to_world, d))
    return r


def build_camera(desc: CameraDesc, width: int, height: int) -> Camera:
    c = Camera()
    c.to_world = wp.mat44(*np.asarray(desc.camera_to_world, dtype=np.float32).ravel())
    aspect = width / height
    t = math.tan(math.radians(desc.fov_deg) / 2.0)
    if aspect >= 1.0:
        c.screen = wp.vec4(-aspect * t, aspect * t, -t, t)
    else:
        c.screen = wp.vec4(-t, t, -t / aspect, t / aspect)
    c.lens_radius = float(desc.lens_radius)
    c.focal_distance = float(desc.focal_distance)
    c.width = int(width)
    c.height = int(height)
    return c
