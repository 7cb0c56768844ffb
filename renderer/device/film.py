"""The film: a running sum of radiance per pixel (float64) and the number of samples in it.
Passes add into it; the image is the sum divided by the count. The ray and dropped-sample counts
are kept per image row: a CPU ``atomic_add`` is a plain read-modify-write, so threads launching
different rows must never add into one counter; each row is written by one launch per pass and
the totals are summed on the host."""
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
        self.bad = wp.zeros(self.height, dtype=int, device=self.device)
        self.rays = wp.zeros(self.height, dtype=wp.float64, device=self.device)

    def image(self) -> np.ndarray:
        """Linear RGB, float32 (H, W, 3): the mean of all samples taken so far."""
        s = self.sum.numpy().reshape(self.height, self.width, 3)
        return (s / max(self.spp, 1)).astype(np.float32)

    @property
    def bad_samples(self) -> int:
        """Samples dropped because their radiance was NaN, infinite or negative."""
        return int(self.bad.numpy().sum())

    @property
    def ray_count(self) -> float:
        """Rays traced so far (camera, continuation and shadow rays)."""
        return float(self.rays.numpy().sum())   # whole numbers below 2**53: the sum is exact

    def set_counts(self, bad_samples: int, rays: float) -> None:
        """Restore the totals of a checkpoint (row 0 holds them; the other rows start at zero)."""
        bad = np.zeros(self.height, dtype=np.int32)
        ray = np.zeros(self.height, dtype=np.float64)
        bad[0], ray[0] = bad_samples, rays
        self.bad.assign(wp.array(bad, dtype=int, device=self.device))
        self.rays.assign(wp.array(ray, dtype=wp.float64, device=self.device))
