"""What runs on a Ray worker: render one contiguous range of sample indices into an empty film
and return its exact fixed-point sums. The worker process keeps the last scene's uploaded session
(and so its loaded kernels) between tasks: the scene is fetched from the object store, written to
a temporary folder and uploaded only when a task names a scene it has not seen."""
from __future__ import annotations

import os
import socket
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from renderer.errors import RenderError
from renderer.settings import RenderSettings

if TYPE_CHECKING:
    from renderer.session import RenderSession

#: The session of the scene this worker rendered last, by its key (one kept: a scene's upload can
#: take gigabytes, and a driver renders one scene at a time).
_SESSIONS: dict[tuple, "RenderSession"] = {}


@dataclass(frozen=True)
class Job:
    """What every task of one render shares; ``shipped`` holds the object-store references of the
    description and its files, nested in a list so Ray fetches them only when a worker needs them."""

    key: str                       # the scene's fingerprint
    settings: RenderSettings
    shipped: list[Any]             # [ObjectRef of SceneDescription, ObjectRef of SceneFiles]


@dataclass(frozen=True)
class Part:
    """One finished range: its film sums and counts, and who rendered it how fast."""

    start: int
    stop: int
    whole: np.ndarray              # (N, 3) int64: the fixed-point sums, see renderer.device.film
    fraction: np.ndarray           # (N, 3) int64
    bad: int
    rays: float
    seconds: float                 # rendering only (upload and kernel load excluded)
    setup_seconds: float           # upload and kernel load when this task built the session, else 0
    worker: str                    # host:pid


def _device_and_threads() -> tuple[str, int]:
    """A GPU when Ray assigned one to this task (Ray sets CUDA_VISIBLE_DEVICES), else the CPU
    with as many threads as the task holds CPUs."""
    import ray

    if ray.get_gpu_ids():
        return "cuda:0", 1
    cpus = ray.get_runtime_context().get_assigned_resources().get("CPU", 1.0)
    return "cpu", max(1, int(cpus))


def _session(job: Job) -> tuple["RenderSession", float]:
    import ray

    from renderer.cluster.shipping import localised
    from renderer.session import RenderSession

    device, threads = _device_and_threads()
    key = (job.key, job.settings, device, threads)
    if key in _SESSIONS:
        return _SESSIONS[key], 0.0
    _SESSIONS.clear()
    t0 = time.perf_counter()
    desc, files = ray.get(job.shipped)
    with tempfile.TemporaryDirectory(prefix="summertime-scene-") as folder:   # read during the upload only
        local, originals = localised(desc, files, Path(folder))
        try:
            session = RenderSession(local, job.settings, device=device, threads=threads)
        except (RenderError, OSError) as e:   # name the driver's files, not this worker's copies
            message = str(e)
            for copy, original in originals.items():
                message = message.replace(copy, original)
            raise RenderError(f"on {socket.gethostname()}: {message}") from None
    _SESSIONS[key] = session
    return session, time.perf_counter() - t0


def render_range(job: Job, start: int, stop: int) -> Part:
    """Samples ``start .. stop-1`` of the render, from an empty film."""
    session, setup = _session(job)
    session.clear()
    t0 = time.perf_counter()
    session.run_samples(range(start, stop))
    if session.film.spp != stop - start:      # Ctrl-C reached the worker: never hand back a partial range
        raise KeyboardInterrupt
    film = session.film
    return Part(start, stop, film.whole.numpy(), film.fraction.numpy(), film.bad_samples, film.ray_count,
                time.perf_counter() - t0, setup, f"{socket.gethostname()}:{os.getpid()}")
