"""Where the beach's sunglasses reflect: for each lens of the placed pair, the elevation and azimuth
of the mirror direction of the camera's rays at the lens front's vertices, by height bands of the
lens, and where those rays are at a few horizontal distances. It is what chose what stands behind
the camera in scenes/beach.pbrt (docs/scenes.md, "Composition"): only directions in these ranges
can show in the lenses. It also prints the lens's luminous transmittance for the scene's tint and
the category 3 tint it replaced (the coating's dispersion left out).

    python benchmarks/lens_reflection.py [--placement PATH]

Azimuth 0 is world +x (behind the camera, which looks along -x); positive towards +z, the image's
right. Geometry only (no occlusion, the lens front as a mirror): the same numbers on any machine.
"""
import argparse
import re
from pathlib import Path

import numpy as np
import trimesh

from renderer.optics.arrays import multilayer_transmittance

SCENES = Path(__file__).resolve().parents[1] / "scenes"
ASSETS = SCENES / "assets" / "beach"


def camera_eye() -> np.ndarray:
    """The LookAt eye of the beach camera."""
    text = (SCENES / "parts" / "beach_camera.pbrt").read_text()
    numbers = re.search(r"^LookAt\s+([-\d.\s]+)", text, re.M).group(1).split()
    return np.array([float(x) for x in numbers[:3]])


def luminous_transmittance(tint: float) -> float:
    """D65 luminous transmittance at normal incidence of the lens of scenes/parts/beach_props.pbrt:
    the 9-layer blue mirror on both faces (no interreflection) and one pass of a grey tint."""
    import colour

    lam = np.arange(380.0, 781.0, 5.0)
    eta = [1.0] + [2.20, 1.448] * 4 + [2.20, 1.52]
    t = multilayer_transmittance(np.ones_like(lam), lam, eta, [0.0] * len(eta), [45.2, 75.0] * 4 + [45.2])
    y = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].align(colour.SpectralShape(380, 780, 5)).values[:, 1]
    d65 = colour.SDS_ILLUMINANTS["D65"].copy().align(colour.SpectralShape(380, 780, 5)).values
    return float((y * d65 * t * t * tint).sum() / (y * d65).sum())


def mirror_directions(lens: trimesh.Trimesh, m: np.ndarray, eye: np.ndarray) -> tuple[np.ndarray, ...]:
    """World positions of the lens front's vertices, their reflected view directions, and their
    height in the lens (0 at the bottom, 1 at the top)."""
    front = lens.vertex_normals[:, 2] > 0.5          # the convex front faces +z in the mesh frame
    p = lens.vertices[front] @ m[:3, :3].T + m[:3, 3]
    n = lens.vertex_normals[front] @ m[:3, :3].T
    n /= np.linalg.norm(n, axis=1)[:, None]
    d = p - eye
    d /= np.linalg.norm(d, axis=1)[:, None]
    r = d - 2.0 * (d * n).sum(1)[:, None] * n
    return p, r, (p[:, 1] - p[:, 1].min()) / np.ptp(p[:, 1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--placement", type=Path, default=ASSETS / "sunglasses_placement" / "placement.npz")
    args = ap.parse_args()
    m, eye = np.load(args.placement)["transform"], camera_eye()
    for tint in (0.45, 0.21):   # the green of "rgb tint" now and before
        print(f"tint {tint} per pass: luminous transmittance {luminous_transmittance(tint):.2f}")
    tilt = np.degrees(np.arcsin(m[1, 2] / np.linalg.norm(m[:3, 2])))
    print(f"lens axis (mesh +z) {tilt:.1f} deg above the horizontal")
    for name in ("lens_left", "lens_right"):
        lens = trimesh.load(ASSETS / "sunglasses" / f"{name}.ply", process=False)
        p, r, height = mirror_directions(lens, m, eye)
        elevation = np.degrees(np.arcsin(np.clip(r[:, 1], -1, 1)))
        azimuth = np.degrees(np.arctan2(r[:, 2], r[:, 0]))
        view = np.degrees(np.arctan2(eye[1] - p[:, 1].mean(), np.linalg.norm((eye - p.mean(0))[[0, 2]])))
        print(f"{name}: centre {np.round(p.mean(0), 3)}, camera {view:.1f} deg above it")
        print("  lens height   elevation (deg)   azimuth (deg)")
        for lo in np.arange(0.0, 1.0, 0.2):
            s = (height >= lo) & (height < lo + 0.2 + 1e-9)
            print(f"  {lo:.1f}-{lo + 0.2:.1f}      {elevation[s].min():6.0f} .. {elevation[s].max():3.0f}"
                  f"     {azimuth[s].min():5.0f} .. {azimuth[s].max():4.0f}")
        up = elevation > 0
        for dist in (7.0, 14.0):
            t = dist / np.maximum(np.hypot(r[up, 0], r[up, 2]), 1e-9)
            q = p[up] + r[up] * t[:, None]
            print(f"  above the horizon, {dist:.0f} m out: x {q[:, 0].min():.1f}..{q[:, 0].max():.1f}, "
                  f"z {q[:, 2].min():.1f}..{q[:, 2].max():.1f}, height up to {q[:, 1].max():.1f} m")


if __name__ == "__main__":
    main()
