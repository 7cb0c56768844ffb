"""MakeNamedMedium, MediumInterface and the camera's medium, read as pbrt-v4 reads them (no Warp)."""
from __future__ import annotations

import numpy as np
import pytest

from renderer.errors import Location, SceneError
from renderer.materials.subsurface import NAMED_MEDIA as MEASURED    # pbrt-v4's measured media, shared
from renderer.scene.media_params import RGBGRID_LE_SCALE, read_medium
from renderer.scene.params import Param, ParamSet
from scene_files import HEAD, error_at, load


def test_homogeneous_defaults_are_pbrts(tmp_path):
    s = load(tmp_path, 'MakeNamedMedium "fog" "string type" "homogeneous"\n' + HEAD)
    m = s.media[0]
    assert (m.kind, m.name, m.g) == ("homogeneous", "fog", 0.0)
    np.testing.assert_array_equal(m.sigma_a, [1, 1, 1])
    np.testing.assert_array_equal(m.sigma_s, [1, 1, 1])
    np.testing.assert_array_equal(m.Le, [0, 0, 0])
    assert s.integrator.kind == "volpath"          # pbrt-v4's default integrator


def test_homogeneous_parameters_scale_and_emission(tmp_path):
    s = load(tmp_path, HEAD + 'MakeNamedMedium "m" "string type" "homogeneous" "rgb sigma_a" [0.1 0.2 0.3]\n'
                              '  "rgb sigma_s" [1 2 3] "float scale" 2 "float g" -0.7 "rgb Le" [1 0.5 0]'
                              ' "float Lescale" 3\n')
    m = s.media[0]
    np.testing.assert_allclose(m.sigma_a, [0.2, 0.4, 0.6])
    np.testing.assert_allclose(m.sigma_s, [2, 4, 6])
    np.testing.assert_allclose(m.Le, [3, 1.5, 0])
    assert m.g == -0.7 and m.emissive


def test_preset_is_pbrts_measured_table(tmp_path):
    s = load(tmp_path, HEAD + 'MakeNamedMedium "m" "string type" "homogeneous" "string preset" "Ketchup"'
                              ' "float scale" 10\n')
    sp, sa = MEASURED["Ketchup"]
    np.testing.assert_allclose(s.media[0].sigma_s, 10 * np.array(sp))
    np.testing.assert_allclose(s.media[0].sigma_a, 10 * np.array(sa))
    s = load(tmp_path, HEAD + 'MakeNamedMedium "m" "string type" "homogeneous" "string preset" "Ketchupp"\n')
    assert any('preset "Ketchupp" not found' in w for w in s.warnings)
    assert len(MEASURED) == 47


def test_uniformgrid_layout_bounds_and_transform(tmp_path):
    s = load(tmp_path, HEAD + 'Translate 1 2 3\nMakeNamedMedium "g" "string type" "uniformgrid"\n'
                              '  "integer nx" 2 "integer ny" 3 "integer nz" 1 "float density" [0 1 2 3 4 5]\n'
                              '  "point3 p0" [1 1 1] "point3 p1" [-1 0 0] "rgb sigma_s" [2 2 2]\n')
    m = s.media[0]
    assert m.density.shape == (1, 3, 2) and m.density[0, 2, 1] == 5.0 and m.density[0, 1, 0] == 2.0
    np.testing.assert_array_equal(m.p0, [-1, 0, 0])
    np.testing.assert_array_equal(m.p1, [1, 1, 1])
    np.testing.assert_array_equal(m.medium_to_world[:3, 3], [1, 2, 3])
    np.testing.assert_array_equal(m.sigma_s, [2, 2, 2])


def test_uniformgrid_temperature(tmp_path):
    s = load(tmp_path, HEAD + 'MakeNamedMedium "g" "string type" "uniformgrid" "integer nx" 2 "float density" [1 2]\n'
                              '  "float temperature" [1500 3000] "float temperaturecutoff" 500 "float temperaturescale" 2\n')
    m = s.media[0]
    assert m.emissive and m.temperature.shape == (1, 1, 2)
    assert (m.temperature_offset, m.temperature_scale) == (500.0, 2.0)
    s = load(tmp_path, HEAD + 'MakeNamedMedium "g" "string type" "uniformgrid" "float density" [1]\n'
                              '  "float temperature" [1500] "float temperatureoffset" 100 "float temperaturecutoff" 500\n')
    assert s.media[0].temperature_offset == 100.0      # offset wins over pbrt's older name


