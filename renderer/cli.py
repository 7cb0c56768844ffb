"""``render scene.pbrt -o out.exr``: the command-line renderer.

Exit codes: 0 done; 2 bad scene or arguments (one line per error, naming file:line); 3 the image was
written but some samples were NaN/Inf and were dropped; 130 interrupted by SIGINT (Ctrl-C) and
143 by SIGTERM, after writing what was rendered (and the checkpoint, if one was asked for).
"""
from __future__ import annotations

import argparse
import os
import signal
import sys
import tempfile
import time
import traceback
import warnings
from pathlib import Path
from typing import Any, Callable

from renderer.io.progress import Progress

EXIT_OK, EXIT_BAD_INPUT, EXIT_BAD_SAMPLES = 0, 2, 3
#: --write-partial-images: how often the image is rewritten, in seconds.
PARTIAL_EVERY = 60.0


def _resolution(text: str) -> tuple[int, int]:
    try:
        w, h = (int(x) for x in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"resolution must look like 640x360, got {text!r}") from None
    from renderer.errors import RenderError
    from renderer.settings import check_resolution

    try:
        check_resolution(w, h)
    except RenderError as e:
        raise argparse.ArgumentTypeError(str(e)) from None
    return w, h


#: PNG exposure beyond this many stops (a factor of 2^64 either way) is surely a typo.
MAX_EXPOSURE = 64.0


def _exposure(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"exposure must be a number of stops, got {text!r}") from None
    if not abs(v) <= MAX_EXPOSURE:                  # also refuses nan
        raise argparse.ArgumentTypeError(f"exposure must be between -{MAX_EXPOSURE:g} and {MAX_EXPOSURE:g} stops, "
                                         f"got {text!r}")
    return v


def _four_numbers(words: list[str], kind: type, what: str) -> tuple:
    """pbrt's ``x0,x1,y0,y1`` (commas or spaces: ``--cropwindow 0 .5 0 .5`` too)."""
    from renderer.errors import RenderError

    parts = [w for word in words for w in word.replace(",", " ").split()]
    try:
        values = tuple(kind(v) for v in parts)
    except ValueError:
        raise RenderError(f"{what} must be 4 numbers x0,x1,y0,y1, got {' '.join(words)!r}") from None
    if len(values) != 4:
        raise RenderError(f"{what} must be 4 numbers x0,x1,y0,y1, got {len(values)}")
    return values


def _aov_list(text: str) -> tuple[str, ...]:
    from renderer.integrators.aov import AOV_NAMES

    names = tuple(n.strip() for n in text.split(",") if n.strip())
    bad = [n for n in names if n not in AOV_NAMES]
    if bad:
        raise argparse.ArgumentTypeError(f"unknown AOV {bad}; choose from {', '.join(AOV_NAMES)}")
    return names


def _number(kind: type, ok: Callable[[Any], bool], what: str) -> Callable[[str], Any]:
    """An argparse type: ``text`` as ``kind``, refused with "``what``, got ..." unless ``ok``."""
    def parse(text: str) -> Any:
        try:
            v = kind(text)
        except ValueError:
            v = None
        if v is None or not ok(v):
            raise argparse.ArgumentTypeError(f"{what}, got {text!r}")
        return v
    return parse


_positive = _number(int, lambda v: v >= 1, "must be a whole number of at least 1")
_gib = _number(float, lambda v: 0.0 < v < 2.0**40, "memory limit must be a positive number of GiB")   # no nan, inf


