"""Seashells: the parametric gastropod shell of Cortie (1989) in Picado's (2009) notation, a
ribbed scallop valve and a pearl-oyster valve (nacreous inside).

The gastropod surface is a logarithmic helico-spiral swept by an elliptical aperture that grows
with it (optionally carrying nodules). For growth angle θ and aperture angle s:

    g = exp(θ cot α),  r(s, θ) = (cos²s/a² + sin²s/b²)^(-1/2) + k(s, θ)
    x = D (A sinβ cosθ + r cos(s+φ) cos(θ+Ω) − r sinμ sin(s+φ) sinθ) g
    y = (−A sinβ sinθ − r cos(s+φ) sin(θ+Ω) − r sinμ sin(s+φ) cosθ) g
    z = (−A cosβ + r sin(s+φ) cosμ) g
    k = L exp(−(2(s−P)/W1)² − (2 G(θ)/W2)²),  G(θ) = (2π/N)(Nθ/2π − round(Nθ/2π))

α is the equiangular (growth) angle, β the spire angle, A the aperture's distance from the axis,
a and b the aperture's semi-axes, φ Ω μ its orientation, D = ±1 the coiling sense, and L P W1 W2 N
the nodules' height, position on the aperture, widths and count per whorl. The spiral's axis (z)
becomes +y, apex up; the shell is scaled to the requested length in metres.

UVs follow growth: u = θ from apex (0) to lip (1), v = s around the aperture; for the scallop
and the pearl oyster u runs from the umbo to the margin and v across the fan. Lines of constant u
are growth lines. A bivalve's inside (the ``_inner`` file) is the concave face of the valve: with
``inside_up`` the valve lies on its convex back, its inside open to the sky.
The wall is solid: an inner surface (the aperture shrunk towards its centre by the wall fraction,
which never folds over), a rim at the lip and a plug-like rim at the apex. Successive whorls of a
gastropod overlap each other as in the published model; each whorl is still a closed solid.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, replace

import numpy as np

from assets_gen.core import Generator, Job, Params, param, require
from assets_gen.core.meshing import Mesh, closed_solid, grid, grid_boundary, seam_grid, thicken


@dataclass(frozen=True)
class Gastropod:
    """Cortie/Picado shell parameters (angles in degrees, lengths relative to each other)."""

    alpha: float    # equiangular spiral angle
    beta: float     # spire angle: between the coiling axis and the spiral's growth
    A: float        # aperture centre's distance from the origin at θ = 0
    a: float        # aperture semi-axis across the whorl (radial)
    b: float        # aperture semi-axis along the coiling axis
    phi: float      # aperture rotation in its plane
    omega: float    # aperture rotation about the coiling axis
    mu: float       # aperture tilt out of the radial plane
    turns: float    # whorls from apex to lip
    D: int = 1      # +1 dextral, -1 sinistral
    L: float = 0.0  # nodule height
    P: float = 0.0  # nodule position on the aperture (rad of s)
    W1: float = 1.0  # nodule width along s (rad)
    W2: float = 1.0  # nodule width along θ (rad)
    N: float = 0.0  # nodules per whorl


#: Presets shaped after real shells (parameters chosen by us in Cortie's/Picado's ranges).
PRESETS: dict[str, Gastropod] = {
    # tall, slowly expanding tower of many whorls
    "turritella": Gastropod(alpha=88.9, beta=4.0, A=22.2, a=1.3, b=1.5, phi=0.0, omega=0.0, mu=0.0,
                            turns=12.0),
    # planispiral, involute: each whorl wraps the last (expansion e^(2π cot 80°) ≈ 3 per whorl)
    "nautilus": Gastropod(alpha=80.0, beta=90.0, A=1.0, a=0.55, b=0.42, phi=0.0, omega=0.0, mu=0.0,
                          turns=3.0),
    # conical spire, large body whorl with a row of knobs on the shoulder
    "conch": Gastropod(alpha=84.0, beta=22.0, A=2.6, a=0.85, b=1.7, phi=-15.0, omega=0.0, mu=4.0,
                       turns=6.0, L=0.55, P=1.0, W1=0.6, W2=0.4, N=9.0),
}
SCALLOP = "scallop"
PEARL_OYSTER = "pearl-oyster"
BIVALVES = (SCALLOP, PEARL_OYSTER)


def gastropod_surface(g: Gastropod, n_theta: int, n_s: int, cords: int = 0,
                      cord_height: float = 0.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Points (n_theta, n_s, 3) of the shell surface in the model's z-up frame, the aperture centres
    (n_theta, 3), and θ (n_theta,). ``cords`` spiral ribs (lines of constant s, as on whelks and
    conchs) raise r by up to ``cord_height`` of itself, with narrow crests and wide troughs."""
    alpha, beta, phi, omega, mu = np.radians([g.alpha, g.beta, g.phi, g.omega, g.mu])
    theta = np.linspace(0.0, 2.0 * np.pi * g.turns, n_theta)[:, None]
    s = np.linspace(-np.pi, np.pi, n_s, endpoint=False)[None, :]
    growth = np.exp(theta / np.tan(alpha))
    r = 1.0 / np.sqrt(np.cos(s) ** 2 / g.a ** 2 + np.sin(s) ** 2 / g.b ** 2)
    if g.N > 0 and g.L > 0:
        nth = g.N * theta / (2.0 * np.pi)
        G = (2.0 * np.pi / g.N) * (nth - np.round(nth))
        r = r + g.L * np.exp(-(2.0 * (s - g.P) / g.W1) ** 2 - (2.0 * G / g.W2) ** 2)
    if cords > 0:
        r = r * (1.0 + cord_height * (0.5 + 0.5 * np.cos(cords * s)) ** 3)
    cx = g.D * g.A * np.sin(beta) * np.cos(theta)
    cy = -g.A * np.sin(beta) * np.sin(theta)
    cz = -g.A * np.cos(beta) * np.ones_like(theta)
    x = g.D * (r * np.cos(s + phi) * np.cos(theta + omega) - r * np.sin(mu) * np.sin(s + phi) * np.sin(theta))
    y = -r * np.cos(s + phi) * np.sin(theta + omega) - r * np.sin(mu) * np.sin(s + phi) * np.cos(theta)
    z = r * np.sin(s + phi) * np.cos(mu)
    centres = np.concatenate([cx, cy, cz], axis=1)
    pts = (np.stack(np.broadcast_arrays(x, y, z), axis=-1) + centres[:, None]) * growth[..., None]
    return pts, centres * growth, theta[:, 0]


