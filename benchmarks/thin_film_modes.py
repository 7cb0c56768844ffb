"""Thin-film colour modes: accuracy (ΔE00 against the 1 nm reference) versus cost per evaluation.

Films of 0–10 µm at several angles, for a soap film in air and the seed's coat (1.55 on 1.66).
Colours are the linear-sRGB reflectances under D65, compared in CIELAB (D65 white, Y = 1) with
CIE 2000. Deterministic modes are the numpy wrapper's quadratures; "jittered:N" is the renderer's
estimator, one evaluation (the noise a single sample carries) and the mean of 64 (what an image
converges to). Cost: the best of four Warp CPU launches of the mode's kernel over 2^20 evaluations
(2^14 for the reference) on one thread, inputs already on the device.

Stacks (``--stacks``): the same modes for multilayer stacks of 1, 10, 100 and 200 layers, two
families: quarter-wave TiO2/SiO2 mirrors (2.4 | 1.46 on glass, design wavelengths 420–680 nm) and
nacre-like stacks (aragonite 1.60, 400 nm ± 20 % | organic matrix 1.43, 30 nm, on matrix, 16
seeds); ΔE00 against the 1 nm reference (monochromatic) and the cost of one RGB evaluation of each
mode (Warp CPU kernel, one thread). ``table`` is the render mode of that name: a table over the
angle baked from the reference (:mod:`renderer.optics.angular_table`), looked up at each angle;
its bake time per side and its largest reflectance error at random angles ("max abs ΔR") are rows
of their own. Then whole renders (``--renders``): scenes/nacre.pbrt and scenes/mirror_coatings.pbrt
at 64x36, 4 spp, with their stacks replaced by 1, 10, 100 and 200 layers of the same materials,
in each mode: seconds of upload (the table's bake) and of rendering, kernels already compiled.

    WARP_CACHE_PATH=.warp-cache .venv/bin/python benchmarks/thin_film_modes.py [--stacks] [--renders]
"""
from __future__ import annotations

import re
import sys
import tempfile
import time
from functools import lru_cache
from pathlib import Path

import colour
import numpy as np
import warp as wp

from renderer.optics import angular_table, arrays as optics
from renderer.color.rgb_weights import make_rgb_weight_table
from renderer.color import spectral

FILMS = {"soap 1.00|1.33|1.00": (1.0, 1.33, 1.0), "coat 1.00|1.55|1.66": (1.0, 1.55, 1.66)}
COS_THETA = np.array([1.0, 0.8, 0.5, 0.2])
THICKNESS_NM = np.linspace(0.0, 10000.0, 401)
MODES = ("rgb3", "spectral:4", "spectral:8", "spectral:16", "spectral:32")
JITTERED = (4, 8, 16, 32)
MEAN_OF = 64
COST_EVALS = 1 << 20


def lab(rgb: np.ndarray) -> np.ndarray:
    """CIELAB of linear-sRGB reflectance under D65 (white (1, 1, 1) → L = 100)."""
    srgb = colour.RGB_COLOURSPACES["sRGB"]
    xyz = rgb @ np.asarray(srgb.matrix_RGB_to_XYZ).T
    white = np.asarray(srgb.matrix_RGB_to_XYZ).sum(axis=1)
    return colour.XYZ_to_Lab(xyz, colour.XYZ_to_xy(white))


def delta_e(rgb: np.ndarray, ref: np.ndarray) -> np.ndarray:
    return np.asarray(colour.delta_E(lab(rgb), lab(ref), method="CIE 2000"))


def grid(film: tuple[float, float, float]):
    n0, n1, n2 = film
    return COS_THETA[:, None], n0, n1, n2, THICKNESS_NM[None, :]


def _time(kernel, m: int, args: list) -> float:
    """Nanoseconds per thread of a kernel: the best of four CPU launches."""
    best = np.inf
    for _ in range(4):
        start = time.perf_counter()
        wp.launch(kernel, dim=m, inputs=args, device="cpu")
        wp.synchronize_device("cpu")
        best = min(best, time.perf_counter() - start)
    return best / m * 1e9


