"""The kernels a render launches, named, in one place: the session loads them, and
``render --compile-only`` compiles exactly these for a GPU it may not have.

Two integrators compute the same image: the megakernel (:mod:`renderer.integrators.path`, one
kernel, fastest on the CPU) and the wavefront (:mod:`renderer.integrators.wavefront`, small kernels
that fit a GPU's registers). CUDA devices use the wavefront and the CPU the megakernel unless
asked otherwise."""
from __future__ import annotations

import warp as wp

from renderer.device.scene import Features


def use_wavefront(device: str, wavefront: bool | None) -> bool:
    """Whether a render on ``device`` runs the wavefront: as asked, else on CUDA devices only."""
    return device.startswith("cuda") if wavefront is None else bool(wavefront)


def render_kernels(features: Features, independent: bool, aov: bool = False,
                   wavefront: bool = False) -> dict[str, wp.Kernel]:
    """By name: the path kernel of ``features`` (its ``independent``-sampler variant or not), or
    with ``wavefront`` the wavefront's kernels in launch order; the film's accumulation and, with
    ``aov`` (``--aov`` or ``--denoise``), the AOV kernel (with ``wavefront``, the AOV pass's steps)."""
    from renderer.device.film import accumulate
    from renderer.integrators.aov import aov_kernel
    from renderer.integrators.aov_steps import aov_step_kernels
    from renderer.integrators.path import integrator_kernel
    from renderer.integrators.wavefront import wavefront_kernels

    if wavefront:
        kernels = wavefront_kernels(features, independent)
    else:
        kernels = {"path": integrator_kernel(features, independent)}
    kernels["film"] = accumulate
    if aov and wavefront:
        kernels.update(aov_step_kernels(features))
    elif aov:
        kernels["aov"] = aov_kernel(features)
    return kernels
