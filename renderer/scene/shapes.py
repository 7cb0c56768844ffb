"""pbrt-v4 shapes as triangle meshes in object space. Analytic shapes are tessellated over pbrt's
own (u, v) parameterisation, so UVs match pbrt's and the per-vertex normals are the exact
analytic ones; triangles are wound so that cross(p1 - p0, p2 - p0) points along pbrt's
cross(dp/du, dp/dv), the side pbrt calls outside."""
from __future__ import annotations

import hashlib
import math
from typing import Callable

import numpy as np

from renderer.errors import Location, SceneError
from renderer.scene.description import MeshDesc
from renderer.scene.params import ParamSet

#: Segments around a full circle (sphere, disk); a UV sphere this fine is within 0.3 % of 4πr².
CIRCLE_SEGMENTS = 64
#: Grid cells along each side of a bilinear patch that is not planar (a planar one needs one).
PATCH_CELLS = 8


def validated_mesh(positions: np.ndarray, indices: np.ndarray, normals: np.ndarray | None, uvs: np.ndarray | None,
                   loc: Location, name: str) -> MeshDesc:
    """The one gate every mesh passes: finite values, consistent counts, indices in range."""
    P = np.asarray(positions, dtype=np.float64).reshape(-1, 3)
    F = np.asarray(indices, dtype=np.int64)
    if F.size % 3:
        raise SceneError(f"{name}: {F.size} indices is not a multiple of 3", loc)
    F = F.reshape(-1, 3)
    if F.size and (F.min() < 0 or F.max() >= len(P)):
        raise SceneError(f"{name}: vertex index {F.min() if F.min() < 0 else F.max()} out of range "
                         f"(the mesh has {len(P)} vertices)", loc)
    arrays = {"P": (P, 3), "N": (normals, 3), "uv": (uvs, 2)}
    out: dict[str, np.ndarray | None] = {}
    for key, (a, width) in arrays.items():
        if a is None:
            out[key] = None
            continue
        a = np.asarray(a, dtype=np.float64)
        if a.size != len(P) * width:
            raise SceneError(f"{name}: {key} has {a.size // width} entries for {len(P)} vertices", loc)
        with np.errstate(over="ignore"):          # too large for float32 becomes inf, refused below
            a32 = a.reshape(-1, width).astype(np.float32)
        if not np.all(np.isfinite(a32)):
            raise SceneError(f"{name}: {key} contains NaN or infinite values", loc)
        out[key] = a32
    return MeshDesc(positions=out["P"], indices=F.astype(np.int32), normals=out["N"], uvs=out["uv"],
                    loc=loc, name=name)


def _grid(P: np.ndarray, N: np.ndarray, UV: np.ndarray) -> tuple[np.ndarray, ...]:
    """Triangulate a surface sampled on a (rows=v, cols=u) grid, two triangles per cell, dropping
    the degenerate ones a pole or a disk's centre makes (their vertices stay, shared by neighbours)."""
    rows, cols = P.shape[:2]
    a = (np.arange(rows - 1)[:, None] * cols + np.arange(cols - 1)[None, :]).ravel()
    b, c, d = a + 1, a + cols + 1, a + cols
    F = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    V = P.reshape(-1, 3)
    area2 = np.linalg.norm(np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]), axis=1)
    scale = np.ptp(V, axis=0).max() if len(V) else 0.0
    F = F[area2 > 1e-12 * scale * scale]
    return V, F, N.reshape(-1, 3), UV.reshape(-1, 2)


def _with_area(mesh: MeshDesc, area: float) -> MeshDesc:
    mesh.analytic_area = float(area)
    return mesh


def _uv_grid(nu: int, nv: int) -> tuple[np.ndarray, np.ndarray]:
    return np.meshgrid(np.linspace(0.0, 1.0, nu + 1), np.linspace(0.0, 1.0, nv + 1))


def _phi_max(params: ParamSet) -> float:
    return math.radians(params.float("phimax", 360.0, min=0.0, max=360.0))


def _segments(angle: float) -> int:
    return max(3, math.ceil(CIRCLE_SEGMENTS * angle / (2.0 * math.pi)))


def _radius(params: ParamSet, loc: Location, default: float = 1.0) -> float:
    r = params.float("radius", default)
    if r <= 0.0:
        raise SceneError(f"radius must be > 0, got {r}", loc)
    return r