def test_rgbgrid(tmp_path):
    s = load(tmp_path, HEAD + 'MakeNamedMedium "g" "string type" "rgbgrid" "integer nx" 2\n'
                              '  "rgb sigma_a" [1 0 0  0 1 0] "rgb Le" [1 1 1  2 2 2] "float scale" 2 "float Lescale" 3\n')
    m = s.media[0]
    assert m.rgb_sigma_a.shape == (1, 1, 2, 3) and m.rgb_sigma_s is None
    np.testing.assert_allclose(m.rgb_sigma_a[0, 0, 1], [0, 2, 0])
    np.testing.assert_allclose(m.rgb_Le[0, 0, 1], np.array([6, 6, 6]) * RGBGRID_LE_SCALE, rtol=1e-6)   # pbrt-v4: unnormalised
    assert m.emissive


def test_cloud_parameters(tmp_path):
    s = load(tmp_path, HEAD + 'MakeNamedMedium "c" "string type" "cloud" "float density" 2 "float wispiness" 0.5\n')
    assert s.media[0].cloud == (2.0, 0.5, 5.0)


def test_medium_interface_on_shapes_and_camera(tmp_path):
    s = load(tmp_path, 'MakeNamedMedium "air" "string type" "homogeneous"\nMediumInterface "" "air"\n'
                       + HEAD + 'MakeNamedMedium "ink" "string type" "homogeneous"\n'
                       'AttributeBegin\nMediumInterface "ink" "air"\nMaterial "interface"\nShape "sphere"\nAttributeEnd\n'
                       'Shape "sphere"\nMediumInterface "ink"\nShape "sphere"\n')
    assert s.camera_medium == 0
    ink_air, plain, both = (sh.media for sh in s.shapes)
    assert (ink_air.inside, ink_air.outside, ink_air.transition) == (1, 0, True)
    assert (plain.inside, plain.outside, plain.transition) == (-1, 0, True)    # state outside pbrt's block
    assert (both.inside, both.outside, both.transition) == (1, 1, False)


def test_medium_may_be_named_before_it_is_defined(tmp_path):
    s = load(tmp_path, HEAD + 'MediumInterface "late" ""\nShape "sphere"\n'
                              'MakeNamedMedium "late" "string type" "homogeneous"\n')
    assert s.shapes[0].media.inside == 0


@pytest.mark.parametrize("text, line, match, kind", [
    (HEAD + 'MakeNamedMedium "m" "string type" "fog"', 3, 'unknown medium type "fog"', SceneError),
    (HEAD + 'MakeNamedMedium "m" "float g" 0', 3, '"string type" is required', SceneError),
    (HEAD + 'MakeNamedMedium "m" "string type" "homogeneous"\nMakeNamedMedium "m" "string type" "homogeneous"',
     4, "defined twice", SceneError),
    (HEAD + 'MakeNamedMedium "m" "string type" "homogeneous" "float g" 1', 3, '"g" must be <=', SceneError),
    (HEAD + 'MakeNamedMedium "m" "string type" "homogeneous"\n "rgb sigma_a" [1 -1 0]', 4, "must not be negative",
     SceneError),
    (HEAD + 'MakeNamedMedium "m" "string type" "uniformgrid"', 3, 'no "density"', SceneError),
    (HEAD + 'MakeNamedMedium "m" "string type" "uniformgrid" "integer nx" 2\n "float density" [1 2 3]', 4,
     "has 3 values; expected nx\\*ny\\*nz = 2\\*1\\*1 = 2", SceneError),
    (HEAD + 'MakeNamedMedium "m" "string type" "uniformgrid" "integer nx" 2\n "float density" [1 -2]', 4,
     "must not be negative", SceneError),
    (HEAD + 'MakeNamedMedium "m" "string type" "uniformgrid" "integer nx" 2 "float density" [1 1]\n'
            ' "float Lescale" 2', 4, '"Lescale" must give', SceneError),
    (HEAD + 'MakeNamedMedium "m" "string type" "uniformgrid" "float density" [1] "rgb Le" [1 1 1]\n'
            ' "float temperature" [900]', 3, 'both "Le" and "temperature"', SceneError),
    (HEAD + 'MakeNamedMedium "m" "string type" "uniformgrid" "float density" [1]\n "float temperature" [900 1]',
     4, '"temperature" has 2 values', SceneError),
    (HEAD + 'MakeNamedMedium "m" "string type" "uniformgrid" "float density" [1] "point3 p1" [1 0 1]', 3,
     "enclose no volume", SceneError),
    (HEAD + 'MakeNamedMedium "m" "string type" "rgbgrid" "rgb Le" [1 1 1]', 3, 'needs "sigma_a" and/or', SceneError),
    (HEAD + 'MakeNamedMedium "m" "string type" "rgbgrid" "rgb sigma_s" [1 1 1]\n "rgb Le" [1 1 1]', 4,
     'needs "sigma_a"', SceneError),
    (HEAD + 'MakeNamedMedium "m" "string type" "nanovdb"', 3, '"filename" is required', SceneError),
    (HEAD + 'MakeNamedMedium "m" "string type" "nanovdb"\n "string filename" "nope.nvdb"', 4, "no file", SceneError),
    (HEAD + 'MediumInterface "nope"\nShape "sphere"', 3, 'no medium named "nope"', SceneError),
])
def test_errors_name_file_and_line(tmp_path, text, line, match, kind):
    error_at(tmp_path, text, line, match, kind=kind)


