"""How much memory a scene will take to render, estimated from its description before anything
is allocated, so a scene that cannot fit is refused with a number instead of ending in an
out-of-memory kill halfway through an upload.

The estimate counts the large arrays only, each as many times as it is held at the peak of an
upload: meshes on the host and on the device plus Warp's BVH nodes; instances with their
transforms and the top-level BVH; image textures and environment maps decoded to float32, then
pooled and copied to the device (with their sampling CDFs); the film's float64 sums. Image
sizes come from file headers (no decoding). It is meant to be within a factor of two of the
measured peak (tests check it against real renders), which is enough to tell a 2 GB scene
from a 40 GB one."""
from __future__ import annotations

import os
from pathlib import Path

from renderer.errors import RenderError
from renderer.scene.description import SceneDescription

#: bytes per vertex (float32 position, normal, uv) and per triangle (int32 indices) of a mesh
_VERTEX, _TRIANGLE = 32, 12
#: Warp's BVH: about two nodes of two float32 bounds per triangle, on the device
_BVH_PER_TRIANGLE = 64
#: one instance: float64 transforms on the host (read, checked, flattened), float32 world and
#: object matrices and bounds on the device, and its top-level BVH nodes (measured: about 880
#: bytes each at 800,000 instances)
_INSTANCE = 900
#: a decoded RGB float32 texel, held in the decoded image, the texture pool and the device copy
_TEXEL = 12 * 3
#: an environment texel: its RGB plus its CDF entry, held about three times while uploading
_ENV_TEXEL = 16 * 3
#: a film pixel: float64 RGB sums plus the float32 image and per-row scratch
_PIXEL = 48
#: what the process itself takes before a scene (Python, numpy, Warp, the kernels)
_BASE = 300 * 2**20


def machine_memory() -> int:
    """This machine's physical memory in bytes."""
    return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")


def image_size(path: Path) -> tuple[int, int]:
    """(width, height) of an image file from its header; (0, 0) when it cannot be read (reading it
    for real reports the error with the scene's location)."""
    try:
        if path.suffix.lower() == ".exr":
            import OpenEXR

            with OpenEXR.File(str(path), header_only=True) as f:
                lo, hi = f.header()["dataWindow"]
                return int(hi[0] - lo[0] + 1), int(hi[1] - lo[1] + 1)
        from PIL import Image

        with Image.open(path) as im:
            return im.size
    except Exception:   # any decoder's error: the real read reports it properly
        return 0, 0


def _images(desc: SceneDescription) -> list[tuple[str, Path, int, int, object]]:
    """(what, path, width, height, scene location) of every image texture and environment map."""
    found = []
    for t in desc.textures.values():
        name = t.params.params.get("filename")
        if t.kind == "imagemap" and name is not None and name.values:
            path = t.base_dir / str(name.values[0])
            found.append(("texture image", path, *image_size(path), t.loc))
    for light in desc.lights:
        fname = light.values.get("filename") if light.kind == "infinite" else None
        if fname:
            found.append(("environment image", Path(fname), *image_size(Path(fname)), light.loc))
    return found


def _image_bytes(what: str, width: int, height: int) -> int:
    return width * height * (_TEXEL if what == "texture image" else _ENV_TEXEL)


def estimate(desc: SceneDescription, width: int, height: int) -> int:
    """Bytes the render of ``desc`` at width x height is expected to hold at its peak."""
    total = _BASE + width * height * _PIXEL
    for m in desc.meshes:
        total += 2 * len(m.positions) * _VERTEX + len(m.indices) * (2 * _TRIANGLE + _BVH_PER_TRIANGLE)
    total += sum(len(s.transforms) * len(s.shapes) for s in desc.instance_sets) * _INSTANCE
    total += sum(_image_bytes(what, w, h) for what, _, w, h, _ in _images(desc))
    return total


def check_fits(desc: SceneDescription, width: int, height: int, limit_bytes: int | None = None) -> int:
    """The estimate, or RenderError if it exceeds ``limit_bytes`` (default: this machine's memory).
    When one image takes most of it, the message names that file: it is what the user must change."""
    need = estimate(desc, width, height)
    limit = machine_memory() if limit_bytes is None else limit_bytes
    if need > limit:
        biggest = max(_images(desc), key=lambda i: _image_bytes(i[0], i[2], i[3]), default=None)
        culprit, where = "", desc.path or "the scene"
        if biggest is not None and 2 * _image_bytes(biggest[0], biggest[2], biggest[3]) > need:
            what, path, w, h, loc = biggest
            where = loc or where
            culprit = (f" (the {what} {path}, {w}x{h} pixels by its header, about "
                       f"{_image_bytes(what, w, h) / 2**30:.1f} GiB of it)")
        raise RenderError(f"{where}: rendering needs about {need / 2**30:.1f} GiB{culprit}, more "
                          f"than the {limit / 2**30:.1f} GiB limit (this machine's memory unless --memory-limit says "
                          "otherwise); lower the resolution, texture sizes or instance counts, or raise the limit")
    return need
