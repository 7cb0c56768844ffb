"""How much memory a scene will take to render, estimated from its description before anything
is allocated, so a scene that cannot fit is refused with a number instead of ending in an
out-of-memory kill halfway through an upload.

The estimate counts the large arrays only, each as many times as it is held at the peak of an
upload: meshes on the host and on the device plus Warp's BVH nodes; instances with their
transforms and the top-level BVH; image textures and environment maps (8-bit files as bytes,
others as float32, with their sampling CDFs); media grids; the film's float64 sums; the wavefront's
path state (about 200 bytes per pixel, all of it live for a whole pass). Image sizes come from
file headers (no decoding). It is meant to be within a factor of two of the
measured peak (tests check it against real renders), which is enough to tell a 2 GB scene
from a 40 GB one."""
from __future__ import annotations

from pathlib import Path

from renderer.device.machine import machine_memory
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
#: a float texture's texel, per channel kept (one or three): float32, held in the decoded image,
#: the linear copy and the device pool
_TEXEL = 4 * 3
#: a float environment texel: its RGB plus its CDF entry, held about three times while uploading
_ENV_TEXEL = 16 * 3
#: an 8-bit file's texels stay 8-bit (one byte per channel, renderer/io/images.py): held on the
#: host and again on a CUDA device; an 8-bit environment texel adds its float32 CDF entry, twice
_CODE_BYTE = 2
_ENV_CDF = 4 * 2
#: a film pixel: a pass's float64 RGB scratch (24 B), the fixed-point int64 RGB sums, whole and
#: fraction (48 B), its int64 ray count (8 B) and the float32 image (12 B)
_PIXEL = 92
#: what the process itself takes before a scene (Python, numpy, Warp, the kernels)
_BASE = 300 * 2**20


def image_size(path: Path) -> tuple[int, int]:
    """(width, height) of an image file from its header; (0, 0) when it cannot be read (reading it
    for real reports the error with the scene's location)."""
    return _header(path)[:2]


def _header(path: Path) -> tuple[int, int, int, bool]:
    from renderer.io.images import image_header

    try:
        return image_header(path)
    except OSError:   # the real read reports it properly
        return 0, 0, 0, False


def _images(desc: SceneDescription) -> list[tuple[str, Path, int, int, int, object]]:
    """(what, path, width, height, bytes per texel, scene location) of every image texture and
    environment map."""
    found = []
    for t in desc.textures.values():
        name = t.params.params.get("filename")
        if t.kind == "imagemap" and name is not None and name.values:
            path = t.base_dir / str(name.values[0])
            w, h, c, eight_bit = _header(path)
            per = (1 if c < 3 else 3) * (_CODE_BYTE if eight_bit else _TEXEL)
            found.append(("texture image", path, w, h, per, t.loc))
    for light in desc.lights:
        fname = light.values.get("filename") if light.kind == "infinite" else None
        if fname:
            w, h, c, eight_bit = _header(Path(fname))
            per = (1 if c < 3 else 3) * _CODE_BYTE + _ENV_CDF if eight_bit else _ENV_TEXEL
            found.append(("environment image", Path(fname), w, h, per, light.loc))
    return found


def estimate(desc: SceneDescription, width: int, height: int, wavefront: bool = False) -> int:
    """Bytes the render of ``desc`` at width x height is expected to hold at its peak, with the
    wavefront integrator's path buffers if ``wavefront``: a path per pixel, as a CUDA render (one
    chunk of rows) holds them; CPU workers hold one chunk each, a fraction of that."""
    total = _BASE + width * height * _PIXEL
    if wavefront:
        from renderer.device.scene import uses_media
        from renderer.integrators.path_state import FIRST_KIND, bytes_per_path
        from renderer.materials import lobe_features, scatters_below

        films = lobe_features(desc.materials)
        kinds = len({m.kind for m in desc.materials})            # a shading queue each, at most
        kinds += films["layered"] and films["unlayered"]         # thin films that walk apart from the others
        bumped = any(m.values.get("displacement") is not None for m in desc.materials)
        total += width * height * bytes_per_path(True, FIRST_KIND + kinds, bumped, uses_media(desc),
                                                 scatters_below(desc.materials))
    for m in desc.meshes:
        total += 2 * len(m.positions) * _VERTEX + len(m.indices) * (2 * _TRIANGLE + _BVH_PER_TRIANGLE)
    total += sum(len(s.transforms) * len(s.shapes) for s in desc.instance_sets) * _INSTANCE
    total += sum(w * h * per for _, _, w, h, per, _ in _images(desc))
    total += sum(2 * m.grid_bytes() for m in desc.media)        # a medium's grids: host arrays, device volumes
    return total


def check_fits(desc: SceneDescription, width: int, height: int, limit_bytes: int | None = None,
               wavefront: bool = False) -> int:
    """The estimate, or RenderError if it exceeds ``limit_bytes`` (default: this machine's memory).
    When one image takes most of it, the message names that file: it is what the user must change."""
    need = estimate(desc, width, height, wavefront)
    limit = machine_memory() if limit_bytes is None else limit_bytes
    if need > limit:
        biggest = max(_images(desc), key=lambda i: i[2] * i[3] * i[4], default=None)
        culprit, where = "", desc.path or "the scene"
        if biggest is not None and 2 * biggest[2] * biggest[3] * biggest[4] > need - _BASE:   # most of the scene
            what, path, w, h, per, loc = biggest
            where = loc or where
            culprit = f" (the {what} {path}, {w}x{h} pixels by its header, about {w * h * per / 2**30:.1f} GiB of it)"
        raise RenderError(f"{where}: rendering needs about {need / 2**30:.1f} GiB{culprit}, more "
                          f"than the {limit / 2**30:.1f} GiB limit (this machine's memory unless --memory-limit says "
                          "otherwise); lower the resolution, texture sizes or instance counts, or raise the limit")
    return need
