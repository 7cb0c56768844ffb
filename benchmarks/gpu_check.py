"""``make gpu-check``: what only an NVIDIA GPU can tell, in one report (out/gpu-check/report.md).

No machine of this project has a GPU, so none of this has run on one; a user with a GPU runs it
and sends the report. In order:

1. the device, the driver and Warp;
2. every render kernel of every scene in ``scenes/`` compiled for the GPU (``--compile-only``'s
   table: registers, stack frame, code, NVRTC seconds);
3. the tests that render (furnaces, energy, determinism, resume, Ray) with ``--device cuda``;
4. every scene on the CPU and on the GPU, compared within noise: the GPU image's RMS difference
   from the CPU image of the same seed, over the RMS difference between two CPU images of
   different seeds (about 1 when the GPU draws from the same distribution; the same seed does
   not give the same bits, as floating-point contraction differs between the devices);
5. throughput and time to error against Mitsuba 3's ``cuda_ad_rgb`` on the scenes the benchmarks
   share with ``llvm_ad_rgb`` (Mitsuba traces with OptiX, on RT cores where the GPU has them;
   Warp's BVH runs on the ordinary cores);
6. the beach's final frame (1080x1920) at 4096 spp, timed.

``--device cpu`` runs the same steps on the CPU (a dry run of the pipeline); without a GPU,
``--device cuda`` stops at once with exit code 2."""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
os.environ.setdefault("WARP_CACHE_PATH", str(ROOT / ".warp-cache"))
sys.path[:0] = [str(ROOT)]

#: The tests that render, run on the GPU by ``pytest --device cuda`` (tests/conftest.py).
DEVICE_TESTS = ("tests/integrators", "tests/materials", "tests/lights", "tests/cli/test_long_render.py",
                "tests/cluster")
#: The noise ratio above which a scene's GPU image is reported as differing from its CPU image.
NOISE_RATIO_LIMIT = 1.5


def require_gpu(device: str) -> None:
    import warp as wp

    from renderer.device.runtime import init_warp

    init_warp()
    if device.startswith("cuda") and not wp.is_cuda_available():
        print("gpu-check: no CUDA GPU on this machine (Warp found no NVIDIA driver or device); it needs one. "
              "`render SCENE --device cuda --compile-only` compiles for a GPU without one.", file=sys.stderr)
        sys.exit(2)


def device_section(device: str) -> list[str]:
    import warp as wp

    d = wp.get_device(device)
    rt = wp._src.context.runtime
    return ["## Device", "", f"- {d.alias}: {d.name}" + (f", sm_{d.arch}" if d.is_cuda else ""),
            f"- Warp {wp.__version__}, CUDA toolkit {rt.toolkit_version}, driver {rt.driver_version}", ""]


def scenes() -> list[Path]:
    return sorted((ROOT / "scenes").glob("*.pbrt"))


def prepare_assets(scene: Path) -> None:
    """The scene's generated assets (its recipe's final level), as a user's render needs them."""
    if scene.with_suffix(".recipe.json").is_file():
        subprocess.run([sys.executable, "-m", "assets_gen", "recipe", str(scene)], check=True,
                       stdout=subprocess.DEVNULL)


def compile_section(device: str, paths: list[Path]) -> list[str]:
    import warp as wp

    from renderer.api import load_scene, settings_for
    from renderer.device.cuda_compile import DEFAULT_ARCH, compile_kernels, table
    from renderer.device.scene import upload
    from renderer.integrators.kernels import render_kernels

    arch = wp.get_device(device).arch if device.startswith("cuda") else DEFAULT_ARCH
    out = ["## Kernels compiled for the GPU", ""]
    for path in paths:
        desc = load_scene(path)
        settings = settings_for(desc)
        ds = upload(desc, "cpu", 8, 8, thin_film=settings.thin_film)
        kernels = render_kernels(ds.features, settings.sampler.name == "independent", wavefront=True)
        rows = compile_kernels(kernels, [arch], lambda m: print(m, file=sys.stderr, flush=True))
        out += [f"### {path.name}", "", table(rows), ""]
    return out


def tests_section(device: str) -> list[str]:
    done = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "--device", device,
                           *DEVICE_TESTS], cwd=ROOT, capture_output=True, text=True)
    summary = done.stdout.strip().splitlines()[-1] if done.stdout.strip() else done.stderr.strip()[-400:]
    failed = [line for line in done.stdout.splitlines() if line.startswith("FAILED")]
    return ["## Tests on the device", "", f"`pytest --device {device} {' '.join(DEVICE_TESTS)}`: {summary}", "",
            *[f"- {line}" for line in failed], ""]


def _render(path: Path, device: str, seed: int, spp: int, width: int) -> tuple[np.ndarray, float]:
    from renderer.api import load_scene, render

    desc = load_scene(path)
    height = max(1, round(width * desc.film.height / desc.film.width))
    t0 = time.perf_counter()
    img = render(desc, spp=spp, device=device, seed=seed, width=width, height=height)
    return img, time.perf_counter() - t0


