"""The kernels a render launches, named, in one place: the session loads them, and
``render --compile-only`` compiles exactly these for a GPU it may not have."""
from __future__ import annotations

import warp as wp

from renderer.device.scene import Features


def render_kernels(features: Features, independent: bool, aov: bool = False) -> dict[str, wp.Kernel]:
    """By name: the path kernel of ``features`` (its ``independent``-sampler variant or not), the
    film's accumulation and, with ``aov`` (``--aov`` or ``--denoise``), the AOV kernel."""
    from renderer.device.film import accumulate
    from renderer.integrators.aov import aov_kernel
    from renderer.integrators.path import integrator_kernel

    kernels = {"path": integrator_kernel(features, independent), "film": accumulate}
    if aov:
        kernels["aov"] = aov_kernel(features)
    return kernels
