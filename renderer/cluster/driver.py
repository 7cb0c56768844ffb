"""The driver of a cluster render: ship the scene once, hand out contiguous sample ranges as Ray
tasks, add the films they return, and offer the session's face (``run``, ``image``, ``state``,
``stats``, ``film.spp``) so the CLI and the API drive it as they drive a one-process render."""
from __future__ import annotations

import math
import time
from collections import deque
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from renderer.cluster.worker import Job, Part, render_range
from renderer.device.film import add_into, image_from_sums
from renderer.errors import RenderError
from renderer.film_state import FilmState
from renderer.sample_ranges import add_range, count, missing
from renderer.scene.description import SceneDescription
from renderer.session import RenderStats, peak_memory_mb
from renderer.settings import RenderSettings

#: Without ``chunk``, each task gets about this many seconds of samples (measured on the tasks
#: finished so far; the first ones get one sample per pixel): long enough that the per-task
#: overhead (benchmarks/cluster.py) is a few percent, short enough that a lost task costs little.
TARGET_TASK_SECONDS = 30.0
#: How often a task is retried after its worker died (killed, out of memory, node gone).
TASK_RETRIES = 5
#: Seconds between looks at the tasks in flight (the stop request and time limit are checked then).
POLL_SECONDS = 0.25


@dataclass(frozen=True)
class Cluster:
    """How to render on Ray: where (``address``: None or "local" starts a local instance, "auto"
    joins ``ray start``'s cluster, "ray://host:port" a remote one) and how the work is cut."""

    address: str | None = None
    chunk: int | None = None       # samples per pixel per task; None: about TARGET_TASK_SECONDS each
    workers: int | None = None     # tasks in flight; None: as many as the cluster has CPUs (GPUs) for
    task_cpus: int = 1             # CPU threads of each task
    task_gpus: float = 0.0         # GPUs of each task (> 0: the task renders on its GPU)


@dataclass
class HostFilm:
    """The merged film on the driver: fixed-point sums of the finished ranges, (N, 3) int64 each
    (whole and fraction apart and contiguous: merging in place then costs ~50 ms at 1080x1920)."""

    width: int
    height: int
    whole: np.ndarray
    fraction: np.ndarray
    spp: int = 0
    bad: int = 0
    rays: float = 0.0

    @property
    def sums(self) -> np.ndarray:
        """(N, 3, 2) as checkpoints hold them."""
        return np.stack([self.whole, self.fraction], axis=-1)

    def image(self) -> np.ndarray:
        return image_from_sums(self.whole, self.fraction, self.width, self.height, self.spp)


@dataclass
class WorkerStats:
    samples: int = 0               # pixel samples (spp x pixels)
    seconds: float = 0.0


