"""What each level of asset detail buys on the beach: build the beach's assets with one knob turned
down, render, and measure error against the full-detail render, render time, build time and memory.

    python benchmarks/asset_study.py [--out out/asset_study] [--spp 32] [--knobs grain_count,...]
    python benchmarks/asset_study.py --levels      # the recipe's named levels instead of single knobs

Knobs (each at the recipe's value, then smaller): grain count and grain mesh detail (icosphere
subdivisions), dune grid spacing, the near-field ripple tessellation (pixels_per_edge), the ripple
map's resolution and the texture maps' (sky, shell maps, lens thickness). Each variant is a folder
with a copy of beach.pbrt, scenes/parts and the reference assets, whose recipe gets the knob's
value as a detail level ``study``: the recipe's hashes then rebuild only the entry the knob changes
and those downstream of it, and that rebuild is what the build time measures (wall and CPU of the
``assets-gen recipe`` process; a variant's full build costs the reference's build time minus what
is reused). Each variant is rendered twice, in its own process so peak memory (RenderStats, the
process's peak RSS) is its own: the whole frame small (216x384) and a 100 % crop of the in-focus
sand, shell and lenses at the full 1080x1920. Errors are against the reference assets rendered with
the SAME seed and spp, so most of the sampler noise cancels; what remains is listed as the noise
floor: the reference against itself at another seed. relMSE is trimmed as in study.py (0.1 %).
"""
from __future__ import annotations

import argparse
import csv
import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from study import ROOT, flip_error  # noqa: E402

from assets_gen.recipe import load as recipe_entries  # noqa: E402
from renderer.io.images import read_exr  # noqa: E402
from renderer.io.metrics import relative_mse  # noqa: E402

SCENES = ROOT / "scenes"
RECIPE = SCENES / "beach.recipe.json"
#: the 100 % crop (pbrt's --cropwindow x0,x1,y0,y1 of the 1080x1920 frame): sand in focus below the
#: lenses, the shell's rim and the lenses' lower half (432x230 pixels)
CROP = "0.15,0.55,0.63,0.75"
SHELL_MAPS = ("shell-height", "shell-pigment", "shell-bump")


