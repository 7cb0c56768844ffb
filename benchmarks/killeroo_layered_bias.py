"""Why pbrt-v4's killeroos in killeroo-simple are brighter than ours (docs/pbrt-v4.md,
"killeroo-simple"): pbrt-v4 against itself and ours on one variant of the scene.

The variant (made from tests/data/pbrt/killeroo_simple.pbrt): grey killeroos (0.3) on a grey floor,
the light a sphere of radius 15 with L 80 (large enough for BSDF sampling to find), the film
cropped to the killeroos' region. Rendered three ways, each with two seeds:

* pbrt-v4 ``volpath`` (its default): light sampling, so the layered f (LayeredBxDF::f) and MIS;
* pbrt-v4 ``simplepath`` with ``samplelights`` false: BSDF sampling only, the layered random walk
  (LayeredBxDF::Sample_f), which needs no MIS weights;
* ours (zsobol), with light sampling.

It prints each image's mean over the killeroo (image rows 45-65, columns 20-60) and over floor and
wall (rows 75-95) relative to pbrt's walk-only image, with one standard error from the seeds.
Measured: pbrt volpath 1.057 +- 0.003 on the killeroo (1.002 on floor and wall), ours 0.993.
Needs the pbrt-v4 binary (tests/data/pbrt/render_references.py finds it); about 6 CPU-minutes.

    WARP_CACHE_PATH=.warp-cache .venv/bin/python benchmarks/killeroo_layered_bias.py
"""
from __future__ import annotations

import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "tests" / "data" / "pbrt"
sys.path.insert(0, str(DATA))
from render_references import pbrt_binary  # noqa: E402

from renderer.api import load_scene, render  # noqa: E402
from renderer.io.images import read_exr  # noqa: E402

EDITS = [
    ('Film "rgb"', 'Film "rgb" "float cropwindow" [ 0 0.5 0.2917 0.7917 ]'),
    ('"rgb L" [ 2000 2000 2000 ]', '"rgb L" [ 80 80 80 ]'),
    ('"float radius" [ 3 ]', '"float radius" [ 15 ]'),
    ('"rgb reflectance" [ 0.5 0.5 0.8 ]', '"rgb reflectance" [ 0.5 0.5 0.5 ]'),
    ('"rgb reflectance" [ 0.4 0.2 0.2 ]', '"rgb reflectance" [ 0.3 0.3 0.3 ]'),
    ('"rgb reflectance" [ 0.4 0.5 0.4 ]', '"rgb reflectance" [ 0.3 0.3 0.3 ]'),
    ("../../../scenes/geometry/killeroo.pbrt", str(ROOT / "scenes" / "geometry" / "killeroo.pbrt")),
]
WALK_ONLY = ("WorldBegin", 'Integrator "simplepath" "bool samplelights" false "integer maxdepth" 5\nWorldBegin')
#: Rows and columns of the cropped image (its first row is the image's row 35).
REGIONS = {"killeroo": (slice(10, 30), slice(20, 60)), "floor and wall": (slice(40, 60), slice(None))}


def variant(text: str, edits: list[tuple[str, str]]) -> str:
    for old, new in edits:
        assert old in text, old
        text = text.replace(old, new)
    return text


def pbrt_pair(scene: Path, spp: int) -> list[np.ndarray]:
    images = []
    for seed in (1, 2):
        out = scene.with_name(f"{scene.stem}-{seed}.exr")
        subprocess.run([str(pbrt_binary()), "--spp", str(spp), "--seed", str(seed), "--outfile", str(out), str(scene)],
                       check=True, capture_output=True)
        channels, _ = read_exr(out)
        images.append(np.stack([channels[c] for c in "RGB"], -1))
    return images


def mean_and_error(pair: list[np.ndarray], region) -> tuple[float, float]:
    a, b = (x[region].mean() for x in pair)
    return 0.5 * (a + b), 0.5 * abs(a - b)


def main() -> None:
    text = variant((DATA / "killeroo_simple.pbrt").read_text(), EDITS)
    with tempfile.TemporaryDirectory() as tmp:
        light = Path(tmp) / "light_sampling.pbrt"
        walk = Path(tmp) / "walk_only.pbrt"
        light.write_text(text)
        walk.write_text(variant(text, [WALK_ONLY]))
        images = {"pbrt volpath": pbrt_pair(light, 1024), "pbrt walk only": pbrt_pair(walk, 4096)}
        scene = load_scene(light)
        images["ours"] = [render(scene, spp=512, seed=s, sampler="zsobol") for s in (11, 12)]
    for name, region in REGIONS.items():
        ref, ref_err = mean_and_error(images["pbrt walk only"], region)
        for who in ("pbrt volpath", "ours"):
            m, err = mean_and_error(images[who], region)
            print(f"{name}: {who} / pbrt walk only = {m / ref:.4f} +- {np.hypot(err / m, ref_err / ref) * m / ref:.4f}")


if __name__ == "__main__":
    main()
