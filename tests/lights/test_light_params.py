"""Lights as plugins, host side (no Warp launch): each light module reads its own parameters from
a pbrt file or from Python keywords, every mistake is reported at load time with the file and
line, and each builds its table row from plain values."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from renderer.color.rgb import luminance
from renderer.errors import MissingFileError, SceneError, UnsupportedError
from renderer.lights import REGISTRY, area, build_light_table, distant, light, parameter_tables
from renderer.scene.description import CameraDesc, SceneDescription
from scene_files import HEAD, error_at, load


def test_distant_light_direction_points_to_the_light_through_the_ctm(tmp_path):
    s = load(tmp_path, HEAD + 'Rotate 90 1 0 0\nLightSource "distant" "point3 from" [0 0 5] "point3 to" [0 0 0]'
                              ' "rgb L" [1 2 3] "float scale" 2 "float angularradius" 0.5\n'
                              'LightSource "distant"\n')
    a, b = s.lights
    assert (a.kind, a.loc.line, a.values["angularradius"]) == ("distant", 4, 0.5)
    ea, eb = distant.entry(a, None), distant.entry(b, None)
    np.testing.assert_allclose(ea.vecs["direction"], [0, -1, 0], atol=1e-12)      # Rx(90) maps +z to -y
    np.testing.assert_allclose(ea.L, [2, 4, 6])
    assert ea.floats["cos_max"] == pytest.approx(np.cos(np.radians(0.5))) and ea.escapes
    np.testing.assert_allclose(eb.vecs["direction"], [0, 1, 0], atol=1e-12)       # default from - to = -z
    assert eb.floats["cos_max"] == 1.0 and not eb.escapes                          # a delta light: never hit


def test_infinite_light_defaults_and_image(tmp_path):
    (tmp_path / "sky.exr").write_bytes(b"")
    s = load(tmp_path, HEAD + 'LightSource "infinite"\nLightSource "infinite" "string filename" "sky.exr" '
                              '"float scale" 3 "float illuminance" 5\n')
    a, b = s.lights
    assert a.values == {"L": (1.0, 1.0, 1.0), "filename": None, "scale": 1.0, "illuminance": -1.0, "portal": None}
    assert b.values["filename"] == str(tmp_path / "sky.exr") and b.values["scale"] == 3.0
    assert b.values["illuminance"] == 5.0 and s.warnings == []
    error_at(tmp_path, HEAD + 'LightSource "infinite" "string filename" "gone.exr"', 3, "not found",
             kind=MissingFileError)
    error_at(tmp_path, HEAD + 'LightSource "infinite" "string filename" "sky.exr" "rgb L" [1 1 1]', 3, "not both")


@pytest.mark.parametrize("text, line, match", [
    ('LightSource "distant"\n  "float angularradius" [120]', 4, r'"angularradius" = 120.0 is outside \[0.0, 90.0\]'),
    ('LightSource "distant" "point3 from" [1 2 3] "point3 to" [1 2 3]', 3, "give no direction"),
    ('LightSource "point"\n\n  "point3 from" [1 2]', 5, '"from" .*needs a multiple of 3 values'),
    ('LightSource "spot" "float coneangle" [-5]', 3, '"coneangle" = -5.0 is outside'),
    ('LightSource "spot" "rgb I" [1 1]', 3, '"I" .*needs a multiple of 3 values'),
    ('AreaLightSource "diffuse"\n "bool twosided" [3]', 4, "twosided"),
    ('AreaLightSource "diffuse" "float scale" [-1]', 3, '"scale" = -1.0 is outside'),
])
def test_a_bad_light_parameter_is_located_at_load_time(tmp_path, text, line, match):
    error_at(tmp_path, HEAD + text, line, match)


@pytest.mark.parametrize("text, match", [
    ('LightSource "sunsky"', 'LightSource "sunsky" is not supported'),
    ('LightSource "nope"', 'LightSource "nope" is not supported .*"infinite", "distant", "point", "spot"'),
    ('LightSource "diffuse"', 'LightSource "diffuse" is not supported'),        # an area light, not a LightSource
    ('AreaLightSource "spot"', 'AreaLightSource "spot" is not supported .*"diffuse"'),
])
def test_unsupported_light_types_are_located(tmp_path, text, match):
    error_at(tmp_path, HEAD + text, 3, match, kind=UnsupportedError)


def test_area_light_values_and_no_lights_warning(tmp_path):
    s = load(tmp_path, HEAD + 'AttributeBegin\n  AreaLightSource "diffuse" "blackbody L" 3000 "bool twosided" true\n'
                              '  Shape "sphere"\nAttributeEnd\nShape "sphere"\n')
    lit, plain = s.shapes
    assert lit.area_light.kind == "diffuse" and lit.area_light.values["twosided"] and plain.area_light is None
    assert luminance(np.asarray(lit.area_light.values["L"])) == pytest.approx(1.0, rel=1e-3)   # as pbrt-v4
    assert not any("no lights" in w for w in s.warnings)
    dark = load(tmp_path, HEAD + 'Shape "sphere"\n')
    assert dark.warnings == [f"{tmp_path / 'scene.pbrt'}: scene has no lights: the image will be black"]


def test_python_lights_take_plain_values():
    sun = light("distant", L=(3, 3, 3), from_=(0, 1, 0), angularradius=0.27)
    assert sun.kind == "distant" and sun.values["from"] == (0.0, 1.0, 0.0) and sun.values["to"] == (0.0, 0.0, 1.0)
    assert sun.loc is None and np.array_equal(sun.light_to_world, np.eye(4))
    with pytest.raises(SceneError, match=r"unknown parameter\(s\) form"):
        light("distant", form=(0, 1, 0))                          # a typo must not vanish
    with pytest.raises(SceneError, match='"scale" must be a number'):
        light("point", scale="bright")
    with pytest.raises(SceneError, match="give no direction"):
        light("spot", from_=(1, 1, 1), to=(1, 1, 1))
    with pytest.raises(UnsupportedError, match='"sunsky" is not supported'):
        light("sunsky")
    with pytest.raises(MissingFileError):
        light("projection", filename=Path("/nonexistent/slide.exr"))
    with pytest.raises(MissingFileError):
        light("infinite", filename=Path("/nonexistent/sky.exr"))


def test_a_light_in_the_wrong_place_is_refused():
    desc = SceneDescription(camera=CameraDesc(np.eye(4)), lights=[light("diffuse")])
    with pytest.raises(SceneError, match='"diffuse" light belongs in ShapeDesc.area_light'):
        build_light_table(desc, np.zeros(0, np.int32), np.zeros((0, 4, 4)))


def test_area_light_ignores_zero_area_triangles():
    """An emissive mesh with degenerate triangles samples only the ones with area."""
    tris = np.array([[[0, 0, 0], [1, 0, 0], [0, 1, 0]],      # area 0.5
                     [[0, 0, 0], [1, 0, 0], [2, 0, 0]],      # collinear
                     [[0, 0, 0], [0, 0, 0], [0, 0, 0]]], float)
    e = area.entry(light("diffuse"), tris)
    assert e.ints["triangles"] == 1 and e.floats["area"] == pytest.approx(0.5)
    assert np.all(np.isfinite(e.f_data)) and e.f_data[-1] == 1.0 and len(e.v_data) == 3
    assert area.entry(light("diffuse"), tris[1:]) is None               # nothing left: no light


def test_every_light_declares_its_plugin_contract():
    for name, module in REGISTRY.items():
        assert module.NAME == name and module.DIRECTIVE in ("LightSource", "AreaLightSource")
        assert callable(module.entry) and callable(module.sample.func)
        assert module.PARAMS.docs_table().count("\n") == len(list(module.PARAMS)) + 1


def test_docs_show_the_declared_parameters():
    """docs/lights.md holds the tables the declarations generate (regenerate it when they change)."""
    docs = (Path(__file__).resolve().parents[2] / "docs" / "lights.md").read_text()
    assert parameter_tables() in docs
