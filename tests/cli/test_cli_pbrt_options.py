"""pbrt-v4's command-line options: ``--cropwindow``, ``--pixelbounds`` (the region rendered, with
pbrt's precedence over the Film's), ``--quick`` and ``--write-partial-images``."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from renderer.cli import EXIT_BAD_INPUT, EXIT_OK, main
from renderer.io.images import read_exr

DATA = Path(__file__).parents[1] / "data" / "pbrt"


def rgb(path: Path) -> np.ndarray:
    ch, _ = read_exr(path)
    return np.stack([ch[c] for c in "RGB"], -1)


def run(tmp_path: Path, scene: str, *extra: str) -> np.ndarray:
    out = tmp_path / "out.exr"
    assert main([str(DATA / scene), "-o", str(out), "--spp", "2", "--seed", "3", "--quiet", *extra]) == EXIT_OK
    return rgb(out)


def test_command_line_crop_is_the_films_crop_bit_for_bit(tmp_path):
    """film_crop.pbrt is filter_box.pbrt with a Film crop window: the same pixels, the same samples."""
    film = run(tmp_path, "film_crop.pbrt")
    assert film.shape == (35, 32, 3)
    assert np.array_equal(run(tmp_path, "filter_box.pbrt", "--cropwindow", "0.2,0.7,0.35,0.9"), film)
    assert np.array_equal(run(tmp_path, "filter_box.pbrt", "--cropwindow", "0.2", "0.7", "0.35", "0.9"), film)
    assert np.array_equal(run(tmp_path, "filter_box.pbrt", "--pixelbounds", "13,45,23,58"), film)
    # written as pbrt-v4 writes a crop: the region's pixels placed in the full frame
    _, ours = read_exr(tmp_path / "out.exr")
    _, pbrt = read_exr(DATA / "film_crop.exr")
    for key in ("dataWindow", "displayWindow"):
        assert [c.tolist() for c in ours[key]] == [c.tolist() for c in pbrt[key]], key
    # pbrt: a command-line window overrides the Film's
    assert run(tmp_path, "film_crop.pbrt", "--pixelbounds", "0,64,0,64").shape == (64, 64, 3)


def test_quick_renders_a_quarter_of_the_resolution_at_one_sample(tmp_path):
    out = tmp_path / "q.exr"
    assert main([str(DATA / "filter_box.pbrt"), "-o", str(out), "--quick", "--quiet"]) == EXIT_OK
    ch, header = read_exr(out)
    assert ch["R"].shape == (16, 16) and header["spp"] == 1


def test_write_partial_images_keeps_the_output_written(tmp_path, monkeypatch):
    import renderer.cli as cli

    monkeypatch.setattr(cli, "PARTIAL_EVERY", 1e-9)
    writes = []
    real = cli.write_outputs
    monkeypatch.setattr(cli, "write_outputs", lambda *a: (writes.append(a[0]), real(*a)))
    out = tmp_path / "p.exr"
    assert main([str(DATA / "filter_box.pbrt"), "-o", str(out), "--spp", "3", "--quiet", "--write-partial-images",
                 "--res", "16x16"]) == EXIT_OK
    assert len(writes) >= 3          # after passes 1..3 (an interval of 1 ns) and the final image


@pytest.mark.parametrize("args, needle", [
    (["--cropwindow", "0.5,0.2,0,1"], "--cropwindow must be"),
    (["--cropwindow", "0,1,0"], "4 numbers"),
    (["--pixelbounds", "a,b,c,d"], "4 numbers"),
    (["--pixelbounds", "70,80,0,10"], "select no pixels"),
])
def test_bad_regions_are_one_line_and_exit_2(tmp_path, capsys, args, needle):
    assert main([str(DATA / "filter_box.pbrt"), "-o", str(tmp_path / "x.exr"), "--quiet", *args]) == EXIT_BAD_INPUT
    assert needle in capsys.readouterr().err
