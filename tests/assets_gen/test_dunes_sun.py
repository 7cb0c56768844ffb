"""Barchanoid dunes measured on their mesh (slip face at the angle of repose, gentle stoss,
meandering crests) and the sun's position from a date against Meeus's worked examples."""
from __future__ import annotations

import hashlib
import json
import math
from datetime import datetime, timezone

import numpy as np
import pytest
import trimesh

from assets_gen.cli import main
from assets_gen.core import GeneratorError
from assets_gen.sky import light_azimuth, sun_direction
from assets_gen.solar_position import sidereal_time_deg, sun_equatorial, sun_position
from renderer.scene.transform import look_at, rotate

BARCHANOID = ["--size-x", "30", "--size-z", "20", "--spacing", "0.15", "--dune-height", "1.6",
              "--dune-wavelength", "22", "--crest-x", "-6", "--crest-wander", "0.6", "--wander-size", "10",
              "--horn-spacing", "6", "--horn-length", "1.5", "--horn-drop", "0.12", "--repose-angle-deg", "32"]


def run(*argv: object) -> int:
    return main([str(a) for a in argv])


@pytest.fixture(scope="module")
def barchanoid(tmp_path_factory):
    out = tmp_path_factory.mktemp("barchanoid")
    assert run("dunes", *BARCHANOID, "--seed", 7, "--out", out) == 0
    return out


def face_slopes(path) -> tuple[np.ndarray, np.ndarray]:
    """(slope in degrees, downwind height gradient dy/dx) of every triangle of a +y-up mesh."""
    mesh = trimesh.load(path, process=False)
    n = mesh.face_normals * np.sign(mesh.face_normals[:, 1:2])
    return np.degrees(np.arccos(np.clip(n[:, 1], -1, 1))), -n[:, 0] / n[:, 1]


def test_barchanoid_dunes_are_deterministic_and_valid(barchanoid, tmp_path):
    assert run("dunes", *BARCHANOID, "--seed", 7, "--out", tmp_path) == 0
    digest = lambda p: hashlib.sha256(p.read_bytes()).hexdigest()    # noqa: E731
    assert digest(tmp_path / "dunes.ply") == digest(barchanoid / "dunes.ply")
    mesh = trimesh.load(barchanoid / "dunes.ply", process=False)
    assert mesh.is_winding_consistent and np.isfinite(mesh.vertices).all()
    assert (mesh.area_faces > 0).all()


def test_slip_face_at_the_angle_of_repose_and_stoss_gentle(barchanoid):
    slope, downwind = face_slopes(barchanoid / "dunes.ply")
    assert slope.max() <= 34.0 + 1e-6
    slip = slope[(downwind < 0) & (slope > 20)]          # falling downwind, steep: the lee faces
    stoss = slope[(downwind > 0) & (slope > 3)]          # climbing downwind: the windward sides
    assert len(slip) > 500 and len(stoss) > 500
    assert 31.0 <= np.median(slip) <= 34.0, np.median(slip)
    assert 10.0 <= np.median(stoss) <= 15.0, np.median(stoss)
    # the slip faces hold much less sand surface than the stoss sides (short lee, long stoss)
    assert len(slip) < 0.5 * len(stoss)