def build_parser() -> argparse.ArgumentParser:
    from renderer.sampling.sampler_spec import DEFAULT_SAMPLER, RANDOMIZATIONS

    p = argparse.ArgumentParser(prog="render", description="Render a pbrt-v4 scene with the Warp path tracer.")
    p.add_argument("scene", type=Path, help="pbrt-v4 scene file")
    p.add_argument("-o", "--output", type=Path, help="output .exr (linear float) or .png (sRGB); "
                   "default: the scene's Film filename")
    p.add_argument("--spp", type=int, help="samples per pixel (default: the scene's Sampler pixelsamples)")
    p.add_argument("--res", type=_resolution, help="resolution WxH (default: the scene's Film)")
    p.add_argument("--device", default="cpu", help="Warp device: cpu, cuda, cuda:N (default: cpu)")
    p.add_argument("--seed", type=int, help="random seed (default: the scene's Sampler seed)")
    p.add_argument("--max-depth", type=int, help="maximum path depth (default: the scene's Integrator maxdepth)")
    p.add_argument("--exposure", type=_exposure, default=0.0, help="PNG exposure in stops (default: 0)")
    p.add_argument("--threads", type=int, help="CPU worker threads (default: all cores)")
    p.add_argument("--memory-limit", type=_gib, metavar="GIB", help="refuse a scene estimated to need more "
                   "memory than this (default: this machine's memory)")
    p.add_argument("--no-nee", action="store_true", help="BSDF sampling only (no light sampling): for checks")
    p.add_argument("--rr-depth", type=int, help="Russian roulette from this path depth on (default 4; -1: off)")
    p.add_argument("--cropwindow", nargs="+", metavar="X0,X1,Y0,Y1",
                   help="render only this part of the image, as fractions in [0, 1] (as pbrt-v4; overrides the Film's)")
    p.add_argument("--pixelbounds", nargs="+", metavar="X0,X1,Y0,Y1",
                   help="render only these pixels, ends exclusive (as pbrt-v4; overrides the Film's)")
    p.add_argument("--quick", action="store_true", help="as pbrt-v4: a quarter of the resolution and 1 spp")
    p.add_argument("--sampler", choices=list(RANDOMIZATIONS), help="pbrt-v4 sampler instead of the scene's "
                   f"(default: the scene's Sampler, else {DEFAULT_SAMPLER})")
    p.add_argument("--thin-film", metavar="MODE", help="thinfilm colour: rgb3 (the seed's 3 wavelengths), "
                   "spectral:N (N jittered wavelengths; default spectral:32) or table[:N] (per-material tables "
                   "over the angle from the 1 nm reference; spectral:N, default 32, for textured coatings)")
    p.add_argument("--multiscatter", action="store_true", help="rough dielectric, conductor and thinfilm: count the "
                   "bounces between microfacets on every material (energy compensation; pbrt-v4 files cannot "
                   "carry the parameter)")
    p.add_argument("--wavefront", action=argparse.BooleanOptionalAction, default=None,
                   help="the wavefront integrator (small kernels per step and material; the default with a CUDA "
                   "device) or, with --no-wavefront, the megakernel (the CPU's default); the image is the same")
    g = p.add_argument_group("long renders")
    g.add_argument("--time-limit", type=float, metavar="SECONDS", help="stop after the pass that crosses this")
    g.add_argument("--checkpoint", type=Path, metavar="PATH", help="write the accumulation here (atomically)")
    g.add_argument("--checkpoint-every", type=float, default=300.0, metavar="SECONDS",
                   help="checkpoint interval (default: 300); a checkpoint is also written at the end")
    g.add_argument("--resume", type=Path, metavar="PATH", help="continue from this checkpoint")
    g.add_argument("--write-partial-every", type=float, metavar="SECONDS", help="keep the output image current")
    g.add_argument("--write-partial-images", action="store_true",
                   help=f"as pbrt-v4: write the image periodically (every {PARTIAL_EVERY:g} s, or as "
                        "--write-partial-every says)")
    g.add_argument("--aov", type=_aov_list, default=(), metavar="LIST",
                   help="extra EXR layers: albedo,normal,depth,material,instance (ids at pixel centres, -1: none)")
    g.add_argument("--denoise", action="store_true", help="denoise with Intel OIDN (pip install '.[denoise]')")
    g.add_argument("--reference", type=Path, metavar="REF.exr", help="reference image for --error-log")
    g.add_argument("--error-log", type=Path, metavar="CSV", help="append spp,seconds,relMSE rows as passes finish")
    r = p.add_argument_group("cluster (Ray; pip install '.[cluster]')")
    r.add_argument("--ray", nargs="?", const="local", metavar="ADDRESS", help="render on Ray: no address starts a "
                   "local instance, auto joins `ray start`'s cluster, ray://host:port a remote one")
    r.add_argument("--ray-chunk", type=_positive, metavar="SPP", help="samples per pixel per task "
                   "(default: about 30 s of work each)")
    r.add_argument("--ray-workers", type=_positive, metavar="N", help="tasks in flight (default: one per CPU, "
                   "or per GPU with --device cuda; --threads sets each task's CPUs)")
    c = p.add_argument_group("CUDA ahead of time (no GPU needed)")
    c.add_argument("--compile-only", action="store_true", help="with --device cuda: compile every kernel a render "
                   "of the scene launches into the kernel cache ($WARP_CACHE_PATH), print each one's registers, "
                   "local memory, code size and compile time, and render nothing")
    c.add_argument("--arch", metavar="LIST", help="architectures for --compile-only, e.g. sm_75,sm_86,sm_90 "
                   "(default: this machine's GPU, else sm_90)")
    p.add_argument("--quiet", action="store_true", help="no progress output")
    p.add_argument("--stats", action="store_true", help="as pbrt-v4: print statistics at the end (scene, rays, "
                   "memory, time per phase)")
    p.add_argument("--display-server", metavar="HOST:PORT", help="as pbrt-v4: show each pass in the tev viewer "
                   "(pip install '.[tev]')")
    p.add_argument("--debug", action="store_true", help="show tracebacks")
    return p


