"""Write media_vdb.nvdb, the NanoVDB density grid media_vdb.pbrt reads: a 12^3 blob (fixed seed)
saved by Warp, with its grid named "density" (pbrt-v4 looks the grid up by that name; Warp writes
none). Not committed (300 KB): render_references.py needs it made first, and the test makes its
own copy with ``write_grid``.

    python tests/data/pbrt/make_media_vdb.py
"""
from __future__ import annotations

import struct
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent


def _name_key(name: str) -> int:
    """NanoVDB's stringHash of a grid name, which its reader compares with the file's."""
    h = 0
    for ch in name.encode():
        h = (h * 67 + ch + (h >> 56)) & 0xFFFFFFFFFFFFFFFF
    return h


def write_grid(path: Path) -> Path:
    import warp as wp

    n = 12
    c = (np.arange(n) + 0.5) / n
    x, y, z = np.meshgrid(c, c, c, indexing="ij")
    rng = np.random.default_rng(30)
    g = (6 * np.exp(-((x - 0.5) ** 2 + (y - 0.45) ** 2 + (z - 0.5) ** 2) / 0.07) * (0.7 + 0.3 * rng.random(x.shape)))
    vol = wp.Volume.load_from_numpy(g.astype(np.float32), min_world=(-0.6, 0.05, -0.6), voxel_size=0.1, bg_value=0.0,
                                    device="cpu")
    vol.array().numpy()[40:48] = np.frombuffer(b"density\x00", np.uint8)     # GridData's name (CPU: shared memory)
    vol.save_to_nvdb(str(path))
    raw = bytearray(path.read_bytes())
    raw[32:40] = struct.pack("<Q", _name_key("density"))     # the file's metadata: nameKey after two sizes
    path.write_bytes(bytes(raw))
    return path


if __name__ == "__main__":
    write_grid(HERE / "media_vdb.nvdb")
