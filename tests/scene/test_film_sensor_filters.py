"""The film side without pbrt: filter importance sampling reproduces each filter, the box default
leaves the camera jitter untouched, the crop rules are pbrt-v4's, and white balance turns its
illuminant white."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import warp as wp

from renderer.color.rgb import blackbody_rgb
from renderer.errors import RenderError, SceneError
from renderer.pixel_filter import PixelFilter, build_pixel_filter, filter_1d, sample_filter
from renderer.scene import load_description
from renderer.scene.description import FilmDesc, FilterDesc
from renderer.scene.imaging import film_region
from renderer.sensor import sensor_output, white_balance

HEAD = 'Camera "perspective"\nWorldBegin\n'


@wp.kernel
def _sample(f: PixelFilter, u: wp.array(dtype=wp.vec2), p: wp.array(dtype=wp.vec2), w: wp.array(dtype=float)):
    i = wp.tid()
    s = sample_filter(f, u[i])
    p[i] = s.p
    w[i] = s.weight


def draw(desc: FilterDesc, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    f, keep = build_pixel_filter(desc, "cpu")
    ua = wp.array(u.astype(np.float32), dtype=wp.vec2, device="cpu")
    p = wp.zeros(len(u), dtype=wp.vec2, device="cpu")
    w = wp.zeros(len(u), dtype=float, device="cpu")
    wp.launch(_sample, dim=len(u), inputs=[f, ua, p, w], device="cpu")
    return p.numpy(), w.numpy()


def test_default_box_returns_the_random_numbers_unchanged():
    """Scenes naming no filter keep their images bit for bit: the pixel offset is the jitter itself."""
    u = np.random.default_rng(1).random((4096, 2), dtype=np.float32)
    p, w = draw(FilterDesc(), u)
    assert np.array_equal(p, u) and np.all(w == 1.0)


@pytest.mark.parametrize("desc", [FilterDesc("box", (1.5, 0.7)), FilterDesc("gaussian", (1.5, 1.5)),
                                  FilterDesc("gaussian", (2.0, 1.0), sigma=0.8),
                                  FilterDesc("mitchell", (2.0, 2.0)), FilterDesc("mitchell", (3.0, 1.5), b=0.2, c=0.4),
                                  FilterDesc("sinc", (4.0, 4.0)), FilterDesc("sinc", (3.0, 2.0), tau=2.0),
                                  FilterDesc("triangle", (2.0, 2.0)), FilterDesc("triangle", (1.5, 1.0))],
                         ids=lambda d: f"{d.kind}-{d.radius[0]}x{d.radius[1]}")
def test_weighted_samples_reproduce_the_normalised_filter(desc):
    """E[weight x 1(offset in bin)] over many samples = the bin's share of the filter's integral, per
    axis (the filters are separable), within 5 standard errors; and the mean weight is 1."""
    n = 400_000
    u = np.random.default_rng(7).random((n, 2))
    p, w = draw(desc, u)
    assert abs(w.mean() - 1.0) < 5.0 * w.std() / np.sqrt(n) + 1e-6
    for axis in (0, 1):
        r = desc.radius[axis]
        x = p[:, axis] - 0.5
        assert np.all(np.abs(x) <= r + 1e-5)
        edges = np.linspace(-r, r, 17)
        fine = np.linspace(-r, r, 16 * 4096 + 1)
        fx = filter_1d(desc, 0.5 * (fine[1:] + fine[:-1]), axis)
        share = np.add.reduceat(fx, np.arange(0, len(fx), 4096)) / fx.sum()
        bins = np.clip(np.searchsorted(edges, x, side="right") - 1, 0, 15)
        est = np.bincount(bins, weights=w, minlength=16) / n
        se = np.sqrt(np.bincount(bins, weights=w * w, minlength=16) / n / n) + 1e-4
        # the table is pbrt's (32 cells per unit radius): allow its discretisation besides the noise
        assert np.all(np.abs(est - share) < 5.0 * se + 0.004), (est - share, se)


def test_negative_lobes_give_negative_weights():
    _, w = draw(FilterDesc("sinc", (4.0, 4.0)), np.random.default_rng(3).random((20_000, 2)))
    assert (w < 0).mean() > 0.05 and len(np.unique(np.abs(w).round(5))) == 1   # +-one constant, as pbrt


def test_crop_window_and_pixel_bounds_follow_pbrt():
    """What pbrt-v4 wrote for a 16x16 film: cropwindow [0.25 0.6 0.1 0.5] -> its data window x 4..9,
    y 2..7; --pixelbounds 2,9,3,20 -> x 2..8, y 3..15 (clipped to the image)."""
    assert film_region(FilmDesc(16, 16, crop_window=(0.25, 0.6, 0.1, 0.5)), 16, 16) == (4, 10, 2, 8)
    assert film_region(FilmDesc(16, 16, pixel_bounds=(2, 9, 3, 20)), 16, 16) == (2, 9, 3, 16)
    assert film_region(FilmDesc(16, 16), 16, 16) == (0, 16, 0, 16)
    with pytest.raises(RenderError, match="select no pixels"):
        film_region(FilmDesc(16, 16, pixel_bounds=(20, 30, 0, 4)), 16, 16)


def _write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "scene.pbrt"
    path.write_text(text)
    return path


def test_film_parameters_as_pbrt_reads_them(tmp_path):
    path = _write(tmp_path, 'Camera "perspective" "float shutteropen" 0.25 "float shutterclose" 0.75\n'
                            'PixelFilter "mitchell" "float xradius" 3 "float B" 0.5\n'
                            'Film "rgb" "integer xresolution" 40 "integer yresolution" 20 "float scale" 2\n'
                            '  "float cropwindow" [0.9 0.1 0 0.5] "integer pixelbounds" [0 4 0 4]\n'
                            '  "float maxsampleluminance" 7 "string sensor" "canon_eos_100d"\nWorldBegin\n')
    s = load_description(path)
    f = s.film
    assert (f.iso, f.max_component_value, f.white_balance, s.camera.exposure_time) == (200.0, 7.0, 6500.0, 0.5)
    assert f.crop_window == (0.1, 0.9, 0.0, 0.5) and f.pixel_bounds is None      # the crop window wins
    assert f.filter == FilterDesc("mitchell", (3.0, 2.0), b=0.5)                  # PixelFilter before Film
    text = "\n".join(s.warnings)
    for part in ('"scale" is pbrt-v3', '"maxsampleluminance" is pbrt-v3', 'sensor "canon_eos_100d"',
                 "the crop window is used"):
        assert part in text


@pytest.mark.parametrize("text, match", [
    ('Camera "perspective" "float shutteropen" 1 "float shutterclose" 1\nWorldBegin\n', "does not open"),
    ('Film "rgb" "float cropwindow" [0 1 0]\nWorldBegin\n', "needs 4 values"),
    ('Film "rgb" "integer xresolution" 8 "integer pixelbounds" [9 12 0 8]\nWorldBegin\n', "select no pixels"),
    ('Film "rgb" "float whitebalance" 50\nWorldBegin\n', "whitebalance"),
    ('PixelFilter "gaussian" "float sigma" 0\nWorldBegin\n', "sigma"),
    ('PixelFilter "box" "float xradius" -1\nWorldBegin\n', "radii"),
    ('PixelFilter "lanczos"\nWorldBegin\n', 'unknown PixelFilter "lanczos"'),
])
def test_bad_film_and_filter_parameters_are_located_errors(tmp_path, text, match):
    with pytest.raises(SceneError, match=match) as info:
        load_description(_write(tmp_path, text))
    assert info.value.loc is not None and info.value.loc.line == 1


def test_white_balance_turns_its_illuminant_white_and_d65_is_left_alone():
    """pbrt's von Kries balance for T maps the light of temperature T (a blackbody below 4000 K) to
    neutral grey, and a 6500 K balance (CIE D65, up to pbrt's 1.4388/1.4380 correction) changes little."""
    cct = 3200.0 * 1.4388 / 1.4380
    balanced = white_balance(3200.0) @ blackbody_rgb(cct)
    np.testing.assert_allclose(balanced / balanced.mean(), 1.0, atol=2e-3)
    np.testing.assert_allclose(white_balance(6500.0), np.eye(3), atol=3e-3)


def test_sensor_output_is_the_identity_by_default_and_scales_by_the_imaging_ratio():
    from renderer.scene.description import CameraDesc

    img = np.random.default_rng(0).random((4, 5, 3)).astype(np.float32)
    cam = CameraDesc(np.eye(4))
    assert np.array_equal(sensor_output(img, FilmDesc(), cam), img)
    cam.exposure_time = 0.5
    np.testing.assert_array_equal(sensor_output(img, FilmDesc(iso=400.0), cam), img * np.float32(2.0))


def test_pbrt_v3_film_camera_and_filter_names_read_as_upgrade_writes_them(tmp_path):
    s = load_description(_write(tmp_path, 'Camera "environment"\nPixelFilter "gaussian" "float xwidth" 2 '
                                          '"float ywidth" 1 "float alpha" 2\nFilm "image"\nWorldBegin\n'))
    assert s.camera.projection == "spherical equirectangular"
    assert s.film.filter == FilterDesc("gaussian", (2.0, 1.0), sigma=0.5)        # 1 / sqrt(2 x 2)
    text = "\n".join(s.warnings)
    for part in ('Camera "environment" is pbrt-v3', 'Film "image" is pbrt-v3', '"xwidth" is pbrt-v3',
                 '"alpha" is pbrt-v3'):
        assert part in text, text


@pytest.mark.parametrize("text, match", [
    ('Film "rgb" "float iso" 1e30\nWorldBegin\n', '"iso" must be <='),
    ('Film "rgb" "float scale" 1e30\nWorldBegin\n', '"scale" must be <='),
    ('Camera "perspective" "float shutterclose" 1e30\nWorldBegin\n', "would overflow"),
])
def test_an_imaging_ratio_that_would_overflow_is_refused(tmp_path, text, match):
    with pytest.raises(SceneError, match=match):
        load_description(_write(tmp_path, text))
