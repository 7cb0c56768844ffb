"""Comparing our render of a small scene with pbrt-v4's own images of it (tests/data/pbrt: each
``.pbrt`` and the ``.exr`` pbrt-v4 made of it, see render_references.py), within the noise of both.

Each renderer renders each scene twice with independent seeds (pbrt: ``<name>.exr`` and
``<name>-2.exr``); a pair's difference estimates the per-pixel variance of its mean,
Var = E[(A - B)^2] / 4. ``chi`` = the sum of squared differences between the two means over the
sum of both variances is about 1 when the images agree up to noise."""
from __future__ import annotations

from functools import lru_cache
from pathlib import Path

import numpy as np

from renderer.api import load_scene, render
from renderer.io.images import read_exr
from renderer.scene.description import SceneDescription

DATA = Path(__file__).parent / "data" / "pbrt"
SPP = 128            # ours, in two halves
CHI = 1.5           # measured 0.95-1.0 for every scene that matches
DISTINCT = 2.5      # what a wrong filter gives at least
MEAN_TOL = 0.01


def reference(name: str) -> tuple[np.ndarray, np.ndarray]:
    """pbrt-v4's mean of its two renders, and that mean's per-pixel variance."""
    a, b = (np.stack([ch[c] for c in "RGB"], -1) for ch, _ in (read_exr(DATA / f"{n}.exr") for n in (name, f"{name}-2")))
    return 0.5 * (a + b), 0.25 * (a - b) ** 2


def ours(scene: SceneDescription, sampler: str | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Our N-spp mean and its per-pixel variance (with ``sampler`` instead of the scene's).

    The variance comes from two seeds, so it is only honest for a sampler whose every dimension
    the seed randomises. pbrt-v4's ``halton`` (and ours, which reproduces it) does not randomise
    the film position (HaltonSampler::GetPixel2D): both seeds share it, and in a pixel whose
    value depends on nothing else (a directly seen emitter) the two halves agree exactly while
    both differ from pbrt's 256-point image by the 64-point pattern's own error. Scenes that
    name halton are therefore compared with ``sampler="zsobol"``."""
    a = render(scene, spp=SPP // 2, seed=11, sampler=sampler)
    b = render(scene, spp=SPP // 2, seed=12, sampler=sampler)
    return 0.5 * (a + b), 0.25 * (a - b) ** 2


def chi(img: np.ndarray, var: np.ndarray, ref: np.ndarray, ref_var: np.ndarray) -> float:
    return float(((img - ref) ** 2).sum() / (var + ref_var).sum())


@lru_cache(maxsize=None)
def ours_of(name: str, sampler: str | None = None) -> tuple[np.ndarray, np.ndarray]:
    return ours(load_scene(DATA / f"{name}.pbrt"), sampler)


def assert_matches_pbrt(name: str, mean_tol: float = MEAN_TOL) -> tuple[np.ndarray, np.ndarray]:
    """Ours against pbrt-v4's image of ``<name>.pbrt``: chi under CHI and per-channel means within
    ``mean_tol``. Returns pbrt's mean and its variance, for a wrong variant to fail against."""
    img, var = ours_of(name)
    ref, ref_var = reference(name)
    c = chi(img, var, ref, ref_var)
    assert c < CHI, f"{name}: chi {c:.3f}"
    np.testing.assert_allclose(img.mean((0, 1)), ref.mean((0, 1)), rtol=mean_tol)
    return ref, ref_var


def variant_chi(name: str, edits: list[tuple[str, str]], ref: np.ndarray, ref_var: np.ndarray, tmp: Path,
                files: tuple[str, ...] = ()) -> float:
    """chi against the reference of our render of ``<name>.pbrt`` with each (old, new) text edit
    applied in order (``files`` it reads are copied beside it): a check has teeth when the wrong
    variant fails it."""
    text = (DATA / f"{name}.pbrt").read_text()
    for old, new in edits:
        text = text.replace(old, new)
    for f in files:
        (tmp / f).write_bytes((DATA / f).read_bytes())
    (tmp / "variant.pbrt").write_text(text)
    img, var = ours(load_scene(tmp / "variant.pbrt"))
    return chi(img, var, ref, ref_var)
