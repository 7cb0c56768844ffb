"""Spectral parameter values (pbrt-v4's named spectra, inline samples, .spd files) become the RGB or
single value this renderer carries, and a scene of named metals and glass matches pbrt-v4's own
(spectral) image within its noise."""
from __future__ import annotations

import numpy as np
import pytest

from pbrt_compare import DATA, MEAN_TOL, assert_matches_pbrt, ours, ours_of
from renderer.color.named_spectra import named, spectrum_mean, spectrum_rgb
from renderer.errors import SceneError
from renderer.api import load_scene
from renderer.scene import load_description

HEAD = 'Camera "perspective"\nWorldBegin\nLightSource "infinite"\n'


def _material(tmp_path, material: str):
    path = tmp_path / "s.pbrt"
    path.write_text(HEAD + material + '\nShape "sphere"\n')
    return load_description(path).materials[0].values


def test_a_constant_spectrum_is_grey_and_glass_takes_its_luminance_weighted_index():
    np.testing.assert_allclose(spectrum_rgb(np.array([[300.0, 2.0], [800.0, 2.0]])), 2.0, rtol=2e-4)
    # BK7: n_d = 1.5168 at 587.6 nm; its Y-weighted mean over the visible lies within 2e-3 of it
    assert spectrum_mean(named()["glass-BK7"]) == pytest.approx(1.5168, abs=2e-3)


def test_named_metals_are_read_by_conductor_and_glass_by_dielectric(tmp_path):
    v = _material(tmp_path, 'Material "conductor" "spectrum eta" "metal-Au-eta" "spectrum k" "metal-Au-k"')
    eta, k = np.array(v["eta"]), np.array(v["k"])
    assert eta[2] > eta[1] > eta[0] > 0.0 and k[0] > k[1] > k[2] > 1.0      # gold: red reflects, blue is absorbed
    v = _material(tmp_path, 'Material "dielectric" "spectrum eta" "glass-BK7"')
    assert v["eta"] == pytest.approx(1.518, abs=1e-3)


def test_inline_and_file_spectra(tmp_path):
    (tmp_path / "flat.spd").write_text("# wavelength value\n400 1.3\n500 1.3 # mid\n700 1.3\n")
    v = _material(tmp_path, 'Material "dielectric" "spectrum eta" "flat.spd"')
    assert v["eta"] == pytest.approx(1.3, rel=1e-4)
    v = _material(tmp_path, 'Material "conductor" "spectrum eta" [380 0.2 780 0.2] "spectrum k" [380 3 780 3]')
    np.testing.assert_allclose(v["eta"], 0.2, rtol=1e-3)
    np.testing.assert_allclose(v["k"], 3.0, rtol=1e-3)


@pytest.mark.parametrize("value, needle", [
    ('"metal-Unobtainium-eta"', "neither one of pbrt-v4's named spectra"),
    ("[400 1.5 500]", "pairs"),
    ("[500 1.5 400 1.6]", "increasing"),
])
def test_bad_spectra_are_refused_where_written(tmp_path, value, needle):
    path = tmp_path / "s.pbrt"
    path.write_text(HEAD + f'Material "dielectric" "spectrum eta" {value}\nShape "sphere"\n')
    with pytest.raises(SceneError, match=needle) as info:
        load_description(path)
    assert f"{path}:4" in str(info.value)


def independent_fresnel_rgb(eta: np.ndarray, k: np.ndarray, cos: np.ndarray) -> np.ndarray:
    """Linear-sRGB reflectance of a conductor from numpy's complex Fresnel equations at every nm,
    integrated with colour-science's CIE 1931 observer under D65 and normalised so R ≡ 1 is white."""
    import colour

    shape = colour.SpectralShape(360, 830, 1)
    lam = shape.wavelengths
    w = (colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(shape).values
         * colour.SDS_ILLUMINANTS["D65"].copy().align(shape).values[:, None])
    to_rgb = np.asarray(colour.RGB_COLOURSPACES["sRGB"].matrix_XYZ_to_RGB)
    n = np.interp(lam, eta[:, 0], eta[:, 1]) + 1j * np.interp(lam, k[:, 0], k[:, 1])
    c = cos[:, None]
    root = np.sqrt(n ** 2 - (1.0 - c ** 2))
    rs = (c - root) / (c + root)
    rp = (n ** 2 * c - root) / (n ** 2 * c + root)
    R = 0.5 * (np.abs(rs) ** 2 + np.abs(rp) ** 2)
    return (R @ w @ to_rgb.T) / (np.ones(len(lam)) @ w @ to_rgb.T)


