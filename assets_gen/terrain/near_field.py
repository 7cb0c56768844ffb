"""The sand surface as the camera sees it: ripples as displaced geometry where the camera resolves
them, the dune mesh with the ripple bump map beyond ("model only what the camera can see").

The near field is a rectangle of whole dune-grid cells in front of the camera. It is cut out of
the dune mesh and re-tessellated in rows across the view direction, spaced so that every edge
projects to about ``pixels_per_edge`` pixels of the full film (rows at equal steps of the angle
below the camera, points along a row at equal steps of the view angle), coarser outside the
frustum. Heights are the dune mesh's own (same triangles) plus the ripple displacement map,
sampled as the renderer samples it, faded to zero over ``taper`` metres at the rectangle's edge.
Every dune-grid vertex on the seam is shared and the dune triangles along the seam are split at
the near field's seam vertices, so the surface is one crack-free, overlap-free sheet. The bump
that the taper takes away from the geometry is given back as a weight map (1 - taper) that
multiplies the bump texture, so geometry + bump is the whole ripple everywhere.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from assets_gen.core import Generator, Job, Params, param, reading, require
from assets_gen.core.camera import PinholeCamera
from assets_gen.core.output import write_ply
from assets_gen.terrain.heightfield import Heightfield, heightfield_faces, read_heightfield


@dataclass(frozen=True)
class NearFieldParams(Params):
    dunes: str = param("assets/dunes/dunes_height.exr", "dune heightfield written by `dunes`", path=True)
    ripples: str = param("assets/ripples/ripples_displacement.exr", "ripple displacement map written by `ripples`",
                         path=True)
    scene: str = param("parts/beach_camera_view.pbrt", "pbrt-v4 scene file with the camera", path=True)
    pixels_per_edge: float = param(1.5, "target projected edge length at the full film, pixels (the detail knob)")
    max_distance: float = param(2.0, "ground distance from the camera out to which ripples are geometry, m")
    taper: float = param(0.5, "width over which the displacement fades to zero at the seam, m")
    grading: float = param(0.3, "growth of the edge length per metre outside the frustum")
    weight_texel: float = param(0.05, "texel of the bump weight map, m")

    def validate(self) -> None:
        for name in ("dunes", "ripples", "scene"):
            require(Path(getattr(self, name)).is_file(), f"{name} file {getattr(self, name)!r} not found")
        require(0.25 <= self.pixels_per_edge <= 100, "pixels per edge must be 0.25..100")
        require(self.max_distance > 0 and self.taper > 0, "max distance and taper must be positive (m)")
        require(0 < self.grading <= 2, "grading must be in (0, 2]")
        require(self.weight_texel > 0, "weight texel must be positive (m)")


@dataclass(frozen=True)
class RippleMap:
    """The ripple displacement (m) over the dune UV square, looked up bilinearly with the row flip
    and clamping of the renderer's image textures, so the mesh shows what the bump map shows."""
    values: np.ndarray     # (rows, cols), row 0 at v = 1
    x0: float
    x1: float
    z0: float
    z1: float

    @classmethod
    def read(cls, path: str | Path) -> RippleMap:
        from renderer.io.images import read_exr

        with reading(path, "ripple map"):
            chans, header = read_exr(path)
        require("Y" in chans and all(k in header for k in ("x0", "x1", "z0", "z1")),
                f"{path} is not a ripple map (needs channel Y and x0/x1/z0/z1 in its header)")
        return cls(chans["Y"].astype(np.float64), *(float(header[k]) for k in ("x0", "x1", "z0", "z1")))

    def __call__(self, x: np.ndarray, z: np.ndarray) -> np.ndarray:
        h, w = self.values.shape
        s = (x - self.x0) / (self.x1 - self.x0)
        t = (z - self.z0) / (self.z1 - self.z0)
        return bilinear(self.values, s * w - 0.5, (1.0 - t) * h - 0.5)


