"""A progressive render: passes of samples added into a film until a sample count, a time limit
or a stop request ends it. Its state (the film's sums and count, which sample indices they hold,
plus what made it) can be saved and restored, and a restored render continues bit for bit as if it
had never stopped: a pass's random numbers depend only on (seed, sample index, pixel), and the
film's fixed-point sums add exactly in any order (:mod:`renderer.device.film`), so neither how a
render is split into runs nor which process rendered which samples changes a bit. On the CPU a
pass is launched in chunks of a few rows that worker threads take on demand (some rows cost far
more than others); each row gets its one sample per pass from exactly one launch."""
from __future__ import annotations

import os
import resource
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from itertools import count
from typing import Callable, Iterable

import numpy as np

from renderer.errors import RenderError
from renderer.film_state import FilmState
from renderer.sample_ranges import Ranges, add_range, missing, samples
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
    """Upload once, then render passes on demand (``run``); ``state``/``restore`` checkpoint it.
    ``wavefront`` chooses the integrator (default: the wavefront on CUDA, the megakernel on the
    CPU); both give the same image, so it is not a setting a checkpoint records. ``aov``: the AOV
    kernel is compiled with the others, side by side, for :meth:`aovs` after the passes."""

    def __init__(self, scene: SceneDescription, settings: RenderSettings, device: str = "cpu",
                 threads: int | None = None, wavefront: bool | None = None, aov: bool = False):
        import warp as wp

        from renderer.device.runtime import require_device
        from renderer.device.scene import upload
        from renderer.device.film import Film
        from renderer.device.sampler import upload_sampler
        from renderer.integrators.kernels import render_kernels, use_wavefront
        from renderer.integrators.wavefront import Wavefront

        require_device(device)
        self.scene = scene
        self.settings = settings
        self.device = device
        self.ds = upload(scene, device, settings.width, settings.height, nee=settings.nee,
                         thin_film=settings.thin_film)
        W, H = self.ds.width, self.ds.height
        self.film = Film(W, H, device)
        self.sampler = upload_sampler(settings.sampler, W, H, device)
        independent = settings.sampler.name == "independent"
        self.wavefront = use_wavefront(device, wavefront)   # the same image either way
        kernels = render_kernels(self.ds.features, independent, aov, wavefront=self.wavefront)
        self.kernel = kernels.get("path")
        t0 = time.perf_counter()
        # one module per kernel, compiled side by side (Warp's codegen is locked, its compilers
        # run outside the GIL): a cold CUDA load of the wavefront takes its longest kernel's time
        wp.force_load(device=device, modules=[k.module for k in kernels.values()], max_workers=os.cpu_count() or 1)
        own = [w] if (w := settings.sampler.warning()) else []
        self.stats = RenderStats(width=W, height=H, compile_seconds=time.perf_counter() - t0,
                                 warnings=list(dict.fromkeys(scene.warnings + self.ds.warnings + own)))   # each once
        self.threads = max(1, min(threads or default_threads(device), H))
        self.chunks = row_chunks(H, self.threads)
        self.paths = Wavefront(kernels, independent, max(r for _, r in self.chunks) * W, self.threads, device) \
            if self.wavefront else None
        self._fingerprint: str | None = None
        self.ranges: Ranges = []      # the sample indices in the film

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

        def worker(slot: int) -> None:
            while (i := next(taken)) < len(self.chunks):
                first, rows = self.chunks[i]
                if self.paths is not None:
                    self.paths.launch(slot, self.ds.struct, self.sampler.params, s.seed, sample, first, rows,
                                      s.max_depth, s.rr_depth, self.film.sample, self.film.bad, self.film.rays)
                else:
                    wp.launch(self.kernel, dim=rows * self.ds.width,
                              inputs=[self.ds.struct, self.sampler.params, s.seed, sample, first, s.max_depth,
                                      s.rr_depth, self.film.sample, self.film.bad, self.film.rays],
                              device=self.device)
                self.film.accumulate(first, rows)
                wp.synchronize_device(self.device)

        for f in [pool.submit(worker, slot) for slot in range(self.threads)]:
            f.result()

    def run(self, spp: int, time_limit: float | None = None, on_pass: Callable[["RenderSession"], None] | None = None,
            should_stop: Callable[[], bool] | None = None) -> RenderStats:
        """Render until the film holds samples ``0 .. spp-1``, or until the pass that crosses
        ``time_limit`` seconds (of this call) ends, or ``should_stop()`` turns true after a pass.
        Ctrl-C raised inside a pass is caught after it: finished passes are kept."""
        if spp < 1:
            raise RenderError(f"spp must be at least 1, got {spp}")
        return self.run_samples(samples(missing(self.ranges, spp)), time_limit, on_pass, should_stop)

    def run_samples(self, indices: Iterable[int], time_limit: float | None = None,
                    on_pass: Callable[["RenderSession"], None] | None = None,
                    should_stop: Callable[[], bool] | None = None) -> RenderStats:
        """Add one pass per sample index (each not yet in the film), stopping as :meth:`run` does."""
        t0 = time.perf_counter()
        base_seconds = self.stats.seconds
        with ThreadPoolExecutor(max_workers=self.threads) as pool:
            try:
                for sample in indices:
                    self._pass(pool, sample)
                    self.ranges = add_range(self.ranges, sample, sample + 1)
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

    def clear(self) -> None:
        """Forget every sample: an empty film, as a cluster worker needs before each range."""
        self.film.clear()
        self.ranges = []
        self.stats.seconds = 0.0
        self._update_stats(0.0)

    def _update_stats(self, seconds: float) -> None:
        st = self.stats
        st.spp, st.seconds = self.film.spp, seconds
        st.bad_samples = self.film.bad_samples
        st.rays = self.film.ray_count
        st.peak_memory_mb = peak_memory_mb()

    def image(self) -> np.ndarray:
        """The image as pbrt-v4's film writes it (imaging ratio and white balance applied)."""
        from renderer.sensor import sensor_output

        return sensor_output(self.film.image(), self.scene.film, self.scene.camera)

    def aovs(self, n_samples: int = 16) -> dict[str, np.ndarray]:
        """The denoiser's guides and the id AOVs (:func:`renderer.integrators.aov.render_aovs`),
        launched over the passes' row chunks and threads."""
        from renderer.integrators.aov import render_aovs

        return render_aovs(self.ds, self.settings.seed, n_samples, self.chunks, self.threads, steps=self.wavefront)

    # ---- checkpoints ----------------------------------------------------------------------

    def state(self) -> dict[str, np.ndarray]:
        """Everything needed to continue: the film and what it was made from."""
        film = FilmState(self.film.sums(), self.ranges, self.film.bad_samples, self.film.ray_count, self.stats.seconds)
        return film.to_state(self.fingerprint, self.settings)

    def restore(self, state: dict[str, np.ndarray], source: str = "checkpoint") -> None:
        """Continue from ``state``; refuses one made by another scene or with other settings."""
        film = FilmState.from_state(state, self.fingerprint, self.settings, self.film.width * self.film.height, source)
        self.film.set_sums(film.sums)
        self.film.set_counts(film.bad, film.rays)
        self.film.spp, self.ranges = film.spp, film.ranges
        self.stats.seconds = film.seconds
        self._update_stats(self.stats.seconds)
