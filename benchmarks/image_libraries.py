"""Image readers compared on what issue 32 asks of them: peak memory, time and formats. Each
(reader, file) pair decodes in its own process; the table gives the peak resident memory above
the process's size after importing the reader (VmHWM, so a decode's transient copies count),
the wall time and the decoded array.

    python benchmarks/image_libraries.py [--out out/image_libraries]   # writes the test images first

Readers: OpenImageIO in strips of rows into one array (what renderer/io/images.py does), its
whole-image read_image, Pillow's np.asarray, OpenEXR's channel read. Files: a 16384x8192 8-bit RGB
PNG (the issue's environment map), a 12000x12000 8-bit RGB PNG and a one-channel one (its
texture), an 8192x4096 float32 RGB EXR, and small .hdr, .pfm and .tga files for the formats."""
from __future__ import annotations

import argparse
import subprocess
import sys
from pathlib import Path

import numpy as np

DECODE = r'''
import sys, time
import numpy as np
reader, path = sys.argv[1], sys.argv[2]

def hwm():
    """This process's own peak resident memory, MB (ru_maxrss would carry the parent's over exec)."""
    line = [ln for ln in open("/proc/self/status") if ln.startswith("VmHWM:")][0]
    return int(line.split()[1]) / 1024

if reader.startswith("oiio"):
    import OpenImageIO as oiio
    from renderer.io.images import read_stored
    import renderer.device.machine   # read_stored's memory check imports it: a render has it already
elif reader == "pillow":
    from PIL import Image
    Image.MAX_IMAGE_PIXELS = None
else:
    import OpenEXR
base = hwm()
t = time.perf_counter()
if reader == "oiio-strips":
    a = read_stored(path)
elif reader == "oiio-whole":
    inp = oiio.ImageInput.open(path)
    spec = inp.spec()
    a = inp.read_image(0, 0, 0, spec.nchannels, "uint8" if spec.format.basetype == oiio.UINT8 else "float")
    inp.close()
elif reader == "pillow":
    with Image.open(path) as im:
        a = np.asarray(im)
else:
    with OpenEXR.File(path, separate_channels=True) as f:
        a = np.stack([np.asarray(c.pixels) for c in f.channels().values()], -1)
dt = time.perf_counter() - t
print(f"{hwm() - base:.0f} {dt:.2f} {a.dtype} {a.nbytes / 2**20:.0f}")
'''


def _pattern(h: int, w: int, c: int) -> np.ndarray:
    """Deterministic, partly compressible 8-bit content."""
    y, x = np.indices((h, w), dtype=np.uint32)
    return np.stack([(((x * (k + 3) + y * (7 - k)) >> 4) ^ ((x // 97 + y // 89) * 37 + k)) & 255
                     for k in range(c)], -1).astype(np.uint8)


def write_inputs(out: Path) -> dict[str, Path]:
    from PIL import Image
    import OpenImageIO as oiio

    from renderer.io.images import write_exr

    files = {"env 16384x8192 RGB PNG": out / "env16k.png", "texture 12000x12000 RGB PNG": out / "tex12k.png",
             "texture 12000x12000 grey PNG": out / "tex12k_grey.png", "8192x4096 float RGB EXR": out / "env8k.exr",
             ".hdr 2048x1024": out / "env.hdr", ".pfm 2048x1024": out / "env.pfm", ".tga 2048x1024": out / "env.tga"}
    for key, (h, w, c) in {"env 16384x8192 RGB PNG": (8192, 16384, 3), "texture 12000x12000 RGB PNG": (12000, 12000, 3),
                           "texture 12000x12000 grey PNG": (12000, 12000, 1)}.items():
        if not files[key].exists():
            Image.fromarray(_pattern(h, w, c).squeeze()).save(files[key], compress_level=1)
    floats = np.random.default_rng(0).random((4096, 8192, 3), dtype=np.float32) * 4
    if not files["8192x4096 float RGB EXR"].exists():
        write_exr(files["8192x4096 float RGB EXR"], floats)
    for key in (".hdr 2048x1024", ".pfm 2048x1024", ".tga 2048x1024"):
        data = floats[:1024, :2048] if key != ".tga 2048x1024" else _pattern(1024, 2048, 3)
        spec = oiio.ImageSpec(2048, 1024, 3, "uint8" if data.dtype == np.uint8 else "float")
        writer = oiio.ImageOutput.create(str(files[key]))
        writer.open(str(files[key]), spec)
        writer.write_image(data)
        writer.close()
    return files


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("out/image_libraries"))
    args = ap.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    files = write_inputs(args.out)
    print("| file | reader | peak above baseline, MB | seconds | decoded |")
    print("|---|---|---|---|---|")
    for key, path in files.items():
        readers = ["oiio-strips", "oiio-whole", "openexr" if path.suffix == ".exr" else "pillow"]
        for reader in readers:
            run = subprocess.run([sys.executable, "-c", DECODE, reader, str(path)], capture_output=True, text=True)
            if run.returncode:
                last = (run.stderr.strip().splitlines() or ["failed"])[-1]
                print(f"| {key} | {reader} | refused: {last[:80]} | | |")
                continue
            peak, seconds, dtype, mb = run.stdout.split()
            print(f"| {key} | {reader} | {peak} | {seconds} | {dtype}, {mb} MB |")


if __name__ == "__main__":
    main()
