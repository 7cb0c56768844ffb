"""Materials' named parameters: one declaration per material gives pbrt parsing with file:line
errors and warnings at load time, Python values with unknown names refused, the device slot and
flag layout, and the docs table."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from bsdf_harness import constant_rows
from renderer.errors import Location, SceneError, UnsupportedError
from renderer.materials import REGISTRY, conductor, device_layout, disney, material, parameter_tables, thinfilm
from renderer.materials.bsdf import FIRST_DERIVED_FLAG, MAX_SLOTS
from renderer.parameters import TextureRef
from renderer.scene import load_description

ROOT = Path(__file__).resolve().parents[2]
HEAD = 'Camera "perspective"\nWorldBegin\nLightSource "infinite"\n'     # scene text after it starts at line 4


def load(tmp_path: Path, text: str):
    path = tmp_path / "scene.pbrt"
    path.write_text(HEAD + text)
    return path, load_description(path)


@pytest.mark.parametrize("text,match", [
    ('Material "diffuse" "rgb reflectance" [1.5 0.2 0.2]', r'"reflectance" = \[1.5, 0.2, 0.2\] is outside \[0.0, 1'),
    ('Material "dielectric" "float eta" 0', r'"eta" = 0.0 is outside'),
    ('MakeNamedMaterial "m" "string type" "disney" "float difftrans" 2.5', '"difftrans"'),
    ('Material "thinfilm" "bool transmission" true "float k_inner" 2', "clear substrate"),
], ids=["rgb-range", "float-range", "named", "derived-check"])
def test_parameter_errors_name_file_and_line_at_load_time(tmp_path, text, match):
    """Range and consistency errors come from load_scene, located at the material's line."""
    with pytest.raises(SceneError, match=match) as info:
        load(tmp_path, text + '\nShape "sphere"\n')
    assert info.value.loc == Location(str(tmp_path / "scene.pbrt"), 4)


def test_undeclared_parameters_warn_at_load_time(tmp_path):
    path, s = load(tmp_path, 'Material "conductor" "float k_inner" 2 "rgb k" [1 2 3]\nShape "sphere"\n')
    assert s.warnings == [f'{path}:4: parameter "k_inner" of material "conductor" is not supported and was ignored']
    assert s.materials[0].values == {"k": (1.0, 2.0, 3.0)}


def test_unknown_materials_are_refused_at_load_time_and_interface_has_three_names(tmp_path):
    with pytest.raises(UnsupportedError, match="not supported") as info:
        load(tmp_path, 'Material "hair"\nShape "sphere"\n')
    assert info.value.loc.line == 4
    with pytest.raises(UnsupportedError, match="supported: diffuse, dielectric"):
        material("plastic")
    for kind in ("interface", "none", ""):          # pbrt-v4's parser reads "" and "none" as interface
        assert load(tmp_path, f'Material "{kind}"\nShape "sphere"\n')[1].materials[0].kind == "interface"


def test_python_values_are_validated():
    assert material("diffuse", reflectance=(0.8, 0.2, 0.2)).values == {"reflectance": (0.8, 0.2, 0.2)}
    assert material("diffuse", reflectance=0.3).values == {"reflectance": (0.3, 0.3, 0.3)}
    with pytest.raises(SceneError, match=r"unknown parameter\(s\) reflectence"):
        material("diffuse", reflectence=0.5)
    with pytest.raises(SceneError, match="outside"):
        material("conductor", reflectance=1.0)             # pbrt's artist mapping needs r < 1
    with pytest.raises(SceneError, match="cannot be a texture"):
        material("thinfilm", k_inner=TextureRef("k"))
    with pytest.raises(SceneError, match="must be true or false"):
        material("disney", thin=1.0)
    with pytest.raises(SceneError, match="must be a float texture"):
        material("diffuse", displacement=0.1)
    assert material("diffuse", displacement=TextureRef("h")).values["displacement"] == TextureRef("h")


def test_slot_layout_comes_from_the_declaration():
    """Slots in declaration order, defaults where nothing is given, bools as flag bits."""
    for name, module in REGISTRY.items():
        assert len(module.PARAMS.slot_names) <= MAX_SLOTS, name
        defaults = {p.name: p.default for p in module.PARAMS}
        for pre in ("", "interface.", "conductor."):        # pbrt's shorthand: roughness sets both
            if f"{pre}uroughness" in defaults:
                r = defaults[f"{pre}roughness"]
                defaults |= {f"{pre}uroughness": r, f"{pre}vroughness": r}
        layout, _ = device_layout(material(name))
        assert [(p.name, v) for p, v in layout] == [(n, defaults[n]) for n in module.PARAMS.slot_names], name
    rows, flags = constant_rows("disney", dict(thin=True, roughness=0.2))
    assert rows[disney.SLOT.roughness, 0] == np.float32(0.2) and rows[disney.SLOT.sheentint, 0] == np.float32(0.5)
    assert flags == disney.FLAG.thin
    rows, flags = constant_rows("thinfilm", dict(transmission=True))
    assert flags == thinfilm.FLAG.transmission | thinfilm.FLAG.remaproughness | thinfilm.FLAG.multiscatter
    assert rows[thinfilm.SLOT.eta_film, 0] == np.float32(1.55)


def test_conductor_derived_values():
    """pbrt's shorthands: roughness sets u and v roughness unless they are given; a given
    reflectance replaces eta and k (a derived flag above the declared ones)."""
    rows, flags = constant_rows("conductor", dict(roughness=0.3, vroughness=0.1))
    assert rows[conductor.SLOT.uroughness, 0] == np.float32(0.3)
    assert rows[conductor.SLOT.vroughness, 0] == np.float32(0.1)
    np.testing.assert_array_equal(rows[conductor.SLOT.eta], np.float32(conductor.COPPER_ETA))
    assert flags == conductor.FLAG.remaproughness and not flags & conductor.ARTIST
    rows, flags = constant_rows("conductor", dict(reflectance=(0.9, 0.5, 0.2), remaproughness=False))
    assert flags == conductor.ARTIST and conductor.ARTIST >= FIRST_DERIVED_FLAG
    np.testing.assert_allclose(rows[conductor.SLOT.reflectance], [0.9, 0.5, 0.2])


def test_texture_parameters_load_as_references(tmp_path):
    path, s = load(tmp_path, 'Texture "t" "float" "constant" "float value" 300\n'
                             'Material "thinfilm" "texture thicknessmap" "t" "float thicknessscale" 0.5\n'
                             'Shape "sphere"\n')
    assert s.materials[0].values == {"thicknessmap": TextureRef("t"), "thicknessscale": 0.5}
    assert s.warnings == []


def test_docs_show_every_material_table():
    """docs/materials.md carries each declaration's generated table; on failure, paste
    ``renderer.materials.parameter_tables()`` into its "Parameters" section."""
    docs = (ROOT / "docs" / "materials.md").read_text()
    assert parameter_tables() in docs
    for name in REGISTRY:
        assert f"### `{name}`" in docs
