"""Colour the eye can see in the beach frame (issue 33, item 2): per region found through the
material AOV, the displayed pixels' mean CIE L*, mean chroma C*ab and hue spread.

    python benchmarks/beach_colour.py                                  # render 270x480, 32 spp, measure
    python benchmarks/beach_colour.py --res 540x960 --spp 16 --denoise # make render's preview settings
    python benchmarks/beach_colour.py --exr out/beach.exr              # measure a render that has a material AOV
    PYTHONPATH=/work/main python benchmarks/beach_colour.py --scene /work/main/scenes/beach.pbrt   # another tree

"Displayed" means what the PNG shows: the linear image at the scene's fixed exposure (0 stops),
clipped to [0, 1], sRGB-encoded and quantised to 8 bits, exactly as ``render -o x.png`` writes
it, then converted with ``skimage.color.rgb2lab`` (D65, 2 degree observer). Regions: materials
whose names contain ``nacre`` (every shell nacre), ``lens`` (front and back faces), and the
sand: all of it, and its brighter half (L* at or above the sand's median) as the sunlit sand,
since the material AOV does not say what is in shadow. The hue spread is taken over the pixels
a viewer sees as coloured (L* >= 30 and C*ab >= 5; darker or greyer pixels have a hue only in
the arithmetic): the circular standard deviation of h_ab and its 5-95 % range about the circular
mean. Targets of the issue for the final frame: nacre mean L* >= 45, mean C*ab >= 15.

CIELAB's white is D65, so a grey surface in the evening sun already has chroma (a reflectance of
0.1 under the beach's sun alone: C*ab 17; the sunlit sand 27): a second table gives the regions
balanced to the sun, the image divided by the sun's linear RGB at luminance 1 before the display
path (von Kries in sRGB primaries, roughly what an eye adapted to the evening light sees). There a
grey surface in the sun has no chroma, and what remains is the surface's own colour.
"""
from __future__ import annotations

import argparse
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import warnings

warnings.filterwarnings("ignore", message=".*Matplotlib.*")

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "scenes" / "beach.pbrt"
OUT = ROOT / "out" / "beach_colour"
#: The issue's visibility thresholds for the hue spread.
MIN_L, MIN_C = 30.0, 5.0


@dataclass(frozen=True)
class ColourStats:
    """What one region of the displayed image looks like."""

    pixels: int
    mean_l: float          # mean CIE L*
    mean_c: float          # mean chroma C*ab
    seen: int              # pixels with L* >= MIN_L and C*ab >= MIN_C
    hue_sd: float          # circular s.d. of h_ab over the seen pixels, degrees
    hue_range: float       # 5-95 % range of h_ab about its circular mean, degrees
    mean_hue: float        # circular mean of h_ab over the seen pixels, degrees

    def row(self, name: str) -> str:
        return (f"| {name} | {self.pixels} | {self.mean_l:.1f} | {self.mean_c:.1f} | "
                f"{self.seen / max(self.pixels, 1):.0%} | {self.hue_sd:.1f} | {self.hue_range:.0f} | {self.mean_hue:.0f} |")


HEADER = ("| region | pixels | mean L* | mean C*ab | L* >= 30 and C* >= 5 | hue s.d. (deg) | hue 5-95 % (deg) | mean hue (deg) |\n"
          "|---|---:|---:|---:|---:|---:|---:|---:|")


def displayed_lab(linear_rgb: np.ndarray, exposure: float = 0.0) -> np.ndarray:
    """CIELAB of what the PNG shows for linear sRGB pixels: exposure, clip, sRGB encoding and
    8-bit quantisation as :func:`renderer.io.images.write_png` does, then skimage's rgb2lab."""
    from skimage.color import rgb2lab

    from renderer.color.rgb import linear_to_srgb

    x = np.nan_to_num(np.asarray(linear_rgb, dtype=np.float64), nan=0.0) * (2.0 ** exposure)
    srgb8 = (linear_to_srgb(x).astype(np.float64) * 255.0 + 0.5).astype(np.uint8)
    return rgb2lab(srgb8.astype(np.float64) / 255.0)


