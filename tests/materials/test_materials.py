"""Each material's sample and eval_pdf agree, pdfs integrate to at most 1, no lobe creates
energy, and samples carry the lobe flags of the lobe they came from."""
from __future__ import annotations

import numpy as np
import pytest

from bsdf_harness import bsdf_moments
from renderer.api import init_warp
from renderer.materials.bsdf import DIFFUSE, GLOSSY, REFLECTION, SPECULAR, TRANSMISSION

init_warp()

CASES = [
    ("diffuse", dict(reflectance=(0.8, 0.5, 0.2))),
    ("conductor", dict(eta=(0.2, 0.9, 1.1), k=(3.9, 2.4, 2.1), uroughness=0.04, vroughness=0.04)),
    ("conductor", dict(eta=1.0, k=100.0, roughness=0.5)),
    ("conductor", dict(eta=1.0, k=100.0, uroughness=0.05, vroughness=0.6)),
    ("dielectric", dict(eta=1.5, roughness=0.3)),
    ("dielectric", dict(eta=1.33, uroughness=0.05, vroughness=0.2)),
]
ANGLES = [(0.3, 0.2, 0.9), (0.9, 0.1, 0.1), (0.0, 0.0, 1.0), (0.5, -0.4, -0.6)]


@pytest.mark.parametrize("name,values", CASES, ids=[f"{c[0]}{i}" for i, c in enumerate(CASES)])
@pytest.mark.parametrize("wo", ANGLES, ids=["oblique", "grazing", "normal", "below"])
def test_sampling_matches_evaluation(name, values, wo):
    m = bsdf_moments(name, values, wo)
    # importance-sampled and uniformly-sampled estimates of the same albedo agree
    tol = 5 * m["albedo_uniform_stderr"] + 0.01 * np.abs(m["albedo_uniform"]) + 1e-3
    assert np.all(np.abs(m["albedo_sampled"] - m["albedo_uniform"]) < tol)
    # a sampling density integrates to at most 1 (less where samples fail, e.g. below the horizon)
    assert m["pdf_integral"] <= 1.0 + 0.02
    # sample() returns the same pdf and f as eval_pdf() for the direction it picked
    assert m["max_inconsistency"] < 2e-3
    limit = 1.0 if name != "dielectric" else 1.5 ** 2  # refraction into a denser medium concentrates radiance
    assert np.all(m["albedo_sampled"] <= limit + 0.01)


def test_diffuse_pdf_integrates_to_one():
    m = bsdf_moments("diffuse", dict(reflectance=1.0), (0.2, 0.1, 0.7))
    assert abs(m["pdf_integral"] - 1.0) < 0.01
    np.testing.assert_allclose(m["albedo_sampled"], 1.0, atol=1e-6)


@pytest.mark.parametrize("name,values,flags", [
    ("diffuse", {}, {REFLECTION | DIFFUSE}),
    ("conductor", {}, {REFLECTION | SPECULAR}),
    ("conductor", dict(roughness=0.3), {REFLECTION | GLOSSY}),
    ("dielectric", {}, {REFLECTION | SPECULAR, TRANSMISSION | SPECULAR}),
    ("dielectric", dict(roughness=0.3), {REFLECTION | GLOSSY, TRANSMISSION | GLOSSY}),
    ("thinfilm", dict(reflectance=0.5), {REFLECTION | SPECULAR, REFLECTION | DIFFUSE}),
    ("thinfilm", dict(transmission=True), {REFLECTION | SPECULAR, TRANSMISSION | SPECULAR}),
    ("disney", dict(thin=True, spectrans=0.5), {REFLECTION | DIFFUSE, REFLECTION | GLOSSY, TRANSMISSION | GLOSSY,
                                                TRANSMISSION | DIFFUSE}),
], ids=["diffuse", "mirror", "rough-metal", "glass", "rough-glass", "film-base", "film-clear", "disney-thin"])
def test_samples_carry_their_lobe_flags(name, values, flags):
    """pbrt's BxDFFlags: the side wi lies on and the kind of lobe, SPECULAR exactly for delta lobes
    (the integrator skips MIS on those and only on those)."""
    m = bsdf_moments(name, values, (0.3, 0.2, 0.9), n=20_000)
    assert m["lobe_flags"] == flags
    if all(f & SPECULAR for f in flags):
        assert m["pdf_integral"] == 0.0    # no density anywhere: next-event estimation cannot reach a delta lobe


CHI2_CASES = [
    ("diffuse", dict(reflectance=(0.8, 0.5, 0.2))),
    ("conductor", dict(eta=1.0, k=100.0, roughness=0.5)),
    ("conductor", dict(eta=1.0, k=100.0, uroughness=0.2, vroughness=0.6)),
    ("dielectric", dict(eta=1.5, roughness=0.4)),
]


@pytest.mark.parametrize("name,values", CHI2_CASES, ids=[f"{c[0]}{i}" for i, c in enumerate(CHI2_CASES)])
@pytest.mark.parametrize("wo", [(0.3, 0.2, 0.9), (0.8, -0.1, 0.3), (0.4, 0.3, -0.7)], ids=["oblique", "low", "below"])
def test_sampled_directions_follow_the_pdf_chi_square(name, values, wo):
    """Histogram of sampled directions against eval_pdf's density integrated over each cell (Pearson chi-square)."""
    from bsdf_harness import chi2_pvalue

    assert chi2_pvalue(name, values, wo) > 1e-4
