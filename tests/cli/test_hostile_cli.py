"""Hostile flags and files given to ``render`` (issue 17): each ends with exit code 2 and one line
naming the bad option or file, before any rendering, and writes nothing."""
from __future__ import annotations

import io
import struct
import subprocess
import sys
import zlib
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from renderer.cli import EXIT_BAD_INPUT, main
from renderer.errors import RenderError
from renderer.io.checkpoint import load_checkpoint
from renderer.io.images import read_image, write_exr
from renderer.settings import MAX_PIXELS, RenderSettings

SCENE = """Camera "perspective"
Film "rgb" "integer xresolution" [{w}] "integer yresolution" [{h}]
WorldBegin
{light}
Shape "sphere"
"""


def scene(tmp_path: Path, w: int = 8, h: int = 6, light: str = 'LightSource "infinite" "rgb L" [1 1 1]') -> Path:
    p = tmp_path / "s.pbrt"
    p.write_text(SCENE.format(w=w, h=h, light=light))
    return p


def refused(capsys, argv: list[str], needle: str) -> str:
    """``render argv`` exits 2 (argparse's exit included) with one error line containing ``needle``
    and no traceback."""
    try:
        code = main(argv)
    except SystemExit as e:
        code = e.code
    assert code == EXIT_BAD_INPUT
    err = capsys.readouterr().err
    lines = [ln for ln in err.splitlines() if ln.startswith("render: error:")]
    assert len(lines) == 1 and needle in lines[0], err
    assert "Traceback" not in err
    return lines[0]


@pytest.mark.parametrize("argv, needle", [
    (["--exposure", "2000"], "exposure must be between"),
    (["--exposure", "nan"], "exposure must be between"),
    (["--res", "40000x40000"], "more than the limit"),
    (["--res", "20000x5000"], "more than the limit"),
    (["--reference", "nope.exr"], "reference image not found: nope.exr"),
    (["--resume", "nope.npz"], "checkpoint not found: nope.npz"),
    (["--thin-film", "spectral:100000000"], "spectral"),
    (["--seed", "4294967296"], "seed must be a 32-bit integer"),
    (["--max-depth", "4294967296"], "max depth must be between"),
])
def test_bad_files_and_values_are_refused_before_rendering(tmp_path, capsys, argv, needle):
    out = tmp_path / "o.exr"
    refused(capsys, [str(scene(tmp_path)), "-o", str(out), "--quiet", *argv], needle)
    assert not out.exists()


def test_a_huge_film_in_the_scene_is_refused_with_its_line(tmp_path, capsys):
    line = refused(capsys, [str(scene(tmp_path, 1000000, 1000000)), "-o", str(tmp_path / "o.exr")],
                   "more than the limit")
    assert f"{tmp_path / 's.pbrt'}:2: Film:" in line


def test_a_1mb_scene_name_is_reported_shortened(tmp_path, capsys):
    line = refused(capsys, [str(tmp_path / ("a" * 1_000_000)), "-o", str(tmp_path / "o.exr")], "characters")
    assert len(line) < 1000


#: An empty zip archive: only its end-of-central-directory record.
EMPTY_ZIP = b"PK\x05\x06" + bytes(18)


def _good_state() -> dict[str, np.ndarray]:
    return {"sum": np.zeros((6, 3)), "spp": np.int64(4), "bad": np.zeros(6, np.int64), "rays": np.zeros(6),
            "seconds": np.float64(1.0), "fingerprint": np.str_("f"), "settings": np.str_("s")}


def _npz(state: dict[str, np.ndarray]) -> bytes:
    buf = io.BytesIO()
    np.savez(buf, **state)
    return buf.getvalue()


@pytest.mark.parametrize("data, needle", [
    (b"", "cannot read checkpoint"),
    (b"\x93NUMPY garbage" * 50, "cannot read checkpoint"),
    (_npz(_good_state())[:200], "cannot read checkpoint"),
    (EMPTY_ZIP, "'fingerprint' is missing"),
    (_npz({"x": np.zeros(3)}), "is missing"),
    (_npz({**_good_state(), "spp": np.int64(-5)}), "'spp' is out of range"),
    (_npz({**_good_state(), "spp": np.float64(1e18)}), "'spp' is not a single number"),
    (_npz({**_good_state(), "sum": np.full((6, 3), np.nan)}), "'sum' holds"),
    (_npz({**_good_state(), "settings": np.zeros(2)}), "'settings' is not a string"),
])
def test_truncated_foreign_or_edited_checkpoints_are_refused_by_name(tmp_path, data, needle):
    path = tmp_path / "ck.npz"
    path.write_bytes(data)
    with pytest.raises(RenderError, match=needle) as info:
        load_checkpoint(path)
    assert str(path) in str(info.value)


