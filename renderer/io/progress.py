"""Progress of a render on stderr: a tqdm bar on a terminal, a plain line per ~10 % of the samples
otherwise, so logs stay readable."""
from __future__ import annotations

import sys
import time


class Progress:
    """Samples per pixel done out of ``total``, from ``done`` (a resumed render starts there); silent
    unless ``enabled``."""

    def __init__(self, enabled: bool, total: int, done: int):
        self.enabled, self.total = enabled, total
        self.bar = None
        self.last = -1
        self.t0 = time.perf_counter()
        self.start = done

    def __call__(self, done: int, note: str = "") -> None:
        if not self.enabled:
            return
        if sys.stderr.isatty():
            if self.bar is None:
                from tqdm import tqdm

                self.bar = tqdm(total=self.total, initial=self.start, unit="spp", file=sys.stderr)
            self.bar.update(done - self.bar.n)
            if note:
                self.bar.set_postfix_str(note)
        else:
            decile = done * 10 // self.total
            if decile != self.last:
                self.last = decile
                el = time.perf_counter() - self.t0
                eta = el / max(done - self.start, 1) * (self.total - done)
                print(f"render: {done}/{self.total} spp, {el:.1f} s elapsed, ETA {eta:.1f} s"
                      f"{', ' + note if note else ''}", file=sys.stderr, flush=True)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