class ClusterRender:
    """A render whose passes run as Ray tasks; see :mod:`renderer.cluster`."""

    def __init__(self, scene: SceneDescription, settings: RenderSettings, cluster: Cluster):
        from renderer.cluster.connect import connect
        from renderer.cluster.shipping import scene_files
        from renderer.io.fingerprint import scene_fingerprint

        self.ray = connect(cluster.address)
        self.scene, self.settings, self.cluster = scene, settings, cluster
        self.fingerprint = scene_fingerprint(scene)
        W, H = settings.width, settings.height
        self.film = HostFilm(W, H, np.zeros((W * H, 3), dtype=np.int64), np.zeros((W * H, 3), dtype=np.int64))
        self.ranges: list[tuple[int, int]] = []
        self.stats = RenderStats(width=W, height=H, warnings=list(dict.fromkeys(scene.warnings)))
        self.workers: dict[str, WorkerStats] = {}
        self.job = Job(self.fingerprint, settings, [self.ray.put(scene), self.ray.put(scene_files(scene))])
        self.task = self.ray.remote(render_range).options(max_retries=TASK_RETRIES, num_cpus=cluster.task_cpus,
                                                          num_gpus=cluster.task_gpus)
        self.width = cluster.workers or self._cluster_width()
        self.flight: dict[Any, tuple[int, int]] = {}     # the tasks in flight and their sample ranges

    def _cluster_width(self) -> int:
        """Tasks the cluster can run at once."""
        res = self.ray.cluster_resources()
        if self.cluster.task_gpus > 0:
            if res.get("GPU", 0) < self.cluster.task_gpus:   # Ray would keep such tasks pending for ever
                raise RenderError(f"tasks asking for {self.cluster.task_gpus:g} GPU each, but the Ray cluster has "
                                  f"{res.get('GPU', 0):g} GPUs (render on its CPUs with --device cpu)")
            return max(1, int(res.get("GPU", 0) / self.cluster.task_gpus))
        return max(1, int(res.get("CPU", 1) // self.cluster.task_cpus))

    @property
    def busy(self) -> int:
        """Tasks in flight (running, or queued by Ray for a free worker)."""
        return len(self.flight)

    def _chunk(self, left: int) -> int:
        if self.cluster.chunk:
            return self.cluster.chunk
        seconds = sum(w.seconds for w in self.workers.values())
        if not seconds:
            return 1
        pixels = self.film.width * self.film.height
        spp_per_second = sum(w.samples for w in self.workers.values()) / pixels / seconds   # one task's rate
        return max(1, min(round(spp_per_second * TARGET_TASK_SECONDS), math.ceil(left / self.width)))

    def _hand_out(self, todo: deque) -> None:
        while todo and self.busy < self.width:
            start, stop = todo.popleft()
            end = min(stop, start + self._chunk(count(list(todo)) + stop - start))
            if end < stop:
                todo.appendleft((end, stop))
            self.flight[self.task.remote(self.job, start, end)] = (start, end)

    def _collect(self, ref: Any) -> Part:
        start, stop = self.flight.pop(ref)
        try:
            return self.ray.get(ref)
        except self.ray.exceptions.RayError as e:
            self._cancel()                               # the render ends here: the other tasks are of no use
            if isinstance(e, self.ray.exceptions.RayTaskError):    # the task raised: its message, not Ray's
                raise RenderError(f"a worker failed on samples {start}..{stop - 1}: {getattr(e, 'cause', None) or e}"
                                  ) from None
            raise RenderError(f"samples {start}..{stop - 1} were lost after {TASK_RETRIES} retries: "
                              f"{str(e).splitlines()[0]}") from None

    def _merge(self, part: Part) -> None:
        f = self.film
        self.ranges = add_range(self.ranges, part.start, part.stop)
        add_into(f.whole, f.fraction, part.whole, part.fraction)
        f.spp, f.bad, f.rays = count(self.ranges), f.bad + part.bad, f.rays + part.rays
        w = self.workers.setdefault(part.worker, WorkerStats())
        w.samples += (part.stop - part.start) * f.width * f.height
        w.seconds += part.seconds
        self.stats.compile_seconds = max(self.stats.compile_seconds, part.setup_seconds)

    def _cancel(self) -> None:
        for ref in self.flight:
            self.ray.cancel(ref)
        self.flight.clear()

    def run(self, spp: int, time_limit: float | None = None, on_pass: Callable[["ClusterRender"], None] | None = None,
            should_stop: Callable[[], bool] | None = None) -> RenderStats:
        """Render the samples below ``spp`` not yet in the film. After ``time_limit`` seconds no
        more tasks are handed out (those in flight finish; the first round always goes out); ``should_stop()`` or Ctrl-C cancels
        the tasks in flight and keeps the finished ranges. ``on_pass`` runs after each merge."""
        if spp < 1:
            raise RenderError(f"spp must be at least 1, got {spp}")
        todo = deque(missing(self.ranges, spp))
        t0, base = time.perf_counter(), self.stats.seconds
        first_round = True              # handed out even past the time limit, as a pass is in one process
        try:
            while True:
                if first_round or time_limit is None or time.perf_counter() - t0 < time_limit:
                    self._hand_out(todo)
                    first_round = False
                if not self.flight:
                    break
                ready, _ = self.ray.wait(list(self.flight), num_returns=1, timeout=POLL_SECONDS)
                for ref in ready:
                    self._merge(self._collect(ref))
                    self._update_stats(base + time.perf_counter() - t0)
                    if on_pass:
                        on_pass(self)
                if should_stop and should_stop():
                    self.stats.interrupted = True
                    self._cancel()
                    break
        except KeyboardInterrupt:
            self.stats.interrupted = True
            self._cancel()
        self._update_stats(base + time.perf_counter() - t0)
        return self.stats

    def _update_stats(self, seconds: float) -> None:
        st = self.stats
        st.spp, st.seconds, st.bad_samples, st.rays = self.film.spp, seconds, self.film.bad, self.film.rays
        st.peak_memory_mb = peak_memory_mb()

    def image(self) -> np.ndarray:
        return self.film.image()

    def summary(self) -> list[str]:
        """One line per worker: its samples and rate while rendering (upload excluded)."""
        return [f"worker {name}: {w.samples / 1e6:.3f} M samples, {w.samples / max(w.seconds, 1e-9) / 1e6:.3f} "
                f"M samples/s" for name, w in sorted(self.workers.items())]

    # ---- checkpoints: the same state as a one-process session's ----------------------------

    def state(self) -> dict[str, np.ndarray]:
        f = self.film
        return FilmState(f.sums, self.ranges, f.bad, f.rays, self.stats.seconds).to_state(self.fingerprint,
                                                                                          self.settings)

    def restore(self, state: dict[str, np.ndarray], source: str = "checkpoint") -> None:
        f = self.film
        film = FilmState.from_state(state, self.fingerprint, self.settings, f.width * f.height, source)
        f.whole, f.fraction = np.ascontiguousarray(film.sums[..., 0]), np.ascontiguousarray(film.sums[..., 1])
        f.spp, f.bad, f.rays = film.spp, film.bad, film.rays
        self.ranges, self.stats.seconds = film.ranges, film.seconds
        self._update_stats(film.seconds)
