"""Checkpoints: a render's state (film sums and what made them) written atomically as ``.npz``
and read back for ``--resume``. What the state holds is the session's business."""
from __future__ import annotations

import hashlib
import zipfile
from pathlib import Path

import numpy as np

from renderer.errors import MissingFileError, RenderError
from renderer.io.images import atomic_path


#: The entry holding a SHA-256 of all the others, written with every checkpoint, so a file whose
#: bytes changed after it was written (a bad disk, a hand edit) is refused instead of resumed.
#: Checkpoints written before it existed have none and are checked by their contents alone.
DIGEST = "sha256"


def content_digest(state: dict[str, np.ndarray]) -> str:
    """SHA-256 over every entry but the digest itself: names, dtypes, shapes and bytes, in name order."""
    h = hashlib.sha256()
    for key in sorted(k for k in state if k != DIGEST):
        a = np.ascontiguousarray(state[key])
        h.update(f"{key}\0{a.dtype.str}\0{a.shape}\0".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def save_checkpoint(path: str | Path, state: dict[str, np.ndarray]) -> None:
    """Write ``state`` and its digest atomically: a crash mid-write keeps the previous checkpoint."""
    state = {k: np.asarray(v) for k, v in state.items() if k != DIGEST}
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as f:
            np.savez(f, **state, **{DIGEST: np.str_(content_digest(state))})


#: What every checkpoint holds, by kind: "text" (a string), "count" (an integer >= 0), "seconds"
#: (a float >= 0) or "array" (finite numbers); the session checks shapes against its own film.
SCHEMA = {"fingerprint": "text", "settings": "text", "spp": "count", "seconds": "seconds",
          "sum": "array", "bad": "array", "rays": "array"}
#: More samples per pixel than this cannot come from a real render (and would overflow counters).
MAX_SPP = 1 << 31


def load_checkpoint(path: str | Path) -> dict[str, np.ndarray]:
    """The arrays of a checkpoint file (no pickles: a checkpoint is data, never code), checked
    against :data:`SCHEMA` so a truncated, foreign or edited file is refused by name."""
    if not Path(path).is_file():
        raise MissingFileError(path, None, "checkpoint")
    try:
        if not zipfile.is_zipfile(path):
            raise ValueError("not a checkpoint (.npz) file")
        with np.load(path, allow_pickle=False) as z:
            state = {k: z[k] for k in z.files}
    except (OSError, ValueError, EOFError, zipfile.BadZipFile) as e:
        raise RenderError(f"cannot read checkpoint {path}: {e}") from e
    if DIGEST in state and (_problem(state[DIGEST], "text") or str(state[DIGEST]) != content_digest(state)):
        raise RenderError(f"checkpoint {path}: its contents do not match the SHA-256 written with them "
                          "(the file was changed or damaged after it was written); refusing to resume")
    for key, kind in SCHEMA.items():
        problem = _problem(state.get(key), kind)
        if problem:
            raise RenderError(f"checkpoint {path}: {key!r} {problem}; not a checkpoint of this renderer?")
    return state


def _problem(value: np.ndarray | None, kind: str) -> str | None:
    """Why ``value`` does not fit ``kind``, or None when it does."""
    if value is None:
        return "is missing"
    if kind == "text":
        return None if value.ndim == 0 and value.dtype.kind == "U" else "is not a string"
    if kind == "array":
        ok = value.dtype.kind in "fiu" and bool(np.all(np.isfinite(value)))
        return None if ok else "holds non-numbers, NaN or infinities"
    if value.ndim != 0 or value.dtype.kind not in ("iu" if kind == "count" else "fiu"):
        return "is not a single number"
    v = float(value)
    limit = MAX_SPP if kind == "count" else float("inf")
    return None if np.isfinite(v) and 0 <= v < limit else f"is out of range ({v})"
