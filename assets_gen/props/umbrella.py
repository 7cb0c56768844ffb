"""Beach umbrella: a segmented fabric canopy stretched over ribs, sagging between them, with a
scalloped valance, on a pole stuck into the sand, optionally tilted at a joint.

The canopy is a thin closed solid (``fabric`` thick) so it renders as a solid with any material.
Canopy UV: u = φ/2π around the pole (segment k spans [k/N, (k+1)/N], so a texture of N vertical
stripes puts one stripe on each segment, edges on the ribs), v from the apex (0) down the ribs and
the valance to its hem (1), proportional to length along the rib.

Placement: ground at y = 0 with the pole's foot ``embed`` below it; +y up; the canopy tilts
towards the azimuth ``tilt_azimuth_deg`` (0 = +x, 90 = −z: measured like a compass seen from above).
Outputs: ``canopy.ply`` (fabric) and ``frame.ply`` (pole, joint, ribs, stretchers, finial).
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from assets_gen.core import Generator, Job, Params, param, require
from assets_gen.core.meshing import Mesh, ellipsoid, rotation, thicken, tube


@dataclass(frozen=True)
class UmbrellaParams(Params):
    radius: float = param(1.0, "canopy radius at the rib tips, m")
    rise: float = param(0.3, "apex above the rim, m")
    segments: int = param(8, "panels (= ribs)")
    sag: float = param(0.04, "fabric sag mid-panel at the rim, m")
    valance: float = param(0.12, "valance depth, m")
    scallops: int = param(1, "valance lobes per panel")
    height: float = param(2.2, "apex above the ground untilted, m")
    embed: float = param(0.35, "pole in the sand, m")
    tilt_deg: float = param(0.0, "canopy tilt at the joint, degrees")
    tilt_azimuth_deg: float = param(0.0, "tilt direction (0 = +x, 90 = -z), degrees")
    fabric: float = param(0.0015, "fabric thickness, m")
    pole_radius: float = param(0.016, "pole radius, m")

    def validate(self) -> None:
        require(0.3 <= self.radius <= 2.5, f"canopy radius must be 0.3..2.5 m, got {self.radius}")
        require(0.0 <= self.rise <= self.radius, f"canopy rise must be 0..radius, got {self.rise}")
        require(3 <= self.segments <= 24, f"segments must be 3..24, got {self.segments}")
        require(0.0 <= self.sag <= 0.2 * self.radius, f"sag must be 0..0.2 x radius, got {self.sag}")
        require(0.0 < self.valance <= 0.4 and 1 <= self.scallops <= 4,
                "valance must be 0..0.4 m and scallops 1..4 per segment")
        require(1.0 <= self.height <= 4.0 and 0.0 <= self.embed <= 1.0, "height must be 1..4 m and embed 0..1 m")
        require(self.height - self.rise - self.valance - 0.6 * self.radius > 0.62 * self.height - 0.5,
                "canopy too large for the pole: its ribs would reach below the tilt joint")
        require(0.0 <= self.tilt_deg <= 45.0, f"tilt must be 0..45 deg, got {self.tilt_deg}")
        require(0.0003 <= self.fabric <= 0.01, f"fabric thickness must be 0.3..10 mm, got {self.fabric}")
        require(0.008 <= self.pole_radius <= 0.04, f"pole radius must be 8..40 mm, got {self.pole_radius}")


def canopy_points(radius: float, rise: float, segments: int, sag: float, valance: float,
                  scallops: int, n_r: int, per_segment: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Canopy surface (n_rows, n_cols, 3) with the apex at the origin (rows from the apex out and
    down the valance; columns around), its row v (arc-length share) and column u (φ/2π)."""
    cols = segments * per_segment
    phi = 2.0 * np.pi * np.arange(cols) / cols
    frac = (phi * segments / (2 * np.pi)) % 1.0                     # position across a segment
    across = np.sin(np.pi * frac)                                   # 0 on a rib, 1 mid-panel
    half = np.pi / segments
    mid = (np.floor(phi / (2 * half)) + 0.5) * 2 * half            # the panel's centre line
    chord = np.cos(half) / np.cos(phi - mid)
    rho = np.linspace(0.03, 1.0, n_r)[:, None]
    # ribs bend down like a loaded cantilever; fabric spans straight between rib tips (chord)
    # and sags below the ribs, most at mid-panel near the rim
    r_plan = radius * rho * (chord - 0.15 * sag / radius * across)
    y = rise * (1.0 - rho ** 2) - sag * across * rho ** 2
    ring = np.stack([np.cos(phi), -np.sin(phi)], 1)                # (x, z) heading per column
    canopy = np.stack([r_plan * ring[:, 0], np.broadcast_to(y, r_plan.shape), r_plan * ring[:, 1]], -1)
    # valance: hangs from the rim, hem in `scallops` round lobes per segment
    lobe = (phi * segments * scallops / (2 * np.pi)) % 1.0
    depth = valance * (0.55 + 0.45 * np.sqrt(np.clip(1.0 - (2 * lobe - 1) ** 2, 0.0, 1.0)))
    drop = np.linspace(0.0, 1.0, max(3, n_r // 4))[1:, None] * depth
    val = canopy[-1][None] + np.stack([0.04 * drop * ring[:, 0], -drop, 0.04 * drop * ring[:, 1]], -1)
    pts = np.concatenate([canopy, val])
    step = np.linalg.norm(np.diff(pts[:, 0], axis=0), axis=1)
    v = np.concatenate([[0.0], np.cumsum(step)]) / step.sum()
    return pts, v, np.linspace(0.0, 1.0, cols + 1)


def umbrella(p: UmbrellaParams, rng: np.random.Generator) -> tuple[Mesh, Mesh]:
    """(canopy, frame) in metres. The seed turns the canopy about the pole and varies the sag a little."""
    radius, rise, segments, valance, height, fabric = p.radius, p.rise, p.segments, p.valance, p.height, p.fabric
    sag = p.sag * rng.uniform(0.85, 1.15)
    spin = rotation([0, 1, 0], rng.uniform(0.0, 2.0 * np.pi / segments))
    pts, v, u = canopy_points(radius, rise, segments, sag, valance, p.scallops, n_r=40, per_segment=16)
    canopy = thicken(pts, fabric, outward=np.array([0.0, 1.0, 0.0]), wrap_v=True, u=v, v=u)
    canopy = replace(canopy, uvs=canopy.uvs[:, ::-1].copy())       # u around, v down the rib
    # ribs just under the fabric, stretchers from a runner on the pole to mid-rib
    rho = np.linspace(0.03, 1.0, 24)[:, None]
    rib_r, stretch_r = 0.004, 0.003
    parts = []
    for k in range(segments):
        phi = 2.0 * np.pi * k / segments
        head = np.array([np.cos(phi), 0.0, -np.sin(phi)])
        rib = radius * rho * head + (rise * (1 - rho ** 2) - fabric - rib_r) * np.array([0, 1.0, 0])
        parts.append(tube(rib, rib_r, sides=8, caps="round"))
        runner = np.array([0.0, rise - 0.45 * radius, 0.0])
        parts.append(tube(np.linspace(runner, rib[len(rib) // 2], 12), stretch_r, sides=8, caps="round"))
    parts.append(ellipsoid(np.array([0.0, rise + 0.01, 0.0]), np.full(3, 0.03), rings=8, sides=12))
    joint_y = 0.62 * height
    top = tube(np.linspace([0.0, rise - 0.6 * radius, 0.0], [0.0, rise, 0.0], 8), p.pole_radius, sides=16)
    upper = [canopy, Mesh.join([*parts, top])]
    # the canopy's apex sits `height` above the ground before tilting; tilt about the joint
    lift = np.array([0.0, height - rise, 0.0])
    # up turns towards the heading (cos a, 0, -sin a) about up x heading
    axis = np.array([-np.sin(np.radians(p.tilt_azimuth_deg)), 0.0, -np.cos(np.radians(p.tilt_azimuth_deg))])
    tilt = rotation(axis, np.radians(p.tilt_deg)) @ spin
    joint = np.array([0.0, joint_y, 0.0])
    canopy, frame_top = (m.transformed(tilt, tilt @ (lift - joint) + joint) for m in upper)
    shaft_top = tilt @ (np.array([0.0, height - 0.6 * radius, 0.0]) - joint) + joint
    lower = tube(np.linspace([0.0, -p.embed, 0.0], joint, 16), p.pole_radius * 1.15, sides=16)
    upper_pole = tube(np.linspace(joint, shaft_top, 16), p.pole_radius, sides=16)
    knuckle = ellipsoid(joint, np.full(3, p.pole_radius * 1.6), rings=8, sides=16)
    return canopy, Mesh.join([frame_top, lower, upper_pole, knuckle])


def write(job: Job) -> list[str]:
    canopy, frame = umbrella(job.params, np.random.default_rng(job.seed))
    canopy.write(job.stage / "canopy.ply")
    frame.write(job.stage / "frame.ply")
    return ["canopy.ply", "frame.ply"]


GENERATOR = Generator("umbrella", "a striped beach umbrella: canopy with valance, pole, ribs",
                      UmbrellaParams, write, __doc__)
