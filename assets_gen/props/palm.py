"""Coconut palms: a curved, tapering trunk with growth rings (leaf scars), a crown of drooping
pinnate fronds, and coconuts under the crown.

The trunk leans at its foot and curves back towards vertical with height, as coconut palms grow
towards the light. Fronds sit on a phyllotactic spiral (golden angle); older, outer fronds droop
more. Each tree draws its own jitter (height, lean direction, frond angles and lengths, leaflet
droop) from the seed, so a few trees side by side are not clones.

Trunk and coconuts are closed solids. Leaflets are single-sided cards (open surfaces, not
watertight, by design: a frond is too thin for a solid); their normals follow their winding.
UVs: trunk u along the height (foot 0, crown 1), v around; rachis the same along the frond;
leaflet u from its base to its tip, v across it.

Placement: trunk foot at the origin on the ground (y = 0), ``embed`` below it; +y up.
Outputs per tree i: ``palm<i>_trunk.ply``, ``palm<i>_fronds.ply``, ``palm<i>_coconuts.ply``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from assets_gen.core import Generator, Job, Params, param, require
from assets_gen.core.meshing import Mesh, ellipsoid, grid_faces, rotation, tube

GOLDEN_ANGLE = np.pi * (3.0 - np.sqrt(5.0))
UP = np.array([0.0, 1.0, 0.0])


@dataclass(frozen=True)
class PalmParams(Params):
    height: float = param(7.0, "trunk length, m")
    lean_deg: float = param(12.0, "lean at the foot, degrees")
    fronds: int = param(14, "fronds per crown")
    frond_length: float = param(3.2, "frond length, m")
    leaflets: int = param(50, "leaflets per side of a frond")
    coconuts: int = param(5, "coconuts per tree")
    count: int = param(1, "trees, each with its own variation")
    embed: float = param(0.3, "trunk below the ground, m")

    def validate(self) -> None:
        require(2.0 <= self.height <= 30.0, f"height must be 2..30 m, got {self.height}")
        require(0.0 <= self.lean_deg <= 40.0, f"lean must be 0..40 deg, got {self.lean_deg}")
        require(3 <= self.fronds <= 40 and 10 <= self.leaflets <= 150,
                "fronds must be 3..40 and leaflets 10..150 per side")
        require(0.5 <= self.frond_length <= 7.0, f"frond length must be 0.5..7 m, got {self.frond_length}")
        require(0 <= self.coconuts <= 30 and 1 <= self.count <= 20, "coconuts must be 0..30 and count 1..20")
        require(0.0 <= self.embed <= 2.0, f"embed must be 0..2 m, got {self.embed}")


def integrate(directions: np.ndarray, length: float) -> np.ndarray:
    """A polyline of total ``length`` whose segments follow the unit ``directions`` (n, 3)."""
    step = length / (len(directions) - 1)
    return np.concatenate([np.zeros((1, 3)), np.cumsum(directions[1:] * step, axis=0)])


def trunk(height: float, lean: float, heading: float, base_r: float, top_r: float, ring_spacing: float,
          embed: float, rng: np.random.Generator) -> tuple[Mesh, np.ndarray, np.ndarray]:
    """Trunk mesh, crown point and crown axis. Rings: a narrow groove every ``ring_spacing``."""
    n = max(32, int(height / ring_spacing * 6))
    s = np.linspace(0.0, 1.0, n)
    tilt = lean * (1.0 - 0.7 * s) + 0.03 * np.sin(2 * np.pi * (s * rng.uniform(0.8, 1.4) + rng.uniform()))
    side = np.array([np.cos(heading), 0.0, -np.sin(heading)])
    dirs = np.cos(tilt)[:, None] * UP + np.sin(tilt)[:, None] * side
    path = integrate(dirs, height + embed) - np.array([0.0, embed, 0.0])
    arc = s * (height + embed)
    radius = top_r + (base_r - top_r) * (1 - s) ** 2 + 0.5 * base_r * np.exp(-np.maximum(arc - embed, 0) / 0.25)
    groove = np.abs(((arc / ring_spacing) % 1.0) - 0.5) * 2.0        # 1 on a ring, 0 between
    radius = radius * (1.0 - 0.05 * groove ** 8)
    body = tube(path, radius, sides=20, caps="flat")
    crown = path[-1]
    axis = dirs[-1]
    bulb = ellipsoid(crown, np.array([1.4, 1.4, 2.2]) * top_r, rotation=_frame_to(axis), rings=8, sides=16)
    return Mesh.join([body, bulb]), crown, axis


def _frame_to(axis: np.ndarray) -> np.ndarray:
    """A rotation taking +z to ``axis`` (for ellipsoids built along z)."""
    z = np.array([0.0, 0.0, 1.0])
    c = np.cross(z, axis)
    if np.linalg.norm(c) < 1e-9:
        return np.eye(3)
    return rotation(c, np.arccos(np.clip(np.dot(z, axis), -1.0, 1.0)))


def frond(base: np.ndarray, azimuth: float, elevation: float, droop: float, length: float,
          leaflets: int, rng: np.random.Generator) -> tuple[Mesh, np.ndarray, np.ndarray, np.ndarray]:
    """A frond's rachis (tube) and its leaflets as raw (vertices, faces, uvs)."""
    s = np.linspace(0.0, 1.0, 40)
    elev = elevation - droop * s ** 1.5
    head = np.array([np.cos(azimuth), 0.0, -np.sin(azimuth)])
    dirs = np.cos(elev)[:, None] * head + np.sin(elev)[:, None] * UP
    path = base + integrate(dirs, length)
    rachis = tube(path, 0.035 * (1 - s) + 0.006, sides=8, caps="round")
    # leaflets along 15..97 % of the rachis, both sides, angled towards the tip and hanging down
    t = np.linspace(0.15, 0.97, leaflets)
    at = np.array([np.interp(t, s, path[:, k]) for k in range(3)]).T
    tangent = np.array([np.interp(t, s, dirs[:, k]) for k in range(3)]).T
    lateral = np.cross(tangent, UP)
    lateral /= np.linalg.norm(lateral, axis=1, keepdims=True)
    below = np.cross(lateral, tangent)                               # rachis "down" (−up-ish)
    size = 0.55 * length * np.sin(np.pi * (t - 0.05)) ** 0.7 + 0.05
    verts, faces, uvs = [], [], []
    rows = 6
    along = np.linspace(0.0, 1.0, rows)[:, None]
    width = (0.012 + 0.03 * np.sin(np.pi * along) ** 0.8) * length / 3.0
    for side in (1.0, -1.0):
        hang = np.radians(35.0) + rng.normal(0.0, np.radians(6.0), leaflets)
        forward = np.radians(50.0) + rng.normal(0.0, np.radians(4.0), leaflets)
        out = (np.cos(forward)[:, None] * side * lateral + np.sin(forward)[:, None] * tangent)
        out = np.cos(hang)[:, None] * out - np.sin(hang)[:, None] * below
        across = np.cross(out, below) * side
        across /= np.linalg.norm(across, axis=1, keepdims=True)
        # centre line bends down under its own weight; three columns: edge, midrib, edge (folded V)
        centre = (at[:, None] + size[:, None, None] * along[None] * out[:, None]
                  - 0.25 * (size[:, None, None] * along[None] ** 2) * UP)
        cols = np.stack([centre - width[None] * across[:, None], centre + 0.15 * width[None] * UP,
                         centre + width[None] * across[:, None]], axis=2)  # (leaflets, rows, 3, 3)
        base_index = sum(len(v) for v in verts)
        verts.append(cols.reshape(-1, 3))
        per = rows * 3
        faces.append((grid_faces(rows, 3)[None] + per * np.arange(leaflets)[:, None, None]).reshape(-1, 3)
                     + base_index)
        uv = np.stack(np.meshgrid(np.linspace(0, 1, rows), np.linspace(0, 1, 3), indexing="ij"), -1)
        uvs.append(np.broadcast_to(uv.reshape(1, -1, 2), (leaflets, per, 2)).reshape(-1, 2))
    return rachis, np.concatenate(verts), np.concatenate(faces), np.concatenate(uvs)


