"""Checkpoints whose contents no render could hold, or that fail the SHA-256 written with them, are
refused by name before anything is resumed or written (issue 32)."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from renderer.cli import EXIT_BAD_INPUT, main
from renderer.device.film import MAX_SAMPLE, ONE, fixed_from_float
from renderer.errors import RenderError
from renderer.io.checkpoint import DIGEST, load_checkpoint, save_checkpoint
from test_cli import write_scene

SPP = 2


@pytest.fixture(scope="module")
def rendered(tmp_path_factory) -> tuple[Path, dict[str, np.ndarray]]:
    """A tiny scene and the checkpoint of a real 2-spp render of it."""
    tmp = tmp_path_factory.mktemp("ck")
    scene = write_scene(tmp)
    assert main([str(scene), "-o", str(tmp / "o.exr"), "--spp", str(SPP), "--checkpoint", str(tmp / "ck.npz"),
                 "--quiet"]) == 0
    return scene, load_checkpoint(tmp / "ck.npz")


def _resume_refused(tmp_path: Path, scene: Path, state: dict[str, np.ndarray], capsys, needle: str) -> None:
    ck, out = tmp_path / "edited.npz", tmp_path / "out.exr"
    save_checkpoint(ck, state)                 # a fresh, matching digest: only the contents are wrong
    capsys.readouterr()
    assert main([str(scene), "-o", str(out), "--spp", "4", "--resume", str(ck), "--quiet"]) == EXIT_BAD_INPUT
    err = capsys.readouterr().err
    assert str(ck) in err and needle in err, err
    assert not out.exists()


def test_a_real_checkpoint_carries_a_digest_and_resumes(tmp_path, rendered):
    scene, state = rendered
    assert DIGEST in state
    save_checkpoint(tmp_path / "ck.npz", state)
    assert main([str(scene), "-o", str(tmp_path / "o.exr"), "--spp", "4", "--resume", str(tmp_path / "ck.npz"),
                 "--quiet"]) == 0


def test_a_changed_byte_fails_the_digest(tmp_path, rendered):
    _, state = rendered
    sums = state["sum"].copy()
    sums[0, 0, 1] ^= 1                         # one bit of one fraction: still a plausible film
    path = tmp_path / "ck.npz"
    with open(path, "wb") as f:                # written with the old digest, as a damaged file would be
        np.savez(f, **{**state, "sum": sums})
    with pytest.raises(RenderError, match="do not match the SHA-256") as info:
        load_checkpoint(path)
    assert str(path) in str(info.value)


def _with_sums(state: dict[str, np.ndarray], edit) -> dict[str, np.ndarray]:
    sums = state["sum"].copy()
    edit(sums)
    return {**state, "sum": sums}


def _nan_as_int64(s: np.ndarray) -> None:
    with np.errstate(invalid="ignore"):
        s[3, 1, 0] = np.array([np.nan]).astype(np.int64)[0]   # what NaN written into int64 becomes


@pytest.mark.parametrize("edit, needle", [
    (_nan_as_int64, "film sums outside"),
    (lambda s: s.__setitem__((0, 0, 0), -1), "film sums outside"),
    (lambda s: s.__setitem__((0, 2, 0), SPP * int(MAX_SAMPLE) + 1), "film sums outside"),
    (lambda s: s.__setitem__((1, 0, 1), ONE), "fractions outside"),
    (lambda s: s.__setitem__((1, 0, 1), -5), "fractions outside"),
])
def test_impossible_sums_are_refused_by_name(tmp_path, capsys, rendered, edit, needle):
    scene, state = rendered
    _resume_refused(tmp_path, scene, _with_sums(state, edit), capsys, needle)


def test_more_dropped_samples_than_samples_is_refused(tmp_path, capsys, rendered):
    scene, state = rendered
    pixels = state["sum"].shape[0]
    _resume_refused(tmp_path, scene, {**state, "bad": np.array([pixels * SPP + 1], np.int32)}, capsys,
                    "dropped samples")


@pytest.mark.parametrize("value", [2.0 ** 63, 1e300, -1.0])
def test_float_sums_that_int64_cannot_hold_are_refused_not_wrapped(tmp_path, capsys, rendered, value):
    scene, state = rendered
    floats = np.zeros(state["sum"].shape[:2])          # an earlier version's (N, 3) float sums
    floats[0, 0] = value
    _resume_refused(tmp_path, scene, {**state, "sum": floats}, capsys, "float film sums must lie in [0, 2^63)")


def test_the_largest_float_sum_below_2_63_converts_exactly():
    below = np.nextafter(2.0 ** 63, 0.0)
    fixed = fixed_from_float(np.array([[below, 0.5, 0.0]]))
    assert int(fixed[0, 0, 0]) == int(below) > 0
    assert int(fixed[0, 1, 1]) == ONE // 2
