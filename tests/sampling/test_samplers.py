"""The samplers' numbers: library tables reproduced, (0,2)-net and stratum properties, one Halton
and one Sobol sequence spread over the image, determinism, decorrelated pixels, refused overflow."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import qmc

from renderer.device.sampler import sample_points, upload_sampler
from renderer.errors import RenderError
from renderer.sampling.sampler_spec import SamplerSpec

SOBOL_LIKE = [("zsobol", r) for r in ("fastowen", "permutedigits", "owen", "none")] + \
             [("paddedsobol", r) for r in ("fastowen", "owen")] + [("sobol", "fastowen")]


def truncated(x: np.ndarray) -> np.ndarray:
    """Values as the samplers return them: the top 24 bits of a 32-bit fraction."""
    return np.floor(np.asarray(x, dtype=np.float64) * 2 ** 24) / 2 ** 24


def is_02_net(pts: np.ndarray) -> bool:
    """Every elementary interval of area 1/n (2^a x 2^b cells, a + b = log2 n) holds one point."""
    n = len(pts)
    m = n.bit_length() - 1
    for a in range(m + 1):
        cells = np.floor(pts[:, 0] * 2 ** a).astype(int) * 2 ** (m - a) + np.floor(pts[:, 1] * 2 ** (m - a)).astype(int)
        if len(np.unique(cells)) != n:
            return False
    return True


def test_unscrambled_sobol_is_scipys_joe_kuo_sequence():
    """On a one-pixel film the sobol sampler's index is the sample number; scipy enumerates the same
    points in Gray-code order (its point n is our point n ^ (n >> 1))."""
    n, d = 256, 12
    ours = sample_points(SamplerSpec("sobol", n, "none"), 1, 1, 0, n, d)[:, 0, 0]
    ref = qmc.Sobol(d, scramble=False, bits=32).random(n)
    gray = np.arange(n) ^ (np.arange(n) >> 1)
    np.testing.assert_array_equal(ours[gray], truncated(ref))


def test_unscrambled_halton_is_scipys_radical_inverse():
    n, d = 200, 9
    ours = sample_points(SamplerSpec("halton", n, "none"), 1, 1, 0, n, d)[:, 0, 0]
    np.testing.assert_allclose(ours, qmc.Halton(d, scramble=False).random(n), atol=1e-6)


def test_halton_spreads_one_sequence_over_the_pixels():
    """On an 8x9 film (Halton scales 2^3 and 3^2) the first sample of every pixel, placed in image
    coordinates, is exactly the first 72 points of the 2D Halton sequence: the Chinese remainder
    theorem gave each pixel its own indices."""
    pts = sample_points(SamplerSpec("halton", 4, "none"), 8, 9, 3, 1, 2)[0]
    py, px = np.mgrid[0:9, 0:8]
    img = np.stack([(px + pts[..., 0]) / 8, (py + pts[..., 1]) / 9], -1).reshape(-1, 2)
    ref = qmc.Halton(2, scramble=False).random(72)
    key = lambda p: np.round(p * 1e5).astype(np.int64).tolist()
    assert sorted(key(img)) == sorted(key(ref))


def test_sobol_spreads_one_sequence_over_the_pixels():
    """On a 4x4 film the first sample of all 16 pixels is the first 16 Sobol points, and the first
    4 samples of all pixels the first 64: each pixel's indices solve the GF(2) pixel system."""
    pts = sample_points(SamplerSpec("sobol", 4, "none"), 4, 4, 3, 4, 2)
    py, px = np.mgrid[0:4, 0:4]
    img = np.stack([(px + pts[..., 0]) / 4, (py + pts[..., 1]) / 4], -1).reshape(-1, 2)
    ref = truncated(qmc.Sobol(2, scramble=False, bits=32).random(64))
    key = lambda p: np.round(p * 2 ** 20).astype(np.int64).tolist()
    assert sorted(key(img)) == sorted(key(ref))


@pytest.mark.parametrize("name, randomize", SOBOL_LIKE)
def test_power_of_two_samples_of_a_pixel_form_a_02_net(name, randomize):
    """64 samples of a pixel: the film dimensions are a (0,6,2)-net (scrambling keeps that); for
    zsobol and paddedsobol every later 2D pair is one too, since it reuses Sobol dimensions 0-1."""
    pts = sample_points(SamplerSpec(name, 64, randomize), 4, 3, 11, 64, 8)
    pairs = [(0, 1)] if name == "sobol" else [(0, 1), (2, 3), (4, 5), (6, 7)]
    for y in range(3):
        for x in range(4):
            for a, b in pairs:
                assert is_02_net(pts[:, y, x, [a, b]]), (x, y, a)


@pytest.mark.parametrize("jitter", [True, False])
def test_stratified_puts_one_sample_in_each_stratum(jitter):
    spec = SamplerSpec("stratified", 12, jitter=jitter, xsamples=4, ysamples=3)
    pts = sample_points(spec, 3, 2, 5, 12, 5)
    for y in range(2):
        for x in range(3):
            p = pts[:, y, x]
            for a in (0, 2):
                cells = np.floor(p[:, a] * 4).astype(int) * 3 + np.floor(p[:, a + 1] * 3).astype(int)
                assert sorted(cells) == list(range(12))
            assert sorted(np.floor(p[:, 4] * 12).astype(int)) == list(range(12))   # 1D: twelve strata
            if not jitter:
                np.testing.assert_allclose((p[:, 4] * 12) % 1, 0.5, atol=1e-5)


