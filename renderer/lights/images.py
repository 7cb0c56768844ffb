"""Images that lights read (an environment map, a goniometric diagram, a projected slide): the file
resolved against the scene file at load time, and its pixels read at upload, refused where they
could not be light (negative, NaN, infinite), as pbrt-v4 refuses them."""
from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from renderer.errors import Location, MissingFileError, SceneError


def resolved(given: dict[str, Any], loc: Location | None, base_dir: Path | None, what: str) -> dict[str, Any]:
    """``given`` with its ``filename`` relative to the scene file's folder, which must exist."""
    path = Path(given["filename"])
    path = base_dir / path if base_dir is not None else path
    if not path.is_file():
        raise MissingFileError(path, loc, what)
    return {**given, "filename": str(path)}


def read_light_image(values: dict[str, Any], loc: Location | None, what: str, stored: bool = False) -> np.ndarray:
    """The (H, W, C) linear float32 pixels of ``values["filename"]`` (8-bit files decoded from sRGB);
    with ``stored``, an 8-bit file's codes instead (uint8, one or three channels: every code
    decodes to a valid radiance, so only float files are checked)."""
    from renderer.io.images import linear, read_stored

    path = Path(values["filename"])
    if not path.is_file():
        raise MissingFileError(path, loc, what)
    try:
        image = read_stored(path, max_channels=3 if stored else None)
    except OSError as e:
        raise SceneError(f"{what}: {e}", loc) from e
    if image.dtype == np.uint8 and stored:
        return image if image.shape[2] != 2 else np.ascontiguousarray(image[..., :1])   # grey + alpha: grey
    image = linear(image, srgb=True)
    if not np.all(np.isfinite(image)) or np.any(image < 0):
        raise SceneError(f"{what} contains negative, NaN or infinite values", loc)
    return np.ascontiguousarray(image, dtype=np.float32)


def rgb_of(image: np.ndarray) -> np.ndarray:
    """(H, W, 3): the first three channels, or a one-channel image repeated."""
    return image[..., :3] if image.shape[2] >= 3 else np.repeat(image[..., :1], 3, axis=2)
