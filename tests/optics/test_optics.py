"""Thin-film optics and Fresnel equations against an independent transfer-matrix computation.

The reference here is written separately from renderer/optics.py: Abelès characteristic matrices
in tilted-admittance form (complex128), not the Airy sum, with its own branch choice. The Warp
functions are run on the CPU device through the same @wp.func code the renderer's kernels call.
"""
from __future__ import annotations

import numpy as np
import pytest
import warp as wp

from renderer import optics
from renderer.optics import fresnel
from renderer.color import spectral

F32_ATOL = 2e-4   # float32 Airy sum vs complex128 matrices, away from degenerate points


# ---------------------------------------------------------------------------------------------
# Independent reference: characteristic (transfer) matrices


def _forward_q(n: np.ndarray, n0_sin: np.ndarray) -> np.ndarray:
    """n cos θ of the wave that carries energy away from the interface (or decays away from it)."""
    q = np.sqrt(n.astype(np.complex128) ** 2 - n0_sin.astype(np.complex128) ** 2)
    flip = (q.imag < 0) | ((q.imag == 0) & (q.real < 0))
    return np.where(flip, -q, q)


def tmm_RT(cos0, lam, n0, n1, n2, d) -> tuple[np.ndarray, np.ndarray]:
    """Unpolarised (R, T) of n0 | n1 (thickness d) | n2 by 2x2 characteristic matrices.

    Admittances (in units of the vacuum admittance) are η_s = n cos θ and η_p = n / cos θ; the film
    matrix is [[cos δ, −i sin δ / η1], [−i η1 sin δ, cos δ]] with δ = 2π n1 cos θ1 d / λ (n + ik
    convention); [B, C] = M [1, η2]; r = (η0 B − C)/(η0 B + C); T = 4 η0 Re η2 / |η0 B + C|².
    """
    cos0, lam, n0, n1, n2, d = np.broadcast_arrays(*(np.asarray(x) for x in (cos0, lam, n0, n1, n2, d)))
    n0 = n0.astype(np.complex128)
    n0_sin = n0 * np.sqrt(1.0 - cos0.astype(np.float64) ** 2)
    q = [n0 * cos0, _forward_q(n1, n0_sin), _forward_q(n2, n0_sin)]
    n = [n0, n1.astype(np.complex128), n2.astype(np.complex128)]
    delta = 2.0 * np.pi * q[1] * d / lam
    cos_d, sin_d = np.cos(delta), np.sin(delta)
    R = np.zeros(cos0.shape)
    T = np.zeros(cos0.shape)
    for eta in ([q[j] for j in range(3)], [n[j] ** 2 / q[j] for j in range(3)]):   # s, then p
        B = cos_d - 1j * sin_d * eta[2] / eta[1]
        C = -1j * eta[1] * sin_d + cos_d * eta[2]
        r = (eta[0] * B - C) / (eta[0] * B + C)
        R += 0.5 * np.abs(r) ** 2
        T += 0.5 * 4.0 * eta[0].real * eta[2].real / np.abs(eta[0] * B + C) ** 2
    return R, T


def tmm_incoherent_R(cos0, lam, n0, n1, n2, d_centre) -> float:
    """The phase-averaged (incoherent) reflectance: TMM averaged over one full fringe in thickness."""
    n0_sin = n0 * np.sqrt(1.0 - cos0 ** 2)
    period = lam / (2.0 * _forward_q(np.asarray(n1), np.asarray(n0_sin)).real)
    d = d_centre + period * (np.arange(4096) + 0.5) / 4096
    return float(tmm_RT(cos0, lam, n0, n1, n2, d)[0].mean())


def textbook_fresnel(cos_i: np.ndarray, eta: np.ndarray) -> np.ndarray:
    """Hecht's unpolarised dielectric reflectance, complex128, TIR included."""
    cos_i = np.asarray(cos_i, dtype=np.complex128)
    cos_t = np.sqrt(1.0 - (1.0 - cos_i ** 2) / np.asarray(eta) ** 2 + 0j)
    rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
    rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
    return 0.5 * (np.abs(rs) ** 2 + np.abs(rp) ** 2)