def scenes_section(device: str, paths: list[Path], spp: int, width: int) -> list[str]:
    out = ["## Every scene on the CPU and on the device", "",
           f"{width} pixels wide, {spp} spp. ratio = RMS(device - CPU, seed 1) / RMS(CPU seed 2 - CPU seed 1): "
           f"about 1 when both sample the same image; above {NOISE_RATIO_LIMIT} is flagged.", "",
           "| scene | CPU s | device s | speed-up | ratio | verdict |", "|---|---:|---:|---:|---:|---|"]
    for path in paths:
        cpu1, t_cpu = _render(path, "cpu", 1, spp, width)
        cpu2, _ = _render(path, "cpu", 2, spp, width)
        _render(path, device, 1, 1, width)                      # load (or compile) the kernels untimed
        dev1, t_dev = _render(path, device, 1, spp, width)
        noise = float(np.sqrt(np.mean((cpu2 - cpu1) ** 2)))
        diff = float(np.sqrt(np.mean((dev1 - cpu1) ** 2)))
        ratio = diff / noise if noise > 0 else (0.0 if diff == 0 else float("inf"))
        verdict = "same within noise" if ratio <= NOISE_RATIO_LIMIT else "DIFFERS"
        out.append(f"| {path.name} | {t_cpu:.1f} | {t_dev:.1f} | {t_cpu / t_dev:.1f}x | {ratio:.2f} | {verdict} |")
        print(out[-1], file=sys.stderr, flush=True)
    return out + [""]


def mitsuba_section(device: str, variant: str, report_dir: Path) -> list[str]:
    runs = [("Throughput (benchmarks/throughput.py)",
             ["benchmarks/throughput.py", "--device", device, "--mitsuba-variants", f"{variant},llvm_ad_rgb"]),
            ("Time to error (benchmarks/time_to_error.py)",
             ["benchmarks/time_to_error.py", "--device", device, "--mitsuba-variant", variant,
              "--out", str(report_dir / "time_to_error")])]
    out = [f"## Against Mitsuba 3 ({variant})", "",
           "Mitsuba traces rays with OptiX, which uses the RT cores where the GPU has them; Warp's BVH runs on "
           "the GPU's ordinary cores.", ""]
    for title, cmd in runs:
        done = subprocess.run([sys.executable, *cmd], cwd=ROOT, capture_output=True, text=True)
        out += [f"### {title}", "", done.stdout.strip() or f"failed: {done.stderr.strip()[-600:]}", ""]
    return out


def beach_section(device: str, spp: int, report_dir: Path) -> list[str]:
    beach = ROOT / "scenes" / "beach.pbrt"
    prepare_assets(beach)
    image = report_dir / "beach_final.exr"
    t0 = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "renderer", str(beach), "-o", str(image), "--device", device,
                           "--spp", str(spp), "--res", "1080x1920", "--quiet"], cwd=ROOT, capture_output=True, text=True)
    seconds = time.perf_counter() - t0
    return ["## The beach's final frame", "", f"1080x1920, {spp} spp on {device}: {seconds:.0f} s whole process "
            f"(exit {done.returncode}): {done.stderr.strip().splitlines()[-1] if done.stderr.strip() else ''}", ""]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--device", default="cuda")
    ap.add_argument("--out", type=Path, default=ROOT / "out" / "gpu-check")
    ap.add_argument("--spp", type=int, default=64, help="spp of the scene comparisons (default 64)")
    ap.add_argument("--width", type=int, default=160, help="width of the scene comparisons (default 160)")
    ap.add_argument("--beach-spp", type=int, default=4096)
    ap.add_argument("--mitsuba-variant", default="cuda_ad_rgb")
    ap.add_argument("--scenes", nargs="*", help="scene files (default: every scene in scenes/)")
    ap.add_argument("--skip", nargs="*", default=[], choices=["compile", "tests", "scenes", "mitsuba", "beach"])
    a = ap.parse_args()
    require_gpu(a.device)
    a.out.mkdir(parents=True, exist_ok=True)
    paths = [Path(p).resolve() for p in a.scenes] if a.scenes is not None else scenes()
    for p in paths:
        prepare_assets(p)
    report = ["# gpu-check", "", *device_section(a.device)]
    steps = {"compile": lambda: compile_section(a.device, paths), "tests": lambda: tests_section(a.device),
             "scenes": lambda: scenes_section(a.device, paths, a.spp, a.width),
             "mitsuba": lambda: mitsuba_section(a.device, a.mitsuba_variant, a.out),
             "beach": lambda: beach_section(a.device, a.beach_spp, a.out)}
    for name, step in steps.items():
        if name in a.skip:
            continue
        print(f"gpu-check: {name} ...", file=sys.stderr, flush=True)
        report += step()
        (a.out / "report.md").write_text("\n".join(report) + "\n")      # what is done so far survives a failure
    print(f"gpu-check: wrote {a.out / 'report.md'}", file=sys.stderr)


if __name__ == "__main__":
    main()