def gastropod_mesh(g: Gastropod, wall: float, per_turn: int, around: int, cords: int = 0,
                   cord_height: float = 0.0) -> tuple[Mesh, int]:
    """The solid shell in the model frame, and how many of its faces (the first) are the outer
    surface; the inner surface's as many follow, then the rims. ``wall`` is the wall's share of the
    aperture radius; over the first half whorl it closes towards the centre so the apex reads as
    sealed. Cords are on the outside only: the inner surface follows the smooth whorl."""
    n_theta = max(8, int(round(per_turn * g.turns)) + 1)
    pts, centres, theta = gastropod_surface(g, n_theta, around, cords, cord_height)
    smooth = gastropod_surface(g, n_theta, around)[0] if cords > 0 else pts
    outer = grid(pts, wrap_v=True)
    if np.einsum("ij,ij->", outer.normals,
                 seam_grid(pts - centres[:, None], wrap_v=True).reshape(-1, 3)) < 0:
        outer = outer.flipped()
    seal = np.clip(theta / np.pi, 0.0, 1.0)
    keep = (1.0 - wall) * seal + 0.3 * (1.0 - seal)      # inner/outer radius about the centre
    c = centres[:, None]
    inner = seam_grid(c + keep[:, None, None] * (smooth - c), wrap_v=True).reshape(-1, 3)
    return closed_solid(outer, inner, grid_boundary(n_theta, around + 1, wrap_v=True)), len(outer.faces)