# ---------------------------------------------------------------------------------------------
# Kernels wrapping the single-interface Fresnel functions


@wp.kernel
def _fresnel_dielectric_kernel(cos_i: wp.array(dtype=float), eta: wp.array(dtype=float), out: wp.array(dtype=float)):
    i = wp.tid()
    out[i] = fresnel.fresnel_dielectric(cos_i[i], eta[i])


@wp.kernel
def _fresnel_conductor_kernel(cos_i: wp.array(dtype=float), eta: wp.array(dtype=wp.vec3), k: wp.array(dtype=wp.vec3),
                              out: wp.array(dtype=wp.vec3)):
    i = wp.tid()
    out[i] = fresnel.fresnel_conductor(cos_i[i], eta[i], k[i])


def _launch(kernel, *arrays, out_dtype=float):
    args = [wp.array(np.ascontiguousarray(a, dtype=np.float32), dtype=wp.vec3 if a.ndim == 2 else float, device="cpu")
            for a in arrays]
    out = wp.empty(len(arrays[0]), dtype=out_dtype, device="cpu")
    wp.launch(kernel, dim=len(arrays[0]), inputs=[*args, out], device="cpu")
    return out.numpy()


# ---------------------------------------------------------------------------------------------
# Airy sum vs transfer matrices


def test_random_parameters_match_transfer_matrix():
    rng = np.random.default_rng(7)
    m = 20000
    cos0 = rng.uniform(0.02, 1.0, m)
    lam = rng.uniform(360.0, 830.0, m)
    n0 = rng.uniform(1.0, 4.0, m)
    n1 = rng.uniform(1.0, 4.0, m)
    n2 = rng.uniform(1.0, 4.0, m) + 1j * np.where(rng.random(m) < 0.5, rng.uniform(0.0, 5.0, m), 0.0)
    d = rng.uniform(0.0, 5000.0, m)
    R, T = optics.thin_film_reflectance_transmittance(cos0, lam, n0, n1, n2, d)
    R_ref, T_ref = tmm_RT(cos0, lam, n0, n1, n2, d)
    np.testing.assert_allclose(R, R_ref, atol=F32_ATOL, rtol=0)
    lossless = n2.imag == 0
    np.testing.assert_allclose(T[lossless], T_ref[lossless], atol=F32_ATOL, rtol=0)


def test_absorbing_film_matches_transfer_matrix():
    rng = np.random.default_rng(8)
    m = 5000
    cos0, lam = rng.uniform(0.05, 1.0, m), rng.uniform(360.0, 830.0, m)
    n1 = rng.uniform(1.0, 4.0, m) + 1j * rng.uniform(0.0, 3.0, m)
    n2 = rng.uniform(1.0, 4.0, m) + 1j * rng.uniform(0.0, 3.0, m)
    d = rng.uniform(0.0, 300.0, m)
    R = optics.thin_film_reflectance(cos0, lam, 1.0, n1, n2, d)
    np.testing.assert_allclose(R, tmm_RT(cos0, lam, 1.0, n1, n2, d)[0], atol=F32_ATOL, rtol=0)


@pytest.mark.parametrize("n0, n1, n2, cos0, what", [
    (1.5, 1.0, 1.5, 0.5, "frustrated TIR: film 1.0 between glass, beyond its critical angle"),
    (1.6, 1.8, 1.0, 0.5, "TIR at the film-substrate interface"),
    (1.0, 1.33, 1.0, 0.3, "soap film in air, oblique"),
    (1.0, 1.5, 0.2 + 3.4j, 0.7, "dielectric film on a metal"),
])
def test_extremes_match_transfer_matrix(n0, n1, n2, cos0, what):
    d = np.array([0.0, 1.0, 30.0, 100.0, 250.0, 600.0, 2000.0])
    lam = np.array([380.0, 550.0, 800.0])[:, None]
    R, T = optics.thin_film_reflectance_transmittance(cos0, lam, n0, n1, n2, d)
    R_ref, T_ref = tmm_RT(cos0, lam, n0, n1, n2, d)
    np.testing.assert_allclose(R, R_ref, atol=F32_ATOL, rtol=0, err_msg=what)
    if np.imag(n2) == 0:
        np.testing.assert_allclose(T, T_ref, atol=F32_ATOL, rtol=0, err_msg=what)


