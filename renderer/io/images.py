"""Reading and writing images: EXR through OpenEXR, PNG/JPEG through Pillow. Writes are atomic."""
from __future__ import annotations

import contextlib
import os
import tempfile
from pathlib import Path
from typing import Iterator

import numpy as np


@contextlib.contextmanager
def atomic_path(path: str | Path) -> Iterator[Path]:
    """Yield a temporary path beside ``path`` and rename it over ``path`` only if the body succeeds,
    so an interrupted write never leaves a truncated file."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=path.suffix, dir=path.parent)
    os.close(fd)
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp, 0o666 & ~umask)  # mkstemp makes 0600; the result should read like any new file
    try:
        yield Path(tmp)
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


_WINDOWS = ("dataWindow", "displayWindow")


def write_exr(path: str | Path, channels: dict[str, np.ndarray] | np.ndarray,
              header: dict[str, object] | None = None) -> None:
    """Write float32 channels (``{"R": (H, W), ...}``, or an (H, W, 3|1) array) with extra header fields.
    ``dataWindow``/``displayWindow`` (pairs of integer corners, inclusive) place a cropped image in
    its full frame, as pbrt-v4 writes a crop; other fields are written as numbers or strings."""
    import OpenEXR

    if isinstance(channels, np.ndarray):
        a = channels if channels.ndim == 3 else channels[..., None]
        names = "RGB" if a.shape[2] == 3 else ("Y" if a.shape[2] == 1 else "RGBA")
        channels = {n: a[..., i] for i, n in enumerate(names)}
    chans = {k: np.ascontiguousarray(v, dtype=np.float32) for k, v in channels.items()}
    hdr = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    for k, v in (header or {}).items():
        if k in _WINDOWS:
            hdr[k] = tuple(np.asarray(corner, dtype=np.int32) for corner in v)
        else:
            hdr[k] = str(v) if not isinstance(v, (int, float)) else float(v)
    with atomic_path(path) as tmp:
        with OpenEXR.File(hdr, chans) as f:
            f.write(str(tmp))


def read_exr(path: str | Path) -> tuple[dict[str, np.ndarray], dict[str, object]]:
    """Return ({channel: (H, W) float32}, header)."""
    import OpenEXR

    with OpenEXR.File(str(path), separate_channels=True) as f:
        chans = {k: np.array(c.pixels, dtype=np.float32) for k, c in f.channels().items()}
        return chans, dict(f.header())


def read_image(path: str | Path, *, srgb: bool | None = None) -> np.ndarray:
    """Any supported image as linear float32 (H, W, C). 8-bit images are decoded from sRGB unless
    ``srgb`` is False; EXR and 16-bit/float images are taken as linear. A file the decoders refuse
    (empty, truncated, garbage, a decompression bomb) raises OSError naming the file."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"image not found: {path}")
    try:
        return _decoded(path, srgb)
    except MemoryError as e:   # a valid (or lying) header asking for more than the machine has
        raise OSError(f"cannot read image {path}: not enough memory to decode it") from e
    except Exception as e:  # each decoder has its own exception types; all mean "not a readable image"
        raise OSError(f"cannot read image {path}: {e or type(e).__name__}") from e


def _decoded(path: Path, srgb: bool | None) -> np.ndarray:
    from renderer.color.rgb import srgb_to_linear

    if path.suffix.lower() == ".exr":
        chans, _ = read_exr(path)
        order = [c for c in ("R", "G", "B", "A") if c in chans] or sorted(chans)
        return np.stack([chans[c] for c in order], axis=-1)
    from PIL import Image

    with Image.open(path) as im:
        a = np.asarray(im)
    if a.ndim == 2:
        a = a[..., None]
    if a.dtype == np.uint8:
        codes = np.arange(256, dtype=np.float32) / 255.0
        lut = srgb_to_linear(codes) if srgb is not False else codes
        return lut[a]       # per code, not per pixel: colour's float64 decode peaked at 16x the float32 image
    if a.dtype == np.uint16:
        return a.astype(np.float32) / 65535.0
    return a.astype(np.float32)


def write_png(path: str | Path, rgb_linear: np.ndarray, exposure: float = 0.0) -> None:
    """Tone-map linear RGB to 8-bit sRGB (exposure in stops, then clip) and write it atomically."""
    from PIL import Image

    from renderer.color.rgb import linear_to_srgb

    x = np.nan_to_num(np.asarray(rgb_linear, dtype=np.float64), nan=0.0) * (2.0 ** exposure)
    img = (linear_to_srgb(x) * 255.0 + 0.5).astype(np.uint8)
    if img.ndim == 3 and img.shape[2] == 1:
        img = img[..., 0]
    with atomic_path(path) as tmp:
        Image.fromarray(img).save(tmp, format="PNG")
