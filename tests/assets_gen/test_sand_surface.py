"""The sand surface (near-field ripples as geometry, props put down on it, the buried shell's
imprint): a small dune field, a small ripple map and a camera close above the sand."""
from __future__ import annotations

import hashlib
from pathlib import Path

import numpy as np
import pytest
import trimesh

from assets_gen.cli import main
from assets_gen.terrain.heightfield import read_heightfield
from assets_gen.terrain.near_field import RippleMap, dune_height
from renderer.geometry.raycast import cast_rays

CAMERA = """LookAt -1 0.14 0   -6 -0.12 0.05   0 1 0
Camera "perspective" "float fov" [40]
Film "rgb" "integer xresolution" [270] "integer yresolution" [480]
WorldBegin
"""
WAVELENGTH, HEIGHT = 0.12, 0.005


def run(*argv) -> int:
    return main([str(a) for a in argv])


def digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


@pytest.fixture(scope="module")
def built(tmp_path_factory) -> Path:
    """Dunes (flat interdune in front of the camera: crests at x = 4 + 10k m), ripples as a map,
    the near field, a box rested, a box wedged at a tilt and a shell-like ellipsoid buried with its
    imprint."""
    root = tmp_path_factory.mktemp("sand")
    assert run("dunes", "--size-x", 12, "--size-z", 8, "--spacing", 0.1, "--dune-height", 0.5,
               "--dune-wavelength", 10, "--crest-x", 4, "--seed", 0, "--out", root / "dunes", "--no-preview") == 0
    assert run("ripples", "--dunes", root / "dunes" / "dunes_height.exr", "--coverage", 1.0, "--defect-density", 0,
               "--seed", 1, "--out", root / "ripples", "--no-preview") == 0
    (root / "cam.pbrt").write_text(CAMERA)
    assert run("near-field", "--dunes", root / "dunes" / "dunes_height.exr", "--ripples",
               root / "ripples" / "ripples_displacement.exr", "--scene", root / "cam.pbrt", "--pixels-per-edge", 1.0,
               "--max-distance", 1.0, "--taper", 0.3, "--out", root / "sand") == 0
    box = trimesh.creation.box((0.05, 0.01, 0.12))
    box.export(root / "box.ply")
    shell = trimesh.creation.icosphere(3, radius=1.0)
    shell.apply_scale((0.03, 0.015, 0.02))
    shell.export(root / "shell.ply")
    sand = root / "sand" / "sand.ply"
    assert run("placement", "--surface", sand, "--mesh", root / "shell.ply", "--mode", "bury", "--depth", 0.4,
               "--position", -1.35, 0.02, "--yaw-deg", 30, "--out", root / "shell_pose") == 0
    assert run("imprint", "--surface", sand, "--mesh", root / "shell.ply", "--placement",
               root / "shell_pose" / "placement.npz", "--out", root / "imprint") == 0
    assert run("placement", "--surface", root / "imprint" / "sand.ply", "--mesh", root / "box.ply", "--mode", "rest",
               "--position", -1.5, -0.05, "--yaw-deg", 20, "--tilt-deg", 10, 5, "--out", root / "box_pose") == 0
    assert run("placement", "--surface", root / "imprint" / "sand.ply", "--mesh", root / "box.ply", "--mode", "wedge",
               "--depth", 0.25, "--position", -1.6, 0.1, "--yaw-deg", 40, "--tilt-deg", 35, 0,
               "--out", root / "box_wedge") == 0
    return root


def load(path: Path) -> tuple[np.ndarray, np.ndarray]:
    m = trimesh.load(path, process=False, force="mesh")
    return np.asarray(m.vertices, dtype=np.float64), np.asarray(m.faces)


def placed(root: Path, mesh: str, pose: str) -> tuple[np.ndarray, np.ndarray]:
    v, f = load(root / mesh)
    m = np.load(root / pose / "placement.npz")["transform"]
    return v @ m[:3, :3].T + m[:3, 3], f


def test_deterministic(built, tmp_path):
    root = built
    assert run("near-field", "--dunes", root / "dunes" / "dunes_height.exr", "--ripples",
               root / "ripples" / "ripples_displacement.exr", "--scene", root / "cam.pbrt", "--pixels-per-edge", 1.0,
               "--max-distance", 1.0, "--taper", 0.3, "--out", tmp_path / "sand") == 0
    for name in ("sand.ply", "bump_weight.exr"):
        assert digest(tmp_path / "sand" / name) == digest(root / "sand" / name)
    assert run("placement", "--surface", root / "imprint" / "sand.ply", "--mesh", root / "box.ply", "--mode", "rest",
               "--position", -1.5, -0.05, "--yaw-deg", 20, "--tilt-deg", 10, 5, "--out", tmp_path / "box") == 0
    assert (tmp_path / "box" / "placement.pbrt").read_text() == (root / "box_pose" / "placement.pbrt").read_text()


