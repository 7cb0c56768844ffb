"""Transverse sand dunes as a displaced, subdivided plane (+y up, metres, wind along +x).

Each dune is asymmetric like a real one: a long stoss side climbing at 10–15° into the wind and a
short slip face falling at the angle of repose downwind of the crest. Crest lines wander with
noise and dune heights vary, which steepens some slopes; avalanching (talus relaxation, run to
convergence) then brings every triangle back to at most the critical slope, conserving sand.
"""
from __future__ import annotations

import argparse
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from assets_gen.common import GeneratorError, require, write_ply
from assets_gen.maps import add_generator_parser, emit, param, params_from_args, smooth_noise, write_preview


@dataclass(frozen=True)
class DuneParams:
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
        require(self.smoothing_steps >= 0, "smoothing steps must be non-negative")


@dataclass(frozen=True)
class Heightfield:
    """Heights y[iz, ix] over a regular (x, z) grid, the form every terrain stage shares."""
    x: np.ndarray        # (nx,) metres
    z: np.ndarray        # (nz,) metres
    y: np.ndarray        # (nz, nx) metres

    @property
    def dx(self) -> float:
        return float(self.x[1] - self.x[0])

    @property
    def dz(self) -> float:
        return float(self.z[1] - self.z[0])

    def slope_deg(self) -> np.ndarray:
        """Slope of the surface at each grid point (central differences), degrees."""
        gz, gx = np.gradient(self.y, self.dz, self.dx)
        return np.degrees(np.arctan(np.hypot(gx, gz)))


def dune_profile(x: np.ndarray, z: np.ndarray, p: DuneParams, rng: np.random.Generator) -> np.ndarray:
    """Unrelaxed dune heights: from each crest the surface falls at the repose slope downwind and
    at the stoss slope upwind; the higher of the two (and of the flat interdune) wins. Crest lines
    are level sets of a wind coordinate bent by noise; distances to them are Euclidean and a slip
    face falls from the height of its nearest crest point, so wandering crests of varying height
    keep their slip faces at the angle of repose (the gentle stoss takes the local height)."""
    lo, hi = (float(x.min()), float(z.min())), (float(x.max()), float(z.max()))
    wander = smooth_noise(rng, lo, hi, p.wander_size)
    height = smooth_noise(rng, lo, hi, p.wander_size * 1.5)
    xx, zz = np.meshgrid(x, z)
    crest_height = p.dune_height * np.clip(1.0 + p.height_variation * height(xx, zz), 0.0, None)
    s = (xx + p.crest_wander * wander(xx, zz)) / p.dune_wavelength
    spacing = (float(z[1] - z[0]) if len(z) > 1 else 1.0, float(x[1] - x[0]) if len(x) > 1 else 1.0)
    (behind, crest_of_slip), (ahead, _) = crest_distances(s, spacing).values()
    slip = crest_height[crest_of_slip] - behind * math.tan(math.radians(p.repose_angle_deg))
    stoss = crest_height - ahead * math.tan(math.radians(p.stoss_angle_deg))
    return np.maximum(np.maximum(slip, stoss), 0.0)


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


def grid_faces(nz: int, nx: int) -> np.ndarray:
    """Two counter-clockwise (seen from +y) triangles per grid cell, split along the same diagonal."""
    i = np.arange(nz * nx).reshape(nz, nx)
    a, b, c, d = i[:-1, :-1].ravel(), i[:-1, 1:].ravel(), i[1:, 1:].ravel(), i[1:, :-1].ravel()
    return np.concatenate([np.stack([a, c, b], 1), np.stack([a, d, c], 1)]).astype(np.int64)


def triangle_slopes(y: np.ndarray, dx: float, dz: float) -> tuple[np.ndarray, np.ndarray]:
    """(gx, gz) height gradients of the two triangles of every grid cell, each (2, nz-1, nx-1),
    in the order of :func:`grid_faces`."""
    a, b, c, d = y[:-1, :-1], y[:-1, 1:], y[1:, 1:], y[1:, :-1]
    gx = np.stack([(b - a) / dx, (c - d) / dx])
    gz = np.stack([(c - b) / dz, (d - a) / dz])
    return gx, gz


def max_triangle_slope_deg(y: np.ndarray, dx: float, dz: float) -> float:
    gx, gz = triangle_slopes(y, dx, dz)
    return float(np.degrees(np.arctan(np.hypot(gx, gz).max()))) if gx.size else 0.0