def test_crests_meander_in_crescents(barchanoid):
    """The crest line (highest point of each across-wind row) wanders by about the horn length,
    and its brink is sharp: the slope changes from stoss to slip within a few grid cells."""
    from assets_gen.terrain.heightfield import read_heightfield

    f = read_heightfield(barchanoid / "dunes_height.exr")
    crest = f.x[np.argmax(f.y, axis=1)]
    assert 0.8 <= crest.max() - crest.min() <= 1.5 + 2 * 0.6 + 0.5, (crest.min(), crest.max())
    row = f.y[len(f.z) // 2]
    g = np.degrees(np.arctan(np.gradient(row, f.dx)))
    top = int(np.argmax(row))
    steep_after = np.flatnonzero(g[top:] < -25)
    assert len(steep_after) and steep_after[0] <= 4          # slip face within four cells of the crest


def test_crests_that_would_cross_are_refused(tmp_path):
    assert run("dunes", "--dune-wavelength", "4", "--dune-height", "0.5", "--crest-wander", "1",
               "--horn-spacing", "3", "--horn-length", "1.5", "--out", tmp_path / "x") == 2


def test_sun_matches_meeus_worked_examples():
    ra, dec = sun_equatorial(2448908.5)                # Meeus Example 25.a: 1992 Oct 13.0
    assert ra == pytest.approx(198.38083, abs=2e-4) and dec == pytest.approx(-7.78507, abs=2e-4)
    gmst_h = sidereal_time_deg(2446895.5) / 15.0       # Example 12.a: 1987 Apr 10, 0h UT
    assert gmst_h == pytest.approx(13 + 10 / 60 + 46.3668 / 3600, abs=1e-6)


@pytest.mark.parametrize("latitude", [-30.0, 0.0, 44.59])
def test_equinox_noon_sun_stands_at_colatitude_due_south_or_north(latitude):
    """At the March 2024 equinox (20 Mar 03:06 UT, declination 0) the sun at Greenwich's local
    noon (12:07 UT, the equation of time being -7.5 min) stands 90 deg - |latitude| high."""
    pos = sun_position(datetime(2024, 3, 20, 12, 7, 30, tzinfo=timezone.utc), latitude, 0.0)
    assert abs(pos.declination_deg) < 0.2
    assert pos.elevation_deg == pytest.approx(90.0 - abs(latitude), abs=0.3)
    if latitude > 1:
        assert pos.azimuth_deg == pytest.approx(180.0, abs=1.0)
    elif latitude < -1:
        assert min(pos.azimuth_deg, 360 - pos.azimuth_deg) == pytest.approx(0.0, abs=1.0)


def test_sky_from_a_date_points_its_sun_there(tmp_path):
    """The sky generator's sun for a date is the solar position turned into the light frame."""
    args = ["--date", "2025-09-20", "--local-time", "18:00", "--utc-offset-h", "2", "--latitude-deg", "44.59",
            "--longitude-deg", "-1.21", "--north-azimuth-deg", "120", "--resolution", "16", "--layout", "latlong"]
    assert run("sky", *args, "--out", tmp_path) == 0
    meta = json.loads((tmp_path / "sky.json").read_text())["params"]
    pos = sun_position(datetime(2025, 9, 20, 16, 0, tzinfo=timezone.utc), 44.59, -1.21)
    assert meta["solar_position"]["elevation_deg"] == pytest.approx(pos.elevation_deg)
    phi, e = math.radians(120 + pos.azimuth_deg), math.radians(pos.elevation_deg)
    d = meta["sun"]["direction_light_frame"]
    assert np.allclose(d, [math.cos(e) * math.cos(phi), math.cos(e) * math.sin(phi), math.sin(e)], atol=1e-9)
    assert run("sky", *args[:2], "--local-time", "23:30", "--utc-offset-h", "2", "--latitude-deg", "44.59",
               "--out", tmp_path / "night") == 2
    with pytest.raises(GeneratorError):
        from assets_gen.solar_position import parse_local_time
        parse_local_time("2025-13-01", "18:00", 0)


@pytest.mark.parametrize("north", [0.0, 120.0, 342.0])
def test_a_sun_east_of_the_view_is_right_of_the_image_centre(north):
    """Compass bearings turn clockwise seen from above. Facing north through the renderer's own
    LookAt (pbrt's, left-handed), a sun at bearing 60 must land right of the image centre and one
    at bearing 300 left of it: a mirrored light frame would swap them."""
    to_world = rotate(-90.0, np.array([1.0, 0.0, 0.0]), None)[:3, :3]   # the scene's "Rotate -90 1 0 0"
    facing = to_world @ sun_direction(0.0, light_azimuth(0.0, north))
    camera = look_at(np.zeros(3), facing, np.array([0.0, 1.0, 0.0]), None)[:3, :3]
    for bearing, side in ((60.0, 1.0), (300.0, -1.0)):
        sun = camera @ to_world @ sun_direction(20.0, light_azimuth(bearing, north))
        assert sun[2] > 0 and np.sign(sun[0]) == side   # ahead, and camera +x is raster right
