"""Hostile scene input (issue 17): every malformed file ends in a SceneError naming the file and
line (or the bad path), never a traceback from numpy or Python, and nothing is allocated for what
a header merely claims."""
from __future__ import annotations

import io
import zipfile
from pathlib import Path

import numpy as np
import pytest

from renderer.errors import Location, SceneError
from renderer.scene import load_description
from renderer.scene import parser as scene_parser

HEAD = 'Camera "perspective"\nWorldBegin\n'          # scene text after it starts at line 3
SPHERE = 'Shape "sphere"\n'


def refused(tmp_path: Path, text: str | bytes, line: int, match: str, name: str = "scene.pbrt") -> SceneError:
    """Loading the scene fails with a SceneError at ``name``:``line`` whose message matches."""
    path = tmp_path / name
    path.write_bytes(text if isinstance(text, bytes) else text.encode())
    with pytest.raises(SceneError, match=match) as info:
        load_description(path)
    assert info.value.loc == Location(str(path), line), str(info.value)
    return info.value


@pytest.mark.parametrize("body, match", [
    ("Rotate 1e400 0 1 0\n", "out of range"),
    ("Translate 1e400 0 0\n", "out of range"),
    ("Translate " + "9" * 400 + " 0 0\n", r"out of range"),
    ('Shape "trianglemesh" "integer indices" [0 1 99999999999999999999999]\n'
     '"point3 P" [0 0 0 1 0 0 0 1 0]\n', "32-bit integers"),
])
def test_numbers_out_of_range_are_refused_where_written(tmp_path, body, match):
    refused(tmp_path, HEAD + body, 3, match)


@pytest.mark.parametrize("transform", ["Scale 0 0 0", "Transform [0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 1]",
                                       "Scale 1e300 1e300 1e300\nScale 1e300 1 1",
                                       # found by the grammar fuzzer: invertible in float64 (det 1e-90),
                                       # zero in the device's float32, where the upload's inverse failed
                                       "Scale 1e-45 -1 -1\nScale 1e-45 -1 -1"])
@pytest.mark.parametrize("use", [SPHERE, 'LightSource "point"\n', 'AreaLightSource "diffuse"\n'])
def test_singular_or_infinite_transform_is_refused_at_its_user(tmp_path, transform, use):
    line = 3 + transform.count("\n") + 1
    refused(tmp_path, HEAD + transform + "\n" + use, line, "singular|infinite")


def test_a_shape_beyond_float32_range_is_refused(tmp_path):
    refused(tmp_path, HEAD + "Translate 1e300 0 0\n" + SPHERE, 4, "beyond single precision")
    refused(tmp_path, HEAD + "Scale 1e39 1 1\n" + SPHERE, 4, "beyond single precision")


@pytest.mark.parametrize("use", ['Texture "t" "spectrum" "imagemap" "string filename" "{}.png"\n',
                                 'Shape "plymesh" "string filename" "{}.ply"\n'])
def test_a_1mb_file_name_in_a_parameter_is_reported_shortened(tmp_path, use):
    err = refused(tmp_path, HEAD + use.format("a" * 1_000_000), 3, "characters")
    assert len(str(err)) < 1000


@pytest.mark.parametrize("encoding", ["gamma ", "gamma abc", "gamma -1", "gamma nan", "srgbx", "Gamma 2.2"])
def test_bad_image_encoding_is_refused(tmp_path, encoding):
    (tmp_path / "t.png").write_bytes(b"")            # exists: the encoding is checked before reading
    refused(tmp_path, HEAD + f'Texture "t" "spectrum" "imagemap" "string filename" "t.png" '
            f'"string encoding" ["{encoding}"]\n', 3, "encoding must be")


def test_a_long_include_chain_is_cut_at_the_depth_limit(tmp_path):
    n = scene_parser.MAX_INCLUDE_DEPTH + 20
    for i in range(n):
        (tmp_path / f"f{i}.pbrt").write_text(f'Include "f{i + 1}.pbrt"\n')
    (tmp_path / f"f{n}.pbrt").write_text(SPHERE)
    path = tmp_path / "scene.pbrt"
    path.write_text(HEAD + 'Include "f0.pbrt"\n')
    with pytest.raises(SceneError, match="nested more than") as info:
        load_description(path)
    assert info.value.loc == Location(str(tmp_path / f"f{scene_parser.MAX_INCLUDE_DEPTH - 2}.pbrt"), 1)


