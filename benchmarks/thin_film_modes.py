"""Thin-film colour modes: accuracy (ΔE00 against the 1 nm reference) versus cost per evaluation.

Films of 0–10 µm at several angles, for a soap film in air and the seed's coat (1.55 on 1.66).
Colours are the linear-sRGB reflectances under D65, compared in CIELAB (D65 white, Y = 1) with
CIE 2000. Deterministic modes are the numpy wrapper's quadratures; "jittered:N" is the renderer's
estimator, one evaluation (the noise a single sample carries) and the mean of 64 (what an image
converges to). Cost: the best of four Warp CPU launches of the mode's kernel over 2^20 evaluations
(2^14 for the reference) on one thread, inputs already on the device.

    WARP_CACHE_PATH=.warp-cache .venv/bin/python benchmarks/thin_film_modes.py
"""
from __future__ import annotations

import time
from functools import lru_cache

import colour
import numpy as np
import warp as wp

from renderer.optics import arrays as optics
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
    best = np.inf
    for _ in range(4):
        start = time.perf_counter()
        wp.launch(kernel, dim=m, inputs=args, device="cpu")
        wp.synchronize_device("cpu")
        best = min(best, time.perf_counter() - start)
    return best / m * 1e9


def main() -> None:
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
