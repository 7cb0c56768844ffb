"""Multilayer stacks against an independent transfer-matrix computation (the ``tmm`` package,
Byrnes: Abelès-style matrices in float64), at random and extreme parameters; energy balance with
tmm's own absorption; the one-layer case against today's Airy film; 500 layers stay physical."""
from __future__ import annotations

import numpy as np
import pytest

from renderer import optics
from renderer.api import init_warp

tmm = pytest.importorskip("tmm")

init_warp()

R_TOL = 5.0e-4


def tmm_rta(cos_theta, wavelength_nm, eta, k, thickness_nm) -> np.ndarray:
    """(R, T, A) per (cos θ, λ) pair from tmm, s and p averaged; A is what the layers absorb."""
    n = np.asarray(eta, np.float64) + 1j * np.asarray(k, np.float64)
    d = [np.inf, *np.asarray(thickness_nm, np.float64).tolist(), np.inf]
    out = []
    for c, lam in zip(np.ravel(cos_theta), np.ravel(wavelength_nm)):
        th = np.arccos(np.clip(c, 0.0, 1.0))
        rta = np.zeros(3)
        for pol in "sp":
            res = tmm.coh_tmm(pol, n, d, th, lam)
            absorbed = tmm.absorp_in_each_layer(res)[1:-1].sum() if len(d) > 2 else 0.0
            rta += 0.5 * np.array([res["R"], res["T"], absorbed])
        out.append(rta)
    return np.array(out)


def ours(cos_theta, wavelength_nm, eta, k, thickness_nm) -> np.ndarray:
    r, t = optics.multilayer_reflectance_transmittance(cos_theta, wavelength_nm, eta, k, thickness_nm)
    return np.stack([np.ravel(r), np.ravel(t)], axis=-1).astype(np.float64)


def random_stack(rng: np.random.Generator, n_layers: int, absorbing: bool, metal: bool):
    eta = rng.uniform(1.0, 2.6, n_layers + 2)
    k = np.zeros(n_layers + 2)
    if absorbing:
        k[1:-1] = rng.uniform(0.0, 3.0, n_layers) * (rng.random(n_layers) < 0.4)
    if metal:
        eta[-1], k[-1] = rng.uniform(0.05, 2.5), rng.uniform(1.0, 6.0)
    d = rng.uniform(0.0, 600.0, n_layers) * (rng.random(n_layers) < 0.9)   # some 0 nm layers
    return eta, k, d


def assert_matches(cos_theta, lam, eta, k, d, tol: float = R_TOL) -> float:
    got = ours(cos_theta, lam, eta, k, d)
    ref = tmm_rta(cos_theta, lam, eta, k, d)
    err = np.abs(got - ref[:, :2]).max(axis=0)
    assert err[0] < tol and err[1] < tol, (err, eta, k, d)
    # energy: our R and T plus what tmm says the layers absorb is everything
    np.testing.assert_allclose(got.sum(axis=1) + ref[:, 2], 1.0, atol=tol)
    assert np.all(1.0 - got.sum(axis=1) >= -1e-5)
    return float(err.max())


@pytest.mark.parametrize("absorbing,metal", [(False, False), (True, False), (False, True), (True, True)])
def test_random_stacks_match_tmm(absorbing, metal):
    rng = np.random.default_rng(11 + 2 * absorbing + metal)
    for n_layers in (1, 2, 3, 5, 8, 13, 21, 40):
        eta, k, d = random_stack(rng, n_layers, absorbing, metal)
        cos0 = np.r_[1.0, 1e-3, rng.uniform(0.0, 1.0, 14)]
        lam = rng.uniform(360.0, 830.0, cos0.size)
        assert_matches(cos0, lam, eta, k, d)


EXTREMES = {
    # name: (eta, k, thickness) — outer first, substrate last
    "tir at the substrate": ([1.6, 1.45, 2.1, 1.0], [0, 0, 0, 0], [120.0, 80.0]),
    "frustrated tir, thin gap": ([1.5, 1.0, 1.5], [0, 0, 0], [90.0]),
    "frustrated tir, thick gap": ([1.5, 1.0, 1.5], [0, 0, 0], [20000.0]),
    "evanescent in several layers": ([1.9, 1.2, 1.3, 1.1, 1.6], [0, 0, 0, 0, 0], [200.0, 50.0, 300.0]),
    "thick metal layer": ([1.0, 1.5, 2.9, 1.5], [0, 0, 3.3, 0], [100.0, 2000.0]),
    "silver substrate under oxide": ([1.0, 2.4, 1.46, 0.05], [0, 0, 0, 3.6], [60.0, 95.0]),
    "zero-thickness layers": ([1.0, 2.4, 1.46, 2.4, 1.52], [0, 0.2, 0, 0, 0], [0.0, 0.0, 0.0]),
    "layers equal to their neighbours": ([1.33, 1.33, 1.6, 1.6, 1.52, 1.52], [0, 0, 0, 0, 0, 0],
                                         [300.0, 120.0, 200.0, 500.0]),
    "chromium / chromium oxide": ([1.0, 2.5, 3.1, 2.5, 1.52], [0, 0.05, 3.3, 0.05, 0], [40.0, 12.0, 40.0]),
}


@pytest.mark.parametrize("name", list(EXTREMES))
def test_extreme_stacks_match_tmm(name):
    eta, k, d = EXTREMES[name]
    cos0 = np.r_[1.0, 0.9, 0.6, 0.4, 0.2, 0.05, 1e-2, 1e-3]
    for lam in (380.0, 550.0, 800.0):
        assert_matches(cos0, np.full_like(cos0, lam), eta, k, d)


