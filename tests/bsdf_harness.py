"""Monte Carlo checks of a material's eval/pdf/sample triple, run through the same Warp functions
the integrator calls."""
from __future__ import annotations

from functools import lru_cache

import numpy as np
import warp as wp

from renderer.materials import REGISTRY, kind_id
from renderer.materials.bsdf import BSDF, MAX_SLOTS, Slots
from renderer.sampling import uniform_sphere


@lru_cache(maxsize=None)
def _kernel(name: str):
    mod = REGISTRY[name]

    @wp.kernel(module="unique")
    def check(p: Slots, kind: int, wo: wp.vec3, seed: int, out: wp.array(dtype=wp.vec3, ndim=2)):
        i = wp.tid()
        rng = wp.rand_init(seed, i)
        b = BSDF()
        b.kind = kind
        b.p = p
        # uniform-sphere estimates of the integrals of pdf and of f |cos|
        wi = uniform_sphere(wp.vec2(wp.randf(rng), wp.randf(rng)))
        inv = 4.0 * 3.14159265358979
        out[i, 0] = wp.vec3(wp.static(mod.pdf)(b, wo, wi) * inv, 0.0, 0.0)
        out[i, 1] = wp.static(mod.eval)(b, wo, wi) * (wp.abs(wi[2]) * inv)
        s = wp.static(mod.sample)(b, wo, wp.vec3(wp.randf(rng), wp.randf(rng), wp.randf(rng)))
        w = wp.vec3(0.0)
        err = float(0.0)
        if s.pdf > 0.0:
            w = s.weight
            if not s.specular:
                # the sample's pdf and weight must agree with pdf() and eval()
                pe = wp.static(mod.pdf)(b, wo, s.wi)
                fe = wp.static(mod.eval)(b, wo, s.wi) * (wp.abs(s.wi[2]) / s.pdf)
                err = wp.abs(pe - s.pdf) / wp.max(s.pdf, 1.0e-6) + wp.length(fe - s.weight) / wp.max(wp.length(s.weight), 1.0e-6)
        out[i, 2] = w
        out[i, 3] = wp.vec3(err, 0.0, 0.0)

    return check


def bsdf_moments(name: str, slots: list, wo, n: int = 400_000, seed: int = 1) -> dict[str, np.ndarray]:
    """Estimates of ∫pdf, ∫f|cos| (uniform sampling), E[sample weight] (importance sampling)
    and the largest sample/pdf/eval inconsistency, for a material with constant slot values."""
    p = np.zeros((MAX_SLOTS, 3), dtype=np.float32)
    for i, v in enumerate(slots):
        p[i] = v
    wo = np.asarray(wo, dtype=np.float64)
    wo = wo / np.linalg.norm(wo)
    out = wp.zeros((n, 4), dtype=wp.vec3, device="cpu")
    wp.launch(_kernel(name), dim=n, inputs=[Slots(*p.ravel().tolist()), kind_id(name), wp.vec3(*wo), seed, out],
              device="cpu")
    o = out.numpy()
    return {"pdf_integral": o[:, 0, 0].mean(), "albedo_uniform": o[:, 1].mean(axis=0),
            "albedo_sampled": o[:, 2].mean(axis=0), "max_inconsistency": o[:, 3, 0].max(),
            "albedo_uniform_stderr": o[:, 1].std(axis=0) / np.sqrt(n)}
