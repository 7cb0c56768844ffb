"""Which sampler draws a render's random numbers: pbrt-v4's names, parameters and defaults as a
plain value (no Warp), so settings, checkpoints and the CLI can hold and compare it.

``pixel_samples`` is the size of the sampler's pattern (pbrt's ``pixelsamples``, or ``xsamples``
x ``ysamples`` for ``stratified``). A render may take more passes than that: each further block
of ``pixel_samples`` passes is the same construction randomised afresh, so it stays unbiased."""
from __future__ import annotations

from dataclasses import dataclass

from renderer.errors import RenderError

#: The sampler a scene gets when it names none: pbrt-v4's default.
DEFAULT_SAMPLER = "zsobol"
#: Every sampler implemented, and the randomisations each offers (the first is pbrt-v4's default).
RANDOMIZATIONS: dict[str, tuple[str, ...]] = {
    "independent": ("none",),
    "stratified": ("none",),
    "halton": ("permutedigits", "owen", "none"),
    "sobol": ("fastowen", "permutedigits", "owen", "none"),
    "paddedsobol": ("fastowen", "permutedigits", "owen", "none"),
    "zsobol": ("fastowen", "permutedigits", "owen", "none"),
}
#: Samplers whose patterns are only complete for a power-of-two sample count (pbrt-v4 warns).
POWER_OF_TWO = frozenset({"sobol", "zsobol", "pmj02bn"})


@dataclass(frozen=True)
class SamplerSpec:
    """A sampler and its parameters; ``randomize`` "" means the sampler's default."""

    name: str = DEFAULT_SAMPLER
    pixel_samples: int = 16
    randomize: str = ""
    jitter: bool = True       # stratified: a random point in each stratum, else its centre
    xsamples: int = 4         # stratified: strata across and down a pixel
    ysamples: int = 4

    def __post_init__(self) -> None:
        if self.name not in RANDOMIZATIONS:
            raise RenderError(f"unknown sampler {self.name!r}; choose one of {', '.join(RANDOMIZATIONS)}")
        if self.randomize and self.randomize not in RANDOMIZATIONS[self.name]:
            raise RenderError(f"sampler {self.name!r} offers randomize {', '.join(RANDOMIZATIONS[self.name])}, "
                              f"not {self.randomize!r}")
        if not 1 <= self.pixel_samples <= 1 << 24:
            raise RenderError(f"pixel samples must be between 1 and {1 << 24}, got {self.pixel_samples}")
        if self.name == "stratified" and self.xsamples * self.ysamples != self.pixel_samples:
            raise RenderError(f"stratified sampler: xsamples x ysamples = {self.xsamples * self.ysamples}, "
                              f"not the pixel samples {self.pixel_samples}")

    @property
    def randomization(self) -> str:
        return self.randomize or RANDOMIZATIONS[self.name][0]

    def warning(self) -> str | None:
        """pbrt-v4's warning for a pattern that a non-power-of-two sample count leaves incomplete."""
        n = self.pixel_samples
        if self.name in POWER_OF_TWO and n & (n - 1):
            return (f"the {self.name} sampler's patterns need a power-of-two sample count; {n} pixel samples "
                    "leave the last pattern incomplete (the image stays unbiased but noisier)")
        return None
