"""Cost per evaluation of the layered materials (pbrt-v4's random walk) against the one-lobe
materials: nanoseconds per ``eval_pdf`` and per ``sample`` call, the best of three Warp CPU
launches over 2^16 random direction pairs on one thread (the integrator calls each once per
vertex: eval_pdf for next-event estimation, sample for the next bounce). ``thinfilm`` over a
diffuse base appears twice, one pass (the default) and ``layered`` (the walk), for one film and a
10-layer stack, in rgb3 and spectral:16.

    WARP_CACHE_PATH=.warp-cache .venv/bin/python benchmarks/layered_cost.py
"""
from __future__ import annotations

import sys
import time
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np
import warp as wp

from renderer.api import init_warp
from renderer.color.rgb_weights import RgbWeightTable, make_rgb_weight_table
from renderer.materials import REGISTRY, device_layout, kind_id, material
from renderer.materials.bsdf import BSDF, MAX_SLOTS, Slots
from renderer.sampling.warps import uniform_sphere

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "materials"))
from bsdf_harness import bsdf_from_rows, layer_table  # noqa: E402

N = 1 << 16
CASES = [
    ("diffuse", {}),
    ("conductor", dict(roughness=0.3)),
    ("coateddiffuse", {}),
    ("coateddiffuse", dict(roughness=0.3)),
    ("coateddiffuse", dict(roughness=0.3, albedo=0.8, thickness=0.5)),
    ("coatedconductor", {}),
    ("coatedconductor", {"interface.roughness": 0.2, "conductor.roughness": 0.3}),
]
FILM = dict(eta_film=1.33, thickness=400.0, eta_inner=1.5, reflectance=0.8)
STACK = dict(layer_eta=[2.4, 1.46], layer_thickness=[57.3, 94.2], repeat=5, eta_inner=1.52, reflectance=0.8)
for _coat in (FILM, STACK):
    for _rough in ({}, dict(roughness=0.3)):
        for _walk in ({}, dict(layered=True)):
            for _n in (0, 16):
                CASES.append(("thinfilm", _coat | _rough | _walk | {"spectral": _n}))


@wp.func
def _bsdf(p: Slots, flags: int, kind: int, layers: wp.array(dtype=wp.vec4), first: int, count: int,
          table: RgbWeightTable, n_lambda: int) -> BSDF:
    """The harness's BSDF (rgb3, the harness's layer table) with the colour-matching table added."""
    b = bsdf_from_rows(p, flags, kind, layers, first, count)
    b.spectral = table
    b.spectral_n = n_lambda
    return b


@lru_cache(maxsize=None)
def kernels(name: str):
    mod = REGISTRY[name]

    @wp.kernel(module="unique")
    def evaluate(p: Slots, flags: int, kind: int, layers: wp.array(dtype=wp.vec4), first: int, count: int,
                 table: RgbWeightTable, n_lambda: int, out: wp.array(dtype=wp.vec3)):
        i = wp.tid()
        rng = wp.rand_init(7, i)
        b = _bsdf(p, flags, kind, layers, first, count, table, n_lambda)
        b.wavelength_u = wp.randf(rng)
        wo = uniform_sphere(wp.vec2(wp.randf(rng), wp.randf(rng)))
        wi = uniform_sphere(wp.vec2(wp.randf(rng), wp.randf(rng)))
        e = wp.static(mod.eval_pdf)(b, wp.vec3(wo[0], wo[1], wp.abs(wo[2])), wp.vec3(wi[0], wi[1], wp.abs(wi[2])))
        out[i] = e.f * e.pdf

    @wp.kernel(module="unique")
    def draw(p: Slots, flags: int, kind: int, layers: wp.array(dtype=wp.vec4), first: int, count: int,
             table: RgbWeightTable, n_lambda: int, out: wp.array(dtype=wp.vec3)):
        i = wp.tid()
        rng = wp.rand_init(7, i)
        b = _bsdf(p, flags, kind, layers, first, count, table, n_lambda)
        b.wavelength_u = wp.randf(rng)
        wo = uniform_sphere(wp.vec2(wp.randf(rng), wp.randf(rng)))
        s = wp.static(mod.sample)(b, wp.vec3(wo[0], wo[1], wp.abs(wo[2])),
                                  wp.vec3(wp.randf(rng), wp.randf(rng), wp.randf(rng)))
        out[i] = s.weight * s.pdf

    return evaluate, draw


def ns_per_call(name: str, values: dict[str, Any], table: RgbWeightTable) -> tuple[float, float]:
    values = dict(values)
    n_lambda = values.pop("spectral", 0)
    desc = material(name, **values)
    layout, flags = device_layout(desc)
    rows = np.zeros((MAX_SLOTS, 3), dtype=np.float32)
    for j, (_, v) in enumerate(layout):
        if v is not None:
            rows[j] = np.broadcast_to(np.asarray(v, dtype=np.float32), (3,))
    layers, first, count = layer_table(name, values)    # the energy tables too, where used
    inputs = [Slots(*rows.ravel().tolist()), int(flags), kind_id(name), layers, first, count, table, n_lambda]
    out = wp.empty(N, dtype=wp.vec3, device="cpu")
    times = []
    for k in kernels(name):
        wp.launch(k, dim=N, inputs=[*inputs, out], device="cpu")   # compile and warm up
        best = np.inf
        for _ in range(3):
            t = time.perf_counter()
            wp.launch(k, dim=N, inputs=[*inputs, out], device="cpu")
            wp.synchronize_device("cpu")
            best = min(best, time.perf_counter() - t)
        times.append(best / N * 1e9)
    return times[0], times[1]


def main() -> None:
    init_warp()
    table = make_rgb_weight_table("cpu")
    base = None
    print(f"{'material':<60} {'eval_pdf ns':>12} {'sample ns':>10} {'eval vs diffuse':>16}")
    for name, values in CASES:
        e, s = ns_per_call(name, values, table)
        base = base or e
        label = f"{name} {values}" if values else name
        if name == "thinfilm":
            label = " ".join(["thinfilm", "stack of 10" if "layer_eta" in values else "film",
                              "rough" if "roughness" in values else "smooth",
                              "layered" if values.get("layered") else "one pass",
                              f"spectral:{values['spectral']}" if values["spectral"] else "rgb3"])
        print(f"{label:<60} {e:>12.0f} {s:>10.0f} {e / base:>15.1f}x")


if __name__ == "__main__":
    main()
