"""Asset recipes (assets_gen/recipe.py): incremental, deterministic builds, clear errors, and a
rebuild hash that follows the generator's imports."""
from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from assets_gen import cli, recipe
from assets_gen.recipe import RecipeError


def _recipe(tmp: Path, assets: list[dict], name: str = "scene.recipe.json") -> Path:
    path = tmp / name
    path.write_text(json.dumps({"recipe": 1, "assets": assets}, indent=1))
    return path


def _small(sky_res: int = 16, scale: float = 0.05) -> list[dict]:
    return [
        {"name": "sky", "generator": "sky", "seed": 0, "out": "assets/t/sky",
         "params": {"resolution": sky_res, "layout": "latlong", "elevation_deg": 30}},
        {"name": "lights", "generator": "sky-lights", "out": "assets/t/lights",
         "params": {"sky": "assets/t/sky", "scale": scale, "sun": "blackbody"}},
        {"name": "glasses", "generator": "sunglasses", "seed": 3, "out": "assets/t/glasses",
         "params": {"lens_width": 0.05}},
    ]


def _snapshot(folder: Path) -> dict[str, tuple[int, bytes]]:
    return {p.relative_to(folder).as_posix(): (p.stat().st_mtime_ns, p.read_bytes())
            for p in sorted(folder.rglob("*")) if p.is_file()}


def test_second_build_is_skipped(tmp_path):
    r = _recipe(tmp_path, _small())
    first = recipe.build(r, log=None)
    assert [x.built for x in first] == [True, True, True]
    assert (tmp_path / "assets/t/sky/sky_latlong.exr").is_file()
    assert (tmp_path / "assets/t/lights/lights.pbrt").is_file()
    before = _snapshot(tmp_path / "assets")
    second = recipe.build(r, log=None)
    assert [x.built for x in second] == [False, False, False]
    assert _snapshot(tmp_path / "assets") == before            # not a byte, not an mtime touched
    assert {p.name for p in second[0].outputs} == {"sky.json", "sky_latlong.exr"}


def test_changed_parameter_rebuilds_that_entry_and_its_dependants(tmp_path):
    r = _recipe(tmp_path, _small(sky_res=16))
    recipe.build(r, log=None)
    glasses = _snapshot(tmp_path / "assets/t/glasses")
    old_sky = (tmp_path / "assets/t/sky/sky_latlong.exr").read_bytes()
    _recipe(tmp_path, _small(sky_res=32))
    res = recipe.build(r, log=None)
    # the sky changed; the lights read the sky folder, so they are redone too; the glasses are not
    assert [x.built for x in res] == [True, True, False]
    assert (tmp_path / "assets/t/sky/sky_latlong.exr").read_bytes() != old_sky
    assert _snapshot(tmp_path / "assets/t/glasses") == glasses
    # a parameter of the last step only
    _recipe(tmp_path, _small(sky_res=32, scale=0.1))
    assert [x.built for x in recipe.build(r, log=None)] == [False, True, False]
    assert '"float scale" [0.1]' in (tmp_path / "assets/t/lights/lights.pbrt").read_text()


def test_missing_output_or_force_rebuilds(tmp_path):
    r = _recipe(tmp_path, _small())
    recipe.build(r, log=None)
    (tmp_path / "assets/t/glasses/frame.ply").unlink()
    assert [x.built for x in recipe.build(r, log=None)] == [False, False, True]
    assert (tmp_path / "assets/t/glasses/frame.ply").is_file()
    assert all(x.built for x in recipe.build(r, force=True, log=None))
    assert [x.built for x in recipe.build(r, only=["sky"], force=True, log=None)] == [True]


def test_same_seed_same_bytes(tmp_path):
    r = _recipe(tmp_path, _small())
    recipe.build(r, root=tmp_path / "a", log=None)
    recipe.build(r, root=tmp_path / "b", log=None)
    a = {k: v[1] for k, v in _snapshot(tmp_path / "a/assets").items()}
    b = {k: v[1] for k, v in _snapshot(tmp_path / "b/assets").items()}
    assert a.keys() == b.keys() and len(a) >= 8
    assert a == b