def test_frustrated_tir_transmits_through_thin_gap_only():
    R, T = optics.thin_film_reflectance_transmittance(0.5, 550.0, 1.5, 1.0, 1.5, np.array([0.0, 50.0, 2000.0]))
    assert T[0] == pytest.approx(1.0, abs=1e-5)            # no gap: glass is continuous
    assert 0.05 < T[1] < 0.95                              # tunnelling through a 50 nm gap
    assert T[2] < 1e-6 and R[2] == pytest.approx(1.0, abs=1e-5)


def test_tir_at_substrate_reflects_everything():
    R, T = optics.thin_film_reflectance_transmittance(0.5, np.linspace(360, 830, 11), 1.6, 1.8, 1.0,
                                                      np.array([0.0, 120.0, 5000.0])[:, None])
    np.testing.assert_allclose(R, 1.0, atol=1e-5)
    np.testing.assert_allclose(T, 0.0, atol=1e-6)


def test_grazing_incidence_reflects_everything():
    n = np.array([1.0, 1.33, 2.5, 4.0])
    R = optics.thin_film_reflectance(0.0, 550.0, n[:, None, None], n[None, :, None], n[None, None, :] + 0.5j, 300.0)
    np.testing.assert_allclose(R, 1.0, atol=1e-4)
    R_near = optics.thin_film_reflectance(1e-3, 550.0, 1.0, 1.33, 1.5, 300.0)
    assert R_near == pytest.approx(tmm_RT(1e-3, 550.0, 1.0, 1.33, 1.5, 300.0)[0], abs=F32_ATOL)


def test_thick_film_coherent_matches_transfer_matrix():
    """10^5 nm: round-trip phases of ~10^3 cycles still come out right monochromatically."""
    lam = np.linspace(500.0, 501.0, 41)
    R = optics.thin_film_reflectance(0.8, lam, 1.0, 1.33, 1.52, 100000.0)
    np.testing.assert_allclose(R, tmm_RT(0.8, lam, 1.0, 1.33, 1.52, 100000.0)[0], atol=2e-3, rtol=0)


def test_thick_film_band_average_is_incoherent_limit():
    R_inc = tmm_incoherent_R(0.8, 550.0, 1.0, 1.33, 1.52, 100000.0)
    lam = np.linspace(540.0, 560.0, 9)
    R_mono = optics.thin_film_reflectance(0.8, lam, 1.0, 1.33, 1.52, 100000.0)
    R = optics.thin_film_reflectance(0.8, lam, 1.0, 1.33, 1.52, 100000.0, band_nm=20.0)
    # A 20 nm band spans ~15 fringes here; a box average keeps ≲ 1/(πW) of the fringe contrast.
    assert np.ptp(R_mono) > 0.3 * R_inc
    np.testing.assert_allclose(R, R_inc, rtol=1e-2)


# ---------------------------------------------------------------------------------------------
# Physics identities


def test_mgf2_antireflection_coating():
    """The π-phase trap: the quarter-wave MgF2 coat must lower glass's reflectance, not raise it."""
    bare, coated = optics.thin_film_reflectance(1.0, 550.0, 1.0, 1.38, 1.52, [0.0, 550.0 / (4 * 1.38)])
    assert round(float(bare), 3) == 0.043 and bare == pytest.approx(0.0426, abs=1e-4)
    assert round(float(coated), 3) == 0.013 and coated == pytest.approx(0.0126, abs=1e-4)