def sphere(params: ParamSet, loc: Location) -> MeshDesc:
    """pbrt's sphere, partial ones too: u = phi / phimax, v runs from zmin to zmax."""
    r = _radius(params, loc)
    zmin = float(np.clip(params.float("zmin", -r), -r, r))
    zmax = float(np.clip(params.float("zmax", r), -r, r))
    theta_min = math.acos(min(zmin, zmax) / r)        # at zmin: the larger polar angle
    theta_max = math.acos(max(zmin, zmax) / r)
    phi_max = _phi_max(params)
    u, v = _uv_grid(_segments(phi_max), max(2, math.ceil(CIRCLE_SEGMENTS / 2 * (theta_min - theta_max) / math.pi)))
    phi, theta = u * phi_max, theta_min + v * (theta_max - theta_min)
    N = np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], -1)
    return _with_area(validated_mesh(*_grid(r * N, N, np.stack([u, v], -1)), loc, "sphere"),
                      phi_max * r * abs(zmax - zmin))


def cylinder(params: ParamSet, loc: Location) -> MeshDesc:
    """pbrt's cylinder about z from zmin to zmax (sorted, as pbrt): u = phi / phimax, v along z."""
    r = _radius(params, loc)
    z0, z1 = sorted((params.float("zmin", -1.0), params.float("zmax", 1.0)))
    if z1 <= z0:
        raise SceneError(f"cylinder: zmin and zmax must differ, got {z0} and {z1}", loc)
    phi_max = _phi_max(params)
    u, v = _uv_grid(_segments(phi_max), 1)
    phi = u * phi_max
    N = np.stack([np.cos(phi), np.sin(phi), np.zeros_like(u)], -1)
    P = np.stack([r * N[..., 0], r * N[..., 1], z0 + v * (z1 - z0)], -1)
    return _with_area(validated_mesh(*_grid(P, N, np.stack([u, v], -1)), loc, "cylinder"), (z1 - z0) * r * phi_max)


def disk(params: ParamSet, loc: Location) -> MeshDesc:
    """pbrt's disk at z = height facing +z: u = phi / phimax, v = 0 on the rim, 1 at innerradius."""
    r = _radius(params, loc)
    ri = params.float("innerradius", 0.0, min=0.0)
    if ri >= r:
        raise SceneError(f"disk: innerradius {ri} must be smaller than radius {r}", loc)
    h = params.float("height", 0.0)
    phi_max = _phi_max(params)
    u, v = _uv_grid(_segments(phi_max), 1)
    phi, rho = u * phi_max, r - v * (r - ri)
    P = np.stack([rho * np.cos(phi), rho * np.sin(phi), np.full_like(u, h)], -1)
    N = np.broadcast_to([0.0, 0.0, 1.0], P.shape)
    return _with_area(validated_mesh(*_grid(P, N, np.stack([u, v], -1)), loc, "disk"), phi_max * 0.5 * (r * r - ri * ri))


def _indices(params: ParamSet, loc: Location, shape: str, n_points: int, corners: int) -> np.ndarray:
    """``indices``, which pbrt lets a single polygon (exactly ``corners`` vertices) leave out."""
    idx = params.ints("indices")
    if idx is None:
        if n_points != corners:
            raise SceneError(f'{shape}: "indices" is required unless there are exactly {corners} vertices', loc)
        idx = np.arange(corners)
    return idx


def triangle_mesh(params: ParamSet, loc: Location) -> MeshDesc:
    P = _points(params, loc, "trianglemesh")
    F = _indices(params, loc, "trianglemesh", len(P), 3)
    return validated_mesh(P, F, params.floats("N", ("normal3",)), _uvs(params), loc, "trianglemesh")


def bilinear_mesh(params: ParamSet, loc: Location) -> MeshDesc:
    """Bilinear patches p(u, v) = lerp(v, lerp(u, p00, p10), lerp(u, p01, p11)) with corners given as
    indices[4i..4i+3] = p00, p10, p01, p11. Planar patches become two triangles, others a grid."""
    P = _points(params, loc, "bilinearmesh")
    Q = _indices(params, loc, "bilinearmesh", len(P), 4)
    if Q.size % 4:
        raise SceneError(f"bilinearmesh: {Q.size} indices is not a multiple of 4", loc)
    if Q.size and (Q.min() < 0 or Q.max() >= len(P)):
        raise SceneError(f"bilinearmesh: vertex index out of range (the mesh has {len(P)} vertices)", loc)
    N = params.floats("N", ("normal3",))
    UV = _uvs(params)
    for key, a, width in (("N", N, 3), ("uv", UV, 2)):
        if a is not None and a.size != len(P) * width:
            raise SceneError(f"bilinearmesh: {key} has {a.size // width} entries for {len(P)} vertices", loc)
    N = None if N is None else N.reshape(-1, 3)
    UV = None if UV is None else UV.reshape(-1, 2)
    if not Q.size:                      # empty: the builder warns and skips it
        return validated_mesh(P, Q, None, None, loc, "bilinearmesh")
    parts = [_patch(P[q], None if N is None else N[q], None if UV is None else UV[q]) for q in Q.reshape(-1, 4)]
    offsets = np.cumsum([0] + [len(part[0]) for part in parts[:-1]])
    V, _, NN, TT = (np.concatenate(xs) for xs in zip(*parts))
    F = np.concatenate([part[1] + o for part, o in zip(parts, offsets)])
    mesh = validated_mesh(V, F, NN, TT, loc, "bilinearmesh")
    mesh.pbrt_shapes = len(parts)
    return mesh


