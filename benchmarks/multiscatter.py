"""What ``multiscatter`` costs and what it changes: nanoseconds per ``eval_pdf`` and ``sample``
call with single and multiple scattering (benchmarks/layered_cost.py's timing: best of three Warp
CPU launches over 2^16 random direction pairs, one thread), and at equal samples per pixel the
noise and time of small renders of closed rough spheres (glass, gold, a soap film on glass, a
TiO2/SiO2 mirror stack on glass) under a white sky, both ways, with their mean (the furnace value
for the lossless ones).

    WARP_CACHE_PATH=.warp-cache .venv/bin/python benchmarks/multiscatter.py [--renders-only|--calls-only]
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from layered_cost import ns_per_call  # noqa: E402
from scenes_py import single_object_scene  # noqa: E402

import renderer  # noqa: E402
from renderer.api import init_warp  # noqa: E402
from renderer.color.rgb_weights import make_rgb_weight_table  # noqa: E402
from renderer.materials import material  # noqa: E402

GOLD = dict(eta=(0.143, 0.374, 1.442), k=(3.983, 2.385, 1.603))
SOAP = dict(eta_film=1.33, thickness=350.0, eta_inner=1.5, transmission=True)
STACK = dict(layer_eta=[2.4, 1.46], layer_thickness=[57.3, 94.2], repeat=3, eta_inner=1.52, transmission=True)
CALLS = [
    ("dielectric", dict(eta=1.5, roughness=0.3)),
    ("conductor", GOLD | dict(roughness=0.3)),
    ("thinfilm", SOAP | dict(roughness=0.3)),
    ("thinfilm", SOAP | dict(roughness=0.3, spectral=16)),
    ("thinfilm", dict(eta_film=1.4, thickness=300.0, eta_inner=0.2, k_inner=3.0, roughness=0.3)),
    ("thinfilm", STACK | dict(roughness=0.3)),
]
SPHERES = {"glass": ("dielectric", dict(eta=1.5)), "gold": ("conductor", GOLD),
           "soap film on glass": ("thinfilm", SOAP), "mirror stack on glass": ("thinfilm", STACK)}
ROUGHNESS = (0.1, 0.3, 0.6, 1.0)


def calls() -> None:
    init_warp()
    table = make_rgb_weight_table("cpu")
    print(f"{'material':<70} {'eval ns single':>14} {'multiple':>9} {'sample ns single':>16} {'multiple':>9}")
    for name, values in CALLS:
        e0, s0 = ns_per_call(name, values | {"multiscatter": False}, table)
        e1, s1 = ns_per_call(name, values | {"multiscatter": True}, table)
        label = f"{name} " + " ".join(f"{k}={v}" for k, v in values.items() if k not in ("layer_thickness",))
        print(f"{label[:70]:<70} {e0:>14.0f} {e1:>9.0f} {s0:>16.0f} {s1:>9.0f}", flush=True)


def _render(kind: str, values: dict, roughness: float, multiscatter: bool, seed: int, spp: int,
            thin_film: str) -> tuple[np.ndarray, float]:
    desc = single_object_scene(material(kind, **values, roughness=roughness, multiscatter=multiscatter), res=32)
    desc.integrator.max_depth = 64
    t = time.perf_counter()
    img = renderer.render(desc, spp=spp, seed=seed, thin_film=thin_film, rr_depth=-1, threads=1)
    return img[8:24, 8:24].astype(np.float64), time.perf_counter() - t


def renders(spp: int = 16, seeds: int = 4, thin_film: str = "rgb3") -> None:
    """Per-pixel relative noise (standard deviation over seeds / mean) of the sphere's middle 16x16
    pixels, their mean, and the seconds per render, single vs multiple scattering."""
    init_warp()
    print(f"{'sphere':<24} {'roughness':>9} {'mean single':>20} {'mean multiple':>20} {'noise single':>12} "
          f"{'noise multiple':>14} {'s single':>8} {'s multiple':>10}")
    for label, (kind, values) in SPHERES.items():
        for r in ROUGHNESS:
            row = []
            for ms in (False, True):
                runs = [_render(kind, values, r, ms, seed, spp, thin_film) for seed in range(seeds)]
                imgs = np.stack([im for im, _ in runs])
                mean = imgs.mean(axis=0)
                noise = float(np.mean(imgs.std(axis=0, ddof=1) / np.maximum(mean, 1e-6)))
                row.append((mean.mean(axis=(0, 1)), noise, float(np.mean([t for _, t in runs[1:]]))))
            (m0, n0, t0), (m1, n1, t1) = row
            fmt = lambda m: "(" + ", ".join(f"{x:.3f}" for x in m) + ")"  # noqa: E731
            print(f"{label:<24} {r:>9} {fmt(m0):>20} {fmt(m1):>20} {n0:>12.3f} {n1:>14.3f} {t0:>8.2f} {t1:>10.2f}",
                  flush=True)


if __name__ == "__main__":
    if "--renders-only" not in sys.argv:
        calls()
    if "--calls-only" not in sys.argv:
        renders()
