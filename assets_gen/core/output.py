"""Writing outputs reproducibly: a staging folder that only moves into place on success, the JSON
manifest, binary PLY meshes and scalar maps (EXR with a greyscale PNG preview)."""
from __future__ import annotations

import contextlib
import errno
import json
import math
import shutil
import tempfile
from pathlib import Path
from typing import Any, Iterator

import numpy as np

from assets_gen import __version__
from assets_gen.core.params import GeneratorError


@contextlib.contextmanager
def staged_output(out_dir: str | Path) -> Iterator[Path]:
    """Yield an empty staging folder; its files move into ``out_dir`` only if the body succeeds,
    so a failed or interrupted generator leaves nothing behind: not a half-written file, and not
    the output folder or its parents either, which are made only then. The stage sits in the
    nearest existing ancestor of ``out_dir`` (the same file system, so the moves are renames)."""
    out_dir = Path(out_dir)
    anchor = out_dir.absolute()
    while not anchor.exists() and anchor != anchor.parent:
        anchor = anchor.parent
    try:
        if not anchor.is_dir():
            raise NotADirectoryError(errno.ENOTDIR, f"{anchor} is not a folder")
        stage = Path(tempfile.mkdtemp(prefix=".staging-", dir=anchor))
    except OSError as e:
        raise GeneratorError(f"cannot write into output folder {str(out_dir)!r}: {e.strerror or e}") from e
    try:
        yield stage
        try:
            out_dir.mkdir(parents=True, exist_ok=True)
        except OSError as e:
            raise GeneratorError(f"cannot write into output folder {str(out_dir)!r}: {e.strerror or e}") from e
        for f in sorted(stage.iterdir()):
            f.replace(out_dir / f.name)
    finally:
        shutil.rmtree(stage, ignore_errors=True)


def write_manifest(path: str | Path, generator: str, params: dict[str, Any], seed: int,
                   outputs: list[str]) -> None:
    """Record what made these files (deterministic JSON: sorted keys, no timestamps)."""
    doc = {"generator": generator, "version": __version__, "seed": int(seed),
           "params": _jsonable(params), "outputs": sorted(outputs)}
    Path(path).write_text(json.dumps(doc, indent=2, sort_keys=True) + "\n")


def _jsonable(x: Any) -> Any:
    if isinstance(x, dict):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    if isinstance(x, np.generic):
        return x.item()
    if isinstance(x, np.ndarray):
        return x.tolist()
    if isinstance(x, Path):
        return str(x)
    return x


def write_ply(path: str | Path, vertices: np.ndarray, faces: np.ndarray, normals: np.ndarray | None = None,
              uvs: np.ndarray | None = None) -> None:
    """Binary little-endian PLY with float32 positions, optional normals (nx, ny, nz) and UVs (u, v),
    the layout pbrt-v4's ``plymesh`` reads. Byte-identical for identical input."""
    from plyfile import PlyData, PlyElement

    v = np.asarray(vertices, dtype=np.float32)
    fields = [("x", "f4"), ("y", "f4"), ("z", "f4")]
    cols = [v[:, 0], v[:, 1], v[:, 2]]
    if normals is not None:
        n = np.asarray(normals, dtype=np.float32)
        fields += [("nx", "f4"), ("ny", "f4"), ("nz", "f4")]
        cols += [n[:, 0], n[:, 1], n[:, 2]]
    if uvs is not None:
        t = np.asarray(uvs, dtype=np.float32)
        fields += [("u", "f4"), ("v", "f4")]
        cols += [t[:, 0], t[:, 1]]
    vert = np.empty(len(v), dtype=fields)
    for (name, _), c in zip(fields, cols):
        vert[name] = c
    f = np.asarray(faces, dtype=np.int32)
    face = np.empty(len(f), dtype=[("vertex_indices", "i4", (3,))])
    face["vertex_indices"] = f
    PlyData([PlyElement.describe(vert, "vertex"), PlyElement.describe(face, "face")],
            byte_order="<").write(str(path))


def write_preview(path: Path, values: np.ndarray, max_side: int = 512) -> None:
    """An 8-bit greyscale PNG of a map, stretched to its own range and shrunk to ``max_side``:
    for looking at, not for rendering (the EXR holds the physical values)."""
    from PIL import Image

    v = np.asarray(values, dtype=np.float64)
    lo, hi = float(np.nanmin(v)), float(np.nanmax(v))
    grey = np.zeros_like(v) if hi <= lo else (v - lo) / (hi - lo)
    step = max(1, int(math.ceil(max(v.shape) / max_side)))
    img = (np.nan_to_num(grey[::step, ::step]) * 255.0 + 0.5).astype(np.uint8)
    Image.fromarray(img).save(path, format="PNG", optimize=False)


def write_map(stage: Path, name: str, values: np.ndarray, units: str, preview: bool,
              header: dict[str, object] | None = None) -> list[str]:
    """``name.exr`` (one float channel ``Y`` in ``units``) and optionally ``name.png``."""
    from renderer.io.images import write_exr

    write_exr(stage / f"{name}.exr", {"Y": np.asarray(values, dtype=np.float32)},
              {"units": units, **(header or {})})
    if not preview:
        return [f"{name}.exr"]
    write_preview(stage / f"{name}.png", values)
    return [f"{name}.exr", f"{name}.png"]
