"""The Disney material chart (scenes/disney_chart.pbrt) rendered by this renderer and by Mitsuba 3's
``principled`` BSDF (variant scalar_rgb), side by side, with per-sphere mean differences.

Mitsuba gets the same camera, sky, sun and sphere parameters (sheentint is passed explicitly:
Mitsuba's default is 0, pbrt-v3's 0.5). Known model differences, which the table shows:
Mitsuba's clearcoat lacks the 1/(4 cos θi cos θo) of a microfacet BRDF (ours follows Burley and
pbrt-v3), its GGX masking is separable where ours is height-correlated, and it has no subsurface
scattering (that sphere is listed for reference only). Mitsuba's image is mirrored left-right
relative to pbrt's camera convention; it is flipped back before comparing.

    WARP_CACHE_PATH=.warp-cache .venv/bin/python benchmarks/disney_vs_mitsuba.py [--spp 64] [--scale 0.5] [--png out.png]
"""
from __future__ import annotations

import argparse
import re
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
CHART = ROOT / "scenes" / "disney_chart.pbrt"
#: Our parameter names → Mitsuba principled's.
MITSUBA_NAMES = {"metallic": "metallic", "roughness": "roughness", "spectrans": "spec_trans", "eta": "eta",
                 "speculartint": "spec_tint", "anisotropic": "anisotropic", "sheen": "sheen", "sheentint": "sheen_tint",
                 "clearcoat": "clearcoat", "clearcoatgloss": "clearcoat_gloss"}


def chart_spheres() -> list[dict]:
    """(centre, radius, parameters) of every sphere in the chart file, in file order."""
    text = CHART.read_text()
    spheres = []
    for block in re.findall(r"AttributeBegin(.*?)AttributeEnd", text, re.S):
        params = {m[2]: [float(x) for x in m[3].split()] for m in re.finditer(r'"(float|rgb) (\w+)" \[([^\]]*)\]', block)}
        centre = [float(x) for x in re.search(r"Translate ([-\d. ]+)", block).group(1).split()]
        spheres.append({"centre": np.array(centre), "radius": params.pop("radius")[0], "params": params})
    return spheres


def mitsuba_render(spheres: list[dict], width: int, height: int, spp: int) -> np.ndarray:
    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    T = mi.ScalarTransform4f
    scene = {"type": "scene", "integrator": {"type": "path", "max_depth": 12},
             "sensor": {"type": "perspective", "fov": 30, "fov_axis": "smaller",
                        "to_world": T().look_at(origin=[0, 0.4, -9], target=[0, 0, 0], up=[0, 1, 0]),
                        "film": {"type": "hdrfilm", "width": width, "height": height, "rfilter": {"type": "box"}},
                        "sampler": {"type": "independent", "sample_count": spp}},
             "sky": {"type": "constant", "radiance": {"type": "rgb", "value": [0.4, 0.42, 0.45]}},
             "sun": {"type": "directional", "direction": [2, -3, 4], "irradiance": {"type": "rgb", "value": [2.5, 2.4, 2.2]}}}
    for i, s in enumerate(spheres):
        p = s["params"]
        bsdf = {"type": "principled", "base_color": {"type": "rgb", "value": p.get("color", [0.5] * 3)},
                "sheen_tint": 0.5, "roughness": 0.5}
        bsdf |= {MITSUBA_NAMES[k]: v[0] for k, v in p.items() if k in MITSUBA_NAMES}
        scene[f"ball{i}"] = {"type": "sphere", "center": s["centre"].tolist(), "radius": s["radius"], "bsdf": bsdf}
    img = np.array(mi.render(mi.load_dict(scene)))[..., :3]
    return img[:, ::-1]


def sphere_masks(spheres: list[dict], width: int, height: int) -> list[np.ndarray]:
    """Pixels well inside each sphere's projection (pinhole, fov 30° on the shorter axis)."""
    eye = np.array([0.0, 0.4, -9.0])
    f = -eye / np.linalg.norm(eye)
    right = np.cross([0.0, 1.0, 0.0], f)
    right /= np.linalg.norm(right)
    up = np.cross(f, right)
    k = 0.5 * min(width, height) / np.tan(np.radians(15.0))
    yy, xx = np.mgrid[0:height, 0:width] + 0.5
    masks = []
    for s in spheres:
        d = s["centre"] - eye
        z = d @ f
        cx, cy = 0.5 * width + k * (d @ right) / z, 0.5 * height - k * (d @ up) / z
        r = 0.7 * k * s["radius"] / z
        masks.append((xx - cx) ** 2 + (yy - cy) ** 2 < r * r)
    return masks


def label(p: dict) -> str:
    return " ".join(f"{k}={v[0]:g}" for k, v in p.items() if k != "color") or "defaults"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--scale", type=float, default=0.5, help="resolution relative to the chart file's 400x320")
    ap.add_argument("--png", type=Path, default=None, help="write ours | Mitsuba side by side")
    args = ap.parse_args()

    import renderer
    from renderer.api import init_warp

    init_warp()
    width, height = int(400 * args.scale), int(320 * args.scale)
    spheres = chart_spheres()
    ours = renderer.render(renderer.load_scene(CHART), spp=args.spp, width=width, height=height)
    theirs = mitsuba_render(spheres, width, height, args.spp)
    print(f"{'sphere':48s} {'ours (mean RGB)':>24s} {'Mitsuba':>24s} {'rel. diff':>9s}")
    rel = []
    for s, m in zip(spheres, sphere_masks(spheres, width, height)):
        a, b = ours[m].mean(axis=0), theirs[m].mean(axis=0)
        d = float(np.abs(a - b).mean() / max(b.mean(), 1e-6))
        sss = "scatterdistance" in s["params"]
        if not sss:
            rel.append(d)
        print(f"{label(s['params']):48s} {np.array2string(a, precision=3):>24s} {np.array2string(b, precision=3):>24s} "
              f"{d:9.3f}{'  (no subsurface in Mitsuba)' if sss else ''}")
    print(f"median relative difference over the comparable spheres: {np.median(rel):.3f}")
    if args.png:
        from renderer.io.images import write_png

        write_png(args.png, np.concatenate([ours, theirs], axis=1))


if __name__ == "__main__":
    main()
