"""The beach props' maps and materials: the shell pigment map (deterministic, its colour bands on
the height map's growth bands, colours between the two CIELAB ends) and scenes/parts/beach_props.pbrt
(loads with its assets built from the beach recipe's quick entries; the lens is the 9-layer blue
mirror over a tinted clear lens, the nacre the layered 5-period stack)."""
from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from assets_gen import recipe
from assets_gen.maps import shell
from renderer.io.images import read_exr

SCENES = Path(__file__).resolve().parents[2] / "scenes"
SMALL = dict(width=96, height=64, bands=12)


def luminance(rgb: np.ndarray) -> np.ndarray:
    return rgb @ np.array([0.2126, 0.7152, 0.0722])


def test_pigment_is_deterministic_and_a_reflectance():
    p = shell.ShellPigmentParams(**SMALL)
    a, b = shell.shell_pigment(p, 4), shell.shell_pigment(p, 4)
    assert a.shape == (64, 96, 3) and np.array_equal(a, b)
    assert not np.array_equal(a, shell.shell_pigment(p, 5))
    assert a.min() >= 0.0 and a.max() <= 1.0


def test_pigment_bands_follow_the_growth_bands():
    """With the height map's seed and bands, the pigment's dark growth-check lines fall where the
    height map's bands meet (height ~ 0); another seed's bands do not line up."""
    profile = shell.shell_height(shell.ShellHeightParams(**SMALL, waviness=0.0), 7).rows(0, 1)[0]   # along u
    edges = (profile <= np.roll(profile, 1)) & (profile <= np.roll(profile, -1))        # band ends
    assert 8 <= edges.sum() <= 14
    ratios = {}
    for seed in (7, 8):
        lum = luminance(shell.shell_pigment(shell.ShellPigmentParams(**SMALL, waviness=0.0, spiral_bands=0), seed))
        ratios[seed] = lum[:, edges].mean() / lum[:, ~edges].mean()
    assert ratios[7] < 0.93 and abs(ratios[8] - 1.0) < 0.04, ratios


def test_pigment_colours_lie_between_the_two_lab_ends():
    from skimage.color import rgb2lab

    from renderer.color.rgb import linear_to_srgb

    p = shell.ShellPigmentParams(**SMALL)
    lab = rgb2lab(linear_to_srgb(shell.shell_pigment(p, 3)).astype(np.float64)).reshape(-1, 3)
    light, dark = np.asarray(p.light_lab), np.asarray(p.dark_lab)
    t = np.clip((lab - light) @ (dark - light) / np.dot(dark - light, dark - light), 0.0, 1.0)
    off = np.linalg.norm(lab - (light + t[:, None] * (dark - light)), axis=1)
    assert off.max() < 1.5                    # on the segment, up to 8-bit-free float round trips
    assert np.ptp(t) > 0.5                    # and spread along it: a pattern, not a flat colour


def test_pigment_cli_writes_rgb(tmp_path):
    from assets_gen.cli import main

    assert main(["shell-pigment", "--width", "32", "--height", "16", "--out", str(tmp_path)]) == 0
    chans, header = read_exr(tmp_path / "shell_pigment.exr")
    assert sorted(chans) == ["B", "G", "R"] and chans["R"].shape == (16, 32)
    assert json.loads((tmp_path / "shell-pigment.json").read_text())["generator"] == "shell-pigment"


@pytest.fixture(scope="module")
def props_scene(tmp_path_factory) -> Path:
    """scenes/parts/beach_props.pbrt staged with the quick maps it reads, and a scene using it."""
    root = tmp_path_factory.mktemp("beach")
    (root / "parts").mkdir()
    shutil.copy2(SCENES / "parts" / "beach_props.pbrt", root / "parts")
    raw = json.loads((SCENES / "beach.recipe.json").read_text())
    raw["assets"] = [a for a in raw["assets"] if a["generator"] in ("lens-thickness", "shell-height",
                                                                    "shell-bump", "shell-pigment")]
    (root / "beach.recipe.json").write_text(json.dumps(raw))
    recipe.build(root / "beach.recipe.json", quick=True, log=None)
    scene = root / "props.pbrt"
    scene.write_text('Camera "perspective"\nWorldBegin\nLightSource "infinite"\nInclude "parts/beach_props.pbrt"\n'
                     + "".join(f'AttributeBegin\n NamedMaterial "{m}"\n Shape "sphere" "float radius" [0.01]\nAttributeEnd\n'
                               for m in ("lens", "frame", "shell", "nacre")))
    return scene


def test_beach_prop_materials_load(props_scene):
    import renderer

    from renderer.scene import load_description

    desc = load_description(props_scene)
    mats = {m.name: m for m in desc.materials}
    assert {n: mats[n].kind for n in ("lens", "frame", "shell", "nacre")} == \
        {"lens": "thinfilm", "frame": "disney", "shell": "disney", "nacre": "thinfilm"}
    lens, nacre = mats["lens"].values, mats["nacre"].values
    assert len(lens["layer_eta"]) == 9 and lens["transmission"] and "thicknessmap" in lens
    luminance = float(np.dot([0.2126, 0.7152, 0.0722], lens["tint"]))
    assert 0.08 < luminance < 0.5       # one pass of a sunglass tint (categories 2-3), not clear glass
    assert nacre["layered"] and nacre["repeat"] == 5 and len(nacre["layer_eta"]) == 2
    scene = renderer.load_scene(props_scene)
    assert scene.warnings == [], scene.warnings
