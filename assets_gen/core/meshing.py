"""Mesh pieces the generators share: quad grids from swept profiles, tubes along curves,
discs, solids made from an open surface plus an inner surface and rims, and smooth normals.

Conventions: a grid is ``points[i, j]`` with ``i`` along the sweep (UV ``u``) and ``j`` around the
profile (UV ``v``); its triangles wind so the face normal is ∂p/∂u × ∂p/∂v. A closed profile
(``wrap_v``) repeats its first column at ``v = 1`` so the UV seam has its own vertices; the
positions still coincide, so welding by position gives a watertight surface.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from assets_gen.core.output import write_ply


@dataclass(frozen=True)
class Mesh:
    """Triangles with per-vertex normals and UVs (metres, +y up once placed)."""

    vertices: np.ndarray  # (N, 3) float64
    faces: np.ndarray     # (F, 3) int64
    normals: np.ndarray   # (N, 3) float64, unit
    uvs: np.ndarray       # (N, 2) float64 in [0, 1]

    @staticmethod
    def part(vertices: np.ndarray, faces: np.ndarray, uvs: np.ndarray) -> "Mesh":
        """One smoothly shaded piece: normals averaged over coincident vertices (UV seams)."""
        v = np.asarray(vertices, dtype=np.float64)
        f = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
        return Mesh(v, f, smooth_normals(v, f), np.asarray(uvs, dtype=np.float64))

    @staticmethod
    def join(meshes: list["Mesh"]) -> "Mesh":
        """Concatenate parts, keeping each part's normals (so edges between parts stay sharp)."""
        offsets = np.cumsum([0] + [len(m.vertices) for m in meshes])
        return Mesh(np.concatenate([m.vertices for m in meshes]),
                    np.concatenate([m.faces + o for m, o in zip(meshes, offsets)]),
                    np.concatenate([m.normals for m in meshes]),
                    np.concatenate([m.uvs for m in meshes]))

    def subset(self, keep: np.ndarray) -> "Mesh":
        """The faces where ``keep`` is true, with only the vertices they use (in their order)."""
        used, faces = np.unique(self.faces[keep], return_inverse=True)
        return Mesh(self.vertices[used], faces.reshape(-1, 3), self.normals[used], self.uvs[used])

    def flipped(self) -> "Mesh":
        return Mesh(self.vertices, self.faces[:, ::-1].copy(), -self.normals, self.uvs)

    def transformed(self, rotation: np.ndarray, translation: np.ndarray = np.zeros(3),
                    scale: float = 1.0) -> "Mesh":
        """``x -> scale * R x + t`` for an orthogonal ``R``; normals turn with it, and a mirror
        (det R < 0) also reverses the winding so faces stay outward."""
        r = np.asarray(rotation, dtype=np.float64)
        faces = self.faces[:, ::-1].copy() if np.linalg.det(r) < 0 else self.faces
        return Mesh(scale * self.vertices @ r.T + translation, faces, self.normals @ r.T, self.uvs)

    def signed_volume(self) -> float:
        """Divergence-theorem volume; positive for a closed surface whose faces wind outward."""
        a, b, c = (self.vertices[self.faces[:, k]] for k in range(3))
        return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)

    def write(self, path: str | Path) -> None:
        write_ply(path, self.vertices, self.faces, self.normals, np.clip(self.uvs, 0.0, 1.0))


def weld_index(vertices: np.ndarray) -> np.ndarray:
    """Index of each vertex's position class (coincident within 1e-9 of the mesh size)."""
    extent = float(np.ptp(vertices, axis=0).max()) if len(vertices) else 1.0
    q = np.round(vertices / (max(extent, 1e-12) * 1e-9)).astype(np.int64)
    return np.unique(q, axis=0, return_inverse=True)[1].reshape(-1)


