"""A participating medium as plain Python: what ``MakeNamedMedium`` describes, with pbrt-v4's
defaults resolved and its grids validated, before anything is uploaded. Nothing here knows Warp.

Coefficients are linear sRGB per unit of world distance (pbrt-v4's render space: a medium's
transform moves and scales where its grid lies, not its coefficients). Grids are stored as pbrt
reads them: ``density[z, y, x]`` over the box [p0, p1] of the medium's own space, sample (x, y, z)
at the centre of its cell, trilinear in between and zero outside the samples (SampledGrid)."""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from renderer.errors import Location

#: pbrt-v4's medium types, in the order the device numbers them.
KINDS = ("homogeneous", "uniformgrid", "rgbgrid", "cloud", "nanovdb")


@dataclass
class MediumDesc:
    kind: str                                   # one of KINDS
    name: str
    loc: Location | None = None
    medium_to_world: np.ndarray = field(default_factory=lambda: np.eye(4))   # the CTM at MakeNamedMedium
    sigma_a: np.ndarray = field(default_factory=lambda: np.ones(3))          # already times "scale"
    sigma_s: np.ndarray = field(default_factory=lambda: np.ones(3))
    g: float = 0.0                              # Henyey-Greenstein asymmetry
    Le: np.ndarray = field(default_factory=lambda: np.zeros(3))              # emitted radiance, times Lescale
    p0: np.ndarray = field(default_factory=lambda: np.zeros(3))              # grid and cloud bounds, medium space
    p1: np.ndarray = field(default_factory=lambda: np.ones(3))
    #: uniformgrid: (nz, ny, nx) density; its optional (nz, ny, nx) Lescale grid (None: 1 everywhere)
    density: np.ndarray | None = None
    le_scale_grid: np.ndarray | None = None
    #: uniformgrid: a (nz, ny, nx) temperature grid (kelvin) emitting pbrt's peak-normalised
    #: blackbody at (T - offset) * scale where that exceeds 100 K (instead of Le)
    temperature: np.ndarray | None = None
    temperature_offset: float = 0.0
    temperature_scale: float = 1.0
    #: rgbgrid: (nz, ny, nx, 3) sigma_a, sigma_s (already times "scale") and Le (times "Lescale");
    #: a grid not given is 1 (sigma) or 0 (Le) everywhere
    rgb_sigma_a: np.ndarray | None = None
    rgb_sigma_s: np.ndarray | None = None
    rgb_Le: np.ndarray | None = None
    #: cloud: pbrt-v4's procedural cloud (density, wispiness, frequency)
    cloud: tuple[float, float, float] = (1.0, 1.0, 5.0)
    #: nanovdb: the file and its density grid's name
    filename: Path | None = None
    grid_name: str = "density"

    @property
    def emissive(self) -> bool:
        return (bool(np.max(self.Le) > 0.0) or self.temperature is not None
                or (self.rgb_Le is not None and bool(np.max(self.rgb_Le) > 0.0)))

    def grid_bytes(self) -> int:
        """What the grids take as float32 on the host (the device holds one more copy)."""
        grids = (self.density, self.le_scale_grid, self.temperature, self.rgb_sigma_a, self.rgb_sigma_s, self.rgb_Le)
        return sum(4 * g.size for g in grids if g is not None)


@dataclass(frozen=True)
class MediumInterfaceDesc:
    """pbrt-v4's MediumInterface: the media on the two sides of a surface, as indices into
    ``SceneDescription.media`` (-1: vacuum). A shape whose inside and outside are the same medium
    does not change the medium of a ray that crosses it (pbrt's IsMediumTransition)."""

    inside: int = -1
    outside: int = -1

    @property
    def transition(self) -> bool:
        return self.inside != self.outside
