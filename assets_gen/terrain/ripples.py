"""Aeolian ripples on the dunes: crests across the wind (+x) about 10–15 cm apart and a few mm
high, with a gentle stoss and a steeper lee side, wandering crests, forks where a crest ends
(phase dislocations) and bare patches. They avalanche away on slopes near the angle of repose.

Where the dune grid resolves a wavelength with enough vertices the ripples are added to the mesh;
otherwise they are written as a displacement map (EXR, metres) over the dune's UV square.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy import ndimage

from assets_gen.core import Generator, Job, Params, param, require
from assets_gen.core.noise import smooth_noise
from assets_gen.core.output import write_map
from assets_gen.terrain.heightfield import Heightfield, read_heightfield, talus_relax, write_heightfield


@dataclass(frozen=True)
class RippleParams(Params):
    dunes: str = param("assets/dunes/dunes_height.exr", "dune heightfield written by `dunes`", path=True)
    wavelength: float = param(0.12, "crest-to-crest distance, m")
    height: float = param(0.005, "trough-to-crest height, m")
    lee_fraction: float = param(0.3, "fraction of a wavelength taken by the steep lee side")
    crest_wander: float = param(0.15, "how far crests wander, in wavelengths")
    wander_size: float = param(0.6, "feature size of the crest wander, m")
    defect_density: float = param(0.5, "crest forks and terminations (phase dislocations) per m^2")
    coverage: float = param(0.85, "fraction of the sand that carries ripples (patchiness)")
    patch_size: float = param(3.0, "feature size of rippled and bare patches, m")
    fade_start_deg: float = param(20.0, "dune slope where ripples start to fade, degrees")
    fade_end_deg: float = param(25.0, "dune slope beyond which sand avalanches and no ripples form, degrees")
    max_slope_deg: float = param(34.0, "critical slope kept after adding ripples as geometry, degrees")
    samples_per_wavelength: float = param(8.0, "grid points per wavelength needed to add ripples as geometry")
    max_map_size: int = param(4096, "largest displacement map side, pixels")

    def validate(self) -> None:
        require(Path(self.dunes).is_file(), f"dune heightfield {self.dunes!r} not found")
        require(self.wavelength > 0 and self.height > 0, "ripple wavelength and height must be positive (m)")
        index = self.wavelength / self.height
        require(12 <= index <= 50, f"ripple index wavelength/height = {index:.3g} is outside the "
                                   "aeolian range 12..50")
        require(0 < self.lee_fraction < 1, "lee fraction must be between 0 and 1")
        require(self.crest_wander >= 0 and self.wander_size > 0, "crest wander >= 0 and wander size > 0")
        require(self.defect_density >= 0, "defect density must be non-negative (per m^2)")
        require(0 < self.coverage <= 1, "coverage must be in (0, 1]")
        require(self.patch_size > 0, "patch size must be positive (m)")
        require(0 < self.fade_start_deg < self.fade_end_deg < 90,
                "need 0 < fade start < fade end < 90 degrees")
        require(0 < self.max_slope_deg < 90, "max slope must be between 0 and 90 degrees")
        require(self.samples_per_wavelength >= 2, "need at least 2 samples per wavelength (Nyquist)")
        require(16 <= self.max_map_size <= 16384, "max map size must be 16..16384 pixels")


def ripple_profile(phase: np.ndarray, lee_fraction: float) -> np.ndarray:
    """Zero-mean asymmetric triangle of unit height: rises over the stoss part of each cycle,
    falls over the lee part."""
    q = phase - np.floor(phase)
    stoss = 1.0 - lee_fraction
    return np.where(q < stoss, q / stoss, (1.0 - q) / lee_fraction) - 0.5


def ripple_displacement(field: Heightfield, p: RippleParams, seed: int, x: np.ndarray,
                        z: np.ndarray) -> np.ndarray:
    """Ripple displacement (m) on the grid x (nx,) by z (nz,), shape (nz, nx); the same (seed,
    place) gives the same value on any grid, so mesh and map agree. The phase is x / wavelength
    plus smooth wander plus the winding of crest-end pairs (two opposite phase dislocations: a
    short extra crest between them, whose influence decays with distance and is cut off smoothly,
    keeping the work local). Amplitude dies in dislocation cores, bare patches and steep slopes."""
    rng = np.random.default_rng(seed)
    lo, hi = (float(field.x[0]), float(field.z[0])), (float(field.x[-1]), float(field.z[-1]))
    wander = smooth_noise(rng, lo, hi, p.wander_size)
    patches = smooth_noise(rng, lo, hi, p.patch_size)
    n_pairs = int(rng.poisson(0.5 * p.defect_density * (hi[0] - lo[0]) * (hi[1] - lo[1])))
    centres = rng.uniform(lo, hi, size=(n_pairs, 2))
    lengths = rng.uniform(2.0, 6.0, size=n_pairs) * p.wavelength
    angles = np.pi / 2 + rng.normal(0.0, 0.3, size=n_pairs)      # extra crests run across the wind
    core = 0.5 * p.wavelength

    xx, zz = np.meshgrid(x, z)
    phase = x[None, :] / p.wavelength + p.crest_wander * wander(xx, zz)
    amp = np.clip((patches(xx, zz) - _patch_threshold(p.coverage)) / 0.3, 0.0, 1.0)
    slope = ndimage.map_coordinates(field.slope_deg(), [(zz - lo[1]) / field.dz, (xx - lo[0]) / field.dx],
                                    order=1, mode="nearest")
    amp *= np.clip((p.fade_end_deg - slope) / (p.fade_end_deg - p.fade_start_deg), 0.0, 1.0)
    for (cx, cz), length, angle in zip(centres, lengths, angles):
        reach = 4.0 * length
        ix = slice(*np.searchsorted(x, [cx - reach, cx + reach]))
        iz = slice(*np.searchsorted(z, [cz - reach, cz + reach]))
        px, pz = xx[iz, ix] - cx, zz[iz, ix] - cz
        hx, hz = 0.5 * length * np.cos(angle), 0.5 * length * np.sin(angle)
        ax, az, bx, bz = px + hx, pz + hz, px - hx, pz - hz       # from the two cores to the point
        subtended = np.arctan2(ax * bz - az * bx, ax * bx + az * bz)
        t = np.clip(2.0 - 2.0 * np.hypot(px, pz) / reach, 0.0, 1.0)   # 1 inside half the reach
        window = t * t * (3.0 - 2.0 * t)
        phase[iz, ix] += window * subtended / (2.0 * np.pi)
        amp[iz, ix] *= np.tanh(np.hypot(ax, az) / core) * np.tanh(np.hypot(bx, bz) / core)
    return p.height * amp * ripple_profile(phase, p.lee_fraction)


def _patch_threshold(coverage: float) -> float:
    """Level of the roughly unit-normal patch noise above which a fraction ``coverage`` lies."""
    from scipy.stats import norm

    return float(norm.ppf(1.0 - coverage)) if coverage < 1 else -np.inf


def resolves_ripples(field: Heightfield, p: RippleParams) -> bool:
    """Whether the dune grid has ``samples_per_wavelength`` points per ripple wavelength."""
    return max(field.dx, field.dz) <= p.wavelength / p.samples_per_wavelength


def rippled_heightfield(field: Heightfield, p: RippleParams, seed: int) -> Heightfield:
    """The dunes with ripples added as geometry, avalanched back under the critical slope."""
    y = field.y + ripple_displacement(field, p, seed, field.x, field.z)
    return Heightfield(field.x, field.z, talus_relax(y, field.dx, field.dz, p.max_slope_deg))


def ripple_map(field: Heightfield, p: RippleParams, seed: int) -> np.ndarray:
    """Displacement (m) at texel centres over the dune's UV square (u along +x, v along +z),
    ``samples_per_wavelength`` texels per wavelength unless that exceeds ``max_map_size``."""
    sx, sz = field.x[-1] - field.x[0], field.z[-1] - field.z[0]
    texel = p.wavelength / p.samples_per_wavelength
    nx = min(p.max_map_size, max(16, int(math.ceil(sx / texel))))
    nz = min(p.max_map_size, max(16, int(math.ceil(sz / texel))))
    x = field.x[0] + (np.arange(nx) + 0.5) / nx * sx
    z = field.z[0] + (np.arange(nz) + 0.5) / nz * sz
    return ripple_displacement(field, p, seed, x, z)


def write(job: Job) -> list[str]:
    """The rippled dunes as geometry where the grid resolves the ripples, else a displacement map."""
    p, field = job.params, read_heightfield(job.params.dunes)
    if resolves_ripples(field, p):
        return write_heightfield(job.stage, "dunes_rippled", rippled_heightfield(field, p, job.seed), job.preview)
    return write_map(job.stage, "ripples_displacement", ripple_map(field, p, job.seed), "m", job.preview,
                     {"x0": float(field.x[0]), "x1": float(field.x[-1]),
                      "z0": float(field.z[0]), "z1": float(field.z[-1])})


GENERATOR = Generator("ripples", "aeolian ripples on the dunes, as geometry or a displacement map",
                      RippleParams, write, __doc__, previews=True)
