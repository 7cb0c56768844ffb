"""Props put down on the sand: ``rest`` drops a rigid mesh until it lies still on the surface
(sunglasses on their lens rims and temple tips), ``bury`` rests it and then sinks it by a fraction
of its height (a shell half in the sand, tilted along the surface), ``wedge`` keeps the given tilt
and sinks the prop's lowest edge into the sand by a fraction of its height (a valve left stuck
at an angle by the swash: the sand around the buried edge holds it, so it need not rest). The result is a pbrt Include
file with the object-to-world ``ConcatTransform`` and the same matrix as ``placement.npz``.

Resting is potential-energy minimisation under non-penetration: with the yaw fixed, the pose's
height and two tilts about the centre of mass are moved by the linear programme "lower the centre
of mass as far as possible without any vertex going below the sand" (the sand height under each
vertex by a ray cast), linearised for small tilts inside a shrinking trust region. An optimum of
three unknowns has three active contacts, and it stops only where no tilt lowers the centre of
mass: the centre of mass is over the triangle of contacts.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from assets_gen.core import Generator, GeneratorError, Job, Params, param, reading, require


#: Final gap left under the lowest contact, m: far below what a pixel resolves, above float32
#: rounding of PLY coordinates a few metres from the origin, so touching never reads as crossing.
LIFT = 2e-6


@dataclass(frozen=True)
class PlacementParams(Params):
    surface: str = param("assets/sand/sand.ply", "sand mesh to put the prop on (PLY, +y up, m)", path=True)
    mesh: str = param("assets/conch/conch.ply", "prop mesh, or a folder whose PLYs move as one rigid body",
                      path=True)
    mode: str = param("rest", "rest: lie still on >= 3 contacts; bury: rest, then sink; wedge: keep the tilt, "
                      "lower to the sand, then sink", choices=("rest", "bury", "wedge"))
    position: tuple[float, float] = param((0.0, 0.0), "approximate (x, z) of the centre of mass, m")
    yaw_deg: float = param(0.0, "rotation about +y, degrees (pbrt's Rotate yaw 0 1 0)")
    tilt_deg: tuple[float, float] = param((0.0, 0.0), "starting rotation about x, then z, before the yaw, degrees")
    depth: float = param(0.3, "bury, wedge: fraction of the placed prop's height sunk below its lowest point")
    contact_tolerance: float = param(5e-5, "gap below which a point counts as touching, m")

    def validate(self) -> None:
        require(Path(self.surface).is_file(), f"surface mesh {self.surface!r} not found")
        require(Path(self.mesh).exists(), f"prop mesh {self.mesh!r} not found")
        require(0 <= self.depth < 1, "depth must be a fraction in [0, 1)")
        require(self.contact_tolerance > LIFT, f"contact tolerance must exceed the {LIFT} m lift (m)")


def read_mesh(path: str | Path) -> tuple[np.ndarray, np.ndarray]:
    """(vertices, faces) of a PLY, or of all PLYs in a folder (sorted by name) as one mesh."""
    import trimesh

    path = Path(path)
    files = sorted(path.glob("*.ply")) if path.is_dir() else [path]
    require(len(files) > 0, f"no PLY files in {str(path)!r}")
    verts, faces, n = [], [], 0
    for f in files:
        with reading(f, "mesh"):
            m = trimesh.load(f, process=False, force="mesh")
        verts.append(np.asarray(m.vertices, dtype=np.float64))
        faces.append(np.asarray(m.faces) + n)
        n += len(m.vertices)
    v, f = np.concatenate(verts), np.concatenate(faces)
    require(len(f) > 0, f"prop mesh {str(path)!r} has no triangles")
    return v, f


def surface_patch(vertices: np.ndarray, faces: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """The faces with a vertex inside the (x, z) box [lo, hi]: the sand a prop can reach."""
    xz = vertices[:, [0, 2]]
    inside = np.all((xz >= lo) & (xz <= hi), axis=1)
    return faces[inside[faces].any(axis=1)]


class Ground:
    """Sand height under (x, z) points, by casting rays straight down onto a patch of the sand."""

    def __init__(self, vertices: np.ndarray, faces: np.ndarray, centre: np.ndarray, reach: float):
        self.vertices = vertices
        self.faces = surface_patch(vertices, faces, centre - reach, centre + reach)
        require(len(self.faces) > 0, f"no sand within {reach:.3g} m of ({centre[0]:.3g}, {centre[1]:.3g})")
        self.patch_vertices = np.unique(self.faces)
        self.top = float(vertices[self.patch_vertices, 1].max()) + 1.0

    def __call__(self, xz: np.ndarray) -> np.ndarray:
        from renderer.geometry.raycast import cast_rays

        origins = np.column_stack([xz[:, 0], np.full(len(xz), self.top), xz[:, 1]])
        t = cast_rays(self.vertices, self.faces, origins, np.tile([0.0, -1.0, 0.0], (len(xz), 1)))
        if not np.isfinite(t).all():
            raise GeneratorError("the prop reaches past the sand mesh; move it or widen the surface")
        return self.top - t

    def beneath(self, v: np.ndarray, f: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The points of the placed prop's lower surface straight above sand vertices, and their
        heights above the sand (negative where the sand pokes into the prop)."""
        from renderer.geometry.raycast import cast_rays

        sand = self.vertices[self.patch_vertices]
        lo, hi = v[:, [0, 2]].min(0), v[:, [0, 2]].max(0)
        sand = sand[np.all((sand[:, [0, 2]] >= lo) & (sand[:, [0, 2]] <= hi), axis=1)]
        bottom = float(min(v[:, 1].min(), sand[:, 1].min(initial=0.0))) - 1.0
        origins = np.column_stack([sand[:, 0], np.full(len(sand), bottom), sand[:, 2]])
        t = cast_rays(v, f, origins, np.tile([0.0, 1.0, 0.0], (len(sand), 1)))
        hit = np.isfinite(t)
        points = origins[hit] + np.outer(t[hit], [0.0, 1.0, 0.0])
        return points, points[:, 1] - sand[hit, 1]


