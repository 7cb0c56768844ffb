"""Image error metrics for convergence studies and error logs."""
from __future__ import annotations

import numpy as np


def relative_mse(img: np.ndarray, ref: np.ndarray, trim: float = 0.0) -> float:
    """relMSE = mean((x - r)^2 / (r^2 + 0.01)). ``trim`` drops that fraction of the largest
    per-pixel errors first (0.001 is the usual choice in the literature), so a handful of
    caustic fireflies does not hide the convergence of everything else."""
    e = ((img - ref) ** 2 / (ref ** 2 + 1e-2)).mean(axis=-1).ravel()
    if trim > 0:
        e = np.sort(e)[: max(1, int(round(len(e) * (1.0 - trim))))]
    return float(e.mean())
