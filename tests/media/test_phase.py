"""The Henyey-Greenstein phase function media scatter with (renderer.materials.phase): it
integrates to 1 over the sphere, its samples follow its own density (so pdf = value is exact),
their mean cosine is g, and forward scattering (g > 0) sends light on along -wo."""
from __future__ import annotations

import numpy as np
import pytest
import warp as wp

import renderer.scene  # noqa: F401  (import order: renderer.scene before the materials)
from renderer.materials.phase import hg_phase, hg_sample

N = 400_000


@wp.kernel
def _phase(g: float, wo: wp.vec3, seed: int, value: wp.array(dtype=float), sample_cos: wp.array(dtype=float),
           sample_value: wp.array(dtype=float)):
    i = wp.tid()
    rng = wp.rand_init(seed, i)
    # uniform direction on the sphere, for the normalisation integral
    z = 1.0 - 2.0 * wp.randf(rng)
    r = wp.sqrt(wp.max(0.0, 1.0 - z * z))
    phi = 2.0 * 3.14159265358979 * wp.randf(rng)
    wu = wp.vec3(r * wp.cos(phi), r * wp.sin(phi), z)
    value[i] = hg_phase(wo, wu, g)
    wi = hg_sample(wo, g, wp.vec2(wp.randf(rng), wp.randf(rng)))
    sample_cos[i] = -wp.dot(wo, wi)             # cosine of the deflection from the incoming direction
    sample_value[i] = hg_phase(wo, wi, g)


def run(g: float):
    wo = np.array([0.3, -0.4, 0.866])
    wo /= np.linalg.norm(wo)
    out = [wp.zeros(N, dtype=float, device="cpu") for _ in range(3)]
    wp.launch(_phase, N, [g, wp.vec3(*wo), 7, *out], device="cpu")
    return [a.numpy().astype(np.float64) for a in out]


def hg(mu: np.ndarray, g: float) -> np.ndarray:
    return (1 - g * g) / (4 * np.pi * (1 + g * g - 2 * g * mu) ** 1.5)


@pytest.mark.parametrize("g", [-0.7, 0.0, 0.3, 0.7])
def test_normalised_sampled_by_its_own_density_with_mean_cosine_g(g):
    value, mu, sampled_value = run(g)
    integral = 4 * np.pi * value.mean()
    assert abs(integral - 1) < 5 * 4 * np.pi * value.std() / np.sqrt(N) + 1e-6
    assert abs(mu.mean() - g) < 5 * mu.std() / np.sqrt(N)
    np.testing.assert_allclose(sampled_value, hg(mu, g), rtol=2e-4)
    # the histogram of the samples' cosines against 2 pi p(mu)
    counts, edges = np.histogram(mu, bins=40, range=(-1, 1))
    fine = edges[:-1, None] + (np.arange(200) + 0.5) / 200 * (edges[1] - edges[0])
    expected = N * 2 * np.pi * hg(fine, g).mean(1) * (edges[1] - edges[0])     # each bin's probability
    z = (counts - expected) / np.sqrt(expected)
    assert np.abs(z).max() < 5, z
    if g != 0:
        assert np.sign(mu.mean()) == np.sign(g)
