"""Large images stay within a small multiple of their float32 size while they are decoded and
turned into a sampling distribution (a black 16384x8192 PNG once took 8-9 GB: colour-science's
float64 sRGB decode alone peaked at 16x the image)."""
from __future__ import annotations

import tracemalloc

import numpy as np
from PIL import Image

from renderer.color.rgb import srgb_to_linear
from renderer.io.images import read_image
from renderer.lights.infinite import MAP_LATLONG, distribution_function
from renderer.sampling.distribution import distribution_2d


def test_8bit_decode_equals_the_per_pixel_formula(tmp_path):
    codes = np.random.default_rng(1).integers(0, 256, size=(17, 23, 3), dtype=np.uint8)
    Image.fromarray(codes).save(tmp_path / "t.png")
    img = read_image(tmp_path / "t.png")
    assert img.dtype == np.float32
    np.testing.assert_array_equal(img, srgb_to_linear(codes.astype(np.float32) / 255.0))
    np.testing.assert_array_equal(read_image(tmp_path / "t.png", srgb=False), codes.astype(np.float32) / 255.0)


def test_decode_and_distribution_peak_under_three_image_sizes(tmp_path):
    h, w = 1024, 2048
    Image.fromarray(np.full((h, w, 3), 90, np.uint8)).save(tmp_path / "env.png")
    size = h * w * 3 * 4
    tracemalloc.start()
    try:
        rgb = read_image(tmp_path / "env.png")
        cond, marg, _ = distribution_2d(*distribution_function(rgb, MAP_LATLONG))
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak < 3 * size, f"peak {peak / size:.2f}x the float32 image"
    assert cond.shape == (h, w + 1) and marg[-1] == 1.0


def test_row_weights_give_the_same_distribution_as_weighting_the_whole_map():
    f = np.random.default_rng(2).random((8, 16)).astype(np.float32)
    weight = np.sin(np.pi * (np.arange(8) + 0.5) / 8)
    whole = distribution_2d(f.astype(np.float64) * weight[:, None])
    rows = distribution_2d(f, weight)
    for a, b in zip(whole, rows):
        np.testing.assert_array_equal(a, b)
