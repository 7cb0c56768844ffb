"""A progressive render: passes of samples added into a film until a sample count, a time limit
or a stop request ends it. Its state (the film's sum and count plus what made it) can be saved
and restored, and a restored render continues bit for bit as if it had never stopped: a pass's
random numbers depend only on (seed, sample index, pixel), and every pass adds exactly one
sample per pixel, so the film's float64 sums are formed in the same order however a render is
split into runs. On the CPU a pass is launched in chunks of a few rows that worker threads take on
demand (some rows cost far more than others), and each row still gets its one sample per pass
from exactly one launch, so how rows are shared out never changes the film."""
from __future__ import annotations

import os
import resource
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import asdict, dataclass, field
from itertools import count
from typing import Callable

import numpy as np

from renderer.errors import RenderError
from renderer.scene.description import SceneDescription
from renderer.settings import RenderSettings


@dataclass
class RenderStats:
    """What a render did and how fast, for the CLI's summary line and the EXR header."""

    spp: int = 0
    seconds: float = 0.0
    compile_seconds: float = 0.0
    bad_samples: int = 0
    rays: float = 0.0
    width: int = 0
    height: int = 0
    interrupted: bool = False
    peak_memory_mb: float = 0.0
    warnings: list[str] = field(default_factory=list)     # the scene's, each once: the CLI prints them

    @property
    def samples_per_second(self) -> float:
        return self.spp * self.width * self.height / max(self.seconds, 1e-9)

    @property
    def rays_per_second(self) -> float:
        return self.rays / max(self.seconds, 1e-9)

    def header(self) -> dict[str, float | int]:
        """The numbers that go into an EXR header."""
        return {"spp": self.spp, "renderTimeSeconds": round(self.seconds, 3),
                "samplesPerSecond": round(self.samples_per_second, 1), "raysPerSecond": round(self.rays_per_second, 1),
                "peakMemoryMB": round(self.peak_memory_mb, 1), "droppedSamples": self.bad_samples}


def default_threads(device: str) -> int:
    """Warp runs a CPU launch on one thread; launching row chunks from several threads uses every core."""
    return (os.cpu_count() or 1) if device == "cpu" else 1


