"""What a cluster render costs beyond the samples, on a local Ray instance, and what that predicts
for many workers. Prints four tables:

1. shipping the scene: its pickled description and files, the ``ray.put`` time, and one worker's
   first-task setup (fetch, upload, kernel load from the cache);
2. the per-task overhead against chunk size and image size: tasks run one at a time (one task in
   flight, so the 2 cores here do not compete), overhead = driver wall time per task minus the
   worker's own render time: scheduling, argument passing, returning the film (48 bytes a pixel),
   the driver's merge and its polling;
3. the cost of the exact fixed-point film (renderer.device.film): the kernel that moves one
   pass's samples into the integer sums, against the pass itself;
4. a model of speed-up against worker count for the full beach frame (1080x1920, 4096 spp) from
   those numbers (see ``model`` below).

    python benchmarks/cluster.py [--scene scenes/demo.pbrt] [--sizes 96x54,384x216,960x540] [--chunks 1,2,8]
"""
from __future__ import annotations

import argparse
import math
import os
import pickle
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
os.environ.setdefault("WARP_CACHE_PATH", str(ROOT / ".warp-cache"))

import numpy as np  # noqa: E402
import ray  # noqa: E402

import renderer  # noqa: E402
from renderer.api import settings_for  # noqa: E402
from renderer.cluster import Cluster, open_cluster  # noqa: E402
from renderer.cluster.driver import TARGET_TASK_SECONDS  # noqa: E402
from renderer.cluster.shipping import scene_files  # noqa: E402
from renderer.device.film import add_into  # noqa: E402
from renderer.session import RenderSession  # noqa: E402

#: The full beach frame and the issue's figure for it on this 2-core CPU: 8.5 G samples in ~8 h.
BEACH_PIXELS, BEACH_SPP = 1080 * 1920, 4096
BEACH_CORE_RATE = 1080 * 1920 * 4096 / (8 * 3600) / 2      # samples/s of one core


def ship(scene) -> None:
    files = scene_files(scene)
    t0 = time.perf_counter()
    ray.put(scene), ray.put(files)
    put = time.perf_counter() - t0
    print(f"scene: description {len(pickle.dumps(scene)) / 1e6:.2f} MB pickled, {len(files)} files "
          f"{sum(map(len, files.values())) / 1e6:.2f} MB, ray.put {put * 1e3:.1f} ms")


def overheads(scene, sizes: list[tuple[int, int]], chunks: list[int], tasks: int) -> dict:
    """Per (size, chunk): (overhead per task s, render s per spp, driver merge s, first-task setup s)."""
    print(f"\n{'image':>9} {'chunk':>5} {'task s':>8} {'render s':>9} {'overhead ms':>11} {'film MB':>8} "
          f"{'merge ms':>8} {'overhead %':>10}")
    out = {}
    for w, h in sizes:
        settings = settings_for(scene, width=w, height=h)
        warm = open_cluster(scene, settings, Cluster(workers=1, chunk=1))
        warm.run(1)                                          # the worker's upload and kernel load
        setup = warm.stats.compile_seconds
        film = warm.film
        whole, fraction = film.whole.copy(), film.fraction.copy()
        t0 = time.perf_counter()
        add_into(whole, fraction, film.whole, film.fraction)
        merge = time.perf_counter() - t0
        for c in chunks:
            render = open_cluster(scene, settings, Cluster(workers=1, chunk=c))
            t0 = time.perf_counter()
            render.run(c * tasks)
            wall = time.perf_counter() - t0
            work = sum(v.seconds for v in render.workers.values())
            over = (wall - work) / tasks
            out[(w, h, c)] = (over, work / (c * tasks), merge, setup)
            print(f"{w:>4}x{h:<4} {c:>5} {wall / tasks:>8.3f} {work / tasks:>9.3f} {over * 1e3:>11.1f} "
                  f"{2 * film.whole.nbytes / 1e6:>8.2f} {merge * 1e3:>8.1f} {100 * over / (wall / tasks):>9.1f}%")
        print(f"{'':>9} first task's setup on a worker (fetch, upload, kernel load): {setup:.2f} s")
    return out


def fixed_point_cost(scene, sizes: list[tuple[int, int]], passes: int = 3) -> None:
    """The accumulate kernel alone against whole passes (which include it), one thread."""
    import warp as wp

    print(f"\n{'image':>9} {'pass ms':>9} {'accumulate ms':>13} {'share':>7}")
    for w, h in sizes:
        s = RenderSession(scene, settings_for(scene, width=w, height=h), threads=1)
        s.run(1)
        t0 = time.perf_counter()
        s.run(1 + passes)
        per_pass = (time.perf_counter() - t0) / passes
        t0 = time.perf_counter()
        for _ in range(passes):
            s.film.accumulate(0, h)
        wp.synchronize_device("cpu")
        acc = (time.perf_counter() - t0) / passes
        print(f"{w:>4}x{h:<4} {per_pass * 1e3:>9.1f} {acc * 1e3:>13.2f} {100 * acc / per_pass:>6.2f}%")