def test_quick_overrides(tmp_path):
    assets = _small(sky_res=64)
    assets[0]["quick"] = {"resolution": 8}
    r = _recipe(tmp_path, assets)
    recipe.build(r, quick=True, log=None)
    stamp = json.loads((tmp_path / "assets/t/sky" / recipe.STAMP).read_text())
    assert stamp["params"]["resolution"] == 8
    # switching back to the full recipe is a change: it rebuilds
    assert recipe.build(r, log=None)[0].built


def test_scene_recipe_lookup(tmp_path):
    (tmp_path / "scene.pbrt").write_text("WorldBegin\n")
    assert recipe.recipe_for(tmp_path / "scene.pbrt") is None
    r = _recipe(tmp_path, _small())
    assert recipe.recipe_for(tmp_path / "scene.pbrt") == r


@pytest.mark.parametrize("entry, message", [
    ({"name": "x", "generator": "nosuch", "out": "assets/x"}, "unknown generator 'nosuch'"),
    ({"name": "x", "generator": "sky", "out": "../elsewhere"}, "inside assets/"),
    ({"name": "x", "generator": "sky", "out": "assets/x", "params": {"resolution": -4}}, "resolution"),
    ({"name": "x", "generator": "sky", "out": "assets/x", "params": {"no_such_option": 1}},
     "asset 0 'x': unknown parameter(s) ['no_such_option']"),
    ({"name": "x", "generator": "sky", "out": "assets/x", "params": {"no-such-option": 1}},
     "asset 0 'x': unknown parameter(s) ['no_such_option']"),
    ({"name": "x", "generator": "sky", "out": "assets/x", "params": {"layout": "cube"}},
     "parameter 'layout': 'cube' is not one of ['both', 'latlong', 'equal-area']"),
    ({"name": "x", "generator": "sky", "out": "assets/x", "params": {"resolution": "big"}},
     "asset 0 'x': parameter 'resolution': expected an integer, got 'big'"),
    ({"name": "x", "generator": "sky", "out": "assets/x", "params": {"resolution": 16.5}},
     "parameter 'resolution': expected an integer"),
    ({"name": "x", "generator": "sky", "out": "assets/x", "params": {"turbidity": True}},
     "parameter 'turbidity': expected a number"),
    ({"name": "x", "generator": "grains", "out": "assets/x", "params": {"camera_up": [0, 1]}},
     "parameter 'camera_up': expected a list of 3 numbers"),
    ({"name": "x", "generator": "sky", "out": "assets/x", "params": {"preview": False}},
     "unknown parameter(s) ['preview']"),                # the sky writes no previews
    ({"name": "x", "generator": "dunes", "out": "assets/x", "params": {"preview": "no"}},
     "parameter 'preview': expected true or false"),
    ({"name": "x", "generator": "sky", "out": "assets/x", "seed": -1}, '"seed"'),
    ({"name": "x", "generator": "sky", "out": "assets/x", "params": {"seed": 2}}, 'give "seed" as a key'),
    ({"name": "x", "generator": "sky", "out": "assets/x", "colour": 1}, "unknown key(s) ['colour']"),
    ({"generator": "sky", "out": "assets/x"}, '"name" must be a non-empty string'),
    ({"name": "x", "generator": "sky-lights", "out": "assets/x", "params": {"sky": "assets/none"}},
     "sky.json not found"),
    ({"name": "x", "generator": "sky-lights", "out": "assets/x", "params": {"sky": "assets/none", "colour": 1}},
     "asset 0 'x': unknown parameter(s) ['colour']"),
])
def test_bad_entry_gives_a_clear_error(tmp_path, entry, message):
    r = _recipe(tmp_path, [entry])
    with pytest.raises(RecipeError) as e:
        recipe.build(r, log=None)
    text = str(e.value)
    assert message in text
    assert "scene.recipe.json" in text                      # names the recipe
    assert "\n" not in text                                 # one line
    assert not (tmp_path / "assets/x" / recipe.STAMP).exists()


def test_bad_recipe_files(tmp_path):
    with pytest.raises(RecipeError, match="not found"):
        recipe.build(tmp_path / "missing.recipe.json", log=None)
    bad = tmp_path / "bad.recipe.json"
    bad.write_text('{"assets": [\n  {"name": }\n]}')
    with pytest.raises(RecipeError, match=r"bad.recipe.json:2: not valid JSON"):
        recipe.build(bad, log=None)
    dup = _recipe(tmp_path, [{"name": "a", "generator": "sky", "out": "assets/s"},
                             {"name": "b", "generator": "sky", "out": "assets/s/"}], "dup.recipe.json")
    with pytest.raises(RecipeError, match="already used by 'a'"):
        recipe.build(dup, log=None)