@pytest.mark.parametrize("name", ["stratified", "halton", "sobol", "paddedsobol", "zsobol"])
def test_same_inputs_same_numbers_other_seed_other_numbers(name):
    spec = SamplerSpec(name, 16)
    a = sample_points(spec, 5, 4, 9, 16, 7)
    np.testing.assert_array_equal(a, sample_points(spec, 5, 4, 9, 16, 7))
    b = sample_points(spec, 5, 4, 10, 16, 7)
    assert np.mean(a[..., 2:] == b[..., 2:]) < 0.01     # randomised dimensions change with the seed
    assert np.all((a >= 0) & (a < 1))


@pytest.mark.parametrize("name", ["stratified", "paddedsobol", "zsobol"])
def test_neighbouring_pixels_are_decorrelated(name):
    """Each pixel's 16 samples of a dimension, against its right neighbour's: the correlations
    average about zero and are no larger than independent sequences' (|r| ~ 0.2 for 16 samples).
    (halton and sobol spread one image-wide sequence under one scramble over the pixels, as pbrt-v4
    does, so their neighbours' sequences are related: docs/samplers.md.)"""
    pts = sample_points(SamplerSpec(name, 16), 16, 16, 4, 16, 8)
    for d in range(2, 8):
        v = pts[..., d] - pts[..., d].mean(axis=0)
        a, b = v[:, :, :-1].reshape(16, -1), v[:, :, 1:].reshape(16, -1)
        r = (a * b).sum(0) / np.sqrt((a * a).sum(0) * (b * b).sum(0))
        assert abs(r.mean()) < 0.06, (d, r.mean())
        assert np.abs(r).mean() < 0.3, (d, np.abs(r).mean())


def test_blocks_past_the_pattern_are_randomised_afresh():
    """Samples 16-31 of a 16-sample zsobol pattern are again a (0,4,2)-net, but not the same one."""
    pts = sample_points(SamplerSpec("zsobol", 16), 2, 2, 1, 32, 4)
    assert is_02_net(pts[16:, 0, 0, :2]) and is_02_net(pts[:16, 0, 0, :2])
    assert not np.array_equal(pts[16:, 0, 0], pts[:16, 0, 0])


def test_indices_past_32_bits_are_refused():
    with pytest.raises(RenderError, match="32 bits"):
        upload_sampler(SamplerSpec("zsobol", 1 << 10), 8192, 8192, "cpu")


def test_spec_checks_names_and_strata():
    with pytest.raises(RenderError, match="offers randomize"):
        SamplerSpec("halton", 16, "fastowen")
    with pytest.raises(RenderError, match="xsamples x ysamples"):
        SamplerSpec("stratified", 16, xsamples=3, ysamples=3)
    assert SamplerSpec("zsobol", 12).warning() and SamplerSpec("sobol", 6).warning()
    assert SamplerSpec("zsobol", 16).warning() is None and SamplerSpec("halton", 12).warning() is None


def test_byte_tables_give_the_column_xor_bits():
    """zsobol's and paddedsobol's byte-table lookup returns the same 32 bits as XORing the
    generator columns of the index's set bits, for indices with every byte populated."""
    import warp as wp

    from renderer.device.runtime import init_warp
    from renderer.sampling.lowdiscrepancy import sobol_bits, sobol_bits_bytes
    from renderer.sampling.lowdiscrepancy_tables import sobol_byte_tables, sobol_matrices

    @wp.kernel
    def both(m: wp.array(dtype=wp.uint32), t: wp.array(dtype=wp.uint32), a: wp.array(dtype=wp.uint32),
             out: wp.array(dtype=wp.uint32, ndim=2)):
        i = wp.tid()
        for d in range(2):
            out[i, 2 * d] = sobol_bits(m, d, a[i])
            out[i, 2 * d + 1] = sobol_bits_bytes(t, d, a[i])

    init_warp()
    cols = sobol_matrices(2)
    idx = np.concatenate([np.random.default_rng(0).integers(0, 2 ** 32, 2000, dtype=np.uint64),
                          [0, 1, 255, 256, 2 ** 24, 2 ** 32 - 1]]).astype(np.uint32)
    out = wp.zeros((len(idx), 4), dtype=wp.uint32)
    wp.launch(both, dim=len(idx), inputs=[wp.array(cols.ravel(), dtype=wp.uint32),
                                          wp.array(sobol_byte_tables(cols).ravel(), dtype=wp.uint32),
                                          wp.array(idx, dtype=wp.uint32), out])
    o = out.numpy()
    np.testing.assert_array_equal(o[:, 0], o[:, 1])
    np.testing.assert_array_equal(o[:, 2], o[:, 3])
    bits = (idx[:, None].astype(np.uint64) >> np.arange(32, dtype=np.uint64)) & 1
    ref0 = np.bitwise_xor.reduce(np.where(bits.astype(bool), cols[0][None], np.uint32(0)), axis=1)
    np.testing.assert_array_equal(o[:, 1], ref0)
