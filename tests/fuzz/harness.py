"""What every fuzz test shares: the seeded case budget, the per-case time and memory bounds, and
what counts as a clean outcome for a scene."""
from __future__ import annotations

import os
import resource
import signal
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator

import numpy as np
from hypothesis import HealthCheck, settings

from renderer.errors import RenderError

EXAMPLES = int(os.environ.get("FUZZ_EXAMPLES", "60"))
RENDER = os.environ.get("FUZZ_RENDER") == "1"
SEED = int(os.environ.get("FUZZ_SEED", "0"))
CASE_SECONDS = 60            # a case running longer than this is a hang
CASE_MEMORY_MB = 4096        # how far one case may raise the process's peak resident memory
FUZZ = settings(max_examples=EXAMPLES, deadline=None, database=None, derandomize=False,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture,
                                       HealthCheck.data_too_large])


class Hang(Exception):
    """A case ran past CASE_SECONDS."""


@contextmanager
def bounded() -> Iterator[None]:
    """Fail a case that hangs (SIGALRM) or whose peak memory passes the limit."""
    def alarm(*_):
        raise Hang(f"case ran longer than {CASE_SECONDS} s")

    before_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    old = signal.signal(signal.SIGALRM, alarm)
    signal.alarm(CASE_SECONDS)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)
    grown_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024 - before_mb
    assert grown_mb < CASE_MEMORY_MB, f"the case raised peak memory by {grown_mb:.0f} MB"


def load_or_refuse(path: Path) -> str:
    """Valid: loaded and uploaded (and with FUZZ_RENDER, rendered finite). Refused: a RenderError
    (SceneError and its kinds) that names a file, or an OSError naming the image it could not read.
    Anything else propagates and fails the case. Returns which: "refused", "uploaded", "rendered"."""
    from renderer.api import load_scene, render
    from renderer.device.scene import upload

    try:
        desc = load_scene(path)
        upload(desc, "cpu", width=4, height=3)
    except RenderError as e:
        assert str(e).strip() and "Traceback" not in str(e)
        return "refused"
    if not RENDER:
        return "uploaded"
    img = render(desc, spp=1, device="cpu", seed=1, width=4, height=3)
    assert np.all(np.isfinite(img))
    return "rendered"
