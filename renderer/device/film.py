"""The film: a running sum of radiance per pixel and the number of samples in it. Passes add into
it; the image is the sum divided by the count.

The sums are exact fixed-point numbers, not floats, so that adding the same samples in any
grouping or order gives the same bits: a render split over processes or machines
(:mod:`renderer.cluster`) equals the one-process render. Each sample (a float32 radiance the
path kernel writes into the float64 ``sample`` scratch) is cut once into a whole part and a
fraction of :data:`FRACTION_BITS` bits, both int64; integers add associatively, so a film is the
same whichever launches, threads or workers formed it. The cut rounds each sample down by less
than 2^-62 (2e-19), far below float32's resolution; a sample of :data:`MAX_SAMPLE` or more would
overflow the whole part over a long render and is dropped and counted like a NaN sample.

Ray counts are kept per pixel: each pixel is written by one thread per pass, so the count is a
plain add, with no atomic (on a GPU, an atomic per thread into one counter per row serialised a
row's threads on one address). Dropped-sample counts are kept per image row (an atomic only when
a sample is dropped): a CPU ``atomic_add`` is a plain read-modify-write, so threads launching
different rows must never add into one counter. The totals are summed on the host."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import warp as wp

#: Bits of a sample's fraction: the unit of the fraction sums is 2^-FRACTION_BITS; a fraction sum
#: stays below 2^63 after adding one more fraction, so a carry never overflows.
FRACTION_BITS = 62
ONE = 1 << FRACTION_BITS
#: Samples at or above this (2^40, about 1.1e12) are dropped: 2^23 spp of them still fit int64.
MAX_SAMPLE = float(1 << 40)

_ONE = wp.constant(wp.int64(ONE))
_SCALE = wp.constant(wp.float64(float(ONE)))
_MAX = wp.constant(wp.float64(MAX_SAMPLE))

wp.set_module_options({"enable_backward": False})   # nothing differentiates a film


@wp.kernel
def accumulate(sample: wp.array(dtype=wp.vec3d), whole: wp.array2d(dtype=wp.int64),
               fraction: wp.array2d(dtype=wp.int64), bad_samples: wp.array(dtype=int), first_row: int, width: int):
    """Move one pass's samples of rows ``first_row``... from ``sample`` into the fixed-point sums."""
    i = first_row * width + wp.tid()
    v = sample[i]
    sample[i] = wp.vec3d(wp.float64(0.0), wp.float64(0.0), wp.float64(0.0))
    if v[0] >= _MAX or v[1] >= _MAX or v[2] >= _MAX:
        wp.atomic_add(bad_samples, i // width, 1)
        return
    for c in range(3):
        w = wp.floor(v[c])
        f = fraction[i, c] + wp.int64((v[c] - w) * _SCALE)   # v - floor(v) and the scaling are exact
        carry = wp.int64(0)
        if f >= _ONE:
            f = f - _ONE
            carry = wp.int64(1)
        fraction[i, c] = f
        whole[i, c] = whole[i, c] + wp.int64(w) + carry


def add_into(whole: np.ndarray, fraction: np.ndarray, part_whole: np.ndarray, part_fraction: np.ndarray) -> None:
    """Add one film's fixed-point sums into another's, in place and exactly (each fraction sum is
    below 2^62, so their sum fits int64 before the carry moves into the whole part)."""
    fraction += part_fraction
    whole += part_whole
    whole += fraction >> FRACTION_BITS
    fraction &= ONE - 1


def fixed_from_float(s: np.ndarray) -> np.ndarray:
    """Float sums ((N, 3), a checkpoint of an earlier version) as fixed-point sums. Sums outside
    [0, 2^63) are refused (ValueError), not saturated: no render makes them (samples are never
    negative, and 2^63 is 2^23 samples at MAX_SAMPLE), int64 cannot hold them (the cast would wrap
    to a negative sum), and a clipped sum would be a wrong image that looks right."""
    s = np.asarray(s, dtype=np.float64)
    if not np.all((s >= 0.0) & (s < 2.0 ** 63)):       # NaN fails both comparisons
        raise ValueError("float film sums must lie in [0, 2^63); these cannot come from a render")
    whole = np.floor(s)
    return np.stack([whole.astype(np.int64), ((s - whole) * float(ONE)).astype(np.int64)], axis=-1)


def image_from_sums(whole: np.ndarray, fraction: np.ndarray, width: int, height: int, spp: int) -> np.ndarray:
    """Linear RGB, float32 (H, W, 3): the mean of the samples in the sums."""
    total = whole.astype(np.float64) + fraction.astype(np.float64) / float(ONE)
    return (total.reshape(height, width, 3) / max(spp, 1)).astype(np.float32)


@dataclass
class Film:
    width: int
    height: int
    device: str
    sample: wp.array = None      # one pass's samples, float64, zero outside a launch
    whole: wp.array = None       # (N, 3) int64
    fraction: wp.array = None    # (N, 3) int64, in units of 2^-FRACTION_BITS
    bad: wp.array = None         # dropped samples per row
    rays: wp.array = None        # rays traced per pixel (int64)
    spp: int = 0

    def __post_init__(self) -> None:
        n = self.width * self.height
        self.sample = wp.zeros(n, dtype=wp.vec3d, device=self.device)
        self.whole = wp.zeros((n, 3), dtype=wp.int64, device=self.device)
        self.fraction = wp.zeros((n, 3), dtype=wp.int64, device=self.device)
        self.bad = wp.zeros(self.height, dtype=int, device=self.device)
        self.rays = wp.zeros(n, dtype=wp.int64, device=self.device)

    def accumulate(self, first_row: int, rows: int) -> None:
        """Add the pass just launched over these rows into the sums."""
        wp.launch(accumulate, dim=rows * self.width, device=self.device,
                  inputs=[self.sample, self.whole, self.fraction, self.bad, first_row, self.width])

    def sums(self) -> np.ndarray:
        """The fixed-point sums, (N, 3, 2) int64 (whole, fraction): what checkpoints and workers hand on."""
        return np.stack([self.whole.numpy(), self.fraction.numpy()], axis=-1)

    def set_sums(self, sums: np.ndarray) -> None:
        self.whole.assign(wp.array(np.ascontiguousarray(sums[..., 0]), dtype=wp.int64, device=self.device))
        self.fraction.assign(wp.array(np.ascontiguousarray(sums[..., 1]), dtype=wp.int64, device=self.device))

    def clear(self) -> None:
        """An empty film (a cluster worker starts each sample range from one)."""
        for a in (self.whole, self.fraction, self.bad, self.rays):
            a.zero_()
        self.spp = 0

    def image(self) -> np.ndarray:
        """Linear RGB, float32 (H, W, 3): the mean of all samples taken so far."""
        return image_from_sums(self.whole.numpy(), self.fraction.numpy(), self.width, self.height, self.spp)

    @property
    def bad_samples(self) -> int:
        """Samples dropped because their radiance was NaN, infinite, negative or beyond MAX_SAMPLE."""
        return int(self.bad.numpy().sum())

    @property
    def ray_count(self) -> float:
        """Rays traced so far (camera, continuation and shadow rays)."""
        return float(self.rays.numpy().sum())

    def set_counts(self, bad_samples: int, rays: float) -> None:
        """Restore the totals of a checkpoint (row and pixel 0 hold them; the others start at zero)."""
        bad = np.zeros(self.height, dtype=np.int32)
        ray = np.zeros(self.width * self.height, dtype=np.int64)
        bad[0], ray[0] = bad_samples, round(rays)
        self.bad.assign(wp.array(bad, dtype=int, device=self.device))
        self.rays.assign(wp.array(ray, dtype=wp.int64, device=self.device))
