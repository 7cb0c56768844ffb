"""Cost per evaluation of the layered materials (pbrt-v4's random walk) against the one-lobe
materials: nanoseconds per ``eval_pdf`` and per ``sample`` call, the best of three Warp CPU
launches over 2^16 random direction pairs on one thread (the integrator calls each once per
vertex: eval_pdf for next-event estimation, sample for the next bounce).

    WARP_CACHE_PATH=.warp-cache .venv/bin/python benchmarks/layered_cost.py
"""
from __future__ import annotations

import time
from functools import lru_cache
from typing import Any

import numpy as np
import warp as wp

from renderer.api import init_warp
from renderer.materials import REGISTRY, device_layout, kind_id, material
from renderer.materials.bsdf import BSDF, MAX_SLOTS, Slots
from renderer.sampling.warps import uniform_sphere

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


@lru_cache(maxsize=None)
def kernels(name: str):
    mod = REGISTRY[name]

    @wp.kernel(module="unique")
    def evaluate(p: Slots, flags: int, kind: int, out: wp.array(dtype=wp.vec3)):
        i = wp.tid()
        rng = wp.rand_init(7, i)
        b = BSDF()
        b.kind = kind
        b.p = p
        b.flags = flags
        b.wavelength_u = wp.randf(rng)
        wo = uniform_sphere(wp.vec2(wp.randf(rng), wp.randf(rng)))
        wi = uniform_sphere(wp.vec2(wp.randf(rng), wp.randf(rng)))
        e = wp.static(mod.eval_pdf)(b, wp.vec3(wo[0], wo[1], wp.abs(wo[2])), wp.vec3(wi[0], wi[1], wp.abs(wi[2])))
        out[i] = e.f * e.pdf

    @wp.kernel(module="unique")
    def draw(p: Slots, flags: int, kind: int, out: wp.array(dtype=wp.vec3)):
        i = wp.tid()
        rng = wp.rand_init(7, i)
        b = BSDF()
        b.kind = kind
        b.p = p
        b.flags = flags
        b.wavelength_u = wp.randf(rng)
        wo = uniform_sphere(wp.vec2(wp.randf(rng), wp.randf(rng)))
        s = wp.static(mod.sample)(b, wp.vec3(wo[0], wo[1], wp.abs(wo[2])),
                                  wp.vec3(wp.randf(rng), wp.randf(rng), wp.randf(rng)))
        out[i] = s.weight * s.pdf

    return evaluate, draw


def ns_per_call(name: str, values: dict[str, Any]) -> tuple[float, float]:
    layout, flags = device_layout(material(name, **values))
    rows = np.zeros((MAX_SLOTS, 3), dtype=np.float32)
    for j, (_, v) in enumerate(layout):
        if v is not None:
            rows[j] = np.broadcast_to(np.asarray(v, dtype=np.float32), (3,))
    inputs = [Slots(*rows.ravel().tolist()), int(flags), kind_id(name)]
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
    base = None
    print(f"{'material':<60} {'eval_pdf ns':>12} {'sample ns':>10} {'eval vs diffuse':>16}")
    for name, values in CASES:
        e, s = ns_per_call(name, values)
        base = base or e
        label = f"{name} {values}" if values else name
        print(f"{label:<60} {e:>12.0f} {s:>10.0f} {e / base:>15.1f}x")


if __name__ == "__main__":
    main()
