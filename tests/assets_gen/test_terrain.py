"""Terrain generators (assets_gen/terrain) and maps (assets_gen/maps): dunes, ripples, grains,
lens and shell maps. Small sizes so the file runs in well under a minute."""
from __future__ import annotations

import hashlib
import json
from pathlib import Path

import numpy as np
import pytest
import trimesh
from scipy import stats
from scipy.spatial import cKDTree

from assets_gen.cli import main
from assets_gen.core import GeneratorError
from assets_gen.core.camera import PinholeCamera
from assets_gen.core.meshing import grid_faces
from assets_gen.terrain.heightfield import heightfield_faces, triangle_slopes
from assets_gen.terrain.grains import GrainParams, scene_camera
from renderer.io.images import read_exr

DUNES = ["--size-x", "8", "--size-z", "6", "--spacing", "0.05", "--dune-height", "0.6",
         "--dune-wavelength", "4", "--crest-wander", "0.6", "--wander-size", "3"]


def run(*argv: str) -> int:
    return main([str(a) for a in argv])


def digests(folder: Path) -> dict[str, str]:
    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in sorted(folder.iterdir())}


@pytest.fixture(scope="module")
def dunes(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("dunes")
    assert run("dunes", *DUNES, "--seed", 3, "--out", out) == 0
    return out


@pytest.fixture(scope="module")
def grains(tmp_path_factory, dunes) -> Path:
    out = tmp_path_factory.mktemp("grains")
    assert run("grains", "--surface", dunes / "dunes.ply", "--count", 4000, "--seed", 5, "--out", out) == 0
    return out


def test_same_seed_same_bytes(tmp_path, dunes, grains):
    assert run("dunes", *DUNES, "--seed", 3, "--out", tmp_path / "d") == 0
    assert digests(tmp_path / "d") == digests(dunes)
    assert run("grains", "--surface", dunes / "dunes.ply", "--count", 4000, "--seed", 5, "--out", tmp_path / "g") == 0
    assert digests(tmp_path / "g") == digests(grains)
    for cmd in ("lens-thickness", "shell-height", "shell-bump"):
        a, b = tmp_path / f"{cmd}1", tmp_path / f"{cmd}2"
        assert run(cmd, "--seed", 1, "--out", a) == 0 and run(cmd, "--seed", 1, "--out", b) == 0
        assert digests(a) == digests(b)
    assert run("dunes", *DUNES, "--seed", 4, "--out", tmp_path / "d4") == 0
    assert digests(tmp_path / "d4")["dunes.ply"] != digests(dunes)["dunes.ply"]
    manifest = json.loads((dunes / "dunes.json").read_text())
    assert manifest["seed"] == 3 and manifest["params"]["spacing"] == 0.05 and "version" in manifest


def test_dune_slopes_never_exceed_34_degrees(dunes):
    mesh = trimesh.load(dunes / "dunes.ply", process=False)
    slope = np.degrees(np.arccos(np.clip(mesh.face_normals[:, 1], -1, 1)))
    assert slope.max() <= 34.0 + 1e-3
    assert np.percentile(slope, 99) > 25.0          # slip faces are there, near the angle of repose
    assert len(mesh.vertex_normals) == len(mesh.vertices) and "uv" in dir(mesh.visual)


def _ripple_stats(disp: np.ndarray, dx: float) -> tuple[float, float]:
    """(mean crest spacing, median trough-to-crest height) of a displacement grid, rows along x."""
    spacings, heights = [], []
    for row in disp:
        up = np.flatnonzero((row[:-1] < 0) & (row[1:] >= 0))
        if len(up) > 1:
            spacings.append((up[-1] - up[0]) * dx / (len(up) - 1))
        heights += [np.ptp(row[a:b + 1]) for a, b in zip(up[:-1], up[1:])]
    return float(np.mean(spacings)), float(np.median(heights))


def test_ripple_wavelength_and_height_from_the_mesh(tmp_path):
    assert run("dunes", "--size-x", 1.2, "--size-z", 1.0, "--spacing", 0.004, "--dune-height", 0,
               "--out", tmp_path / "flat") == 0
    assert run("ripples", "--dunes", tmp_path / "flat" / "dunes_height.exr", "--wavelength", 0.13,
               "--height", 0.006, "--coverage", 1.0, "--defect-density", 4, "--out", tmp_path / "r") == 0
    flat = trimesh.load(tmp_path / "flat" / "dunes.ply", process=False).vertices
    rippled = trimesh.load(tmp_path / "r" / "dunes_rippled.ply", process=False).vertices
    disp = (rippled[:, 1] - flat[:, 1]).reshape(251, 301)
    wavelength, height = _ripple_stats(disp, 0.004)
    assert wavelength == pytest.approx(0.13, rel=0.10)
    assert height == pytest.approx(0.006, rel=0.10)


def test_coarse_dunes_get_a_ripple_map(tmp_path, dunes):
    assert run("ripples", "--dunes", dunes / "dunes_height.exr", "--max-map-size", 256, "--out", tmp_path) == 0
    chans, header = read_exr(tmp_path / "ripples_displacement.exr")
    assert chans["Y"].shape == (256, 256) and header["units"] == "m"
    assert 0 < np.abs(chans["Y"]).max() <= 0.005 and (tmp_path / "ripples_displacement.png").is_file()


def test_grains_in_frustum_visible_apart_and_lognormal(dunes, grains):
    from renderer.geometry.raycast import cast_rays

    surface = trimesh.load(dunes / "dunes.ply", process=False)
    cam = scene_camera(GrainParams(surface=str(dunes / "dunes.ply")), surface.vertices, surface.faces)
    data = np.load(grains / "grains.npz")
    xf, d, kind = data["transforms"], data["scales"].astype(np.float64), data["kind"]
    assert xf.shape == (4000, 4, 4) and xf.dtype == np.float32
    centres = xf[:, :3, 3].astype(np.float64)
    assert np.allclose(np.linalg.norm(xf[:, :3, :3], axis=1), d[:, None], rtol=1e-4)

    assert cam.in_frustum(centres).all()
    eye = cam.position
    dist = np.linalg.norm(centres - eye, axis=1)
    hit = cast_rays(surface.vertices, surface.faces, np.tile(eye, (len(centres), 1)),
                    (centres - eye) / dist[:, None])
    assert (hit >= dist - d / 2).all()
    assert (hit < np.inf).any()                     # the rays do meet the sand (just not before a grain)

    pairs = cKDTree(centres).query_pairs(d.max(), output_type="ndarray")
    gap = np.linalg.norm(centres[pairs[:, 0]] - centres[pairs[:, 1]], axis=1)
    assert (gap >= (d[pairs[:, 0]] + d[pairs[:, 1]]) / 2).all()

    assert stats.kstest(d, "lognorm", args=(0.25, 0, 0.35e-3)).pvalue > 0.01
    assert set(np.unique(kind)) == {0, 1, 2, 3}
    per_class = [np.load(grains / f"grains_{c}.npz") for c in ("quartz", "feldspar", "heavy", "shell")]
    assert sum(len(c["transforms"]) for c in per_class) == 4000
    for k, c in enumerate(per_class):
        assert np.array_equal(c["transforms"], xf[kind == k])
    for c in ("quartz", "feldspar", "heavy", "shell"):
        m = trimesh.load(grains / f"grain_{c}.ply", process=False)
        assert np.linalg.norm(m.vertices, axis=1).max() == pytest.approx(0.5, rel=1e-5)
        assert m.is_watertight


def test_pinhole_camera_matches_pbrt_look_at():
    cam = PinholeCamera.from_look_at((0, 1, 0), (0, 1, 5), (0, 1, 0), 60.0, 200, 100)
    xy, z = cam.to_raster(np.array([[0, 1, 5.0], [0, 2, 5.0]]))
    assert np.allclose(xy[0], [100, 50]) and z[0] == pytest.approx(5.0)
    assert xy[1, 1] < 50                            # up in the world is up in the image (raster y down)
    assert cam.max_depth_for_coverage(1e-3, 1.0) * cam.pixel_pitch == pytest.approx(1e-3 / np.sqrt(4 / np.pi))


@pytest.mark.parametrize("position, target, up, message", [
    ((0, 1, 0), (0, 1, 0), (0, 1, 0), "coincide"),
    ((0, 1, 0), (0, 2, 0), (0, 1, 0), "parallel"),
])
def test_degenerate_camera_is_a_parameter_error(position, target, up, message):
    with pytest.raises(GeneratorError, match=message):
        PinholeCamera.from_look_at(position, target, up, 40.0, 64, 64)


def test_heightfield_triangles_are_the_mesh_grid_in_slope_order():
    """The terrain's triangles are meshing's grid triangles, wound to +y, in the order whose
    slopes :func:`triangle_slopes` returns (first the triangle on the +x side of each diagonal)."""
    nz, nx = 4, 5
    faces = heightfield_faces(nz, nx)
    assert sorted(map(tuple, faces)) == sorted(map(tuple, grid_faces(nz, nx)))
    rng = np.random.default_rng(0)
    y = rng.normal(size=(nz, nx))
    xx, zz = np.meshgrid(np.arange(nx) * 0.5, np.arange(nz) * 0.25)
    verts = np.stack([xx.ravel(), y.ravel(), zz.ravel()], 1)
    a, b, c = (verts[faces[:, k]] for k in range(3))
    n = np.cross(b - a, c - a)
    assert np.all(n[:, 1] > 0)                                     # counter-clockwise seen from +y
    gx, gz = triangle_slopes(y, 0.5, 0.25)
    assert np.allclose(-n[:, 0] / n[:, 1], gx.ravel()) and np.allclose(-n[:, 2] / n[:, 1], gz.ravel())


def test_camera_from_a_scene_file_matches_the_parameters(tmp_path):
    scene = tmp_path / "cam.pbrt"
    scene.write_text('LookAt 0 1 -2  0 0.5 0  0 1 0\nCamera "perspective" "float fov" 35\n'
                     'Film "rgb" "integer xresolution" 320 "integer yresolution" 200\nWorldBegin\n')
    a = PinholeCamera.from_scene(scene)
    b = PinholeCamera.from_look_at((0, 1, -2), (0, 0.5, 0), (0, 1, 0), 35.0, 320, 200)
    assert np.allclose(a.camera_to_world, b.camera_to_world) and (a.fov_deg, a.width, a.height) == (35.0, 320, 200)


def _along_rays(t: np.ndarray, mask: np.ndarray) -> list[np.ndarray]:
    cy, cx = (np.array(t.shape) - 1) / 2
    out = []
    for angle in np.linspace(0, 2 * np.pi, 24, endpoint=False):
        r = np.arange(0, max(t.shape))
        y, x = np.round(cy + r * np.sin(angle)).astype(int), np.round(cx + r * np.cos(angle)).astype(int)
        keep = (y >= 0) & (y < t.shape[0]) & (x >= 0) & (x < t.shape[1])
        y, x = y[keep], x[keep]
        inside = mask[y, x]
        out.append(t[y[inside], x[inside]][: np.argmin(inside) if not inside.all() else None])
    return out


@pytest.mark.parametrize("outline", ["superellipse", "mask"])
def test_lens_thickness_grows_from_centre_to_rim(tmp_path, outline):
    extra = []
    if outline == "mask":
        from PIL import Image

        yy, xx = np.indices((90, 120))
        Image.fromarray((((xx - 59.5) / 55) ** 2 + ((yy - 44.5) / 40) ** 2 < 1).astype(np.uint8) * 255).save(
            tmp_path / "mask.png")
        extra = ["--mask", tmp_path / "mask.png"]
    assert run("lens-thickness", "--resolution", 120, *extra, "--out", tmp_path / "o") == 0
    t = read_exr(tmp_path / "o" / "lens_thickness.exr")[0]["Y"]
    mask = t > 0
    for ray in _along_rays(t, mask):
        assert len(ray) > 10 and (np.diff(ray) >= -1e-3).all()
        assert ray[0] < 310 and ray[-1] > 380
    assert (tmp_path / "o" / "lens_thickness.png").is_file()


def test_a_map_written_a_band_at_a_time_equals_the_whole_map_written_at_once(tmp_path):
    """lens-thickness makes its map a band of rows at a time (a 16384-pixel map took 7.2 GB whole);
    the EXR and the preview are the same bytes as writing the whole map (noise included, 700 rows:
    three bands and a part, a preview step of 2)."""
    from assets_gen.core.output import Banded, write_map
    from assets_gen.maps.lens_thickness import LensThicknessParams, lens_thickness

    rows, shape = lens_thickness(LensThicknessParams(resolution=700, noise_nm=5.0, noise_size_mm=3.0), seed=4)
    (tmp_path / "band").mkdir()
    (tmp_path / "whole").mkdir()
    write_map(tmp_path / "band", "t", Banded(shape, rows), "nm", True)
    write_map(tmp_path / "whole", "t", rows(0, shape[0]), "nm", True)
    for name in ("t.exr", "t.png"):
        assert (tmp_path / "band" / name).read_bytes() == (tmp_path / "whole" / name).read_bytes()
    t = read_exr(tmp_path / "band" / "t.exr")[0]["Y"]
    assert t.shape == shape and t.max() > 400 and (t == 0).any()       # a lens, rim and outside


def test_shell_maps_load_in_metres(tmp_path):
    assert run("shell-height", "--width", 64, "--height", 128, "--out", tmp_path / "h") == 0
    assert run("shell-bump", "--pattern", "concentric", "--ridges", 8, "--width", 64, "--height", 64,
               "--out", tmp_path / "b") == 0
    h = read_exr(tmp_path / "h" / "shell_height.exr")[0]["Y"]
    b = read_exr(tmp_path / "b" / "shell_bump.exr")[0]["Y"]
    assert h.shape == (128, 64) and 0 < h.max() < 2e-3
    assert b.shape == (64, 64) and b.max() == pytest.approx(5e-5, rel=0.05)
    # concentric ridges are growth lines: constant u (image columns), so they vary along u only
    assert np.abs(np.diff(b, axis=0)).mean() < 0.2 * np.abs(np.diff(b, axis=1)).mean()


@pytest.mark.parametrize("argv", [
    ["dunes", "--size-x", "-5"],
    ["dunes", "--repose-angle-deg", "95"],
    ["dunes", "--max-slope-deg", "90"],
    ["ripples", "--dunes", "missing.exr"],
    ["lens-thickness", "--width-mm", "0"],
    ["grains", "--surface", "missing.ply"],
])
def test_bad_parameters_exit_2_and_leave_nothing(tmp_path, argv):
    out = tmp_path / "out"
    assert run(*argv, "--out", out) == 2
    assert not out.exists()


def test_empty_mask_and_impossible_placement_exit_2(tmp_path, dunes):
    from PIL import Image

    Image.fromarray(np.zeros((32, 32), dtype=np.uint8)).save(tmp_path / "empty.png")
    assert run("lens-thickness", "--mask", tmp_path / "empty.png", "--out", tmp_path / "o1") == 2
    assert run("ripples", "--dunes", dunes / "dunes_height.exr", "--height", "0.1", "--out", tmp_path / "o2") == 2
    assert run("grains", "--surface", dunes / "dunes.ply", "--camera-position", 0, 30, -1,
               "--out", tmp_path / "o3") == 2          # too far for a grain to cover a quarter pixel
    assert not any((tmp_path / f"o{i}").exists() for i in (1, 2, 3))
