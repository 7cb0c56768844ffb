"""Each material's sample/pdf/eval agree, pdfs integrate to at most 1, no lobe creates energy."""
from __future__ import annotations

import numpy as np
import pytest

from bsdf_harness import bsdf_moments
from renderer.api import init_warp

init_warp()

CASES = [
    ("diffuse", [(0.8, 0.5, 0.2)]),
    ("conductor", [(0.2, 0.9, 1.1), (3.9, 2.4, 2.1), (0.04,) * 3, (0.04,) * 3, (1, 1, 1), (0, 0, 0), (0, 0, 0)]),
    ("conductor", [(1, 1, 1), (100, 100, 100), (0.5,) * 3, (0.5,) * 3, (1, 1, 1), (0, 0, 0), (0, 0, 0)]),
    ("conductor", [(1, 1, 1), (100, 100, 100), (0.05,) * 3, (0.6,) * 3, (1, 1, 1), (0, 0, 0), (0, 0, 0)]),
    ("dielectric", [(1.5,) * 3, (0.3,) * 3, (0.3,) * 3, (1, 1, 1)]),
    ("dielectric", [(1.33,) * 3, (0.05,) * 3, (0.2,) * 3, (1, 1, 1)]),
]
ANGLES = [(0.3, 0.2, 0.9), (0.9, 0.1, 0.1), (0.0, 0.0, 1.0), (0.5, -0.4, -0.6)]


@pytest.mark.parametrize("name,slots", CASES, ids=[f"{c[0]}{i}" for i, c in enumerate(CASES)])
@pytest.mark.parametrize("wo", ANGLES, ids=["oblique", "grazing", "normal", "below"])
def test_sampling_matches_evaluation(name, slots, wo):
    m = bsdf_moments(name, slots, wo)
    # importance-sampled and uniformly-sampled estimates of the same albedo agree
    tol = 5 * m["albedo_uniform_stderr"] + 0.01 * np.abs(m["albedo_uniform"]) + 1e-3
    assert np.all(np.abs(m["albedo_sampled"] - m["albedo_uniform"]) < tol)
    # a sampling density integrates to at most 1 (less where samples fail, e.g. below the horizon)
    assert m["pdf_integral"] <= 1.0 + 0.02
    # sample() returns the same pdf and f as pdf() and eval() for the direction it picked
    assert m["max_inconsistency"] < 2e-3
    limit = 1.0 if name != "dielectric" else 1.5 ** 2  # refraction into a denser medium concentrates radiance
    assert np.all(m["albedo_sampled"] <= limit + 0.01)


def test_diffuse_pdf_integrates_to_one():
    m = bsdf_moments("diffuse", [(1, 1, 1)], (0.2, 0.1, 0.7))
    assert abs(m["pdf_integral"] - 1.0) < 0.01
    np.testing.assert_allclose(m["albedo_sampled"], 1.0, atol=1e-6)


CHI2_CASES = [
    ("diffuse", [(0.8, 0.5, 0.2)]),
    ("conductor", [(1, 1, 1), (100, 100, 100), (0.5,) * 3, (0.5,) * 3, (1, 1, 1), (0, 0, 0), (0, 0, 0)]),
    ("conductor", [(1, 1, 1), (100, 100, 100), (0.2,) * 3, (0.6,) * 3, (1, 1, 1), (0, 0, 0), (0, 0, 0)]),
    ("dielectric", [(1.5,) * 3, (0.4,) * 3, (0.4,) * 3, (1, 1, 1)]),
]


@pytest.mark.parametrize("name,slots", CHI2_CASES, ids=[f"{c[0]}{i}" for i, c in enumerate(CHI2_CASES)])
@pytest.mark.parametrize("wo", [(0.3, 0.2, 0.9), (0.8, -0.1, 0.3), (0.4, 0.3, -0.7)], ids=["oblique", "low", "below"])
def test_sampled_directions_follow_the_pdf_chi_square(name, slots, wo):
    """Histogram of sampled directions against the pdf integrated over each cell (Pearson chi-square)."""
    from bsdf_harness import chi2_pvalue

    assert chi2_pvalue(name, slots, wo) > 1e-4
