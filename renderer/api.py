"""The Python API: ``load_scene`` (parse and build, no device work) and ``render``."""
from __future__ import annotations

from pathlib import Path
from typing import Callable

import numpy as np

from renderer.scene.description import SceneDescription
from renderer.device.runtime import init_warp
from renderer.session import RenderSession, RenderStats
from renderer.settings import RenderSettings, settings_for

__all__ = ["load_scene", "render", "init_warp", "settings_for", "RenderStats", "RenderSettings", "RenderSession"]


def load_scene(path: str | Path) -> SceneDescription:
    """Parse a pbrt-v4 file (and its includes) into a :class:`SceneDescription`."""
    from renderer.scene import load_description

    return load_description(path)


def render(scene: SceneDescription, spp: int | None = None, device: str = "cpu", seed: int | None = None,
           width: int | None = None, height: int | None = None, max_depth: int | None = None,
           nee: bool = True, rr_depth: int | None = None, threads: int | None = None, time_limit: float | None = None,
           progress: Callable[[int, int], None] | None = None, stats: RenderStats | None = None,
           thin_film: str | None = None) -> np.ndarray:
    """Render and return linear RGB as float32 (H, W, 3). ``spp``, ``seed``, ``max_depth`` and the
    resolution default to the scene file's values. ``progress(done, total)`` runs after every pass.
    ``thin_film``: the thinfilm material's colour mode, ``rgb3`` or ``spectral:N`` (default spectral:32)."""
    session = RenderSession(scene, settings_for(scene, seed=seed, width=width, height=height, max_depth=max_depth,
                                                nee=nee, rr_depth=rr_depth, thin_film=thin_film),
                            device=device, threads=threads)
    spp = scene.sampler.spp if spp is None else int(spp)
    on_pass = (lambda s: progress(s.film.spp, spp)) if progress else None
    result = session.run(spp, time_limit=time_limit, on_pass=on_pass)
    if stats is not None:
        stats.__dict__.update(result.__dict__)
    return session.image()
