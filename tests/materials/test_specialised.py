"""Kernels compile only the lobes a scene's materials can reach (``Features.multiscatter``,
``.layered``, ``.smooth``; :func:`renderer.materials.hooks`). What a material does must not change:
for every material a scene of it alone gets specialised functions, and they return exactly what
the functions with every lobe return, at the same directions and random numbers."""
from __future__ import annotations

from functools import lru_cache
from pathlib import Path

import numpy as np
import pytest
import warp as wp

from renderer.api import load_scene
from renderer.device.kernel_options import KERNEL_OPTIONS
from renderer.device.scene import Features
from renderer.materials import REGISTRY, hooks, lobe_features, material, with_multiscatter
from renderer.materials.bsdf import Slots
from bsdf_harness import _bsdf_inputs, bsdf_from_rows

ROOT = Path(__file__).resolve().parents[2]
N = 4096


@lru_cache(maxsize=None)
def _kernel(eval_pdf: wp.Function, sample: wp.Function):
    @wp.kernel(module="unique", module_options=KERNEL_OPTIONS)
    def run(p: Slots, flags: int, kind: int, layers: wp.array(dtype=wp.vec4), first: int, count: int,
            seed: int, out: wp.array(dtype=float, ndim=2)):
        i = wp.tid()
        rng = wp.rand_init(seed, i)
        b = bsdf_from_rows(p, flags, kind, layers, first, count)
        b.wavelength_u = wp.randf(rng)
        # directions on both sides, so transmission and hits from below are covered
        wo = wp.normalize(wp.vec3(wp.randf(rng) - 0.5, wp.randf(rng) - 0.5, wp.randf(rng) - 0.3))
        wi = wp.normalize(wp.vec3(wp.randf(rng) - 0.5, wp.randf(rng) - 0.5, wp.randf(rng) - 0.5))
        e = wp.static(eval_pdf)(b, wo, wi)
        s = wp.static(sample)(b, wo, wp.vec3(wp.randf(rng), wp.randf(rng), wp.randf(rng)))
        row = wp.vector(e.f[0], e.f[1], e.f[2], e.pdf, s.wi[0], s.wi[1], s.wi[2], s.weight[0], s.weight[1],
                        s.weight[2], s.pdf, float(s.flags), s.eta, length=13, dtype=float)
        for j in range(13):
            out[i, j] = row[j]

    return run


def _outputs(name: str, values: dict, funcs: tuple[wp.Function, wp.Function]) -> np.ndarray:
    out = wp.zeros((N, 13), dtype=float, device="cpu")
    wp.launch(_kernel(*funcs), dim=N, inputs=[*_bsdf_inputs(name, values), 7, out], device="cpu")
    return out.numpy()


def _features(name: str, values: dict) -> Features:
    """The features of a scene whose only material is this one."""
    return Features(materials=(name,), bump=False, lights=(), escaping=(),
                    **lobe_features([material(name, **values)]))


CASES = [
    ("dielectric", {}),
    ("dielectric", {"roughness": 0.3}),
    ("dielectric", {"roughness": 0.3, "eta": 1.0 / 1.33}),
    ("conductor", {}),
    ("conductor", {"roughness": 0.2}),
    ("conductor", {"reflectance": (0.9, 0.6, 0.3)}),
    ("thinfilm", {"reflectance": (0.5, 0.4, 0.3)}),
    ("thinfilm", {"transmission": True, "tint": (0.8, 0.9, 0.7)}),
    ("thinfilm", {"roughness": 0.1, "reflectance": 0.3, "multiscatter": False}),
    ("thinfilm", {"roughness": 0.1, "transmission": True, "multiscatter": False}),
    ("thinfilm", {"roughness": 0.1, "reflectance": 0.3}),
    ("thinfilm", {"roughness": 0.1, "transmission": True, "thickness": 300.0}),
    ("thinfilm", {"k_inner": 2.0, "eta_inner": 0.5}),
    ("thinfilm", {"layered": True, "reflectance": (0.6, 0.5, 0.4)}),     # the walk under a smooth coating
]


@pytest.mark.parametrize("name,values", CASES, ids=[f"{n}-{'-'.join(v)}" for n, v in CASES])
def test_specialised_lobes_equal_every_lobe(name, values):
    module = REGISTRY[name]
    specialised = hooks(module, _features(name, values))
    assert specialised != (module.eval_pdf, module.sample)    # something was left out
    full = _outputs(name, values, (module.eval_pdf, module.sample))
    assert np.any(full[:, 10] > 0.0)                         # some samples succeed
    np.testing.assert_array_equal(_outputs(name, values, specialised), full)


def test_scene_features():
    demo = load_scene(ROOT / "scenes" / "demo.pbrt")      # smooth glass and mirror, rough copper
    assert lobe_features(demo.materials) == {"multiscatter": False, "layered": False, "unlayered": False,
                                             "smooth": ("dielectric",), "coated_body": False, "coated_disney": False}
    assert lobe_features(with_multiscatter(demo).materials)["multiscatter"]
    # smooth films: their multiscatter (on by default) has nothing to compensate
    coating = load_scene(ROOT / "scenes" / "ar_coating.pbrt")
    assert lobe_features(coating.materials) == {"multiscatter": False, "layered": False, "unlayered": True,
                                                "smooth": ("thinfilm",), "coated_body": False, "coated_disney": False}
    rough = [material("thinfilm", roughness=0.1), material("thinfilm", layered=True)]
    assert lobe_features(rough) == {"multiscatter": True, "layered": True, "unlayered": True, "smooth": (),
                                    "coated_body": False, "coated_disney": False}
    assert lobe_features([material("conductor", uroughness=0.0, vroughness=0.1, multiscatter=True)]) == {
        "multiscatter": True, "layered": False, "unlayered": False, "smooth": (), "coated_body": False,
        "coated_disney": False}
