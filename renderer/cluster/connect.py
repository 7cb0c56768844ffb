"""Joining Ray: a local instance, the cluster ``ray start`` made (``auto``) or a remote one
(``ray://host:port``), with a clear error when Ray is missing or the address cannot be reached."""
from __future__ import annotations

import logging
import os
import socket
from types import ModuleType

from renderer.errors import RenderError

INSTALL_HINT = "install it with: pip install 'summertime[cluster]' (or pip install 'ray[default]')"
#: Environment the workers need from the driver: the kernel cache, so each worker process loads
#: the compiled kernels instead of compiling them again.
WORKER_ENV = ("WARP_CACHE_PATH",)


def import_ray() -> ModuleType:
    try:
        import ray
    except ImportError:
        raise RenderError(f"--ray needs Ray, which is not installed; {INSTALL_HINT}") from None
    return ray


#: Ray 2.5x clusters use token authentication by default, and a ray:// client sends the token only
#: when told to (the server logs "Authentication required but no authorization header provided").
TOKEN_HINT = ("; if the cluster uses token authentication, set RAY_AUTH_MODE=token with the head's "
              "~/.ray/auth_token copied here")
#: Seconds to wait for a TCP connection to the given address before calling it unreachable (Ray's
#: own attempts retry for 30 s on a ray:// address and for minutes on a GCS host:port).
REACH_TIMEOUT = 5.0


def check_reachable(address: str) -> None:
    """Refuse quickly an explicit ``[ray://]host:port`` that accepts no connection."""
    host, sep, port = address.removeprefix("ray://").rpartition(":")
    if not sep or not port.isdigit():
        raise RenderError(f"Ray address must be local, auto, host:port or ray://host:port, got {address!r}")
    try:
        socket.create_connection((host.strip("[]"), int(port)), timeout=REACH_TIMEOUT).close()
    except OSError as e:
        raise RenderError(f"cannot reach the Ray cluster at {address}: {e.strerror or e}") from None


def connect(address: str | None) -> ModuleType:
    """Ray, initialised: an already initialised Ray is used as it is (a test or a notebook set it
    up); ``None`` or ``"local"`` starts a local instance on this machine's cores."""
    ray = import_ray()
    if ray.is_initialized():
        return ray
    env = {k: os.environ[k] for k in WORKER_ENV if k in os.environ}
    local = address in (None, "local")
    explicit = os.environ.get("RAY_ADDRESS") if address == "auto" else address   # auto reads RAY_ADDRESS first
    if not local and explicit:
        check_reachable(explicit)
    options = {"include_dashboard": False} if local else {}
    try:
        ray.init(address=None if local else address, runtime_env={"env_vars": env}, log_to_driver=False,
                 logging_level=logging.WARNING, **options)
    except Exception as e:   # Ray raises ConnectionError, RuntimeError, ValueError or its own kinds here
        where = "start a local Ray instance" if local else f"reach the Ray cluster at {address}"
        hint = TOKEN_HINT if str(address).startswith("ray://") and "timeout" in str(e) else ""
        raise RenderError(f"cannot {where}: {str(e).splitlines()[0] if str(e) else type(e).__name__}{hint}") from None
    return ray
