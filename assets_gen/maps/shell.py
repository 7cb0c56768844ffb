"""Shell maps in the shell's (u apex-to-margin, v across) parameter square, the UVs
`assets-gen seashell` writes: growth bands (height, m), fine radial ribs or concentric ridges
(bump, m) and the outside's pigment (linear RGB reflectance). Bands and concentric ridges are lines
of constant u, radial ribs and spiral colour bands lines of constant v. The pigment map with the
height map's seed, size, bands and irregularity has its colour bands on the same growth bands."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from assets_gen.core import Generator, Job, Params, param, require
from assets_gen.core.noise import smooth_noise
from assets_gen.core.output import Banded, write_map

#: The largest map side, and so the most bands or ridges a map can show.
MAX_MAP = 16384


def band_edges(count: int, irregularity: float, rng: np.random.Generator) -> np.ndarray:
    """The ``count + 1`` edges in [0, 1] of bands whose widths vary by ``irregularity``
    (gamma-distributed, like growth increments that follow the seasons: 0 gives equal bands)."""
    if irregularity > 0:
        k = 1.0 / irregularity ** 2
        widths = rng.gamma(k, 1.0 / k, size=count)
    else:
        widths = np.ones(count)
    return np.concatenate([[0.0], np.cumsum(widths) / widths.sum()])


def phase_in(t: np.ndarray, edges: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(phase in [0, 1) within its band, band index) for positions t in [0, 1]."""
    count = len(edges) - 1
    idx = np.clip(np.searchsorted(edges, t, side="right") - 1, 0, count - 1)
    phase = (t - edges[idx]) / (edges[idx + 1] - edges[idx])
    return np.clip(phase, 0.0, 1.0 - 1e-12), idx


