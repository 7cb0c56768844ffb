"""Speed versus accuracy: render a converged reference once, then measure error against time for
each knob a user can turn, and write a CSV, a Markdown table and log-log plots.

    python benchmarks/study.py [--scene scenes/fig1_thinfilm.pbrt] [--res 160x90] [--ref-spp 2048] [--out out/study]

Knobs: samples per pixel (one progressive render, measured at powers of two), maximum path
depth, Russian roulette, the sampler (each of pbrt-v4's, its pattern as large as the run), and — when the scene uses the thin-film material, as the default scene
(the seed's Figure 1) does — its spectral mode.
Errors are relMSE (mean (x - r)^2 / (r^2 + 0.01), with the 0.1 % largest per-pixel errors
dropped so rare caustic fireflies don't mask convergence; the untrimmed value is in the CSV) and
FLIP (HDR, flip-evaluator) against the reference; time is wall clock of the passes (kernel
compilation excluded).
"""
from __future__ import annotations

import argparse
import csv
import os
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
os.environ.setdefault("WARP_CACHE_PATH", str(ROOT / ".warp-cache"))

import renderer  # noqa: E402
from renderer.api import settings_for  # noqa: E402
from renderer.io.metrics import relative_mse  # noqa: E402
from renderer.sampling.sampler_spec import RANDOMIZATIONS  # noqa: E402
from renderer.session import RenderSession  # noqa: E402


def flip_error(img: np.ndarray, ref: np.ndarray) -> float:
    """Mean HDR-FLIP, or NaN when flip-evaluator is not installed."""
    try:
        import flip_evaluator as flip
    except ImportError:
        return float("nan")
    _, mean, _ = flip.evaluate(np.maximum(ref, 0).astype(np.float32), np.maximum(img, 0).astype(np.float32),
                               "HDR", applyMagma=False)
    return float(mean)


def session(scene, res, **kw) -> RenderSession:
    return RenderSession(scene, settings_for(scene, width=res[0], height=res[1], **kw))


def measure(s: RenderSession, ref: np.ndarray, knob: str, value) -> dict:
    """One table row: the session's samples and time, and its errors against the reference."""
    img = s.image()
    return {"knob": knob, "value": value, "spp": s.film.spp, "seconds": s.stats.seconds,
            "samples_per_s": s.stats.samples_per_second, "relmse": relative_mse(img, ref, trim=1e-3),
            "relmse_untrimmed": relative_mse(img, ref), "flip": flip_error(img, ref)}


def spp_sweep(scene, res, ref, max_spp: int, seed: int) -> list[dict]:
    """One progressive render read out at 1, 2, 4, ... spp: error vs time along one run."""
    s = session(scene, res, seed=seed)
    rows, spp = [], 1
    while spp <= max_spp:
        s.run(spp)
        rows.append(measure(s, ref, "spp", spp))
        spp *= 2
    return rows


def fixed_spp_runs(scene, res, ref, spp: int, knob: str, values: list, seed: int, **fixed) -> list[dict]:
    rows = []
    for v in values:
        s = session(scene, res, seed=seed, **{**fixed, knob: v})
        s.run(spp)
        rows.append(measure(s, ref, knob, v))
    return rows


def slope(rows: list[dict]) -> float:
    """Least-squares slope of log relMSE against log time (about -1 for an unbiased estimator)."""
    t = np.log([r["seconds"] for r in rows])
    e = np.log([r["relmse"] for r in rows])
    return float(np.polyfit(t, e, 1)[0])


def plot(rows: list[dict], path: Path, title: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(1, 2, figsize=(8, 3.2), dpi=90)
    for knob in dict.fromkeys(r["knob"] for r in rows):
        sel = [r for r in rows if r["knob"] == knob]
        for a, metric in zip(ax, ("relmse", "flip")):
            a.loglog([r["seconds"] for r in sel], [r[metric] for r in sel], "o-", label=knob, ms=3)
            for r in sel:
                a.annotate(str(r["value"]), (r["seconds"], r[metric]), fontsize=6)
            a.set_xlabel("seconds")
            a.set_ylabel(metric)
            a.grid(True, which="both", alpha=0.3)
    ax[0].legend(fontsize=7)
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", type=Path, default=ROOT / "scenes/fig1_thinfilm.pbrt")
    ap.add_argument("--res", default="160x90")
    ap.add_argument("--ref-spp", type=int, default=2048)
    ap.add_argument("--max-spp", type=int, default=256)
    ap.add_argument("--knob-spp", type=int, default=32, help="spp for the depth and roulette sweeps")
    ap.add_argument("--out", type=Path, default=ROOT / "out/study")
    a = ap.parse_args()
    res = tuple(int(x) for x in a.res.split("x"))
    a.out.mkdir(parents=True, exist_ok=True)
    scene = renderer.load_scene(a.scene)
    t0 = time.perf_counter()
    ref_session = session(scene, res, seed=12345, max_depth=max(scene.integrator.max_depth, 16))
    ref_session.run(a.ref_spp)
    ref = ref_session.image()
    print(f"reference: {a.ref_spp} spp, depth {ref_session.settings.max_depth}, {ref_session.stats.seconds:.1f} s",
          flush=True)
    depth_fixed = dict(max_depth=max(scene.integrator.max_depth, 16))
    rows = spp_sweep(scene, res, ref, a.max_spp, seed=1)
    rows += fixed_spp_runs(scene, res, ref, a.knob_spp, "max_depth", [1, 2, 3, 5, 8, 16], seed=1)
    rows += fixed_spp_runs(scene, res, ref, a.knob_spp, "rr_depth", [-1, 1, 2, 4], seed=1, **depth_fixed)
    patterned = replace(scene, sampler=replace(scene.sampler, spp=a.knob_spp))
    rows += fixed_spp_runs(patterned, res, ref, a.knob_spp, "sampler", list(RANDOMIZATIONS), seed=1)
    if any(m.kind == "thinfilm" for m in scene.materials):
        # the reference is spectral:32 (jittered, unbiased); rgb3's colour error is a bias that stays
        rows += fixed_spp_runs(scene, res, ref, a.knob_spp, "thin_film",
                               ["rgb3", "spectral:4", "spectral:8", "spectral:16", "spectral:32"], seed=1,
                               **depth_fixed)
    with open(a.out / "study.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    lines = [f"Scene `{a.scene.relative_to(ROOT) if a.scene.is_relative_to(ROOT) else a.scene}` at {res[0]}x{res[1]}; "
             f"reference {a.ref_spp} spp. Slope of log relMSE vs log time over the spp sweep: "
             f"{slope([r for r in rows if r['knob'] == 'spp']):.2f}.", "",
             "| knob | value | spp | seconds | M samples/s | relMSE (0.1 % trimmed) | relMSE | FLIP |",
             "|---|---:|---:|---:|---:|---:|---:|---:|"]
    lines += [f"| {r['knob']} | {r['value']} | {r['spp']} | {r['seconds']:.2f} | {r['samples_per_s'] / 1e6:.3f} | "
              f"{r['relmse']:.3g} | {r['relmse_untrimmed']:.3g} | {r['flip']:.4f} |" for r in rows]
    (a.out / "study.md").write_text("\n".join(lines) + "\n")
    plot(rows, a.out / "study.png", f"error vs time, {a.scene.name} {res[0]}x{res[1]}")
    print("\n".join(lines))
    print(f"\nwrote {a.out}/study.csv, study.md, study.png in {time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    sys.exit(main())
