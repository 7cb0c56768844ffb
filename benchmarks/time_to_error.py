"""Time to error: each of our samplers and Mitsuba 3's ``independent``, ``multijitter`` and
``ldsampler`` at equal spp, on small scenes, with whole-process seconds.

    python benchmarks/time_to_error.py [--scenes spheres thinfilm beach] [--out out/time_to_error]

Every run is its own process (import, scene load, cached-kernel load, render, image written)
that imports only its own renderer (the spheres' meshes are made once here and pickled),
timed from outside after one untimed warm-up run of the same configuration (so neither renderer
pays its first JIT/compile), as wall seconds and as the process's CPU seconds (user + system:
the fairer number on a machine other jobs share; both renderers use every core). Each renderer is compared with its own high-spp reference rendered
with its independent sampler, so a systematic difference between the two renderers does not count
as noise. relMSE is the study's (0.1 % largest per-pixel errors trimmed); efficiency = 1 / (relMSE
x seconds): equal efficiency means equal time to reach a given error. Writes a CSV, a Markdown
table and a plot. Scenes: "spheres" (diffuse and glass spheres under a sky and a sun, shared with
the Mitsuba cross-check), the thin-film figure and the beach (ours only: Mitsuba has neither the
thin-film material nor our pbrt scene reader)."""
from __future__ import annotations

import argparse
import csv
import os
import pickle
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
os.environ.setdefault("WARP_CACHE_PATH", str(ROOT / ".warp-cache"))
sys.path[:0] = [str(ROOT), str(ROOT / "tests")]

OURS = ("independent", "stratified", "halton", "sobol", "paddedsobol", "zsobol")
MITSUBA = ("independent", "multijitter", "ldsampler")
#: (resolution, spp of the runs, spp of the reference) per scene: small enough for two CPU cores.
SIZES = {"spheres": ((128, 96), 64, 4096), "thinfilm": ((128, 72), 32, 1024), "beach": ((54, 96), 16, 512)}
SEED, REF_SEED = 3, 99


def spheres_spec(res: tuple[int, int], spp: int):
    """Diffuse and glass spheres on a grey floor under a sky and a sun (the issue's scene)."""
    from crosscheck_scenes import Spec, floor, sphere

    sun = np.array([0.4, 1.0, -0.5])
    return Spec(objects=[sphere((-0.9, 0.0, 0.2), 0.6, rgb=(0.8, 0.3, 0.2)),
                         sphere((0.15, 0.05, -0.3), 0.55, subdiv=4, kind="dielectric", eta=1.5),
                         sphere((1.1, -0.1, 0.6), 0.5, rgb=(0.2, 0.5, 0.8)), floor(rgb=(0.6, 0.6, 0.6))],
                eye=(0.0, 1.0, -4.0), target=(0.0, -0.1, 0.0), width=res[0], height=res[1], sky=0.4,
                sun=(sun / np.linalg.norm(sun), 3.0), max_depth=8, spp=spp)


def _spec(path: Path):
    """The spheres' meshes and settings as the parent pickled them (made once, with trimesh), so
    that a child imports only its own renderer, as a user's process would."""
    with open(path, "rb") as f:
        return pickle.load(f)


def our_image(scene: str, sampler: str, spp: int, seed: int, spec: Path, device: str) -> np.ndarray:
    import renderer
    from renderer.session import RenderSession
    from renderer.settings import settings_for

    res = SIZES[scene][0]
    if scene == "spheres":
        from crosscheck_scenes import ours

        desc = ours(_spec(spec))
    else:
        desc = renderer.load_scene(ROOT / "scenes" / {"thinfilm": "fig1_thinfilm.pbrt", "beach": "beach.pbrt"}[scene])
    desc.sampler.spp = spp          # the sampler's pattern is the run's sample count, as pbrt's --spp
    s = RenderSession(desc, settings_for(desc, seed=seed, width=res[0], height=res[1], sampler=sampler), device=device)
    s.run(spp)
    return s.image()


def mitsuba_image(sampler: str, spp: int, seed: int, spec: Path, variant: str) -> np.ndarray:
    llvm19 = "/usr/lib/x86_64-linux-gnu/libLLVM-19.so"     # Dr.Jit's LLVM backend needs libllvm19 here
    if "DRJIT_LIBLLVM_PATH" not in os.environ and os.path.exists(llvm19):
        os.environ["DRJIT_LIBLLVM_PATH"] = llvm19
    import mitsuba as mi

    mi.set_variant(variant)
    from crosscheck_scenes import mitsuba_scene

    with tempfile.TemporaryDirectory() as tmp:
        scene = mitsuba_scene(_spec(spec), tmp, sampler=sampler)
        # mirrored in x relative to pbrt's LookAt (see the cross-check's docstring): flip back
        return np.asarray(mi.render(scene, spp=spp, seed=seed), dtype=np.float32)[:, ::-1, :3]


def child(argv: list[str]) -> None:
    """One configuration in this process: render and save the image as .npy."""
    who, scene, sampler, spp, seed, out, spec, device, variant = argv
    img = mitsuba_image(sampler, int(spp), int(seed), Path(spec), variant) if who == "mitsuba" else \
        our_image(scene, sampler, int(spp), int(seed), Path(spec), device)
    np.save(out, img)


def _children_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def spec_file(scene: str, spp: int, out: Path) -> Path:
    """The pickled spheres scene at ``spp`` (made here, outside the timed children)."""
    path = out / f"spec_{scene}_{spp}.pkl"
    if scene == "spheres" and not path.exists():
        with open(path, "wb") as f:
            pickle.dump(spheres_spec(SIZES[scene][0], spp), f)
    return path


