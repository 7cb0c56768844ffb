"""The film: a running sum of radiance per pixel (float64) and the number of samples in it.
Passes add into it; the image is the sum divided by the count."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import warp as wp


@dataclass
class Film:
    width: int
    height: int
    device: str
    sum: wp.array = None
    bad: wp.array = None
    rays: wp.array = None
    spp: int = 0

    def __post_init__(self) -> None:
        self.sum = wp.zeros(self.width * self.height, dtype=wp.vec3d, device=self.device)
        self.bad = wp.zeros(1, dtype=int, device=self.device)
        self.rays = wp.zeros(1, dtype=wp.float64, device=self.device)

    def image(self) -> np.ndarray:
        """Linear RGB, float32 (H, W, 3): the mean of all samples taken so far."""
        s = self.sum.numpy().reshape(self.height, self.width, 3)
        return (s / max(self.spp, 1)).astype(np.float32)

    @property
    def bad_samples(self) -> int:
        """Samples dropped because their radiance was NaN, infinite or negative."""
        return int(self.bad.numpy()[0])

    @property
    def ray_count(self) -> float:
        """Rays traced so far (camera, continuation and shadow rays)."""
        return float(self.rays.numpy()[0])
