"""``render scene.pbrt -o out.exr``: the command-line renderer.

Exit codes: 0 success, 2 bad scene or arguments (one line naming file:line), 3 the image has
dropped NaN/Inf samples (written anyway, with a warning), 130 interrupted (what was rendered is
written).
"""
from __future__ import annotations

import argparse
import sys
import time
import traceback
from pathlib import Path

EXIT_OK, EXIT_BAD_INPUT, EXIT_BAD_SAMPLES, EXIT_INTERRUPTED = 0, 2, 3, 130


def _resolution(text: str) -> tuple[int, int]:
    try:
        w, h = (int(x) for x in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"resolution must look like 640x360, got {text!r}") from None
    if w < 1 or h < 1:
        raise argparse.ArgumentTypeError(f"resolution must be positive, got {text!r}")
    return w, h


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="render", description="Render a pbrt-v4 scene with the Warp path tracer.")
    p.add_argument("scene", type=Path, help="pbrt-v4 scene file")
    p.add_argument("-o", "--output", type=Path, help="output .exr (linear float) or .png (sRGB); "
                   "default: the scene's Film filename")
    p.add_argument("--spp", type=int, help="samples per pixel (default: the scene's Sampler pixelsamples)")
    p.add_argument("--res", type=_resolution, help="resolution WxH (default: the scene's Film)")
    p.add_argument("--device", default="cpu", help="Warp device: cpu, cuda, cuda:N (default: cpu)")
    p.add_argument("--seed", type=int, help="random seed (default: the scene's Sampler seed)")
    p.add_argument("--max-depth", type=int, help="maximum path depth (default: the scene's Integrator maxdepth)")
    p.add_argument("--exposure", type=float, default=0.0, help="PNG exposure in stops (default: 0)")
    p.add_argument("--threads", type=int, help="CPU worker threads (default: all cores)")
    p.add_argument("--no-nee", action="store_true", help="BSDF sampling only (no light sampling): for checks")
    p.add_argument("--quiet", action="store_true", help="no progress output")
    p.add_argument("--debug", action="store_true", help="show tracebacks")
    return p


class _Progress:
    """A tqdm bar on a terminal, a plain line per ~10% otherwise (logs stay readable)."""

    def __init__(self, enabled: bool):
        self.enabled = enabled
        self.bar = None
        self.last = -1
        self.t0 = time.perf_counter()

    def __call__(self, done: int, total: int) -> None:
        if not self.enabled:
            return
        if sys.stderr.isatty():
            if self.bar is None:
                from tqdm import tqdm

                self.bar = tqdm(total=total, unit="spp", file=sys.stderr)
            self.bar.update(done - self.bar.n)
        else:
            decile = done * 10 // total
            if decile != self.last:
                self.last = decile
                el = time.perf_counter() - self.t0
                eta = el / done * (total - done)
                print(f"render: {done}/{total} spp, {el:.1f} s elapsed, ETA {eta:.1f} s", file=sys.stderr, flush=True)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def write_image(path: Path, img, exposure: float, header: dict) -> None:
    from renderer.imageio import write_exr, write_png

    if path.suffix.lower() == ".exr":
        write_exr(path, img, header)
    elif path.suffix.lower() == ".png":
        write_png(path, img, exposure)
    else:
        raise ValueError(f"output must end in .exr or .png, got {path}")


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    from renderer.errors import RenderError

    try:
        from renderer.api import RenderStats, load_scene, render

        scene = load_scene(args.scene)
        for w in scene.warnings:
            print(f"warning: {w}", file=sys.stderr)
        out = args.output or Path(scene.film.filename)
        if out.suffix.lower() not in (".exr", ".png"):
            raise RenderError(f"output must end in .exr or .png, got {out}")
        w, h = args.res or (None, None)
        stats = RenderStats()
        prog = _Progress(not args.quiet)
        try:
            img = render(scene, spp=args.spp, device=args.device, seed=args.seed, width=w, height=h,
                         max_depth=args.max_depth, nee=not args.no_nee, threads=args.threads,
                         progress=prog, stats=stats)
        finally:
            prog.close()
        seed = args.seed if args.seed is not None else scene.sampler.seed
        header = {"spp": stats.spp, "seed": seed, "renderTimeSeconds": round(stats.seconds, 3),
                  "scene": str(args.scene), "renderer": "summertime"}
        write_image(out, img, args.exposure, header)
        print(f"wrote {out}: {stats.width}x{stats.height}, {stats.spp} spp in {stats.seconds:.2f} s "
              f"(+{stats.compile_seconds:.2f} s kernel load), {stats.samples_per_second / 1e6:.3f} M samples/s",
              file=sys.stderr)
        if stats.interrupted:
            print(f"render: interrupted; wrote the {stats.spp} spp finished so far", file=sys.stderr)
            return EXIT_INTERRUPTED
        if stats.bad_samples:
            print(f"warning: dropped {stats.bad_samples} NaN/Inf/negative samples (not averaged into the image)",
                  file=sys.stderr)
            return EXIT_BAD_SAMPLES
        return EXIT_OK
    except (RenderError, ValueError, OSError) as e:
        if args.debug:
            traceback.print_exc()
        print(f"render: error: {e}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        print("render: interrupted before any pass finished; nothing written", file=sys.stderr)
        return EXIT_INTERRUPTED


if __name__ == "__main__":
    sys.exit(main())
