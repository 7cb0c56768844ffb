"""pbrt-v4's ``subsurface`` material against pbrt-v4's own images (tests/data/pbrt/subsurface_*.pbrt,
made by render_references.py with ``volpath``; compared as :mod:`pbrt_compare` does: chi of the two
means over both renderers' noise, and per-channel means).

- ``subsurface_named``: measured media that are nearly grey (Marble, whole milk), smooth and rough;
- ``subsurface_reflectance``: a body from ``reflectance`` and ``mfp``, and one from ``sigma_a``,
  ``sigma_s``, ``g`` 0.6 and ``eta`` 1.5 under a rough boundary; another mfp must fail;
- ``subsurface_skin``: Skin1 and Ketchup, whose coefficients change 15-fold over the spectrum. pbrt-v4
  evaluates the BSSRDF per wavelength and we per RGB channel, so our RGB image differs from pbrt's
  by more than noise in the most translucent channel (red: +16 % and +84 %). Rendering the same
  scene as pbrt does, one grey render per wavelength with the coefficients of pbrt-v4's RGB
  upsampling (``unbounded_spectrum``: Jakob and Hanika's sigmoid-quadratic spectra, fitted here),
  summed with CIE 1931/D65 to sRGB weights, agrees with pbrt-v4 within noise: the difference is
  the colour model, not the BSSRDF.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from pbrt_compare import CHI, DATA, DISTINCT, assert_matches_pbrt, chi, ours_of, reference, variant_chi
import renderer
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


#: The visible range pbrt-v4 samples wavelengths from, and a 1 nm grid over it.
GRID = np.arange(360.0, 831.0, 1.0)


def _sigmoid(c: np.ndarray, lam: np.ndarray) -> np.ndarray:
    t = (lam - 360.0) / 470.0
    x = c[0] * t * t + c[1] * t + c[2]
    return 0.5 + x / (2.0 * np.sqrt(1.0 + x * x))


def unbounded_spectrum(rgb: tuple[float, float, float], lam: np.ndarray) -> np.ndarray:
    """pbrt-v4's RGBUnboundedSpectrum of ``rgb`` at ``lam``: 2 max(rgb) times the sigmoid of a
    quadratic whose colour (CIE 1931 under D65, sRGB) is rgb / (2 max(rgb)) (Jakob and Hanika 2019;
    pbrt-v4 interpolates a precomputed table of these fits, we solve for the one we need)."""
    rgb = np.asarray(rgb, np.float64)
    m = rgb.max()
    if m <= 0.0:
        return np.zeros_like(lam)
    target = rgb / (2.0 * m)
    w = spectrum_to_rgb_weights(GRID)
    colour = lambda c: _sigmoid(c, GRID) @ w  # noqa: E731
    c = np.zeros(3)
    for _ in range(200):
        r = colour(c) - target
        if np.abs(r).max() < 1e-8:
            break
        J = np.stack([(colour(c + d) - colour(c - d)) / 2e-6 for d in np.eye(3) * 1e-6], 1)
        step = np.linalg.lstsq(J, -r, rcond=None)[0]
        k = 1.0
        while k > 1e-4 and np.abs(colour(c + k * step) - target).max() >= np.abs(r).max():
            k *= 0.5
        c = c + k * step
    assert np.abs(colour(c) - target).max() < 1e-6
    return 2.0 * m * _sigmoid(c, lam)


def spectral_render(name: str, media: dict[str, str], n_lambda: int, spp: int, seed: int, tmp: Path) -> np.ndarray:
    """Our image of ``<name>.pbrt`` rendered as pbrt-v4 renders it: one render per wavelength (the
    midpoints of n_lambda strata of [360, 830] nm) in which each named medium of ``media`` (its
    directive text, in the file) has the grey coefficients of its spectra at that wavelength, summed
    with the CIE 1931/D65 to sRGB weights. Everything else in the scene must be grey."""
    lam = 360.0 + (np.arange(n_lambda) + 0.5) * 470.0 / n_lambda
    weights = spectrum_to_rgb_weights(lam)
    spectra = {text: (unbounded_spectrum(NAMED_MEDIA[medium][1], lam), unbounded_spectrum(NAMED_MEDIA[medium][0], lam))
               for text, medium in media.items()}
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
def test_coloured_media_match_pbrt_v4_rendered_spectrally(tmp_path):
    """Skin1 and Ketchup as pbrt-v4 renders them (per wavelength) agree with pbrt-v4 within noise,
    where our RGB image does not (its red is 16 % and 84 % above pbrt's)."""
    ref, ref_var = reference("subsurface_skin")
    a, b = (spectral_render("subsurface_skin", SKIN, 16, 24, seed, tmp_path) for seed in (1, 2))
    img, var = 0.5 * (a + b), 0.25 * (a - b) ** 2
    c = chi(img, var, ref, ref_var)
    assert c < CHI, c
    assert_spheres_agree(img, var, ref, ref_var)
    rgb, rgb_var = ours_of("subsurface_skin")
    assert chi(rgb, rgb_var, ref, ref_var) > c
    assert sphere_means(rgb)[1][0] > 1.5 * sphere_means(ref)[1][0]     # Ketchup's red, per RGB channel