def scallop_mesh(ribs: int, wall: float, n_r: int, n_fan: int) -> tuple[Mesh, int]:
    """A scallop valve of unit length (umbo to margin) in a z-up frame: a domed fan with ``ribs``
    radial ribs and two flat ears on the hinge line, built in polar coordinates around the umbo;
    and the count of its outer (convex, upper) surface's faces, which come first."""
    fan = np.radians(60.0)
    rho = np.linspace(0.04, 1.0, n_r)[:, None]
    psi = np.linspace(-np.pi / 2, np.pi / 2, n_fan)[None, :]
    ear = 0.28
    # outline: a circle through the umbo (r = cos ψ) inside the fan, straight ears beyond it
    t = np.clip((np.abs(psi) - fan) / (np.pi / 2 - fan), 0.0, 1.0)
    r_max = np.where(np.abs(psi) <= fan, np.cos(psi), (1 - t) * np.cos(fan) + t * ear)
    r = rho * r_max
    x, y = r * np.sin(psi), r * np.cos(psi)
    dome = 0.2 * np.clip(1.0 - (x ** 2 + (y - 0.5) ** 2) / 0.4, 0.0, None)
    in_fan = np.clip(1.0 - t * 3.0, 0.0, 1.0)
    rib = 0.025 * rho * in_fan * (0.5 + 0.5 * np.cos(ribs * np.pi * psi / fan)) ** 1.5
    pts = np.stack(np.broadcast_arrays(x, y, dome + rib), axis=-1)
    # the wall thins towards the umbo, where the valve tapers to its beak
    return (thicken(pts, wall * np.clip(rho / 0.3, 0.03, 1.0) * np.ones_like(psi), outward=np.array([0.0, 0.0, 1.0]),
                    height_field=True), 2 * (n_r - 1) * (n_fan - 1))


def valve_outline(psi: np.ndarray, radius: float, hinge: float, oblique: float) -> np.ndarray:
    """Distance from the umbo (the origin, mid-hinge) along the directions ``psi`` (from +y, the
    umbo-margin axis) to a valve's margin: the convex hull of a disc of ``radius`` through the
    umbo, stretched by ``1 + oblique`` on the +x (posterior) side, and the straight hinge line
    from x = -hinge to +hinge on y = 0."""
    from scipy.spatial import ConvexHull

    phi = np.linspace(0.0, 2.0 * np.pi, 721)[:-1]
    x, y = radius * np.sin(phi), radius * (1.0 - np.cos(phi))
    pts = np.concatenate([np.stack([x * np.where(x > 0, 1.0 + oblique, 1.0), y], 1), [[-hinge, 0.0], [hinge, 0.0]]])
    hull = pts[ConvexHull(pts).vertices]
    a, e = hull, np.roll(hull, -1, axis=0) - hull                    # edges a + s e, s in [0, 1]
    d = np.stack([np.sin(psi), np.cos(psi)], 1)
    # origin + r d = a + s e  ->  solve per (ray, edge) with 2D cross products
    cross = d[:, None, 0] * e[None, :, 1] - d[:, None, 1] * e[None, :, 0]
    safe = np.where(np.abs(cross) > 1e-12, cross, np.inf)
    r = (a[None, :, 0] * e[None, :, 1] - a[None, :, 1] * e[None, :, 0]) / safe
    s = (a[None, :, 0] * d[:, None, 1] - a[None, :, 1] * d[:, None, 0]) / safe
    r = np.where((s >= -1e-9) & (s <= 1 + 1e-9), r, 0.0)
    return np.maximum(r.max(axis=1), np.where(np.abs(np.abs(psi) - np.pi / 2) < 1e-9, hinge, 0.0))


