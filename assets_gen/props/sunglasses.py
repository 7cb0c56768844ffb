"""Sunglasses: two superellipse lenses cut from a sphere of the frame's base curve, a wire rim
round each, a bridge and two temples.

Base curve B (dioptres, at the tooling index 1.53) gives the front radius R = 530 mm / B, so
base 6 is R ≈ 88 mm. Lens outline |x/a|^n + |y/b|^n = 1 (a, b: half the lens width and height).
Lenses are meniscus shells (back sphere concentric, ``thickness`` thinner) and written as their
own closed meshes for the thin-film material. Lens UV: u = 0.5 + x/(2a), v = 0.5 + y/(2b) in the
lens's own plane, so (0.5, 0.5) is the lens centre and the outline touches the unit square's
inscribed superellipse; u grows towards the temple on both lenses (mirror images), v upwards.

Placement: worn pose, wearer looking along +z, +y up, origin at the bridge's centre; the temples
run back along −z. The wearer's left lens is on +x.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from assets_gen.core import Generator, Job, Params, param, require
from assets_gen.core.meshing import Mesh, closed_solid, disc, rotation, tube

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
    wire: float = param(0.0022, "frame wire radius, m")

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
        require(0.0005 <= self.wire <= 0.005, "wire (rim, bridge and temple radius) must be 0.5..5 mm")


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
    at mid-thickness (for the rim). The temporal side is +x."""
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


def sunglasses(p: SunglassesParams, rng: np.random.Generator) -> tuple[Mesh, Mesh, Mesh]:
    """(left lens, right lens, frame) in metres. The seed only nudges the temples' splay and droop."""
    a, b = p.lens_width / 2, p.lens_height / 2
    bridge, temple, wire = p.bridge, p.temple, p.wire
    lens, outline = lens_mesh(a, b, p.squareness, p.front_radius, p.lens_thickness)
    rim = tube(outline, wire, sides=10, closed=True)
    # lens frame -> worn: pantoscopic tilt (bottom towards the face), wrap (temple edge back),
    # then out to the left of the bridge
    pose = rotation([0, 1, 0], np.radians(p.wrap_deg)) @ rotation([1, 0, 0], np.radians(p.tilt_deg))
    shift = np.array([bridge / 2 + a, 0.0, 0.0])
    left_lens, left_rim = (m.transformed(pose, shift) for m in (lens, rim))
    place = lambda p: p @ pose.T + shift                          # noqa: E731 (a point map)
    nasal = place(outline[np.argmin(np.abs(np.arctan2(outline[:, 1], outline[:, 0]) - np.radians(150)))])
    hinge = place(outline[np.argmin(np.abs(np.arctan2(outline[:, 1], outline[:, 0]) - np.radians(15)))])
    # bridge: an arch from one lens's upper-nasal corner to the other's
    s = np.linspace(0.0, 1.0, 24)[:, None]
    far = nasal * [-1, 1, 1]
    ctrl = np.array([0.0, nasal[1] + 0.4 * bridge, nasal[2] + 0.1 * bridge])
    arch = (1 - s) ** 2 * nasal + 2 * s * (1 - s) * ctrl + s ** 2 * far
    bridge_mesh = tube(arch, wire * 0.8, sides=10, caps="round")
    # temple: straight back with a little splay, then bent down over the ear
    splay = np.radians(3.0 + rng.uniform(-1.0, 1.0))
    droop = np.radians(28.0 + rng.uniform(-3.0, 3.0))
    arc = np.linspace(0.0, temple, 64)
    bend = droop * np.clip((arc - 0.72 * temple) / (0.12 * temple), 0.0, 1.0) ** 2
    step = np.stack([np.sin(splay) * np.cos(bend), -np.sin(bend), -np.cos(splay) * np.cos(bend)], 1)
    path = hinge + np.concatenate([[np.zeros(3)], np.cumsum(step[1:] * np.diff(arc)[:, None], 0)])
    temple_mesh = tube(path, wire, sides=10, caps="round")
    left_frame = Mesh.join([left_rim, temple_mesh])
    right_lens, right_frame = (m.transformed(MIRROR_X) for m in (left_lens, left_frame))
    return left_lens, right_lens, Mesh.join([left_frame, right_frame, bridge_mesh])


def write(job: Job) -> list[str]:
    """The two lenses and the frame; the manifest also records the front radius."""
    job.note(front_radius_m=job.params.front_radius)
    names = ["lens_left.ply", "lens_right.ply", "frame.ply"]
    for mesh, name in zip(sunglasses(job.params, np.random.default_rng(job.seed)), names):
        mesh.write(job.stage / name)
    return names


GENERATOR = Generator("sunglasses", "superellipse lenses on a base-curve sphere, rims, bridge, temples",
                      SunglassesParams, write, __doc__)