#: Where each renderer runs: our Warp device and Mitsuba's variant (``make gpu-check``: cuda, cuda_ad_rgb).
TARGET = {"device": "cpu", "variant": "llvm_ad_rgb"}


def run(who: str, scene: str, sampler: str, spp: int, seed: int, out: Path) -> tuple[float, float]:
    """Whole-process (wall, CPU) seconds of one configuration."""
    spec = spec_file(scene, spp, out.parent)
    t0, c0 = time.perf_counter(), _children_cpu()
    subprocess.run([sys.executable, __file__, "--child", who, scene, sampler, str(spp), str(seed), str(out), str(spec),
                    TARGET["device"], TARGET["variant"]],
                   check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - t0, _children_cpu() - c0


def measure(scenes: list[str], out: Path) -> list[dict]:
    from renderer.io.metrics import relative_mse

    rows = []
    for scene in scenes:
        res, spp, ref_spp = SIZES[scene]
        for who, samplers in (("ours", OURS), ("mitsuba", MITSUBA if scene == "spheres" else ())):
            if not samplers:
                continue
            ref_path = out / f"ref_{who}_{scene}_{res[0]}x{res[1]}_{ref_spp}.npy"
            if not ref_path.exists():
                print(f"{scene}: {who} reference at {ref_spp} spp ...", flush=True)
                run(who, scene, "independent", ref_spp, REF_SEED, ref_path)
            ref = np.load(ref_path)
            for sampler in samplers:
                img_path = out / f"{who}_{scene}_{sampler}.npy"
                run(who, scene, sampler, spp, SEED, img_path)        # warm-up: compile / JIT caches
                seconds, cpu = run(who, scene, sampler, spp, SEED, img_path)
                err = relative_mse(np.load(img_path), ref, trim=1e-3)
                rows.append({"scene": scene, "renderer": who, "sampler": sampler, "res": f"{res[0]}x{res[1]}",
                             "spp": spp, "seconds": round(seconds, 3), "cpu_seconds": round(cpu, 3), "relmse": err,
                             "efficiency": 1.0 / (err * seconds), "cpu_efficiency": 1.0 / (err * cpu)})
                print(f"{scene:9s} {who:8s} {sampler:12s} {seconds:7.2f} s  {cpu:7.2f} cpu-s  relMSE {err:.3g}",
                      flush=True)
    return rows


def table(rows: list[dict]) -> str:
    lines = ["| scene | renderer | sampler | res | spp | wall s | CPU s | relMSE | efficiency (wall) | "
             "efficiency (CPU) | vs our independent (CPU) | vs Mitsuba best (CPU) |",
             "|---|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        same = [q for q in rows if q["scene"] == r["scene"]]
        ours = next(q["cpu_efficiency"] for q in same if q["renderer"] == "ours" and q["sampler"] == "independent")
        best = max((q["cpu_efficiency"] for q in same if q["renderer"] == "mitsuba"), default=None)
        vs_best = f"{r['cpu_efficiency'] / best:.2f}x" if best else "—"
        lines.append(f"| {r['scene']} | {r['renderer']} | {r['sampler']} | {r['res']} | {r['spp']} | "
                     f"{r['seconds']:.2f} | {r['cpu_seconds']:.2f} | {r['relmse']:.3g} | {r['efficiency']:.3g} | "
                     f"{r['cpu_efficiency']:.3g} | {r['cpu_efficiency'] / ours:.2f}x | {vs_best} |")
    return "\n".join(lines)


def plot(rows: list[dict], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    scenes = list(dict.fromkeys(r["scene"] for r in rows))
    fig, axes = plt.subplots(1, len(scenes), figsize=(5 * len(scenes), 4), squeeze=False)
    for ax, scene in zip(axes[0], scenes):
        mine = [r for r in rows if r["scene"] == scene]
        labels = [f"{'mi ' if r['renderer'] == 'mitsuba' else ''}{r['sampler']}" for r in mine]
        ax.bar(labels, [r["cpu_efficiency"] for r in mine],
               color=["tab:orange" if r["renderer"] == "mitsuba" else "tab:blue" for r in mine])
        ax.set_yscale("log")
        ax.set_title(f"{scene} ({mine[0]['res']}, {mine[0]['spp']} spp)")
        ax.set_ylabel("efficiency 1 / (relMSE x CPU s)")
        ax.tick_params(axis="x", rotation=60)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def main() -> None:
    if sys.argv[1:2] == ["--child"]:
        child(sys.argv[2:])
        return
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", nargs="+", choices=list(SIZES), default=list(SIZES))
    ap.add_argument("--out", type=Path, default=ROOT / "out" / "time_to_error")
    ap.add_argument("--device", default="cpu", help="our Warp device (default: cpu)")
    ap.add_argument("--mitsuba-variant", default="llvm_ad_rgb", help="e.g. cuda_ad_rgb (default: llvm_ad_rgb)")
    a = ap.parse_args()
    TARGET.update(device=a.device, variant=a.mitsuba_variant)
    a.out.mkdir(parents=True, exist_ok=True)
    rows = measure(a.scenes, a.out)
    with open(a.out / "time_to_error.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    md = table(rows)
    (a.out / "time_to_error.md").write_text(md + "\n")
    plot(rows, a.out / "time_to_error.png")
    print("\n" + md)
    print(f"\nwrote {a.out / 'time_to_error.csv'}, .md and .png")


if __name__ == "__main__":
    main()
