"""The ``render`` command: outputs, metadata, and one-line located errors with exit code 2."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from renderer.cli import EXIT_BAD_INPUT, EXIT_OK, main
from renderer.io.images import read_exr, read_image

TINY = """LookAt 0 0 -4  0 0 0  0 1 0
Camera "perspective" "float fov" [40]
Film "rgb" "integer xresolution" [12] "integer yresolution" [8] "string filename" ["tiny.exr"]
Sampler "independent" "integer pixelsamples" [2]
WorldBegin
LightSource "infinite" "rgb L" [1 1 1]
{material}
Shape "sphere" "float radius" [1]
"""


def write_scene(tmp_path: Path, material: str = 'Material "diffuse" "rgb reflectance" [0.5 0.5 0.5]') -> Path:
    p = tmp_path / "tiny.pbrt"
    p.write_text(TINY.format(material=material))
    return p


def test_render_exr_with_metadata(tmp_path):
    out = tmp_path / "out.exr"
    assert main([str(write_scene(tmp_path)), "-o", str(out), "--spp", "3", "--seed", "5", "--quiet"]) == EXIT_OK
    chans, header = read_exr(out)
    assert chans["R"].shape == (8, 12)
    assert header["spp"] == 3 and header["seed"] == 5 and "renderTimeSeconds" in header
    assert 0.3 < chans["G"].mean() < 1.0


def test_render_png_with_resolution_override(tmp_path):
    out = tmp_path / "out.png"
    assert main([str(write_scene(tmp_path)), "-o", str(out), "--res", "10x6", "--quiet"]) == EXIT_OK
    assert read_image(out).shape == (6, 10, 3)
    assert not list(tmp_path.glob(".out*"))  # no temporary file left behind


@pytest.mark.parametrize("material,needle", [
    ('Material "diffuse" "rgb reflectance" [0.5 0.5', "tiny.pbrt:"),
    ('Material "plastic-unknown"', "tiny.pbrt:7"),
    ('Texture "t" "spectrum" "imagemap" "string filename" ["nope.png"]\nMaterial "diffuse" "texture reflectance" ["t"]',
     "nope.png"),
    ('Material "dielectric" "float eta" [-1]', "tiny.pbrt:7"),
])
def test_bad_scene_is_one_located_line_and_exit_2(tmp_path, capsys, material, needle):
    code = main([str(write_scene(tmp_path, material)), "-o", str(tmp_path / "x.png"), "--quiet"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == EXIT_BAD_INPUT
    assert needle in err[-1] and "Traceback" not in "\n".join(err)
    assert not (tmp_path / "x.png").exists()


def test_missing_scene_file(tmp_path, capsys):
    assert main([str(tmp_path / "missing.pbrt"), "--quiet"]) == EXIT_BAD_INPUT
    assert "missing.pbrt" in capsys.readouterr().err


def test_python_api_returns_linear_float32(tmp_path):
    import renderer

    scene = renderer.load_scene(write_scene(tmp_path))
    img = renderer.render(scene, spp=2, seed=0)
    assert img.dtype == np.float32 and img.shape == (8, 12, 3) and np.all(np.isfinite(img))


def test_sampler_option_selects_a_sampler_and_warns_like_pbrt(tmp_path, capsys):
    """--sampler replaces the scene's; zsobol with the scene's 2 pixel samples is fine, with 6
    (set by a sampler directive) it warns on stderr; an unknown name is refused by argparse."""
    scene = write_scene(tmp_path)
    a, b = tmp_path / "a.exr", tmp_path / "b.exr"
    assert main([str(scene), "-o", str(a), "--spp", "2", "--sampler", "zsobol", "--quiet"]) == EXIT_OK
    assert main([str(scene), "-o", str(b), "--spp", "2", "--sampler", "independent", "--quiet"]) == EXIT_OK
    assert "power-of-two" not in capsys.readouterr().err
    assert not np.array_equal(read_exr(a)[0]["G"], read_exr(b)[0]["G"])
    scene.write_text(scene.read_text().replace('"independent" "integer pixelsamples" [2]',
                                               '"zsobol" "integer pixelsamples" [6]'))
    assert main([str(scene), "-o", str(a), "--spp", "1", "--quiet"]) == EXIT_OK
    assert "power-of-two" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main([str(scene), "--sampler", "pmj"])
