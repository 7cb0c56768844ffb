"""Every warning reaches the caller, and every unsupported type is reported at load time at once."""
from __future__ import annotations

import warnings
from pathlib import Path

import pytest

import renderer
from renderer.cli import EXIT_BAD_INPUT, EXIT_OK, main
from renderer.errors import RenderWarning, SceneErrors

HEAD = """LookAt 0 0 -4  0 0 0  0 1 0
Camera "perspective" "float fov" [40]
Film "rgb" "integer xresolution" [8] "integer yresolution" [6]
Sampler "independent" "integer pixelsamples" [1]
WorldBegin
"""


def scene(tmp_path: Path, body: str) -> Path:
    p = tmp_path / "s.pbrt"
    p.write_text(HEAD + body)
    return p


UNSUPPORTED = """LightSource "infinite" "rgb L" [1 1 1]
Material "measured"
Shape "sphere"
Texture "t" "float" "noise"
Material "hair"
Shape "disk"
"""


def test_every_unsupported_type_is_reported_at_once_with_its_line(tmp_path):
    path = scene(tmp_path, UNSUPPORTED)
    with pytest.raises(SceneErrors) as info:
        renderer.load_scene(path)
    lines = str(info.value).splitlines()
    assert len(lines) == 3, lines
    assert [int(ln.split(":")[1]) for ln in lines] == [7, 9, 10]
    assert "measured" in lines[0] and "unknown texture class \"noise\"" in lines[1] and "hair" in lines[2]


def test_cli_prints_every_unsupported_type(tmp_path, capsys):
    assert main([str(scene(tmp_path, UNSUPPORTED)), "-o", str(tmp_path / "o.exr"), "--quiet"]) == EXIT_BAD_INPUT
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.startswith("render: error:")]
    assert len(err) == 3 and all("s.pbrt:" in ln for ln in err)


def test_a_scene_without_lights_warns_the_python_caller(tmp_path):
    desc = renderer.load_scene(scene(tmp_path, 'Shape "sphere"\n'))
    stats = renderer.api.RenderStats()
    with pytest.warns(RenderWarning, match="no lights"):
        img = renderer.render(desc, spp=1, stats=stats)
    assert float(img.max()) == 0.0
    assert any("no lights" in w for w in stats.warnings)


def test_a_scene_without_lights_warns_on_the_command_line(tmp_path, capsys):
    with warnings.catch_warnings():
        warnings.simplefilter("error")      # the CLI prints warnings, it does not raise them
        code = main([str(scene(tmp_path, 'Shape "sphere" "float bogus" [1]\n')), "-o", str(tmp_path / "o.exr"),
                     "--quiet"])
    assert code == EXIT_OK
    err = capsys.readouterr().err
    assert "warning:" in err and "no lights" in err
    assert 's.pbrt:6: Shape "sphere": parameter "float bogus" is not supported' in err
