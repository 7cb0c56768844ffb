"""Rough ``thinfilm``: GGX facets carrying the coating (one film or a stack). Sampling agrees with
evaluation and follows the pdf (chi-square), reciprocity, a 0 nm film is the rough dielectric, a
coated rough glass sphere in a white furnace matches the rough dielectric one, and roughness → 0
converges to the smooth film."""
from __future__ import annotations

import numpy as np
import pytest

import renderer
from bsdf_harness import assert_reciprocal, bsdf_moments, bsdf_values, chi2_pvalue, random_pairs
from renderer import optics
from renderer.api import init_warp
from renderer.color import spectral
from renderer.materials import material
from scenes_py import single_object_scene

init_warp()

RGB3 = np.array(spectral.RGB3_WAVELENGTHS_NM)
CASES = {
    "clear film": dict(eta_film=1.33, thickness=400.0, eta_inner=1.5, transmission=True, roughness=0.3),
    "opaque film": dict(eta_film=1.55, thickness=500.0, eta_inner=1.66, reflectance=0.5, roughness=0.3),
    "black metal-backed film": dict(eta_film=1.4, thickness=300.0, eta_inner=0.2, k_inner=3.0, roughness=0.2),
    "tinted clear film": dict(eta_film=1.33, thickness=400.0, eta_inner=1.5, transmission=True, roughness=0.3,
                              tint=(0.7, 0.4, 0.1)),
    "clear stack, anisotropic": dict(layer_eta=[2.4, 1.46], layer_thickness=[57.3, 94.2], repeat=3, eta_inner=1.52,
                                     transmission=True, uroughness=0.1, vroughness=0.4),
}
ANGLES = [(0.3, 0.2, 0.9), (0.9, 0.1, 0.15), (0.0, 0.0, 1.0), (0.5, -0.4, -0.6)]


@pytest.mark.parametrize("name", list(CASES))
@pytest.mark.parametrize("wo", ANGLES, ids=["oblique", "grazing", "normal", "below"])
def test_sampling_matches_evaluation(name, wo):
    m = bsdf_moments("thinfilm", CASES[name], wo)
    tol = 5 * m["albedo_uniform_stderr"] + 0.01 * np.abs(m["albedo_uniform"]) + 1e-3
    assert np.all(np.abs(m["albedo_sampled"] - m["albedo_uniform"]) < tol)
    assert m["pdf_integral"] <= 1.0 + 0.02
    assert m["max_inconsistency"] < 2e-3
    assert np.all(m["albedo_sampled"] <= 1.5 ** 2 + 0.01)
    assert not any(f & 16 for f in m["lobe_flags"])   # no delta lobe once rough


@pytest.mark.parametrize("name", list(CASES))
@pytest.mark.parametrize("wo", [(0.3, 0.2, 0.9), (0.6, -0.3, -0.5)], ids=["above", "below"])
def test_sampled_directions_follow_the_pdf_chi_square(name, wo):
    assert chi2_pvalue("thinfilm", CASES[name], wo) > 1e-4


@pytest.mark.parametrize("name", list(CASES))
def test_reciprocity(name):
    assert_reciprocal("thinfilm", CASES[name], CASES[name]["eta_inner"])


def test_zero_thickness_is_the_rough_dielectric():
    wo, wi = random_pairs(2)
    # single scattering on both (pbrt's dielectric by default); the compensated pair is in test_multiscatter.py
    film = bsdf_values("thinfilm", dict(eta_film=1.33, thickness=0.0, eta_inner=1.5, transmission=True,
                                        roughness=0.2, multiscatter=False), wo, wi)
    bare = bsdf_values("dielectric", dict(eta=1.5, roughness=0.2), wo, wi)
    np.testing.assert_allclose(film, bare, rtol=1e-4, atol=1e-5)   # Airy vs Fresnel rounding near grazing


@pytest.mark.parametrize("thickness", [0.0, 400.0])
def test_furnace_rough_coated_glass_sphere_matches_rough_dielectric(thickness):
    """A lossless film on rough glass moves energy between R and T per wavelength but keeps
    R + T = 1: in a white furnace the sphere renders as the rough dielectric sphere does (both
    lose the same few per cent to single-scattering microfacets: the film's default compensation
    is off here, as the dielectric's is; compensated spheres are in test_multiscatter.py)."""
    def furnace(m) -> np.ndarray:
        desc = single_object_scene(m)
        desc.integrator.max_depth = 32
        return renderer.render(desc, spp=64, thin_film="rgb3", seed=5)[4:12, 4:12].mean(axis=(0, 1))
    coated = furnace(material("thinfilm", eta_film=1.33, eta_inner=1.5, thickness=thickness, transmission=True,
                              roughness=0.1, multiscatter=False))
    bare = furnace(material("dielectric", eta=1.5, roughness=0.1))
    assert np.all(bare < 1.0 + 1e-3) and np.all(bare > 0.5)
    np.testing.assert_allclose(coated, bare, atol=0.01 if thickness else 1e-4)


@pytest.mark.parametrize("transmission", [False, True])
def test_roughness_to_zero_converges_to_the_smooth_film(transmission):
    """The albedo seen from wo approaches the smooth film's R (black substrate) or R + T/η'²
    (clear glass) as the roughness goes to 0, the error falling with it (on clear glass the
    choice between R and T makes the estimate noisy, about 1e-3 at 4e5 samples)."""
    wo = np.array([0.4, 0.1, 0.8])
    wo = wo / np.linalg.norm(wo)
    base = dict(eta_film=1.33, thickness=450.0, eta_inner=1.5, transmission=transmission)
    r, t = optics.thin_film_reflectance_transmittance(wo[2], RGB3, 1.0, 1.33, 1.5, 450.0)
    smooth = r + (t / 1.5 ** 2 if transmission else 0.0)
    errors = []
    for roughness in (1e-2, 1e-3, 1e-4, 1e-5):
        m = bsdf_moments("thinfilm", base | dict(roughness=roughness), wo, n=400_000)
        errors.append(np.abs(m["albedo_sampled"] - smooth).max())
    assert errors[-1] < (4e-3 if transmission else 5e-4)
    if not transmission:
        assert errors[0] > 2 * errors[-1]