def smooth_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Area-weighted vertex normals that agree with the face winding, welded across seams."""
    weld = weld_index(vertices)
    a, b, c = (vertices[faces[:, k]] for k in range(3))
    fn = np.cross(b - a, c - a)
    acc = np.zeros((weld.max() + 1, 3))
    for k in range(3):
        np.add.at(acc, weld[faces[:, k]], fn)
    n = acc[weld]
    length = np.linalg.norm(n, axis=1, keepdims=True)
    return n / np.where(length > 0, length, 1.0)


def grid_faces(n_u: int, n_v: int) -> np.ndarray:
    """Two triangles per quad of an ``n_u`` × ``n_v`` vertex grid, wound as ∂p/∂u × ∂p/∂v."""
    i, j = np.meshgrid(np.arange(n_u - 1), np.arange(n_v - 1), indexing="ij")
    a = (i * n_v + j).ravel()
    b, c, d = a + n_v, a + n_v + 1, a + 1
    return np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])


def seam_grid(points: np.ndarray, wrap_v: bool = False, wrap_u: bool = False) -> np.ndarray:
    """Repeat the first column (row) at the end of a closed profile (path) so UVs can reach 1."""
    p = np.asarray(points, dtype=np.float64)
    if wrap_v:
        p = np.concatenate([p, p[:, :1]], axis=1)
    if wrap_u:
        p = np.concatenate([p, p[:1]], axis=0)
    return p


def grid(points: np.ndarray, wrap_v: bool = False, wrap_u: bool = False,
         u: np.ndarray | None = None, v: np.ndarray | None = None) -> Mesh:
    """A swept surface: ``points`` (n_u, n_v, 3), UV ``u`` down the rows and ``v`` across columns
    (both 0 → 1 by default, seam columns included)."""
    p = seam_grid(points, wrap_v, wrap_u)
    n_u, n_v = p.shape[:2]
    u = np.linspace(0.0, 1.0, n_u) if u is None else np.asarray(u, dtype=np.float64)
    v = np.linspace(0.0, 1.0, n_v) if v is None else np.asarray(v, dtype=np.float64)
    uv = np.stack(np.meshgrid(u, v, indexing="ij"), axis=-1).reshape(-1, 2)
    return Mesh.part(p.reshape(-1, 3), grid_faces(n_u, n_v), uv)


def disc(rings: np.ndarray, centre: np.ndarray, ring_uvs: np.ndarray, centre_uv: np.ndarray) -> Mesh:
    """A disc-like surface: concentric closed ``rings`` (n_r, n_t, 3), innermost first, joined to a
    ``centre`` vertex by a fan (no collapsed rows, so no degenerate triangles). Winding follows
    ∂p/∂r × ∂p/∂t, i.e. +z for counter-clockwise rings seen from +z. ``ring_uvs`` (n_r, n_t, 2)."""
    p = seam_grid(rings, wrap_v=True)
    uv = seam_grid(ring_uvs, wrap_v=True)
    n_r, n_t = p.shape[:2]
    ring0 = np.arange(n_t) + 1
    fan = np.stack([np.zeros(n_t - 1, dtype=np.int64), ring0[:-1], ring0[1:]], 1)
    return Mesh.part(np.concatenate([[centre], p.reshape(-1, 3)]),
                     np.concatenate([fan, grid_faces(n_r, n_t) + 1]),
                     np.concatenate([[centre_uv], uv.reshape(-1, 2)]))


def closed_solid(outer: Mesh, inner_vertices: np.ndarray, loops: list[np.ndarray]) -> Mesh:
    """Close an open surface into a solid: an inner surface with the same connectivity (winding
    reversed) at ``inner_vertices``, and a rim strip along each boundary ``loop`` (closed index
    loops into ``outer.vertices``). The rim winds against the outer surface's boundary edges so
    the whole solid is consistently oriented; rims are flat-shaded quads, so their edges stay sharp."""
    inner = Mesh.part(inner_vertices, outer.faces[:, ::-1], outer.uvs)
    directed = set(map(tuple, np.concatenate([outer.faces[:, [0, 1]], outer.faces[:, [1, 2]],
                                              outer.faces[:, [2, 0]]]).tolist()))
    rims = []
    for loop in loops:
        loop = np.asarray(loop)
        if (int(loop[0]), int(loop[1])) not in directed:
            loop = loop[::-1]
        # one flat quad (own 4 vertices) per boundary edge: the rim is as narrow as the wall, and
        # smoothing it around the loop's corners would bend normals against the faces
        a, b = loop, np.roll(loop, -1)
        quads = np.stack([outer.vertices[b], outer.vertices[a], inner_vertices[a], inner_vertices[b]], 1)
        n = np.cross(quads[:, 1] - quads[:, 0], quads[:, 2] - quads[:, 0])
        n += np.cross(quads[:, 2] - quads[:, 0], quads[:, 3] - quads[:, 0])
        n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
        base = 4 * np.arange(len(loop))[:, None]
        faces = np.concatenate([base + [0, 1, 2], base + [0, 2, 3]])
        uvs = np.stack([outer.uvs[b], outer.uvs[a], outer.uvs[a], outer.uvs[b]], 1)
        rims.append(Mesh(quads.reshape(-1, 3), faces, np.repeat(n, 4, axis=0), uvs.reshape(-1, 2)))
    return Mesh.join([outer, inner, *rims])


def grid_boundary(n_u: int, n_v: int, wrap_v: bool) -> list[np.ndarray]:
    """Boundary loops of a grid laid out by :func:`grid` (seam column included when ``wrap_v``)."""
    idx = np.arange(n_u * n_v).reshape(n_u, n_v)
    if wrap_v:
        return [idx[0, :-1], idx[-1, :-1]]
    return [np.concatenate([idx[0, :-1], idx[:-1, -1], idx[-1, :0:-1], idx[:0:-1, 0]])]


def thicken(points: np.ndarray, thickness: np.ndarray | float, outward: np.ndarray,
            wrap_v: bool = False, u: np.ndarray | None = None, v: np.ndarray | None = None,
            height_field: bool = False) -> Mesh:
    """A solid wall from an open swept surface: the surface is the outside (its normals turned to
    agree on average with the ``outward`` hint, (3,) or per point), the inside is the surface moved
    ``thickness`` (scalar or per point, (n_u, n_v)) along the inward normal, with rims on the boundary.
    A ``height_field`` over the plane normal to a fixed ``outward`` is moved straight along it
    instead: corrugations sharper than the wall (scallop ribs) then stay corrugated, not folded."""
    outer = grid(points, wrap_v=wrap_v, u=u, v=v)
    hint = np.broadcast_to(np.asarray(outward, dtype=np.float64), np.shape(points))
    if np.einsum("ij,ij->", outer.normals, seam_grid(hint, wrap_v).reshape(-1, 3)) < 0:
        outer = outer.flipped()
    t = seam_grid(np.broadcast_to(np.asarray(thickness, dtype=np.float64)[..., None],
                                  np.shape(points)[:2] + (1,)), wrap_v).reshape(-1, 1)
    n_u, n_v = np.shape(points)[0], np.shape(points)[1] + int(wrap_v)
    inward = hint.reshape(-1, 3)[:1] if height_field else outer.normals
    return closed_solid(outer, outer.vertices - t * inward, grid_boundary(n_u, n_v, wrap_v))


def transport_frames(path: np.ndarray, closed: bool = False) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rotation-minimising (parallel-transport) frames (T, N, B) along a polyline, so a swept
    tube does not twist."""
    p = np.asarray(path, dtype=np.float64)
    d = (np.roll(p, -1, 0) - np.roll(p, 1, 0)) if closed else np.gradient(p, axis=0)
    t = d / np.linalg.norm(d, axis=1, keepdims=True)
    seed = np.eye(3)[np.argmin(np.abs(t[0]))]
    n = np.empty_like(t)
    n[0] = np.cross(t[0], np.cross(seed, t[0]))
    n[0] /= np.linalg.norm(n[0])
    for k in range(1, len(p)):
        m = n[k - 1] - t[k] * np.dot(n[k - 1], t[k])
        n[k] = m / np.linalg.norm(m)
    return t, n, np.cross(t, n)


