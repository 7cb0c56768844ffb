"""Transverse sand dunes as a displaced, subdivided plane (+y up, metres, wind along +x).

Each dune is asymmetric like a real one: a long stoss side climbing at 10–15° into the wind and a
short slip face falling at the angle of repose downwind of the crest. Crest lines wander with
noise and dune heights vary, which steepens some slopes; avalanching (talus relaxation, run to
convergence) then brings every triangle back to at most the critical slope, conserving sand.

Barchanoid ridges (``horn_spacing`` > 0): each crest line is a chain of crescents, concave
downwind, whose horns reach ``horn_length`` downwind of the crescent centres and stand lower by
``horn_drop``; the crescents' spacing wanders with seeded low-frequency noise, so no two are alike
(McKee 1979's barchanoid ridge, between barchans and straight transverse dunes). The brink is the
crest itself: the slip face starts at the crest and only ``smoothing_steps`` round it.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from assets_gen.core import Generator, Job, Params, param, require
from assets_gen.core.noise import smooth_noise
from assets_gen.terrain.heightfield import (Heightfield, grid_vertices, heightfield_faces, talus_relax,
                                            write_heightfield)


@dataclass(frozen=True)
class DuneParams(Params):
    size_x: float = param(40.0, "extent along the wind (+x), m")
    size_z: float = param(40.0, "extent across the wind (z), m")
    spacing: float = param(0.1, "grid spacing of the subdivided plane, m")
    dune_height: float = param(1.5, "mean crest height above the interdune flats, m")
    dune_wavelength: float = param(18.0, "crest-to-crest distance along the wind, m")
    height_variation: float = param(0.3, "relative spread of crest heights")
    stoss_angle_deg: float = param(12.0, "slope of the windward (stoss) side, degrees")
    repose_angle_deg: float = param(32.0, "slope of the slip face (angle of repose), degrees")
    max_slope_deg: float = param(34.0, "critical slope no triangle may exceed after avalanching, degrees")
    crest_wander: float = param(2.5, "how far crest lines wander along the wind, m")
    wander_size: float = param(12.0, "feature size of the crest wander and height variation, m")
    crest_x: float = param(0.0, "x of one crest line before wander and horns (the others every wavelength), m")
    horn_spacing: float = param(0.0, "mean crest-wise spacing of barchanoid crescents (0: straight ridges), m")
    horn_length: float = param(0.0, "how far the horns reach downwind of the crescent centres, m")
    horn_drop: float = param(0.25, "relative height lost from a crescent centre to its horns")
    smoothing_steps: int = param(3, "Laplacian smoothing steps that round crests and brinks")

    def validate(self) -> None:
        require(self.size_x > 0 and self.size_z > 0, "dune field size must be positive (m)")
        require(self.spacing > 0, "grid spacing must be positive (m)")
        n = (self.size_x / self.spacing + 1) * (self.size_z / self.spacing + 1)
        require(n >= 4, "grid spacing is larger than the dune field")
        require(n <= 2.0e7, f"grid of {n:.3g} vertices is too large; raise --spacing")
        require(self.dune_height >= 0, "dune height must be non-negative (m)")
        require(self.dune_wavelength > 0, "dune wavelength must be positive (m)")
        require(0 <= self.height_variation < 1, "height variation must be in [0, 1)")
        for name in ("stoss_angle_deg", "repose_angle_deg", "max_slope_deg"):
            require(0 < getattr(self, name) < 90, f"{name.replace('_', ' ')} must be between 0 and 90 degrees")
        require(self.stoss_angle_deg < self.repose_angle_deg <= self.max_slope_deg,
                "need stoss angle < angle of repose <= max slope")
        require(self.crest_wander >= 0 and self.wander_size > 0, "crest wander >= 0 and wander size > 0 (m)")
        require(self.horn_spacing >= 0 and self.horn_length >= 0, "horn spacing and length must be >= 0 (m)")
        require(self.horn_length == 0 or self.horn_spacing > 0, "horns need a horn spacing > 0 (m)")
        require(self.crest_wander + self.horn_length < 0.5 * self.dune_wavelength,
                "crest wander + horn length must stay under half a wavelength (crests would cross)")
        require(0 <= self.horn_drop < 1, "horn drop must be in [0, 1)")
        require(0 <= self.smoothing_steps <= 100, "smoothing steps must be 0..100 (crests are gone long before)")
        tallest = self.dune_wavelength * math.tan(math.radians(self.stoss_angle_deg))
        require(self.dune_height <= tallest,
                f"dune height must be at most wavelength x tan(stoss angle) = {tallest:.3g} m: taller crests "
                "leave no interdune flats (the stoss slope cannot fall that far in one wavelength)")


def dune_profile(x: np.ndarray, z: np.ndarray, p: DuneParams, rng: np.random.Generator) -> np.ndarray:
    """Unrelaxed dune heights: from each crest the surface falls at the repose slope downwind and
    at the stoss slope upwind; the higher of the two (and of the flat interdune) wins. Crest lines
    are level sets of a wind coordinate bent by noise and by the crescents; distances to them are
    Euclidean and a slip face falls from the height of its nearest crest point, so wandering crests
    of varying height keep their slip faces at the angle of repose (the gentle stoss takes the
    local height)."""
    lo, hi = (float(x.min()), float(z.min())), (float(x.max()), float(z.max()))
    wander = smooth_noise(rng, lo, hi, p.wander_size)
    height = smooth_noise(rng, lo, hi, p.wander_size * 1.5)
    xx, zz = np.meshgrid(x, z)
    horns = crescent_offset(z, p, rng)[:, None]                       # 0 at centres .. 1 at horns
    crest_height = p.dune_height * np.clip(1.0 + p.height_variation * height(xx, zz), 0.0, None)
    crest_height = crest_height * (1.0 - p.horn_drop * horns)
    shift = p.crest_wander * np.tanh(wander(xx, zz)) + p.horn_length * horns   # crest moves downwind
    s = (xx - p.crest_x - shift) / p.dune_wavelength
    spacing = (float(z[1] - z[0]) if len(z) > 1 else 1.0, float(x[1] - x[0]) if len(x) > 1 else 1.0)
    (behind, crest_of_slip), (ahead, _) = crest_distances(s, spacing).values()
    slip = crest_height[crest_of_slip] - behind * slip_gradient(crest_height, s, spacing, p)[crest_of_slip]
    stoss = crest_height - ahead * math.tan(math.radians(p.stoss_angle_deg))
    return np.maximum(np.maximum(slip, stoss), 0.0)


def slip_gradient(crest_height: np.ndarray, s: np.ndarray, spacing: tuple[float, float],
                  p: DuneParams) -> np.ndarray:
    """How steeply a slip face must fall away from each crest point for the surface to slope at the
    angle of repose: a crest whose height changes along it by g per metre gives the face below it
    that gradient too, so the fall is sqrt(tan^2 repose - g^2) (at least tan(repose - 8 deg))."""
    hz, hx = np.gradient(crest_height, *spacing)
    sz, sx = np.gradient(s, *spacing)
    along = np.abs(hx * sz - hz * sx) / np.maximum(np.hypot(sx, sz), 1e-12)   # dH/d(crest arc length)
    tan_repose = math.tan(math.radians(p.repose_angle_deg))
    least = math.tan(math.radians(p.repose_angle_deg - 8.0))
    return np.sqrt(np.maximum(tan_repose ** 2 - along ** 2, least ** 2))


def crescent_offset(z: np.ndarray, p: DuneParams, rng: np.random.Generator) -> np.ndarray:
    """Across-wind profile of a barchanoid crest, 0 at each crescent's centre and 1 at the cusp
    where two crescents' horns meet: 1 - |sin(pi z' / spacing)|, smooth at the centres and cusped
    at the horns, with z' = z warped by noise so the crescents' widths vary (+-30 %)."""
    if p.horn_spacing == 0:
        return np.zeros_like(z)
    warp = smooth_noise(rng, (float(z.min()), 0.0), (float(z.max()), 1.0), 2.0 * p.horn_spacing)
    zw = z + 0.3 * p.horn_spacing * np.tanh(warp(z, np.zeros_like(z)))
    return 1.0 - np.abs(np.sin(np.pi * zw / p.horn_spacing))


def crest_distances(s: np.ndarray, spacing: tuple[float, float]) -> dict[str, tuple[np.ndarray, tuple]]:
    """For the crest upwind of each grid point (``behind``) and downwind of it (``ahead``): the
    distance (m, inf where that crest lies off the grid) and the index of its nearest crest point.
    Crest k is the line s = k of the bent wind coordinate s (in wavelengths)."""
    from scipy import ndimage

    band = np.floor(s)
    first = band > ndimage.minimum_filter(band, footprint=ndimage.generate_binary_structure(2, 1),
                                          mode="nearest")          # just downwind of a crest
    out = {side: (np.full(s.shape, np.inf), np.indices(s.shape)) for side in ("behind", "ahead")}
    for k in np.unique(band[first]):
        dist, idx = ndimage.distance_transform_edt(~(first & (band == k)), sampling=spacing,
                                                   return_indices=True)
        for side, members in (("behind", band == k), ("ahead", band == k - 1)):
            d, nearest = out[side]
            d[members] = dist[members]
            nearest[:, members] = idx[:, members]
    return {side: (d, (nearest[0], nearest[1])) for side, (d, nearest) in out.items()}


def laplacian_smooth(field: Heightfield, steps: int) -> Heightfield:
    """Round crests and brinks with pymeshlab's Laplacian smoothing of the grid mesh. On a regular
    grid interior vertices keep their (x, z), so this filters heights only."""
    if steps == 0:
        return field
    import pymeshlab

    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=grid_vertices(field), face_matrix=heightfield_faces(*field.y.shape)))
    ms.apply_coord_laplacian_smoothing(stepsmoothnum=steps, boundary=True, cotangentweight=False)
    y = ms.current_mesh().vertex_matrix()[:, 1].reshape(field.y.shape)
    return Heightfield(field.x, field.z, y)


def dune_heightfield(p: DuneParams, seed: int) -> Heightfield:
    """Dunes for (parameters, seed): profile, smoothing, avalanching."""
    p.validate()
    rng = np.random.default_rng(seed)
    nx = int(round(p.size_x / p.spacing)) + 1
    nz = int(round(p.size_z / p.spacing)) + 1
    x = np.linspace(-p.size_x / 2, p.size_x / 2, nx)
    z = np.linspace(-p.size_z / 2, p.size_z / 2, nz)
    field = laplacian_smooth(Heightfield(x, z, dune_profile(x, z, p, rng)), p.smoothing_steps)
    return Heightfield(x, z, talus_relax(field.y, field.dx, field.dz, p.max_slope_deg))


def write(job: Job) -> list[str]:
    return write_heightfield(job.stage, "dunes", dune_heightfield(job.params, job.seed), job.preview)


GENERATOR = Generator("dunes", "transverse sand dunes as a displaced, subdivided plane (PLY + height EXR)",
                      DuneParams, write, __doc__, previews=True)
