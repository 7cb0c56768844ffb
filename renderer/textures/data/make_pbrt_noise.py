"""Extract pbrt-v4's Perlin-noise permutation table from its source into ``pbrt_noise.json``, the
table ``renderer.textures.noise`` reads.

pbrt-v4 (github.com/mmp/pbrt-v4, Apache-2.0) defines ``NoisePerm`` in ``src/pbrt/util/noise.cpp``:
Perlin's permutation of 0..255, written out twice. Its noise, FBm and turbulence textures (fbm,
wrinkled, windy, marble, dots) only reproduce pbrt's images with exactly this table, so it is taken
as pbrt ships it rather than typed in. Run with a pbrt-v4 checkout:

    python renderer/textures/data/make_pbrt_noise.py PATH/TO/pbrt-v4/src/pbrt/util/noise.cpp
"""
from __future__ import annotations

import json
import re
import sys
from pathlib import Path


def extract(source: str) -> list[int]:
    """The 512 entries of ``NoisePerm``; checked to be a permutation of 0..255 written twice."""
    m = re.search(r"NoisePerm\[2 \* NoisePermSize\] = \{(.*?)\};", source, flags=re.S)
    if m is None:
        raise SystemExit("NoisePerm not found")
    body = re.sub(r"//[^\n]*", "", m.group(1))
    perm = [int(x) for x in re.findall(r"\d+", body)]
    if len(perm) != 512 or sorted(perm[:256]) != list(range(256)) or perm[:256] != perm[256:]:
        raise SystemExit(f"NoisePerm is not a permutation of 0..255 written twice ({len(perm)} entries)")
    return perm


if __name__ == "__main__":
    data = {"source": "pbrt-v4 src/pbrt/util/noise.cpp NoisePerm (github.com/mmp/pbrt-v4, Apache-2.0)",
            "perm": extract(Path(sys.argv[1]).read_text())}
    (Path(__file__).parent / "pbrt_noise.json").write_text(json.dumps(data) + "\n")
