"""Errors a user can act on: every one names where in which file the problem is."""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path


@dataclass(frozen=True)
class Location:
    """A place in a scene file, carried by every directive so later stages can point back to it."""

    file: str
    line: int

    def __str__(self) -> str:
        return f"{self.file}:{self.line}"


class RenderError(Exception):
    """Base class of errors the CLI reports as one line with exit code 2."""


class SceneError(RenderError):
    """A malformed or unsupported scene, reported as ``file:line: message``."""

    def __init__(self, message: str, loc: Location | None = None):
        self.loc = loc
        self.message = message
        super().__init__(f"{loc}: {message}" if loc else message)


class MissingFileError(SceneError):
    """A file the scene refers to (mesh, texture, include) does not exist."""

    def __init__(self, path: str | Path, loc: Location | None = None, what: str = "file"):
        self.path = Path(path)
        super().__init__(f"{what} not found: {path}", loc)


class RenderWarning(UserWarning):
    """A scene or setting the renderer accepts but not quite as written (an ignored parameter, a
    feature rendered approximately, no lights): ``render()`` issues one per scene warning."""


class UnsupportedError(SceneError):
    """A type name (material, texture, light, shape, ...) this renderer does not implement. The
    builder collects these and reports every one at once, each with its file and line."""


class SceneErrors(SceneError):
    """Several located errors found in one pass over a scene, reported together (one per line)."""

    def __init__(self, errors: list[SceneError]):
        self.errors = list(errors)
        super().__init__("\n".join(str(e) for e in self.errors))
