"""A physically based path tracer on NVIDIA Warp that reads pbrt-v4 scenes.

``load_scene`` parses and builds a scene (no device work); ``render`` runs it on a Warp device
and returns linear RGB as a numpy float32 (H, W, 3) array.
"""
from __future__ import annotations

__version__ = "0.1.0"

from renderer.api import load_scene, render  # noqa: E402

__all__ = ["load_scene", "render", "__version__"]
