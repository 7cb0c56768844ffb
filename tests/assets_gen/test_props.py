"""Prop and sky generators (assets_gen/props, assets_gen/sky.py): determinism, mesh validity
(closed, outward, no degenerate triangles, UVs in [0, 1], real sizes), the sky's sun position,
equal-area mapping and daylight level, parameter errors."""
from __future__ import annotations

import json

import numpy as np
import pytest
import trimesh
from plyfile import PlyData

from assets_gen import sky
from assets_gen.cli import main
from assets_gen.core import GeneratorError
from assets_gen.props import palm, seashell, sunglasses, umbrella
from renderer.io.images import read_exr

SMALL = {
    "seashell": dict(per_turn=16, around=16),
    "sunglasses": {},
    "umbrella": {},
    "palm": dict(fronds=4, leaflets=12, coconuts=2),
    "sky": dict(resolution=32),
}
GENERATORS = {m.GENERATOR.name: m.GENERATOR for m in (seashell, sunglasses, umbrella, palm, sky)}


def build(name: str, out, seed: int = 0, **values) -> list[str]:
    gen = GENERATORS[name]
    return gen.build(gen.params(**values), seed, out)


def load_ply(path):
    v = PlyData.read(str(path))["vertex"]
    f = np.stack(PlyData.read(str(path))["face"]["vertex_indices"]).astype(np.int64)
    pos = np.stack([v["x"], v["y"], v["z"]], 1).astype(np.float64)
    nrm = np.stack([v["nx"], v["ny"], v["nz"]], 1).astype(np.float64)
    uv = np.stack([v["u"], v["v"]], 1).astype(np.float64)
    return pos, f, nrm, uv


def check_mesh(path, closed: bool = True, extent: tuple[float, float] | None = None) -> trimesh.Trimesh:
    """Normals agree with the winding, no degenerate triangles, UVs in [0, 1]; closed meshes are
    watertight (after welding UV seams) with positive volume."""
    pos, f, nrm, uv = load_ply(path)
    assert np.all(np.isfinite(pos)) and np.all(np.isfinite(nrm))
    assert uv.min() >= 0.0 and uv.max() <= 1.0
    e1, e2 = pos[f[:, 1]] - pos[f[:, 0]], pos[f[:, 2]] - pos[f[:, 0]]
    fn = np.cross(e1, e2)
    area = 0.5 * np.linalg.norm(fn, axis=1)
    longest = np.max([np.linalg.norm(e1, axis=1), np.linalg.norm(e2, axis=1),
                      np.linalg.norm(e2 - e1, axis=1)], axis=0)
    assert np.all(area > 1e-4 * longest ** 2), "degenerate (collapsed or needle) triangles"
    assert np.all(np.einsum("ij,ij->i", fn, nrm[f].sum(1)) > 0), "vertex normals disagree with winding"
    mesh = trimesh.Trimesh(pos, f, process=True)
    if closed:
        assert mesh.is_watertight and mesh.is_winding_consistent
        assert mesh.volume > 0
    if extent is not None:
        size = np.ptp(pos, axis=0).max()
        assert extent[0] <= size <= extent[1], size
    return mesh


@pytest.mark.parametrize("name", sorted(GENERATORS))
def test_deterministic_with_manifest(tmp_path, name):
    a = build(name, tmp_path / "a", 7, **SMALL[name])
    b = build(name, tmp_path / "b", 7, **SMALL[name])
    for pa, pb in zip(a, b):
        assert open(pa, "rb").read() == open(pb, "rb").read(), pa
    manifest = json.loads(open(a[-1]).read())
    assert manifest["generator"] == name and manifest["seed"] == 7
    assert sorted(manifest["outputs"]) == sorted(p.split("/")[-1] for p in a[:-1])
    assert {k: manifest["params"][k] for k in SMALL[name]} == SMALL[name]


def test_manifest_records_derived_facts(tmp_path):
    """Writers add what they computed (here the lens's front radius, the shell model) to the manifest."""
    glasses = json.loads(open(build("sunglasses", tmp_path / "g", base_curve=4.0)[-1]).read())
    assert glasses["params"]["front_radius_m"] == pytest.approx(0.53 / 4.0)
    assert glasses["params"]["base_curve"] == 4.0
    shell = json.loads(open(build("seashell", tmp_path / "s", preset="nautilus", **SMALL["seashell"])[-1]).read())
    assert shell["params"]["model"]["alpha"] == seashell.PRESETS["nautilus"].alpha


