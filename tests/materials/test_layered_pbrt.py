"""The layered materials against pbrt-v4 itself: the committed reference renders in
tests/data/pbrt (``render_references.py`` makes them with pbrt-v4) against ours at modest spp."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import renderer
from renderer.io.images import read_image
from renderer.io.metrics import relative_mse

DATA = Path(__file__).parents[1] / "data" / "pbrt"
SPP = 64
REFERENCE_SPP = 1024
#: Column ranges (x) of the three spheres, rows 10-40: the per-material means compared.
SPHERES = [(8, 37), (37, 59), (59, 88)]


def measure(name: str) -> dict[str, object]:
    scene = renderer.load_scene(DATA / f"{name}.pbrt")
    # every material parameter of the scene was read (only the pixel filter is approximated)
    assert all("PixelFilter" in w for w in scene.warnings), scene.warnings
    a = renderer.render(scene, spp=SPP, seed=1)
    b = renderer.render(scene, spp=SPP, seed=2)
    ref = read_image(DATA / f"{name}.exr")[..., :3]
    ours = 0.5 * (a + b)
    # our variance per image at SPP from two independent renders; pbrt's scaled by its sample count
    noise = 0.5 * relative_mse(a, b)
    expected = noise / 2 + noise * SPP / REFERENCE_SPP
    spheres = [(ours[10:40, x0:x1].reshape(-1, 3).mean(0), ref[10:40, x0:x1].reshape(-1, 3).mean(0))
               for x0, x1 in SPHERES]
    return {"relmse": relative_mse(ours, ref), "expected": expected, "ours": ours.reshape(-1, 3).mean(0),
            "pbrt": ref.reshape(-1, 3).mean(0), "spheres": spheres}


@pytest.mark.filterwarnings("ignore::renderer.errors.RenderWarning")
@pytest.mark.parametrize("name", ["coateddiffuse", "coatedconductor"])
def test_layered_materials_match_pbrt_v4(name):
    m = measure(name)
    # within the two renders' noise plus an allowance for pbrt being spectral (and its copper spectra)
    assert m["relmse"] < 1.3 * m["expected"] + 0.002, m
    np.testing.assert_allclose(m["ours"], m["pbrt"], rtol=0.02)
    for ours, ref in m["spheres"]:
        np.testing.assert_allclose(ours, ref, rtol=0.04)
