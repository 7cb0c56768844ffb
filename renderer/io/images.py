"""Reading and writing images: every format is read through OpenImageIO (in strips, at the file's
own precision); EXR is written through OpenEXR and PNG through Pillow. Writes are atomic."""
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


#: Rows per strip when decoding: a strip is the only temporary beside the image itself.
_STRIP_BYTES = 8 << 20


def _open(path: Path):
    """An OpenImageIO reader of ``path``, or OSError with the library's reason."""
    import OpenImageIO as oiio

    # our own budget applies (the memory check below and the scene's footprint, which names the
    # file and line), so OpenImageIO's is lifted: it refused to read even a header over it
    oiio.attribute("limits:imagesize_MB", 1 << 30)
    config = oiio.ImageSpec()
    config.attribute("oiio:UnassociatedAlpha", 1)   # the stored colour, not premultiplied by alpha
    with _quiet_decoders():
        reader = oiio.ImageInput.open(str(path), config)
    if reader is None:
        raise OSError(f"cannot read image {path}: {_library_error(oiio) or 'not a readable image'}")
    return reader


def _quiet_decoders():
    """libpng prints its errors to stderr itself ("libpng error: IEND: out of place") beside the
    same reason in our one-line refusal: its lines are dropped, anything else passes."""
    from renderer.io.native_stderr import native_stderr

    return native_stderr(keep=lambda line: not line.startswith("libpng "))


def _library_error(source) -> str:
    """The last error of OpenImageIO (or of one reader), read and cleared, as one line. Its message
    can quote the file's own bytes (a mangled attribute name), which the binding fails to decode as
    UTF-8: that message is replaced, not raised in place of ours."""
    try:
        message = source.geterror()
    except UnicodeDecodeError:
        return "the decoder's message is not text (a mangled header)"
    return " ".join(message.split())    # OpenImageIO's messages span lines; ours are one line each


def _channels(names: tuple[str, ...]) -> list[int]:
    """Which stored channels are the image's colour, in order: R, G, B, A where named so (EXR
    layers such as ``albedo.R`` are not colour), else every channel in name order (pbrt's choice)."""
    named = [names.index(c) for c in ("R", "G", "B", "A") if c in names]
    return named or sorted(range(len(names)), key=lambda i: names[i])


def image_header(path: str | Path) -> tuple[int, int, int, bool]:
    """(width, height, colour channels, 8-bit) from the file's header, nothing decoded."""
    import OpenImageIO as oiio

    path = Path(path)
    reader = _open(path)
    try:
        spec = reader.spec()
        return spec.width, spec.height, len(_channels(tuple(spec.channelnames))), spec.format.basetype == oiio.UINT8
    finally:
        reader.close()


def read_stored(path: str | Path, max_channels: int | None = None) -> np.ndarray:
    """The pixels as the file stores them, (H, W, C): uint8 codes for 8-bit files, uint16 for
    16-bit integer files, float32 otherwise (half widens exactly). ``max_channels`` keeps the
    first colour channels only. Decoded in strips of rows straight into the one result array, so
    the peak is the image plus a strip; refused naming the file when unreadable or when it could
    not fit this machine's memory."""
    import OpenImageIO as oiio

    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"image not found: {path}")
    reader = _open(path)
    try:
        spec = reader.spec()
        chans = _channels(tuple(spec.channelnames))[:max_channels]
        base = spec.format.basetype
        fmt, dtype = ((oiio.UINT8, np.uint8) if base == oiio.UINT8 else (oiio.UINT16, np.uint16)
                      if base == oiio.UINT16 else (oiio.FLOAT, np.float32))
        w, h, n = spec.width, spec.height, spec.nchannels
        need = w * h * len(chans) * np.dtype(dtype).itemsize
        from renderer.device.machine import machine_memory

        if w <= 0 or h <= 0 or not chans:
            raise OSError(f"cannot read image {path}: it holds no pixels ({w}x{h}, {n} channels)")
        if need > machine_memory():
            raise OSError(f"cannot read image {path}: {w}x{h} pixels of {len(chans)} channels need "
                          f"{need / 2**30:.1f} GiB, more than this machine's memory")
        out = np.empty((h, w, len(chans)), dtype)
        lo, hi = min(chans), max(chans) + 1
        pick = None if chans == list(range(lo, hi)) else [c - lo for c in chans]
        band = spec.tile_height if spec.tile_width else 1       # tiled files are read in whole tile rows
        step = band * max(1, _STRIP_BYTES // (w * band * (hi - lo) * out.itemsize))
        for y in range(0, h, step):
            y1 = min(h, y + step)
            with _quiet_decoders():
                if spec.tile_width:
                    strip = reader.read_tiles(0, 0, spec.x, spec.x + w, spec.y + y, spec.y + y1, spec.z,
                                              spec.z + max(1, spec.depth), lo, hi, fmt)
                else:
                    strip = reader.read_scanlines(0, 0, spec.y + y, spec.y + y1, spec.z, lo, hi, fmt)
            if strip is None:
                raise OSError(f"cannot read image {path}: {_library_error(reader) or 'its pixels are unreadable'}")
            strip = strip.reshape(y1 - y, w, hi - lo)
            out[y:y1] = strip if pick is None else strip[..., pick]
        return out
    except MemoryError as e:   # a valid (or lying) header asking for more than the machine has
        raise OSError(f"cannot read image {path}: not enough memory to decode it") from e
    except (TypeError, ValueError, RuntimeError) as e:   # the binding's own complaints about a bad file
        raise OSError(f"cannot read image {path}: {e or type(e).__name__}") from e
    finally:
        reader.close()
        _library_error(oiio)   # clear it: OpenImageIO complains at exit about unread errors


def code_values(srgb: bool | None) -> np.ndarray:
    """The linear value of each 8-bit code, float32 (256,): sRGB-decoded unless ``srgb`` is False.
    Decoding per code, not per pixel, keeps an 8-bit image 8-bit until a texel is looked up."""
    from renderer.color.rgb import srgb_to_linear

    codes = np.arange(256, dtype=np.float32) / 255.0
    return srgb_to_linear(codes) if srgb is not False else codes


def linear(stored: np.ndarray, srgb: bool | None) -> np.ndarray:
    """Float32 linear values of :func:`read_stored`'s pixels (8-bit: through :func:`code_values`)."""
    if stored.dtype == np.uint8:
        return code_values(srgb)[stored]
    if stored.dtype == np.uint16:
        return stored.astype(np.float32) / 65535.0
    return stored


def read_image(path: str | Path, *, srgb: bool | None = None) -> np.ndarray:
    """Any supported image (EXR, PNG, JPEG, TIFF, Radiance .hdr, .pfm, .tga, ... through
    OpenImageIO) as linear float32 (H, W, C). 8-bit images are decoded from sRGB unless ``srgb``
    is False; EXR, 16-bit and float images are taken as linear. A file the decoder refuses (empty,
    truncated, garbage, too big) raises OSError naming the file."""
    return linear(read_stored(path), srgb)


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