def banded_phase(t: np.ndarray, count: int, irregularity: float,
                 rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """(phase in [0, 1) within its band, band index) for positions t in [0, 1] cut into ``count``
    bands whose widths vary by ``irregularity``."""
    return phase_in(t, band_edges(count, irregularity, rng))


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


def _shell_wander(p: ShellMapParams, rng: np.random.Generator) -> Callable[[int, int], tuple[np.ndarray, np.ndarray]]:
    """``grid(y0, y1)``: the (u, v) texel centres of rows y0..y1, each coordinate wandered by smooth
    noise so lines are not ruled. The noise is drawn here, once; rows are made on demand, each
    texel as a whole-map grid would have it."""
    u = (np.arange(p.width) + 0.5) / p.width
    v = (np.arange(p.height) + 0.5) / p.height
    wander_u = smooth_noise(rng, (0.0, 0.0), (1.0, 1.0), p.waviness_size)
    wander_v = smooth_noise(rng, (0.0, 0.0), (1.0, 1.0), p.waviness_size)

    def grid(y0: int, y1: int) -> tuple[np.ndarray, np.ndarray]:
        uu, vv = np.meshgrid(u, v[y0:y1])
        return (np.clip(uu + p.waviness * wander_u(uu, vv), 0, 1),
                np.clip(vv + p.waviness * wander_v(uu, vv), 0, 1))

    return grid


def _shell_grid(p: ShellMapParams, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """(u, v) texel centres of the whole map, wandered (see :func:`_shell_wander`)."""
    return _shell_wander(p, rng)(0, p.height)


@dataclass(frozen=True)
class ShellPigmentParams(ShellMapParams):
    bands: int = param(14, "growth bands from apex to margin (as the height map's, to share them)")
    irregularity: float = param(0.35, "relative spread of band widths (as the height map's)")
    spiral_bands: int = param(4, "dark spiral bands across v (lines of constant v)")
    light_lab: tuple[float, float, float] = param((92.0, 3.0, 11.0), "CIELAB of the pale ground colour")
    dark_lab: tuple[float, float, float] = param((48.0, 20.0, 32.0), "CIELAB of the dark pigment")

    def validate(self) -> None:
        super().validate()
        require(1 <= self.bands <= MAX_MAP, f"growth bands must be 1..{MAX_MAP} (one per texel of the largest map)")
        require(0 <= self.irregularity <= 2, "irregularity must be between 0 and 2")
        require(0 <= self.spiral_bands <= 64, "spiral bands must be 0..64")
        for lab in (self.light_lab, self.dark_lab):
            require(len(lab) == 3 and 0 <= lab[0] <= 100, f"a CIELAB colour is (L 0..100, a, b), got {lab}")


def growth_bands(p: ShellHeightParams | ShellPigmentParams,
                 rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(u, v, phase within the band, band index) per texel: the height and pigment maps draw these
    first, so one seed gives both the same bands."""
    u, v = _shell_grid(p, rng)
    phase, idx = banded_phase(u, p.bands, p.irregularity, rng)
    return u, v, phase, idx


def shell_pigment(p: ShellPigmentParams, seed: int) -> np.ndarray:
    """Linear-RGB reflectance (H, W, 3) of the outside: how much pigment each growth band laid down
    (a random share per band, as the mantle's secretion varies with the season), a darker line at
    each growth check, dark spiral bands and a faint mottle, blended between the two CIELAB colours
    (perceptually even steps) and converted with scikit-image."""
    from skimage.color import lab2rgb

    from renderer.color.rgb import srgb_to_linear

    rng = np.random.default_rng(seed)
    u, v, phase, idx = growth_bands(p, rng)
    per_band = rng.beta(1.5, 1.5, size=p.bands)
    check = np.exp(-(phase / 0.05) ** 2) + np.exp(-((1.0 - phase) / 0.03) ** 2)
    offset = rng.uniform(0.0, 1.0)
    spiral = (0.5 + 0.5 * np.cos(2.0 * np.pi * (p.spiral_bands * v + offset))) ** 4 if p.spiral_bands else 0.0 * v
    mottle = smooth_noise(rng, (0.0, 0.0), (1.0, 1.0), 0.03)(u, v)
    dark = np.clip(0.05 + per_band[idx] * (0.15 + 0.85 * spiral) + 0.3 * check + 0.06 * mottle, 0.0, 1.0)
    lab = (1.0 - dark)[..., None] * np.asarray(p.light_lab) + dark[..., None] * np.asarray(p.dark_lab)
    return srgb_to_linear(np.clip(lab2rgb(lab), 0.0, 1.0))


def shell_height(p: ShellHeightParams, seed: int) -> Banded:
    """Height (m) of growth bands: the shell swells across each band and thins again at the growth
    check that ends it; band heights vary like the widths (a good and a poor season). Made a band
    of rows at a time (a 16384-pixel map took 14.8 GB whole), drawing the random numbers in the
    order :func:`growth_bands` does, so the pigment map with the same seed shares the bands."""
    rng = np.random.default_rng(seed)
    grid = _shell_wander(p, rng)
    edges = band_edges(p.bands, p.irregularity, rng)
    amp = p.band_height_mm * 1e-3 * rng.lognormal(0.0, p.irregularity * 0.5, size=p.bands)

    def rows(y0: int, y1: int) -> np.ndarray:
        phase, idx = phase_in(grid(y0, y1)[0], edges)
        return amp[idx] * np.sin(np.pi * phase) ** 2

    return Banded((p.height, p.width), rows)


def shell_bump(p: ShellBumpParams, seed: int) -> Banded:
    """Height (m) of fine regular ridges: |cos|^sharpness peaks, radial (constant v) or concentric
    (constant u); made a band of rows at a time."""
    rng = np.random.default_rng(seed)
    grid = _shell_wander(p, rng)
    edges = band_edges(p.ridges, 0.0, rng)

    def rows(y0: int, y1: int) -> np.ndarray:
        u, v = grid(y0, y1)
        phase, _ = phase_in(v if p.pattern == "radial" else u, edges)
        return p.ridge_height_mm * 1e-3 * np.sin(np.pi * phase) ** p.sharpness

    return Banded((p.height, p.width), rows)


def write_height(job: Job) -> list[str]:
    return write_map(job.stage, "shell_height", shell_height(job.params, job.seed), "m", job.preview)


def write_bump(job: Job) -> list[str]:
    return write_map(job.stage, "shell_bump", shell_bump(job.params, job.seed), "m", job.preview)


def write_pigment(job: Job) -> list[str]:
    """``shell_pigment.exr`` (linear RGB) and optionally its sRGB preview."""
    from PIL import Image

    from renderer.color.rgb import linear_to_srgb
    from renderer.io.images import write_exr

    rgb = shell_pigment(job.params, job.seed)
    write_exr(job.stage / "shell_pigment.exr", rgb.astype(np.float32), {"units": "reflectance"})
    if not job.preview:
        return ["shell_pigment.exr"]
    Image.fromarray((linear_to_srgb(rgb) * 255.0 + 0.5).astype(np.uint8)).save(job.stage / "shell_pigment.png")
    return ["shell_pigment.exr", "shell_pigment.png"]


SHELL_HEIGHT = Generator("shell-height", "shell height map (m) of growth bands in the shell's (u, v) square",
                         ShellHeightParams, write_height, __doc__, previews=True)
SHELL_BUMP = Generator("shell-bump", "shell bump map (m) of fine radial ribs or concentric ridges",
                       ShellBumpParams, write_bump, __doc__, previews=True)
SHELL_PIGMENT = Generator("shell-pigment", "shell pigment map (linear RGB) of growth and spiral colour bands",
                          ShellPigmentParams, write_pigment, __doc__, previews=True)
