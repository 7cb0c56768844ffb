"""What a beach sand's grains are made of, and where on the ripples each kind lies.

Four grain classes with their number fractions (sources and ranges in docs/assets.md): quartz
(clear to pale, glossy), feldspar (pink to cream), heavy minerals (magnetite and ilmenite, near
black) and shell fragments (white carbonate, flat). Wind sorts them over the ripples: the dense
heavy minerals lag in the troughs, and the coarsest grains collect on the crests (Bagnold 1941,
ch. 10; Anderson & Bunas 1993). Both are modelled as an acceptance probability for a proposed
position: 1/2 (1 + k c) with c in [-1, 1] the ripple phase (crest +1, trough -1) read from the
ripple displacement map, k = -heavy_trough_bias for heavy minerals and size_crest_bias x the
grain's size rank (ln d in units of sigma_ln, clipped to [-1, 1]) for the others. Classes and
diameters are drawn before placement and every grain is placed, so the fractions and the
lognormal size distribution stay exact; only the positions are sorted.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from assets_gen.core import reading, require


@dataclass(frozen=True)
class GrainClass:
    name: str
    jitter: float        # radial roughness, times the generator's shape jitter (feldspar: angular)
    elongation: float    # axis shortening, times the generator's elongation
    flatness: float      # thickness / width of the shape (1: equant)


#: The classes in ``kind`` order; their fractions are the grain generator's parameters.
CLASSES = (GrainClass("quartz", 1.0, 1.0, 1.0), GrainClass("feldspar", 1.5, 1.2, 0.8),
           GrainClass("heavy", 0.75, 0.8, 1.0), GrainClass("shell", 1.25, 0.8, 0.3))
HEAVY = 2


def draw_classes(rng: np.random.Generator, n: int, fractions: tuple[float, ...]) -> np.ndarray:
    """(n,) uint8 class of every grain, drawn with the given number fractions."""
    f = np.asarray(fractions, dtype=np.float64)
    require(len(f) == len(CLASSES) and (f >= 0).all() and abs(f.sum() - 1.0) < 1e-6,
            f"need {len(CLASSES)} class fractions >= 0 summing to 1 ({', '.join(c.name for c in CLASSES)})")
    return rng.choice(len(CLASSES), size=n, p=f / f.sum()).astype(np.uint8)


class RipplePhase:
    """Ripple phase c in [-1, 1] (crest +1, trough -1) at world (x, z), from a displacement map
    written by ``assets-gen ripples`` (metres over the dune extent in its header)."""

    def __init__(self, path: str | Path):
        from renderer.io.images import read_exr

        require(Path(path).is_file(), f"ripple map {str(path)!r} not found")
        with reading(path, "ripple displacement map"):
            chans, header = read_exr(path)
        require("Y" in chans and all(k in header for k in ("x0", "x1", "z0", "z1")),
                f"{path} is not a ripple displacement map (needs channel Y and x0/x1/z0/z1 in its header)")
        self.map = chans["Y"].astype(np.float64)
        self.box = tuple(float(header[k]) for k in ("x0", "x1", "z0", "z1"))
        self.half_height = max(float(np.abs(self.map).max()), 1e-12)

    def __call__(self, x: np.ndarray, z: np.ndarray) -> np.ndarray:
        from scipy import ndimage

        x0, x1, z0, z1 = self.box
        nz, nx = self.map.shape
        coords = np.stack([(z - z0) / (z1 - z0) * nz - 0.5, (x - x0) / (x1 - x0) * nx - 0.5])
        d = ndimage.map_coordinates(self.map, coords, order=1, mode="nearest")
        return np.clip(d / self.half_height, -1.0, 1.0)


def acceptance(phase: np.ndarray, kind: np.ndarray, size_rank: np.ndarray, heavy_trough_bias: float,
               size_crest_bias: float) -> np.ndarray:
    """Probability of keeping a proposed position at ripple phase ``phase`` (see the module text)."""
    k = np.where(kind == HEAVY, -heavy_trough_bias, size_crest_bias * np.clip(size_rank, -1.0, 1.0))
    return 0.5 * (1.0 + k * phase)
