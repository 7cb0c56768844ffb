"""Media against pbrt-v4's own images (tests/data/pbrt/media_*.pbrt, rendered by pbrt-v4's volpath:
render_references.py; the grids' scene is written by make_media_grids.py), within both renderers'
noise: chi < CHI and per-channel means within 4 standard errors of the difference. Each scene
also fails with a wrong medium (another g, sigma or emission) by a margin."""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parents[1]))
from pbrt_compare import CHI, DATA, DISTINCT, chi, ours, ours_of, reference, variant_chi  # noqa: E402

from renderer.api import load_scene, render  # noqa: E402
from renderer.device.scene import uses_media  # noqa: E402


def assert_media_matches(name: str, path: Path | None = None) -> tuple[np.ndarray, np.ndarray]:
    """chi < CHI and each channel mean within 4 standard errors of the difference (our render of
    ``path`` if given, else of the scene in tests/data/pbrt)."""
    img, var = ours_of(name) if path is None else ours(load_scene(path))
    ref, ref_var = reference(name)
    c = chi(img, var, ref, ref_var)
    assert c < CHI, f"{name}: chi {c:.3f}"
    se = np.sqrt((var + ref_var).sum((0, 1))) / (img.shape[0] * img.shape[1])
    diff = img.mean((0, 1)) - ref.mean((0, 1))
    assert np.all(np.abs(diff) < 4 * se), f"{name}: means {img.mean((0, 1))} vs {ref.mean((0, 1))}, se {se}"
    return ref, ref_var


def assert_variant_fails(name: str, edits: list[tuple[str, str]], ref: np.ndarray, ref_var: np.ndarray,
                         tmp_path: Path) -> None:
    """Our render of ``name`` with ``edits`` fails the comparison by a margin: chi above DISTINCT
    or a channel mean 8 standard errors off. Rendered at 4 x 128 spp: media images are noisy, and
    a wrong medium must show above our noise, not only above pbrt's."""
    text = (DATA / f"{name}.pbrt").read_text()
    for old, new in edits:
        assert old in text
        text = text.replace(old, new)
    (tmp_path / "variant.pbrt").write_text(text)
    assert_variant_fails_at(tmp_path / "variant.pbrt", ref, ref_var)


def assert_variant_fails_at(path: Path, ref: np.ndarray, ref_var: np.ndarray) -> None:
    scene = load_scene(path)
    name = path.stem
    a, b = render(scene, spp=256, seed=21), render(scene, spp=256, seed=22)
    img, var = 0.5 * (a + b), 0.25 * (a - b) ** 2
    se = np.sqrt((var + ref_var).sum((0, 1))) / (img.shape[0] * img.shape[1])
    z = np.abs(img.mean((0, 1)) - ref.mean((0, 1))) / se
    c = chi(img, var, ref, ref_var)
    assert c > DISTINCT or z.max() > 8, f"{name} variant: chi {c:.2f}, means {z} standard errors off"


def test_fog_lit_by_a_spot_light_with_the_camera_inside(tmp_path):
    ref, ref_var = assert_media_matches("media_fog")
    assert_variant_fails("media_fog", [('"rgb sigma_s" [0.25 0.25 0.25]', '"rgb sigma_s" [0.6 0.6 0.6]')], ref, ref_var,
                         tmp_path)
    assert_variant_fails("media_fog", [('"float g" 0.3', '"float g" -0.3')], ref, ref_var, tmp_path)


def test_scattering_cubes_at_three_asymmetries(tmp_path):
    ref, ref_var = assert_media_matches("media_cube")
    swapped = [('"float g" -0.7', '"float g" X'), ('"float g" 0.7', '"float g" -0.7'), ('"float g" X', '"float g" 0.7')]
    assert variant_chi("media_cube", swapped, ref, ref_var, tmp_path) > DISTINCT


