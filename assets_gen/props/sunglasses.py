"""Sunglasses: two superellipse lenses cut from a sphere of the frame's base curve, held in molded
(acetate-like) rims of oval section with a browline, joined by a bridge, with end pieces and flat
temples.

Base curve B (dioptres, at the tooling index 1.53) gives the front radius R = 530 mm / B, so
base 6 is R ≈ 88 mm. Lens outline |x/a|^n + |y/b|^n = 1 (a, b: half the lens width and height).
Lenses are meniscus shells (back sphere concentric, ``thickness`` thinner: 2 mm by default),
each written in two files that together are the closed solid: the convex front face
(``lens_<side>_front.ply``, where a mirror coating goes) and the concave back face with the
ground edge (``lens_<side>_back.ply``), so a scene can coat the front only. Lens UV: u = 0.5 + x/(2a),
v = 0.5 + y/(2b) in the lens's own plane, so (0.5, 0.5) is the lens centre and the outline touches
the unit square's inscribed superellipse; u grows towards the temple on both lenses (mirror
images), v upwards. Each lens edge sits ``groove`` deep inside its rim.

Frame of the meshes (metres): worn pose, wearer looking along +z, +y up, origin at the bridge's
centre; the temples run back along −z. The wearer's left lens is on +x. The manifest records how
the pair rests on flat ground (see :func:`rest_pose`): contact at both rim bottoms and both temple
tips.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from assets_gen.core import Generator, Job, Params, param, require
from assets_gen.core.meshing import Mesh, closed_solid, disc, ellipsoid, rotation, transport_frames, tube

MIRROR_X = np.diag([-1.0, 1.0, 1.0])


@dataclass(frozen=True)
class SunglassesParams(Params):
    lens_width: float = param(0.055, "lens outline width, m")
    lens_height: float = param(0.045, "lens outline height, m")
    squareness: float = param(3.0, "superellipse exponent of the lens outline")
    base_curve: float = param(6.0, "base curve, dioptres (front radius 530 mm / base)")
    bridge: float = param(0.018, "gap between the lenses, m")
    temple: float = param(0.140, "temple length, m")
    wrap_deg: float = param(6.0, "wrap of each lens about the vertical, degrees")
    tilt_deg: float = param(8.0, "pantoscopic tilt, degrees")
    lens_thickness: float = param(0.002, "lens thickness, m")
    rim_width: float = param(0.0045, "rim face width around the lens (below and at the sides), m")
    brow: float = param(0.002, "extra rim width along the top (a browline), m")
    rim_depth: float = param(0.0042, "rim depth along the lens axis, m (more than the lens thickness)")
    groove: float = param(0.001, "how far the lens edge sits inside the rim, m")
    temple_height: float = param(0.006, "temple height at the hinge, m (tapering to 2/3 at the tip)")
    temple_thickness: float = param(0.0028, "temple thickness, m")

    @property
    def front_radius(self) -> float:
        """The lens front's sphere radius, m."""
        return 0.53 / self.base_curve

    def validate(self) -> None:
        require(0.02 <= self.lens_width <= 0.09 and 0.015 <= self.lens_height <= 0.08,
                "lens width must be 0.02..0.09 m and height 0.015..0.08 m")
        require(1.5 <= self.squareness <= 12,
                f"squareness (superellipse exponent) must be 1.5..12, got {self.squareness}")
        require(1 <= self.base_curve <= 10, f"base curve must be 1..10 dioptres, got {self.base_curve}")
        require(self.front_radius > 0.55 * np.hypot(self.lens_width, self.lens_height),
                "base curve too steep for the lens size: the lens would not fit on its sphere")
        require(0.008 <= self.bridge <= 0.03 and 0.08 <= self.temple <= 0.18,
                "bridge must be 8..30 mm, temple 80..180 mm")
        require(0 <= self.wrap_deg <= 25 and -5 <= self.tilt_deg <= 20, "wrap must be 0..25 deg, tilt -5..20 deg")
        require(0.0005 <= self.lens_thickness <= 0.005, "lens thickness must be 0.5..5 mm")
        require(0.001 <= self.rim_width <= 0.012 and 0 <= self.brow <= 0.01,
                "rim width must be 1..12 mm and brow 0..10 mm")
        require(self.lens_thickness < self.rim_depth <= 0.012,
                "rim depth must exceed the lens thickness (the rim holds the lens) and be at most 12 mm")
        require(0 < self.groove < self.rim_width / 2, "groove must be positive and under half the rim width")
        require(0.002 <= self.temple_height <= 0.015 and 0.001 <= self.temple_thickness <= 0.006,
                "temple height must be 2..15 mm and thickness 1..6 mm")


