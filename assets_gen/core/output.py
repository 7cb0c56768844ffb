"""Writing outputs reproducibly: a staging folder that only moves into place on success, the JSON
manifest, binary PLY meshes and scalar maps (EXR with a greyscale PNG preview)."""
from __future__ import annotations

import contextlib
import errno
import json
import math
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Iterator

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


@dataclass(frozen=True)
class Banded:
    """A map made a band of rows at a time: ``rows(y0, y1)`` gives rows y0..y1 (float64) of a
    ``shape`` map, so a 16384-pixel map is written without holding it in float64."""
    shape: tuple[int, int]
    rows: Callable[[int, int], np.ndarray]


#: Rows per band of a Banded map
_BAND_ROWS = 256


def _preview_step(shape: tuple[int, ...], max_side: int) -> int:
    return max(1, int(math.ceil(max(shape) / max_side)))


def _save_preview(path: Path, sample: np.ndarray, lo: float, hi: float) -> None:
    """The PNG of the map's every step-th texel, stretched to the map's own [lo, hi]."""
    from PIL import Image

    grey = np.zeros_like(sample) if hi <= lo else (sample - lo) / (hi - lo)
    img = (np.nan_to_num(grey) * 255.0 + 0.5).astype(np.uint8)
    Image.fromarray(img).save(path, format="PNG", optimize=False)


def write_preview(path: Path, values: np.ndarray, max_side: int = 512) -> None:
    """An 8-bit greyscale PNG of a map, stretched to its own range and shrunk to ``max_side``:
    for looking at, not for rendering (the EXR holds the physical values)."""
    v = np.asarray(values, dtype=np.float64)
    step = _preview_step(v.shape, max_side)
    _save_preview(path, v[::step, ::step], float(np.nanmin(v)), float(np.nanmax(v)))


def write_map(stage: Path, name: str, values: np.ndarray | Banded, units: str, preview: bool,
              header: dict[str, object] | None = None) -> list[str]:
    """``name.exr`` (one float channel ``Y`` in ``units``) and optionally ``name.png``. A
    :class:`Banded` map gives the same two files, holding only its float32 copy whole."""
    from renderer.io.images import write_exr

    sample = None
    if isinstance(values, Banded):
        h, w = values.shape
        step = _preview_step(values.shape, 512)
        flat, sampled, lo, hi = np.empty((h, w), np.float32), [], np.inf, -np.inf
        for y0 in range(0, h, _BAND_ROWS):
            band = values.rows(y0, min(h, y0 + _BAND_ROWS))
            flat[y0:y0 + len(band)] = band
            if band.size and not np.all(np.isnan(band)):
                lo, hi = min(lo, float(np.nanmin(band))), max(hi, float(np.nanmax(band)))
            sampled.append(band[(-y0) % step::step, ::step])   # the rows y = 0, step, 2 step, ...
        sample, values = np.concatenate(sampled), flat
    write_exr(stage / f"{name}.exr", {"Y": np.asarray(values, dtype=np.float32)},
              {"units": units, **(header or {})})
    if not preview:
        return [f"{name}.exr"]
    if sample is None:
        write_preview(stage / f"{name}.png", values)
    else:
        _save_preview(stage / f"{name}.png", sample, lo, hi)
    return [f"{name}.exr", f"{name}.png"]
