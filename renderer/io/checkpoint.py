"""Checkpoints: a render's state (film sums and what made them) written atomically as ``.npz``
and read back for ``--resume``. What the state holds is the session's business."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from renderer.errors import MissingFileError, RenderError
from renderer.io.images import atomic_path


def save_checkpoint(path: str | Path, state: dict[str, np.ndarray]) -> None:
    """Write ``state`` atomically: a crash mid-write keeps the previous checkpoint."""
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as f:
            np.savez(f, **state)


def load_checkpoint(path: str | Path) -> dict[str, np.ndarray]:
    """The arrays of a checkpoint file (no pickles: a checkpoint is data, never code)."""
    if not Path(path).is_file():
        raise MissingFileError(path, None, "checkpoint")
    try:
        with np.load(path, allow_pickle=False) as z:
            return {k: z[k] for k in z.files}
    except (OSError, ValueError) as e:
        raise RenderError(f"cannot read checkpoint {path}: {e}") from e
