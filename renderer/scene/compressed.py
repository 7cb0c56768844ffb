"""Files pbrt-v4 reads gzipped when their name ends in ``.gz`` (scene files, ``Include``/``Import``
targets and PLY meshes), decompressed with a bound on the size they expand to, so a small
hostile file (a "gzip bomb") is refused before it fills memory."""
from __future__ import annotations

import gzip
import zlib
from pathlib import Path

from renderer.errors import Location, SceneError

_CHUNK = 1 << 20


class TooLargeError(SceneError):
    """A file (after decompression) larger than its reader's bound."""


def is_gzipped(path: Path) -> bool:
    """pbrt-v4 decides by the name, as here: ``.gz`` means gzip."""
    return path.suffix.lower() == ".gz"


def read_bytes(path: Path, limit: int, loc: Location | None, what: str) -> bytes:
    """The file's bytes (decompressed when its name ends in ``.gz``); more than ``limit`` bytes is
    a SceneError naming the file, raised before more than ``limit`` + 1 MiB is held."""
    shown = path.name
    try:
        if not is_gzipped(path):
            size = path.stat().st_size
            if size > limit:
                raise TooLargeError(f"{what} {shown} is {size:,} bytes, more than the limit of {limit:,}", loc)
            return path.read_bytes()
        parts: list[bytes] = []
        total = 0
        with gzip.open(path, "rb") as f:
            while chunk := f.read(_CHUNK):
                total += len(chunk)
                if total > limit:
                    raise TooLargeError(f"{what} {shown} decompresses to more than the limit of {limit:,} bytes",
                                     loc)
                parts.append(chunk)
        return b"".join(parts)
    except (gzip.BadGzipFile, zlib.error, EOFError) as e:
        raise SceneError(f"{what} {shown}: not a readable gzip file ({e})", loc) from None
    except OSError as e:
        raise SceneError(f"cannot read {what} {shown}: {e.strerror or e}", loc) from None
