"""Textures are clamped to their parameter's declared range, as pbrt-v4 clamps (a reflectance
texture of 100 reflects like 1, one of -5 like 0): constants out of range are refused at load,
but a texture's values are only known where it is evaluated."""
from __future__ import annotations

import numpy as np
import pytest

from renderer.api import load_scene, render

SCENE = ('LookAt 0 0 -4  0 0 0  0 1 0\nCamera "perspective"\nWorldBegin\nLightSource "infinite"\n'
         'Texture "t" "spectrum" "constant" "rgb value" [{v}]\nMaterial "diffuse" "texture reflectance" "t"\n'
         'Shape "sphere"\n')


def _image(tmp_path, value: str) -> np.ndarray:
    path = tmp_path / f"s{abs(hash(value))}.pbrt"
    path.write_text(SCENE.format(v=value))
    return render(load_scene(path), spp=2, width=8, height=8, seed=3)


@pytest.mark.parametrize("out_of_range, clamped", [("100 100 100", "1 1 1"), ("-5 -5 -5", "0 0 0"),
                                                   ("2 0.5 -1", "1 0.5 0")])
def test_out_of_range_reflectance_textures_render_as_their_clamped_value(tmp_path, out_of_range, clamped):
    np.testing.assert_array_equal(_image(tmp_path, out_of_range), _image(tmp_path, clamped))


def test_in_range_textures_are_untouched(tmp_path):
    assert not np.array_equal(_image(tmp_path, "0.5 0.5 0.5"), _image(tmp_path, "1 1 1"))