def test_absorbing_liquid_in_glass(tmp_path):
    ref, ref_var = assert_media_matches("media_glass")
    assert variant_chi("media_glass", [("[0.5 0.8 1.2]", "[0.25 0.4 0.6]")], ref, ref_var, tmp_path) > DISTINCT


def test_uniformgrid_and_emissive_rgbgrid(tmp_path):
    ref, ref_var = assert_media_matches("media_grids")
    assert variant_chi("media_grids", [('"float Lescale" 1.5', '"float Lescale" 0.5')], ref, ref_var,
                       tmp_path) > DISTINCT
    assert_variant_fails("media_grids", [('"rgb sigma_s" [1.5 1.5 1.5]', '"rgb sigma_s" [0.4 0.4 0.4]')], ref,
                         ref_var, tmp_path)


def test_cloud(tmp_path):
    ref, ref_var = assert_media_matches("media_cloud")
    assert_variant_fails("media_cloud", [('"float g" 0.6', '"float g" 0.6 "float frequency" 6')], ref, ref_var,
                         tmp_path)
    assert_variant_fails("media_cloud", [('"float g" 0.6', '"float g" -0.6')], ref, ref_var, tmp_path)


def test_path_integrator_ignores_media_as_pbrts_does(tmp_path):
    """pbrt-v4's path integrator renders a scene as if it had no media: the fog scene under
    ``path`` is, bit for bit, the same scene without its medium, and compiles no media."""
    text = (DATA / "media_fog.pbrt").read_text().replace('Integrator "volpath"', 'Integrator "path"')
    (tmp_path / "path.pbrt").write_text(text)
    (tmp_path / "none.pbrt").write_text(text.replace('MediumInterface "" "fog"', ""))
    with_medium, without = load_scene(tmp_path / "path.pbrt"), load_scene(tmp_path / "none.pbrt")
    assert not uses_media(with_medium) and uses_media(load_scene(DATA / "media_fog.pbrt"))
    np.testing.assert_array_equal(render(with_medium, spp=2, seed=3), render(without, spp=2, seed=3))


def test_temperature_grid_glows_as_pbrts_blackbody(tmp_path):
    ref, ref_var = assert_media_matches("media_fire")
    assert_variant_fails("media_fire", [('"float temperaturescale" 1.6', '"float temperaturescale" 1.4')], ref,
                         ref_var, tmp_path)


def test_aovs_look_through_interfaces_in_scenes_with_media():
    """With media the path kernel hits interface surfaces (to change medium); the AOVs still show
    the first real surface: no pixel is labelled with the interface material."""
    from renderer.device.scene import upload
    from renderer.integrators.aov import render_aovs
    from renderer.materials.selection import INTERFACE

    desc = load_scene(DATA / "media_cube.pbrt")
    interface = [i for i, m in enumerate(desc.materials) if m.kind == INTERFACE]
    ds = upload(desc, "cpu")
    assert ds.features.media and interface
    ids = render_aovs(ds, seed=1, n_samples=2)["material"][..., 0]
    assert not np.isin(ids, interface).any()
    assert (ids >= 0).mean() > 0.5            # floor and wall behind the cubes


def test_nanovdb_grid(tmp_path):
    """The grid file is made by make_media_vdb.py (as for pbrt's reference), here in tmp_path."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("make_media_vdb", DATA / "make_media_vdb.py")
    maker = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(maker)
    maker.write_grid(tmp_path / "media_vdb.nvdb")
    (tmp_path / "media_vdb.pbrt").write_text((DATA / "media_vdb.pbrt").read_text())
    ref, ref_var = assert_media_matches("media_vdb", tmp_path / "media_vdb.pbrt")
    text = (tmp_path / "media_vdb.pbrt").read_text()
    (tmp_path / "media_vdb.pbrt").write_text(text.replace('"rgb sigma_s" [4 4 4]', '"rgb sigma_s" [2 2 2]'))
    assert_variant_fails_at(tmp_path / "media_vdb.pbrt", ref, ref_var)
