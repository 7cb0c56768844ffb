"""What besides the scene changes the image, and every default for it. Plain Python: no Warp, no
kernels, so the CLI, the API, checkpoints and benchmarks can all read it cheaply."""
from __future__ import annotations

from dataclasses import dataclass

from renderer.color.spectral import parse_mode
from renderer.errors import RenderError
from renderer.scene.description import SceneDescription

#: Depth from which Russian roulette may end a path by default; a negative value turns it off.
#: pbrt-v4 starts after the second bounce (2); `benchmarks/study.py` measured 4 as 2.4x more
#: efficient (relMSE x time) on the thin-film figure, whose dark coated spheres make early
#: roulette kill most paths, and equal on the demo scene.
RR_DEPTH = 4
#: The thin-film colour mode by default: 32 jittered wavelengths per evaluation (docs/thinfilm.md).
THIN_FILM_MODE = "spectral:32"


def thin_film_samples(mode: str) -> int:
    """Wavelengths per thin-film evaluation in a render: ``rgb3`` → 0, ``spectral:N`` → N."""
    kind, n = parse_mode(mode)
    if kind == "reference":
        raise ValueError("the thin-film mode 'reference' is for optics tools, not renders: use 'spectral:N'")
    return n


@dataclass(frozen=True)
class RenderSettings:
    """Everything besides the scene that changes the image; a checkpoint must match it."""

    width: int
    height: int
    seed: int
    max_depth: int
    nee: bool = True
    rr_depth: int = RR_DEPTH            # Russian roulette from this depth on; negative: never
    thin_film: str = THIN_FILM_MODE     # thin-film colour mode: rgb3 or spectral:N

    def __post_init__(self) -> None:
        if self.width < 1 or self.height < 1:
            raise RenderError(f"resolution must be positive, got {self.width}x{self.height}")
        if self.max_depth < 0:
            raise RenderError(f"max depth must be >= 0, got {self.max_depth}")
        try:
            thin_film_samples(self.thin_film)
        except ValueError as e:
            raise RenderError(str(e)) from None


def settings_for(scene: SceneDescription, seed: int | None = None, width: int | None = None,
                 height: int | None = None, max_depth: int | None = None, nee: bool = True,
                 rr_depth: int | None = None, thin_film: str | None = None) -> RenderSettings:
    """Render settings: explicit values, else the scene file's, else the defaults above."""
    return RenderSettings(width=width or scene.film.width, height=height or scene.film.height,
                          seed=scene.sampler.seed if seed is None else int(seed),
                          max_depth=scene.integrator.max_depth if max_depth is None else int(max_depth), nee=nee,
                          rr_depth=RR_DEPTH if rr_depth is None else int(rr_depth),
                          thin_film=thin_film or THIN_FILM_MODE)
