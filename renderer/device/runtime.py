"""Warp's runtime: initialised once, with kernels cached under $WARP_CACHE_PATH, and the check
that a requested device exists."""
from __future__ import annotations

import os
import sys
import tempfile

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
    """``wp.init()`` with the native library's stderr captured, passing on all but the no-driver line.

    Python's own writes keep reaching the real stderr throughout: a signal handler that runs
    inside ``wp.init()`` (the render command's, which prints and leaves through ``os._exit``)
    must not have its message swallowed by the capture file."""
    sys.stderr.flush()
    saved = os.dup(2)
    python_stderr = sys.stderr
    try:
        python_on_fd2 = python_stderr.fileno() == 2
    except (AttributeError, OSError, ValueError):   # pytest's capsys and the like: not fd 2
        python_on_fd2 = False
    with tempfile.TemporaryFile() as captured, \
            open(saved, "w", buffering=1, encoding=getattr(python_stderr, "encoding", None) or "utf-8",
                 errors="backslashreplace", closefd=False) as real_stderr:
        # sys.stderr is moved before fd 2 and restored after it, so at every instant a Python
        # write lands on the real stderr
        if python_on_fd2:
            sys.stderr = real_stderr
        os.dup2(captured.fileno(), 2)
        try:
            wp.init()
        finally:
            os.dup2(saved, 2)
            sys.stderr = python_stderr
            captured.seek(0)
            for line in captured.read().decode(errors="replace").splitlines(keepends=True):
                if _NO_DRIVER not in line:
                    sys.stderr.write(line)
    os.close(saved)


def require_device(device: str) -> None:
    """Refuse a CUDA device on a machine without one, before any upload."""
    import warp as wp

    init_warp()
    if device.startswith("cuda") and not wp.is_cuda_available():
        raise RenderError(f'device "{device}" requested but no CUDA GPU is available (use --device cpu)')
