"""Tables over the angle of incidence (the thin-film mode ``table``, spectral conductors): the device
lookup against the exact per-wavelength optics integrated at every nm, at random angles and at the
extremes (grazing, normal, total internal reflection and its critical angle, absorbing layers,
metal substrates), energy (R + T = 1 for lossless stacks), and the grid's node at the branch point."""
from __future__ import annotations

import numpy as np
import pytest

from renderer.api import init_warp
from renderer.color import spectral
from renderer.optics import angular_table, arrays as optics

init_warp()

TOL_R = 5e-4        # the tolerance in R (and T), stacks of up to 40 layers


def exact_rgb(cos: np.ndarray, eta, k, d) -> tuple[np.ndarray, np.ndarray]:
    """RGB (R, T) at each cos θ from the monochromatic R and T at every nm (reference weights)."""
    lam, weights, _ = spectral.mode_wavelengths("reference")
    r, t = optics.multilayer_reflectance_transmittance(cos[:, None], lam[None, :], eta, k, d)
    return r.astype(np.float64) @ weights, t.astype(np.float64) @ weights


def table_of(eta, k, d) -> np.ndarray:
    n0, n_sub, rows = optics.stack_layers(eta, k, d)
    return angular_table.stack_table(n0, complex(*n_sub), rows)


def random_stack(rng: np.random.Generator, n_layers: int, absorbing: bool, metal: bool):
    eta = np.r_[1.0, rng.uniform(1.2, 2.5, n_layers), rng.uniform(0.2, 2.0) if metal else rng.uniform(1.3, 1.8)]
    k = np.r_[0.0, rng.uniform(0.0, 0.3, n_layers) * absorbing, rng.uniform(2.0, 5.0) if metal else 0.0]
    return eta, k, rng.uniform(0.0, 300.0, n_layers)


ANGLES = np.r_[0.0, 1e-4, 0.02, 0.999, 1.0, np.random.default_rng(3).uniform(0.0, 1.0, 40)]


@pytest.mark.parametrize("n_layers,absorbing,metal,seed", [
    (1, False, False, 0), (7, True, False, 1), (20, False, True, 2), (40, False, False, 3), (40, True, True, 4),
], ids=["film", "absorbing", "metal substrate", "40 layers", "40 absorbing on metal"])
def test_table_matches_the_exact_optics_at_random_and_extreme_angles(n_layers, absorbing, metal, seed):
    eta, k, d = random_stack(np.random.default_rng(seed), n_layers, absorbing, metal)
    table = table_of(eta, k, d)
    r_ref, t_ref = exact_rgb(ANGLES, eta, k, d)
    np.testing.assert_allclose(angular_table.lookup(table, ANGLES, offset=0), r_ref, atol=TOL_R)
    np.testing.assert_allclose(angular_table.lookup(table, ANGLES, offset=1), t_ref, atol=TOL_R)


def test_total_internal_reflection_from_the_substrate_side():
    """Light leaving glass (1.52) through a stack into air: R = 1 beyond the critical angle and a
    square-root rise before it, which the grid's node at the branch point keeps exact."""
    eta, k, d = np.r_[1.52, 2.3, 1.45, 2.3, 1.0], np.zeros(5), np.array([60.0, 95.0, 60.0])
    a = 1.0 - (1.0 / 1.52) ** 2
    cos_c = np.sqrt(a)
    cos = np.r_[np.linspace(0.0, 1.0, 41), cos_c, cos_c * (1 + 1e-4), cos_c * (1 - 1e-4), cos_c + 0.01]
    table = table_of(eta, k, d)
    r_ref, t_ref = exact_rgb(cos, eta, k, d)
    r = angular_table.lookup(table, cos, offset=0)
    np.testing.assert_allclose(r, r_ref, atol=TOL_R)
    np.testing.assert_allclose(angular_table.lookup(table, cos, offset=1), t_ref, atol=TOL_R)
    np.testing.assert_allclose(r[cos < cos_c * (1 - 1e-3)], 1.0, atol=1e-5)


def test_grid_has_a_node_at_the_branch_point_and_spans_every_angle():
    for a in (0.0, 0.3, 1.0 - (1 / 1.52) ** 2, 0.99):
        cos, zero = angular_table.grid(a, 512)
        assert cos[0] == pytest.approx(0.0, abs=1e-7) and cos[-1] == pytest.approx(1.0, abs=1e-12) and len(cos) == 512
        assert cos[zero] == pytest.approx(np.sqrt(a), abs=1e-12)
        assert np.all(np.diff(cos) > 0.0)


def test_lossless_tables_conserve_energy_at_every_angle():
    """R + T = 1 per channel, between the nodes too: the tables hold the white-normalised 1 nm
    quadrature, so no wavelength noise is left to clip (unlike a jittered spectral:N estimate)."""
    eta, k, d = np.r_[1.0, np.resize([2.4, 1.46], 30), 1.52], np.zeros(32), np.resize([57.3, 94.2], 30)
    cos = np.random.default_rng(9).uniform(0.0, 1.0, 200)
    for table in (table_of(eta, k, d), table_of(eta[::-1], k, d[::-1])):
        total = angular_table.lookup(table, cos, offset=0) + angular_table.lookup(table, cos, offset=1)
        np.testing.assert_allclose(total, 1.0, atol=1e-4)     # float32 sums of 471 wavelengths


def test_a_perfect_conductor_table_is_white():
    lam = spectral.mode_wavelengths("reference")[0]
    mirror = angular_table.conductor_table(np.full_like(lam, 0.05), np.full_like(lam, 50.0))   # R > 0.9999
    np.testing.assert_allclose(angular_table.lookup(mirror, ANGLES, stride=1), 1.0, atol=1e-3)
