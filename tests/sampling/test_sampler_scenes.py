"""Samplers in renders: every sampler is unbiased in the furnaces, the Sampler directive selects one
with pbrt-v4's parameters, and a non-power-of-two count warns where pbrt-v4 warns."""
from __future__ import annotations

import warnings

import numpy as np
import pytest

import renderer
from renderer.errors import RenderWarning, SceneError
from renderer.materials import material
from scenes_py import single_object_scene, sphere_mesh

ALL = ["independent", "stratified", "halton", "sobol", "paddedsobol", "zsobol"]


@pytest.mark.parametrize("sampler", ALL)
def test_white_furnace_is_one_for_every_sampler(sampler):
    """Albedo 1 in a sky of 1 with light sampling and MIS: the estimate has variance, its mean is 1."""
    mesh = sphere_mesh()
    mesh.normals = None
    desc = single_object_scene(material("diffuse", reflectance=(1.0, 1.0, 1.0)), mesh=mesh)
    img = renderer.render(desc, spp=16, sampler=sampler)
    assert abs(img.mean() - 1.0) < 0.01


@pytest.mark.parametrize("sampler", ALL)
def test_grey_furnace_and_glass_for_every_sampler(sampler):
    """A grey sphere returns its albedo; a smooth glass sphere returns the sky exactly."""
    desc = single_object_scene(material("diffuse", reflectance=(0.25, 0.5, 0.75)))
    img = renderer.render(desc, spp=16, sampler=sampler)
    np.testing.assert_allclose(centre(img).mean(axis=(0, 1)), [0.25, 0.5, 0.75], rtol=0.03)
    glass = single_object_scene(material("dielectric", eta=1.5))
    glass.integrator.max_depth = 64
    np.testing.assert_allclose(centre(renderer.render(glass, spp=4, sampler=sampler)), 1.0, atol=1e-5)


def centre(img: np.ndarray) -> np.ndarray:
    """The central pixels, which all see the sphere (the silhouette's grazing facets can lose paths)."""
    h, w, _ = img.shape
    return img[h // 4: 3 * h // 4, w // 4: 3 * w // 4]


SCENE = 'Sampler "{name}" {params}\nFilm "rgb" "integer xresolution" 8 "integer yresolution" 8\n' \
        'Camera "perspective"\nWorldBegin\nLightSource "infinite"\nShape "sphere"\n'


def load(tmp_path, name: str, params: str = ""):
    p = tmp_path / "s.pbrt"
    p.write_text(SCENE.format(name=name, params=params))
    return renderer.load_scene(p)


def test_sampler_directive_reads_pbrts_parameters(tmp_path):
    s = load(tmp_path, "stratified", '"integer xsamples" 2 "integer ysamples" 3 "bool jitter" false "integer seed" 5')
    assert (s.sampler.kind, s.sampler.spp, s.sampler.jitter, s.sampler.seed) == ("stratified", 6, False, 5)
    s = load(tmp_path, "halton", '"integer pixelsamples" 8 "string randomize" "owen"')
    assert (s.sampler.kind, s.sampler.spp, s.sampler.randomize) == ("halton", 8, "owen")
    p = tmp_path / "none.pbrt"
    p.write_text(SCENE.split("\n", 1)[1])
    assert renderer.load_scene(p).sampler.kind == "zsobol"       # pbrt-v4's default


def test_bad_randomize_is_an_error_at_its_line(tmp_path):
    with pytest.raises(SceneError, match="offers randomize") as info:
        load(tmp_path, "halton", '"string randomize" "fastowen"')
    assert info.value.loc.line == 1


def test_pmj02bn_warns_and_renders_with_zsobol(tmp_path):
    s = load(tmp_path, "pmj02bn")
    assert s.sampler.kind == "zsobol" and any("pmj02bn" in w for w in s.warnings)


@pytest.mark.parametrize("name, warns", [("zsobol", True), ("sobol", True), ("halton", False),
                                         ("paddedsobol", False)])
def test_non_power_of_two_samples_warn_like_pbrt(tmp_path, name, warns):
    s = load(tmp_path, name, '"integer pixelsamples" 6')
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        renderer.render(s, spp=1)
    ours = [w for w in caught if issubclass(w.category, RenderWarning) and "power-of-two" in str(w.message)]
    assert len(ours) == (1 if warns else 0)
