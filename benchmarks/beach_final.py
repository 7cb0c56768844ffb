"""The beach's final frame: render it (checkpointed, resumable, time-boxed) and measure it.

    python benchmarks/beach_final.py render --spp 256 --minutes 45     # again later: it resumes
    python benchmarks/beach_final.py measure                           # table + README images

`render` runs the CLI at 1080x1920 with the material, instance and albedo AOVs and the denoiser
(the EXR keeps the undenoised image as its `noisy` layer), resuming from the checkpoint when one
is there. `measure` reads that EXR and prints, per region found through the material AOV, what the
beach issue asks to be measured: the lens pixels' mean reflectance (albedo AOV luminance) and CIELAB
chroma, the nacre pixels' hue spread, and the number of distinct grain instances seen in the
in-focus sand crop below the lenses; it also writes the full frame and 100 % crops (noisy beside denoised) as PNGs.
"""
from __future__ import annotations

import argparse
import fnmatch
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "scenes" / "beach.pbrt"
OUT = ROOT / "out" / "beach_final"
CROP = 320                                   # 100 % crops: CROP x CROP pixels of the full frame


def render(spp: int, minutes: float, threads: int | None) -> int:
    """One time-boxed session of the final render; resumes when a checkpoint exists. The assets
    are built at the recipe's final level first: ``make render`` leaves the preview level there."""
    OUT.mkdir(parents=True, exist_ok=True)
    subprocess.check_call([sys.executable, "-m", "assets_gen", "recipe", str(SCENE)], cwd=ROOT,
                          stdout=subprocess.DEVNULL)
    ckpt = OUT / "beach_final.ckpt.npz"
    cmd = [sys.executable, "-m", "renderer", str(SCENE), "-o", str(OUT / "beach_final.exr"),
           "--res", "1080x1920", "--spp", str(spp), "--checkpoint", str(ckpt), "--checkpoint-every", "300",
           "--time-limit", str(60.0 * minutes), "--aov", "material,instance,albedo", "--denoise"]
    if ckpt.exists():
        cmd += ["--resume", str(ckpt)]
    if threads:
        cmd += ["--threads", str(threads)]
    print(" ".join(cmd), file=sys.stderr)
    return subprocess.call(cmd, cwd=ROOT)


def _lab(rgb: np.ndarray) -> np.ndarray:
    """CIELAB (D65) of linear sRGB values, white = (1, 1, 1)."""
    import warnings

    warnings.filterwarnings("ignore", message='"Matplotlib" related API features are not available')
    import colour

    xyz = colour.RGB_to_XYZ(rgb, colour.RGB_COLOURSPACES["sRGB"], apply_cctf_decoding=False)
    return colour.XYZ_to_Lab(xyz, colour.CCS_ILLUMINANTS["CIE 1931 2 Degree Standard Observer"]["D65"])


def _mask(material: np.ndarray, names: list[str], pattern: str) -> np.ndarray:
    ids = [i for i, n in enumerate(names) if fnmatch.fnmatch(n, pattern)]
    return np.isin(material, ids)


def _crop_box(mask: np.ndarray, size: int) -> tuple[slice, slice] | None:
    """A size x size window centred on the mask's centroid, kept inside the frame."""
    ys, xs = np.nonzero(mask)
    if len(ys) == 0:
        return None
    h, w = mask.shape
    y0 = int(np.clip(ys.mean() - size / 2, 0, max(h - size, 0)))
    x0 = int(np.clip(xs.mean() - size / 2, 0, max(w - size, 0)))
    return slice(y0, y0 + size), slice(x0, x0 + size)


def _hue_spread(lab: np.ndarray) -> tuple[float, float]:
    """(circular standard deviation, 5–95 % range about the circular mean) of hue in degrees,
    over pixels with chroma above 3 (greys have no hue)."""
    c = np.hypot(lab[:, 1], lab[:, 2])
    h = np.arctan2(lab[c > 3.0, 2], lab[c > 3.0, 1])
    if len(h) == 0:
        return 0.0, 0.0
    mean = np.arctan2(np.sin(h).mean(), np.cos(h).mean())
    r = np.hypot(np.sin(h).mean(), np.cos(h).mean())
    d = np.degrees(np.angle(np.exp(1j * (h - mean))))
    lo, hi = np.percentile(d, [5, 95])
    return float(np.degrees(np.sqrt(-2.0 * np.log(max(r, 1e-12))))), float(hi - lo)