def test_an_exponential_include_graph_is_refused_by_the_total_count(tmp_path, monkeypatch):
    monkeypatch.setattr(scene_parser, "MAX_INCLUDED_FILES", 200)
    reads: list[Path] = []
    real = scene_parser._read_scene_text
    monkeypatch.setattr(scene_parser, "_read_scene_text", lambda p, *a: reads.append(p) or real(p, *a))
    for i in range(30):                               # each includes the next twice: 2^30 files
        (tmp_path / f"f{i}.pbrt").write_text(f'Include "f{i + 1}.pbrt"\nInclude "f{i + 1}.pbrt"\n')
    (tmp_path / "f30.pbrt").write_text("")
    path = tmp_path / "scene.pbrt"
    path.write_text(HEAD + 'Include "f0.pbrt"\n')
    with pytest.raises(SceneError, match="more than 200 files included"):
        load_description(path)
    assert len(reads) == 201                          # the top file and 200 includes, then stop


def test_non_utf8_is_located_by_line_and_latin1_comments_are_accepted(tmp_path):
    ok = tmp_path / "ok.pbrt"
    ok.write_bytes((HEAD + "# caf\xe9 cr\xe8me\n" + SPHERE).encode("latin-1"))
    assert len(load_description(ok).shapes) == 1
    refused(tmp_path, (HEAD + '\nShape "sph\xe8re"\n').encode("latin-1"), 4, "not valid UTF-8")
    refused(tmp_path, (HEAD + 'Shape sph\xe8re\n').encode("latin-1"), 3, "not valid UTF-8")


def test_a_1mb_include_name_is_reported_shortened(tmp_path):
    err = refused(tmp_path, HEAD + f'Include "{"a" * 1_000_000}.pbrt"\n', 3, "characters")
    assert len(str(err)) < 1000


def _npy_header(shape: tuple[int, ...]) -> bytes:
    buf = io.BytesIO()
    np.lib.format.write_array_header_1_0(buf, {"descr": "<f8", "fortran_order": False, "shape": shape})
    return buf.getvalue()


def _instances(tmp_path: Path, name: str, data: bytes, match: str) -> SceneError:
    (tmp_path / name).write_bytes(data)
    return refused(tmp_path, HEAD + f'ObjectBegin "o"\n{SPHERE}ObjectEnd\n'
                   f'ObjectInstance "o" "string transforms" "{name}"\n', 6, match)


def _zip(members: dict[str, bytes]) -> bytes:
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as z:
        for k, v in members.items():
            z.writestr(k, v)
    return buf.getvalue()


@pytest.mark.parametrize("name, data, match", [
    ("huge.npy", _npy_header((999999999, 4, 4)), "999999999 instances exceed the limit"),
    ("big.npy", _npy_header((5000, 4, 4)), "promises 5000 matrices"),
    ("short.npy", _npy_header((2, 4, 4)) + b"\0" * 100, "promises 2 matrices"),
    ("empty.npy", b"", "cannot read"),
    ("garbage.npy", b"hello world" * 10, "cannot read"),
    ("empty.npz", _zip({}), 'no array named "transforms"'),
    ("huge.npz", _zip({"transforms.npy": _npy_header((999999999, 4, 4))}), "999999999 instances exceed"),
    ("truncated.npz", _zip({"transforms.npy": _npy_header((3, 4, 4)) + b"\0" * 1000})[:-40], "cannot read"),
    ("shape.npy", _npy_header((3, 3)) + b"\0" * 72, r"shape \(N, 4, 4\)"),
])
def test_bad_instance_transform_files_are_refused_before_allocation(tmp_path, name, data, match):
    assert name in str(_instances(tmp_path, name, data, match))


def test_good_instance_transform_files_still_load(tmp_path):
    T = np.tile(np.eye(4), (3, 1, 1))
    T[:, 0, 3] = [1, 2, 3]
    np.save(tmp_path / "t.npy", T)
    np.savez_compressed(tmp_path / "t.npz", transforms=T)
    for name in ("t.npy", "t.npz"):
        s = load_description(_write(tmp_path, HEAD + f'ObjectBegin "o"\n{SPHERE}ObjectEnd\n'
                                    f'ObjectInstance "o" "string transforms" "{name}"\n'))
        np.testing.assert_allclose(s.instance_sets[-1].transforms[:, 0, 3], [1, 2, 3])


def _write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "scene.pbrt"
    path.write_text(text)
    return path


def test_ply_header_claiming_more_faces_than_the_file_holds_is_refused(tmp_path):
    header = ("ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
              "property float z\nelement face 999999999\nproperty list uchar int vertex_indices\nend_header\n")
    (tmp_path / "m.ply").write_bytes(header.encode() + np.zeros(9, np.float32).tobytes() + b"\3" + b"\0" * 12)
    err = refused(tmp_path, HEAD + 'Shape "plymesh" "string filename" "m.ply"\n', 3, "999999999")
    assert "m.ply" in str(err)