def bilinear(img: np.ndarray, px: np.ndarray, py: np.ndarray) -> np.ndarray:
    """Bilinear lookup at continuous pixel coordinates (texel centres at integers), edges clamped."""
    h, w = img.shape
    x0, y0 = np.floor(px), np.floor(py)
    fx, fy = px - x0, py - y0
    ix0, iy0 = np.clip(x0.astype(int), 0, w - 1), np.clip(y0.astype(int), 0, h - 1)
    ix1, iy1 = np.clip(x0.astype(int) + 1, 0, w - 1), np.clip(y0.astype(int) + 1, 0, h - 1)
    a = img[iy0, ix0] * (1 - fx) + img[iy0, ix1] * fx
    b = img[iy1, ix0] * (1 - fx) + img[iy1, ix1] * fx
    return a * (1 - fy) + b * fy


def dune_height(field: Heightfield, x: np.ndarray, z: np.ndarray) -> np.ndarray:
    """Height of the dune mesh itself at (x, z): linear on its two triangles per cell, which share
    the diagonal from (iz, ix) to (iz + 1, ix + 1) (see heightfield_faces)."""
    gx = np.clip((x - field.x[0]) / field.dx, 0, len(field.x) - 1 - 1e-9)
    gz = np.clip((z - field.z[0]) / field.dz, 0, len(field.z) - 1 - 1e-9)
    ix, iz = np.floor(gx).astype(int), np.floor(gz).astype(int)
    fx, fz = gx - ix, gz - iz
    y = field.y
    y00, y01, y10, y11 = y[iz, ix], y[iz, ix + 1], y[iz + 1, ix], y[iz + 1, ix + 1]
    upper = fx >= fz
    return np.where(upper, y00 + fx * (y01 - y00) + fz * (y11 - y01), y00 + fz * (y10 - y00) + fx * (y11 - y10))


