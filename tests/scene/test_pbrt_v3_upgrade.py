"""pbrt-v3 syntax read as pbrt-v4's ``--upgrade`` writes it: tests/data/pbrt/v3_syntax.pbrt against
v3_syntax_upgraded.pbrt, the file pbrt-v4 itself wrote from it (``pbrt --upgrade``), which must
describe the same scene; every upgraded construct is warned about at its own line."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from pbrt_compare import DATA
from renderer.errors import SceneError
from renderer.scene import load_description


def test_v3_scene_reads_as_pbrts_own_upgrade_of_it():
    v3 = load_description(DATA / "v3_syntax.pbrt")
    v4 = load_description(DATA / "v3_syntax_upgraded.pbrt")
    assert v4.warnings == []
    assert (v3.sampler, v3.integrator) == (v4.sampler, v4.integrator)
    for f in dataclasses.fields(v3.camera):
        np.testing.assert_array_equal(getattr(v3.camera, f.name), getattr(v4.camera, f.name))
    assert (v3.film.width, v3.film.height, v3.film.filename) == (v4.film.width, v4.film.height, v4.film.filename)
    assert [(d.kind, d.values) for d in v3.lights] == [(d.kind, d.values) for d in v4.lights]
    for a, b in zip(v3.lights, v4.lights):
        np.testing.assert_array_equal(a.light_to_world, b.light_to_world)
    assert [s.area_light and s.area_light.values for s in v3.shapes] == \
        [s.area_light and s.area_light.values for s in v4.shapes]
    assert len(v3.meshes) == len(v4.meshes)
    for a, b in zip(v3.meshes, v4.meshes):
        np.testing.assert_array_equal(a.positions, b.positions)
        np.testing.assert_array_equal(a.indices, b.indices)
    # what --upgrade did, in numbers: 0.5 grey L with mapname, 2 x 5 and 3 folded into scale
    assert [d.values["scale"] for d in v3.lights] == [0.5, 10.0, 3.0]
    assert (v3.integrator.max_depth, v3.sampler.kind) == (1, "paddedsobol")


def test_each_upgraded_construct_is_warned_at_its_line():
    warned = {}
    for w in load_description(DATA / "v3_syntax.pbrt").warnings:
        line = int(w.split(":")[1])
        warned.setdefault(line, []).append(w)
    assert sorted(warned) == [5, 6, 7, 9, 10, 13, 16, 17, 18]
    assert len(warned[6]) == 2 and len(warned[9]) == 3 and len(warned[13]) == 3     # each construct once
    assert all("pbrt-v3" in w for ws in warned.values() for w in ws)


@pytest.mark.parametrize("directive, message", [
    ('LightSource "infinite" "rgb scale" [1 2 3]', "only converts a grey rgb"),
    ('LightSource "infinite" "string mapname" "sky.png" "rgb L" [1 0.5 0.5]', "only converts a grey rgb"),
    # materials and textures (renderer.scene.upgrade_materials): --upgrade's "Please manually edit the file"
    ('Texture "s" "color" "scale" "color tex1" [0.5 0.6 0.5] "texture tex2" "t"', "not a grey"),
    ('Texture "s" "color" "scale" "texture tex1" "a" "texture tex2" "b"', "both scale inputs are textures"),
    ('Texture "s" "color" "scale" "color tex1" [1 1 1] "color tex2" [2 2 2]', 'both scale inputs are "rgb"'),
    ('Material "uber" "texture opacity" "o"', 'no material "opacity"'),
    ('Material "uber" "color opacity" [0.5 0.5 0.5]', 'no material "opacity"'),
    ('MakeNamedMaterial "u" "string type" "uber" "color opacity" [1 0 1]', 'no material "opacity"'),
    ('Material "mix" "string namedmaterial1" "a"', 'needs both "namedmaterial1" and "namedmaterial2"'),
    ('Material "mix" "spectrum amount" [400 0.5 700 0.5] "string namedmaterial1" "a" "string namedmaterial2" "b"',
     'spectrum "amount"'),
    ('Material "glass" "float index" [1.5 1.6]', "more than one value"),
    ('Material "glass" "float index" 1.5 "float eta" 1.4', 'both "index" and "eta"'),
])
def test_what_upgrade_cannot_convert_is_a_located_error(tmp_path, directive, message):
    path = tmp_path / "scene.pbrt"
    path.write_text(f'Camera "perspective"\nWorldBegin\n{directive}\n')
    with pytest.raises(SceneError, match=message) as info:
        load_description(path)
    assert info.value.loc.line == 3
    assert "upgrade" in str(info.value)
