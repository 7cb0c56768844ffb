"""pbrt-v4's scene semantics, as its binary behaves (see docs/pbrt-v4.md for what was run): the last
of a repeated parameter wins, named materials and textures resolve when the scene is complete,
every unsupported thing is reported at load together, and gzipped files are read wherever pbrt
reads them, with the hostile-input bounds still applied to their decompressed size."""
from __future__ import annotations

import gzip
from pathlib import Path

import numpy as np
import pytest

from renderer.errors import Location, SceneError, SceneErrors
from renderer.scene import load_description
from renderer.scene import parser as scene_parser

HEAD = 'Camera "perspective"\nWorldBegin\n'          # scene text after it starts at line 3


def write(tmp_path: Path, text: str, name: str = "scene.pbrt") -> Path:
    path = tmp_path / name
    path.write_bytes(gzip.compress(text.encode()) if name.endswith(".gz") else text.encode())
    return path


def test_a_repeated_parameter_takes_the_last_value_and_warns(tmp_path):
    path = write(tmp_path, 'Camera "perspective" "float fov" 10 "float fov" 40\nWorldBegin\n'
                           'Material "diffuse" "rgb reflectance" [1 0 0]\n  "rgb reflectance" [0 0 1]\n'
                           'Shape "sphere"\n')
    s = load_description(path)
    assert s.camera.fov_deg == 40.0
    assert s.materials[s.shapes[0].material].values["reflectance"] == (0.0, 0.0, 1.0)
    shadowed = [w for w in s.warnings if "given again later" in w]
    assert shadowed == [f'{path}:1: Camera "perspective": parameter "fov" is given again later; the later value '
                        'is used (as pbrt-v4)',
                        f'{path}:3: material "diffuse": parameter "reflectance" is given again later; the later '
                        'value is used (as pbrt-v4)']


def test_named_material_used_before_its_definition_resolves_at_the_end(tmp_path):
    s = load_description(write(tmp_path, HEAD + 'NamedMaterial "red"\nShape "sphere"\n'
                                                'ObjectBegin "o"\nShape "disk"\nObjectEnd\n'
                                                'Scale -1 1 1\nObjectInstance "o"\n'       # mirrored copy
                                                'MakeNamedMaterial "red" "string type" "conductor"\n'
                                                'Material "dielectric"\nShape "disk"\n'))
    kinds = [s.materials[sh.material].kind for sh in s.shapes]
    assert kinds == ["conductor", "conductor", "conductor", "dielectric"]
    assert s.materials[s.shapes[0].material].name == "red"


def test_a_named_material_never_defined_is_an_error_at_each_shape_using_it(tmp_path):
    path = write(tmp_path, HEAD + 'NamedMaterial "nope"\nAttributeBegin\nShape "sphere"\nAttributeEnd\n'
                                  'Shape "disk"\nNamedMaterial "unused"\n')
    with pytest.raises(SceneErrors) as info:
        load_description(path)
    assert [e.loc for e in info.value.errors] == [Location(str(path), 5), Location(str(path), 7)]
    assert all('no material named "nope"' in e.message for e in info.value.errors)


def test_material_may_name_a_texture_defined_later_but_not_an_undefined_one(tmp_path):
    s = load_description(write(tmp_path, HEAD + 'Material "diffuse" "texture reflectance" "later"\nShape "sphere"\n'
                                                'Texture "later" "spectrum" "constant" "rgb value" [0 1 0]\n'))
    assert "later" in s.textures
    path = write(tmp_path, HEAD + 'Material "diffuse" "texture reflectance" "nosuch"\nShape "sphere"\n')
    with pytest.raises(SceneError, match='names texture "nosuch", which is not defined') as info:
        load_description(path)
    assert info.value.loc == Location(str(path), 3)


def test_every_unsupported_thing_is_reported_at_load_in_one_error(tmp_path):
    path = write(tmp_path, HEAD + 'Texture "w" "float" "ptex"\n'
                                  'MakeNamedMaterial "c" "string type" "measured"\n'
                                  'NamedMaterial "c"\nShape "curve"\nShape "sphere"\n'
                                  'Material "diffuse" "texture reflectance" "w"\nShape "sphere"\n'
                                  'Material "diffuse" "texture reflectance" "gone"\nShape "disk"\n'
                                  'LightSource "sunsky"\n')
    with pytest.raises(SceneErrors) as info:
        load_description(path)
    lines = [e.loc.line for e in info.value.errors]
    # ptex, measured, curve, the undefined texture, sunsky: not the follow-ons of a
    # refused texture or named material
    assert lines == [3, 4, 6, 12, 10], [str(e) for e in info.value.errors]