@pytest.mark.parametrize("metal", ["Au", "Cu", "Ag"])
def test_a_named_metal_reflects_its_spectral_fresnel_colour(tmp_path, metal):
    """The conductor's baked table (spectral Fresnel at every nm, to RGB) against an independent
    numpy integration, at random angles and the extremes; the RGB projections of eta and k put
    into the per-channel formula are visibly different (for gold, its red)."""
    from renderer.materials import conductor
    from renderer.optics import angular_table

    v = _material(tmp_path, f'Material "conductor" "spectrum eta" "metal-{metal}-eta" "spectrum k" "metal-{metal}-k"')
    rows, warning = conductor.table_rows(v, None, "spectral:32")
    assert len(rows) and not warning
    cos = np.r_[0.0, 1e-3, 1.0, np.random.default_rng(4).uniform(0.0, 1.0, 30)]
    expect = independent_fresnel_rgb(named()[f"metal-{metal}-eta"], named()[f"metal-{metal}-k"], cos)
    np.testing.assert_allclose(angular_table.lookup(rows, cos, stride=1), expect, atol=1e-3)
    if metal == "Au":
        eta, k = np.array(v["eta"]), np.array(v["k"])
        n = eta + 1j * k
        projected_red = np.abs((1 - n[0]) / (1 + n[0])) ** 2            # normal incidence, per channel
        assert expect[2, 0] - projected_red > 0.02


def test_named_metals_and_glass_match_pbrt():
    """Measured: chi 1.12, image means within 0.25 %; gold within 1.5 % of pbrt-v4 in every channel
    (the RGB projections of its eta and k had left its red 6 % low)."""
    ref, _ = assert_matches_pbrt("named_spectra", mean_tol=2 * MEAN_TOL)
    img, _ = ours_of("named_spectra")
    gold = (slice(16, 30), slice(17, 27))
    np.testing.assert_allclose(img[gold].mean((0, 1)), ref[gold].mean((0, 1)), rtol=0.03)


def test_a_spectral_colour_keeps_its_spectrum_through_python_values_and_pickles():
    """A colour read from a spectrum is its RGB projection everywhere, and still carries the
    samples for the conductor's spectral Fresnel table (also from Python and after pickling)."""
    import pickle

    from renderer.color.named_spectra import SpectralRGB
    from renderer.materials import conductor, material

    eta, k = (SpectralRGB(spectrum_rgb(named()[f"metal-Au-{p}"]), named()[f"metal-Au-{p}"]) for p in ("eta", "k"))
    m = material("conductor", eta=eta, k=k)
    assert isinstance(m.values["eta"], SpectralRGB) and tuple(m.values["eta"]) == tuple(eta)
    back = pickle.loads(pickle.dumps(m.values["k"]))
    np.testing.assert_array_equal(back.samples, k.samples)
    assert len(conductor.table_rows(m.values, None, "rgb3")[0]) > 0
    assert len(conductor.table_rows(material("conductor").values, None, "rgb3")[0]) == 0   # RGB copper: no table


def _red_over_green(img: np.ndarray) -> float:
    """The gold sphere's (left) colour: its mean red over its mean green."""
    m = img[14:44, 4:28].mean((0, 1))
    return float(m[0] / m[1])


def test_coatedconductor_bases_of_named_metals_match_pbrt(tmp_path):
    """Named gold and copper as coatedconductor bases (smooth and rough coats) take the conductor's
    spectral Fresnel table, baked relative to the coat. Measured: chi 1.13, means within 0.3 %;
    gold's red over green 2.5 % above pbrt-v4's, where the RGB projections of eta and k (the former
    behaviour) leave it 4.1 % below (their chi, 1.15, does not tell them apart)."""
    from renderer.materials import coatedconductor

    v = _material(tmp_path, 'Material "coatedconductor" "spectrum conductor.eta" "metal-Au-eta" '
                            '"spectrum conductor.k" "metal-Au-k"')
    rows, warning = coatedconductor.table_rows(v, None, "rgb3")
    assert len(rows) and not warning
    ref, _ = assert_matches_pbrt("coated_spectra")
    img, _ = ours_of("coated_spectra")
    assert _red_over_green(img) == pytest.approx(_red_over_green(ref), rel=0.04)
    eta, k = (tuple(np.round(spectrum_rgb(named()[f"metal-Au-{p}"]), 4)) for p in ("eta", "k"))
    text = (DATA / "coated_spectra.pbrt").read_text().replace(
        '"spectrum conductor.eta" "metal-Au-eta" "spectrum conductor.k" "metal-Au-k"',
        f'"rgb conductor.eta" [{eta[0]} {eta[1]} {eta[2]}] "rgb conductor.k" [{k[0]} {k[1]} {k[2]}]')
    (tmp_path / "projected.pbrt").write_text(text)
    projected, _ = ours(load_scene(tmp_path / "projected.pbrt"))
    assert _red_over_green(projected) < 0.97 * _red_over_green(ref)