def test_grid_over_the_memory_budget_is_refused_before_allocation():
    """A grid declared 4096^3 is refused from its dimensions: its 256 values are never reshaped."""
    loc = Location("big.pbrt", 7)
    params = ParamSet()
    for name, typ, vals in (("nx", "integer", [4096]), ("ny", "integer", [4096]), ("nz", "integer", [4096]),
                            ("density", "float", [1.0] * 256)):
        params.add(Param(typ, name, vals, loc))
    with pytest.raises(SceneError, match=r"big.pbrt:7.*4096x4096x4096 grid needs about 768.0 GiB"):
        read_medium("uniformgrid", "big", params, np.eye(4), loc, lambda *a: None, memory_limit=2**30)


def test_nan_density_is_refused_with_its_location():
    """The tokenizer reads no NaN, but a grid can arrive through the API's ParamSet."""
    loc = Location("grid.pbrt", 3)
    params = ParamSet()
    params.add(Param("float", "density", [1.0, float("nan")], loc))
    params.add(Param("integer", "nx", [2], loc))
    with pytest.raises(SceneError, match=r"grid.pbrt:3.*NaN"):
        read_medium("uniformgrid", "g", params, np.eye(4), loc, lambda *a: None)


def test_nanovdb_file_ships_to_cluster_workers_and_counts_in_the_fingerprint(tmp_path):
    """A worker without the scene's folder reads the shipped copy; editing the file changes the
    scene's fingerprint (a checkpoint of the old grid is not resumed into the new one)."""
    from renderer.cluster.shipping import localised, scene_files
    from renderer.io.fingerprint import scene_fingerprint

    (tmp_path / "grid.nvdb").write_bytes(b"NanoVDB0 stand-in bytes")
    s = load(tmp_path, HEAD + 'MakeNamedMedium "v" "string type" "nanovdb" "string filename" "grid.nvdb"\n')
    files = scene_files(s)
    assert list(files.values()) == [b"NanoVDB0 stand-in bytes"]
    moved, names = localised(s, files, tmp_path / "worker")
    assert moved.media[0].filename != s.media[0].filename
    assert moved.media[0].filename.read_bytes() == b"NanoVDB0 stand-in bytes"
    before = scene_fingerprint(s)
    (tmp_path / "grid.nvdb").write_bytes(b"NanoVDB0 other bytes")
    assert scene_fingerprint(s) != before


def test_mirrored_instances_keep_their_medium_interface(tmp_path):
    """An instance whose transform mirrors uses copies of the object's shapes: they keep its media."""
    s = load(tmp_path, HEAD + 'ObjectBegin "blob"\nMediumInterface "ink" ""\nMaterial "interface"\nShape "sphere"\n'
                              'ObjectEnd\nObjectInstance "blob"\nScale -1 1 1\nObjectInstance "blob"\n'
                              'MakeNamedMedium "ink" "string type" "homogeneous"\n')
    assert len(s.shapes) == 2
    assert all((sh.media.inside, sh.media.outside) == (0, -1) for sh in s.shapes)