class _StopSignals:
    """SIGINT/SIGTERM handling for the whole command, installed before the scene is read.

    While loading and compiling, a signal ends the process at once with its exit code (nothing has
    been written, and unwinding through a library mid-import or mid-compile is not reliable: an
    interrupt raised there sometimes surfaced again at interpreter exit). While rendering, the
    first sets ``signum`` and the render stops after the pass in flight; a second stops that pass
    too (the session keeps the finished ones). While writing, and after a signal has decided the
    exit, further signals are ignored, so the image and checkpoint are always written whole and the
    exit code stays 128 + the first signal's number. Handlers are restored on exit unless a signal
    arrived (the process is then on its way out)."""

    def __init__(self):
        self.signum: int | None = None
        self.phase = "load"

    def __enter__(self) -> "_StopSignals":
        self.saved = {s: signal.signal(s, self._handle) for s in (signal.SIGINT, signal.SIGTERM)}
        return self

    def _handle(self, signum, frame) -> None:
        first = self.signum is None
        self.signum = self.signum or signum
        if self.phase == "load" and first:
            print("render: interrupted before any pass finished; nothing written", file=sys.stderr, flush=True)
            os._exit(128 + signum)
        if self.phase == "render":
            if not first:
                raise KeyboardInterrupt       # caught by the session after the pass in flight
            print(f"\nrender: {signal.Signals(signum).name}: finishing the current pass, then writing",
                  file=sys.stderr, flush=True)

    def __exit__(self, *exc) -> None:
        for s, h in self.saved.items():
            signal.signal(s, h if self.signum is None else signal.SIG_IGN)


def _check_writable(path: Path, what: str) -> None:
    """Fail before the first pass, not after the last, when ``path`` cannot be written: its folder
    is made (as the writers would) and a temporary file is created and removed there."""
    from renderer.errors import RenderError
    from renderer.scene.parser import shown_path

    try:
        if path.is_dir():
            raise IsADirectoryError(f"{shown_path(path)} is a folder")
        path.parent.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=path.parent):
            pass
    except OSError as e:
        raise RenderError(f"cannot write the {what} {shown_path(path)}: {e.strerror or e}") from None


def write_outputs(path: Path, img, layers: dict, exposure: float, header: dict) -> None:
    from renderer.integrators.aov import AOV_CHANNELS
    from renderer.io.images import write_exr, write_png

    if path.suffix.lower() == ".exr":
        chans = {c: img[..., i] for i, c in enumerate("RGB")}
        for name, data in layers.items():
            names = AOV_CHANNELS.get(name, ("R", "G", "B"))
            chans.update({f"{name}.{c}": data[..., i] for i, c in enumerate(names)})
        write_exr(path, chans, header)
    else:
        write_png(path, img, exposure)


def _apply_region(scene, args: argparse.Namespace):
    """pbrt-v4's precedence: --cropwindow, then --pixelbounds, then the Film's crop window, then its
    pixel bounds. Returns the rule giving the rendered region at a resolution (errors if empty)."""
    from renderer.errors import RenderError
    from renderer.scene.imaging import film_region

    if args.cropwindow:
        crop = _four_numbers(args.cropwindow, float, "--cropwindow")
        if not all(0.0 <= v <= 1.0 for v in crop) or crop[0] >= crop[1] or crop[2] >= crop[3]:
            raise RenderError(f"--cropwindow must be x0 < x1, y0 < y1 in [0, 1], got {crop}")
        scene.film.crop_window, scene.film.pixel_bounds = crop, None
    elif args.pixelbounds:
        scene.film.pixel_bounds = _four_numbers(args.pixelbounds, int, "--pixelbounds")
        scene.film.crop_window = None
    return lambda width, height: film_region(scene.film, width, height)


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    # colour-science warns at import that matplotlib (plotting, unused here) is missing: the user
    # of the command should see only its own messages
    warnings.filterwarnings("ignore", message='"Matplotlib" related API features are not available')
    from renderer.errors import RenderError

    with _StopSignals() as stop:
        try:
            return _run(args, stop)
        except (RenderError, ValueError, OSError) as e:
            if args.debug:
                traceback.print_exc()
            for line in str(e).splitlines() or [type(e).__name__]:   # SceneErrors: one located error per line
                print(f"render: error: {line}", file=sys.stderr)
            return EXIT_BAD_INPUT
        except KeyboardInterrupt:
            print("render: interrupted before any pass finished; nothing written", file=sys.stderr)
            return 128 + (stop.signum or signal.SIGINT)