@lru_cache(maxsize=None)
def cost_ns(mode: str) -> float:
    """Nanoseconds per RGB evaluation of a mode: the Warp CPU kernel alone (one thread), inputs prepared."""
    rng = np.random.default_rng(0)
    m = COST_EVALS if mode != "reference" else COST_EVALS // 64
    _, inputs, (u,) = optics._film_inputs(rng.uniform(0.0, 1.0, m), 1.0, 1.33, 1.52, rng.uniform(0.0, 10000.0, m),
                                          rng.random(m))
    out = wp.empty(m, dtype=wp.vec3, device="cpu")
    if mode == "rgb3":
        kernel, args = optics._rgb3_kernel, [*inputs, out]
    elif mode.startswith("jittered:"):
        table = make_rgb_weight_table("cpu")
        kernel, args = optics._rgb_sampled_kernel, [*inputs, u, int(mode.split(":")[1]), table, out,
                                                    wp.empty(m, dtype=wp.vec3, device="cpu")]
    else:
        lam, weights, band = spectral.mode_wavelengths(mode)
        kernel, args = optics._rgb_quadrature_kernel, [
            *inputs, wp.array(lam.astype(np.float32), dtype=float, device="cpu"),
            wp.array(weights.astype(np.float32), dtype=wp.vec3, device="cpu"), float(band), out]
    return _time(kernel, m, args)


STACK_LAYERS = (1, 10, 100, 200)
STACK_VARIANTS = 16


