"""Render pbrt-v4's own image of every small test scene in this folder: ``<name>.pbrt`` → ``<name>.exr``.

The EXRs are committed, so tests compare against pbrt-v4 without needing it. Run this only to
(re)make them, on a machine with the pbrt-v4 binary (``../shared/tools/pbrt-v4/pbrt.gz``, see its
README for the shared libraries it needs). A scene sets its sample count with a first-lines comment
``# reference-spp: N`` (default 1024); the seed is 1. With ``# reference-seeds: K`` it is rendered K
times, with seeds 1..K, into ``<name>.exr``, ``<name>-2.exr``, ...: the images' differences give
pbrt's own noise (its spectral sampling makes it differ from ours), for tests to size tolerances.
A pbrt-v3 scene, marked ``# reference-upgrade: 1``, is first converted with ``pbrt --upgrade`` into
``<name>_upgraded.pbrt`` (committed too: tests compare our reading of the v3 file with it); its
images, still ``<name>.exr`` ..., are rendered from that file, and only if it gives a reference-spp.

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


def header_number(scene: Path, key: str, default: int) -> int:
    """``# key: N`` from the scene's first lines."""
    for line in scene.read_text().splitlines()[:5]:
        m = re.match(rf"#\s*{key}:\s*(\d+)", line)
        if m:
            return int(m.group(1))
    return default


def reference_spp(scene: Path) -> int:
    return header_number(scene, "reference-spp", DEFAULT_SPP)


def reference_images(scene: Path) -> list[Path]:
    """The EXRs a scene's references go to, one per seed (seed 1 first)."""
    k = header_number(scene, "reference-seeds", 1)
    return [scene.with_suffix(".exr")] + [scene.with_name(f"{scene.stem}-{i}.exr") for i in range(2, k + 1)]


def upgraded(scene: Path, exe: Path) -> Path | None:
    """For a pbrt-v3 scene, pbrt-v4's ``--upgrade`` of it, written beside it; None for others."""
    if not header_number(scene, "reference-upgrade", 0):
        return None
    out = scene.with_name(f"{scene.stem}_upgraded.pbrt")
    print(f"{scene.name}: pbrt --upgrade -> {out.name}", flush=True)
    text = subprocess.run([str(exe), "--upgrade", str(scene)], check=True, cwd=HERE, stdout=subprocess.PIPE,
                          text=True).stdout
    out.write_text(text)
    return out


def main(names: list[str]) -> int:
    scenes = [HERE / f"{n}.pbrt" for n in names] if names else \
        sorted(s for s in HERE.glob("*.pbrt") if not s.stem.endswith("_upgraded"))
    exe = pbrt_binary()
    for scene in scenes:
        source = upgraded(scene, exe)
        if source is not None and header_number(scene, "reference-spp", 0) == 0:
            continue
        spp = reference_spp(scene)
        for seed, out in enumerate(reference_images(scene), 1):
            print(f"{scene.name}: {spp} spp, seed {seed} -> {out.name}", flush=True)
            subprocess.run([str(exe), "--quiet", "--spp", str(spp), "--seed", str(seed), "--outfile", str(out),
                            str(source or scene)], check=True, cwd=HERE)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