def superellipse(a: float, b: float, n: float, t: np.ndarray) -> np.ndarray:
    """Points (len(t), 2) on |x/a|^n + |y/b|^n = 1, counter-clockwise."""
    c, s = np.cos(t), np.sin(t)
    return np.stack([a * np.sign(c) * np.abs(c) ** (2 / n), b * np.sign(s) * np.abs(s) ** (2 / n)], 1)


def sphere_sag(xy: np.ndarray, radius: float) -> np.ndarray:
    """Height of a sphere of ``radius`` through the origin, centred on −z, over the points ``xy``."""
    return np.sqrt(radius ** 2 - (xy ** 2).sum(-1)) - radius


def lens_mesh(a: float, b: float, n: float, radius: float, thickness: float,
              rings: int = 10, sides: int = 96) -> tuple[Mesh, np.ndarray]:
    """One lens in its own frame (front vertex at the origin, optical axis +z), and its outline
    at mid-thickness (for the rim). The temporal side is +x. The front face's triangles come
    first (:func:`front_faces` counts them), then the back face's and the edge's."""
    t = 2.0 * np.pi * np.arange(sides) / sides
    outline = superellipse(a, b, n, t)
    rho = np.linspace(1.0 / rings, 1.0, rings)
    xy = rho[:, None, None] * outline[None]
    uv = np.stack([0.5 + xy[..., 0] / (2 * a), 0.5 + xy[..., 1] / (2 * b)], -1)
    front = disc(np.concatenate([xy, sphere_sag(xy, radius)[..., None]], -1), np.zeros(3), uv,
                 np.array([0.5, 0.5]))
    back_xy = front.vertices[:, :2]
    back = np.concatenate([back_xy, (sphere_sag(back_xy, radius - thickness) - thickness)[:, None]], 1)
    edge = 1 + (rings - 1) * (sides + 1) + np.arange(sides)      # outermost ring, seam excluded
    lens = closed_solid(front, back, [edge])
    mid = np.concatenate([outline, (sphere_sag(outline, radius) - 0.5 * thickness)[:, None]], 1)
    return lens, mid


def front_faces(rings: int = 10, sides: int = 96) -> int:
    """How many of :func:`lens_mesh`'s first triangles are the front face: the centre fan and the
    quads between the ``rings`` outline rings (each ring with its seam vertex)."""
    return sides + 2 * (rings - 1) * sides


def lens_faces(lens: Mesh, rings: int = 10, sides: int = 96) -> tuple[Mesh, Mesh]:
    """(front face, back face with the edge) of a lens from :func:`lens_mesh`, each with only its
    own vertices: together the closed lens, apart each takes its own material."""
    front = np.zeros(len(lens.faces), dtype=bool)
    front[:front_faces(rings, sides)] = True
    return lens.subset(front), lens.subset(~front)