def stack(family: str, n_layers: int, variant: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(eta, k, thickness) of one stack of a family (see the module docstring)."""
    if family == "mirror":
        lam0 = 420.0 + 260.0 * variant / (STACK_VARIANTS - 1)
        inner = np.resize([2.4, 1.46], n_layers)
        return np.r_[1.0, inner, 1.52], np.zeros(n_layers + 2), lam0 / (4.0 * inner)
    rng = np.random.default_rng(variant)
    inner = np.resize([1.60, 1.43], n_layers)
    d = np.resize([400.0, 30.0], n_layers) * np.maximum(1.0 + np.resize([0.2, 0.0], n_layers)
                                                        * rng.standard_normal(n_layers), 0.0)
    return np.r_[1.0, inner, 1.43], np.zeros(n_layers + 2), d


@lru_cache(maxsize=None)
def stack_cost_ns(mode: str, n_layers: int) -> float:
    """Nanoseconds per RGB evaluation of a stack in a mode (Warp CPU kernel, one thread)."""
    n0, n_sub, rows = optics.stack_layers(*stack("nacre", n_layers, 0))
    n_lambda = 3 if mode == "rgb3" else 471 if mode == "reference" else int(mode.split(":")[1])
    m = max(64, (1 << 23) // (n_layers * n_lambda))
    rng = np.random.default_rng(0)
    cos0 = wp.array(rng.uniform(0.0, 1.0, m).astype(np.float32), dtype=float, device="cpu")
    layers = wp.array(rows, dtype=wp.vec4, device="cpu")
    out = wp.empty(m, dtype=wp.vec3, device="cpu")
    if mode.startswith("jittered:"):
        u = wp.array(rng.random(m).astype(np.float32), dtype=float, device="cpu")
        return _time(optics._stack_rgb_sampled_kernel, m, [cos0, n0, wp.vec2(*n_sub), layers, u, n_lambda,
                                                            make_rgb_weight_table("cpu"), out])
    lam, weights, _ = spectral.mode_wavelengths(mode)
    return _time(optics._stack_rgb_quadrature_kernel, m, [
        cos0, n0, wp.vec2(*n_sub), layers, wp.array(lam.astype(np.float32), dtype=float, device="cpu"),
        wp.array(weights.astype(np.float32), dtype=wp.vec3, device="cpu"), out])


TABLE_ANGLES = 64     # random cosines per stack at which the table is checked


@lru_cache(maxsize=None)
def table_cost_ns() -> float:
    """Nanoseconds per RGB (R, T) lookup of a baked table (Warp CPU kernel, one thread): the same
    for every stack, whose size only enters the bake."""
    n0, n_sub, rows = optics.stack_layers(*stack("nacre", 10, 0))
    table = wp.array(angular_table.stack_table(n0, complex(*n_sub), rows), dtype=wp.vec4, device="cpu")
    m = COST_EVALS
    cos0 = wp.array(np.random.default_rng(0).uniform(0.0, 1.0, m).astype(np.float32), dtype=float, device="cpu")
    return _time(angular_table._lookup_kernel, m, [table, cos0, 2, 0, wp.empty(m, dtype=wp.vec3, device="cpu")])


def table_errors(eta, k, d, rng) -> tuple[np.ndarray, float, float]:
    """(ΔE00 at COS_THETA and random angles, largest |ΔR|, bake seconds) of one stack's table."""
    cos = np.concatenate([COS_THETA, rng.uniform(0.0, 1.0, TABLE_ANGLES)])
    n0, n_sub, rows = optics.stack_layers(eta, k, d)
    start = time.perf_counter()
    table = angular_table.stack_table(n0, complex(*n_sub), rows)
    bake = time.perf_counter() - start
    r = angular_table.lookup(table, cos)
    ref = optics.multilayer_rgb(cos, eta, k, d, mode="reference")
    return delta_e(r, ref), float(np.abs(r - ref).max()), bake


def stack_errors(family: str, n_layers: int) -> dict[str, np.ndarray]:
    """ΔE00 of each mode against the reference over the family's variants and COS_THETA (the
    table also at random angles); "table max abs ΔR" and "table bake s" hold one value per stack."""
    errors: dict[str, list[np.ndarray]] = {}
    rng = np.random.default_rng(2)
    for v in range(STACK_VARIANTS):
        eta, k, d = stack(family, n_layers, v)
        e, dr, bake = table_errors(eta, k, d, rng)
        errors.setdefault("table", []).append(e)
        errors.setdefault("table max abs ΔR", []).append(np.array([dr]))
        errors.setdefault("table bake s", []).append(np.array([bake]))
        ref = optics.multilayer_rgb(COS_THETA, eta, k, d, mode="reference")
        for mode in MODES:
            errors.setdefault(mode, []).append(delta_e(optics.multilayer_rgb(COS_THETA, eta, k, d, mode=mode), ref))
        for n in (8, 32):
            r = optics.multilayer_rgb_jittered(COS_THETA[None, :], eta, k, d, rng.random((MEAN_OF, len(COS_THETA))), n)
            errors.setdefault(f"jittered:{n} (1 sample)", []).append(delta_e(r[0], ref))
            errors.setdefault(f"jittered:{n} (mean of {MEAN_OF})", []).append(delta_e(r.mean(axis=0), ref))
    return {m: np.concatenate(e) for m, e in errors.items()}


def main_stacks() -> None:
    wp.config.quiet = True
    wp.init()
    print(f"Stack colour error against the 1 nm reference (ΔE00 mean / max over {STACK_VARIANTS} stacks × cos θ ∈ "
          f"{COS_THETA.tolist()}) and cost per RGB evaluation (µs, Warp CPU device, one thread).\n")
    head = " | ".join(f"{n} layers" for n in STACK_LAYERS)
    print(f"| mode | mirror ΔE00: {head} | nacre ΔE00: {head} | µs / evaluation: {head} |")
    print("|---|" + "---:|" * (3 * len(STACK_LAYERS)))
    table = {f: {n: stack_errors(f, n) for n in STACK_LAYERS} for f in ("mirror", "nacre")}
    for name in list(table["mirror"][1]) + ["reference"]:
        mode = name.split(" ")[0]
        cells = []
        for f in ("mirror", "nacre"):
            for n in STACK_LAYERS:
                e = table[f][n].get(name)
                cells.append("0" if e is None else f"{e.mean():.2f} / {e.max():.1f}" if name.count(" ") == 0
                             or "(" in name else f"{e.mean():.2g} / {e.max():.2g}")
        if name.startswith("table "):
            cost = [""] * len(STACK_LAYERS)
        elif mode == "table":
            cost = [f"{table_cost_ns() / 1000:,.3f}"] * len(STACK_LAYERS)
        else:
            cost = [f"{stack_cost_ns(mode, n) / 1000:,.2f}" for n in STACK_LAYERS]
        print(f"| {name} | " + " | ".join(cells + cost) + " |")


RENDER_MODES = ("rgb3", "spectral:8", "spectral:32", "table")
RENDER_SCENES = ("nacre", "mirror_coatings")


def _layers(text: str, name: str, values: list[float]) -> str:
    return re.sub(rf'"float {name}" \[[^\]]*\]', f'"float {name}" [{" ".join(f"{v:g}" for v in values)}]', text)


def scene_with_layers(scene: str, n_layers: int) -> str:
    """The scene's text with every stack replaced by n_layers of its own materials: nacre's cell
    (tablet, matrix) or the mirror's (H, L) alternated, starting with the first."""
    text = (Path(__file__).parent.parent / "scenes" / f"{scene}.pbrt").read_text()
    if scene == "nacre":
        cell = 2 if n_layers > 1 else 1
        text = text.replace('"integer repeat" [40]', f'"integer repeat" [{n_layers // cell}]')
        text = text.replace('"float layer_disorder" [0.15 0.3]', '"float layer_disorder" [0.15 0.3]' if cell == 2
                            else '"float layer_disorder" [0.15]')
        return _layers(_layers(text, "layer_eta", [1.68, 1.43][:cell]), "layer_thickness", [400.0, 25.0][:cell])
    out = []
    for line in text.splitlines():
        for name in ("layer_eta", "layer_cauchyb", "layer_thickness"):
            m = re.search(rf'"float {name}" \[([^\]]*)\]', line)
            if m:
                pair = [float(x) for x in m.group(1).split()[:2]]
                line = _layers(line, name, [pair[i % 2] for i in range(n_layers)])
        out.append(line)
    return "\n".join(out) + "\n"


def main_renders() -> None:
    from renderer.api import load_scene, open_session
    from renderer.settings import settings_for

    print("Whole renders at 64x36, 4 spp, seed 7 (2 threads, loaded machine): seconds of upload (with the "
          "table's bake) + rendering, kernels compiled beforehand.\n")
    print("| scene | layers | " + " | ".join(RENDER_MODES) + " |")
    print("|---|---:|" + "---:|" * len(RENDER_MODES))
    with tempfile.TemporaryDirectory() as tmp:
        for scene in RENDER_SCENES:
            for n in STACK_LAYERS:
                path = Path(tmp) / f"{scene}_{n}.pbrt"
                path.write_text(scene_with_layers(scene, n))
                desc = load_scene(path)
                cells = []
                for mode in RENDER_MODES:
                    settings = settings_for(desc, seed=7, width=64, height=36, thin_film=mode)
                    start = time.perf_counter()
                    session = open_session(desc, settings)
                    upload = time.perf_counter() - start - session.stats.compile_seconds
                    stats = session.run(4)
                    cells.append(f"{upload:.1f} + {stats.seconds:.1f}")
                print(f"| {scene} | {n} | " + " | ".join(cells) + " |", flush=True)


def main() -> None:
    if "--renders" in sys.argv[1:]:
        wp.config.quiet = True
        main_renders()
        return
    if "--stacks" in sys.argv[1:]:
        main_stacks()
        return
    wp.config.quiet = True
    wp.init()
    rows: dict[str, list[np.ndarray]] = {}
    for film in FILMS.values():
        ref = optics.thin_film_rgb(*grid(film), mode="reference")
        for mode in MODES:
            rows.setdefault(mode, []).append(delta_e(optics.thin_film_rgb(*grid(film), mode=mode), ref).ravel())
        rng = np.random.default_rng(1)
        for n in JITTERED:
            shape = (MEAN_OF,) + ref.shape[:-1]
            r, _ = optics.thin_film_rgb_jittered(*grid(film), u_jitter=rng.random(shape), n_samples=n)
            rows.setdefault(f"jittered:{n} (1 sample)", []).append(delta_e(r[0], ref).ravel())
            rows.setdefault(f"jittered:{n} (mean of {MEAN_OF})", []).append(delta_e(r.mean(axis=0), ref).ravel())

    thin = THICKNESS_NM <= 2000.0
    print(f"Thin-film colour error against the 1 nm reference (ΔE00), {len(THICKNESS_NM)} thicknesses in "
          f"0–10 µm × cos θ ∈ {COS_THETA.tolist()} × films {list(FILMS)}; cost on the Warp CPU device, one thread.\n")
    print("| mode | ΔE00 mean | ΔE00 p95 | ΔE00 max | p95, films ≤ 2 µm | ns / evaluation |")
    print("|---|---:|---:|---:|---:|---:|")
    for name, errors in list(rows.items()) + [("reference", None)]:
        mode = name.split(" ")[0]
        ns = cost_ns(mode)
        if errors is None:
            print(f"| {name} | 0 | 0 | 0 | 0 | {ns:,.0f} |")
            continue
        e = np.concatenate(errors)
        e_thin = np.concatenate([x.reshape(len(COS_THETA), -1)[:, thin].ravel() for x in errors])
        print(f"| {name} | {e.mean():.2f} | {np.percentile(e, 95):.2f} | {e.max():.2f} | "
              f"{np.percentile(e_thin, 95):.2f} | {ns:,.0f} |")


if __name__ == "__main__":
    main()