def _texture_maps(f: int) -> dict[str, dict]:
    """The texture maps (sky, shell maps, lens thickness) at 1/f of the recipe's resolution (its
    values as written, or the generators' defaults)."""
    v = {e.name: e.values for e in recipe_entries(RECIPE)}
    return {**{m: {"resolution": v[m].resolution // f} for m in ("sky", "lens-thickness")},
            **{m: {"width": v[m].width // f, "height": v[m].height // f} for m in SHELL_MAPS}}


#: knob -> (values, the overrides {entry: {param: value}} for a value); values[0] is the recipe's
#: (three values where the cost is in doubt, two where one step down tells; the CPU budget is ~40 min)
KNOBS: dict[str, tuple[list, object]] = {
    "grain_count": ([100000, 30000, 10000], lambda v: {"grains": {"count": v}}),
    "grain_subdivisions": ([2, 0], lambda v: {"grains": {"subdivisions": v}}),
    "dune_spacing_m": ([0.15, 0.3, 0.6], lambda v: {"dunes": {"spacing": v}}),
    "ripple_pixels_per_edge": ([1.5, 3, 6], lambda v: {"sand": {"pixels_per_edge": v}}),
    "ripple_map_px": ([4096, 2048, 1024], lambda v: {"ripples": {"max_map_size": v}}),
    "texture_maps_div": ([1, 4], _texture_maps),
}


def timed(cmd: list[str], cwd: Path) -> tuple[float, float, float, str]:
    """Run ``cmd``; its wall seconds, CPU seconds (user + system), peak RSS (MB) and stderr."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    t0 = time.perf_counter()
    p = subprocess.Popen(cmd, cwd=cwd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    err = p.stderr.read() if p.stderr else ""
    _, status, ru = os.wait4(p.pid, 0)
    p.returncode = os.waitstatus_to_exitcode(status)
    if p.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed ({p.returncode}): {err[-2000:]}")
    return time.perf_counter() - t0, ru.ru_utime + ru.ru_stime, ru.ru_maxrss / 1024.0, err


def stage(folder: Path, reference: Path | None, overrides: dict[str, dict] | None) -> Path:
    """A variant folder: beach.pbrt, parts/, the reference's assets (to be reused where current) and
    the recipe with ``overrides`` as its level ``study``. Returns the recipe's path."""
    if folder.exists():
        shutil.rmtree(folder)
    folder.mkdir(parents=True)
    shutil.copy(SCENES / "beach.pbrt", folder)
    shutil.copytree(SCENES / "parts", folder / "parts")
    if reference is not None:
        shutil.copytree(reference / "assets", folder / "assets")
    doc = json.loads(RECIPE.read_text())
    if overrides:
        doc.setdefault("levels", {})["study"] = "the asset study's variant"
        names = {e["name"] for e in doc["assets"]}
        assert set(overrides) <= names, sorted(set(overrides) - names)
        for e in doc["assets"]:
            if e["name"] in overrides:
                e.setdefault("levels", {})["study"] = overrides[e["name"]]
    (folder / RECIPE.name).write_text(json.dumps(doc, indent=1))
    return folder / RECIPE.name


def build(recipe: Path, level: str | None) -> dict:
    """Build the folder's out-of-date assets; the numbers of that build and the entries it rebuilt."""
    cmd = [sys.executable, "-m", "assets_gen", "recipe", str(recipe)] + (["--level", level] if level else [])
    wall, cpu, rss, log = timed(cmd, recipe.parent)
    rebuilt = [line.split(":")[1].strip() for line in log.splitlines() if "building with" in line]
    size = sum(p.stat().st_size for p in (recipe.parent / "assets").rglob("*") if p.is_file())
    return {"build_wall_s": wall, "build_cpu_s": cpu, "build_peak_mb": rss, "assets_mb": size / 2**20,
            "rebuilt": " ".join(rebuilt)}


def render(folder: Path, view: str, spp: int, seed: int, res: str) -> tuple[np.ndarray, dict]:
    """Render one view of the folder's beach in a process of its own; the image and its numbers."""
    out = folder / f"{view}_s{seed}.exr"
    view_args = ["--res", res] if view == "frame" else ["--res", "1080x1920", "--cropwindow", CROP]
    wall, cpu, _, _ = timed([sys.executable, "-m", "renderer", str(folder / "beach.pbrt"), "-o", str(out),
                             "--spp", str(spp), "--seed", str(seed), "--quiet", *view_args], folder)
    chans, header = read_exr(out)
    img = np.stack([chans[c] for c in "RGB"], axis=-1)
    return img, {f"{view}_render_s": float(header["renderTimeSeconds"]), f"{view}_wall_s": wall,
                 f"{view}_cpu_s": cpu, f"{view}_peak_mb": float(header["peakMemoryMB"])}


def measure(folder: Path, refs: dict[str, np.ndarray], spp: int, seed: int, res: str) -> dict:
    row: dict = {}
    for view in ("frame", "crop"):
        img, nums = render(folder, view, spp, seed, res)
        row.update(nums)
        if view in refs:
            row[f"{view}_relmse"] = relative_mse(img, refs[view], trim=1e-3)
            row[f"{view}_flip"] = flip_error(img, refs[view])
        else:
            refs[view] = img
            row[f"{view}_relmse"] = row[f"{view}_flip"] = 0.0
    return row


def reference(a: argparse.Namespace) -> tuple[list[dict], dict[str, np.ndarray]]:
    """The reference's row, the noise floor's and the reference images; made once per ``--out``
    folder and settings (kept in reference/rows.json), so a ``--levels`` run reuses them."""
    ref_dir = a.out / "reference"
    key = {"spp": a.spp, "seed": a.seed, "res": a.res, "crop": CROP,
           "assets": [[e.name, e.seed, e.params] for e in recipe_entries(RECIPE)]}
    cache = ref_dir / "rows.json"
    if cache.is_file() and json.loads(cache.read_text())["key"] == key:
        refs = {}
        for view in ("frame", "crop"):
            chans, _ = read_exr(ref_dir / f"{view}_s{a.seed}.exr")
            refs[view] = np.stack([chans[c] for c in "RGB"], axis=-1)
        return json.loads(cache.read_text())["rows"], refs
    row = {"knob": "reference", "value": "recipe", **build(stage(ref_dir, None, None), None)}
    refs = {}
    row.update(measure(ref_dir, refs, a.spp, a.seed, a.res))
    floor = {"knob": "noise floor", "value": f"seed {a.seed + 1}",
             **{k: v for k, v in row.items() if k.startswith("build") or k in ("assets_mb", "rebuilt")}}
    floor.update(measure(ref_dir, dict(refs), a.spp, a.seed + 1, a.res))
    cache.write_text(json.dumps({"key": key, "rows": [row, floor]}))
    return [row, floor], refs


def variants(args: argparse.Namespace) -> list[tuple[str, object, dict | None, str | None]]:
    """(knob, value, overrides, level) of every variant after the reference."""
    if args.levels:
        doc = json.loads(RECIPE.read_text())
        # "final" is the reference (the recipe as written: the same hashes, nothing rebuilt)
        return [("level", name, None, name) for name in [*doc.get("levels", {}), "quick"] if name != "final"]
    wanted = args.knobs.split(",") if args.knobs else list(KNOBS)
    unknown = sorted(set(wanted) - set(KNOBS))
    if unknown:
        raise SystemExit(f"unknown knob(s) {unknown}; known: {sorted(KNOBS)}")
    return [(k, v, KNOBS[k][1](v), "study") for k in wanted for v in KNOBS[k][0][1:]]


def table(rows: list[dict]) -> list[str]:
    """Render time is RenderStats' (the passes' wall clock, as the EXR header has it); the render
    process's wall and CPU seconds (with scene loading and BVH build) are in the CSV."""
    lines = ["| knob | value | rebuilt | build wall s | build CPU s | assets MB | frame render s | crop render s | "
             "render peak MB | frame relMSE | frame FLIP | crop relMSE | crop FLIP |",
             "|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        rebuilt = {"reference": "all, from nothing", "noise floor": "(the reference's)"}.get(r["knob"], r["rebuilt"])
        lines.append(f"| {r['knob']} | {r['value']} | {rebuilt or '-'} | {r['build_wall_s']:.1f} | "
                     f"{r['build_cpu_s']:.1f} | {r['assets_mb']:.0f} | {r['frame_render_s']:.0f} | "
                     f"{r['crop_render_s']:.0f} | {max(r['frame_peak_mb'], r['crop_peak_mb']):.0f} | "
                     f"{r['frame_relmse']:.3g} | {r['frame_flip']:.4f} | {r['crop_relmse']:.3g} | "
                     f"{r['crop_flip']:.4f} |")
    return lines


def read_rows(path: Path) -> list[dict]:
    """The rows of a CSV this script wrote, numbers as numbers."""
    def value(v: str) -> object:
        try:
            return float(v)
        except ValueError:
            return v
    with open(path, newline="") as f:
        return [{k: (v if k in ("knob", "value", "rebuilt") else value(v)) for k, v in r.items()}
                for r in csv.DictReader(f)]


FIELDS = ["knob", "value", "rebuilt", "build_wall_s", "build_cpu_s", "build_peak_mb", "assets_mb",
          *(f"{v}_{k}" for v in ("frame", "crop") for k in ("render_s", "wall_s", "cpu_s", "peak_mb", "relmse", "flip"))]


def write_rows(path: Path, rows: list[dict]) -> None:
    """Append rows to the CSV (made with its header if new): an interrupted run keeps what it measured."""
    new = not path.is_file()
    with open(path, "a", newline="") as f:
        w = csv.DictWriter(f, fieldnames=FIELDS, restval="nan")
        if new:
            w.writeheader()
        w.writerows(rows)


def ordered(rows: list[dict]) -> list[dict]:
    """The rows in KNOBS' order, each knob's values as listed there (a resumed run appends a value
    added later at the end of the CSV); other rows (the reference, the levels) keep their order."""
    def key(i_r: tuple[int, dict]) -> tuple:
        i, r = i_r
        if r["knob"] not in KNOBS:
            return (-1, i)
        values = [str(v) for v in KNOBS[r["knob"]][0]]
        rank = values.index(r["value"]) if r["value"] in values else len(values)
        return (list(KNOBS).index(r["knob"]), rank, i)
    return [r for _, r in sorted(enumerate(rows), key=key)]


def write_report(rows: list[dict], out: Path, name: str, head: str) -> None:
    """``name``.md (the table under ``head``) and ``name``.png in ``out``."""
    rows = ordered(rows)
    (out / f"{name}.md").write_text("\n".join([head, "", *table(rows)]) + "\n")
    plot(rows, out / f"{name}.png", next(r for r in rows if r["knob"] == "noise floor"))


def plot(rows: list[dict], path: Path, floor: dict) -> None:
    """Error against cost per knob, from the reference down, with the noise floor dashed."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    # against memory, not time: no knob moved render time beyond the spread of repeated runs
    # (docs/study.md), and render times swing with the shared machine's load
    fig, ax = plt.subplots(1, 2, figsize=(8, 3.4), dpi=90)
    panels = [("frame_peak_mb", "frame_flip", "whole frame 216x384: FLIP vs render peak MB"),
              ("crop_peak_mb", "crop_flip", "100 % crop of 1080x1920: FLIP vs render peak MB")]
    for knob in dict.fromkeys(r["knob"] for r in rows if r["knob"] not in ("reference", "noise floor")):
        sel = [r for r in rows if r["knob"] in (knob, "reference")]
        for a, (x, y, title) in zip(ax, panels):
            a.plot([r[x] for r in sel], [r[y] for r in sel], "o-", ms=3, label=knob)
            for r in sel[1:]:
                a.annotate(str(r["value"]), (r[x], r[y]), fontsize=6)
            a.set_title(title, fontsize=8)
            a.set_xlabel("render peak MB")
            a.grid(True, alpha=0.3)
    for a, key in zip(ax, ("frame_flip", "crop_flip")):
        a.axhline(floor[key], ls="--", c="grey", lw=0.8, label="noise floor (other seed)")
    ax[0].legend(fontsize=6)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=ROOT / "out/asset_study")
    ap.add_argument("--spp", type=int, default=32)
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--res", default="216x384", help="the whole frame's resolution")
    ap.add_argument("--knobs", help=f"comma-separated subset of {','.join(KNOBS)}")
    ap.add_argument("--levels", action="store_true", help="measure the recipe's named detail levels")
    ap.add_argument("--from-csv", type=Path, help="only remake the table and plot from this CSV "
                    "(a run resumes by itself: variants already in <out>/asset_study.csv are skipped)")
    a = ap.parse_args()
    a.out = a.out.resolve()                     # the builds and renders run with the variant folder as cwd
    a.out.mkdir(parents=True, exist_ok=True)
    name = "asset_levels" if a.levels else "asset_study"
    head = (f"Beach assets, {a.spp} spp, seed {a.seed}; frame {a.res}, crop {CROP} of 1080x1920. "
            f"Errors against the reference assets at the same seed and spp.")
    if a.from_csv:
        write_report(read_rows(a.from_csv), a.out, name, head)
        return 0
    t0 = time.perf_counter()
    rows, refs = reference(a)
    ref_dir, csv_path = a.out / "reference", a.out / f"{name}.csv"
    done = read_rows(csv_path) if csv_path.is_file() else []
    if not done:
        write_rows(csv_path, rows)
    print("\n".join(table(rows)), flush=True)
    for knob, value, overrides, level in variants(a):
        if any(r["knob"] == knob and r["value"] == str(value) for r in done):
            continue                            # measured by an earlier, interrupted run
        folder = a.out / f"{knob}_{value}"
        recipe = stage(folder, ref_dir, overrides or {})
        row = {"knob": knob, "value": value, **build(recipe, level)}
        row.update(measure(folder, refs, a.spp, a.seed, a.res))
        rows.append(row)
        write_rows(csv_path, [row])
        print(table([row])[-1], flush=True)
        for exr in folder.glob("*.exr"):
            exr.rename(a.out / f"{knob}_{value}_{exr.name}")
        shutil.rmtree(folder)                   # the assets: up to 150 MB a variant
    write_report(read_rows(csv_path), a.out, name, head)
    print(f"\nwrote {a.out}/{name}.csv, .md, .png in {time.perf_counter() - t0:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
