"""The material and instance id AOVs label every pixel with the surface its centre sees."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from renderer.api import load_scene, open_session, settings_for
from renderer.integrators.aov import render_aovs

ROOT = Path(__file__).resolve().parents[2]
SCENE = """LookAt 0 0 -6  0 0 0  0 1 0
Camera "perspective" "float fov" [40]
Film "rgb" "integer xresolution" [24] "integer yresolution" [12]
WorldBegin
LightSource "infinite" "rgb L" [1 1 1]
Material "diffuse" "rgb reflectance" [0.5 0.5 0.5]
AttributeBegin
  Translate -1.1 0 0
  Material "conductor"
  Shape "sphere" "float radius" [0.9]
AttributeEnd
AttributeBegin
  Translate 1.1 0 0
  Material "dielectric"
  Shape "sphere" "float radius" [0.9]
AttributeEnd
"""


def test_material_and_instance_ids_label_each_region(tmp_path):
    path = tmp_path / "ids.pbrt"
    path.write_text(SCENE)
    desc = load_scene(path)
    settings = settings_for(desc)
    aov = render_aovs(open_session(desc, settings).ds, settings.seed)
    mat, inst = aov["material"][..., 0], aov["instance"][..., 0]
    kinds = [m.kind for m in desc.materials]
    # pbrt's x axis points left in the image here (the camera looks along +z from -z)
    left, right = mat[6, 8], mat[6, 15]
    assert {kinds[int(left)], kinds[int(right)]} == {"conductor", "dielectric"}
    assert mat[0, 0] == -1 and inst[0, 0] == -1                       # the corner sees the sky
    assert set(np.unique(mat)) == {-1.0, left, right}
    assert set(np.unique(inst)) == {-1.0, 0.0, 1.0}
    assert np.array_equal(mat == -1, inst == -1)                      # one background, two labels
    assert np.all(mat == np.round(mat)) and np.all(inst == np.round(inst))


def test_aovs_cut_into_row_chunks_over_threads_equal_one_launch(tmp_path):
    """The session launches the AOVs over its passes' row chunks from several threads; every
    pixel's numbers are its own, so the layers equal one launch over the whole film bit for bit."""
    path = tmp_path / "ids.pbrt"
    path.write_text(SCENE)
    desc = load_scene(path)
    settings = settings_for(desc)
    session = open_session(desc, settings, threads=2, aov=True)
    assert len(session.chunks) > 2
    whole = render_aovs(session.ds, settings.seed, 4)
    chunked = session.aovs(4)
    for name, layer in whole.items():
        assert np.array_equal(layer, chunked[name]), name
    assert whole["albedo"].max() > 0.1


@pytest.mark.parametrize("scene", ["films_walk.pbrt", "material_mix.pbrt", "media_cube.pbrt"])
def test_aov_steps_equal_the_one_kernel(scene):
    """What the wavefront launches (GPUs), the AOV pass in steps (a first-hit kernel, one per
    material kind's shader: thin films that walk apart; bump maps, mixes, media), adds the same
    numbers in the same order per pixel as the one kernel: equal bit for bit, over row chunks."""
    desc = load_scene(ROOT / "tests" / "data" / "pbrt" / scene)
    settings = settings_for(desc, width=24, height=16)
    session = open_session(desc, settings, threads=2, wavefront=True, aov=True)
    assert session.wavefront
    whole = render_aovs(session.ds, settings.seed, 4)
    steps = session.aovs(4)
    for name, layer in whole.items():
        assert np.array_equal(layer, steps[name]), name
    assert whole["albedo"].max() > 0.05 and (whole["material"] >= 0).any()