@pytest.mark.parametrize("preset", [*seashell.PRESETS, seashell.SCALLOP])
def test_seashell_solid(tmp_path, preset):
    ply, _ = build("seashell", tmp_path, preset=preset, length=0.06, per_turn=20, around=16)
    mesh = check_mesh(ply, extent=(0.0599, 0.0601))
    assert mesh.bounds[0][1] == pytest.approx(0.0, abs=1e-6)      # rests on the sand


def test_seashell_uv_follows_growth():
    """u grows with the spiral: the lip (u = 1) has the largest aperture, the apex (u = 0) the smallest."""
    m = seashell.gastropod_mesh(seashell.PRESETS["turritella"], 0.08, 16, 16)
    outer = slice(0, 17 * (int(16 * 12) + 1))                         # first part: the outer grid
    u, pos = m.uvs[outer, 0], m.vertices[outer]
    lip, apex = np.ptp(pos[u == 1.0], axis=0).max(), np.ptp(pos[u == 0.0], axis=0).max()
    assert lip > 3 * apex


def test_sunglasses(tmp_path):
    left, right, frame, _ = build("sunglasses", tmp_path)
    for lens in (left, right):
        check_mesh(lens, extent=(0.054, 0.056))
        pos, f, _, uv = load_ply(lens)
        centre = np.argmin(np.linalg.norm(uv - 0.5, axis=1))
        assert np.allclose(uv[centre], 0.5)
        # the outline spans the unit square: it touches the inscribed superellipse
        assert np.ptp(uv[:, 0]) == pytest.approx(1.0) and np.ptp(uv[:, 1]) == pytest.approx(1.0)
    check_mesh(frame, extent=(0.13, 0.16))
    l_pos = load_ply(left)[0]
    r_pos = load_ply(right)[0]
    assert l_pos[:, 0].min() > 0 > r_pos[:, 0].max()                # the bridge's gap between lenses


def test_lens_on_base_curve_sphere():
    lens, _ = sunglasses.lens_mesh(0.0275, 0.0225, 3.0, 0.53 / 6, 0.002)
    front = lens.vertices[:97 + 9 * 97]                              # centre + rings (with seams)
    r = np.linalg.norm(front - [0, 0, -0.53 / 6], axis=1)
    assert np.allclose(r, 0.53 / 6, atol=1e-9)


def test_umbrella(tmp_path):
    canopy, frame, _ = build("umbrella", tmp_path, tilt_deg=15.0, segments=6)
    check_mesh(canopy, extent=(1.9, 2.2))
    mesh = check_mesh(frame)
    assert mesh.bounds[0][1] == pytest.approx(-0.35, abs=1e-3)     # pole foot in the sand
    pos, f, _, uv = load_ply(canopy)
    # u around the pole: each of the 6 panels spans 1/6 of u
    top = pos[:, 1] > np.percentile(pos[:, 1], 50)
    assert np.ptp(uv[top, 0]) == pytest.approx(1.0)


def test_palm_trees_differ(tmp_path):
    paths = build("palm", tmp_path, 3, count=2, **SMALL["palm"])
    names = [p.split("/")[-1] for p in paths]
    assert names[:-1] == [f"palm{i}_{k}.ply" for i in range(2) for k in ("trunk", "fronds", "coconuts")]
    trunks = [check_mesh(tmp_path / f"palm{i}_trunk.ply", extent=(5.0, 9.5)) for i in range(2)]
    check_mesh(tmp_path / "palm0_coconuts.ply")
    check_mesh(tmp_path / "palm0_fronds.ply", closed=False)          # leaflet cards are open
    assert not np.allclose(trunks[0].bounds, trunks[1].bounds)


