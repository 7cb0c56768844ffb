"""The pinhole camera grain placement needs: where it is, what it sees (frustum), and how big a
pixel is at a given depth. Same conventions as the renderer's perspective camera (pbrt's): camera
space looks down +z with +y up, fov on the shorter image axis."""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from assets_gen.core.params import GeneratorError, require


@dataclass(frozen=True)
class PinholeCamera:
    camera_to_world: np.ndarray     # (4, 4)
    fov_deg: float                  # on the shorter image axis
    width: int
    height: int

    def __post_init__(self) -> None:
        require(0 < self.fov_deg < 180, "camera fov must be between 0 and 180 degrees")
        require(self.width > 0 and self.height > 0, "film resolution must be positive")

    @classmethod
    def from_look_at(cls, position: tuple[float, float, float], target: tuple[float, float, float],
                     up: tuple[float, float, float], fov_deg: float, width: int, height: int) -> PinholeCamera:
        from renderer.scene.transform import world_from_camera

        try:
            camera_to_world = world_from_camera(position, target, up)
        except ValueError as e:
            raise GeneratorError(f"camera: {e}") from None
        return cls(camera_to_world, fov_deg, width, height)

    @classmethod
    def from_scene(cls, path: str | Path) -> PinholeCamera:
        """The camera and film of a pbrt-v4 scene file, through the renderer's own parser."""
        require(Path(path).is_file(), f"scene file {str(path)!r} not found")
        from renderer.scene import load_description

        desc = load_description(path)
        require(desc.camera.projection == "perspective" and desc.camera.screen_window is None,
                f"{path}: the grain generator sizes grains for a perspective camera with pbrt's default screen "
                f"window, not a {desc.camera.projection} one")
        return cls(np.asarray(desc.camera.camera_to_world, dtype=np.float64), float(desc.camera.fov_deg),
                   int(desc.film.width), int(desc.film.height))

    @property
    def position(self) -> np.ndarray:
        return self.camera_to_world[:3, 3].copy()

    @property
    def screen_half_extent(self) -> tuple[float, float]:
        """Half width and height of the image at unit depth (pbrt's screen window times tan)."""
        t = math.tan(math.radians(self.fov_deg) / 2)
        aspect = self.width / self.height
        return (aspect * t, t) if aspect >= 1 else (t, t / aspect)

    @property
    def pixel_pitch(self) -> float:
        """Side of one pixel at unit depth: a thing of size s at depth z spans s / (z * pitch) pixels."""
        return 2.0 * math.tan(math.radians(self.fov_deg) / 2) / min(self.width, self.height)

    def to_camera(self, points: np.ndarray) -> np.ndarray:
        """World points (N, 3) into camera space (N, 3)."""
        m = self.camera_to_world
        return (np.asarray(points, dtype=np.float64) - m[:3, 3]) @ m[:3, :3]

    def to_raster(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(raster xy (N, 2) with +x right and +y down, depth (N,)) of world points."""
        c = self.to_camera(points)
        sx, sy = self.screen_half_extent
        z = c[:, 2]
        with np.errstate(divide="ignore", invalid="ignore"):
            px = (c[:, 0] / z + sx) / (2 * sx) * self.width
            py = (sy - c[:, 1] / z) / (2 * sy) * self.height
        return np.stack([px, py], axis=1), z

    def in_frustum(self, points: np.ndarray) -> np.ndarray:
        """Which world points project inside the image, in front of the camera."""
        xy, z = self.to_raster(points)
        return (z > 0) & (xy[:, 0] >= 0) & (xy[:, 0] <= self.width) & (xy[:, 1] >= 0) & (xy[:, 1] <= self.height)

    def max_depth_for_coverage(self, diameter: float, pixel_fraction: float) -> float:
        """Deepest camera depth at which a sphere of ``diameter`` still covers ``pixel_fraction``
        of a pixel's area (its disc of area pi d^2 / 4, projected at that depth)."""
        return diameter / (self.pixel_pitch * math.sqrt(4.0 * pixel_fraction / math.pi))

    def frustum_planes(self, max_depth: float) -> np.ndarray:
        """(6, 4) camera-space half-spaces a.p + b <= 0 bounding the view out to ``max_depth``."""
        sx, sy = self.screen_half_extent
        return np.array([[1.0, 0.0, -sx, 0.0], [-1.0, 0.0, -sx, 0.0],
                         [0.0, 1.0, -sy, 0.0], [0.0, -1.0, -sy, 0.0],
                         [0.0, 0.0, -1.0, 0.0], [0.0, 0.0, 1.0, -max_depth]])