def test_ascii_ply_counts_are_checked_and_a_valid_one_loads(tmp_path):
    good = ("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
            "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")
    (tmp_path / "g.ply").write_text(good)
    assert len(load_description(_write(tmp_path, HEAD + 'Shape "plymesh" "string filename" "g.ply"\n')).shapes) == 1
    (tmp_path / "b.ply").write_text(good.replace("element face 1", "element face 1000"))
    refused(tmp_path, HEAD + 'Shape "plymesh" "string filename" "b.ply"\n', 3, "declares 3, 1000 elements")


@pytest.mark.parametrize("light, line", [
    ('LightSource "distant" "rgb L" [-1 -1 -1]', 3),
    ('LightSource "infinite" "rgb L" [1 -0.5 1]', 3),
    ('LightSource "point" "rgb I" [1 1 1] "float scale" [-2]', 3),
    ('AttributeBegin\nAreaLightSource "diffuse" "rgb L" [-3 0 0]\nShape "sphere"\nAttributeEnd', 4),
])
def test_negative_light_is_refused_where_written(tmp_path, light, line):
    refused(tmp_path, HEAD + light + "\n" + SPHERE, line, r"outside \[0(\.0)?, inf\]")


def test_a_blackbody_below_the_srgb_gamut_emits_no_negative_component():
    from renderer.color.rgb import blackbody_rgb

    warm = blackbody_rgb(1200.0)
    assert warm.min() == 0.0 and warm[0] > warm[1] > 0.0     # deep red: blue clipped, not negative
    assert np.all(blackbody_rgb(6500.0) > 0.5)


def test_many_identical_spheres_share_one_tessellation(tmp_path):
    """20,000 spheres once took 8 GB (one tessellation each); equal shapes now share one mesh,
    and each line still warns about its own unused parameter."""
    lines = [f'AttributeBegin\nTranslate {i} 0 0\nShape "sphere" "float radius" [0.5] "float bogus" [1]\nAttributeEnd'
             for i in range(2000)]
    lines.append('Shape "sphere" "float radius" [0.25]')
    path = tmp_path / "spheres.pbrt"
    path.write_text(HEAD + "\n".join(lines) + "\n")
    desc = load_description(path)
    assert len(desc.meshes) == 2 and len(desc.shapes) == 2001
    assert sum('"float bogus"' in w for w in desc.warnings) == 2000
    big, small = (np.ptp(m.positions[:, 0]) for m in desc.meshes)
    assert big == pytest.approx(1.0, rel=1e-3) and small == pytest.approx(0.5, rel=1e-3)


def test_equal_meshes_merge_only_when_their_bytes_are_equal(tmp_path):
    tri = 'Shape "trianglemesh" "integer indices" [0 1 2] "point3 P" [0 0 0 1 0 0 0 1 {z}]\n'
    path = tmp_path / "tris.pbrt"
    path.write_text(HEAD + tri.format(z=0) + tri.format(z=0) + tri.format(z=1e-7))
    desc = load_description(path)
    assert [s.mesh for s in desc.shapes] == [0, 0, 1]


def test_fuzzer_finds_singular_instance_transforms_and_garbled_npy_headers(tmp_path):
    """Two cases the fuzzer found: one singular matrix among the instances (numpy's LinAlgError at
    upload) and a NUL byte in the .npy header (numpy's SyntaxError while parsing it)."""
    T = np.stack([np.eye(4)] * 3)
    T[1, :3, :3] = 0.0
    np.save(tmp_path / "t.npy", T)
    body = 'ObjectBegin "o"\nShape "sphere"\nObjectEnd\nObjectInstance "o" "string transforms" "t.npy"\n'
    refused(tmp_path, HEAD + body, 6, "instance transform 1 is singular")
    buf = io.BytesIO()
    np.save(buf, np.stack([np.eye(4)] * 3))
    raw = bytearray(buf.getvalue())
    raw[raw.index(b"}") - 1] = 0
    (tmp_path / "t.npy").write_bytes(bytes(raw))
    refused(tmp_path, HEAD + body, 6, "cannot read instance transforms")


@pytest.mark.parametrize("kelvin", ["0", "-5", "1e7"])
def test_blackbody_temperatures_outside_the_tabulated_range_are_refused(tmp_path, kelvin):
    refused(tmp_path, HEAD + f'LightSource "distant" "blackbody L" [{kelvin}]\n' + SPHERE, 3,
            "between 0 and 1e6 kelvin")