def test_gzipped_include_and_ply_mesh(tmp_path):
    ply = ("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
           "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")
    (tmp_path / "tri.ply.gz").write_bytes(gzip.compress(ply.encode()))
    write(tmp_path, 'Shape "plymesh" "string filename" "tri.ply.gz"\n', "part.pbrt.gz")
    s = load_description(write(tmp_path, HEAD + 'Include "part.pbrt.gz"\nImport "part.pbrt.gz"\n'))
    assert len(s.shapes) == 2
    np.testing.assert_array_equal(s.meshes[0].positions, [[0, 0, 0], [1, 0, 0], [0, 1, 0]])
    top = load_description(write(tmp_path, HEAD + 'Shape "sphere"\n', "top.pbrt.gz"))
    assert len(top.shapes) == 1


def test_gzip_bomb_include_is_cut_by_the_decompressed_size_budget(tmp_path, monkeypatch):
    monkeypatch.setattr(scene_parser, "MAX_INCLUDED_BYTES", 1 << 20)
    (tmp_path / "bomb.pbrt.gz").write_bytes(gzip.compress(b"#" * (8 << 20)))   # 8 KiB that expand to 8 MiB
    path = write(tmp_path, HEAD + 'Include "bomb.pbrt.gz"\n')
    with pytest.raises(SceneError, match="exceed 1 MiB in all") as info:
        load_description(path)
    assert info.value.loc == Location(str(path), 3)


def test_gzip_bomb_ply_is_refused(tmp_path, monkeypatch):
    from renderer.scene import plymesh

    monkeypatch.setattr(plymesh, "MAX_PLY_BYTES", 1 << 20)
    (tmp_path / "m.ply.gz").write_bytes(gzip.compress(b"ply\n" + b" " * (4 << 20)))
    with pytest.raises(SceneError, match="decompresses to more than the limit"):
        load_description(write(tmp_path, HEAD + 'Shape "plymesh" "string filename" "m.ply.gz"\n'))


@pytest.mark.parametrize("name", ["part.pbrt.gz", "m.ply.gz"])
def test_a_corrupt_gzip_file_is_a_located_error(tmp_path, name):
    (tmp_path / name).write_bytes(b"\x1f\x8b\x08\x00garbage")
    use = f'Include "{name}"' if name.endswith("pbrt.gz") else f'Shape "plymesh" "string filename" "{name}"'
    path = write(tmp_path, HEAD + use + "\n")
    with pytest.raises(SceneError, match="not a readable gzip file") as info:
        load_description(path)
    assert info.value.loc == Location(str(path), 3)


def test_mix_inputs_must_be_defined_before_and_nest_at_most_the_stack_deep(tmp_path):
    with pytest.raises(SceneError, match='no texture named "later" is defined before it'):
        load_description(write(tmp_path, HEAD + 'Texture "m" "float" "mix" "texture tex1" "later"\n'
                                                'Texture "later" "float" "constant"\n'))
    chain = ['Texture "t0" "float" "constant" "float value" 0.2\n']
    chain += [f'Texture "t{i}" "float" "mix" "float tex1" 0.5 "texture tex2" "t{i - 1}"\n' for i in range(1, 7)]
    # a mix holds its tex1 while tex2 is evaluated, then both and the amount: t_i holds i + 2 values
    assert "t6" in load_description(write(tmp_path, HEAD + "".join(chain))).textures
    path = write(tmp_path, HEAD + "".join(chain) + 'Texture "t7" "float" "mix" "float tex1" 0.5 "texture tex2" "t6"\n')
    with pytest.raises(SceneError, match='"t7": its inputs nest too deeply') as info:
        load_description(path)
    assert info.value.loc == Location(str(path), 10)


def test_float_and_spectrum_textures_have_separate_name_spaces(tmp_path):
    """pbrt-v4 allows a float and a spectrum texture of one name (it rendered such a scene); each
    material parameter finds the one of its type. Two of one type are an error."""
    from renderer.textures import TextureTable

    s = load_description(write(tmp_path, HEAD + 'Texture "b" "spectrum" "constant" "rgb value" [0 1 0]\n'
                                                'Texture "b" "float" "constant" "float value" 0.25\n'
                                                'Material "conductor" "texture reflectance" "b" "texture roughness" "b"\n'
                                                'Shape "sphere"\n'))
    table = TextureTable()
    assert table.scale[table.lookup("b", "spectrum", s.textures, None)].tolist() == [0.0, 1.0, 0.0]
    assert table.scale[table.lookup("b", "float", s.textures, None)].tolist() == [0.25] * 3
    path = write(tmp_path, HEAD + 'Texture "b" "float" "constant"\nTexture "b" "spectrum" "constant"\n'
                                  'Texture "b" "float" "constant"\n')
    with pytest.raises(SceneError, match='float texture "b" is defined twice') as info:
        load_description(path)
    assert info.value.loc == Location(str(path), 5)