def measure(exr: Path, lens: str, nacre: str, shell: str, grains: str, images: Path) -> None:
    from renderer.api import load_scene
    from renderer.io.images import read_exr, write_png

    chans, header = read_exr(exr)
    img = np.stack([chans[c] for c in "RGB"], -1)
    noisy = np.stack([chans[f"noisy.{c}"] for c in "RGB"], -1) if "noisy.R" in chans else img
    albedo = np.stack([chans[f"albedo.{c}"] for c in "RGB"], -1)
    material, instance = chans["material.id"], chans["instance.id"]
    names = [m.name for m in load_scene(SCENE).materials]
    h, w = material.shape
    print(f"{exr.name}: {w}x{h}, {header.get('spp', '?')} spp, {float(header.get('renderTimeSeconds', 0)):.0f} s render (this session)")
    print("| region | pixels | measurement |\n|---|---:|---|")
    lens_m = _mask(material, names, lens)
    if lens_m.any():
        a = albedo[lens_m]
        lab = _lab(np.clip(a, 0.0, None))
        print(f"| lens ({lens}) | {lens_m.sum()} | mean reflectance (albedo luminance) "
              f"{float((a @ [0.2126, 0.7152, 0.0722]).mean()):.3f}; mean chroma C*ab {np.hypot(lab[:, 1], lab[:, 2]).mean():.1f} "
              f"(albedo), {np.hypot(*_lab(np.clip(img[lens_m], 0, None))[:, 1:].T).mean():.1f} (image) |")
    nacre_m = _mask(material, names, nacre)
    if nacre_m.any():
        sd, rng = _hue_spread(_lab(np.clip(img[nacre_m], 0.0, None)))
        print(f"| nacre ({nacre}) | {nacre_m.sum()} | hue circular s.d. {sd:.1f} deg, 5-95 % range {rng:.1f} deg |")
    grain_m = _mask(material, names, grains)
    fg = np.zeros_like(grain_m)   # the sand in focus: just below the lenses (the focus distance), else the lowest third
    below = int(np.nonzero(lens_m)[0].max()) if lens_m.any() else 2 * h // 3
    fg[below:below + CROP, :] = True
    box = _crop_box(grain_m & fg, CROP)
    if box is not None:
        seen = instance[box][grain_m[box]]
        ids, counts = np.unique(seen, return_counts=True)
        print(f"| grains ({grains}), {CROP}x{CROP} in-focus crop below the lenses | {int(grain_m[box].sum())} | "
              f"{len(ids)} distinct grain instances seen, {int((counts >= 4).sum())} of them over 4 pixels |")
    images.mkdir(parents=True, exist_ok=True)
    write_png(images / "beach_final.png", img)
    for name, m in (("lens", lens_m), ("shell", _mask(material, names, shell)), ("grains", grain_m & fg)):
        b = _crop_box(m, CROP)
        if b is not None:
            write_png(images / f"beach_final_{name}.png", np.concatenate([noisy[b], img[b]], axis=1))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("render")
    r.add_argument("--spp", type=int, default=256)
    r.add_argument("--minutes", type=float, default=45.0, help="stop after the pass that crosses this")
    r.add_argument("--threads", type=int)
    m = sub.add_parser("measure")
    m.add_argument("--exr", type=Path, default=OUT / "beach_final.exr")
    m.add_argument("--lens", default="lens*", help="material-name pattern of the lens pixels")
    m.add_argument("--nacre", default="*nacre*", help="the nacre pixels whose hue spread is measured (every shell's)")
    m.add_argument("--shell", default="oyster*", help="the shell the crop is centred on (the pearl oyster, issue 33)")
    m.add_argument("--grains", default="grain*")
    m.add_argument("--images", type=Path, default=OUT, help="where the PNGs go (docs/images for the README)")
    a = ap.parse_args()
    if a.cmd == "render":
        return render(a.spp, a.minutes, a.threads)
    measure(a.exr, a.lens, a.nacre, a.shell, a.grains, a.images)
    return 0


if __name__ == "__main__":
    sys.exit(main())