def test_one_layer_is_the_airy_film():
    rng = np.random.default_rng(5)
    n = 400
    cos0, lam = rng.uniform(0.0, 1.0, n), rng.uniform(360.0, 830.0, n)
    n0, n1, n2 = rng.uniform(1.0, 2.0, n), rng.uniform(1.0, 2.5, n), rng.uniform(1.0, 2.5, n)
    k1, k2, d = rng.uniform(0.0, 0.3, n), rng.uniform(0.0, 3.0, n), rng.uniform(0.0, 2000.0, n)
    for i in range(n):
        r, t = optics.thin_film_reflectance_transmittance(cos0[i], lam[i], n0[i], n1[i] + 1j * k1[i],
                                                          n2[i] + 1j * k2[i], d[i])
        got = ours(cos0[i], lam[i], [n0[i], n1[i], n2[i]], [0.0, k1[i], k2[i]], [d[i]])[0]
        np.testing.assert_allclose(got, [r, t], atol=2e-6)


def test_mgf2_quarter_wave_on_glass():
    """DESIGN.md's trap: the coat must lower R from 0.0426 to 0.0126 at its design wavelength."""
    bare = ours(1.0, 550.0, [1.0, 1.52], [0.0, 0.0], [])[0, 0]
    coat = ours(1.0, 550.0, [1.0, 1.38, 1.52], [0.0, 0.0, 0.0], [550.0 / (4 * 1.38)])[0, 0]
    assert bare == pytest.approx(0.0426, abs=1e-4)
    assert coat == pytest.approx(0.0126, abs=1e-4)


def test_lossless_stacks_conserve_energy():
    rng = np.random.default_rng(9)
    for n_layers in (1, 4, 17, 40, 120):
        eta = rng.uniform(1.0, 2.6, n_layers + 2)
        d = rng.uniform(0.0, 800.0, n_layers)
        cos0 = np.r_[1.0, 1e-3, rng.uniform(0.0, 1.0, 62)]
        lam = rng.uniform(360.0, 830.0, cos0.size)
        r, t = optics.multilayer_reflectance_transmittance(cos0, lam, eta, np.zeros_like(eta), d)
        np.testing.assert_allclose(r + t, 1.0, atol=1e-4)


def test_quarter_wave_mirror_saturates():
    """A TiO2/SiO2 quarter-wave stack reflects nearly all of its design wavelength, and its
    reflectance at normal incidence matches the closed form of a (HL)^N H stack."""
    n_h, n_l, n_s, lam0, pairs = 2.4, 1.46, 1.52, 550.0, 6
    eta = [1.0] + [n_h, n_l] * pairs + [n_h, n_s]
    d = [lam0 / (4 * n) for n in eta[1:-1]]
    r = ours(1.0, lam0, eta, np.zeros(len(eta)), d)[0, 0]
    y = (n_h / n_l) ** (2 * pairs) * n_h ** 2 / n_s
    assert r == pytest.approx(((1 - y) / (1 + y)) ** 2, abs=1e-5)


def test_500_layers_stay_finite_and_physical():
    rng = np.random.default_rng(3)
    n_layers = 500
    cos0 = np.r_[1.0, 0.5, 1e-2, 1e-4, rng.uniform(0.0, 1.0, 60)]
    lam = rng.uniform(360.0, 830.0, cos0.size)
    cases = {
        "nacre-like": (np.r_[1.0, np.tile([1.6, 1.43], n_layers // 2), 1.6], np.zeros(n_layers + 2),
                       rng.uniform(300.0, 500.0, n_layers)),
        "thick absorbing": (np.r_[1.0, rng.uniform(1.0, 3.0, n_layers), 0.2],
                            np.r_[0.0, rng.uniform(0, 5, n_layers), 4.0], rng.uniform(500.0, 5000.0, n_layers)),
        "evanescent from a dense medium": (np.r_[2.5, rng.uniform(1.0, 1.3, n_layers), 1.0], np.zeros(n_layers + 2),
                                           rng.uniform(100.0, 3000.0, n_layers)),
    }
    for name, (eta, k, d) in cases.items():
        r, t = optics.multilayer_reflectance_transmittance(cos0, lam, eta, k, d)
        assert np.all(np.isfinite(r)) and np.all(np.isfinite(t)), name
        assert np.all((r >= 0) & (r <= 1) & (t >= 0) & (t <= 1) & (r + t <= 1 + 1e-4)), name
    eta, k, d = cases["nacre-like"]
    r, t = optics.multilayer_reflectance_transmittance(cos0, lam, eta, k, d)
    np.testing.assert_allclose(r + t, 1.0, atol=1e-3)
    # a dense medium over 500 layers that are all below its critical angle at 1e-2: total reflection
    eta, k, d = cases["evanescent from a dense medium"]
    r, t = optics.multilayer_reflectance_transmittance(0.3, 550.0, eta, k, d)
    assert float(r) == pytest.approx(1.0, abs=1e-5) and float(t) < 1e-6


def test_bad_stack_shapes_are_refused():
    with pytest.raises(ValueError, match="need 4 values"):
        optics.multilayer_reflectance(1.0, 550.0, [1.0, 1.5, 1.5], [0, 0, 0], [100.0, 100.0])
    with pytest.raises(ValueError, match="lossless"):
        optics.multilayer_reflectance(1.0, 550.0, [1.0, 1.5, 1.5], [0.1, 0, 0], [100.0])
