"""Shell maps (m) in the shell's (u apex-to-margin, v across) parameter square, the UVs
`assets-gen seashell` writes: growth bands (height) and fine radial ribs or concentric ridges
(bump). Bands and concentric ridges are lines of constant u, radial ribs lines of constant v."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from assets_gen.core import Generator, Job, Params, param, require
from assets_gen.core.noise import smooth_noise
from assets_gen.core.output import write_map

#: The largest map side, and so the most bands or ridges a map can show.
MAX_MAP = 16384


def banded_phase(t: np.ndarray, count: int, irregularity: float,
                 rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """(phase in [0, 1) within its band, band index) for positions t in [0, 1] cut into ``count``
    bands whose widths vary by ``irregularity`` (gamma-distributed, like growth increments that
    follow the seasons: 0 gives equal bands)."""
    if irregularity > 0:
        k = 1.0 / irregularity ** 2
        widths = rng.gamma(k, 1.0 / k, size=count)
    else:
        widths = np.ones(count)
    edges = np.concatenate([[0.0], np.cumsum(widths) / widths.sum()])
    idx = np.clip(np.searchsorted(edges, t, side="right") - 1, 0, count - 1)
    phase = (t - edges[idx]) / (edges[idx + 1] - edges[idx])
    return np.clip(phase, 0.0, 1.0 - 1e-12), idx


@dataclass(frozen=True)
class ShellMapParams(Params):
    width: int = param(1024, "map pixels along u (apex to margin)")
    height: int = param(1024, "map pixels along v (across the shell)")
    waviness: float = param(0.01, "how far band and ridge lines wander, as a fraction of the map")
    waviness_size: float = param(0.1, "feature size of the wander, as a fraction of the map")

    def validate(self) -> None:
        require(8 <= self.width <= MAX_MAP and 8 <= self.height <= MAX_MAP, f"map size must be 8..{MAX_MAP} pixels")
        require(0 <= self.waviness <= 0.2, "waviness must be between 0 and 0.2")
        require(self.waviness_size > 0, "waviness size must be positive")


@dataclass(frozen=True)
class ShellHeightParams(ShellMapParams):
    bands: int = param(14, "growth bands from apex to margin")
    band_height_mm: float = param(0.3, "shell thickening across one growth band, mm")
    irregularity: float = param(0.35, "relative spread of band widths and heights (0 = regular)")

    def validate(self) -> None:
        super().validate()
        require(1 <= self.bands <= MAX_MAP, f"growth bands must be 1..{MAX_MAP} (one per texel of the largest map)")
        require(self.band_height_mm >= 0, "band height must be non-negative (mm)")
        require(0 <= self.irregularity <= 2, "irregularity must be between 0 and 2")


@dataclass(frozen=True)
class ShellBumpParams(ShellMapParams):
    pattern: str = param("radial", "ridges along the growth direction (radial ribs) or across it "
                         "(concentric growth lines)", choices=("radial", "concentric"))
    ridges: int = param(60, "number of ridges across the map")
    ridge_height_mm: float = param(0.05, "ridge height, mm")
    sharpness: float = param(4.0, "ridge profile exponent: 1 rounded, larger = narrow crests")

    def validate(self) -> None:
        super().validate()
        require(1 <= self.ridges <= MAX_MAP, f"ridges must be 1..{MAX_MAP} (one per texel of the largest map)")
        require(self.ridge_height_mm >= 0, "ridge height must be non-negative (mm)")
        require(self.sharpness >= 1, "sharpness must be at least 1")


def _shell_grid(p: ShellMapParams, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """(u, v) texel centres, each coordinate wandered by smooth noise so lines are not ruled."""
    u = (np.arange(p.width) + 0.5) / p.width
    v = (np.arange(p.height) + 0.5) / p.height
    uu, vv = np.meshgrid(u, v)
    wander_u = smooth_noise(rng, (0.0, 0.0), (1.0, 1.0), p.waviness_size)
    wander_v = smooth_noise(rng, (0.0, 0.0), (1.0, 1.0), p.waviness_size)
    return (np.clip(uu + p.waviness * wander_u(uu, vv), 0, 1),
            np.clip(vv + p.waviness * wander_v(uu, vv), 0, 1))


def shell_height(p: ShellHeightParams, seed: int) -> np.ndarray:
    """Height (m) of growth bands: the shell swells across each band and thins again at the growth
    check that ends it; band heights vary like the widths (a good and a poor season)."""
    rng = np.random.default_rng(seed)
    u, _ = _shell_grid(p, rng)
    phase, idx = banded_phase(u, p.bands, p.irregularity, rng)
    amp = p.band_height_mm * 1e-3 * rng.lognormal(0.0, p.irregularity * 0.5, size=p.bands)
    return amp[idx] * np.sin(np.pi * phase) ** 2


def shell_bump(p: ShellBumpParams, seed: int) -> np.ndarray:
    """Height (m) of fine regular ridges: |cos|^sharpness peaks, radial (constant v) or concentric
    (constant u)."""
    rng = np.random.default_rng(seed)
    u, v = _shell_grid(p, rng)
    t = v if p.pattern == "radial" else u
    phase, _ = banded_phase(t, p.ridges, 0.0, rng)
    return p.ridge_height_mm * 1e-3 * np.sin(np.pi * phase) ** p.sharpness


def write_height(job: Job) -> list[str]:
    return write_map(job.stage, "shell_height", shell_height(job.params, job.seed), "m", job.preview)


def write_bump(job: Job) -> list[str]:
    return write_map(job.stage, "shell_bump", shell_bump(job.params, job.seed), "m", job.preview)


SHELL_HEIGHT = Generator("shell-height", "shell height map (m) of growth bands in the shell's (u, v) square",
                         ShellHeightParams, write_height, __doc__, previews=True)
SHELL_BUMP = Generator("shell-bump", "shell bump map (m) of fine radial ribs or concentric ridges",
                       ShellBumpParams, write_bump, __doc__, previews=True)
