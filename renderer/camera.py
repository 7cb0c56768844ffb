"""pbrt's ``perspective`` camera with a thin lens (fov on the shorter image axis), its
``orthographic`` one and its ``spherical`` one (equal-area or equirectangular, the whole sphere of
directions over the image); raster +x to the right and +y down, camera space looking down +z with +y up,
pbrt's screen window (from the frame aspect ratio, or given). The camera also carries what the
film does per sample (the pixel filter, the sensor's clamp) and the rendered region: with a crop
window the kernel's pixels are the region's, offset by ``origin`` into the full image."""
from __future__ import annotations

import math

import numpy as np
import warp as wp

from renderer.pixel_filter import PixelFilter, build_pixel_filter
from renderer.sampling.equal_area import equal_area_square_to_sphere
from renderer.sampling.warps import concentric_disk
from renderer.scene.description import CameraDesc, FilmDesc
from renderer.scene.imaging import film_region
from renderer.sensor import Sensor, build_sensor


PERSPECTIVE, ORTHOGRAPHIC, EQUAL_AREA, EQUIRECTANGULAR = range(4)
#: CameraDesc.projection -> the device's number
PROJECTIONS = {"perspective": PERSPECTIVE, "orthographic": ORTHOGRAPHIC, "spherical equalarea": EQUAL_AREA,
               "spherical equirectangular": EQUIRECTANGULAR}


@wp.struct
class Camera:
    to_world: wp.mat44
    screen: wp.vec4           # (x min, x max, y min, y max) of the screen window times tan(fov/2)
    lens_radius: float
    focal_distance: float
    projection: int           # PERSPECTIVE, ORTHOGRAPHIC, EQUAL_AREA or EQUIRECTANGULAR
    width: int                # the rendered region's size (the whole image unless cropped)
    height: int
    origin: wp.vec2           # the region's first pixel in the full image
    full: wp.vec2             # the full image's resolution
    filter: PixelFilter
    sensor: Sensor


@wp.struct
class Ray:
    o: wp.vec3
    d: wp.vec3


@wp.func
def generate_ray(cam: Camera, px: float, py: float, u_lens: wp.vec2) -> Ray:
    """The world-space ray through raster point (px, py), refocused through a point on the lens."""
    sx = cam.screen[0] + (cam.screen[1] - cam.screen[0]) * ((px + cam.origin[0]) / cam.full[0])
    sy = cam.screen[3] - (cam.screen[3] - cam.screen[2]) * ((py + cam.origin[1]) / cam.full[1])
    if cam.projection == ORTHOGRAPHIC:
        return _orthographic_ray(cam, sx, sy, u_lens)
    if cam.projection >= EQUAL_AREA:
        return _spherical_ray(cam, (px + cam.origin[0]) / cam.full[0], (py + cam.origin[1]) / cam.full[1])
    d = wp.normalize(wp.vec3(sx, sy, 1.0))
    return _through_lens(cam, wp.vec3(0.0), d, d * (cam.focal_distance / d[2]), u_lens)


@wp.func
def _orthographic_ray(cam: Camera, sx: float, sy: float, u_lens: wp.vec2) -> Ray:
    """pbrt-v4's orthographic ray; with a lens it leaves the lens point (around the camera's
    origin, as pbrt writes it) towards the screen point's place on the plane of focus."""
    o = wp.vec3(sx, sy, 0.0)
    d = wp.vec3(0.0, 0.0, 1.0)
    return _through_lens(cam, o, d, o + d * cam.focal_distance, u_lens)


@wp.func
def _through_lens(cam: Camera, o: wp.vec3, d: wp.vec3, focus: wp.vec3, u_lens: wp.vec2) -> Ray:
    """The camera-space ray (o, d) in world space; with a thin lens it starts at a lens point and
    passes through ``focus``, where (o, d) meets the plane of focus."""
    start = o
    direction = d
    if cam.lens_radius > 0.0:
        lens = concentric_disk(u_lens) * cam.lens_radius
        start = wp.vec3(lens[0], lens[1], 0.0)
        direction = wp.normalize(focus - start)
    r = Ray()
    r.o = wp.transform_point(cam.to_world, start)
    r.d = wp.normalize(wp.transform_vector(cam.to_world, direction))
    return r


@wp.func
def _spherical_ray(cam: Camera, u: float, v: float) -> Ray:
    """pbrt-v4's spherical camera: the image's (u, v) in [0, 1]^2 to a direction (equal-area,
    with pbrt's mirroring of points just outside the square, or equirectangular), y and z swapped."""
    d = wp.vec3(0.0)
    if cam.projection == EQUAL_AREA:
        if u < 0.0:
            u = -u
            v = 1.0 - v
        elif u > 1.0:
            u = 2.0 - u
            v = 1.0 - v
        if v < 0.0:
            u = 1.0 - u
            v = -v
        elif v > 1.0:
            u = 1.0 - u
            v = 2.0 - v
        d = equal_area_square_to_sphere(wp.vec2(u, v))
    else:
        theta = wp.pi * v
        phi = 2.0 * wp.pi * u
        d = wp.vec3(wp.sin(theta) * wp.cos(phi), wp.sin(theta) * wp.sin(phi), wp.cos(theta))
    r = Ray()
    r.o = wp.transform_point(cam.to_world, wp.vec3(0.0))
    r.d = wp.normalize(wp.transform_vector(cam.to_world, wp.vec3(d[0], d[2], d[1])))
    return r


def build_camera(desc: CameraDesc, film: FilmDesc, width: int, height: int, device: str) -> tuple[Camera, list]:
    """The camera for a ``width`` x ``height`` image, cropped as the film says; with the arrays it
    points into (keep them alive)."""
    c = Camera()
    c.to_world = wp.mat44(*np.asarray(desc.camera_to_world, dtype=np.float32).ravel())
    aspect = desc.frame_aspect or width / height
    ortho = desc.projection == "orthographic"
    t = 1.0 if ortho else math.tan(math.radians(desc.fov_deg) / 2.0)
    if desc.screen_window is not None:
        x0, x1, y0, y1 = desc.screen_window
        c.screen = wp.vec4(x0 * t, x1 * t, y0 * t, y1 * t)
    elif aspect >= 1.0:
        c.screen = wp.vec4(-aspect * t, aspect * t, -t, t)
    else:
        c.screen = wp.vec4(-t, t, -t / aspect, t / aspect)
    c.projection = PROJECTIONS[desc.projection]
    c.lens_radius = float(desc.lens_radius)
    c.focal_distance = float(desc.focal_distance)
    x0, x1, y0, y1 = film_region(film, width, height)
    c.width, c.height = x1 - x0, y1 - y0
    c.origin = wp.vec2(float(x0), float(y0))
    c.full = wp.vec2(float(width), float(height))
    c.filter, keep = build_pixel_filter(film.filter, device)
    c.sensor = build_sensor(film, desc)
    return c, keep
