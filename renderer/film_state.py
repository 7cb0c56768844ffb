"""A film's state as a checkpoint holds it, shared by the one-process session and the cluster
driver so each resumes the other's checkpoints: the fixed-point sums, which sample indices they
hold, the counters, and what scene and settings made them (a resume into anything else is refused)."""
from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from renderer.device.film import MAX_SAMPLE, ONE, fixed_from_float
from renderer.errors import RenderError
from renderer.sample_ranges import Ranges, count, from_array, to_array
from renderer.settings import RenderSettings


def settings_key(settings: RenderSettings) -> str:
    return repr(sorted(asdict(settings).items()))


@dataclass
class FilmState:
    sums: np.ndarray          # (N, 3, 2) int64: renderer.device.film's fixed-point sums
    ranges: Ranges            # the sample indices in the sums
    bad: int = 0
    rays: float = 0.0
    seconds: float = 0.0

    @property
    def spp(self) -> int:
        return count(self.ranges)

    def to_state(self, fingerprint: str, settings: RenderSettings) -> dict[str, np.ndarray]:
        """The arrays of a checkpoint (see renderer.io.checkpoint)."""
        return {"sum": self.sums, "spp": np.int64(self.spp), "ranges": to_array(self.ranges),
                "bad": np.array([self.bad], dtype=np.int32), "rays": np.array([self.rays]),
                "seconds": np.float64(self.seconds), "fingerprint": np.str_(fingerprint),
                "settings": np.str_(settings_key(settings))}

    @classmethod
    def from_state(cls, state: dict[str, np.ndarray], fingerprint: str, settings: RenderSettings, pixels: int,
                   source: str = "checkpoint") -> "FilmState":
        """The film of ``state``; refused when another scene or other settings made it, or when its
        sums or ranges do not fit. Float sums (an earlier version's) are converted."""
        mine = settings_key(settings)
        if str(state["fingerprint"]) != fingerprint:
            raise RenderError(f"{source} was made from a different scene (content differs); refusing to resume")
        if str(state["settings"]) != mine:
            raise RenderError(f"{source} was made with other settings {state['settings']}, not {mine}; "
                              "refusing to resume")
        sums = state["sum"]
        if sums.dtype.kind == "f" and sums.shape == (pixels, 3):
            try:
                sums = fixed_from_float(sums)
            except ValueError as e:
                raise RenderError(f"{source}: {e}; refusing to resume") from None
        if sums.shape != (pixels, 3, 2) or sums.dtype.kind not in "iu":
            raise RenderError(f"{source} holds film sums of shape {sums.shape}, not ({pixels}, 3, 2) integers; "
                              "refusing to resume")
        spp = int(state["spp"])
        _check_contents(sums, spp, int(np.sum(state["bad"])), float(np.sum(state["rays"])), pixels, source)
        try:
            ranges = from_array(state["ranges"]) if "ranges" in state else ([(0, spp)] if spp else [])
        except ValueError as e:
            raise RenderError(f"{source}: {e}") from None
        if count(ranges) != spp:
            raise RenderError(f"{source} holds {spp} spp but sample ranges of {count(ranges)}; refusing to resume")
        return cls(sums.astype(np.int64), ranges, int(np.sum(state["bad"])), float(np.sum(state["rays"])),
                   float(state["seconds"]))


def _check_contents(sums: np.ndarray, spp: int, bad: int, rays: float, pixels: int, source: str) -> None:
    """Refuse sums and counts no render of ``spp`` samples per pixel could hold: a whole part below 0
    or above spp x MAX_SAMPLE (NaN written into int64 becomes -2^63), a fraction outside [0, 1),
    more dropped samples than samples, a ray count below 0 or beyond what the film's int64 counts hold."""
    whole, fraction = sums[..., 0], sums[..., 1]
    most = min(spp * int(MAX_SAMPLE), (1 << 63) - 1)
    if sums.size and (whole.min() < 0 or whole.max() > most):
        raise RenderError(f"{source} holds film sums outside [0, {spp} spp x {MAX_SAMPLE:.3g}] "
                          f"(from {int(whole.min())} to {int(whole.max())}); refusing to resume")
    if sums.size and (fraction.min() < 0 or fraction.max() >= ONE):
        raise RenderError(f"{source} holds film sum fractions outside [0, 2^62); refusing to resume")
    if not 0 <= bad <= pixels * spp:
        raise RenderError(f"{source} counts {bad} dropped samples, not within 0..{pixels * spp} "
                          f"({pixels} pixels x {spp} spp); refusing to resume")
    if not 0 <= rays < 2.0 ** 62:       # the film counts rays in int64
        raise RenderError(f"{source} counts {rays} rays; refusing to resume")
