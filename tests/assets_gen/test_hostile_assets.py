"""assets-gen refuses bad options, input files, output folders and recipes with exit code 2 and
one line naming what is wrong, before any long computation, and leaves no output behind."""
from __future__ import annotations

import json

import numpy as np
import pytest

from assets_gen import cli

EXIT_BAD_INPUT = 2
JUNK = b"garbage\xff\x00not a file format"


def run(argv: list[str], capsys) -> tuple[int, str]:
    rc = cli.main(argv)
    err = capsys.readouterr().err.strip().splitlines()
    return rc, err[-1] if err else ""


@pytest.mark.parametrize("argv, needle", [
    (["umbrella", "--tilt-azimuth-deg", "nan"], "expected a finite number"),
    (["sky", "--azimuth-deg", "nan"], "expected a finite number"),
    (["dunes", "--dune-height", "inf"], "expected a finite number"),
    (["dunes", "--dune-height", "1e6"], "dune height must be at most"),
    (["dunes", "--smoothing-steps", "1000000000"], "smoothing steps must be 0..100"),
    (["sky", "--resolution", "8192"], "resolution must be 8..4096"),
    (["shell-height", "--bands", "1000000000"], "growth bands must be 1..16384"),
    (["shell-bump", "--ridges", "100000"], "ridges must be 1..16384"),
    (["dunes", "--seed", "-1"], "seed must be a non-negative integer"),
])
def test_out_of_range_options_are_refused_in_one_line(tmp_path, capsys, argv, needle):
    rc, line = run([*argv, "--out", str(tmp_path / "out")], capsys)
    assert rc == EXIT_BAD_INPUT
    assert line.startswith(f"assets-gen {argv[0]}: error: ") and needle in line
    assert not (tmp_path / "out").exists()


def test_the_grain_count_is_capped_at_the_renderers_instance_limit(tmp_path, capsys):
    surface = tmp_path / "s.ply"
    surface.write_bytes(b"ply\n")
    rc, line = run(["grains", "--surface", str(surface), "--count", "1000000000", "--out", str(tmp_path / "o")], capsys)
    assert rc == EXIT_BAD_INPUT and "grain count must be 1..16777216" in line


@pytest.mark.parametrize("argv, what", [
    (["ripples", "--dunes"], "heightfield"),
    (["grains", "--surface"], "surface mesh"),
    (["lens-thickness", "--mask"], "lens mask"),
])
def test_garbage_input_files_are_named(tmp_path, capsys, argv, what):
    junk = tmp_path / "junk.bin"
    junk.write_bytes(JUNK)
    rc, line = run([*argv, str(junk), "--out", str(tmp_path / "out")], capsys)
    assert rc == EXIT_BAD_INPUT
    assert f"cannot read {what} '{junk}'" in line
    assert not (tmp_path / "out").exists()


def _all_black_png(path) -> None:
    from PIL import Image

    Image.fromarray(np.zeros((16, 16), np.uint8)).save(path, format="PNG")


def _flat_exr(path) -> None:
    from renderer.io.images import write_exr

    write_exr(path, np.zeros((8, 8, 1), np.float32))      # a valid EXR, but not a dunes heightfield


@pytest.mark.parametrize("argv, make, needle", [
    (["ripples", "--dunes"], lambda p: p.write_bytes(b""), "cannot read heightfield"),
    (["ripples", "--dunes"], _flat_exr, "is not a dunes heightfield"),
    (["grains", "--surface"], lambda p: p.write_bytes(b""), "cannot read surface mesh"),
    (["lens-thickness", "--mask"], lambda p: p.write_bytes(b""), "cannot read lens mask"),
    (["lens-thickness", "--mask"], _all_black_png, "lens mask is empty"),
])
def test_a_refused_input_leaves_no_output_folder_nor_its_parents(tmp_path, capsys, argv, make, needle):
    given = tmp_path / "input"
    make(given)
    rc, line = run([*argv, str(given), "--out", str(tmp_path / "made" / "for" / "out")], capsys)
    assert rc == EXIT_BAD_INPUT and needle in line
    assert sorted(p.name for p in tmp_path.iterdir()) == ["input"]      # no folder, no staging left


@pytest.mark.parametrize("text, needle", [
    ('WorldBegin\nShape "sphere" "float radius" [ 1\n', 'unterminated "["'),
    ('Camera "nope"\nWorldBegin\n', 'unknown Camera "nope"'),
    ('WorldBegin\nShape "plymesh" "string filename" "missing.ply"\n', "PLY mesh not found"),
])
def test_grains_with_a_scene_that_fails_to_load_is_one_located_line(tmp_path, capsys, text, needle):
    import trimesh

    trimesh.creation.box().export(tmp_path / "box.ply")
    (tmp_path / "s.pbrt").write_text(text)
    rc, line = run(["grains", "--surface", str(tmp_path / "box.ply"), "--scene", str(tmp_path / "s.pbrt"),
                    "--count", "10", "--out", str(tmp_path / "out")], capsys)
    assert rc == EXIT_BAD_INPUT
    assert line.startswith("assets-gen grains: error: ") and f"{tmp_path / 's.pbrt'}:" in line and needle in line
    assert not (tmp_path / "out").exists()


def test_an_output_folder_that_is_a_file_is_refused(tmp_path, capsys):
    target = tmp_path / "afile"
    target.write_text("keep me")
    rc, line = run(["lens-thickness", "--resolution", "8", "--out", str(target)], capsys)
    assert rc == EXIT_BAD_INPUT and "cannot write into output folder" in line
    assert target.read_text() == "keep me"


@pytest.mark.parametrize("params, needle", [
    ({}, "not found"),                                              # no sky.json at all
    ({"sky.json": b"{not json"}, "cannot read sky description"),
    ({"sky.json": json.dumps({"params": {"elevation_deg": 30}}).encode()}, "it has no 'sun' entry"),
])
def test_a_corrupt_or_incomplete_sky_description_is_named(tmp_path, capsys, params, needle):
    sky = tmp_path / "sky"
    sky.mkdir()
    for name, data in params.items():
        (sky / name).write_bytes(data)
    (sky / "sky_latlong.exr").write_bytes(b"")
    rc, line = run(["sky-lights", "--sky", str(sky), "--out", str(tmp_path / "out")], capsys)
    assert rc == EXIT_BAD_INPUT and needle in line
    assert str(sky / "sky.json") in line               # the description is what is wrong, not the map
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("text, needle", [
    (b"\xff\xfe{}", "not UTF-8 text (byte 0)"),
    (b"[" * 100_000 + b"]" * 100_000, "not a usable JSON document"),
    (b'{"assets": [{"name": "a", "generator": "dunes", "out": "assets/a", "seed": ' + b"9" * 5000 + b"}]}",
     "not a usable JSON document"),
    (b'{"assets": [{"name": "a", "generator": "dunes", "out": "assets/a", "seed": "one"}]}',
     '"seed" must be a non-negative integer'),
    (b'{"assets": [{"name": "a", "generator": "dunes", "out": "assets/a", "params": {"spacing": [1, 2]}}]}',
     "spacing"),
])
def test_malformed_recipes_are_refused_by_file(tmp_path, capsys, text, needle):
    scene = tmp_path / "s.pbrt"
    scene.write_text("WorldBegin\n")
    (tmp_path / "s.recipe.json").write_bytes(text)
    rc, line = run(["recipe", str(scene), "--quick"], capsys)
    assert rc == EXIT_BAD_INPUT
    assert str(tmp_path / "s.recipe.json") in line and needle in line
    assert not (tmp_path / "assets").exists()