def model(workers: int, task_seconds: float, overhead: float, driver: float, setup: float,
          spp_seconds: float) -> tuple[float, float]:
    """Fraction of ideal and the makespan (s) of the beach frame on ``workers`` equal workers.

    Each task renders ``chunk = round(task_seconds / spp_seconds)`` spp (at least 1, at most
    4096 / workers so every worker gets one) and costs ``overhead`` more on its worker; every
    worker pays ``setup`` once. The driver takes each returned film in and merges it serially
    (``driver`` seconds a task), which caps the throughput at one task per ``driver`` seconds.
    Tasks come in rounds of ``workers``; the last round may be partial. Ideal: 4096 x
    ``spp_seconds`` / ``workers``."""
    chunk = max(1, min(round(task_seconds / spp_seconds), BEACH_SPP // workers))
    tasks = math.ceil(BEACH_SPP / chunk)
    per_task = chunk * spp_seconds + overhead
    makespan = max(setup + math.ceil(tasks / workers) * per_task, tasks * driver)
    return BEACH_SPP * spp_seconds / workers / makespan, makespan


def print_model(measured: dict, link: float) -> None:
    """The measured per-task overhead is a fixed part (the smallest image's) plus a part per pixel
    (the largest image's excess), both averaged over chunk sizes, scaled to the beach frame; the
    driver's share per task is its measured merge plus the film's transfer over a ``link`` (bytes/s)
    into the driver, which a local instance (shared memory) cannot measure."""
    by_size: dict[tuple[int, int], list] = {}
    for (w, h, _), v in measured.items():
        by_size.setdefault((w, h), []).append(v)
    small, large = min(by_size, key=lambda k: k[0] * k[1]), max(by_size, key=lambda k: k[0] * k[1])
    fixed = float(np.mean([v[0] for v in by_size[small]]))
    excess = float(np.mean([v[0] for v in by_size[large]])) - fixed
    overhead = fixed + max(excess, 0.0) / (large[0] * large[1] - small[0] * small[1]) * BEACH_PIXELS
    merge = by_size[large][0][2] / (large[0] * large[1]) * BEACH_PIXELS
    film_bytes = 48 * BEACH_PIXELS
    driver = merge + film_bytes / link
    setup = max(v[3] for v in measured.values())
    print(f"\nmodel inputs (beach frame {BEACH_PIXELS:,} px): worker overhead {overhead:.3f} s/task, driver merge "
          f"{merge:.3f} s + film {film_bytes / 1e6:.0f} MB over {link / 1e9:.2f} GB/s = {driver:.3f} s/task, "
          f"setup {setup:.1f} s/worker, target task {TARGET_TASK_SECONDS:.0f} s")
    counts = (1, 4, 16, 64, 256)
    print(f"{'worker':>14} {'s/spp':>7} " + " ".join(f"{n:>11}" for n in counts) + "   (fraction of ideal, makespan)")
    for name, rate in (("CPU core", BEACH_CORE_RATE), ("16-core node", 16 * BEACH_CORE_RATE),
                       ("GPU (5 min)", BEACH_PIXELS * BEACH_SPP / 300.0)):
        spp_seconds = BEACH_PIXELS / rate
        cells = []
        for n in counts:
            frac, span = model(n, TARGET_TASK_SECONDS, overhead, driver, setup, spp_seconds)
            cells.append(f"{100 * frac:5.1f}% {span / 3600:4.1f}h" if span > 3600 else f"{100 * frac:5.1f}% {span:4.0f}s")
        print(f"{name:>14} {spp_seconds:>7.2f} " + " ".join(f"{c:>11}" for c in cells))


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--scene", type=Path, default=ROOT / "scenes" / "demo.pbrt")
    p.add_argument("--sizes", default="96x54,384x216,960x540")
    p.add_argument("--chunks", default="1,2,8")
    p.add_argument("--tasks", type=int, default=3, help="tasks per measurement")
    p.add_argument("--link", type=float, default=1.25e9, help="bytes/s into the driver in the model (10 GbE)")
    args = p.parse_args()
    sizes = [tuple(int(v) for v in s.split("x")) for s in args.sizes.split(",")]
    chunks = [int(c) for c in args.chunks.split(",")]
    ray.init(num_cpus=1, include_dashboard=False, log_to_driver=False,
             runtime_env={"env_vars": {"WARP_CACHE_PATH": os.environ["WARP_CACHE_PATH"]}})
    scene = renderer.load_scene(args.scene)
    ship(scene)
    measured = overheads(scene, sizes, chunks, args.tasks)
    fixed_point_cost(scene, sizes)
    print_model(measured, args.link)
    ray.shutdown()


if __name__ == "__main__":
    main()