def test_zero_thickness_and_equal_indices_are_the_bare_interface():
    rng = np.random.default_rng(3)
    cos0, lam = rng.uniform(0, 1, 500), rng.uniform(360, 830, 500)
    n0, n1, n2, d = rng.uniform(1, 4, 500), rng.uniform(1, 4, 500), rng.uniform(1, 4, 500), rng.uniform(0, 5e4, 500)
    bare = tmm_RT(cos0, lam, n0, n2, n2, 0.0)[0]
    for film, thickness in ((n1, 0.0), (n0, d), (n2, d)):
        R = optics.thin_film_reflectance(cos0, lam, n0, film, n2, thickness)
        np.testing.assert_allclose(R, bare, atol=5e-6, rtol=0)


def test_energy_conservation_lossless():
    rng = np.random.default_rng(11)
    m = 20000
    R, T = optics.thin_film_reflectance_transmittance(rng.uniform(0, 1, m), rng.uniform(360, 830, m),
                                                      rng.uniform(1, 4, m), rng.uniform(1, 4, m),
                                                      rng.uniform(1, 4, m), rng.uniform(0, 1e5, m),
                                                      band_nm=rng.choice([0.0, 1.0, 15.0]))
    np.testing.assert_allclose(R + T, 1.0, atol=2e-5)


def test_no_nan_anywhere():
    cos0 = np.concatenate([[0.0, 1e-7, 1e-3], np.linspace(0.0, 1.0, 23), [1.0]])[:, None, None, None, None]
    d = np.concatenate([[0.0, 1e-3], np.geomspace(1.0, 1e5, 14)])[None, :, None, None, None]
    n = np.linspace(1.0, 4.0, 7)
    n0, n1, n2 = n[None, None, :, None, None], n[None, None, None, :, None], n[None, None, None, None, :]
    for band in (0.0, 1.0, 50.0):
        R, T = optics.thin_film_reflectance_transmittance(cos0, 550.0, n0, n1, n2, d, band_nm=band)
        assert np.all(np.isfinite(R)) and np.all(np.isfinite(T))
        assert R.min() >= 0.0 and R.max() <= 1.0 and T.min() >= 0.0 and T.max() <= 1.0
    small = (cos0[::4], n0, n1, n2 + 0.3j, d[:, ::3])
    for mode in ("rgb3", "spectral:4", "reference"):
        assert np.all(np.isfinite(optics.thin_film_rgb(small[0], small[1], small[2], small[3], small[4], mode=mode)))
    r, t = optics.thin_film_rgb_jittered(*small, u_jitter=0.37, n_samples=8)
    assert np.all(np.isfinite(r)) and np.all(np.isfinite(t))


# ---------------------------------------------------------------------------------------------
# Fresnel at one interface


def test_fresnel_dielectric_against_textbook_and_airy():
    cos_i = np.linspace(-1.0, 1.0, 401)
    for eta in (1.0 / 1.5, 1.33, 1.5, 2.4):
        etas = np.full_like(cos_i, eta)
        F = _launch(_fresnel_dielectric_kernel, cos_i, etas)
        expected = np.where(cos_i >= 0, textbook_fresnel(np.abs(cos_i), eta), textbook_fresnel(np.abs(cos_i), 1 / eta))
        np.testing.assert_allclose(F, expected, atol=2e-6)
        front = cos_i >= 0
        airy = optics.thin_film_reflectance(cos_i[front], 550.0, 1.0, 1.7, eta, 0.0)
        np.testing.assert_allclose(F[front], airy, atol=5e-6)


def test_fresnel_conductor_against_textbook_and_airy():
    rng = np.random.default_rng(5)
    m = 2000
    cos_i = rng.uniform(0.0, 1.0, m)
    eta, k = rng.uniform(0.05, 4.0, (m, 3)), rng.uniform(0.0, 6.0, (m, 3))
    F = _launch(_fresnel_conductor_kernel, cos_i, eta, k, out_dtype=wp.vec3)
    n = eta + 1j * k
    np.testing.assert_allclose(F, tmm_RT(cos_i[:, None], 550.0, 1.0, n, n, 0.0)[0], atol=5e-6)
    airy = optics.thin_film_reflectance(cos_i[:, None], 550.0, 1.0, 1.9, n, 0.0)
    np.testing.assert_allclose(F, airy, atol=5e-6)
    np.testing.assert_allclose(_launch(_fresnel_conductor_kernel, -cos_i, eta, k, out_dtype=wp.vec3), F)


