"""What the render kernels will cost on a GPU, for every scene in ``scenes/`` and for a kernel
with every feature at once (every material, light, bump, cut-outs, mixes, subsurface,
dispersion, media): ``--compile-only``'s table from a cold kernel cache, so the compile seconds are
NVRTC's own. No GPU needed.

    python benchmarks/gpu_kernels.py [--arch sm_90] [--scenes scenes/demo.pbrt ... every] [--aov] [--megakernel]
                                     [--kernels 'shade_*' ...] [--out out/gpu_kernels.md]

``--scenes`` names scene files, and ``every`` for the every-feature kernels (by default: every scene
in ``scenes/`` and ``every``); ``--kernels`` keeps only the kernels whose names match one of its
patterns (``fnmatch``), to measure one kernel while changing it.

A CUDA render launches the wavefront's kernels; ``--megakernel`` compiles the one-kernel
integrator instead (the CPU's default), for the comparison in docs/gpu.md.

Scenes with a recipe need their assets (``assets-gen recipe SCENE``) first."""
from __future__ import annotations

import argparse
import fnmatch
import os
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT)]


def scene_features(path: Path):
    from renderer.api import load_scene, settings_for
    from renderer.device.scene import upload

    desc = load_scene(path)
    settings = settings_for(desc)
    return upload(desc, "cpu", 8, 8, thin_film=settings.thin_film).features, settings.sampler.name == "independent"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--arch", default="sm_90")
    ap.add_argument("--scenes", nargs="*", help="scene files and 'every' (default: every scene in scenes/, every)")
    ap.add_argument("--kernels", nargs="*", help="only the kernels whose names match one of these patterns")
    ap.add_argument("--out", type=Path, default=ROOT / "out" / "gpu_kernels.md")
    ap.add_argument("--cache", type=Path, help="kernel cache to fill (default: a new, empty one)")
    ap.add_argument("--aov", action="store_true", help="also the AOV kernel (what --aov and --denoise launch)")
    ap.add_argument("--megakernel", action="store_true", help="the megakernel instead of the wavefront's kernels")
    a = ap.parse_args()
    os.environ["WARP_CACHE_PATH"] = str(a.cache or tempfile.mkdtemp(prefix="gpu_kernels_"))
    from renderer.device.cuda_compile import compile_kernels, every_feature, parse_archs, table
    from renderer.integrators.kernels import render_kernels

    archs = parse_archs(a.arch)
    names = a.scenes if a.scenes is not None else [*sorted(map(str, (ROOT / "scenes").glob("*.pbrt"))), "every"]
    jobs = [("every feature", every_feature(), False) if n == "every" else (Path(n).name, *scene_features(Path(n)))
            for n in names]
    say = lambda m: print(m, file=sys.stderr, flush=True)  # noqa: E731
    parts = [f"Kernel cache: {os.environ['WARP_CACHE_PATH']} (cold at the start; a kernel two scenes share "
             "compiles once and shows as cached the second time)", ""]
    for name, features, independent in jobs:
        say(f"== {name}: {features}")
        kernels = render_kernels(features, independent, aov=a.aov, wavefront=not a.megakernel)
        if a.kernels:
            kernels = {k: v for k, v in kernels.items() if any(fnmatch.fnmatch(k, pat) for pat in a.kernels)}
        rows = compile_kernels(kernels, archs, say)
        parts += [f"### {name}", "", table(rows), ""]
        a.out.parent.mkdir(parents=True, exist_ok=True)
        a.out.write_text("\n".join(parts) + "\n")
        print("\n".join(parts[-4:]), flush=True)
    say(f"wrote {a.out}")


if __name__ == "__main__":
    main()
