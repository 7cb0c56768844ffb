"""benchmarks/beach_colour.py's measurement (issue 33, item 2): on synthetic images whose CIELAB
values are known, mean L*, mean chroma and the hue spread come out as constructed, through the
same display path (clip, sRGB, 8 bits) a render's PNG takes."""
from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest
from skimage.color import lab2rgb

from renderer.color.rgb import srgb_to_linear

SPEC = importlib.util.spec_from_file_location(
    "beach_colour", Path(__file__).resolve().parents[2] / "benchmarks" / "beach_colour.py")
beach_colour = importlib.util.module_from_spec(SPEC)
sys.modules["beach_colour"] = beach_colour       # dataclasses look their module up there
SPEC.loader.exec_module(beach_colour)


def linear_image(lab: np.ndarray) -> np.ndarray:
    """Linear sRGB pixels whose displayed (sRGB-encoded) colour has the CIELAB values ``lab``."""
    srgb = lab2rgb(lab)
    assert np.all((srgb > 0.02) & (srgb < 0.98)), "test colours must lie inside the sRGB gamut"
    return np.asarray(srgb_to_linear(srgb), dtype=np.float64)


def test_known_lab_patches():
    """Two patches, L* 60 / C* 20 at hues 30 and 90 deg, and a grey and a dark pixel that the hue
    spread must leave out: means over all four kinds, hue statistics over the coloured two."""
    h = np.radians([30.0, 90.0])
    coloured = np.stack([np.full(2, 60.0), 20 * np.cos(h), 20 * np.sin(h)], 1)
    grey, dark = [70.0, 1.0, 1.0], [20.0, 12.0, 0.0]          # C* < 5; L* < 30
    patch = np.concatenate([np.repeat(coloured, 50, 0), np.repeat([grey], 25, 0), np.repeat([dark], 25, 0)])
    img = linear_image(patch.reshape(1, -1, 3))
    lab = beach_colour.displayed_lab(img)
    s = beach_colour.colour_stats(lab, np.ones(lab.shape[:2], dtype=bool))
    assert s.pixels == 150 and s.seen == 100
    tol = 0.6                                                 # 8-bit quantisation in L*, a*, b*
    assert s.mean_l == pytest.approx((100 * 60 + 25 * 70 + 25 * 20) / 150, abs=tol)
    assert s.mean_c == pytest.approx((100 * 20 + 25 * np.hypot(1, 1) + 25 * 12) / 150, abs=tol)
    assert s.mean_hue == pytest.approx(60.0, abs=1.5)
    assert s.hue_range == pytest.approx(60.0, abs=2.0)        # 5-95 % of two equal halves: the full 60
    # circular s.d. of two equal hues 60 deg apart: sqrt(-2 ln cos 30)
    assert s.hue_sd == pytest.approx(np.degrees(np.sqrt(-2 * np.log(np.cos(np.radians(30))))), abs=1.5)


def test_exposure_and_clipping_follow_the_png():
    """A pixel twice as bright as white displays as white (L* 100, no chroma) at exposure 0, and
    one stop down shows its real colour: the measurement sees what the PNG shows."""
    colour = linear_image(np.array([[[50.0, 30.0, -20.0]]]))
    lab = beach_colour.displayed_lab(np.concatenate([colour, 2.0 + 0 * colour, colour * 2.0], 1), exposure=0.0)
    assert lab[0, 1, 0] == pytest.approx(100.0, abs=0.01) and np.hypot(*lab[0, 1, 1:]) < 0.5
    down = beach_colour.displayed_lab(colour * 2.0, exposure=-1.0)
    assert np.allclose(down[0, 0], [50.0, 30.0, -20.0], atol=0.8)


def test_masks_pick_regions_by_material_name():
    """Nacre is every material whose name holds "nacre"; the lens every "lens" one; the sunlit
    sand the brighter half of the sand."""
    names = ["sand", "nacre", "oyster-nacre", "lens", "lens-back", "frame"]
    material = np.array([[0, 0, 0, 0, 1, 2, 3, 4, 5, -1]])
    lab = np.zeros(material.shape + (3,))
    lab[0, :4, 0] = [40, 50, 70, 80]
    r = beach_colour.regions(material, names, lab)
    assert r["nacre"].sum() == 2 and r["lens"].sum() == 2 and r["sand (all)"].sum() == 4
    assert r["sand, sunlit (L* >= median)"].tolist()[0][:4] == [False, False, True, True]
    assert r["  oyster-nacre"].sum() == 1


def test_empty_region_is_nan_not_an_error():
    lab = np.zeros((2, 2, 3))
    s = beach_colour.colour_stats(lab, np.zeros((2, 2), dtype=bool))
    assert s.pixels == 0 and np.isnan(s.mean_l)


def test_sun_balance_takes_the_light_colour_out():
    """A grey reflector (0.2) lit by the scene's distant light has the light's chroma as displayed,
    and none once balanced to that light; the white is the light's RGB times scale at luminance 1."""
    from renderer.color.rgb import luminance
    from renderer.scene.description import CameraDesc, LightDesc, SceneDescription

    sky = LightDesc("infinite", {"L": (1.0, 1.0, 1.0), "scale": 1.0})
    sun = LightDesc("distant", {"L": (3.9, 2.7, 1.4), "scale": 2.0})
    scene = SceneDescription(camera=CameraDesc(np.eye(4)), lights=[sky, sun])
    white = beach_colour.sun_white(scene)
    assert float(luminance(white)) == pytest.approx(1.0) and white[0] / white[2] == pytest.approx(3.9 / 1.4)
    grey = np.full((1, 4, 3), 0.2) * white
    shown = beach_colour.displayed_lab(grey)[0, 0]
    balanced = beach_colour.displayed_lab(grey / white)[0, 0]
    assert np.hypot(*shown[1:]) > 15.0
    assert np.hypot(*balanced[1:]) < 0.8                     # 8-bit quantisation only
    assert balanced[0] == pytest.approx(shown[0], abs=3.0)   # the same lightness, near enough
    assert beach_colour.sun_white(SceneDescription(camera=CameraDesc(np.eye(4)), lights=[sky])) is None