def tube(path: np.ndarray, radius: np.ndarray | float, sides: int = 12, closed: bool = False,
         caps: str = "flat", u: np.ndarray | None = None) -> Mesh:
    """Sweep a circle (radius per path point, or (n, sides) for a shaped profile) along ``path``;
    outward normals, UV ``u`` along the path and ``v`` around. ``caps``: "flat" (separate sharp
    discs), "round" (fan to a point one end radius beyond each end, shaded with the body), or
    "none"; a ``closed`` path (a loop) has no caps."""
    p = np.asarray(path, dtype=np.float64)
    t, n, b = transport_frames(p, closed)
    psi = 2.0 * np.pi * np.arange(sides) / sides
    r = np.asarray(radius, dtype=np.float64)
    r = np.broadcast_to(r.reshape(len(p), -1) if r.ndim else r, (len(p), sides))
    # the profile turns from N towards -B, so ∂p/∂u × ∂p/∂v points away from the axis
    ring = np.cos(psi)[None, :, None] * n[:, None] - np.sin(psi)[None, :, None] * b[:, None]
    pts = p[:, None] + r[..., None] * ring
    body = grid(pts, wrap_v=True, wrap_u=closed, u=u)
    if closed or caps == "none":
        return body
    ends = []
    for k, sign, uend in ((0, -1.0, 0.0), (len(p) - 1, 1.0, 1.0)):
        rim = np.concatenate([pts[k], pts[k, :1]])
        apex = p[k] + (sign * r[k].mean() * t[k] if caps == "round" else 0.0)
        ends.append(_cap(rim, apex, sign < 0, uend))
    if caps == "round":
        return Mesh.part(*_concat([body, *ends]))
    return Mesh.join([body, *(Mesh.part(*e) for e in ends)])


