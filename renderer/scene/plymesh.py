"""pbrt's ``plymesh``: a PLY file (ASCII or binary) read with plyfile into a triangle mesh."""
from __future__ import annotations

import io
from pathlib import Path

import numpy as np
import plyfile

from renderer.errors import Location, SceneError
from renderer.scene.compressed import is_gzipped, read_bytes
from renderer.scene.description import MeshDesc
from renderer.scene.parser import require_file
from renderer.scene.params import ParamSet
from renderer.scene.shapes import validated_mesh

#: Vertex property pairs that exporters use for texture coordinates, in pbrt-v4's order of preference.
UV_NAMES = (("u", "v"), ("s", "t"), ("texture_u", "texture_v"), ("texture_s", "texture_t"))


def ply_mesh(params: ParamSet, loc: Location) -> MeshDesc:
    """The mesh of ``"string filename"``, resolved against the folder of the file that names it."""
    name = params.string("filename")
    if not name:
        raise SceneError('plymesh: "string filename" is required', loc)
    path = Path(loc.file).parent / name
    return read_ply(require_file(path, loc, "PLY mesh"), loc)


def read_ply(path: Path, loc: Location) -> MeshDesc:
    """Positions, optional nx/ny/nz normals and UVs; polygons are fanned into triangles (a quad
    becomes (0, 1, 2), (0, 2, 3), which keeps its winding). A ``.ply.gz`` is gunzipped first, as
    pbrt-v4 reads it, to at most MAX_PLY_BYTES. Errors name the PLY file and ``loc``."""
    data = read_bytes(path, MAX_PLY_BYTES, loc, "PLY mesh") if is_gzipped(path) else None
    _check_counts(path, data, loc)
    try:
        ply = _read_triangles(path) if data is None else None
        if ply is None:
            ply = plyfile.PlyData.read(io.BytesIO(data) if data is not None else str(path))
    except (plyfile.PlyParseError, plyfile.PlyHeaderParseError, ValueError, OSError) as e:
        raise SceneError(f"{path}: not a readable PLY file ({e})", loc) from e
    if "vertex" not in ply:
        raise SceneError(f'{path}: no "vertex" element', loc)
    vertex = ply["vertex"].data
    names = set(vertex.dtype.names or ())

    def columns(*keys: str) -> np.ndarray | None:
        return np.stack([vertex[k] for k in keys], -1).astype(np.float64) if names.issuperset(keys) else None

    P = columns("x", "y", "z")
    if P is None:
        raise SceneError(f"{path}: vertices lack x, y, z", loc)
    N = columns("nx", "ny", "nz")
    UV = next((uv for keys in UV_NAMES if (uv := columns(*keys)) is not None), None)
    F = _faces(ply, path, loc)
    return validated_mesh(P, F, N, UV, loc, f"plymesh {path.name}")


#: Bytes of each PLY scalar type, by every name the format allows.
_SIZES = {**dict.fromkeys(("char", "uchar", "int8", "uint8"), 1), **dict.fromkeys(("short", "ushort", "int16",
          "uint16"), 2), **dict.fromkeys(("int", "uint", "float", "int32", "uint32", "float32"), 4),
          **dict.fromkeys(("double", "float64"), 8)}
_MAX_HEADER = 1 << 16
#: The most a gzipped PLY may expand to in memory (2 GiB: far beyond the largest mesh of pbrt-v4-scenes).
MAX_PLY_BYTES = 1 << 31


def _check_counts(path: Path, data: bytes | None, loc: Location) -> None:
    """Refuse a header whose element counts need more bytes than the file has, before plyfile
    allocates for them: each element takes at least its scalars' bytes (binary) or two characters
    per property (ASCII: a digit and a separator); a list takes at least its count. ``data``: the
    decompressed bytes of a gzipped file (None: read the file itself)."""
    if data is not None:
        head, file_size = data[:_MAX_HEADER], len(data)
    else:
        with open(path, "rb") as f:
            head = f.read(_MAX_HEADER)
        file_size = path.stat().st_size
    end = head.find(b"end_header")
    if not head.startswith(b"ply") or end < 0:
        raise SceneError(f"{path}: not a readable PLY file (no 'ply ... end_header' header in its first 64 KiB)", loc)
    lines = head[:end].decode("ascii", errors="replace").splitlines()
    ascii_format = any(ln.split()[:2] == ["format", "ascii"] for ln in lines)
    counts: list[list[int]] = []
    for words in (ln.split() for ln in lines):
        if words[:1] == ["element"] and len(words) == 3 and words[2].isdigit():
            counts.append([int(words[2]), 0])
        elif words[:1] == ["property"] and counts and len(words) >= 3:
            size = _SIZES.get(words[2] if words[1] == "list" else words[1], 1)
            counts[-1][1] += 2 if ascii_format else size
    need = sum(n * max(per, 1) for n, per in counts)
    have = file_size - end
    if need > have:
        raise SceneError(f"{path}: the header declares {', '.join(str(n) for n, _ in counts)} elements, "
                         f"needing at least {need} bytes, but the file holds {have}", loc)


def _read_triangles(path: Path) -> plyfile.PlyData | None:
    """A binary PLY of triangles memory-mapped whole (plyfile's ``known_list_len``), or None when
    some face is not a triangle or the file is ASCII: plyfile otherwise reads a binary file's
    faces one by one in Python, seconds for the beach's million-triangle sand."""
    try:
        return plyfile.PlyData.read(str(path), known_list_len={"face": {"vertex_indices": 3, "vertex_index": 3}})
    except plyfile.PlyElementParseError:
        return None


def _faces(ply: plyfile.PlyData, path: Path, loc: Location) -> np.ndarray:
    if "face" not in ply:
        return np.zeros((0, 3), dtype=np.int64)
    face = ply["face"].data
    key = next((k for k in ("vertex_indices", "vertex_index") if k in (face.dtype.names or ())), None)
    if key is None:
        raise SceneError(f'{path}: faces lack a "vertex_indices" list', loc)
    polygons = face[key]
    if polygons.ndim == 2:                      # memory-mapped triangles (_read_triangles)
        return polygons.astype(np.int64)
    counts = np.fromiter((len(p) for p in polygons), dtype=np.int64, count=len(polygons))
    if np.any(counts < 3):
        raise SceneError(f"{path}: face {int(np.argmax(counts < 3))} has fewer than 3 vertices", loc)
    triangles, sources = [], []
    for k in np.unique(counts):
        faces = np.nonzero(counts == k)[0]
        group = np.stack(polygons[faces]).astype(np.int64)
        for i in range(1, k - 1):
            triangles.append(group[:, [0, i, i + 1]])
            sources.append(faces * len(polygons) + i)  # sorts triangles into the file's face order
    if not triangles:
        return np.zeros((0, 3), dtype=np.int64)
    return np.concatenate(triangles)[np.argsort(np.concatenate(sources), kind="stable")]
