"""Multiple importance sampling weights."""
from __future__ import annotations

import warp as wp


@wp.func
def power_heuristic(pdf_a: float, pdf_b: float) -> float:
    """Veach's power heuristic (β = 2) weight for the strategy with density ``pdf_a``."""
    a = pdf_a * pdf_a
    b = pdf_b * pdf_b
    if a + b <= 0.0:
        return 0.0
    if a > 1.0e30:
        return 1.0
    return a / (a + b)