def oval_tube(path: np.ndarray, across: np.ndarray, half_across: np.ndarray | float,
              half_along: np.ndarray | float, sides: int = 16, closed: bool = False) -> Mesh:
    """A tube of elliptical section along ``path``: semi-axis ``half_across`` along the per-point
    direction ``across`` (made normal to the path) and ``half_along`` along the third axis. Molded
    plastic frames have flat, wide sections, not a wire's round one."""
    t, n, b = transport_frames(path, closed)
    a = across - t * np.einsum("ij,ij->i", across, t)[:, None]
    a /= np.linalg.norm(a, axis=1, keepdims=True)
    s = np.cross(t, a)
    psi = 2.0 * np.pi * np.arange(sides) / sides
    d = np.cos(psi)[None, :, None] * n[:, None] - np.sin(psi)[None, :, None] * b[:, None]
    ha = np.broadcast_to(np.asarray(half_across, dtype=np.float64), (len(path),))[:, None]
    hs = np.broadcast_to(np.asarray(half_along, dtype=np.float64), (len(path),))[:, None]
    r = 1.0 / np.sqrt((np.einsum("kjc,kc->kj", d, a) / ha) ** 2 + (np.einsum("kjc,kc->kj", d, s) / hs) ** 2)
    return tube(path, r, sides=sides, closed=closed, caps="round")


def rim_mesh(p: SunglassesParams, outline: np.ndarray) -> Mesh:
    """The rim round one lens (its own frame): an oval section whose inner edge overlaps the lens
    edge by ``groove`` (the lens sits in the rim's groove), wider along the top (the brow)."""
    nxt, prv = np.roll(outline, -1, 0), np.roll(outline, 1, 0)
    tangent = nxt - prv
    outward = np.stack([tangent[:, 1], -tangent[:, 0], np.zeros(len(outline))], 1)   # CCW outline
    outward /= np.linalg.norm(outward, axis=1, keepdims=True)
    up = np.clip(outline[:, 1] / np.abs(outline[:, 1]).max(), 0.0, 1.0) ** 2
    half = 0.5 * (p.rim_width + p.brow * up)
    path = outline + (half - p.groove)[:, None] * outward
    return oval_tube(path, outward, half, 0.5 * p.rim_depth, sides=14, closed=True)


