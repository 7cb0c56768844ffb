"""The Python API: ``load_scene`` (parse and build, no device work), ``open_session`` (upload, resume) and ``render``."""
from __future__ import annotations

import warnings
from pathlib import Path
from typing import TYPE_CHECKING, Callable

import numpy as np

from renderer.device.footprint import check_fits
from renderer.device.runtime import init_warp
from renderer.errors import RenderWarning
from renderer.io.checkpoint import load_checkpoint
from renderer.materials import with_multiscatter
from renderer.scene.description import SceneDescription
from renderer.session import RenderSession, RenderStats
from renderer.settings import RenderSettings, settings_for

if TYPE_CHECKING:
    from renderer.cluster import Cluster

__all__ = ["load_scene", "open_session", "render", "init_warp", "settings_for", "RenderStats", "RenderSettings",
           "RenderSession"]


def load_scene(path: str | Path) -> SceneDescription:
    """Parse a pbrt-v4 file (and its includes) into a :class:`SceneDescription`."""
    from renderer.scene import load_description

    return load_description(path)


def open_session(scene: SceneDescription, settings: RenderSettings, device: str = "cpu", threads: int | None = None,
                 resume: str | Path | None = None, memory_limit_gb: float | None = None,
                 wavefront: bool | None = None, aov: bool = False) -> RenderSession:
    """Upload ``scene`` and get a session ready to render passes; with ``resume``, continue the
    checkpoint at that path (refused if it was made from another scene or with other settings).
    A scene estimated to need more than ``memory_limit_gb`` (default: this machine's memory) is
    refused before anything is allocated. ``wavefront``: the wavefront integrator (True) or the
    megakernel (False) instead of the device's default (the wavefront on CUDA); the same image.
    ``aov``: compile the AOV kernel with the others (``session.aovs()`` follows the passes).
    ``render`` and the ``render`` command both start here."""
    from renderer.integrators.kernels import use_wavefront

    limit = None if memory_limit_gb is None else int(memory_limit_gb * 2**30)
    check_fits(scene, settings.width, settings.height, limit, use_wavefront(device, wavefront))
    session = RenderSession(scene, settings, device=device, threads=threads, wavefront=wavefront, aov=aov)
    if resume is not None:
        session.restore(load_checkpoint(resume), source=str(resume))
    return session


def render(scene: SceneDescription, spp: int | None = None, device: str = "cpu", seed: int | None = None,
           width: int | None = None, height: int | None = None, max_depth: int | None = None,
           nee: bool = True, rr_depth: int | None = None, threads: int | None = None, time_limit: float | None = None,
           progress: Callable[[int, int], None] | None = None, stats: RenderStats | None = None,
           thin_film: str | None = None, sampler: str | None = None,
           cluster: "Cluster | str | None" = None, multiscatter: bool = False,
           wavefront: bool | None = None) -> np.ndarray:
    """Render and return linear RGB as float32 (H, W, 3). ``spp``, ``seed``, ``max_depth`` and the
    resolution default to the scene file's values. ``progress(done, total)`` runs after every pass.
    ``thin_film``: the thinfilm material's colour mode, ``rgb3``, ``spectral:N`` (default spectral:32)
    or ``table[:N]`` (docs/thinfilm.md).
    ``sampler``: a pbrt-v4 sampler name instead of the scene's (which defaults to ``zsobol``).
    Each of the scene's warnings is issued as a :class:`RenderWarning` (and listed in ``stats.warnings``).
    ``cluster``: render on Ray (a :class:`renderer.cluster.Cluster`, or an address: "local", "auto",
    "ray://host:port"); the image is bit-identical to the one-process render.
    ``multiscatter``: count the bounces between microfacets on every rough ``dielectric``, ``conductor``
    and ``thinfilm`` (as if each had ``"bool multiscatter" true``; docs/materials.md).
    ``wavefront``: True runs the wavefront integrator, False the megakernel; None (default) the
    wavefront on CUDA and the megakernel on the CPU. The image is the same."""
    if multiscatter:
        scene = with_multiscatter(scene)
    settings = settings_for(scene, seed=seed, width=width, height=height, max_depth=max_depth, nee=nee,
                            rr_depth=rr_depth, thin_film=thin_film, sampler=sampler)
    if cluster is not None:
        from renderer.cluster import open_cluster

        session = open_cluster(scene, settings, cluster, device=device, threads=threads)
    else:
        session = open_session(scene, settings, device=device, threads=threads, wavefront=wavefront)
    for w in session.stats.warnings:
        warnings.warn(w, RenderWarning, stacklevel=2)
    spp = scene.sampler.spp if spp is None else int(spp)
    on_pass = (lambda s: progress(s.film.spp, spp)) if progress else None
    result = session.run(spp, time_limit=time_limit, on_pass=on_pass)
    if stats is not None:
        stats.__dict__.update(result.__dict__)
    return session.image()