def colour_stats(lab: np.ndarray, mask: np.ndarray) -> ColourStats:
    """Mean L*, mean C*ab and the hue spread of the masked pixels of a Lab image (H, W, 3)."""
    px = lab[mask]
    if len(px) == 0:
        return ColourStats(0, float("nan"), float("nan"), 0, float("nan"), float("nan"), float("nan"))
    chroma = np.hypot(px[:, 1], px[:, 2])
    seen = (px[:, 0] >= MIN_L) & (chroma >= MIN_C)
    sd = rng = mean_hue = float("nan")
    if seen.any():
        h = np.arctan2(px[seen, 2], px[seen, 1])
        s, c = np.sin(h).mean(), np.cos(h).mean()
        mean = np.arctan2(s, c)
        sd = float(np.degrees(np.sqrt(-2.0 * np.log(max(np.hypot(s, c), 1e-12)))))
        lo, hi = np.percentile(np.degrees(np.angle(np.exp(1j * (h - mean)))), [5, 95])
        rng, mean_hue = float(hi - lo), float(np.degrees(mean) % 360.0)
    return ColourStats(int(len(px)), float(px[:, 0].mean()), float(chroma.mean()), int(seen.sum()), sd, rng, mean_hue)


def sun_white(scene) -> np.ndarray | None:
    """The scene's first distant light's RGB (L times scale) at luminance 1, or None without one:
    the white of the sun-balanced table."""
    from renderer.color.rgb import luminance

    for light in scene.lights:
        if light.kind == "distant":
            rgb = np.asarray(light.values["L"], np.float64) * float(light.values.get("scale", 1.0))
            return rgb / float(luminance(rgb))
    return None


def regions(material: np.ndarray, names: list[str], lab: np.ndarray) -> dict[str, np.ndarray]:
    """Masks of the measured regions, from the material AOV's ids (indices into ``names``)."""
    def having(pred) -> np.ndarray:
        return np.isin(material, [i for i, n in enumerate(names) if pred(n)])

    sand = having(lambda n: n == "sand")
    out = {"nacre": having(lambda n: "nacre" in n), "lens": having(lambda n: "lens" in n), "sand (all)": sand}
    if sand.any():
        out["sand, sunlit (L* >= median)"] = sand & (lab[..., 0] >= np.median(lab[sand][:, 0]))
    for n in sorted({n for n in names if "nacre" in n}):
        out[f"  {n}"] = having(lambda m, n=n: m == n)
    return out


def render(scene: Path, exr: Path, res: str, spp: int, denoise: bool, threads: int | None) -> None:
    """The scene at its fixed camera, with the material AOV, through the CLI of the tree on PYTHONPATH."""
    exr.parent.mkdir(parents=True, exist_ok=True)
    cmd = [sys.executable, "-m", "renderer", str(scene), "-o", str(exr), "--res", res, "--spp", str(spp),
           "--aov", "material,instance", "--quiet"] + (["--denoise"] if denoise else []) + \
          (["--threads", str(threads)] if threads else [])
    print(" ".join(cmd), file=sys.stderr)
    subprocess.check_call(cmd)


def measure(exr: Path, scene: Path, png: Path | None = None) -> dict[str, ColourStats]:
    """Read a render with a material AOV, print the table, and return it."""
    from renderer.api import load_scene
    from renderer.io.images import read_exr, write_png

    chans, header = read_exr(exr)
    img = np.stack([chans[c] for c in "RGB"], -1)
    lab = displayed_lab(img)
    desc = load_scene(scene)
    names = [m.name for m in desc.materials]
    h, w = lab.shape[:2]
    print(f"{exr}: {w}x{h}, {header.get('spp', '?')} spp, scene {scene}")
    print(HEADER)
    stats = {}
    masks = regions(chans["material.id"], names, lab)
    for name, mask in masks.items():
        stats[name] = colour_stats(lab, mask)
        print(stats[name].row(name))
    white = sun_white(desc)
    if white is not None:
        balanced = displayed_lab(img / white)
        print(f"\nbalanced to the sun (image / {np.round(white, 3).tolist()}), the same regions:")
        print(HEADER)
        for name, mask in masks.items():
            print(colour_stats(balanced, mask).row(name))
    if png is not None:
        write_png(png, img)
    return stats


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", type=Path, default=SCENE)
    ap.add_argument("--exr", type=Path, help="measure this render (it needs the material AOV) instead of rendering")
    ap.add_argument("--out", type=Path, help="where the render goes (default out/beach_colour/<res>_<spp>spp.exr)")
    ap.add_argument("--res", default="270x480")
    ap.add_argument("--spp", type=int, default=32)
    ap.add_argument("--denoise", action="store_true")
    ap.add_argument("--threads", type=int)
    a = ap.parse_args()
    exr = a.exr
    if exr is None:
        exr = a.out or OUT / f"{a.res}_{a.spp}spp.exr"
        render(a.scene, exr, a.res, a.spp, a.denoise, a.threads)
    measure(exr, a.scene, exr.with_suffix(".png"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
