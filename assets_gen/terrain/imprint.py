"""A buried prop's imprint in the sand: a dent under it and a raised rim around it, so the sand
meets the prop instead of cutting through it.

The prop's lower surface is rasterised from below (ray casts up through a fine (x, z) grid). Every
sand vertex within ``reach`` of the prop's footprint (more than the longest sand edge there) drops
to ``clearance`` below the lowest point of the prop's lower surface within ``reach`` of it, so no
sand triangle can rise into the prop. The sand pushed out of the dent is heaped into a rim
just outside, of profile (s / w) exp(1 - s / w) in the distance s from the footprint, scaled so the
rim holds the dent's volume (sand is conserved).
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from assets_gen.core import Generator, Job, Params, param, reading, require
from assets_gen.terrain.near_field import write_sand
from assets_gen.terrain.placement import read_mesh


@dataclass(frozen=True)
class ImprintParams(Params):
    surface: str = param("assets/sand/sand.ply", "sand mesh to deform (PLY, +y up, m)", path=True)
    mesh: str = param("assets/conch/conch.ply", "prop mesh (PLY, or a folder of PLYs)", path=True)
    placement: str = param("assets/conch_placement/placement.npz", "prop pose written by `placement`", path=True)
    clearance: float = param(2e-4, "gap left between the dent and the prop, m")
    rim_width: float = param(0.015, "distance from the footprint to the rim's crest, m")
    raster: float = param(2.5e-4, "grid step of the prop's lower-surface raster, m")

    def validate(self) -> None:
        for name in ("surface", "mesh", "placement"):
            require(Path(getattr(self, name)).exists(), f"{name} {getattr(self, name)!r} not found")
        require(self.clearance > 0 and self.rim_width > 0, "clearance and rim width must be positive (m)")
        require(1e-5 <= self.raster <= 0.01, "raster step must be 1e-5..0.01 m")


def vertex_areas(v: np.ndarray, f: np.ndarray) -> np.ndarray:
    """A third of the (x, z)-projected area of each vertex's triangles: volume per unit height."""
    e1, e2 = v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]
    area = 0.5 * np.abs(e1[:, 2] * e2[:, 0] - e1[:, 0] * e2[:, 2])
    return np.bincount(f.ravel(), np.repeat(area / 3.0, 3), minlength=len(v))


def lower_surface(v: np.ndarray, f: np.ndarray, lo: np.ndarray, step: float,
                  shape: tuple[int, int]) -> np.ndarray:
    """Height of the prop's lowest surface over each raster cell centre (inf where none)."""
    from renderer.geometry.raycast import cast_rays

    ix, iz = np.meshgrid(np.arange(shape[1]), np.arange(shape[0]))
    x, z = lo[0] + (ix.ravel() + 0.5) * step, lo[1] + (iz.ravel() + 0.5) * step
    bottom = float(v[:, 1].min()) - 1.0
    origins = np.column_stack([x, np.full(len(x), bottom), z])
    t = cast_rays(v, f, origins, np.tile([0.0, 1.0, 0.0], (len(x), 1)))
    return (bottom + t).reshape(shape)


def imprint(sand_v: np.ndarray, sand_f: np.ndarray, prop_v: np.ndarray, prop_f: np.ndarray,
            p: ImprintParams) -> tuple[np.ndarray, float]:
    """Sand vertices with the dent and rim, and the volume moved (m^3)."""
    from scipy import ndimage

    step = p.raster
    xz = sand_v[:, [0, 2]]
    near = np.isin(np.arange(len(sand_v)), sand_f[
        np.all((xz[sand_f] >= prop_v[:, [0, 2]].min(0) - 0.01) & (xz[sand_f] <= prop_v[:, [0, 2]].max(0) + 0.01),
               axis=(1, 2))])
    edges = sand_v[sand_f[:, [1, 2, 0]]] - sand_v[sand_f]
    local = near[sand_f].all(axis=1)
    require(local.any(), "the prop is not over the sand mesh")
    longest = float(np.linalg.norm(edges[local][..., [0, 2]], axis=2).max())
    reach = 1.5 * longest + 2 * step
    margin = reach + 8 * p.rim_width
    lo = prop_v[:, [0, 2]].min(0) - margin
    shape = tuple(np.ceil((prop_v[:, [0, 2]].max(0) + margin - lo) / step).astype(int))[::-1]
    lower = lower_surface(prop_v, prop_f, lo, step, shape)
    radius = int(np.ceil(reach / step))
    disk = np.hypot(*np.mgrid[-radius:radius + 1, -radius:radius + 1]) <= radius
    lowest = ndimage.minimum_filter(lower, footprint=disk, mode="constant", cval=np.inf)
    dist = ndimage.distance_transform_edt(~np.isfinite(lowest)) * step

    cell = np.floor((xz - lo) / step).astype(int)
    inside = np.all((cell >= 0) & (cell < np.array(shape[::-1])), axis=1)
    ci, cj = cell[inside, 1], cell[inside, 0]
    y = sand_v[:, 1].copy()
    idx = np.flatnonzero(inside)
    limit = lowest[ci, cj] - p.clearance
    dent = np.maximum(y[idx] - limit, 0.0)
    dent[~np.isfinite(limit)] = 0.0
    y[idx] -= dent
    areas = vertex_areas(sand_v, sand_f)
    volume = float((areas[idx] * dent).sum())
    s = dist[ci, cj] / p.rim_width
    t = np.clip(2.0 - s / 4.0, 0.0, 1.0)                               # fade out from 4 to 8 widths
    profile = np.where(np.isfinite(limit), 0.0, s * np.exp(1.0 - s) * t * t * (3 - 2 * t))
    held = float((areas[idx] * profile).sum())
    require(volume == 0 or held > 0, "the rim has no room on the sand mesh around the prop")
    if volume > 0:
        y[idx] += volume / held * profile
    out = sand_v.copy()
    out[:, 1] = y
    return out, volume


def write(job: Job) -> list[str]:
    import trimesh

    p = job.params
    with reading(p.surface, "surface mesh"):
        sand = trimesh.load(p.surface, process=False, force="mesh")
    with reading(p.placement, "placement"):
        m = np.load(p.placement)["transform"]
    v, f = read_mesh(p.mesh)
    prop_v = v @ m[:3, :3].T + m[:3, 3]
    sand_v = np.asarray(sand.vertices, dtype=np.float64)
    uv = np.asarray(sand.visual.uv) if hasattr(sand.visual, "uv") and sand.visual.uv is not None else None
    require(uv is not None, f"{p.surface}: the sand mesh has no UVs (write it with `near-field`)")
    out, volume = imprint(sand_v, np.asarray(sand.faces), prop_v, f, p)
    write_sand(job.stage / "sand.ply", out, np.asarray(sand.faces), uv)
    job.note(moved_volume_m3=volume)
    return ["sand.ply"]


GENERATOR = Generator("imprint", "a buried prop's dent and rim in the sand (no intersection)",
                      ImprintParams, write, __doc__)
