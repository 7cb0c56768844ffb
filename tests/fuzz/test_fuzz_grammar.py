"""The grammar-aware fuzzer (issue 32): well-formed scenes with hostile values, image and mesh files
whose headers lie, and checkpoints holding what no render could, each ending as a valid input or
a clean refusal that names its file, within the per-case time and memory bounds.

The seeded count and ``make fuzz``'s long run are shared with test_fuzz_inputs.py
(``FUZZ_EXAMPLES``, ``FUZZ_SEED``, ``FUZZ_RENDER``). With ``-s``, each test prints how its cases
ended (refused, uploaded, rendered, resumed), so a run says how many reached the device."""
from __future__ import annotations

import shutil
from collections import Counter
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, seed
from hypothesis import strategies as st

from grammar import grammar_scene, hostile_state, lying_files
from harness import FUZZ, SEED, bounded, load_or_refuse
from mutations import ROOT
from renderer.errors import RenderError

OUTCOMES: dict[str, Counter] = {}


@pytest.fixture(scope="module", autouse=True)
def tally():
    """Print each test's outcomes at the end of the module (seen with -s)."""
    yield
    for test, counts in OUTCOMES.items():
        print(f"\n{test} (seed {SEED}): {sum(counts.values())} cases, " + ", ".join(
            f"{k} {v}" for k, v in sorted(counts.items())))


def _count(test: str, outcome: str) -> None:
    OUTCOMES.setdefault(test, Counter())[outcome] += 1


@FUZZ
@seed(SEED)
@given(data=st.data())
def test_grammar_scenes_with_lying_files_load_or_are_refused_cleanly(tmp_path_factory, data):
    case = tmp_path_factory.mktemp("grammar")
    for name, blob in data.draw(lying_files(case)).items():
        (case / name).write_bytes(blob)
    (case / "scene.pbrt").write_text(data.draw(grammar_scene()))
    with bounded():
        _count("grammar scenes", load_or_refuse(case / "scene.pbrt"))


@pytest.fixture(scope="module")
def checkpoint(tmp_path_factory) -> tuple[Path, dict[str, np.ndarray]]:
    """The mini scene and the checkpoint of a real 2-spp render of it at 4x3."""
    from renderer.cli import main
    from renderer.io.checkpoint import load_checkpoint

    tmp = tmp_path_factory.mktemp("ck")
    shutil.copy(ROOT / "tests" / "data" / "scenes" / "mini.pbrt", tmp / "s.pbrt")
    (tmp / "sub").symlink_to(ROOT / "tests" / "data" / "scenes" / "sub")
    assert main([str(tmp / "s.pbrt"), "-o", str(tmp / "o.exr"), "--spp", "2", "--res", "4x3", "--quiet",
                 "--checkpoint", str(tmp / "ck.npz")]) == 0
    return tmp / "s.pbrt", load_checkpoint(tmp / "ck.npz")


@FUZZ
@seed(SEED)
@given(data=st.data())
def test_checkpoints_holding_impossible_values_resume_sanely_or_are_refused_by_name(tmp_path_factory, checkpoint,
                                                                                    data):
    """Resumed, a checkpoint renders on to a finite, non-negative image; else it is refused with the
    file's name (whether or not its digest was rewritten to match)."""
    from renderer.api import load_scene, open_session, settings_for
    from renderer.io.checkpoint import save_checkpoint

    scene, state = checkpoint
    path = tmp_path_factory.mktemp("ckf") / "ck.npz"
    edited = data.draw(hostile_state(state))
    if data.draw(st.booleans()):
        save_checkpoint(path, edited)              # a digest that matches the edit
    else:
        with open(path, "wb") as f:                # the original digest, or none: as a damaged file
            np.savez(f, **{**edited, **({"sha256": state["sha256"]} if data.draw(st.booleans()) else {})})
    desc = load_scene(scene)
    with bounded():
        try:
            session = open_session(desc, settings_for(desc, width=4, height=3), resume=path)
        except RenderError as e:
            assert str(path) in str(e)
            _count("checkpoints", "refused")
            return
        spp = session.film.spp
        session.run(spp + 1)           # fills the sample indices below spp + 1 that the ranges lack
        img = session.image()
        assert np.all(np.isfinite(img)) and np.all(img >= 0) and session.film.spp > spp
        _count("checkpoints", "resumed")
