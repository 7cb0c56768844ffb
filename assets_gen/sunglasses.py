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

import argparse
from pathlib import Path
from typing import Any

import numpy as np

from assets_gen.common import require, staged_output, write_manifest
from assets_gen.meshing import Mesh, closed_solid, disc, rotation, tube

MIRROR_X = np.diag([-1.0, 1.0, 1.0])


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


def sunglasses(lens_width: float, lens_height: float, squareness: float, base_curve: float,
               bridge: float, temple: float, wrap_deg: float, tilt_deg: float, lens_thickness: float,
               wire: float, rng: np.random.Generator) -> tuple[Mesh, Mesh, Mesh]:
    """(left lens, right lens, frame) in metres. The seed only nudges the temples' splay and droop."""
    a, b = lens_width / 2, lens_height / 2
    radius = 0.530 / base_curve
    lens, outline = lens_mesh(a, b, squareness, radius, lens_thickness)
    rim = tube(outline, wire, sides=10, closed=True)
    # lens frame -> worn: pantoscopic tilt (bottom towards the face), wrap (temple edge back),
    # then out to the left of the bridge
    pose = rotation([0, 1, 0], np.radians(wrap_deg)) @ rotation([1, 0, 0], np.radians(tilt_deg))
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


def generate(out_dir: str | Path, lens_width: float = 0.055, lens_height: float = 0.045,
             squareness: float = 3.0, base_curve: float = 6.0, bridge: float = 0.018, temple: float = 0.140,
             wrap_deg: float = 6.0, tilt_deg: float = 8.0, lens_thickness: float = 0.002,
             wire: float = 0.0022, seed: int = 0) -> list[str]:
    """Write ``lens_left.ply``, ``lens_right.ply``, ``frame.ply`` and ``sunglasses.json``."""
    params = dict(lens_width=lens_width, lens_height=lens_height, squareness=squareness,
                  base_curve=base_curve, bridge=bridge, temple=temple, wrap_deg=wrap_deg,
                  tilt_deg=tilt_deg, lens_thickness=lens_thickness, wire=wire)
    require(0.02 <= lens_width <= 0.09 and 0.015 <= lens_height <= 0.08,
            "lens width must be 0.02..0.09 m and height 0.015..0.08 m")
    require(1.5 <= squareness <= 12, f"squareness (superellipse exponent) must be 1.5..12, got {squareness}")
    require(1 <= base_curve <= 10, f"base curve must be 1..10 dioptres, got {base_curve}")
    require(0.53 / base_curve > 0.55 * np.hypot(lens_width, lens_height),
            "base curve too steep for the lens size: the lens would not fit on its sphere")
    require(0.008 <= bridge <= 0.03 and 0.08 <= temple <= 0.18, "bridge must be 8..30 mm, temple 80..180 mm")
    require(0 <= wrap_deg <= 25 and -5 <= tilt_deg <= 20, "wrap must be 0..25 deg, tilt -5..20 deg")
    require(0.0005 <= lens_thickness <= 0.005, "lens thickness must be 0.5..5 mm")
    require(0.0005 <= wire <= 0.005, "wire (rim, bridge and temple radius) must be 0.5..5 mm")
    meshes = sunglasses(lens_width, lens_height, squareness, base_curve, bridge, temple, wrap_deg,
                        tilt_deg, lens_thickness, wire, np.random.default_rng(seed))
    names = ["lens_left.ply", "lens_right.ply", "frame.ply"]
    with staged_output(out_dir) as stage:
        for m, name in zip(meshes, names):
            m.write(stage / name)
        write_manifest(stage / "sunglasses.json", "sunglasses",
                       {**params, "front_radius_m": 0.53 / base_curve}, seed, names)
    return [str(Path(out_dir) / n) for n in (*names, "sunglasses.json")]


def register(subparsers: Any) -> None:
    p = subparsers.add_parser("sunglasses", help="superellipse lenses on a base-curve sphere, rims, bridge, temples",
                              description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    for flag, default, unit in (("--lens-width", 0.055, "m"), ("--lens-height", 0.045, "m"),
                                ("--squareness", 3.0, "superellipse exponent"), ("--base-curve", 6.0, "D"),
                                ("--bridge", 0.018, "m"), ("--temple", 0.140, "m"), ("--wrap-deg", 6.0, "deg"),
                                ("--tilt-deg", 8.0, "deg, pantoscopic"), ("--lens-thickness", 0.002, "m"),
                                ("--wire", 0.0022, "m, frame wire radius")):
        p.add_argument(flag, type=float, default=default, help=f"{unit} (default {default})")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument("--out", type=Path, default=Path("assets") / "sunglasses", help="output folder")
    p.set_defaults(run=lambda a: generate(a.out, a.lens_width, a.lens_height, a.squareness, a.base_curve,
                                          a.bridge, a.temple, a.wrap_deg, a.tilt_deg, a.lens_thickness,
                                          a.wire, a.seed))
