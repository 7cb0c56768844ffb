"""A dielectric whose eta is a spectrum that varies (pbrt-v4's glass-F11) disperses: each path picks
one wavelength at its first dispersive interface and refracts with eta(λ) from then on, weighted
by that wavelength's RGB over its density (renderer.optics.dispersion). Against pbrt-v4's own
(spectral) image of a glass-F11 sphere before a checkerboard, whose checks are fringed in colour."""
from __future__ import annotations

import pickle

import numpy as np
import pytest
import warp as wp

from pbrt_compare import DATA, assert_matches_pbrt, ours, ours_of
from renderer.api import load_scene
from renderer.color.named_spectra import SpectralFloat, named
from renderer.color.rgb_weights import RgbWeightTable, make_rgb_weight_table
from renderer.device.scene import upload
from renderer.io.images import read_exr
from renderer.materials import dielectric, material
from renderer.optics.dispersion import eta_at, eta_rows, is_dispersive, sample_wavelength, wavelength_weight
from renderer.scene import load_description


@wp.kernel
def _wavelength_kernel(table: RgbWeightTable, u: wp.array(dtype=float), out: wp.array(dtype=wp.vec4)):
    i = wp.tid()
    s = sample_wavelength(u[i])
    w = wavelength_weight(table, s)
    out[i] = wp.vec4(s[0], w[0], w[1], w[2])


@wp.kernel
def _eta_kernel(rows: wp.array(dtype=wp.vec4), lam: wp.array(dtype=float), out: wp.array(dtype=float)):
    i = wp.tid()
    out[i] = eta_at(rows, 0, lam[i])


def test_a_wavelength_weighs_a_flat_spectrum_white_on_average():
    """pbrt-v4's visible-wavelength density over 360-830 nm, inverted: λ covers the range, and the
    weight w(λ)/p(λ) averages to (1, 1, 1) over u (a flat spectrum stays white)."""
    n = 200_000
    u = wp.array(((np.arange(n) + 0.5) / n).astype(np.float32), dtype=float, device="cpu")
    out = wp.empty(n, dtype=wp.vec4, device="cpu")
    wp.launch(_wavelength_kernel, dim=n, inputs=[make_rgb_weight_table("cpu"), u, out], device="cpu")
    v = out.numpy()
    assert v[0, 0] == pytest.approx(360.0, abs=0.5) and v[-1, 0] == pytest.approx(830.0, abs=1.0)
    assert np.all(np.diff(v[:, 0]) > 0)
    np.testing.assert_allclose(v[:, 1:].mean(0), 1.0, atol=2e-3)
    assert v[:, 1:].min() < 0.0          # single wavelengths lie outside the sRGB gamut


def test_glass_eta_is_a_dispersive_spectrum_and_its_table_is_its_curve(tmp_path):
    path = tmp_path / "s.pbrt"
    path.write_text('Camera "perspective"\nWorldBegin\nMaterial "dielectric" "spectrum eta" "glass-F11"\n'
                    'Shape "sphere"\n')
    eta = load_description(path).materials[0].values["eta"]
    assert isinstance(eta, SpectralFloat) and is_dispersive(eta) and 1.77 < eta < 1.85
    np.testing.assert_array_equal(pickle.loads(pickle.dumps(eta)).samples, eta.samples)
    lam = np.random.default_rng(3).uniform(360.0, 830.0, 50).astype(np.float32)
    out = wp.empty(len(lam), dtype=float, device="cpu")
    rows = wp.array(eta_rows(eta), dtype=wp.vec4, device="cpu")
    wp.launch(_eta_kernel, dim=len(lam), inputs=[rows, wp.array(lam, dtype=float, device="cpu"), out], device="cpu")
    f11 = named()["glass-F11"]
    np.testing.assert_allclose(out.numpy(), np.interp(lam, f11[:, 0], f11[:, 1]), atol=1e-5)


def test_only_scenes_with_a_varying_index_get_the_dispersive_kernel(tmp_path):
    flat = SpectralFloat(1.5, np.array([[400.0, 1.5], [700.0, 1.5]]))
    assert not dielectric.disperses(material("dielectric", eta=flat).values)
    assert not dielectric.disperses(material("dielectric", eta=1.5).values)
    assert upload(load_description(DATA / "dispersion.pbrt"), "cpu").features.dispersion
    path = tmp_path / "flat.pbrt"
    path.write_text((DATA / "dispersion.pbrt").read_text().replace('"glass-F11"', "[400 1.5 700 1.5]"))
    assert not upload(load_description(path), "cpu").features.dispersion


def _fringe_amplitude(img: np.ndarray) -> float:
    """How much of pbrt-v4's colour-fringe pattern (its blue minus red, per pixel) an image has:
    the projection of the image's blue minus red onto pbrt's, over pbrt's pattern's own energy
    less its noise (from its two seeds). 1 for the same fringes, 0 for none; the estimate is
    unbiased in our noise, which is independent of pbrt's."""
    a, b = (np.stack([ch[c] for c in "RGB"], -1) for ch, _ in
            (read_exr(DATA / f"{n}.exr") for n in ("dispersion", "dispersion-2")))
    ca, cb = a[..., 2] - a[..., 0], b[..., 2] - b[..., 0]
    ref = 0.5 * (ca + cb)
    return float(((img[..., 2] - img[..., 0]) * ref).sum() / (ref ** 2 - 0.25 * (ca - cb) ** 2).sum())


def test_a_dispersive_glass_sphere_matches_pbrt_and_shows_its_fringes(tmp_path):
    """Measured: chi 1.05, means within 0.4 %, fringe amplitude 0.97 (its noise ~0.07); the
    sphere at its mean index instead shows no colour at all."""
    assert_matches_pbrt("dispersion")
    img, _ = ours_of("dispersion")
    assert _fringe_amplitude(img) == pytest.approx(1.0, abs=0.25)
    text = (DATA / "dispersion.pbrt").read_text().replace('"spectrum eta" "glass-F11"', '"float eta" 1.79')
    (tmp_path / "mean.pbrt").write_text(text)
    grey, _ = ours(load_scene(tmp_path / "mean.pbrt"))
    assert abs(_fringe_amplitude(grey)) < 0.05