def rotation(axis: str, deg: float) -> np.ndarray:
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    i, j = {"x": (1, 2), "y": (2, 0), "z": (0, 1)}[axis]
    r = np.eye(3)
    r[i, i], r[i, j], r[j, i], r[j, j] = c, -s, s, c
    return r


def rodrigues(w: np.ndarray) -> np.ndarray:
    """The rotation by the vector ``w`` (axis times angle, rad)."""
    angle = float(np.linalg.norm(w))
    if angle < 1e-15:
        return np.eye(3)
    k = w / angle
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(angle) * kx + (1 - math.cos(angle)) * kx @ kx


def centre_of_mass(v: np.ndarray, f: np.ndarray) -> np.ndarray:
    """Area-weighted centroid of the surface (props are shells of uniform thickness)."""
    tri = v[f]
    area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
    return (tri.mean(axis=1) * area[:, None]).sum(0) / max(area.sum(), 1e-300)


@dataclass(frozen=True)
class Pose:
    rotation: np.ndarray     # (3, 3)
    translation: np.ndarray  # (3,)
    contacts: int            # vertices within the contact tolerance
    min_gap: float           # lowest vertex above the sand, m (negative: below)

    def matrix(self) -> np.ndarray:
        m = np.eye(4)
        m[:3, :3], m[:3, 3] = self.rotation, self.translation
        return m

    def apply(self, v: np.ndarray) -> np.ndarray:
        return v @ self.rotation.T + self.translation