def _run(args: argparse.Namespace, stop: _StopSignals) -> int:
    """The command after its arguments are parsed; errors and interrupts are main's."""
    from renderer.api import load_scene, open_session, settings_for
    from renderer.errors import RenderError
    from renderer.io.checkpoint import save_checkpoint
    from renderer.io.metrics import relative_mse
    from renderer.scene.parser import shown_path
    from renderer.session import RenderSession

    for what, path in (("reference image", args.reference), ("checkpoint", args.resume)):
        if path is not None and not path.is_file():
            raise RenderError(f"{what} not found: {path}")
    clock0 = time.perf_counter()
    scene = load_scene(args.scene)
    if args.multiscatter:
        from renderer.materials import with_multiscatter

        scene = with_multiscatter(scene)
    phases = {"Scene parsing and building": time.perf_counter() - clock0}
    out = args.output or Path(scene.film.filename)
    if out.suffix.lower() not in (".exr", ".png"):
        source = "" if args.output else " (the scene's Film \"filename\"; choose another with -o)"
        raise RenderError(f"output must end in .exr or .png, got {shown_path(out)}{source}")
    if args.aov and out.suffix.lower() != ".exr":
        raise RenderError(f"--aov layers need an .exr output, not {shown_path(out)}")
    if args.error_log and not args.reference:
        raise RenderError("--error-log needs --reference REF.exr")
    w, h = args.res or (None, None)
    region = _apply_region(scene, args)
    if args.quick:          # pbrt-v4's --quick: resolution / 4 and one sample per pixel
        w, h = max(1, (w or scene.film.width) // 4), max(1, (h or scene.film.height) // 4)
        args.spp = 1
    settings = settings_for(scene, seed=args.seed, width=w, height=h, max_depth=args.max_depth, nee=not args.no_nee,
                            rr_depth=args.rr_depth, thin_film=args.thin_film, sampler=args.sampler)
    x0, x1, y0, y1 = region(settings.width, settings.height)       # an empty region fails here
    if args.compile_only or args.arch:
        from renderer.device.cuda_compile import compile_scene

        if not args.compile_only:
            raise RenderError("--arch needs --compile-only")
        say = (lambda _m: None) if args.quiet else (lambda m: print(m, file=sys.stderr, flush=True))
        print(compile_scene(scene, settings, args.device, args.arch, args.wavefront, bool(args.aov or args.denoise),
                            say))
        return EXIT_OK
    ref = None
    if args.reference:
        from renderer.io.images import read_image

        ref = read_image(args.reference)[..., :3]
        if ref.shape[:2] != (y1 - y0, x1 - x0):
            raise RenderError(f"reference {args.reference} is {ref.shape[1]}x{ref.shape[0]}, "
                              f"not the rendered {x1 - x0}x{y1 - y0}")
    for what, path in (("output", out), ("checkpoint", args.checkpoint), ("error log", args.error_log)):
        if path is not None:
            _check_writable(path, what)
    if args.ray is None and (args.ray_chunk or args.ray_workers):
        raise RenderError("--ray-chunk and --ray-workers need --ray")
    if args.ray is not None and args.wavefront is not None:
        raise RenderError("--wavefront/--no-wavefront choose the integrator of one process; Ray workers use their "
                          "device's (the wavefront on a GPU, the megakernel on CPUs: the same image)")
    display = None
    if args.display_server:             # before the upload, so a wrong address fails at once
        from renderer.io.display import DisplayServer

        display = DisplayServer(args.display_server, out.name, x1 - x0, y1 - y0)
    if args.ray is not None:
        from renderer.cluster import Cluster, open_cluster

        session = open_cluster(scene, settings, Cluster(args.ray, args.ray_chunk, args.ray_workers),
                               device=args.device, threads=args.threads, resume=args.resume)
    else:
        session = open_session(scene, settings, device=args.device, threads=args.threads, resume=args.resume,
                               memory_limit_gb=args.memory_limit, wavefront=args.wavefront,
                               aov=bool(args.aov or args.denoise))
    phases["Upload (Warp start, geometry, textures, lights)"] = time.perf_counter() - clock0 - sum(phases.values()) \
        - session.stats.compile_seconds
    phases["Kernel load"] = session.stats.compile_seconds
    for w in session.stats.warnings:
        print(f"warning: {w}", file=sys.stderr)
    passes = [0]
    if args.resume:
        print(f"render: resumed {args.resume} at {session.film.spp} spp", file=sys.stderr)
    spp = scene.sampler.spp if args.spp is None else args.spp
    prog = Progress(not args.quiet, spp, session.film.spp)
    clock = {"checkpoint": time.perf_counter(), "partial": time.perf_counter()}
    partial_every = args.write_partial_every or (PARTIAL_EVERY if args.write_partial_images else None)

    def on_pass(s: RenderSession) -> None:
        prog(s.film.spp, f"{s.busy} tasks busy" if args.ray is not None else "")
        passes[0] += 1
        if display is not None:
            display.show(s.image())
        now = time.perf_counter()
        if args.checkpoint and now - clock["checkpoint"] >= args.checkpoint_every:
            save_checkpoint(args.checkpoint, s.state())
            clock["checkpoint"] = now
        if partial_every and now - clock["partial"] >= partial_every:
            write_outputs(out, s.image(), {}, args.exposure, header(s))
            clock["partial"] = now
        if args.error_log:
            new = not args.error_log.exists()
            with open(args.error_log, "a") as f:
                if new:
                    f.write("spp,seconds,relmse\n")
                f.write(f"{s.film.spp},{s.stats.seconds:.4f},{relative_mse(s.image(), ref):.6g}\n")

    full = (0, settings.width, 0, settings.height)
    # a crop is written as pbrt-v4 writes it: its pixels, placed in the full frame
    windows = {} if (x0, x1, y0, y1) == full else {
        "dataWindow": ((x0, y0), (x1 - 1, y1 - 1)), "displayWindow": ((0, 0), (settings.width - 1, settings.height - 1))}

    def header(s: RenderSession) -> dict:
        return {**s.stats.header(), "seed": settings.seed, "scene": str(args.scene), "sceneHash": s.fingerprint,
                "renderer": "summertime", **windows}

    stop.phase = "render"
    try:
        stats = session.run(spp, time_limit=args.time_limit, on_pass=on_pass,
                            should_stop=lambda: stop.signum is not None)
    finally:
        stop.phase = "finish"
        prog.close()
        if display is not None:
            display.close()
    clock0 = time.perf_counter()
    img = session.image()
    layers: dict = {}
    if args.aov or args.denoise:
        local = session if args.ray is None else open_session(scene, settings, args.device, args.threads, aov=True)
        aovs = local.aovs()
        layers = {k: aovs[k] for k in args.aov}
        if args.denoise:
            from renderer.io.denoise import denoise

            layers["noisy"] = img
            img = denoise(img, aovs["albedo"], aovs["normal"])
    write_outputs(out, img, layers, args.exposure, header(session))
    if args.checkpoint:
        save_checkpoint(args.checkpoint, session.state())
    print(f"wrote {out}: {stats.width}x{stats.height}, {stats.spp} spp in {stats.seconds:.2f} s "
          f"(+{stats.compile_seconds:.2f} s kernel load), {stats.samples_per_second / 1e6:.3f} M samples/s, "
          f"{stats.rays_per_second / 1e6:.3f} M rays/s, peak memory {stats.peak_memory_mb:.0f} MB",
          file=sys.stderr)
    for line in session.summary() if args.ray is not None else ():
        print(f"render: {line}", file=sys.stderr)
    if args.stats:
        from renderer.io.statistics import report

        phases["Rendering"] = stats.seconds
        phases["Image output"] = time.perf_counter() - clock0
        print(report(scene, settings, session, phases, passes[0]))           # stdout, as pbrt-v4
    if stats.spp < spp:
        limited = "time limit" if args.time_limit is not None else "interrupt"
        why = signal.Signals(stop.signum).name if stop.signum else limited
        print(f"render: stopped by {why} at {stats.spp}/{spp} spp", file=sys.stderr)
    if stop.signum is not None:
        return 128 + stop.signum
    if stats.interrupted:
        return 128 + signal.SIGINT
    if stats.bad_samples:
        print(f"warning: dropped {stats.bad_samples} NaN/Inf/negative samples (not averaged into the image)",
              file=sys.stderr)
        return EXIT_BAD_SAMPLES
    return EXIT_OK


if __name__ == "__main__":
    sys.exit(main())