def test_cli_subcommand(tmp_path, capsys):
    r = _recipe(tmp_path, _small())
    assert cli.main(["recipe", str(r)]) == 0
    assert "lights.pbrt" in capsys.readouterr().out
    assert cli.main(["recipe", str(r)]) == 0
    assert capsys.readouterr().out == ""                    # nothing written the second time
    bad = _recipe(tmp_path, [{"name": "x", "generator": "nosuch", "out": "assets/x"}], "bad.recipe.json")
    assert cli.main(["recipe", str(bad)]) == 2
    assert "unknown generator 'nosuch'" in capsys.readouterr().err


def test_scene_inputs_include_their_includes(tmp_path, monkeypatch):
    """An entry whose path parameter names a .pbrt file depends on the files it includes (e.g.
    grains on the camera), resolved against the recipe's folder, not the working folder."""
    (tmp_path / "cam.pbrt").write_text('LookAt 0 1 0  0 0 1  0 1 0\n')
    (tmp_path / "view.pbrt").write_text('Include "cam.pbrt"\nWorldBegin\n')
    (tmp_path / "sand.ply").write_text("not read: only hashed\n")
    r = _recipe(tmp_path, [{"name": "g", "generator": "grains", "out": "assets/g",
                            "params": {"surface": "sand.ply", "scene": "view.pbrt"}}])
    e = recipe.load(r)[0]
    monkeypatch.chdir(tmp_path.parent)
    before = recipe.entry_hash(e, tmp_path)
    assert recipe.entry_hash(e, tmp_path) == before
    (tmp_path / "cam.pbrt").write_text('LookAt 0 2 0  0 0 1  0 1 0\n')
    assert recipe.entry_hash(e, tmp_path) != before


def _entry(tmp: Path, generator: str, params: dict) -> recipe.Entry:
    return recipe.load(_recipe(tmp, [{"name": "e", "generator": generator, "out": "assets/e",
                                      "params": params}], f"{generator}.recipe.json"))[0]


def test_hash_covers_transitively_imported_sources(tmp_path, monkeypatch):
    """Editing a module the generator only reaches through another (here the renderer's vecmath,
    which the sky reaches through the renderer's equal-area map, and the meshing helpers, which
    the seashell imports and the sky does not) changes exactly the hashes of the entries using it."""
    sky = _entry(tmp_path, "sky", {"resolution": 8})
    shell = _entry(tmp_path, "seashell", {"per_turn": 8})
    copies = {}
    for name in ("renderer.vecmath", "assets_gen.core.meshing"):
        copies[name] = tmp_path / f"{name}.py"
        shutil.copy(recipe._module_file(name), copies[name])
    real = recipe._module_file
    monkeypatch.setattr(recipe, "_module_file", lambda name: copies.get(name) or real(name))
    assert {"renderer.vecmath", "renderer.sampling.equal_area"} <= set(recipe.module_sources("assets_gen.sky"))
    assert "assets_gen.core.meshing" not in recipe.module_sources("assets_gen.sky")
    assert "renderer.vecmath" not in recipe.module_sources("assets_gen.props.seashell")
    sky0, shell0 = recipe.entry_hash(sky, tmp_path), recipe.entry_hash(shell, tmp_path)

    copies["renderer.vecmath"].write_text(copies["renderer.vecmath"].read_text() + "\n# edited\n")
    assert recipe.entry_hash(sky, tmp_path) != sky0
    assert recipe.entry_hash(shell, tmp_path) == shell0
    sky1 = recipe.entry_hash(sky, tmp_path)

    copies["assets_gen.core.meshing"].write_text(copies["assets_gen.core.meshing"].read_text() + "\n# edited\n")
    assert recipe.entry_hash(shell, tmp_path) != shell0
    assert recipe.entry_hash(sky, tmp_path) == sky1


