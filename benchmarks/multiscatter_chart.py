"""The chart of docs/thinfilm.md and the README's gallery: closed rough spheres (glass, gold, a 350 nm
soap-water film on glass, a 6-layer TiO2/SiO2-like mirror stack on glass) in a white furnace (a sky of
radiance 1, depth 64, no roulette, rgb3) at four roughnesses, single scattering beside ``multiscatter``,
each tile labelled with its mean over the middle pixels (the furnace value). A lossless sphere that
keeps its energy disappears into the sky; one that loses it shows as a dark disc; gold keeps its
colour and loses less of it with multiple scattering.

    WARP_CACHE_PATH=.warp-cache .venv/bin/python benchmarks/multiscatter_chart.py [--res 64] [--spp 48]
        [--png docs/images/multiscatter_chart.png]
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
from scenes_py import single_object_scene  # noqa: E402

import renderer  # noqa: E402
from renderer.api import init_warp  # noqa: E402
from renderer.io.images import write_png  # noqa: E402
from renderer.materials import material  # noqa: E402

SPHERES = {
    "glass": ("dielectric", dict(eta=1.5)),
    "gold": ("conductor", dict(eta=(0.143, 0.374, 1.442), k=(3.983, 2.385, 1.603))),
    "soap film on glass": ("thinfilm", dict(eta_film=1.33, thickness=350.0, eta_inner=1.5, transmission=True)),
    "mirror stack on glass": ("thinfilm", dict(layer_eta=[2.4, 1.46], layer_thickness=[57.3, 94.2], repeat=3,
                                               eta_inner=1.52, transmission=True)),
}
ROUGHNESS = (0.1, 0.3, 0.6, 1.0)
LABEL_H = 14      # pixels of text under each tile
HEAD_H = 28       # the column headings


def tile(kind: str, values: dict, roughness: float, multiscatter: bool, res: int, spp: int) -> np.ndarray:
    desc = single_object_scene(material(kind, **values, roughness=roughness, multiscatter=multiscatter), res=res,
                               fov=26.0)
    desc.integrator.max_depth = 64
    return renderer.render(desc, spp=spp, thin_film="rgb3", seed=1, rr_depth=-1, threads=1)


def centre_mean(img: np.ndarray) -> np.ndarray:
    """The furnace value: the mean over the middle half of the tile (well inside the sphere)."""
    n = img.shape[0]
    return img[n // 4:3 * n // 4, n // 4:3 * n // 4].reshape(-1, 3).astype(np.float64).mean(axis=0)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--res", type=int, default=64)
    ap.add_argument("--spp", type=int, default=48)
    ap.add_argument("--png", type=Path, default=ROOT / "docs" / "images" / "multiscatter_chart.png")
    a = ap.parse_args()
    init_warp()
    rows, cols, r = len(SPHERES), 2 * len(ROUGHNESS), a.res
    canvas = np.ones((HEAD_H + rows * (r + LABEL_H), cols * r, 3), np.float32) * 0.18
    labels = []
    print("| sphere | roughness | furnace, single | furnace, multiple | s single | s multiple |")
    print("|---|---:|---|---|---:|---:|")
    for i, (name, (kind, values)) in enumerate(SPHERES.items()):
        for j, rough in enumerate(ROUGHNESS):
            row = []
            for k, ms in enumerate((False, True)):
                t = time.perf_counter()
                img = tile(kind, values, rough, ms, r, a.spp)
                row.append((centre_mean(img), time.perf_counter() - t))
                y, x = HEAD_H + i * (r + LABEL_H), (2 * j + k) * r
                canvas[y:y + r, x:x + r] = img
                labels.append((x, y + r, row[-1][0]))
            fmt = lambda m: "(" + ", ".join(f"{v:.3f}" for v in m) + ")"  # noqa: E731
            print(f"| {name} | {rough} | {fmt(row[0][0])} | {fmt(row[1][0])} | {row[0][1]:.1f} | {row[1][1]:.1f} |",
                  flush=True)
    write_png(a.png, canvas)
    _annotate(a.png, labels, r)
    print(f"wrote {a.png}")


def _annotate(path: Path, labels: list, r: int) -> None:
    """Column headings (roughness; single | multiple) and each tile's furnace value (mean of RGB)."""
    from PIL import Image, ImageDraw

    im = Image.open(path).convert("RGB")
    d = ImageDraw.Draw(im)
    for j, rough in enumerate(ROUGHNESS):
        d.text((2 * j * r + 4, 2), f"roughness {rough}", fill=(255, 255, 255))
        d.text((2 * j * r + 4, 15), "single", fill=(200, 200, 200))
        d.text(((2 * j + 1) * r + 4, 15), "multiple", fill=(200, 200, 200))
    for x, y, m in labels:
        d.text((x + 4, y + 1), f"{float(np.mean(m)):.3f}", fill=(255, 255, 255))
    im.save(path)


if __name__ == "__main__":
    main()