# ---------------------------------------------------------------------------------------------
# Spectrum to RGB


def test_white_is_exactly_white():
    for mode in ("spectral:4", "spectral:8", "spectral:32", "reference"):
        _, weights, _ = spectral.mode_wavelengths(mode)
        np.testing.assert_allclose(weights.sum(axis=0), 1.0, atol=1e-12)
    w, lam0, step = spectral.rgb_weight_table()
    np.testing.assert_allclose(step * (w.sum(axis=0) - 0.5 * (w[0] + w[-1])), 1.0, atol=1e-5)
    np.testing.assert_allclose(spectral.spectrum_to_rgb_weights([450.0, 550.0, 610.0], [1.0, 2.0, 1.0]).sum(0), 1.0)
    # R ≡ 1 (total internal reflection) through the device integrators
    tir = (0.5, 1.6, 1.8, 1.0, 300.0)
    for mode in ("rgb3", "spectral:4", "spectral:32", "reference"):
        np.testing.assert_allclose(optics.thin_film_rgb(*tir, mode=mode), 1.0, atol=2e-5)
    u = (np.arange(512) + 0.5) / 512
    r, t = optics.thin_film_rgb_jittered(*tir, u_jitter=u, n_samples=8)
    np.testing.assert_allclose(r.mean(axis=0), 1.0, atol=1e-3)
    np.testing.assert_allclose(t, 0.0, atol=1e-6)


def test_spectral_weights_come_from_cie_tables():
    import colour

    xyz_to_rgb = colour.RGB_COLOURSPACES["sRGB"].matrix_XYZ_to_RGB
    sd = colour.SpectralDistribution({float(l): 1.0 if 500 <= l < 600 else 0.0 for l in range(360, 831)})
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    d65 = colour.SDS_ILLUMINANTS["D65"].copy().align(cmfs.shape)
    xyz = colour.sd_to_XYZ(sd, cmfs, d65, method="Integration") / 100.0
    lam, weights, _ = spectral.mode_wavelengths("reference")
    box = ((lam >= 500) & (lam < 600)).astype(float)
    np.testing.assert_allclose(box @ weights, xyz_to_rgb @ xyz, atol=5e-3)


def test_jittered_estimator_is_unbiased():
    u = (np.arange(1024) + 0.5) / 1024
    film = (0.9, 1.0, 1.33, 1.52, np.array([250.0, 600.0, 1500.0])[:, None])
    r, t = optics.thin_film_rgb_jittered(*film, u_jitter=u, n_samples=8)
    ref = optics.thin_film_rgb(*film, mode="reference")
    np.testing.assert_allclose(r.mean(axis=1), ref[:, 0], atol=1.5e-3)
    np.testing.assert_allclose((r + t).mean(axis=1), 1.0, atol=1e-3)


@pytest.mark.parametrize("thickness_nm", [50000.0, 100000.0])
def test_thick_films_converge_to_incoherent_limit(thickness_nm):
    """No false colour from aliased fringes: every spectral mode lands on the grey incoherent value."""
    for cos0, n1, n2 in ((1.0, 1.33, 1.0), (0.6, 1.38, 1.52), (0.9, 2.0, 1.5)):
        R_inc = tmm_incoherent_R(cos0, 550.0, 1.0, n1, n2, thickness_nm)
        for mode in ("spectral:32", "reference"):
            rgb = optics.thin_film_rgb(cos0, 1.0, n1, n2, thickness_nm, mode=mode)
            np.testing.assert_allclose(rgb, R_inc, rtol=0.02, err_msg=f"{mode} cos={cos0} n1={n1}")
        u = (np.arange(256) + 0.5) / 256
        r, _ = optics.thin_film_rgb_jittered(cos0, 1.0, n1, n2, thickness_nm, u_jitter=u, n_samples=32)
        np.testing.assert_allclose(r.mean(axis=0), R_inc, rtol=0.02, err_msg=f"jittered cos={cos0} n1={n1}")
