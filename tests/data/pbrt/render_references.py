"""Render pbrt-v4's own image of every small test scene in this folder: ``<name>.pbrt`` → ``<name>.exr``.

The EXRs are committed, so tests compare against pbrt-v4 without needing it. Run this only to
(re)make them, on a machine with the pbrt-v4 binary (``../shared/tools/pbrt-v4/pbrt.gz``, see its
README for the shared libraries it needs). A scene sets its sample count with a first-lines comment
``# reference-spp: N`` (default 1024); the seed is always 1.

    python tests/data/pbrt/render_references.py [name ...]     # no names: every scene here
"""
from __future__ import annotations

import gzip
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
PACKED = HERE.parents[2].parent / "shared" / "tools" / "pbrt-v4" / "pbrt.gz"
DEFAULT_SPP = 1024


def pbrt_binary() -> Path:
    """$PBRT if set, else the packed binary unpacked once into /tmp."""
    if os.environ.get("PBRT"):
        return Path(os.environ["PBRT"])
    exe = Path("/tmp/pbrt-v4")
    if not exe.exists():
        with gzip.open(PACKED) as src, open(exe, "wb") as dst:
            shutil.copyfileobj(src, dst)
        exe.chmod(0o755)
    return exe


def reference_spp(scene: Path) -> int:
    head = scene.read_text().splitlines()[:5]
    for line in head:
        m = re.match(r"#\s*reference-spp:\s*(\d+)", line)
        if m:
            return int(m.group(1))
    return DEFAULT_SPP


def main(names: list[str]) -> int:
    scenes = [HERE / f"{n}.pbrt" for n in names] if names else sorted(HERE.glob("*.pbrt"))
    exe = pbrt_binary()
    for scene in scenes:
        out = scene.with_suffix(".exr")
        spp = reference_spp(scene)
        print(f"{scene.name}: {spp} spp -> {out.name}", flush=True)
        subprocess.run([str(exe), "--spp", str(spp), "--seed", "1", "--outfile", str(out), str(scene)],
                       check=True, cwd=HERE)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
