"""Every scene in scenes/ renders: its recipe builds (with the recipe's small "quick" assets, into a
temporary copy so scenes/assets/ is untouched), it parses without warnings, and a tiny CPU render
is finite and not black."""
from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

from assets_gen import recipe

SCENES_DIR = Path(__file__).resolve().parents[2] / "scenes"
#: top-level scenes (files in scenes/parts/ are pieces included by them)
SCENES = sorted(p.stem for p in SCENES_DIR.glob("*.pbrt"))
LONG_SIDE = 32           # pixels
SPP = 2


@pytest.fixture(scope="module")
def staged(tmp_path_factory) -> Path:
    """A copy of scenes/ without its generated assets."""
    dst = tmp_path_factory.mktemp("scenes")
    for p in SCENES_DIR.iterdir():
        if p.is_file() and p.suffix in (".pbrt", ".json", ".png", ".exr", ".ply"):
            shutil.copy2(p, dst / p.name)
        elif p.is_dir() and p.name != "assets":
            shutil.copytree(p, dst / p.name)
    return dst


def test_known_scenes_are_all_here():
    assert {"demo", "props", "beach", "fig1_killeroos", "fig2_shell", "fig3_heightmaps", "fig8_bump"} <= set(SCENES)


@pytest.mark.parametrize("name", SCENES)
def test_scene_renders(staged, name):
    import renderer

    scene_path = staged / f"{name}.pbrt"
    rec = recipe.recipe_for(scene_path)
    if rec is not None:
        recipe.build(rec, quick=True, log=None)
    scene = renderer.load_scene(scene_path)
    assert scene.warnings == [], scene.warnings
    w, h = scene.film.width, scene.film.height
    k = LONG_SIDE / max(w, h)
    width, height = max(4, round(w * k)), max(4, round(h * k))
    img = renderer.render(scene, spp=SPP, device="cpu", width=width, height=height)
    assert img.shape == (height, width, 3)
    assert np.all(np.isfinite(img))
    assert float(img.mean()) > 0.01, f"{name} rendered (nearly) black: mean {img.mean():.4g}"
    assert scene.warnings == [], scene.warnings
