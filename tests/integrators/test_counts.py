"""The film's counters: rays and dropped samples are counted exactly whatever the thread count
(a CPU atomic_add is a plain read-modify-write, so rows keep their own counters), and a NaN
sample is dropped from the image and counted, also with the host compiler told to assume no NaNs."""
from __future__ import annotations

import numpy as np

import renderer
from renderer.api import RenderStats
from renderer.materials import material
from renderer.session import row_chunks
from scenes_py import single_object_scene


def render_counts(desc, threads: int) -> tuple[np.ndarray, RenderStats]:
    stats = RenderStats()
    img = renderer.render(desc, spp=3, threads=threads, stats=stats)
    return img, stats


def test_row_chunks_cover_every_row_once():
    for height, threads in [(1, 2), (7, 2), (48, 2), (256, 3), (10, 1)]:
        rows = [r for first, n in row_chunks(height, threads) for r in range(first, first + n)]
        assert rows == list(range(height))
    assert len(row_chunks(256, 2)) > 2          # several chunks per thread, taken on demand


def test_ray_count_does_not_depend_on_threads():
    desc = single_object_scene(material("diffuse", reflectance=(0.8, 0.8, 0.8)))
    img1, s1 = render_counts(desc, 1)
    img2, s2 = render_counts(desc, 2)
    img3, s3 = render_counts(desc, 3)
    assert s1.rays > 3 * s1.width * s1.height    # camera rays plus bounces and shadow rays
    assert s1.rays == s2.rays == s3.rays
    np.testing.assert_array_equal(img1, img2)
    np.testing.assert_array_equal(img1, img3)


def test_nan_sample_is_dropped_and_counted():
    m = material("diffuse", reflectance=(0.5, 0.5, 0.5))
    m.values["reflectance"] = (float("nan"), 0.5, 0.5)   # past load-time validation, as a bug would
    desc = single_object_scene(m)
    img1, s1 = render_counts(desc, 1)
    img2, s2 = render_counts(desc, 2)
    assert np.all(np.isfinite(img1))
    assert 0 < s1.bad_samples < 3 * s1.width * s1.height   # the sphere's samples, not the sky's
    assert s1.bad_samples == s2.bad_samples and s1.rays == s2.rays
    np.testing.assert_array_equal(img1, img2)


def test_counts_survive_a_checkpoint():
    from renderer.api import settings_for
    from renderer.session import RenderSession

    desc = single_object_scene(material("diffuse", reflectance=(0.8, 0.8, 0.8)))
    whole = RenderSession(desc, settings_for(desc, seed=5), threads=2)
    whole.run(4)
    first = RenderSession(desc, settings_for(desc, seed=5), threads=2)
    first.run(2)
    second = RenderSession(desc, settings_for(desc, seed=5), threads=1)
    second.restore(first.state())
    second.run(4)
    assert second.stats.rays == whole.stats.rays and second.stats.bad_samples == whole.stats.bad_samples == 0
    np.testing.assert_array_equal(second.image(), whole.image())
