"""The hostile-input fuzzer (issue 17): mutated scenes, files and flags each end either as a valid
input (loaded and uploaded, or rendered to a finite image) or as a clean refusal — one of our
errors with its location, exit code 2 and nothing written — never a traceback, a hang or a
runaway allocation.

CI runs a bounded, seeded number of cases (``FUZZ_EXAMPLES`` per test, default 60). A long run is
one command: ``make fuzz`` (``FUZZ_EXAMPLES=5000 FUZZ_RENDER=1``: valid scene mutants are also
rendered, 4x3 pixels at 1 spp). ``FUZZ_SEED`` picks another seeded sequence of cases."""
from __future__ import annotations

import io
import shutil
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, seed
from hypothesis import strategies as st

from harness import FUZZ, SEED, bounded, load_or_refuse
from mutations import ROOT, mutated_bytes, mutated_scene, render_flags, seed_scenes
from renderer.errors import RenderError

SEEDS = seed_scenes()


def stage(folder: Path, tmp: Path) -> Path:
    """A fresh case folder whose entries link to the seed's folder, so relative paths still resolve."""
    case = tmp / f"case{len(list(tmp.iterdir()))}"
    case.mkdir()
    for entry in folder.iterdir():
        if not entry.name.endswith(".pbrt"):
            (case / entry.name).symlink_to(entry)
    return case


@FUZZ
@seed(SEED)
@given(case=mutated_scene(SEEDS))
def test_mutated_scenes_load_or_are_refused_cleanly(tmp_path_factory, case):
    text, folder = case
    root = tmp_path_factory.mktemp("scene")
    path = stage(folder, root) / "scene.pbrt"
    path.write_text(text, errors="surrogateescape")
    with bounded():
        load_or_refuse(path)


def _ply_bytes(tmp: Path) -> bytes:
    from assets_gen.core.output import write_ply

    write_ply(tmp / "seed.ply", np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], float), np.array([[0, 1, 2]]))
    return (tmp / "seed.ply").read_bytes()


def _exr_bytes(tmp: Path) -> bytes:
    from renderer.io.images import write_exr

    write_exr(tmp / "seed.exr", np.full((4, 8, 3), 0.5, np.float32))
    return (tmp / "seed.exr").read_bytes()


def _png_bytes() -> bytes:
    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(np.full((4, 4, 3), 128, np.uint8)).save(buf, format="PNG")
    return buf.getvalue()


def _npy_bytes() -> bytes:
    buf = io.BytesIO()
    np.save(buf, np.stack([np.eye(4)] * 3))
    return buf.getvalue()


#: (file name, how a scene uses it) for each kind of file a scene reads.
FILE_USES = {
    "m.ply": 'Shape "plymesh" "string filename" "m.ply"',
    "env.exr": 'LightSource "infinite" "string filename" "env.exr"',
    "tex.png": 'Texture "t" "spectrum" "imagemap" "string filename" "tex.png"\nMaterial "diffuse" "texture reflectance" "t"\nShape "sphere"',
    "tex.exr": 'Texture "t" "float" "imagemap" "string filename" "tex.exr"\nMaterial "diffuse" "texture displacement" "t"\nShape "sphere"',
    "t.npy": 'ObjectBegin "o"\nShape "sphere"\nObjectEnd\nObjectInstance "o" "string transforms" "t.npy"',
}


@pytest.fixture(scope="module")
def seed_files(tmp_path_factory) -> dict[str, bytes]:
    tmp = tmp_path_factory.mktemp("seeds")
    exr = _exr_bytes(tmp)
    return {"m.ply": _ply_bytes(tmp), "env.exr": exr, "tex.png": _png_bytes(), "tex.exr": exr, "t.npy": _npy_bytes()}


@FUZZ
@seed(SEED)
@given(data=st.data())
def test_mutated_files_load_or_are_refused_cleanly(tmp_path_factory, seed_files, data):
    name = data.draw(st.sampled_from(sorted(FILE_USES)))
    blob = data.draw(mutated_bytes(seed_files[name]))
    case = tmp_path_factory.mktemp("file")
    (case / name).write_bytes(blob)
    light = "" if name == "env.exr" else 'LightSource "distant" "rgb L" [1 1 1]\n'
    (case / "scene.pbrt").write_text(f'Camera "perspective"\nWorldBegin\n{light}{FILE_USES[name]}\nShape "sphere"\n')
    with bounded():
        load_or_refuse(case / "scene.pbrt")


@pytest.fixture(scope="module")
def good_checkpoint(tmp_path_factory) -> bytes:
    from renderer.cli import main

    tmp = tmp_path_factory.mktemp("ck")
    scene = tmp / "s.pbrt"
    shutil.copy(ROOT / "tests" / "data" / "scenes" / "mini.pbrt", scene)
    (tmp / "sub").symlink_to(ROOT / "tests" / "data" / "scenes" / "sub")
    assert main([str(scene), "-o", str(tmp / "o.exr"), "--spp", "2", "--res", "4x3", "--quiet",
                 "--checkpoint", str(tmp / "ck.npz")]) == 0
    return (tmp / "ck.npz").read_bytes()


@FUZZ
@seed(SEED)
@given(data=st.data())
def test_mutated_checkpoints_load_or_are_refused_by_name(tmp_path_factory, good_checkpoint, data):
    from renderer.io.checkpoint import load_checkpoint

    path = tmp_path_factory.mktemp("ckf") / "ck.npz"
    path.write_bytes(data.draw(mutated_bytes(good_checkpoint)))
    with bounded():
        try:
            state = load_checkpoint(path)
        except RenderError as e:
            assert str(path) in str(e)
            return
        assert int(state["spp"]) >= 0


@FUZZ
@seed(SEED)
@given(flags=render_flags())
def test_hostile_flags_render_or_are_refused_in_one_line(tmp_path_factory, capsys, flags):
    from renderer.cli import EXIT_BAD_INPUT, EXIT_BAD_SAMPLES, EXIT_OK, main

    case = tmp_path_factory.mktemp("flags")
    scene = case / "s.pbrt"
    shutil.copy(ROOT / "tests" / "data" / "scenes" / "mini.pbrt", scene)
    (case / "sub").symlink_to(ROOT / "tests" / "data" / "scenes" / "sub")
    out = case / "out.exr"
    defaults = [] if "--res" in flags else ["--res", "4x3"]
    defaults += [] if "--spp" in flags else ["--spp", "1"]
    defaults += [] if "--time-limit" in flags else ["--time-limit", "20"]
    capsys.readouterr()
    with bounded():
        try:
            code = main([str(scene), "-o", str(out), "--quiet", *defaults, *flags])
        except SystemExit as e:         # argparse refuses a malformed value itself
            code = e.code
    err = capsys.readouterr().err
    assert "Traceback" not in err
    if code == EXIT_BAD_INPUT:
        assert not out.exists(), "a refusal left an image behind"
        errors = [ln for ln in err.splitlines() if ln.startswith(("render: error:", "usage:", "render: ")) and "error" in ln]
        assert errors, err
    else:
        assert code in (EXIT_OK, EXIT_BAD_SAMPLES), (code, err)
        from renderer.io.images import read_exr

        chans, _ = read_exr(out)
        assert all(np.all(np.isfinite(c)) for c in chans.values())


if __name__ == "__main__":     # the long run without make: python tests/fuzz/test_fuzz_inputs.py
    sys.exit(pytest.main([__file__, "-q"]))
