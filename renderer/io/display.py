"""pbrt-v4's ``--display-server host:port``: each finished pass is sent to the tev image viewer
over its TCP protocol, through the ``tevclient`` package (the ``[tev]`` extra). The image is
created once, named after the output file, and its R, G, B are replaced after every pass. A
viewer that cannot be reached at the start is an error (exit 2); one that goes away mid-render
stops the streaming with one warning, and the render goes on."""
from __future__ import annotations

import sys
from typing import Any

import numpy as np

from renderer.errors import RenderError

CHANNELS = ["R", "G", "B"]


def parse_address(text: str) -> tuple[str, int]:
    """``host:port`` (``[v6]:port`` too) as (host, port)."""
    host, sep, port = text.rpartition(":")
    if not sep or not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise RenderError(f"--display-server wants HOST:PORT (tev listens on 14158 by default), got {text!r}")
    return host.strip("[]"), int(port)


class DisplayServer:
    """A connection to tev showing one image of ``width`` x ``height``."""

    def __init__(self, address: str, name: str, width: int, height: int):
        try:
            import tevclient
        except ImportError as e:
            raise RenderError("--display-server needs the tevclient package: pip install '.[tev]'") from e
        host, port = parse_address(address)
        self.name = name
        self._ipc: Any = tevclient.Ipc(host, port)
        try:
            self._ipc.__enter__()
            self._ipc.create_image(name, width, height, CHANNELS)
        except OSError as e:
            raise RenderError(f"--display-server {address}: cannot reach tev ({e.strerror or e})") from e
        self._open = True

    def show(self, image: np.ndarray) -> None:
        """Replace the viewer's pixels with ``image`` (H, W, 3), the current mean."""
        if not self._open:
            return
        try:
            self._ipc.update_image(self.name, np.ascontiguousarray(image, dtype=np.float32), CHANNELS)
        except OSError as e:
            print(f"warning: --display-server: tev went away ({e.strerror or e}); no longer streaming",
                  file=sys.stderr)
            self.close()

    def close(self) -> None:
        if self._open:
            self._open = False
            try:
                self._ipc.__exit__(None, None, None)
            except OSError:
                pass

