"""A shader split into its light sample (``light_<kind>``) and its BSDF sample (``shade_<kind>``) computes
the one kernel's image: both halves draw the vertex's numbers, take dispersion's wavelength and the
probe step's moved vertex as the whole does, and only the light half's shadow ray and the BSDF half's
path are kept. The wavefront splits only the kinds whose one kernel spills past 1 KB
(``split_shading``); here every shader of each scene is split, so the features those kinds do not
meet in the test scenes (media: the shadow ray's medium; a dispersive dielectric; the independent
sampler's stream) are checked against the megakernel too."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from renderer.api import load_scene, render
from renderer.device.scene import upload
from renderer.integrators import wavefront
from renderer.integrators.kernels import render_kernels
from renderer.session import RenderStats

ROOT = Path(__file__).resolve().parents[2]
PBRT = ROOT / "tests" / "data" / "pbrt"

#: (scene, sampler or None for the scene's, width, height, spp), as in test_wavefront: media (fog, interfaces,
#: inside glass), dispersion, the independent sampler, subsurface's probe step with bump maps, the walk's kernel.
SPLIT_CASES = [
    (ROOT / "scenes" / "demo.pbrt", "independent", 32, 18, 2),
    (PBRT / "dispersion.pbrt", "stratified", 24, 24, 2),
    (PBRT / "bumped_subsurface.pbrt", None, 32, 18, 2),
    (PBRT / "films_walk.pbrt", None, 32, 18, 2),
    (PBRT / "media_fog.pbrt", "zsobol", 24, 18, 2),
    (PBRT / "media_cube.pbrt", None, 36, 16, 2),
    (PBRT / "media_glass.pbrt", None, 24, 24, 2),
]


@pytest.fixture
def split_every_shader(monkeypatch) -> list[str]:
    """Splits every shader of a scene that samples lights; returns the names of the wavefront kernels
    built, so a test sees that the split kernels are the ones that ran."""
    built: list[str] = []
    whole = wavefront.wavefront_kernels

    def recorded(features, independent):
        kernels = whole(features, independent)
        built.extend(kernels)
        return kernels

    monkeypatch.setattr(wavefront, "split_shading", lambda features, shader: features.nee and len(features.lights) > 0)
    monkeypatch.setattr(wavefront, "wavefront_kernels", recorded)
    return built


def test_cases_meet_the_features():
    features = [upload(load_scene(c[0]), "cpu", 8, 8).features for c in SPLIT_CASES]
    for flag in ("media", "dispersion", "subsurface", "bump", "layered"):
        assert any(getattr(f, flag) for f in features), flag


@pytest.mark.parametrize("case", SPLIT_CASES, ids=[f"{c[0].stem}-{c[1] or 'scene'}" for c in SPLIT_CASES])
def test_split_shaders_image_equals_megakernel(case, split_every_shader):
    path, sampler, w, h, spp = case
    images, stats = [], []
    for wf in (False, True):
        stats.append(RenderStats())
        images.append(render(load_scene(path), spp=spp, width=w, height=h, sampler=sampler, threads=1, stats=stats[-1],
                             wavefront=wf))
    assert images[0].mean() > 0.0
    assert any(name.startswith("light_") for name in split_every_shader), split_every_shader
    assert np.array_equal(images[1], images[0])
    assert stats[1].rays == stats[0].rays and stats[1].bad_samples == stats[0].bad_samples


def test_split_kinds_by_rule():
    """Thin films (walking or not), Disney and the coated materials are split, diffuse is not; the
    demo's conductor, dielectric and diffuse are whole."""
    def shading(scene: str) -> list[str]:
        features = upload(load_scene(ROOT / "tests" / "data" / "pbrt" / scene), "cpu", 8, 8).features
        return [n for n in render_kernels(features, False, wavefront=True) if n.startswith(("light_", "shade_"))]

    assert shading("films_walk.pbrt") == ["shade_diffuse", "light_thinfilm", "shade_thinfilm", "light_thinfilm_walk",
                                          "shade_thinfilm_walk"]
    assert shading("bumped_subsurface.pbrt") == ["shade_diffuse", "light_disney", "shade_disney"]
    assert shading("coatedconductor.pbrt") == ["light_coatedconductor", "shade_coatedconductor", "shade_diffuse"]
    demo = upload(load_scene(ROOT / "scenes" / "demo.pbrt"), "cpu", 8, 8).features
    assert not any(n.startswith("light_") for n in render_kernels(demo, False, wavefront=True))