def _cap(rim: np.ndarray, apex: np.ndarray, reverse: bool, u: float):
    """Fan from ``apex`` to a closed ``rim`` (seam vertex repeated), as raw (verts, faces, uvs)."""
    m = len(rim)
    j = np.arange(m - 1) + 1
    faces = np.stack([np.zeros(m - 1, dtype=np.int64), j, j + 1], 1)
    faces = faces[:, ::-1] if not reverse else faces
    uvs = np.concatenate([[[u, 0.5]], np.stack([np.full(m, u), np.linspace(0, 1, m)], 1)])
    return np.concatenate([[apex], rim]), faces, uvs


def _concat(pieces) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Concatenate Meshes / raw (verts, faces, uvs) into one raw piece."""
    raw = [(m.vertices, m.faces, m.uvs) if isinstance(m, Mesh) else m for m in pieces]
    offsets = np.cumsum([0] + [len(r[0]) for r in raw])
    return (np.concatenate([r[0] for r in raw]), np.concatenate([r[1] + o for r, o in zip(raw, offsets)]),
            np.concatenate([r[2] for r in raw]))


def ellipsoid(centre: np.ndarray, radii: np.ndarray, rotation: np.ndarray = np.eye(3),
              rings: int = 12, sides: int = 16) -> Mesh:
    """A closed ellipsoid (radii along the rotated x, y, z axes; poles on z), built as a round-capped
    tube so it has no collapsed rows."""
    theta = np.linspace(0.0, np.pi, rings + 2)[1:-1]
    path = np.stack([np.zeros_like(theta), np.zeros_like(theta), -np.cos(theta)], 1)
    sphere = tube(path, np.sin(theta), sides=sides, caps="none")
    poles = [_cap(np.concatenate([sphere.vertices[:sides + 1]]), np.array([0, 0, -1.0]), True, 0.0),
             _cap(sphere.vertices[-(sides + 1):], np.array([0, 0, 1.0]), False, 1.0)]
    unit = _concat([sphere, *poles])
    v = unit[0] * np.asarray(radii, dtype=np.float64)
    return Mesh.part(v @ np.asarray(rotation).T + centre, unit[1], unit[2])


def rotation(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rodrigues rotation matrix about ``axis`` by ``angle`` radians."""
    k = np.asarray(axis, dtype=np.float64)
    k = k / np.linalg.norm(k)
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(angle) * kx + (1 - np.cos(angle)) * kx @ kx