def talus_relax(y: np.ndarray, dx: float, dz: float, max_slope_deg: float,
                max_iterations: int = 20000) -> np.ndarray:
    """Avalanche until no triangle is steeper than ``max_slope_deg``: every over-steep triangle
    flattens its three corners towards their mean, just below the critical slope. Its push is
    divided by the largest number of over-steep triangles sharing one of its corners, so shared
    corners never overshoot, and each push sums to zero, so sand is conserved. Runs to convergence."""
    limit = math.tan(math.radians(max_slope_deg))
    target = math.tan(math.radians(max_slope_deg) * 0.98)
    y = np.array(y, dtype=np.float64)
    for _ in range(max_iterations):
        gx, gz = triangle_slopes(y, dx, dz)
        g = np.hypot(gx, gz)
        if g.max(initial=0.0) <= limit:
            return y
        steep = g > target
        shares = np.zeros_like(y)
        shares[:-1, :-1] += steep[0] + steep[1]
        shares[:-1, 1:] += steep[0]
        shares[1:, 1:] += steep[0] + steep[1]
        shares[1:, :-1] += steep[1]
        a, b, c, d = y[:-1, :-1], y[:-1, 1:], y[1:, 1:], y[1:, :-1]
        sa, sb, sc, sd = shares[:-1, :-1], shares[:-1, 1:], shares[1:, 1:], shares[1:, :-1]
        crowd = np.stack([np.maximum(np.maximum(sa, sb), sc), np.maximum(np.maximum(sa, sc), sd)])
        shrink = np.where(steep, (1.0 - target / np.maximum(g, 1e-300)) / np.maximum(crowd, 1.0), 0.0)
        m1, m2 = (a + b + c) / 3.0, (a + c + d) / 3.0
        push = np.zeros_like(y)
        push[:-1, :-1] -= shrink[0] * (a - m1) + shrink[1] * (a - m2)
        push[:-1, 1:] -= shrink[0] * (b - m1)
        push[1:, 1:] -= shrink[0] * (c - m1) + shrink[1] * (c - m2)
        push[1:, :-1] -= shrink[1] * (d - m2)
        y += push
    raise GeneratorError(f"talus relaxation did not converge in {max_iterations} iterations")


def laplacian_smooth(field: Heightfield, steps: int) -> Heightfield:
    """Round crests and brinks with pymeshlab's Laplacian smoothing of the grid mesh. On a regular
    grid interior vertices keep their (x, z), so this filters heights only."""
    if steps == 0:
        return field
    import pymeshlab

    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=grid_vertices(field), face_matrix=grid_faces(*field.y.shape)))
    ms.apply_coord_laplacian_smoothing(stepsmoothnum=steps, boundary=True, cotangentweight=False)
    y = ms.current_mesh().vertex_matrix()[:, 1].reshape(field.y.shape)
    return Heightfield(field.x, field.z, y)


def grid_vertices(field: Heightfield) -> np.ndarray:
    xx, zz = np.meshgrid(field.x, field.z)
    return np.stack([xx.ravel(), field.y.ravel(), zz.ravel()], axis=1)


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


def write_heightfield(stage: Path, name: str, field: Heightfield, preview: bool) -> list[str]:
    """``name.ply`` (positions, normals, UVs over the field's extent), ``name_height.exr`` (heights
    in metres with the grid extent in its header, what ``ripples`` reads) and a hillshade PNG."""
    import trimesh

    from renderer.io.images import write_exr

    verts = grid_vertices(field)
    faces = grid_faces(*field.y.shape)
    normals = trimesh.Trimesh(verts, faces, process=False).vertex_normals
    uu, vv = np.meshgrid((field.x - field.x[0]) / (field.x[-1] - field.x[0]),
                         (field.z - field.z[0]) / (field.z[-1] - field.z[0]))
    write_ply(stage / f"{name}.ply", verts, faces, normals, np.stack([uu.ravel(), vv.ravel()], 1))
    write_exr(stage / f"{name}_height.exr", {"Y": field.y.astype(np.float32)},
              {"units": "m", "x0": float(field.x[0]), "x1": float(field.x[-1]),
               "z0": float(field.z[0]), "z1": float(field.z[-1])})
    names = [f"{name}.ply", f"{name}_height.exr"]
    if preview:
        write_preview(stage / f"{name}.png", hillshade(field))
        names.append(f"{name}.png")
    return names


def read_heightfield(path: str | Path) -> Heightfield:
    """A heightfield written by :func:`write_heightfield`."""
    from renderer.io.images import read_exr

    require(Path(path).is_file(), f"heightfield {str(path)!r} not found")
    chans, header = read_exr(path)
    require("Y" in chans and all(k in header for k in ("x0", "x1", "z0", "z1")),
            f"{path} is not a dunes heightfield (needs channel Y and x0/x1/z0/z1 in its header)")
    y = chans["Y"].astype(np.float64)
    x = np.linspace(float(header["x0"]), float(header["x1"]), y.shape[1])
    z = np.linspace(float(header["z0"]), float(header["z1"]), y.shape[0])
    return Heightfield(x, z, y)


def hillshade(field: Heightfield, sun_deg: tuple[float, float] = (315.0, 35.0)) -> np.ndarray:
    """Lambertian shading under a low sun, the usual way to look at terrain relief."""
    gz, gx = np.gradient(field.y, field.dz, field.dx)
    az, el = np.radians(sun_deg[0]), np.radians(sun_deg[1])
    sun = np.array([math.cos(el) * math.sin(az), math.sin(el), math.cos(el) * math.cos(az)])
    n = np.stack([-gx, np.ones_like(gx), -gz])
    return np.clip(np.tensordot(sun, n, 1) / np.linalg.norm(n, axis=0), 0.0, 1.0)


def _run(args: argparse.Namespace) -> list[str]:
    p = params_from_args(args, DuneParams)
    return emit(args.out, "dunes", p, args.seed,
                lambda stage: write_heightfield(stage, "dunes", dune_heightfield(p, args.seed), args.preview))


def register(subparsers: Any) -> None:
    add_generator_parser(subparsers, "dunes", __doc__, DuneParams, _run)
