"""pbrt-v4's ``thindielectric`` and ``diffusetransmission``: the sheet's summed reflectance against
an independent Fresnel computation, energy, sampling against the density, and both against
pbrt-v4's own image of a scene that uses them."""
from __future__ import annotations

import numpy as np
import pytest
import warp as wp

from bsdf_harness import bsdf_moments, chi2_pvalue
from pbrt_compare import DATA, MEAN_TOL, assert_matches_pbrt
from renderer.api import init_warp, load_scene, render
from renderer.materials.thindielectric import sheet_reflectance

init_warp()


def fresnel(c: np.ndarray, eta: float) -> np.ndarray:
    """Unpolarised reflectance from the side of index 1, written here independently."""
    s2 = (1 - c ** 2) / eta ** 2
    ct = np.sqrt(np.maximum(0.0, 1 - s2))
    rs = (c - eta * ct) / (c + eta * ct)
    rp = (eta * c - ct) / (eta * c + ct)
    return 0.5 * (rs ** 2 + rp ** 2)


@wp.kernel
def _sheet(cos: wp.array(dtype=float), eta: float, out: wp.array(dtype=float)):
    i = wp.tid()
    out[i] = sheet_reflectance(cos[i], eta)


@pytest.mark.parametrize("eta", [1.0, 1.33, 1.5, 2.4])
def test_sheet_reflectance_sums_the_internal_bounces(eta):
    c = np.array([1.0, 0.7, 0.3, 0.05, -0.4], np.float32)
    out = wp.zeros(len(c), dtype=float, device="cpu")
    wp.launch(_sheet, dim=len(c), inputs=[wp.array(c, dtype=float, device="cpu"), eta, out], device="cpu")
    r = fresnel(np.abs(c.astype(np.float64)), eta)
    bounces = sum(r * (1 - r) ** 2 * r ** (2 * k) for k in range(200))       # the series, not its sum
    np.testing.assert_allclose(out.numpy(), r + bounces, atol=2e-6)


def test_a_thin_shell_in_a_white_furnace_is_invisible():
    """A lossless sheet only redirects light: a thindielectric sphere under a uniform sky is 1."""
    path = DATA.parent / "scenes" / "mini.pbrt"        # any folder: the scene is written below
    text = ('LookAt 0 0 -4  0 0 0  0 1 0\nCamera "perspective" "float fov" [30]\nWorldBegin\n'
            'LightSource "infinite" "rgb L" [1 1 1]\nMaterial "thindielectric" "float eta" [1.7]\nShape "sphere"\n')
    scene = path.with_name("furnace_thin.pbrt")
    try:
        scene.write_text(text)
        img = render(load_scene(scene), spp=8, width=16, height=16, max_depth=64)
    finally:
        scene.unlink(missing_ok=True)
    np.testing.assert_allclose(img, 1.0, atol=2e-3)


@pytest.mark.parametrize("wo", [(0.3, 0.2, 0.9), (0.9, 0.1, 0.1), (0.2, 0.4, -0.8)])
def test_diffuse_transmission_energy_and_sampling(wo):
    values = {"reflectance": (0.2, 0.5, 0.1), "transmittance": (0.3, 0.4, 0.8)}
    m = bsdf_moments("diffusetransmission", values, wo)
    np.testing.assert_allclose(m["pdf_integral"], 1.0, atol=0.01)
    expected = np.array([0.5, 0.9, 0.9])
    np.testing.assert_allclose(m["albedo_uniform"], expected, atol=6 * m["albedo_uniform_stderr"].max() + 1e-3)
    np.testing.assert_allclose(m["albedo_sampled"], expected, atol=6 * m["albedo_sampled_stderr"].max())
    assert m["max_inconsistency"] < 1e-4
    assert chi2_pvalue("diffusetransmission", values, wo) > 1e-3


def test_both_match_pbrt():
    assert_matches_pbrt("thin_transmissive", mean_tol=2 * MEAN_TOL)