def test_one_sheet_without_cracks_or_overlaps(built):
    """Every edge inside the field is shared by exactly two triangles (no crack, no T-junction),
    all triangles face up, and their (x, z) areas add up to the field's: nothing overlaps."""
    v, f = load(built / "sand" / "sand.ply")
    field = read_heightfield(built / "dunes" / "dunes_height.exr")
    edges = np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), axis=1)
    uniq, count = np.unique(edges, axis=0, return_counts=True)
    assert count.max() == 2
    border = v[uniq[count == 1].ravel()]
    on_border = (np.isclose(border[:, 0], field.x[0]) | np.isclose(border[:, 0], field.x[-1])
                 | np.isclose(border[:, 2], field.z[0]) | np.isclose(border[:, 2], field.z[-1]))
    assert on_border.all()
    e1, e2 = v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]
    up = np.cross(e1, e2)[:, 1]
    assert (up > 0).all()
    area = (field.x[-1] - field.x[0]) * (field.z[-1] - field.z[0])
    assert 0.5 * up.sum() == pytest.approx(area, rel=1e-6)
    assert len(v) == len(np.unique(v[:, [0, 2]].round(9), axis=0))          # no duplicated vertex


def test_seam_heights_are_the_dunes_and_far_field_untouched(built):
    v, _ = load(built / "sand" / "sand.ply")
    field = read_heightfield(built / "dunes" / "dunes_height.exr")
    meta = __import__("json").loads((built / "sand" / "near-field.json").read_text())["params"]
    a0, a1, b0, b1 = meta["near_rect"]
    outside = (v[:, 0] <= a0) | (v[:, 0] >= a1) | (v[:, 2] <= b0) | (v[:, 2] >= b1)
    assert np.abs(v[outside, 1] - dune_height(field, v[outside, 0], v[outside, 2])).max() < 1e-6
    inside = ~outside
    assert inside.sum() > outside.sum()                   # the near field holds most vertices


def test_near_field_edges_are_about_the_target_pixels(built):
    """Edges of visible near-field triangles project to ~1 pixel (the detail asked for)."""
    from assets_gen.core.camera import PinholeCamera

    cam = PinholeCamera.from_scene(built / "cam.pbrt")
    v, f = load(built / "sand" / "sand.ply")
    xy, depth = cam.to_raster(v)
    tri = f[cam.in_frustum(v)[f].all(axis=1) & (depth[f] < 0.9).all(axis=1)]
    assert len(tri) > 10000
    lengths = np.linalg.norm(xy[tri] - xy[np.roll(tri, 1, axis=1)], axis=2)
    assert 0.7 < np.median(lengths) < 1.5                # the rows' and columns' steps, and diagonals
    assert np.percentile(lengths.max(axis=1), 99) < 3.0


def test_displaced_ripples_match_the_generator(built):
    """Along the wind through the fully displaced part, the mesh's heights minus the dunes have
    their spectral peak at the ripple wavelength and a trough-to-crest height near the generator's."""
    v, f = load(built / "sand" / "sand.ply")
    field = read_heightfield(built / "dunes" / "dunes_height.exr")
    x = np.arange(-1.9, -1.3, 0.002)
    rows = []
    for z in (-0.1, 0.0, 0.1):
        top = np.column_stack([x, np.full_like(x, 5.0), np.full_like(x, z)])
        t = cast_rays(v, f, top, np.tile([0.0, -1.0, 0.0], (len(x), 1)))
        rows.append(5.0 - t - dune_height(field, x, np.full_like(x, z)))
    r = np.array(rows)
    spectrum = np.abs(np.fft.rfft(r - r.mean(axis=1, keepdims=True), n=8192, axis=1)).mean(axis=0)
    freq = np.fft.rfftfreq(8192, 0.002)
    peak = 1.0 / freq[np.argmax(spectrum[1:]) + 1]
    assert peak == pytest.approx(WAVELENGTH, rel=0.1)
    span = np.percentile(r, 98, axis=1) - np.percentile(r, 2, axis=1)
    assert np.median(span) == pytest.approx(HEIGHT, rel=0.25)
    ripple = RippleMap.read(built / "ripples" / "ripples_displacement.exr")
    full = (v[:, 0] > -1.95) & (v[:, 0] < -1.35) & (np.abs(v[:, 2]) < 0.2)   # weight 1: the map itself
    assert full.sum() > 1000
    offset = v[full, 1] - dune_height(field, v[full, 0], v[full, 2])
    assert np.abs(offset - ripple(v[full, 0], v[full, 2])).max() < 1e-6


def mesh_crossings(av: np.ndarray, af: np.ndarray, bv: np.ndarray, bf: np.ndarray) -> int:
    """How many edges of mesh A pass through a triangle of mesh B (ray casts along each edge)."""
    edges = np.unique(np.sort(np.concatenate([af[:, [0, 1]], af[:, [1, 2]], af[:, [2, 0]]]), axis=1), axis=0)
    p, q = av[edges[:, 0]], av[edges[:, 1]]
    d = q - p
    length = np.linalg.norm(d, axis=1)
    t = cast_rays(bv, bf, p, d / length[:, None])
    return int((t < length).sum())


