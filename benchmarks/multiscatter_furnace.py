"""The acceptance furnace of ``multiscatter`` (issue 29): closed rough spheres of lossless interfaces
(glass, a 350 nm water film on glass, a 6-layer TiO2/SiO2-like mirror stack on glass, a conductor of
reflectance 1) under a white sky, depth 64, no roulette, rgb3, at roughness 0.3 and 1; printed as the
mean of the middle 8×8 pixels of a 16×16 render ± the standard error over independent seeds.

The error bar comes from the seeds, not from the pixels: a coated sphere's estimator is heavy-tailed
(the sampler picks reflection or refraction by the mean of R and T over the channels, so a channel
whose R differs from the mean carries weights R_c / mean R, compounded over internal bounces; single
paths of the stack weigh up to ~300 for a mean of 1), and one render's pixel spread then understates
its error (the stack at roughness 1 read (0.999, 0.987, 0.991) ± 0.003 over seeds 1-8 and
(1.000, 1.000, 1.001) ± 0.003 over seeds 9-24: pass 24 seeds for that row). Also printed: the same
spheres by the scene-free chain of tests/materials/sphere_chain.py.

    WARP_CACHE_PATH=.warp-cache .venv/bin/python benchmarks/multiscatter_furnace.py [spp] [seeds]
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "materials"))
from scenes_py import single_object_scene  # noqa: E402
from sphere_chain import sphere_furnace  # noqa: E402

import renderer  # noqa: E402
from renderer.api import init_warp  # noqa: E402
from renderer.materials import material  # noqa: E402

CASES = {
    "glass": ("dielectric", dict(eta=1.5, multiscatter=True)),
    "water film on glass": ("thinfilm", dict(eta_film=1.33, thickness=350.0, eta_inner=1.5, transmission=True)),
    "mirror stack on glass": ("thinfilm", dict(layer_eta=[2.4, 1.46], layer_thickness=[57.3, 94.2], repeat=3,
                                               eta_inner=1.52, transmission=True)),
    "conductor, R = 1": ("conductor", dict(eta=(1.0, 1.0, 1.0), k=(1000.0, 1000.0, 1000.0), multiscatter=True)),
}
ROUGHNESS = (0.3, 1.0)


def furnace_render(kind: str, values: dict, roughness: float, spp: int, seed: int) -> np.ndarray:
    desc = single_object_scene(material(kind, **values, roughness=roughness))
    desc.integrator.max_depth = 64
    img = renderer.render(desc, spp=spp, thin_film="rgb3", seed=seed, rr_depth=-1, threads=1)
    return img[4:12, 4:12].reshape(-1, 3).astype(np.float64).mean(axis=0)


def fmt(v: np.ndarray) -> str:
    return "(" + ", ".join(f"{x:.3f}" for x in v) + ")"


def main(spp: int = 256, seeds: int = 8, chain_paths: int = 400_000) -> None:
    init_warp()
    print(f"| case | roughness | render, {seeds} seeds × {spp} spp | ± | chain, {chain_paths} paths | ± | s |")
    print("|---|---:|---|---|---|---|---:|")
    for name, (kind, values) in CASES.items():
        for r in ROUGHNESS:
            t = time.perf_counter()
            means = np.stack([furnace_render(kind, values, r, spp, seed) for seed in range(1, seeds + 1)])
            err = means.std(axis=0, ddof=1) / np.sqrt(seeds)
            ch = sphere_furnace(kind, values | dict(roughness=r), n=chain_paths)
            print(f"| {name} | {r} | {fmt(means.mean(axis=0))} | {fmt(err)} | {fmt(ch['value'])} | "
                  f"{fmt(ch['stderr'])} | {time.perf_counter() - t:.0f} |", flush=True)


if __name__ == "__main__":
    main(*(int(a) for a in sys.argv[1:]))