def _patch(corners: np.ndarray, normals: np.ndarray | None, uvs: np.ndarray | None) -> tuple[np.ndarray, ...]:
    p00, p10, p01, p11 = corners
    extent = np.ptp(corners, axis=0).max()
    planar = abs(np.dot(np.cross(p10 - p00, p01 - p00), p11 - p00)) <= 1e-9 * extent ** 3
    n = 1 if planar else PATCH_CELLS
    u, v = _uv_grid(n, n)
    bilerp: Callable[[np.ndarray], np.ndarray] = lambda c: (
        ((1 - u) * (1 - v))[..., None] * c[0] + (u * (1 - v))[..., None] * c[1]
        + ((1 - u) * v)[..., None] * c[2] + (u * v)[..., None] * c[3])
    if normals is not None:
        N = bilerp(normals)
    else:
        # evaluated just inside the patch, where a corner collapsed to a point has a normal
        uc, vc = (np.clip(x, 1e-4, 1 - 1e-4)[..., None] for x in (u, v))
        dpdu = (1 - vc) * (p10 - p00) + vc * (p11 - p01)
        dpdv = (1 - uc) * (p01 - p00) + uc * (p11 - p10)
        N = np.cross(dpdu, dpdv)
    N = N / np.maximum(np.linalg.norm(N, axis=-1, keepdims=True), 1e-300)
    T = bilerp(uvs) if uvs is not None else np.stack([u, v], -1)
    return _grid(bilerp(corners), N, T)


def _points(params: ParamSet, loc: Location, shape: str) -> np.ndarray:
    P = params.floats("P", ("point3",))
    if P is None:
        raise SceneError(f'{shape}: "point3 P" is required', loc)
    return P.reshape(-1, 3)


def _uvs(params: ParamSet) -> np.ndarray | None:
    """pbrt-v4 writes ``point2 uv``; pbrt-v3 files have ``float uv`` (or ``float st``)."""
    return params.floats("uv" if "uv" in params or "st" not in params else "st", ("point2", "float"))



class MeshPool:
    """The scene's meshes with identical ones stored once, as pbrt shares a shape's data: 20,000
    ``Shape "sphere"`` lines of one radius become one tessellation (one BVH on the device) placed
    20,000 times, not 20,000 copies. An analytic shape is tessellated once per distinct parameter
    list; any other mesh merges with an earlier one whose arrays hold the same bytes (after any
    object-space transform), so only truly equal meshes merge."""

    #: Shapes whose tessellation is a pure function of their parameter list (no files read).
    ANALYTIC = ("sphere", "disk", "cylinder")

    def __init__(self, meshes: list[MeshDesc]):
        self.meshes = meshes
        self._by_bytes: dict[bytes, int] = {}
        self._by_object: dict[int, int] = {}
        self._by_params: dict[tuple, tuple[MeshDesc, list[str]]] = {}

    def shape(self, name: str, make: Callable[[ParamSet, Location], MeshDesc], params: ParamSet,
              loc: Location) -> MeshDesc:
        """``make(params, loc)``, made once per parameter list for an analytic shape; a repeat
        marks the same parameters read, so the unused-parameter warnings stay the same."""
        if name not in self.ANALYTIC:
            return make(params, loc)
        key = (name, tuple(sorted((p.name, p.type, repr(p.values)) for p in params.params.values())))
        if key not in self._by_params:
            mesh = make(params, loc)
            self._by_params[key] = (mesh, [n for n, p in params.params.items() if p.used])
        mesh, read = self._by_params[key]
        for n in read:
            params.get(n)
        return mesh

    def add(self, mesh: MeshDesc) -> int:
        """The index of ``mesh`` in the list, appending it only when no equal mesh is there."""
        known = self._by_object.get(id(mesh))
        if known is not None and self.meshes[known] is mesh:
            return known
        h = hashlib.blake2b(digest_size=20)
        for a in (mesh.positions, mesh.indices, mesh.normals, mesh.uvs):
            h.update(b"-" if a is None else np.ascontiguousarray(a).view(np.uint8).tobytes() + str(a.shape).encode())
        index = self._by_bytes.setdefault(h.digest(), len(self.meshes))
        if index == len(self.meshes):
            self.meshes.append(mesh)
        self._by_object[id(mesh)] = index
        return index