def test_a_good_checkpoint_loads(tmp_path):
    path = tmp_path / "ck.npz"
    path.write_bytes(_npz(_good_state()))
    assert int(load_checkpoint(path)["spp"]) == 4


@pytest.mark.parametrize("data", [b"", b"not an image at all" * 20])
@pytest.mark.parametrize("suffix", [".exr", ".png"])
def test_unreadable_images_raise_oserror_naming_the_file(tmp_path, data, suffix):
    path = tmp_path / f"bad{suffix}"
    path.write_bytes(data)
    with pytest.raises(OSError, match="cannot read image") as info:
        read_image(path)
    assert str(path) in str(info.value)


def test_a_garbage_environment_map_is_a_located_scene_error(tmp_path, capsys):
    (tmp_path / "env.exr").write_bytes(b"")
    p = scene(tmp_path, light='LightSource "infinite" "string filename" "env.exr"')
    out = tmp_path / "o.exr"
    line = refused(capsys, [str(p), "-o", str(out), "--quiet"], "cannot read image")
    assert f"{p}:4:" in line and "env.exr" in line
    assert not out.exists()


def test_resolution_limit_is_the_documented_bound():
    RenderSettings(width=8192, height=MAX_PIXELS // 8192, seed=0, max_depth=5)
    with pytest.raises(RenderError, match="more than the limit"):
        RenderSettings(width=8192, height=MAX_PIXELS // 8192 + 1, seed=0, max_depth=5)


def _png_header_only(width: int, height: int) -> bytes:
    """A PNG whose header claims ``width`` x ``height`` pixels and that holds no pixel data."""
    def chunk(kind: bytes, data: bytes) -> bytes:
        return len(data).to_bytes(4, "big") + kind + data + zlib.crc32(kind + data).to_bytes(4, "big")

    ihdr = width.to_bytes(4, "big") + height.to_bytes(4, "big") + bytes([8, 2, 0, 0, 0])
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IEND", b"")


def test_a_decompression_bomb_environment_map_is_a_located_scene_error(tmp_path, capsys):
    (tmp_path / "env.png").write_bytes(_png_header_only(100_000, 50_000))
    p = scene(tmp_path, light='LightSource "infinite" "string filename" "env.png"')
    line = refused(capsys, [str(p), "-o", str(tmp_path / "o.exr"), "--quiet"], "cannot read image")
    assert f"{p}:4:" in line and "env.png" in line


@pytest.mark.parametrize("argv, needle", [
    (["-o", "{tmp}/o.png", "--aov", "albedo"], "--aov layers need an .exr output"),
    (["-o", "{tmp}/file/o.exr"], "cannot write the output"),
    (["-o", "{tmp}/o.exr", "--checkpoint", "{tmp}/file/ck.npz"], "cannot write the checkpoint"),
    (["-o", "{tmp}/o.exr", "--checkpoint", "{tmp}"], "is a folder"),
    (["-o", "{tmp}/o.exr", "--error-log", "{tmp}/file/log.csv", "--reference", "{tmp}/ref.exr"],
     "cannot write the error log"),
])
def test_output_locations_are_checked_before_the_first_pass(tmp_path, capsys, argv, needle):
    (tmp_path / "file").write_text("a file, not a folder")
    write_exr(tmp_path / "ref.exr", np.zeros((6, 8, 3), np.float32))
    refused(capsys, [str(scene(tmp_path)), "--quiet", *(a.format(tmp=tmp_path) for a in argv)], needle)
    assert not (tmp_path / "o.exr").exists() and not (tmp_path / "o.png").exists()


def test_a_film_filename_of_another_format_says_where_it_came_from(tmp_path, capsys):
    p = tmp_path / "s.pbrt"
    p.write_text(SCENE.format(w=8, h=6, light="").replace('"integer xresolution"', '"string filename" "out.tiff" '
                                                                                  '"integer xresolution"'))
    refused(capsys, [str(p)], "out.tiff (the scene's Film \"filename\"")


def test_a_zero_time_limit_is_reported_as_the_time_limit(tmp_path, capsys):
    out = tmp_path / "o.exr"
    main([str(scene(tmp_path)), "-o", str(out), "--quiet", "--spp", "64", "--time-limit", "0"])
    assert "stopped by time limit" in capsys.readouterr().err and out.exists()


def test_only_our_own_messages_reach_stderr(tmp_path):
    """A fresh process (so colour-science is imported anew) that reads a blackbody colour, then refuses."""
    p = scene(tmp_path, light='LightSource "point" "blackbody I" [5500]')
    run = subprocess.run([sys.executable, "-m", "renderer.cli", str(p), "-o", str(tmp_path / "o.tiff")],
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == EXIT_BAD_INPUT
    assert run.stderr.splitlines() == [f"render: error: output must end in .exr or .png, got {tmp_path / 'o.tiff'}"]


def test_a_scene_too_big_for_the_memory_limit_is_refused_before_upload(tmp_path, capsys):
    p = scene(tmp_path, w=4000, h=4000)            # 16 M pixels: the film alone needs about 0.7 GiB
    line = refused(capsys, [str(p), "-o", str(tmp_path / "o.exr"), "--memory-limit", "0.5"], "GiB limit")
    assert str(p) in line and "needs about" in line
    assert not (tmp_path / "o.exr").exists()


@pytest.mark.parametrize("value", ["0", "-1", "nan", "inf", "lots"])
def test_memory_limit_must_be_a_positive_number(tmp_path, capsys, value):
    refused(capsys, [str(scene(tmp_path)), "-o", str(tmp_path / "o.exr"), "--memory-limit", value],
            "memory limit must be a positive number of GiB")


def _exr_claiming(path: Path, width: int, height: int) -> None:
    """A valid 4x4 EXR whose dataWindow is then rewritten to claim ``width`` x ``height`` pixels."""
    write_exr(path, np.zeros((4, 4, 3), np.float32))
    data = path.read_bytes()
    at = data.index(b"dataWindow\x00box2i\x00") + len(b"dataWindow\x00box2i\x00") + 4   # after the size field
    path.write_bytes(data[:at] + struct.pack("<4i", 0, 0, width - 1, height - 1) + data[at + 16:])


def test_an_environment_map_header_claiming_80000x40000_is_refused_by_file_and_line(tmp_path, capsys):
    _exr_claiming(tmp_path / "env.exr", 80_000, 40_000)
    p = scene(tmp_path, light='LightSource "infinite" "string filename" "env.exr"')
    line = refused(capsys, [str(p), "-o", str(tmp_path / "o.exr"), "--quiet"], "env.exr")
    assert f"{p}:4:" in line and "header claims" in line


def test_an_image_that_takes_the_scene_over_the_memory_limit_is_named_with_its_line(tmp_path, capsys):
    y, x = np.indices((1024, 2048))
    Image.fromarray(((x ^ y) & 255).astype(np.uint8)).convert("RGB").save(tmp_path / "env.png")
    p = scene(tmp_path, light='LightSource "infinite" "string filename" "env.png"')
    line = refused(capsys, [str(p), "-o", str(tmp_path / "o.exr"), "--quiet", "--memory-limit", "0.3"], "GiB limit")
    assert f"{p}:4:" in line and "environment image" in line and "env.png" in line and "2048x1024" in line
    assert not (tmp_path / "o.exr").exists()


def test_a_truncated_png_is_one_line_without_the_decoders_own_output(tmp_path):
    """libpng prints 'libpng error: ...' on fd 2 itself; the user sees only our located line."""
    def chunk(kind: bytes, data: bytes) -> bytes:
        return len(data).to_bytes(4, "big") + kind + data + zlib.crc32(kind + data).to_bytes(4, "big")

    ihdr = (4).to_bytes(4, "big") + (2).to_bytes(4, "big") + bytes([8, 2, 0, 0, 0])
    (tmp_path / "env.png").write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr)
                                       + chunk(b"IDAT", zlib.compress(b"\0" * 3)))
    p = scene(tmp_path, light='LightSource "infinite" "string filename" "env.png"')
    run = subprocess.run([sys.executable, "-m", "renderer", str(p), "-o", str(tmp_path / "o.exr"), "--quiet"],
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == EXIT_BAD_INPUT
    assert len(run.stderr.splitlines()) == 1, run.stderr
    assert run.stderr.startswith(f"render: error: {p}:4: environment image: cannot read image")