def test_builds_from_any_working_folder_without_changing_it(tmp_path, monkeypatch):
    """Relative paths resolve against the recipe's folder explicitly: building from elsewhere
    writes nothing there and leaves the working folder where it was."""
    (tmp_path / "scene").mkdir()
    r = _recipe(tmp_path / "scene", _small())
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    chdirs = []
    monkeypatch.setattr("os.chdir", lambda p: chdirs.append(p))
    assert all(x.built for x in recipe.build(r, log=None))
    assert chdirs == [] and not any(elsewhere.iterdir())
    lights = (tmp_path / "scene/assets/t/lights/lights.pbrt").read_text()
    assert '"string filename" ["../sky/sky_latlong.exr"]' in lights
    assert "from assets/t/sky/sky.json:" in lights               # as the recipe names it


def test_json_numbers_become_the_fields_types(tmp_path):
    """An integer given for a float parameter is recorded as a float, as the CLI would parse it,
    so the same recipe makes the same manifest whichever spelling it uses."""
    r = _recipe(tmp_path, [{"name": "u", "generator": "umbrella", "out": "assets/u", "params": {"tilt_deg": 8}},
                           {"name": "v", "generator": "umbrella", "out": "assets/v", "params": {"tilt_deg": 8.0}}])
    recipe.build(r, log=None)
    u, v = ((tmp_path / f"assets/{n}/umbrella.json").read_text() for n in "uv")
    assert u == v and '"tilt_deg": 8.0' in u
    assert (tmp_path / "assets/u/canopy.ply").read_bytes() == (tmp_path / "assets/v/canopy.ply").read_bytes()


def test_generator_reading_a_bad_scene_names_the_entry(tmp_path):
    """Errors from inside a generator (here: the grain generator parsing a broken camera scene)
    come out as one RecipeError naming the recipe and the entry."""
    (tmp_path / "view.pbrt").write_text('Camera "orthographic"\nWorldBegin\n')
    r = _recipe(tmp_path, [
        {"name": "dunes", "generator": "dunes", "out": "assets/d",
         "params": {"size_x": 2, "size_z": 2, "spacing": 0.25, "preview": False}},
        {"name": "grains", "generator": "grains", "out": "assets/g",
         "params": {"surface": "assets/d/dunes.ply", "scene": "view.pbrt", "count": 10, "preview": False}}])
    with pytest.raises(RecipeError, match=r"scene.recipe.json: asset 1 'grains' \(grains\): .*orthographic"):
        recipe.build(r, log=None)


def _levelled(tmp: Path, sky_levels: dict, declared: dict | None = None, name: str = "scene.recipe.json") -> Path:
    assets = _small(sky_res=32)
    assets[0]["levels"] = sky_levels
    doc: dict = {"recipe": 1, "assets": assets}
    if declared is not None:
        doc["levels"] = declared
    path = tmp / name
    path.write_text(json.dumps(doc, indent=1))
    return path


def test_level_overrides_apply_and_a_level_without_overrides_is_the_recipe(tmp_path):
    r = _levelled(tmp_path, {"draft": {"resolution": 8}, "final": {}},
                  {"draft": "small", "preview": "medium", "final": "as written"})
    assert [x.built for x in recipe.build(r, level="draft", log=None)] == [True, True, True]
    stamp = json.loads((tmp_path / "assets/t/sky" / recipe.STAMP).read_text())
    assert stamp["params"]["resolution"] == 8 and stamp["level"] == "draft"
    draft_sky = (tmp_path / "assets/t/sky/sky_latlong.exr").read_bytes()
    # the default build rebuilds the sky (and the lights that read it), not the glasses
    assert [x.built for x in recipe.build(r, log=None)] == [True, True, False]
    assert (tmp_path / "assets/t/sky/sky_latlong.exr").read_bytes() != draft_sky
    default = _snapshot(tmp_path / "assets")
    # "final" (no overrides) and "preview" (declared, no entry overrides it) are the recipe as written
    for level in ("final", "preview"):
        assert [x.built for x in recipe.build(r, level=level, log=None)] == [False, False, False]
    assert _snapshot(tmp_path / "assets") == default
    assert recipe.load(r, level="final")[0].params == recipe.load(r)[0].params