def local(v: np.ndarray, f: np.ndarray, around: np.ndarray, reach: float) -> np.ndarray:
    near = np.all(np.abs(v[:, [0, 2]] - around[[0, 2]]) < reach, axis=1)
    return f[near[f].all(axis=1)]


def test_rest_pose_has_three_contacts_and_no_penetration(built):
    import json

    meta = json.loads((built / "box_pose" / "placement.json").read_text())["params"]
    assert meta["contacts"] >= 3 and meta["min_gap_m"] >= 0
    bv, bf = placed(built, "box.ply", "box_pose")
    sv, sf = load(built / "imprint" / "sand.ply")
    top = np.column_stack([bv[:, 0], np.full(len(bv), 5.0), bv[:, 2]])
    ground = 5.0 - cast_rays(sv, sf, top, np.tile([0.0, -1.0, 0.0], (len(bv), 1)))
    gap = bv[:, 1] - ground
    origins = sv[np.unique(local(sv, sf, bv.mean(0), 0.1))] - [0.0, 1.0, 0.0]
    t = cast_rays(bv, bf, origins, np.tile([0.0, 1.0, 0.0], (len(origins), 1)))
    clearance = t[np.isfinite(t)] - 1.0                          # prop's underside above sand vertices
    assert gap.min() > 0 and clearance.min() > 0
    touching = np.concatenate([bv[gap < 1e-4], origins[np.isfinite(t)][clearance < 1e-4]])
    assert len(touching) >= 3
    assert np.ptp(touching[:, 0]) > 0.02 or np.ptp(touching[:, 2]) > 0.02     # spread out, not one corner
    patch = local(sv, sf, bv.mean(0), 0.1)
    assert mesh_crossings(sv, patch, bv, bf) == 0 and mesh_crossings(bv, bf, sv, patch) == 0


def test_wedged_prop_keeps_its_tilt_and_sinks_its_low_edge(built):
    """``wedge`` keeps the requested yaw and tilts exactly, puts the centre of mass over the given
    (x, z), and sinks the lowest corner a quarter of the prop's height below the sand under it."""
    from assets_gen.terrain.placement import centre_of_mass, rotation

    m = np.load(built / "box_wedge" / "placement.npz")["transform"]
    assert np.allclose(m[:3, :3], rotation("y", 40) @ rotation("x", 35) @ rotation("z", 0), atol=1e-12)
    v, f = load(built / "box.ply")
    com = m[:3, :3] @ centre_of_mass(v, f) + m[:3, 3]
    assert com[[0, 2]] == pytest.approx([-1.6, 0.1], abs=1e-9)
    bv, _ = placed(built, "box.ply", "box_wedge")
    sv, sf = load(built / "imprint" / "sand.ply")
    top = np.column_stack([bv[:, 0], np.full(len(bv), 5.0), bv[:, 2]])
    gap = bv[:, 1] - (5.0 - cast_rays(sv, sf, top, np.tile([0.0, -1.0, 0.0], (len(bv), 1))))
    sunk = 0.25 * np.ptp(bv[:, 1])
    assert -sunk - 1e-6 <= gap.min() <= -sunk + 5e-4
    assert (gap > 0).sum() >= len(bv) // 2                                   # the rest stands out of the sand


def test_buried_shell_sits_in_its_imprint(built):
    """The shell is sunk below the undisturbed sand, yet no sand edge crosses it nor it the sand;
    sand under it lies below it, and the rim holds the dent's sand."""
    sv0, sf = load(built / "sand" / "sand.ply")
    sv, _ = load(built / "imprint" / "sand.ply")
    hv, hf = placed(built, "shell.ply", "shell_pose")
    below = np.column_stack([hv[:, 0], np.full(len(hv), 5.0), hv[:, 2]])
    undisturbed = 5.0 - cast_rays(sv0, sf, below, np.tile([0.0, -1.0, 0.0], (len(hv), 1)))
    assert (hv[:, 1] < undisturbed).mean() > 0.2                              # really buried
    patch = local(sv, sf, hv.mean(0), 0.15)
    assert mesh_crossings(sv, patch, hv, hf) == 0 and mesh_crossings(hv, hf, sv, patch) == 0
    under = np.unique(patch)
    origin = sv[under] - [0.0, 1e-7, 0.0]
    up = cast_rays(hv, hf, origin, np.tile([0.0, 1.0, 0.0], (len(under), 1)))
    down = cast_rays(hv, hf, sv[under] + [0.0, 1e-7, 0.0], np.tile([0.0, -1.0, 0.0], (len(under), 1)))
    covered = np.isfinite(up)
    assert covered.sum() > 100 and not np.isfinite(down[covered]).any()     # shell above, never below
    from assets_gen.terrain.imprint import vertex_areas

    change = (sv[:, 1] - sv0[:, 1]) * vertex_areas(sv0, sf)
    assert change[change < 0].sum() < -1e-7
    assert change.sum() == pytest.approx(0.0, abs=0.02 * -change[change < 0].sum())