def temple_path(p: SunglassesParams, hinge: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Straight back from the hinge with a little splay, then bent down over the ear; the seed only
    nudges the splay and the droop."""
    splay = np.radians(3.0 + rng.uniform(-1.0, 1.0))
    droop = np.radians(28.0 + rng.uniform(-3.0, 3.0))
    arc = np.linspace(0.0, p.temple, 64)
    bend = droop * np.clip((arc - 0.72 * p.temple) / (0.12 * p.temple), 0.0, 1.0) ** 2
    step = np.stack([np.sin(splay) * np.cos(bend), -np.sin(bend), -np.cos(splay) * np.cos(bend)], 1)
    return hinge + np.concatenate([[np.zeros(3)], np.cumsum(step[1:] * np.diff(arc)[:, None], 0)])


def sunglasses(p: SunglassesParams, rng: np.random.Generator) -> tuple[Mesh, Mesh, Mesh]:
    """(left lens, right lens, frame) in metres, worn pose (see the module's docstring)."""
    a, b = p.lens_width / 2, p.lens_height / 2
    lens, outline = lens_mesh(a, b, p.squareness, p.front_radius, p.lens_thickness)
    rim = rim_mesh(p, outline)
    # lens frame -> worn: pantoscopic tilt (bottom towards the face), wrap (temple edge back),
    # then out to the left of the bridge
    pose = rotation([0, 1, 0], np.radians(p.wrap_deg)) @ rotation([1, 0, 0], np.radians(p.tilt_deg))
    shift = np.array([p.bridge / 2 + a, 0.0, 0.0])
    left_lens, left_rim = (m.transformed(pose, shift) for m in (lens, rim))
    place = lambda q: q @ pose.T + shift                          # noqa: E731 (a point map)
    angle = np.arctan2(outline[:, 1], outline[:, 0])
    outer = p.rim_width - p.groove                                # lens edge to the rim's outer edge
    nasal = place(outline[np.argmin(np.abs(angle - np.radians(150)))]) + [-0.5 * outer, 0.0, 0.0]
    hinge = place(outline[np.argmin(np.abs(angle - np.radians(15)))]) + [outer, 0.0, -0.5 * p.rim_depth]
    # bridge: an arch from one rim's upper-nasal corner to the other's, a flat oval like the rim
    s = np.linspace(0.0, 1.0, 24)[:, None]
    far = nasal * [-1, 1, 1]
    ctrl = np.array([0.0, nasal[1] + 0.4 * p.bridge, nasal[2] + 0.1 * p.bridge])
    arch = (1 - s) ** 2 * nasal + 2 * s * (1 - s) * ctrl + s ** 2 * far
    bridge = oval_tube(arch, np.tile([0.0, 1.0, 0.0], (len(arch), 1)), 0.5 * p.rim_width, 0.4 * p.rim_depth)
    # end piece (the hinge block joining rim and temple), then the temple: a flat bar, taller than
    # thick, tapering to the tip
    end_piece = ellipsoid(hinge + [-0.3 * outer, 0.0, 0.1 * p.rim_depth],
                          np.array([0.6 * outer + 0.5 * p.temple_thickness, 0.55 * p.temple_height,
                                    0.6 * p.rim_depth]), rings=8, sides=14)
    path = temple_path(p, hinge, rng)
    taper = 1.0 - np.linspace(0.0, 1.0 / 3.0, len(path))
    temple = oval_tube(path, np.tile([0.0, 1.0, 0.0], (len(path), 1)), 0.5 * p.temple_height * taper,
                       0.5 * p.temple_thickness)
    left_frame = Mesh.join([left_rim, end_piece, temple])
    right_lens, right_frame = (m.transformed(MIRROR_X) for m in (left_lens, left_frame))
    return left_lens, right_lens, Mesh.join([left_frame, right_frame, bridge])


def rest_pose(lenses: list[Mesh], frame: Mesh) -> dict[str, object]:
    """How the pair rests on flat ground, upright and facing forward: the tilt about +x (applied to
    the worn pose first) that puts the lowest points of the front (rims, lenses) and of the temple
    tips at one height, the lift that then sets them on y = 0, and those contact points in the
    mesh's own frame. "Front" is within 4 cm of the bridge, "tips" the temples' last 3 cm; the
    height of the front's lowest point relative to the tips' is monotonic in the tilt, so bisect."""
    v = np.concatenate([frame.vertices, *(m.vertices for m in lenses)])
    front, back = v[v[:, 2] > -0.04], v[v[:, 2] < v[:, 2].min() + 0.03]

    def low(q: np.ndarray, tilt: float) -> float:
        return float((q @ rotation([1, 0, 0], tilt).T)[:, 1].min())

    lo, hi = np.radians(-45.0), np.radians(30.0)
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if low(front, mid) < low(back, mid) else (mid, hi)
    tilt = 0.5 * (lo + hi)
    r = rotation([1, 0, 0], tilt)
    contacts = []
    for q in (front[front[:, 0] > 0], front[front[:, 0] < 0], back[back[:, 0] > 0], back[back[:, 0] < 0]):
        contacts.append(q[np.argmin((q @ r.T)[:, 1])].round(5).tolist())
    return {"rest_tilt_deg": round(float(np.degrees(tilt)), 3), "rest_lift_m": round(-low(v, tilt), 5),
            "contact_points_m": contacts}


def write(job: Job) -> list[str]:
    """Each lens's front and back (with its edge) and the frame; the manifest also records the
    front radius and the rest pose."""
    left, right, frame = sunglasses(job.params, np.random.default_rng(job.seed))
    job.note(front_radius_m=job.params.front_radius, **rest_pose([left, right], frame))
    parts = {**{f"lens_{side}_{face}.ply": m for side, lens in (("left", left), ("right", right))
                for face, m in zip(("front", "back"), lens_faces(lens))}, "frame.ply": frame}
    for name, mesh in parts.items():
        mesh.write(job.stage / name)
    return list(parts)


GENERATOR = Generator("sunglasses", "superellipse lenses on a base-curve sphere, rims, bridge, temples",
                      SunglassesParams, write, __doc__)
