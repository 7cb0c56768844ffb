"""Warp's runtime: initialised once, with kernels cached under $WARP_CACHE_PATH, and the check
that a requested device exists."""
from __future__ import annotations

from renderer.errors import RenderError

#: What Warp's native code prints on every machine without an NVIDIA driver: expected there, and
#: not the user's concern (asking for ``--device cuda`` is refused with our own message instead).
_NO_DRIVER = "Could not find or load the NVIDIA CUDA driver"


def init_warp(quiet: bool = True) -> None:
    """Initialise Warp (again: a no-op), with kernels cached under $WARP_CACHE_PATH when it is set."""
    import warp as wp

    # Warp's log level (1.19 dropped config.quiet): the banner and per-module load times are INFO
    wp.config.log_level = wp.LOG_WARNING if quiet else wp.LOG_INFO
    # CUDA kernels load as cubins for the GPU's exact architecture, never as PTX that the driver
    # JIT-compiles: what runs is what `render --compile-only` compiled and measured, under the
    # name it wrote into the cache (Warp would otherwise pick PTX by driver version, for sm_75)
    wp.config.cuda_output = "cubin"
    # Warp itself reads $WARP_CACHE_PATH and keeps one subfolder per Warp version; setting
    # config.kernel_cache_dir to it here would, on a second call, point later compiles at the
    # unversioned folder (where the next process never looks, and Warp warns about them)
    if quiet:
        _init_without_driver_notice(wp)
    else:
        wp.init()


def _init_without_driver_notice(wp) -> None:
    """``wp.init()`` with the native library's stderr captured, passing on all but the no-driver
    line; Python's own writes (a signal handler's message) reach the real stderr throughout."""
    from renderer.io.native_stderr import native_stderr

    with native_stderr(keep=lambda line: _NO_DRIVER not in line):
        wp.init()


def require_device(device: str) -> None:
    """Refuse a CUDA device on a machine without one, before any upload."""
    import warp as wp

    init_warp()
    if device.startswith("cuda") and not wp.is_cuda_available():
        raise RenderError(f'device "{device}" requested but no CUDA GPU is available (use --device cpu)')
