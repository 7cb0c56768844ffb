"""The generator contract (assets_gen/core): every registered generator gets its CLI from its
parameter dataclass, with ``--seed`` and ``--out`` (and ``--preview`` where it has previews)."""
from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import pytest

from assets_gen.cli import build_parser, main
from assets_gen.core import GeneratorError, Params
from assets_gen.core.options import params_from_args
from assets_gen.core.params import kind
from assets_gen.registry import BY_NAME, GENERATORS

NAMES = [g.name for g in GENERATORS]


def test_registry_names_are_unique_and_in_the_cli():
    assert len(set(NAMES)) == len(NAMES) == 16
    sub = build_parser().parse_args(["recipe", "x.recipe.json"])
    assert sub.command == "recipe"


@pytest.mark.parametrize("name", NAMES)
def test_every_generator_gets_seed_out_and_its_parameters(tmp_path, name):
    gen = BY_NAME[name]
    parser = build_parser()
    args = parser.parse_args([name, "--seed", "3", "--out", str(tmp_path / "o")])
    assert args.seed == 3 and args.out == tmp_path / "o"
    assert hasattr(args, "preview") == gen.previews
    assert params_from_args(args, gen.params) == gen.params()          # defaults from the dataclass
    defaults = parser.parse_args([name])
    assert defaults.seed == 0 and defaults.out == Path("assets") / name
    for f in dataclasses.fields(gen.params):
        flag = "--" + f.name.replace("_", "-")
        if kind(f) is bool:
            continue
        if kind(f) is tuple:
            value, argv = tuple(float(v) + 1 for v in f.default), [str(float(v) + 1) for v in f.default]
        elif "choices" in f.metadata:
            value = f.metadata["choices"][-1]
            argv = [value]
        elif kind(f) is str:
            value, argv = "some/file", ["some/file"]
        else:
            value = kind(f)(f.default + 1)
            argv = [str(value)]
        parsed = params_from_args(parser.parse_args([name, flag, *argv]), gen.params)
        assert getattr(parsed, f.name) == value, flag


@pytest.mark.parametrize("name", NAMES)
def test_parameter_fields_are_typed_by_their_defaults(name):
    """The CLI and the recipe convert values by the default's type: the annotation must agree."""
    cls = BY_NAME[name].params
    assert issubclass(cls, Params) and dataclasses.is_dataclass(cls)
    for f in dataclasses.fields(cls):
        assert str(f.type).split("[")[0] == kind(f).__name__, (name, f.name, f.type)
        assert f.metadata["help"], (name, f.name)


def test_cli_runs_through_build_and_writes_the_manifest(tmp_path, capsys):
    out = tmp_path / "u"
    assert main(["umbrella", "--segments", "5", "--seed", "2", "--out", str(out)]) == 0
    printed = capsys.readouterr().out.split()
    assert printed == [str(out / n) for n in ("canopy.ply", "frame.ply", "umbrella.json")]
    manifest = json.loads((out / "umbrella.json").read_text())
    assert manifest["seed"] == 2 and manifest["params"]["segments"] == 5
    assert not [p for p in out.iterdir() if p.name.startswith(".staging")]


def test_from_dict_names_the_bad_key():
    cls = BY_NAME["umbrella"].params
    assert cls.from_dict({"radius": 1, "segments": 6}) == cls(radius=1.0, segments=6)
    with pytest.raises(GeneratorError, match=r"unknown parameter\(s\) \['radus'\]"):
        cls.from_dict({"radus": 1.0})
    with pytest.raises(GeneratorError, match="parameter 'segments': expected an integer, got 6.5"):
        cls.from_dict({"segments": 6.5})


def test_input_paths_resolve_against_the_base_and_the_manifest_keeps_them_as_given(tmp_path):
    dunes, ripples = BY_NAME["dunes"], BY_NAME["ripples"]
    dunes.build(dunes.params(size_x=1.0, size_z=1.0, spacing=0.05, dune_height=0.0), 0, tmp_path / "d",
                preview=False)
    p = ripples.params(dunes="d/dunes_height.exr", max_map_size=16)
    with pytest.raises(GeneratorError, match="not found"):
        ripples.build(p, 1, tmp_path / "r0")                    # the working folder has no d/
    written = ripples.build(p, 1, tmp_path / "r", base=tmp_path, preview=False)
    manifest = json.loads(Path(written[-1]).read_text())
    assert manifest["params"]["dunes"] == "d/dunes_height.exr"
    assert not (tmp_path / "r0").exists()