def peak_memory_mb() -> float:
    """Peak resident memory of this process (Linux reports ru_maxrss in KiB)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


#: Chunks per thread and pass: enough that a thread finishing its cheap rows takes more, few
#: enough that the per-launch overhead stays small.
CHUNKS_PER_THREAD = 16


def row_chunks(height: int, threads: int) -> list[tuple[int, int]]:
    """(first row, row count) of the chunks one pass is launched in; one chunk without threads."""
    if threads <= 1:
        return [(0, height)]
    size = max(1, -(-height // (threads * CHUNKS_PER_THREAD)))
    return [(r, min(size, height - r)) for r in range(0, height, size)]


class RenderSession:
    """Upload once, then render passes on demand (``run``); ``state``/``restore`` checkpoint it."""

    def __init__(self, scene: SceneDescription, settings: RenderSettings, device: str = "cpu",
                 threads: int | None = None):
        import warp as wp

        from renderer.device.runtime import require_device
        from renderer.device.scene import upload
        from renderer.device.film import Film
        from renderer.device.sampler import upload_sampler
        from renderer.integrators.path import integrator_kernel

        require_device(device)
        self.scene = scene
        self.settings = settings
        self.device = device
        self.ds = upload(scene, device, settings.width, settings.height, nee=settings.nee,
                         thin_film=settings.thin_film)
        W, H = self.ds.width, self.ds.height
        self.film = Film(W, H, device)
        self.sampler = upload_sampler(settings.sampler, W, H, device)
        self.kernel = integrator_kernel(self.ds.features, settings.sampler.name == "independent")
        t0 = time.perf_counter()
        wp.load_module(self.kernel.module, device=device)
        own = [w] if (w := settings.sampler.warning()) else []
        self.stats = RenderStats(width=W, height=H, compile_seconds=time.perf_counter() - t0,
                                 warnings=list(dict.fromkeys(scene.warnings + own)))   # each once
        self.threads = max(1, min(threads or default_threads(device), H))
        self.chunks = row_chunks(H, self.threads)
        self._fingerprint: str | None = None

    @property
    def fingerprint(self) -> str:
        if self._fingerprint is None:
            from renderer.io.fingerprint import scene_fingerprint

            self._fingerprint = scene_fingerprint(self.scene)
        return self._fingerprint

    def _pass(self, pool: ThreadPoolExecutor, sample: int) -> None:
        import warp as wp

        s = self.settings
        taken = count()   # the next chunk; next() on it is atomic under the GIL

        def worker() -> None:
            while (i := next(taken)) < len(self.chunks):
                first, rows = self.chunks[i]
                wp.launch(self.kernel, dim=rows * self.ds.width,
                          inputs=[self.ds.struct, self.sampler.params, s.seed, sample, first, s.max_depth, s.rr_depth,
                                  self.film.sum, self.film.bad, self.film.rays],
                          device=self.device)
                wp.synchronize_device(self.device)

        for f in [pool.submit(worker) for _ in range(self.threads)]:
            f.result()

    def run(self, spp: int, time_limit: float | None = None, on_pass: Callable[["RenderSession"], None] | None = None,
            should_stop: Callable[[], bool] | None = None) -> RenderStats:
        """Render until the film holds ``spp`` samples per pixel, or until the pass that crosses
        ``time_limit`` seconds (of this call) ends, or ``should_stop()`` turns true after a pass.
        Ctrl-C raised inside a pass is caught after it: finished passes are kept."""
        if spp < 1:
            raise RenderError(f"spp must be at least 1, got {spp}")
        t0 = time.perf_counter()
        base_seconds = self.stats.seconds
        with ThreadPoolExecutor(max_workers=self.threads) as pool:
            try:
                while self.film.spp < spp:
                    self._pass(pool, self.film.spp)
                    self.film.spp += 1
                    self._update_stats(base_seconds + time.perf_counter() - t0)
                    if on_pass:
                        on_pass(self)
                    if time_limit is not None and time.perf_counter() - t0 >= time_limit:
                        break
                    if should_stop and should_stop():
                        self.stats.interrupted = True
                        break
            except KeyboardInterrupt:
                self.stats.interrupted = True
        self._update_stats(base_seconds + time.perf_counter() - t0)
        return self.stats

    def _update_stats(self, seconds: float) -> None:
        st = self.stats
        st.spp, st.seconds = self.film.spp, seconds
        st.bad_samples = self.film.bad_samples
        st.rays = self.film.ray_count
        st.peak_memory_mb = peak_memory_mb()

    def image(self) -> np.ndarray:
        return self.film.image()

    # ---- checkpoints ----------------------------------------------------------------------

    def state(self) -> dict[str, np.ndarray]:
        """Everything needed to continue: the film and what it was made from."""
        return {"sum": self.film.sum.numpy(), "spp": np.int64(self.film.spp),
                "bad": np.array([self.film.bad_samples], dtype=np.int32),
                "rays": np.array([self.film.ray_count]), "seconds": np.float64(self.stats.seconds),
                "fingerprint": np.str_(self.fingerprint),
                "settings": np.str_(repr(sorted(asdict(self.settings).items())))}

    def restore(self, state: dict[str, np.ndarray], source: str = "checkpoint") -> None:
        """Continue from ``state``; refuses one made by another scene or with other settings."""
        import warp as wp

        mine = repr(sorted(asdict(self.settings).items()))
        if str(state["fingerprint"]) != self.fingerprint:
            raise RenderError(f"{source} was made from a different scene (content differs); refusing to resume")
        if str(state["settings"]) != mine:
            raise RenderError(f"{source} was made with other settings {state['settings']}, not {mine}; "
                              "refusing to resume")
        self.film.sum.assign(wp.array(state["sum"], dtype=wp.vec3d, device=self.device))
        self.film.set_counts(int(np.sum(state["bad"])), float(np.sum(state["rays"])))
        self.film.spp = int(state["spp"])
        self.stats.seconds = float(state["seconds"])
        self._update_stats(self.stats.seconds)
