"""The Python API: ``load_scene`` (parse and build, no device work) and ``render``."""
from __future__ import annotations

import os
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from renderer.errors import RenderError
from renderer.scene.description import SceneDescription


def load_scene(path: str | Path) -> SceneDescription:
    """Parse a pbrt-v4 file (and its includes) into a :class:`SceneDescription`."""
    from renderer.scene import load_description

    return load_description(path)


def init_warp(quiet: bool = True) -> None:
    """Initialise Warp once, with kernels cached under $WARP_CACHE_PATH when it is set."""
    import warp as wp

    cache = os.environ.get("WARP_CACHE_PATH")
    if cache:
        wp.config.kernel_cache_dir = cache
    wp.config.quiet = quiet
    wp.init()


@dataclass
class RenderStats:
    spp: int = 0
    seconds: float = 0.0
    compile_seconds: float = 0.0
    bad_samples: int = 0
    width: int = 0
    height: int = 0
    warnings: list[str] = field(default_factory=list)
    interrupted: bool = False

    @property
    def samples_per_second(self) -> float:
        return self.spp * self.width * self.height / max(self.seconds, 1e-9)


def default_threads(device: str) -> int:
    """Warp runs a CPU launch on one thread; launching row bands from several threads uses every core."""
    return (os.cpu_count() or 1) if device == "cpu" else 1


def render(scene: SceneDescription, spp: int | None = None, device: str = "cpu", seed: int | None = None,
           width: int | None = None, height: int | None = None, max_depth: int | None = None,
           nee: bool = True, threads: int | None = None,
           progress: Callable[[int, int], None] | None = None, stats: RenderStats | None = None) -> np.ndarray:
    """Render and return linear RGB as float32 (H, W, 3). ``spp``, ``seed``, ``max_depth`` and the
    resolution default to the scene file's values. Progress is reported after every pass."""
    import warp as wp

    from renderer.device_scene import upload
    from renderer.film import Film
    from renderer.integrator import integrator_kernel

    init_warp()
    spp = scene.sampler.spp if spp is None else int(spp)
    seed = scene.sampler.seed if seed is None else int(seed)
    max_depth = scene.integrator.max_depth if max_depth is None else int(max_depth)
    if spp < 1:
        raise RenderError(f"spp must be at least 1, got {spp}")
    if max_depth < 0:
        raise RenderError(f"max depth must be >= 0, got {max_depth}")
    ds = upload(scene, device, width, height, nee=nee)
    W, H = ds.width, ds.height
    film = Film(W, H, device)
    kernel = integrator_kernel(ds.features)
    t0 = time.perf_counter()
    wp.load_module(kernel.module, device=device)
    t_compile = time.perf_counter() - t0

    n_threads = max(1, min(threads or default_threads(device), H))
    bands = np.array_split(np.arange(H), n_threads)
    # enough samples per launch to amortise launch overhead, few enough to report progress often
    per_pass = int(max(1, min(spp, (1 << 19) // max(W * H, 1))))

    def launch(band: np.ndarray, start: int, count: int) -> None:
        wp.launch(kernel, dim=len(band) * W,
                  inputs=[ds.struct, seed, start, count, int(band[0]), max_depth, film.sum, film.bad],
                  device=device)
        wp.synchronize_device(device)

    t1 = time.perf_counter()
    done = 0
    interrupted = False
    with ThreadPoolExecutor(max_workers=n_threads) as pool:
        try:
            while done < spp:
                count = min(per_pass, spp - done)
                list(pool.map(lambda b: launch(b, done, count), [b for b in bands if len(b)]))
                done += count
                film.spp = done
                if progress:
                    progress(done, spp)
        except KeyboardInterrupt:
            # keep every finished pass: the film holds exactly ``done`` samples per pixel
            interrupted = True
    if stats is not None:
        stats.interrupted = interrupted
        stats.spp, stats.seconds, stats.compile_seconds = done, time.perf_counter() - t1, t_compile
        stats.bad_samples, stats.width, stats.height = film.bad_samples, W, H
        stats.warnings = list(scene.warnings)
    return film.image()