def oyster_mesh(wall: float, depth: float, lamellae: int, n_r: int, n_fan: int,
                rng: np.random.Generator) -> tuple[Mesh, int]:
    """A pearl-oyster (Pinctada) valve 1.1 units from umbo to ventral margin (``shell_mesh`` scales
    it to its length) in a z-up frame, its convex outside up; and the count of its outer surface's
    faces, which come first. The outline is
    nearly round with a long straight hinge (:func:`valve_outline`), the valve a cup ``depth``
    deep; the outside carries ``lamellae`` concentric growth lamellae (each a step ending in a
    lip, as the overlapping growth scales of Pinctada), the inside is smooth: it is the nacre.
    Built in polar coordinates around the umbo like :func:`scallop_mesh`; the seed only varies the
    outline's obliquity and the lamellae's spacing."""
    rho = np.linspace(0.03, 1.0, n_r)[:, None]
    psi = np.linspace(-np.pi / 2, np.pi / 2, n_fan)[None, :]
    oblique = 0.08 + 0.04 * rng.uniform(-1.0, 1.0)      # the posterior side grows a little further
    r_max = valve_outline(psi[0], 0.55, hinge=0.42, oblique=oblique)[None, :]
    r = rho * r_max
    x, y = r * np.sin(psi), r * np.cos(psi)
    # the cup: highest over the valve's centre, falling to the margin as (1 - d²)^0.75
    d2 = (x / 0.57) ** 2 + ((y - 0.55) / 0.57) ** 2
    cup = depth * np.clip(1.0 - d2, 0.0, None) ** 0.75
    # lamellae: a sawtooth in ρ (slow rise, sharp lip), their spacing widening towards the margin
    edges = np.cumsum(rng.gamma(8.0, 1.0 / 8.0, size=lamellae))
    phase = np.interp(np.sqrt(rho), np.concatenate([[0.0], edges / edges[-1]]), np.arange(lamellae + 1.0)) % 1.0
    step = 0.35 * wall * rho * phase ** 2
    smooth = np.stack(np.broadcast_arrays(x, y, cup), axis=-1)
    outer = grid(smooth + step[..., None] * np.array([0.0, 0.0, 1.0]))
    if outer.normals[:, 2].sum() < 0:
        outer = outer.flipped()
    # the wall (straight down, so the thin margin never folds) thins towards the margin and the umbo
    t_wall = wall * np.clip(rho / 0.2, 0.05, 1.0) * (1.0 - 0.6 * rho ** 4) * np.ones_like(psi)
    inner = smooth.reshape(-1, 3) - t_wall.reshape(-1, 1) * np.array([0.0, 0.0, 1.0])
    n_u, n_v = np.shape(smooth)[:2]
    return closed_solid(outer, inner, grid_boundary(n_u, n_v, False)), len(outer.faces)


def solid_parts(solid: Mesh, n_outer: int) -> tuple[Mesh, Mesh]:
    """(exterior, interior) of a solid laid out by :func:`closed_solid` (outer faces, as many inner
    faces, then rims): the outer surface with the rims, and the inner surface, each with only its
    own vertices. Together they are the watertight solid; apart, each takes its own material."""
    inner = np.zeros(len(solid.faces), dtype=bool)
    inner[n_outer:2 * n_outer] = True
    return solid.subset(~inner), solid.subset(inner)


def aperture(interior: Mesh) -> dict[str, list[float]]:
    """Centre of the lip (the inner surface's u = 1 ring) and the unit normal of the ring's best-fit
    plane pointing out of the shell: where to look into the aperture from."""
    ring = interior.vertices[interior.uvs[:, 0] == 1.0]
    centre = ring.mean(0)
    normal = np.linalg.svd(ring - centre)[2][-1]
    if np.dot(normal, centre - interior.vertices.mean(0)) < 0:
        normal = -normal
    return {"aperture_centre_m": centre.round(5).tolist(), "aperture_normal": normal.round(4).tolist()}


def inside_facing(interior: Mesh) -> dict[str, object]:
    """Where a bivalve's inside faces: its area-weighted mean normal (mesh frame) and the share of
    its area whose normal points up (+y), for placing the valve where the sky and sun reach it."""
    a, b, c = (interior.vertices[interior.faces[:, k]] for k in range(3))
    n = np.cross(b - a, c - a)
    mean = n.sum(0) / np.linalg.norm(n.sum(0))
    area = np.linalg.norm(n, axis=1)
    return {"inside_normal": mean.round(4).tolist(), "inside_up_share": round(float(area[n[:, 1] > 0].sum() / area.sum()), 4)}


