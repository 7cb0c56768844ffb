"""Ctrl-C on ``render --ray`` (a local Ray instance the command starts itself) cancels the tasks
in flight and writes the image and the checkpoint of the finished ranges, exit code 130."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from cluster_scenes import write_cluster_scene
from renderer.io.checkpoint import load_checkpoint
from renderer.io.images import read_exr
from renderer.sample_ranges import count, from_array

ROOT = Path(__file__).resolve().parents[2]
SPP = 4000


def test_sigint_writes_the_finished_ranges(tmp_path):
    pytest.importorskip("ray")
    scene = write_cluster_scene(tmp_path)
    out, ck = tmp_path / "out.exr", tmp_path / "ck.npz"
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    proc = subprocess.Popen([sys.executable, "-m", "renderer", str(scene), "-o", str(out), "--res", "96x64",
                             "--spp", str(SPP), "--ray", "--ray-workers", "2", "--ray-chunk", "8",
                             "--checkpoint", str(ck), "--checkpoint-every", "0", "--quiet"],
                            stderr=subprocess.PIPE, text=True, env=env, cwd=ROOT)
    deadline = time.monotonic() + 120
    while not ck.exists() and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.1)
    proc.send_signal(signal.SIGINT)
    err = proc.communicate(timeout=120)[1]
    assert proc.returncode == 130, err
    state = load_checkpoint(ck)
    ranges = from_array(state["ranges"])
    assert 0 < int(state["spp"]) == count(ranges) < SPP
    assert all((b - a) % 8 == 0 for a, b in ranges)          # whole tasks only, never part of one
    assert read_exr(out)[1]["spp"] == int(state["spp"])
    assert "stopped by SIGINT" in err
