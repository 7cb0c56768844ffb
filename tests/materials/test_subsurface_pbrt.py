"""pbrt-v4's ``subsurface`` material against pbrt-v4's own images (tests/data/pbrt/subsurface_*.pbrt,
made by render_references.py with ``volpath``; compared as :mod:`pbrt_compare` does: chi of the two
means over both renderers' noise, and per-channel means).

- ``subsurface_named``: measured media that are nearly grey (Marble, whole milk), smooth and rough;
- ``subsurface_reflectance``: a body from ``reflectance`` and ``mfp``, and one from ``sigma_a``,
  ``sigma_s``, ``g`` 0.6 and ``eta`` 1.5 under a rough boundary; another mfp must fail;
- ``subsurface_skin``: Skin1 and Ketchup, whose coefficients change 15-fold over the spectrum. Our
  step evaluates such bodies at three wavelengths (``SPECTRAL``) with pbrt-v4's RGB upsampling of
  the coefficients, as pbrt-v4 does; per RGB channel their red came out 16 % and 84 % above
  pbrt-v4's. That estimator is also checked against the scene rendered as sixteen grey scenes,
  one per wavelength, summed with CIE 1931/D65 to sRGB weights.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from pbrt_compare import CHI, DATA, DISTINCT, assert_matches_pbrt, chi, ours_of, reference, variant_chi
import renderer
from renderer.color import rgb_spectrum
from renderer.color.spectral import spectrum_to_rgb_weights
from renderer.materials.subsurface import NAMED_MEDIA

#: Columns of the two spheres in the 80x48 images, rows 12-36.
SPHERES = [(12, 36), (44, 68)]
ROWS = slice(12, 36)


def sphere_means(img: np.ndarray) -> list[np.ndarray]:
    return [img[ROWS, x0:x1].reshape(-1, 3).mean(0) for x0, x1 in SPHERES]


def assert_spheres_agree(img: np.ndarray, var: np.ndarray, ref: np.ndarray, ref_var: np.ndarray) -> None:
    """Each sphere's per-channel mean within 4 standard errors of both renders' noise, plus 1 %."""
    for (x0, x1), ours, theirs in zip(SPHERES, sphere_means(img), sphere_means(ref)):
        n = (ROWS.stop - ROWS.start) * (x1 - x0)
        se = np.sqrt((var[ROWS, x0:x1] + ref_var[ROWS, x0:x1]).reshape(-1, 3).sum(0)) / n
        assert np.all(np.abs(ours - theirs) < 4 * se + 0.01 * theirs), (ours, theirs, se)


@pytest.mark.filterwarnings("ignore::renderer.errors.RenderWarning")
def test_named_media_match_pbrt_v4():
    ref, ref_var = assert_matches_pbrt("subsurface_named")
    assert_spheres_agree(*ours_of("subsurface_named"), ref, ref_var)


@pytest.mark.filterwarnings("ignore::renderer.errors.RenderWarning")
def test_reflectance_body_matches_pbrt_v4_and_another_mfp_does_not(tmp_path):
    ref, ref_var = assert_matches_pbrt("subsurface_reflectance")
    assert_spheres_agree(*ours_of("subsurface_reflectance"), ref, ref_var)
    for mfp in ("0.1", "0.4"):      # half and twice the mean free path
        wrong = variant_chi("subsurface_reflectance", [("[0.2 0.2 0.2]", f"[{mfp} {mfp} {mfp}]")], ref, ref_var, tmp_path)
        assert wrong > DISTINCT, (mfp, wrong)


def spectral_render(name: str, media: dict[str, str], n_lambda: int, spp: int, seed: int, tmp: Path) -> np.ndarray:
    """Our image of ``<name>.pbrt`` as a sum of grey images: one render per wavelength (the
    midpoints of n_lambda strata of [360, 830] nm) in which each named medium of ``media`` (its
    directive text, in the file) has the grey coefficients of its upsampled spectra at that
    wavelength, summed with the CIE 1931/D65 to sRGB weights. Everything else must be grey."""
    lam = 360.0 + (np.arange(n_lambda) + 0.5) * 470.0 / n_lambda
    weights = spectrum_to_rgb_weights(lam)
    spectra = {}
    for text, medium in media.items():
        (c_a, s_a, _), (c_s, s_s, _) = (rgb_spectrum.unbounded(v) for v in NAMED_MEDIA[medium][::-1])
        spectra[text] = (s_a * rgb_spectrum.sigmoid(c_a, lam), s_s * rgb_spectrum.sigmoid(c_s, lam))
    text = (DATA / f"{name}.pbrt").read_text()
    out = 0.0
    for k in range(n_lambda):
        t = text
        for old, (sa, ss) in spectra.items():
            t = t.replace(old, f'"rgb sigma_a" [{sa[k]:.8g} {sa[k]:.8g} {sa[k]:.8g}] '
                               f'"rgb sigma_s" [{ss[k]:.8g} {ss[k]:.8g} {ss[k]:.8g}]')
        (tmp / "grey.pbrt").write_text(t)
        grey = renderer.render(renderer.load_scene(tmp / "grey.pbrt"), spp=spp, seed=seed + 1000 * k)
        out = out + weights[k] * grey.mean(-1, keepdims=True)
    return out


#: The named media of subsurface_skin.pbrt, by their text in the file.
SKIN = {'"string name" "Skin1"': "Skin1", '"string name" "Ketchup"': "Ketchup"}


@pytest.mark.filterwarnings("ignore::renderer.errors.RenderWarning")
def test_coloured_media_match_pbrt_v4():
    """Skin1 and Ketchup, evaluated per wavelength as pbrt-v4 does."""
    ref, ref_var = assert_matches_pbrt("subsurface_skin")
    assert_spheres_agree(*ours_of("subsurface_skin"), ref, ref_var)


@pytest.mark.filterwarnings("ignore::renderer.errors.RenderWarning")
def test_spectral_body_is_the_sum_of_grey_bodies(tmp_path):
    """The step's three-wavelength estimate of a coloured body equals, within noise, the scene
    rendered once per wavelength with grey coefficients and summed to RGB: the wavelengths, their
    density and their sRGB weights are right."""
    a, b = (spectral_render("subsurface_skin", SKIN, 16, 24, seed, tmp_path) for seed in (1, 2))
    grey, grey_var = 0.5 * (a + b), 0.25 * (a - b) ** 2
    img, var = ours_of("subsurface_skin")
    assert chi(img, var, grey, grey_var) < CHI
    assert_spheres_agree(img, var, grey, grey_var)