def test_equal_area_pixels_are_where_the_renderer_looks_them_up():
    """The sky's equal-area pixel centres come from the renderer's own map: mapped back they land
    on the centres of their pixels, and they cover the sphere uniformly (equal solid angles)."""
    from renderer.sampling.equal_area import sphere_to_square

    n = 64
    dirs = sky.equal_area_directions(n)
    assert dirs.dtype == np.float64 and np.allclose(np.linalg.norm(dirs, axis=-1), 1.0, atol=1e-6)
    c = (np.arange(n) + 0.5) / n
    assert np.allclose(sphere_to_square(dirs), np.stack(np.meshgrid(c, c, indexing="xy"), -1), atol=1e-6)
    # equal solid angles: z of uniform directions is uniform on [-1, 1]
    for z in (-0.5, 0.0, 0.5, 0.9):
        assert np.mean(dirs[..., 2] > z) == pytest.approx((1 - z) / 2, abs=2.0 / n)


@pytest.mark.parametrize("elevation,azimuth", [(20.0, 40.0), (55.0, 250.0)])
def test_sky_peak_at_sun(tmp_path, elevation, azimuth):
    build("sky", tmp_path, elevation_deg=elevation, azimuth_deg=azimuth, turbidity=3.0, resolution=64)
    sun = sky.sun_direction(elevation, azimuth)
    manifest = json.loads((tmp_path / "sky.json").read_text())
    assert np.allclose(manifest["params"]["sun"]["direction_light_frame"], sun)
    for name, dirs in (("sky_latlong.exr", sky.latlong_directions(64)),
                       ("sky_equalarea.exr", sky.equal_area_directions(64))):
        ch, _ = read_exr(tmp_path / name)
        lum = 0.2126 * ch["R"] + 0.7152 * ch["G"] + 0.0722 * ch["B"]
        peak = dirs[np.unravel_index(np.argmax(lum), lum.shape)]
        assert np.degrees(np.arccos(np.clip(peak @ sun, -1, 1))) < 5.0, name


def test_sky_daylight_levels():
    """Diffuse horizontal illuminance against the IES clear-sky formula E = 0.8 + 15.5 √(sin h) klx
    (IES Lighting Handbook; Preetham runs about 2x brighter, so accept 0.7x..2.7x), and the direct
    normal illuminance against clear-sky measurements (70..110 klx at h >= 30 deg, T = 2.5..3)."""
    for h in (15.0, 30.0, 60.0):
        sun = sky.sun_direction(h, 0.0)
        dirs = sky.equal_area_directions(96)
        e = sky.diffuse_horizontal_klx(sky.sky_radiance(dirs, sun, 3.0), dirs,
                                       np.full(dirs.shape[:2], 4 * np.pi / 96 ** 2))
        ref = 0.8 + 15.5 * np.sqrt(np.sin(np.radians(h)))
        assert 0.7 * ref < e < 2.7 * ref, (h, e, ref)
        if h >= 30:
            assert 70_000 < sky.sun_light(sun, 2.5)["normal_illuminance_lux"] < 110_000


def test_sky_below_horizon_is_ground(tmp_path):
    build("sky", tmp_path, resolution=16, layout="latlong", ground_albedo=0.3)
    ch, _ = read_exr(tmp_path / "sky_latlong.exr")
    assert ch["R"].shape == (16, 32)
    lower = ch["G"][8:]
    assert np.all(lower == lower[0, 0]) and lower[0, 0] > 0


@pytest.mark.parametrize("argv", [
    ["seashell", "--preset", "octopus"],
    ["seashell", "--length", "-1"],
    ["sunglasses", "--base-curve", "40"],
    ["umbrella", "--segments", "2"],
    ["palm", "--fronds", "0"],
    ["sky", "--elevation-deg", "-5"],
    ["sky", "--turbidity", "50"],
])
def test_bad_params_exit_2(tmp_path, argv, capsys):
    out = tmp_path / "out"
    try:
        code = main([*argv, "--out", str(out)])
    except SystemExit as e:                 # argparse's own check (a choice) exits with 2 as well
        code = e.code
    assert code == 2
    assert "error" in capsys.readouterr().err
    assert not out.exists()


def test_bad_params_in_python_raise_and_leave_nothing(tmp_path):
    with pytest.raises(GeneratorError, match="segments must be 3..24"):
        build("umbrella", tmp_path / "u", segments=2)
    with pytest.raises(GeneratorError, match="seed must be a non-negative integer"):
        build("palm", tmp_path / "p", -1)
    assert not (tmp_path / "u").exists() and not (tmp_path / "p").exists()
