"""The regular (x, z) heightfield every terrain stage shares: its triangles, avalanching, and the
PLY + height EXR pair that ``ripples`` reads back."""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from assets_gen.core.meshing import grid_faces
from assets_gen.core.output import write_ply, write_preview
from assets_gen.core.params import GeneratorError, reading, require


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


def heightfield_faces(nz: int, nx: int) -> np.ndarray:
    """Two counter-clockwise (seen from +y) triangles per grid cell (meshing's grid), all those on
    the +x side of the cells' diagonals first: the order terrain files have always had, and that
    of :func:`triangle_slopes`."""
    faces = grid_faces(nz, nx)
    return np.roll(faces, len(faces) // 2, axis=0)


def triangle_slopes(y: np.ndarray, dx: float, dz: float) -> tuple[np.ndarray, np.ndarray]:
    """(gx, gz) height gradients of the two triangles of every grid cell, each (2, nz-1, nx-1),
    in the order of :func:`heightfield_faces`."""
    a, b, c, d = y[:-1, :-1], y[:-1, 1:], y[1:, 1:], y[1:, :-1]
    gx = np.stack([(b - a) / dx, (c - d) / dx])
    gz = np.stack([(c - b) / dz, (d - a) / dz])
    return gx, gz


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


def grid_vertices(field: Heightfield) -> np.ndarray:
    xx, zz = np.meshgrid(field.x, field.z)
    return np.stack([xx.ravel(), field.y.ravel(), zz.ravel()], axis=1)


def write_heightfield(stage: Path, name: str, field: Heightfield, preview: bool) -> list[str]:
    """``name.ply`` (positions, normals, UVs over the field's extent), ``name_height.exr`` (heights
    in metres with the grid extent in its header, what ``ripples`` reads) and a hillshade PNG."""
    import trimesh

    from renderer.io.images import write_exr

    verts = grid_vertices(field)
    faces = heightfield_faces(*field.y.shape)
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
    with reading(path, "heightfield"):
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