def rest(v: np.ndarray, f: np.ndarray, ground: Ground, position: np.ndarray, start: np.ndarray,
         tolerance: float, iterations: int = 300) -> Pose:
    """The rest pose of the rigid mesh (v, f) near ``position`` (x, z), from rotation ``start``."""
    from scipy.optimize import linprog

    com0 = centre_of_mass(v, f)
    rot = start.copy()
    trans = np.array([position[0], 0.0, position[1]]) - rot @ com0
    trust, band = 0.05, 0.02
    for _ in range(iterations):
        points, gap = _gaps(v, f, rot, trans, ground)
        trans[1] -= gap.min()
        points[:, 1] -= gap.min()
        gap -= gap.min()
        near = np.flatnonzero(gap < band)
        r = points[near] - (rot @ com0 + trans)
        # unknowns (dy, wx, wz): a contact's height change dy + wz r_x - wx r_z keeps gap_i + change >= 0
        a_ub = np.stack([-np.ones(len(near)), r[:, 2], -r[:, 0]], axis=1)
        res = linprog([1.0, 0.0, 0.0], A_ub=a_ub, b_ub=gap[near],
                      bounds=[(None, None), (-trust, trust), (-trust, trust)], method="highs")
        if res.status != 0:
            raise GeneratorError(f"rest pose: the linear programme failed ({res.message})")
        w = np.array([res.x[1], 0.0, res.x[2]])
        if np.abs(w).max() < 1e-9:
            break
        com = rot @ com0 + trans
        rot = rodrigues(w) @ rot
        trans = com + np.array([0.0, res.x[0], 0.0]) - rot @ com0
        if np.abs(w).max() < 0.99 * trust:
            trust = max(0.5 * trust, 1e-8)
    _, gap = _gaps(v, f, rot, trans, ground)
    lift = LIFT - gap.min()
    trans[1] += lift
    gap += lift
    return Pose(rot, trans, int((gap < tolerance).sum()), float(gap.min()))


def _gaps(v: np.ndarray, f: np.ndarray, rot: np.ndarray, trans: np.ndarray,
          ground: Ground) -> tuple[np.ndarray, np.ndarray]:
    """Points of the placed prop that may touch the sand (its vertices, and its lower surface over
    sand vertices) and their heights above the sand: both ways, so no sand crest pokes through a
    large prop triangle either."""
    p = v @ rot.T + trans
    above, gap = ground.beneath(p, f)
    return np.concatenate([p, above]), np.concatenate([p[:, 1] - ground(p[:, [0, 2]]), gap])


def place(p: PlacementParams) -> Pose:
    """The prop's pose on the sand for these parameters."""
    import trimesh

    v, f = read_mesh(p.mesh)
    with reading(p.surface, "surface mesh"):
        sand = trimesh.load(p.surface, process=False, force="mesh")
    start = rotation("y", p.yaw_deg) @ rotation("x", p.tilt_deg[0]) @ rotation("z", p.tilt_deg[1])
    reach = float(np.linalg.norm(v - centre_of_mass(v, f), axis=1).max()) + 0.01
    centre = np.array(p.position)
    ground = Ground(np.asarray(sand.vertices, dtype=np.float64), np.asarray(sand.faces), centre, reach)
    if p.mode == "wedge":
        trans = np.array([centre[0], 0.0, centre[1]]) - start @ centre_of_mass(v, f)
        _, gap = _gaps(v, f, start, trans, ground)
        trans[1] += LIFT - gap.min()
        pose = Pose(start, trans, 1, LIFT)
    else:
        pose = rest(v, f, ground, centre, start, p.contact_tolerance)
    if p.mode in ("bury", "wedge"):
        y = pose.apply(v)[:, 1]
        sink = p.depth * float(y.max() - y.min())
        pose = Pose(pose.rotation, pose.translation - [0.0, sink, 0.0], 0, pose.min_gap - sink)
    return pose


def pbrt_transform(m: np.ndarray) -> str:
    """pbrt's ConcatTransform lists the matrix column by column (translation last)."""
    return "ConcatTransform [" + " ".join(f"{x:.9g}" for x in m.T.ravel()) + "]"


def write(job: Job) -> list[str]:
    p = job.params
    pose = place(p)
    m = pose.matrix()
    np.savez(job.stage / "placement.npz", transform=m)
    (job.stage / "placement.pbrt").write_text(
        f"# {p.mode} of {Path(job.given.mesh).name} on {Path(job.given.surface).name}, written by "
        f"assets-gen placement: object-to-world\n{pbrt_transform(m)}\n")
    job.note(contacts=pose.contacts, min_gap_m=pose.min_gap, translation=[float(x) for x in pose.translation])
    return ["placement.npz", "placement.pbrt"]


GENERATOR = Generator("placement", "put a prop on the sand: rest on >= 3 contacts, or bury partly",
                      PlacementParams, write, __doc__)
