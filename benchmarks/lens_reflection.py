"""Where the beach's sunglasses reflect: for each lens of the placed pair, the elevation and azimuth
of the mirror direction of the camera's rays at the lens front's vertices, by height bands of the
lens, and where those rays are at a few horizontal distances. It is what chose what stands behind
the camera in scenes/beach.pbrt (docs/scenes.md, "Composition"): only directions in these ranges
can show in the lenses. It also prints the lens's luminous transmittance, from the stack and tint
that scenes/parts/beach_props.pbrt gives the "lens" material (or another tint, --tint).

    python benchmarks/lens_reflection.py [--placement PATH] [--tint G ...]

Azimuth 0 is world +x (behind the camera, which looks along -x); positive towards +z, the image's
right. Geometry only (no occlusion, the lens front as a mirror): the same numbers on any machine.
Needs the beach's assets (assets-gen recipe scenes/beach.pbrt).
"""
import argparse
from pathlib import Path

import numpy as np
import trimesh

from beach_scene import ASSETS, SCENES, blocked, camera_eye, load_fragment
from renderer.optics.arrays import multilayer_transmittance
from renderer.scene.description import MaterialDesc


def lens_material() -> MaterialDesc:
    """The "lens" material of scenes/parts/beach_props.pbrt, as the renderer reads it."""
    return next(m for m in load_fragment(SCENES / "parts" / "beach_props.pbrt").materials if m.name == "lens")


def luminous_transmittance(lens: MaterialDesc, tint: float, coated_back: bool = False) -> float:
    """D65 luminous transmittance at normal incidence of the lens: its coating (with the layers'
    Cauchy dispersion, not the thickness map) on the front, a bare glass back face as the scene
    has it (or, ``coated_back``, the coating there too, as the scene had it until issue 33), no
    interreflection, and one pass of a grey tint."""
    import colour

    v = lens.values
    lam = np.arange(380.0, 781.0, 5.0)
    n_lens = float(np.ravel(v["eta_inner"])[0])
    eta = [1.0, *v["layer_eta"], n_lens]
    front = multilayer_transmittance(np.ones_like(lam), lam, eta, [0.0] * len(eta), v["layer_thickness"],
                                     v.get("layer_cauchyb"))
    back = front if coated_back else multilayer_transmittance(np.ones_like(lam), lam, [1.0, n_lens], [0.0, 0.0], [])
    shape = colour.SpectralShape(380, 780, 5)
    y = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(shape).values[:, 1]
    d65 = colour.SDS_ILLUMINANTS["D65"].copy().align(shape).values
    return float((y * d65 * front * back * tint).sum() / (y * d65).sum())


def lens_front(lens: trimesh.Trimesh, m: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """World positions and unit normals of the lens front's vertices (the convex front faces +z in
    the mesh frame), and each vertex's area weight: a third of the area of each face around it."""
    front = lens.vertex_normals[:, 2] > 0.5
    n = lens.vertex_normals[front] @ m[:3, :3].T
    w = np.zeros(len(lens.vertices))
    np.add.at(w, lens.faces.ravel(), np.repeat(lens.area_faces / 3.0, 3))
    return lens.vertices[front] @ m[:3, :3].T + m[:3, 3], n / np.linalg.norm(n, axis=1)[:, None], w[front]


def frame_behind(p: np.ndarray, d: np.ndarray, frame: trimesh.Trimesh, m: np.ndarray) -> np.ndarray:
    """Whether the camera's line of sight d through each lens-front point p, continued straight past
    the 2 mm lens (its refraction shifts it by under 1 mm), meets the frame (a temple or the rim
    behind): where the frame can show through the lens."""
    world = trimesh.Trimesh(frame.vertices @ m[:3, :3].T + m[:3, 3], frame.faces, process=False)
    return blocked(world, p + 0.004 * d, d)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--placement", type=Path, default=ASSETS / "sunglasses_placement" / "placement.npz")
    ap.add_argument("--tint", type=float, nargs="*", default=[],
                    help="other grey tints per pass to compare (the category 3 lens before 2026-12-02: 0.21)")
    args = ap.parse_args()
    m, eye, lens_mat = np.load(args.placement)["transform"], camera_eye(), lens_material()
    tint = float(lens_mat.values["tint"][1])   # the scene's: the green of its "rgb tint"
    print(f"tint {tint} per pass: luminous transmittance {luminous_transmittance(lens_mat, tint):.2f} "
          f"(coated front, bare back), {luminous_transmittance(lens_mat, tint, coated_back=True):.2f} "
          "with both faces coated")
    for other in args.tint:
        print(f"tint {other} per pass: luminous transmittance {luminous_transmittance(lens_mat, other):.2f}")
    tilt = np.degrees(np.arcsin(m[1, 2] / np.linalg.norm(m[:3, 2])))
    print(f"lens axis (mesh +z) {tilt:.1f} deg above the horizontal")
    frame = trimesh.load(ASSETS / "sunglasses" / "frame.ply", process=False)
    for name in ("lens_left", "lens_right"):
        p, n, w = lens_front(trimesh.load(ASSETS / "sunglasses" / f"{name}_front.ply", process=False), m)
        d = (p - eye) / np.linalg.norm(p - eye, axis=1)[:, None]
        r = d - 2.0 * (d * n).sum(1)[:, None] * n                   # the mirror direction
        height = (p[:, 1] - p[:, 1].min()) / np.ptp(p[:, 1])        # 0 at the lens's bottom, 1 at its top
        bands = [(lo, (height >= lo) & (height < lo + 0.2 + 1e-9)) for lo in np.arange(0.0, 1.0, 0.2)]
        elevation = np.degrees(np.arcsin(np.clip(r[:, 1], -1, 1)))
        azimuth = np.degrees(np.arctan2(r[:, 2], r[:, 0]))
        view = np.degrees(np.arctan2(eye[1] - p[:, 1].mean(), np.linalg.norm((eye - p.mean(0))[[0, 2]])))
        print(f"{name}: centre {np.round(p.mean(0), 3)}, camera {view:.1f} deg above it")
        print("  lens height   elevation (deg)   azimuth (deg)")
        for lo, s in bands:
            print(f"  {lo:.1f}-{lo + 0.2:.1f}      {elevation[s].min():6.0f} .. {elevation[s].max():3.0f}"
                  f"     {azimuth[s].min():5.0f} .. {azimuth[s].max():4.0f}")
        covered = w * frame_behind(p, d, frame, m)
        print(f"  the frame lies behind {covered.sum() / w.sum():.1%} of the lens front's area"
              + "".join(f"; {covered[s].sum() / w[s].sum():.0%} of heights {lo:.1f}-{lo + 0.2:.1f}"
                        for lo, s in bands if covered[s].sum() > 0))
        up = elevation > 0
        for dist in (7.0, 14.0):
            t = dist / np.maximum(np.hypot(r[up, 0], r[up, 2]), 1e-9)
            q = p[up] + r[up] * t[:, None]
            print(f"  above the horizon, {dist:.0f} m out: x {q[:, 0].min():.1f}..{q[:, 0].max():.1f}, "
                  f"z {q[:, 2].min():.1f}..{q[:, 2].max():.1f}, height up to {q[:, 1].max():.1f} m")


if __name__ == "__main__":
    main()
