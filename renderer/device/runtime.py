"""Warp's runtime: initialised once, with kernels cached under $WARP_CACHE_PATH, and the check
that a requested device exists."""
from __future__ import annotations

import os

from renderer.errors import RenderError


def init_warp(quiet: bool = True) -> None:
    """Initialise Warp once, with kernels cached under $WARP_CACHE_PATH when it is set."""
    import warp as wp

    cache = os.environ.get("WARP_CACHE_PATH")
    if cache:
        wp.config.kernel_cache_dir = cache
    # Warp's log level (1.19 dropped config.quiet): the banner and per-module load times are INFO
    wp.config.log_level = wp.LOG_WARNING if quiet else wp.LOG_INFO
    wp.init()


def require_device(device: str) -> None:
    """Refuse a CUDA device on a machine without one, before any upload."""
    import warp as wp

    init_warp()
    if device.startswith("cuda") and not wp.is_cuda_available():
        raise RenderError(f'device "{device}" requested but no CUDA GPU is available (use --device cpu)')
