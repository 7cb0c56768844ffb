"""The film's fixed-point sums are exact: any grouping and order of the same samples gives the same
integers, equal to an independent exact (Python integer) sum of each sample rounded down to 2^-62,
and the sample ranges a checkpoint records are checked."""
from __future__ import annotations

import numpy as np
import pytest
import warp as wp

from renderer.device.film import FRACTION_BITS, MAX_SAMPLE, Film, add_into
from renderer.sample_ranges import add_range, from_array, missing

W, H, PASSES = 8, 4, 12


def samples() -> np.ndarray:
    """(PASSES, W*H, 3) float32 radiance over 22 decades, with zeros, as the path kernel writes them."""
    rng = np.random.default_rng(11)
    v = (10.0 ** rng.uniform(-12, 10, (PASSES, W * H, 3))).astype(np.float32)
    v[rng.random(v.shape) < 0.1] = 0.0
    return v


def film_of(passes: list[int], v: np.ndarray) -> Film:
    film = Film(W, H, "cpu")
    for p in passes:
        film.sample.assign(wp.array(v[p].astype(np.float64), dtype=wp.vec3d, device="cpu"))
        film.accumulate(0, H)
        film.spp += 1
    return film


def test_any_grouping_and_order_gives_the_same_exact_sums():
    v = samples()
    in_order = film_of(list(range(PASSES)), v).sums()
    parts = [film_of(list(g), v) for g in ([7, 8, 9, 10, 11], [3, 0], [5, 6, 4, 1, 2])]
    for order in ([2, 0, 1], [1, 0, 2]):
        whole, fraction = np.zeros((W * H, 3), np.int64), np.zeros((W * H, 3), np.int64)
        for i in order:
            add_into(whole, fraction, parts[i].whole.numpy(), parts[i].fraction.numpy())
        assert np.array_equal(np.stack([whole, fraction], axis=-1), in_order)
    # independently: each sample rounded down to a multiple of 2^-62, summed as Python integers
    one = 1 << FRACTION_BITS
    exact = [[sum(int(np.floor(np.ldexp(float(v[p, i, c]), FRACTION_BITS))) for p in range(PASSES)) for c in range(3)]
             for i in range(W * H)]
    got = in_order[..., 0].astype(object) * one + in_order[..., 1].astype(object)
    assert got.tolist() == exact
    assert np.all((0 <= in_order[..., 1]) & (in_order[..., 1] < one))


def test_image_is_the_mean_to_float32_precision():
    v = samples()
    img = film_of(list(range(PASSES)), v).image()
    np.testing.assert_allclose(img.reshape(-1, 3), v.astype(np.float64).mean(axis=0), rtol=2e-7)


def test_samples_too_large_for_the_sums_are_dropped_and_counted():
    v = np.ones((1, W * H, 3), dtype=np.float32)
    v[0, 5, 1] = MAX_SAMPLE
    film = film_of([0], v)
    assert film.bad_samples == 1 and film.sums()[5].sum() == 0
    assert film.sums()[4, :, 0].tolist() == [1, 1, 1]


def test_an_earlier_versions_float_sums_resume_as_fixed_point():
    from renderer.film_state import FilmState, settings_key
    from renderer.settings import RenderSettings

    settings = RenderSettings(width=2, height=1, seed=0, max_depth=1)
    state = {"sum": np.array([[1.5, 0.25, 3.0], [0.0, 2.0 ** -62, 7.75]]), "spp": np.int64(4),
             "bad": np.zeros(1), "rays": np.zeros(1), "seconds": np.float64(1.0),
             "fingerprint": np.str_("f"), "settings": np.str_(settings_key(settings))}
    film = FilmState.from_state(state, "f", settings, pixels=2)
    half = 1 << (FRACTION_BITS - 1)
    assert film.sums[..., 0].tolist() == [[1, 0, 3], [0, 0, 7]]
    assert film.sums[..., 1].tolist() == [[half, half // 2, 0], [0, 1, 3 * half // 2]]
    assert film.ranges == [(0, 4)]


def test_sample_ranges():
    r = add_range(add_range(add_range([], 4, 6), 0, 2), 2, 4)
    assert r == [(0, 6)]
    assert missing([(2, 4), (8, 9)], 10) == [(0, 2), (4, 8), (9, 10)]
    assert missing([(0, 12)], 6) == []
    with pytest.raises(ValueError, match="overlaps"):
        add_range([(0, 4)], 3, 5)
    with pytest.raises(ValueError, match="sorted, disjoint"):
        from_array(np.array([[4, 6], [0, 5]]))