def shell_mesh(preset: str, length: float, wall: float, per_turn: int, around: int, ribs: int,
               rng: np.random.Generator, cords: int = 0, cord_height: float = 0.0,
               depth: float = 0.22, inside_up: bool = False) -> tuple[Mesh, Mesh]:
    """(exterior, interior) of the shell in metres, y up, resting on y = 0, its largest extent
    ``length``. The seed varies the preset slightly (growth angle, aperture, nodules) so no two
    shells are clones. A bivalve ``inside_up`` is turned over about its umbo-margin axis first."""
    if preset == SCALLOP:
        m, n_outer = scallop_mesh(ribs + int(rng.integers(-2, 3)), wall * 0.15,
                                  n_r=max(8, per_turn // 2), n_fan=max(2 * around, 12 * ribs))
    elif preset == PEARL_OYSTER:
        m, n_outer = oyster_mesh(wall * 0.25, depth, ribs, n_r=max(12, per_turn), n_fan=max(24, 2 * around), rng=rng)
    else:
        j = rng.normal(1.0, 0.02, size=4)
        base = PRESETS[preset]
        g = replace(base, alpha=base.alpha + 0.15 * rng.standard_normal(), a=base.a * j[0], b=base.b * j[1],
                    turns=base.turns * j[2], L=base.L * j[3])
        m, n_outer = gastropod_mesh(g, wall, per_turn, around, cords, cord_height)
    if inside_up and preset in BIVALVES:
        m = m.transformed(np.diag([-1.0, 1.0, -1.0]))     # half a turn about the umbo-margin axis
    # model frame z-up -> scene y-up: (x, y, z) -> (x, z, -y), a proper rotation
    m = m.transformed(np.array([[1.0, 0, 0], [0, 0, 1.0], [0, -1.0, 0]]))
    lo, hi = m.vertices.min(0), m.vertices.max(0)
    scale = length / float((hi - lo).max())
    m = m.transformed(np.eye(3), -scale * np.array([(lo[0] + hi[0]) / 2, lo[1], (lo[2] + hi[2]) / 2]), scale)
    return solid_parts(m, n_outer)


@dataclass(frozen=True)
class SeashellParams(Params):
    preset: str = param("conch", "shell preset", choices=(*PRESETS, *BIVALVES))
    length: float = param(0.07, "largest extent, m")
    wall: float = param(0.08, "wall thickness as a share of the aperture radius")
    per_turn: int = param(48, "mesh rows per whorl")
    around: int = param(40, "mesh columns around the aperture")
    ribs: int = param(18, "scallop: radial ribs; pearl-oyster: concentric growth lamellae")
    depth: float = param(0.22, "pearl-oyster: the cup's depth as a share of the valve's height")
    inside_up: bool = param(False, "bivalves: lie on the convex back, the (nacreous) inside up")
    cords: int = param(0, "gastropods: spiral cords (ribs along the growth) around the aperture; "
                       "give 'around' at least 5 columns per cord")
    cord_height: float = param(0.05, "gastropods: cord height as a share of the aperture radius")

    def validate(self) -> None:
        require(self.preset in (*PRESETS, *BIVALVES),
                f"unknown preset {self.preset!r}; choose from {[*PRESETS, *BIVALVES]}")
        require(0.005 <= self.length <= 1.0, f"length must be 0.005..1 m, got {self.length}")
        require(0.01 <= self.wall <= 0.5, f"wall (share of the aperture radius) must be 0.01..0.5, got {self.wall}")
        require(8 <= self.per_turn <= 512 and 8 <= self.around <= 512, "per-turn and around must be 8..512")
        require(3 <= self.ribs <= 60, f"ribs must be 3..60, got {self.ribs}")
        require(0 <= self.cords <= 64 and 0 <= self.cord_height <= 0.3, "cords must be 0..64, cord height 0..0.3")
        require(0.05 <= self.depth <= 0.45, f"depth (share of the valve's height) must be 0.05..0.45, got {self.depth}")


def write(job: Job) -> list[str]:
    """``<preset>.ply`` (the outside and the rims) and ``<preset>_inner.ply`` (the inside: nacre);
    the manifest also records the preset's model parameters and where the aperture faces."""
    p = job.params
    if p.preset not in BIVALVES:
        job.note(model=asdict(PRESETS[p.preset]))
    exterior, interior = shell_mesh(p.preset, p.length, p.wall, p.per_turn, p.around, p.ribs,
                                    np.random.default_rng(job.seed), p.cords, p.cord_height, p.depth, p.inside_up)
    if p.preset not in BIVALVES:
        job.note(**aperture(interior))
    else:
        job.note(**inside_facing(interior))
    names = [f"{p.preset}.ply", f"{p.preset}_inner.ply"]
    for mesh, name in zip((exterior, interior), names):
        mesh.write(job.stage / name)
    return names


GENERATOR = Generator("seashell", "a parametric gastropod shell, a ribbed scallop or a pearl-oyster valve (PLY)",
                      SeashellParams, write, __doc__)
