"""The parse and build stage: a pbrt-v4 file (and its includes) -> :class:`SceneDescription`."""
from __future__ import annotations

from pathlib import Path

from renderer.scene.builder import Builder
from renderer.scene.description import SceneDescription
from renderer.scene.parser import parse_file


def load_description(path: str | Path) -> SceneDescription:
    """Parse and build; no device work. Errors are :class:`renderer.errors.SceneError` with file:line."""
    scene = Builder(str(path)).build(parse_file(path))
    scene.path = Path(path)
    return scene


__all__ = ["load_description"]
