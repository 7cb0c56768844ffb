"""A content hash of a scene, so a checkpoint is only resumed into the scene that made it."""
from __future__ import annotations

import dataclasses
import hashlib
from pathlib import Path
from typing import Any

import numpy as np

from renderer.scene.description import SceneDescription
from renderer.scene.params import ParamSet


def _feed(h: "hashlib._Hash", x: Any) -> None:
    if isinstance(x, np.ndarray):
        h.update(str((x.dtype.str, x.shape)).encode())
        h.update(np.ascontiguousarray(x).tobytes())
    elif isinstance(x, ParamSet):
        for name in sorted(x.params):
            p = x.params[name]
            _feed(h, (p.type, p.name, list(p.values)))
    elif isinstance(x, Path):
        # a referenced file counts by its bytes: editing a texture invalidates a checkpoint
        h.update(str(x).encode())
        if x.is_file():
            h.update(hashlib.sha256(x.read_bytes()).digest())
    elif dataclasses.is_dataclass(x):
        for f in dataclasses.fields(x):
            if f.name not in ("loc", "warnings", "path"):
                h.update(f.name.encode())
                _feed(h, getattr(x, f.name))
    elif isinstance(x, dict):
        for k in sorted(x):
            _feed(h, (k, x[k]))
    elif isinstance(x, (list, tuple)):
        h.update(b"[")
        for v in x:
            _feed(h, v)
        h.update(b"]")
    else:
        h.update(repr(x).encode())


def referenced_files(desc: SceneDescription) -> list[Path]:
    """The files the device upload reads (image textures, environment images, NanoVDB media),
    resolved, in scene order; meshes, instance transforms and dense grids are already arrays in
    the description."""
    files = []
    for t in desc.textures.values():
        name = t.params.params.get("filename")
        if name is not None:
            files.append((t.base_dir / str(name.values[0])).resolve())
    for light in desc.lights:
        if light.values.get("filename") is not None:
            files.append(Path(light.values["filename"]).resolve())
    files += [m.filename.resolve() for m in desc.media if m.filename is not None]
    return files


def scene_fingerprint(desc: SceneDescription) -> str:
    """SHA-256 over everything that determines the image (geometry, materials, textures and the
    files they name by their bytes, lights, camera), ignoring source locations and warnings."""
    h = hashlib.sha256()
    _feed(h, desc)
    for path in referenced_files(desc):
        _feed(h, path)
    return h.hexdigest()
