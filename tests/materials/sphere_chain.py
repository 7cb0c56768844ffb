"""The white furnace of a closed sphere without a scene: inside a sphere a straight ray meets the
surface again at the cosine it left with (a chord makes equal angles with the normal at both ends),
so for an isotropic BSDF a path is a chain of local directions, wo → sampled wi → the next wo at
cos = −|wi.z| with the azimuth irrelevant. That chain, run through the material's own eval_pdf and
sample with the 1/η'² radiance scaling the integrator uses, is the integrator's estimate of a closed
sphere under a sky of radiance 1 minus the geometry: BSDF sampling alone, or with a light sample
(uniform over the sphere of directions) at every vertex, power-heuristic weighted against BSDF
sampling, as next-event estimation does. The two agree only if eval_pdf's density is the sampler's.
A lossless sphere must return 1 whatever its number of internal bounces, so a bias per bounce of
1e-4 shows here as 1e-3 once compounded, at a cost a test can pay."""
from __future__ import annotations

from functools import lru_cache

import numpy as np
import warp as wp

from bsdf_harness import _bsdf_inputs, bsdf_from_rows
from renderer.materials import REGISTRY
from renderer.materials.bsdf import SPECULAR, Slots
from renderer.sampling.mis import power_heuristic
from renderer.sampling.warps import uniform_sphere

INV_4PI = 1.0 / (4.0 * np.pi)


@lru_cache(maxsize=None)
def _kernel(name: str):
    mod = REGISTRY[name]

    @wp.kernel(module="unique")
    def chain(p: Slots, flags: int, kind: int, layers: wp.array(dtype=wp.vec4), first: int, count: int,
              mu0: float, max_depth: int, nee: int, seed: int, out: wp.array(dtype=wp.vec4)):
        """out[i]: the path's radiance (xyz) and its number of vertices (w)."""
        i = wp.tid()
        rng = wp.rand_init(seed, i)
        b = bsdf_from_rows(p, flags, kind, layers, first, count)
        wo = wp.vec3(wp.sqrt(1.0 - mu0 * mu0), 0.0, mu0)
        beta = wp.vec3(1.0)
        L = wp.vec3(0.0)
        p_light = wp.static(INV_4PI)
        depth = int(0)
        while depth < max_depth:
            depth += 1
            if nee != 0:
                wl = uniform_sphere(wp.vec2(wp.randf(rng), wp.randf(rng)))
                if wl[2] > 0.0:        # towards the sky: the shadow ray escapes; inwards it meets the sphere
                    e = wp.static(mod.eval_pdf)(b, wo, wl)
                    if e.pdf > 0.0:
                        L += wp.cw_mul(beta, e.f) * (wl[2] / p_light * power_heuristic(p_light, e.pdf))
            s = wp.static(mod.sample)(b, wo, wp.vec3(wp.randf(rng), wp.randf(rng), wp.randf(rng)))
            if s.pdf <= 0.0:
                break
            beta = wp.cw_mul(beta, s.weight)
            if s.wi[2] > 0.0:
                w = float(1.0)
                if nee != 0 and (s.flags & SPECULAR) == 0:
                    w = power_heuristic(s.pdf, p_light)
                L += beta * w
                break
            mu = wp.abs(s.wi[2])
            wo = wp.vec3(wp.sqrt(wp.max(1.0 - mu * mu, 0.0)), 0.0, -mu)
        out[i] = wp.vec4(L[0], L[1], L[2], float(depth))

    return chain


def sphere_furnace(name: str, values: dict, mu0: float = 0.8, n: int = 100_000, max_depth: int = 64,
                   nee: bool = True, seed: int = 1) -> dict[str, np.ndarray]:
    """The furnace value (RGB) of a closed sphere of this material seen at cosine ``mu0``, its
    standard error, and the mean number of vertices per path."""
    out = wp.zeros(n, dtype=wp.vec4, device="cpu")
    wp.launch(_kernel(name), dim=n, inputs=[*_bsdf_inputs(name, values), float(mu0), max_depth, int(nee), seed, out],
              device="cpu")
    o = out.numpy().astype(np.float64)
    return {"value": o[:, :3].mean(axis=0), "stderr": o[:, :3].std(axis=0) / np.sqrt(n),
            "vertices": o[:, 3].mean()}