@dataclass(frozen=True)
class Layout:
    """Where the near field lies and how finely: the rectangle [a0, a1] x [b0, b1] in (along, across)
    coordinates, where ``axis`` (0 = x, 2 = z) is the along axis, and the camera's spacing rules."""
    axis: int
    cam_a: float
    cam_b: float
    height: float          # camera height above the sand, m
    near: float            # nearest visible ground distance, m
    half_tan: float        # lateral half-width of the view per metre of distance
    edge_angle: float      # target edge, rad (pixels_per_edge x pixel pitch)
    grading: float
    cell: float            # dune-grid spacing (coarsest edge)
    a_lines: np.ndarray    # dune-grid lines along, inside the rectangle (sorted)
    b_lines: np.ndarray    # dune-grid lines across
    taper: float

    def along_spacing(self, a: np.ndarray) -> np.ndarray:
        """Row spacing: equal steps of the depression angle atan(h / d) on flat ground."""
        d = np.abs(a - self.cam_a)
        dv = np.maximum(d, self.near)
        s = self.edge_angle * (dv * dv + self.height ** 2) / self.height
        return np.minimum(s + self.grading * np.maximum(self.near - d, 0.0), self.cell)

    def across_spacing(self, a: float, b: np.ndarray) -> np.ndarray:
        """Point spacing in a row: equal steps of the view angle inside the frustum, graded outside."""
        d = max(abs(a - self.cam_a), self.near)
        half = self.half_tan * d
        s = self.edge_angle * math.hypot(d, self.height)
        return np.minimum(s + self.grading * np.maximum(np.abs(b - self.cam_b) - half, 0.0), self.cell)

    def weight(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Displacement weight: 1 inside, smoothly 0 at the rectangle's edge (exactly 0 on it)."""
        edge = np.minimum(np.minimum(a - self.a_lines[0], self.a_lines[-1] - a),
                          np.minimum(b - self.b_lines[0], self.b_lines[-1] - b))
        t = np.clip(edge / self.taper, 0.0, 1.0)
        return t * t * (3.0 - 2.0 * t)


def layout(field: Heightfield, cam: PinholeCamera, p: NearFieldParams) -> Layout:
    """The near-field rectangle for this camera: from just behind the bottom of the frame to
    ``max_distance + taper`` ahead, as wide as the view there, snapped out to dune-grid lines."""
    pos = cam.position
    fwd = cam.camera_to_world[:3, 2]
    horiz = math.hypot(fwd[0], fwd[2])
    require(horiz > 0.1, "the near field needs a camera that looks roughly horizontally")
    axis = 0 if abs(fwd[0]) >= abs(fwd[2]) else 2
    other = 2 - axis
    sign = float(np.sign(fwd[axis]))
    ground = float(dune_height(field, np.array([pos[0]]), np.array([pos[2]]))[0])
    h = float(pos[1]) - ground
    require(h > 0, f"the camera is {-h:.3g} m below the sand")
    sx, sy = cam.screen_half_extent
    down = math.atan2(-fwd[1], horiz) + math.atan(sy)            # steepest ray below the horizon
    near = h / math.tan(down) if down < math.pi / 2 - 1e-6 else 0.0
    half_tan = 1.1 * sx + abs(fwd[other]) / horiz     # the view's half-width, 10 % margin, and its drift
    far = p.max_distance + p.taper
    grid_a, grid_b = (field.x, field.z) if axis == 0 else (field.z, field.x)
    cam_a, cam_b = float(pos[axis]), float(pos[other])
    lo_a, hi_a = sorted((cam_a + sign * 0.5 * near, cam_a + sign * far))
    half = half_tan * far + p.taper
    a_lines = _snap(grid_a, lo_a, hi_a)
    b_lines = _snap(grid_b, cam_b - half, cam_b + half)
    require(len(a_lines) >= 2 and len(b_lines) >= 2, "the near field lies outside the dune field")
    cell = max(field.dx, field.dz)
    return Layout(axis, cam_a, cam_b, h, near, half_tan, p.pixels_per_edge * cam.pixel_pitch, p.grading,
                  cell, a_lines, b_lines, p.taper)


def _snap(lines: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """The grid lines from the last one at or below ``lo`` to the first at or above ``hi``."""
    i0 = max(int(np.searchsorted(lines, lo, side="right")) - 1, 0)
    i1 = min(int(np.searchsorted(lines, hi, side="left")), len(lines) - 1)
    return lines[i0:i1 + 1]


def graded_points(lines: np.ndarray, spacing: Callable[[np.ndarray], np.ndarray], samples: int = 32) -> np.ndarray:
    """Points from lines[0] to lines[-1], including every line, spaced by ``spacing(t)`` (m):
    in each interval the point count is the integral of 1 / spacing, placed at equal steps of it."""
    out = [lines[:1]]
    for lo, hi in zip(lines[:-1], lines[1:]):
        t = np.linspace(lo, hi, samples)
        inv = 1.0 / spacing(t)
        cum = np.concatenate([[0.0], np.cumsum(0.5 * (inv[1:] + inv[:-1]) * np.diff(t))])
        n = max(1, int(math.ceil(cum[-1] - 1e-9)))
        pts = np.interp(np.linspace(0.0, cum[-1], n + 1)[1:-1], cum, t)
        out += [pts, [hi]]
    return np.concatenate(out)


def zipper(lo: np.ndarray, hi: np.ndarray, base_lo: int, base_hi: int) -> np.ndarray:
    """Triangles joining two rows of points (sorted across-coordinates ``lo`` and ``hi``, first
    vertex indices ``base_lo``/``base_hi``), advancing along whichever row's next point comes first."""
    key = np.concatenate([lo[1:], hi[1:]])
    which = np.concatenate([np.zeros(len(lo) - 1, int), np.ones(len(hi) - 1, int)])
    order = np.lexsort((which, key))
    which = which[order]
    i = np.concatenate([[0], np.cumsum(which == 0)])
    j = np.concatenate([[0], np.cumsum(which == 1)])
    step_lo = which == 0
    a = base_lo + i[:-1]
    b = np.where(step_lo, base_lo + i[1:], base_hi + j[1:])
    c = base_hi + j[:-1]
    return np.stack([a, b, c], axis=1)


@dataclass(frozen=True)
class Sand:
    """The whole sand sheet: vertices (N, 3), faces (M, 3), which faces are near field, the layout."""
    vertices: np.ndarray
    faces: np.ndarray
    near_faces: np.ndarray   # (M,) bool
    layout: Layout


def near_grid(lay: Layout) -> tuple[list[np.ndarray], np.ndarray, np.ndarray]:
    """Row positions along, the across-points of each row, and the near-field triangles."""
    rows_a = graded_points(lay.a_lines, lay.along_spacing)
    rows = [graded_points(lay.b_lines, lambda b, a=a: lay.across_spacing(a, b)) for a in rows_a]
    starts = np.concatenate([[0], np.cumsum([len(r) for r in rows])])
    faces = np.concatenate([zipper(rows[k], rows[k + 1], starts[k], starts[k + 1]) for k in range(len(rows) - 1)])
    return rows, rows_a, faces


def build_sand(field: Heightfield, ripples: RippleMap, cam: PinholeCamera, p: NearFieldParams) -> Sand:
    """Cut the near-field rectangle out of the dune mesh, tessellate it for the camera, and stitch."""
    lay = layout(field, cam, p)
    rows, rows_a, near_faces = near_grid(lay)
    a = np.concatenate([np.full(len(r), ra) for r, ra in zip(rows, rows_a)])
    b = np.concatenate(rows)
    x, z = (a, b) if lay.axis == 0 else (b, a)
    y = dune_height(field, x, z) + lay.weight(a, b) * ripples(x, z)
    near_v = np.stack([x, y, z], axis=1)

    nz, nx = field.y.shape
    xx, zz = np.meshgrid(field.x, field.z)
    far_v = np.stack([xx.ravel(), field.y.ravel(), zz.ravel()], axis=1)
    far_f = heightfield_faces(nz, nx)
    ca, cb = (far_v[far_f].mean(axis=1)[:, k] for k in ((lay.axis, 2 - lay.axis)))
    inside = (ca > lay.a_lines[0]) & (ca < lay.a_lines[-1]) & (cb > lay.b_lines[0]) & (cb < lay.b_lines[-1])
    far_f = far_f[~inside]

    # share the seam: a near vertex on a dune-grid node becomes that node
    ia = np.searchsorted(lay.a_lines, a)
    on_a = (ia < len(lay.a_lines)) & (lay.a_lines[np.minimum(ia, len(lay.a_lines) - 1)] == a)
    ib = np.searchsorted(lay.b_lines, b)
    on_b = (ib < len(lay.b_lines)) & (lay.b_lines[np.minimum(ib, len(lay.b_lines) - 1)] == b)
    gx = np.rint((x - field.x[0]) / field.dx).astype(int)
    gz = np.rint((z - field.z[0]) / field.dz).astype(int)
    seam_line = np.isin(a, lay.a_lines[[0, -1]]) | np.isin(b, lay.b_lines[[0, -1]])
    node = on_a & on_b & seam_line
    remap = np.arange(len(near_v)) + len(far_v)
    remap[node] = gz[node] * nx + gx[node]
    near_f = remap[near_faces]
    far_f = _split_seam(far_f, far_v, remap, lay, a, b, seam_line, len(far_v))

    vertices = np.concatenate([far_v, near_v])
    faces = np.concatenate([far_f, near_f])
    near_mask = np.concatenate([np.zeros(len(far_f), bool), np.ones(len(near_f), bool)])
    return _compact(vertices, faces, near_mask, lay)


def _split_seam(far_f: np.ndarray, far_v: np.ndarray, remap: np.ndarray, lay: Layout, a: np.ndarray,
                b: np.ndarray, on_edge: np.ndarray, n_far: int) -> np.ndarray:
    """Split every dune triangle with an edge on the seam into a fan through the near field's
    seam vertices on that edge, so no vertex of one side lies inside an edge of the other."""
    seam = np.flatnonzero(on_edge & (remap >= n_far))
    if len(seam) == 0:
        return far_f
    pa, pb = far_v[:, lay.axis], far_v[:, 2 - lay.axis]
    ends_a, ends_b = (lay.a_lines[0], lay.a_lines[-1]), (lay.b_lines[0], lay.b_lines[-1])
    on_seam = np.isin(pa, ends_a) | np.isin(pb, ends_b)
    near = np.flatnonzero(on_seam[far_f].sum(axis=1) >= 2)     # faces that may have an edge on it
    directed = {(int(far_f[k, e]), int(far_f[k, (e + 1) % 3])): (k, e) for k in near for e in range(3)}
    fans, split = [], []
    for (u, v), (k, e) in directed.items():
        if (v, u) in directed:
            continue                                    # an interior edge of the dune mesh
        if pa[u] == pa[v] and pa[u] in ends_a:          # seam row: points differ across
            fixed, t, start = a[seam] == pa[u], b[seam], pb[u]
            lo, hi = sorted((pb[u], pb[v]))
        elif pb[u] == pb[v] and pb[u] in ends_b:        # seam column: points differ along
            fixed, t, start = b[seam] == pb[u], a[seam], pa[u]
            lo, hi = sorted((pa[u], pa[v]))
        else:
            continue                                    # the dune field's outer edge
        sel = fixed & (t > lo) & (t < hi)
        if not sel.any():
            continue
        chain = [u, *remap[seam[sel][np.argsort(np.abs(t[sel] - start))]], v]
        apex = far_f[k][(e + 2) % 3]
        fans += [[chain[i], chain[i + 1], apex] for i in range(len(chain) - 1)]
        split.append(k)
    keep = np.ones(len(far_f), bool)
    keep[split] = False
    return np.concatenate([far_f[keep], np.asarray(fans, dtype=far_f.dtype).reshape(-1, 3)])


def _compact(vertices: np.ndarray, faces: np.ndarray, near_mask: np.ndarray, lay: Layout) -> Sand:
    """Drop unreferenced vertices; wind every triangle counter-clockwise seen from +y."""
    used = np.unique(faces)
    index = np.full(len(vertices), -1)
    index[used] = np.arange(len(used))
    v, f = vertices[used], index[faces]
    e1, e2 = v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]
    down = (e1[:, 2] * e2[:, 0] - e1[:, 0] * e2[:, 2]) < 0           # y of e1 x e2
    f[down] = f[down][:, ::-1]
    return Sand(v, f, near_mask, lay)


def bump_weight(field: Heightfield, lay: Layout, texel: float) -> np.ndarray:
    """1 - displacement weight at texel centres over the dune UV square, rows flipped for the
    renderer (row 0 at v = 1): the share of the ripples left to the bump map."""
    sx, sz = field.x[-1] - field.x[0], field.z[-1] - field.z[0]
    nx, nz = max(2, int(math.ceil(sx / texel))), max(2, int(math.ceil(sz / texel)))
    x = field.x[0] + (np.arange(nx) + 0.5) / nx * sx
    z = field.z[0] + (np.arange(nz) + 0.5) / nz * sz
    xx, zz = np.meshgrid(x, z)
    a, b = (xx, zz) if lay.axis == 0 else (zz, xx)
    inside = (a > lay.a_lines[0]) & (a < lay.a_lines[-1]) & (b > lay.b_lines[0]) & (b < lay.b_lines[-1])
    return np.flipud(1.0 - np.where(inside, lay.weight(a, b), 0.0))


def sand_uvs(vertices: np.ndarray, extent: tuple[float, float, float, float]) -> np.ndarray:
    """UVs over the dune UV square (u along +x, v along +z), as the dune mesh has them."""
    x0, x1, z0, z1 = extent
    return np.stack([(vertices[:, 0] - x0) / (x1 - x0), (vertices[:, 2] - z0) / (z1 - z0)], axis=1)


def write_sand(path: Path, vertices: np.ndarray, faces: np.ndarray, uvs: np.ndarray) -> None:
    """The sand sheet as PLY with smooth normals."""
    import trimesh

    normals = trimesh.Trimesh(vertices, faces, process=False).vertex_normals
    write_ply(path, vertices, faces, normals, uvs)


def write(job: Job) -> list[str]:
    from renderer.io.images import write_exr

    p = job.params
    field = read_heightfield(p.dunes)
    sand = build_sand(field, RippleMap.read(p.ripples), PinholeCamera.from_scene(p.scene), p)
    extent = (float(field.x[0]), float(field.x[-1]), float(field.z[0]), float(field.z[-1]))
    write_sand(job.stage / "sand.ply", sand.vertices, sand.faces, sand_uvs(sand.vertices, extent))
    write_exr(job.stage / "bump_weight.exr", {"Y": bump_weight(field, sand.layout, p.weight_texel).astype(np.float32)},
              {"units": "1"})
    lay = sand.layout
    job.note(near_triangles=int(sand.near_faces.sum()), triangles=int(len(sand.faces)),
             near_rect=[float(lay.a_lines[0]), float(lay.a_lines[-1]), float(lay.b_lines[0]), float(lay.b_lines[-1])],
             along_axis="xz"[lay.axis // 2], camera_height=lay.height, nearest_visible=lay.near)
    return ["sand.ply", "bump_weight.exr"]


GENERATOR = Generator("near-field", "the sand sheet: ripples as camera-tessellated geometry near, dune mesh beyond",
                      NearFieldParams, write, __doc__)
