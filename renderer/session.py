"""A progressive render: passes of samples added into a film until a sample count, a time limit
or a stop request ends it. Its state (the film's sum and count plus what made it) can be saved
and restored, and a restored render continues bit for bit as if it had never stopped: a pass's
random numbers depend only on (seed, sample index, pixel), and every pass adds exactly one
sample per pixel, so the film's float64 sums are formed in the same order however a render is
split into runs."""
from __future__ import annotations

import os
import resource
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import asdict, dataclass, field
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
    """Warp runs a CPU launch on one thread; launching row bands from several threads uses every core."""
    return (os.cpu_count() or 1) if device == "cpu" else 1


def peak_memory_mb() -> float:
    """Peak resident memory of this process (Linux reports ru_maxrss in KiB)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


class RenderSession:
    """Upload once, then render passes on demand (``run``); ``state``/``restore`` checkpoint it."""

    def __init__(self, scene: SceneDescription, settings: RenderSettings, device: str = "cpu",
                 threads: int | None = None):
        import warp as wp

        from renderer.device.runtime import require_device
        from renderer.device.scene import upload
        from renderer.device.film import Film
        from renderer.integrators.path import integrator_kernel

        require_device(device)
        self.scene = scene
        self.settings = settings
        self.device = device
        self.ds = upload(scene, device, settings.width, settings.height, nee=settings.nee,
                         thin_film=settings.thin_film)
        W, H = self.ds.width, self.ds.height
        self.film = Film(W, H, device)
        self.kernel = integrator_kernel(self.ds.features)
        t0 = time.perf_counter()
        wp.load_module(self.kernel.module, device=device)
        self.stats = RenderStats(width=W, height=H, compile_seconds=time.perf_counter() - t0,
                                 warnings=list(dict.fromkeys(scene.warnings)))   # each once
        n_threads = max(1, min(threads or default_threads(device), H))
        self.bands = [b for b in np.array_split(np.arange(H), n_threads) if len(b)]
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

        def launch(band: np.ndarray) -> None:
            wp.launch(self.kernel, dim=len(band) * self.ds.width,
                      inputs=[self.ds.struct, s.seed, sample, int(band[0]), s.max_depth, s.rr_depth,
                              self.film.sum, self.film.bad, self.film.rays],
                      device=self.device)
            wp.synchronize_device(self.device)

        list(pool.map(launch, self.bands))

    def run(self, spp: int, time_limit: float | None = None, on_pass: Callable[["RenderSession"], None] | None = None,
            should_stop: Callable[[], bool] | None = None) -> RenderStats:
        """Render until the film holds ``spp`` samples per pixel, or until the pass that crosses
        ``time_limit`` seconds (of this call) ends, or ``should_stop()`` turns true after a pass.
        Ctrl-C raised inside a pass is caught after it: finished passes are kept."""
        if spp < 1:
            raise RenderError(f"spp must be at least 1, got {spp}")
        t0 = time.perf_counter()
        base_seconds = self.stats.seconds
        with ThreadPoolExecutor(max_workers=len(self.bands)) as pool:
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
        return {"sum": self.film.sum.numpy(), "spp": np.int64(self.film.spp), "bad": self.film.bad.numpy(),
                "rays": self.film.rays.numpy(), "seconds": np.float64(self.stats.seconds),
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
        self.film.bad.assign(wp.array(state["bad"], dtype=int, device=self.device))
        self.film.rays.assign(wp.array(state["rays"], dtype=wp.float64, device=self.device))
        self.film.spp = int(state["spp"])
        self.stats.seconds = float(state["seconds"])
        self._update_stats(self.stats.seconds)