def test_level_build_is_deterministic(tmp_path):
    r = _levelled(tmp_path, {"draft": {"resolution": 8}})
    recipe.build(r, root=tmp_path / "a", level="draft", log=None)
    recipe.build(r, root=tmp_path / "b", level="draft", log=None)
    a = {k: v[1] for k, v in _snapshot(tmp_path / "a/assets").items()}
    b = {k: v[1] for k, v in _snapshot(tmp_path / "b/assets").items()}
    assert a == b and len(a) >= 8


def test_quick_is_a_level(tmp_path):
    """``quick`` as an entry key and as a level are the same overrides, and always known."""
    as_key = _small(sky_res=64)
    as_key[0]["quick"] = {"resolution": 8}
    r1 = _recipe(tmp_path, as_key, "key.recipe.json")
    r2 = _levelled(tmp_path, {"quick": {"resolution": 8}}, {"draft": "d"}, "level.recipe.json")
    for r in (r1, r2):
        assert recipe.load(r, level="quick")[0].params["resolution"] == 8
        assert recipe.build(r, root=tmp_path / r.stem, quick=True, log=None)[0].entry.params["resolution"] == 8
    with pytest.raises(RecipeError, match="give one"):
        recipe.build(r1, quick=True, level="draft", log=None)


@pytest.mark.parametrize("sky_levels, declared, level, message", [
    ({"draft": {"resolution": 8}}, None, "drat", "no detail level 'drat'; its levels: ['draft', 'quick']"),
    ({}, {"draft": "d", "final": "f"}, "fnal", "no detail level 'fnal'; its levels: ['draft', 'final', 'quick']"),
    ({"draft": {"no_such": 1}}, None, None, "asset 0 'sky': level 'draft': unknown parameter(s) ['no_such']"),
    ({"draft": {"resolution": "big"}}, None, "quick",
     "asset 0 'sky': level 'draft': parameter 'resolution': expected an integer, got 'big'"),
    ({"draft": {"seed": 3}}, None, None, 'give "seed" as a key of the entry, not in "levels.draft"'),
    ({"draft": [1]}, None, None, '"levels.draft" must be an object'),
    ({"preveiw": {"resolution": 8}}, {"preview": "p"}, None,
     "asset 0 'sky': level(s) ['preveiw'] not declared in the recipe's \"levels\": ['preview', 'quick']"),
])
def test_bad_level_gives_a_located_error(tmp_path, sky_levels, declared, level, message):
    """Every level of every entry is checked whichever is built, and the error names the recipe,
    the entry and the level."""
    r = _levelled(tmp_path, sky_levels, declared)
    with pytest.raises(RecipeError) as e:
        recipe.build(r, level=level, log=None)
    assert message in str(e.value) and "scene.recipe.json" in str(e.value) and "\n" not in str(e.value)
    assert not (tmp_path / "assets").exists()


def test_bad_level_declaration_and_double_quick(tmp_path):
    r = _levelled(tmp_path, {}, {"draft": 3})
    with pytest.raises(RecipeError, match='"levels" must be an object of level name: description'):
        recipe.load(r)
    assets = _small()
    assets[0].update({"quick": {"resolution": 8}, "levels": {"quick": {"resolution": 4}}})
    with pytest.raises(RecipeError, match=r"asset 0 'sky': \"quick\" given twice"):
        recipe.load(_recipe(tmp_path, assets))


def test_cli_level(tmp_path, capsys):
    r = _levelled(tmp_path, {"draft": {"resolution": 8}})
    assert cli.main(["recipe", str(r), "--level", "draft"]) == 0
    assert json.loads((tmp_path / "assets/t/sky" / recipe.STAMP).read_text())["params"]["resolution"] == 8
    capsys.readouterr()
    assert cli.main(["recipe", str(r), "--level", "nosuch"]) == 2
    assert "no detail level 'nosuch'" in capsys.readouterr().err


def test_beach_levels_all_validate():
    """Every named level of the beach recipe loads (validated parameters), and the level "final"
    is the recipe as written: the final frame's assets."""
    path = Path(__file__).resolve().parents[2] / "scenes" / "beach.recipe.json"
    declared = json.loads(path.read_text())["levels"]
    assert {"draft", "preview", "final"} <= set(declared)
    default = [e.params for e in recipe.load(path)]
    assert [e.params for e in recipe.load(path, level="final")] == default
    for level in declared:
        assert len(recipe.load(path, level=level)) == len(default)
    assert [e.params for e in recipe.load(path, level="draft")] != default