def palm(p: PalmParams, rng: np.random.Generator) -> tuple[Mesh, Mesh, Mesh | None]:
    """(trunk, fronds, coconuts or None) for one tree, in metres."""
    fronds, coconuts = p.fronds, p.coconuts
    height = p.height * rng.uniform(0.9, 1.1)
    lean = np.radians(p.lean_deg) * rng.uniform(0.8, 1.2)
    heading = rng.uniform(0.0, 2 * np.pi)
    stem, crown, axis = trunk(height, lean, heading, 0.2 * height / 7 + 0.08, 0.13 * height / 7 + 0.05,
                              0.12, p.embed, rng)
    rachises, leaf_parts = [], []
    phase = rng.uniform(0.0, 2 * np.pi)
    for i in range(fronds):
        age = i / max(fronds - 1, 1)                                 # 0 = young, upright, inner
        elevation = np.radians(65.0 - 75.0 * age + rng.normal(0, 5))
        droop = np.radians(50.0 + 40.0 * age + rng.normal(0, 8))
        length = p.frond_length * (0.75 + 0.35 * age) * rng.uniform(0.9, 1.1)
        r, *raw = frond(crown + 0.1 * axis, phase + i * GOLDEN_ANGLE, elevation, droop, length, p.leaflets, rng)
        rachises.append(r)
        leaf_parts.append(raw)
    offsets = np.cumsum([0] + [len(p[0]) for p in leaf_parts])
    leaves = Mesh.part(np.concatenate([p[0] for p in leaf_parts]),
                       np.concatenate([p[1] + o for p, o in zip(leaf_parts, offsets)]),
                       np.concatenate([p[2] for p in leaf_parts]))
    nuts = None
    if coconuts:
        balls = []
        for k in range(coconuts):
            a = 2 * np.pi * k / coconuts + rng.normal(0, 0.3)
            centre = crown - (0.18 + rng.uniform(0.0, 0.12)) * axis + 0.2 * np.array([np.cos(a), 0, -np.sin(a)])
            spin = rotation(rng.normal(size=3), rng.uniform(0, np.pi))
            balls.append(ellipsoid(centre, np.array([0.10, 0.10, 0.13]) * rng.uniform(0.9, 1.1), spin,
                                   rings=10, sides=14))
        nuts = Mesh.join(balls)
    return stem, Mesh.join([*rachises, leaves]), nuts


def write(job: Job) -> list[str]:
    """``count`` trees, ``palm<i>_{trunk,fronds,coconuts}.ply``, each from its own seed drawn from the job's."""
    names: list[str] = []
    seeds = np.random.default_rng(job.seed).integers(0, 2 ** 63, size=job.params.count)
    for i, tree_seed in enumerate(seeds):
        for part, name in zip(palm(job.params, np.random.default_rng(int(tree_seed))), ("trunk", "fronds", "coconuts")):
            if part is not None:
                names.append(f"palm{i}_{name}.ply")
                part.write(job.stage / names[-1])
    return names


GENERATOR = Generator("palm", "coconut palms: curved ringed trunk, drooping fronds, coconuts",
                      PalmParams, write, __doc__)
