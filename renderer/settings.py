"""What besides the scene changes the image, and every default for it. Plain Python: no Warp, no
kernels, so the CLI, the API, checkpoints and benchmarks can all read it cheaply."""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from renderer.color.spectral import parse_mode
from renderer.errors import RenderError
from renderer.sampling.sampler_spec import RANDOMIZATIONS, SamplerSpec

if TYPE_CHECKING:                  # the scene builder checks its Film and Sampler with the functions below
    from renderer.scene.description import SamplerDesc, SceneDescription

#: Depth from which Russian roulette may end a path by default; a negative value turns it off.
#: pbrt-v4 starts after the second bounce (2); `benchmarks/study.py` measured 4 as 2.4x more
#: efficient (relMSE x time) on the thin-film figure, whose dark coated spheres make early
#: roulette kill most paths, and equal on the demo scene.
RR_DEPTH = 4
#: The thin-film colour mode by default: 32 jittered wavelengths per evaluation (docs/thinfilm.md).
THIN_FILM_MODE = "spectral:32"
#: The largest film: 2^26 pixels (8192x8192) keeps the film's sums, counters and the image under
#: about 7 GB of host memory and every launch far inside Warp's 32-bit launch dimensions.
MAX_PIXELS = 1 << 26
#: Seeds and depths reach the kernels as 32-bit integers: larger values would silently wrap.
INT32_MIN, INT32_MAX = -(1 << 31), (1 << 31) - 1


def check_resolution(width: int, height: int) -> None:
    """Refuse a film that is empty or beyond :data:`MAX_PIXELS`, before anything is allocated."""
    if width < 1 or height < 1:
        raise RenderError(f"resolution must be positive, got {width}x{height}")
    if width * height > MAX_PIXELS:
        raise RenderError(f"resolution {width}x{height} has {width * height:,} pixels, more than the limit of "
                          f"{MAX_PIXELS:,} (8192x8192)")


def thin_film_samples(mode: str) -> int:
    """Wavelengths per thin-film evaluation in a render: ``rgb3`` → 0, ``spectral:N`` → N,
    ``table:N`` → N (for the materials no table describes)."""
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
    thin_film: str = THIN_FILM_MODE     # thin-film colour mode: rgb3, spectral:N or table[:N]
    sampler: SamplerSpec = SamplerSpec()

    def __post_init__(self) -> None:
        check_resolution(self.width, self.height)
        if not 0 <= self.max_depth <= INT32_MAX:
            raise RenderError(f"max depth must be between 0 and {INT32_MAX}, got {self.max_depth}")
        for what, v in (("seed", self.seed), ("Russian roulette depth", self.rr_depth)):
            if not INT32_MIN <= v <= INT32_MAX:
                raise RenderError(f"{what} must be a 32-bit integer ({INT32_MIN} to {INT32_MAX}), got {v}")
        try:
            thin_film_samples(self.thin_film)
        except ValueError as e:
            raise RenderError(str(e)) from None


def sampler_spec(desc: SamplerDesc, name: str | None = None) -> SamplerSpec:
    """The scene's Sampler, or the sampler ``name`` with the scene's sample count (and seed);
    the scene's randomisation and strata carry over where the other sampler has them."""
    if name is None or name == desc.kind:
        return SamplerSpec(desc.kind, desc.spp, desc.randomize, desc.jitter, desc.xsamples, desc.ysamples)
    randomize = desc.randomize if desc.randomize in RANDOMIZATIONS.get(name, ()) else ""
    xs = next(k for k in range(int(desc.spp ** 0.5), 0, -1) if desc.spp % k == 0)   # strata as square as spp allows
    return SamplerSpec(name, desc.spp, randomize, desc.jitter, desc.spp // xs, xs)


def settings_for(scene: SceneDescription, seed: int | None = None, width: int | None = None,
                 height: int | None = None, max_depth: int | None = None, nee: bool = True,
                 rr_depth: int | None = None, thin_film: str | None = None, sampler: str | None = None) -> RenderSettings:
    """Render settings: explicit values, else the scene file's, else the defaults above."""
    return RenderSettings(width=width or scene.film.width, height=height or scene.film.height,
                          seed=scene.sampler.seed if seed is None else int(seed),
                          max_depth=scene.integrator.max_depth if max_depth is None else int(max_depth), nee=nee,
                          rr_depth=RR_DEPTH if rr_depth is None else int(rr_depth),
                          thin_film=thin_film or THIN_FILM_MODE, sampler=sampler_spec(scene.sampler, sampler))
