"""A physically based path tracer on NVIDIA Warp that reads pbrt-v4 scenes.

``load_scene`` parses and builds a scene (no device work); ``render`` runs it on a Warp device
and returns linear RGB as a numpy float32 (H, W, 3) array. Both are imported lazily so that the
parser and the asset generator can be used without initialising Warp.
"""
from __future__ import annotations

__version__ = "0.1.0"
__all__ = ["load_scene", "render", "__version__"]


def __getattr__(name: str):
    if name in ("load_scene", "render"):
        from renderer import api

        return getattr(api, name)
    raise AttributeError(f"module 'renderer' has no attribute {name!r}")
