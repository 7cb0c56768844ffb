"""Asset recipes: build every generated asset a scene needs, and only what is out of date.

A recipe is a JSON file beside a scene (``scenes/beach.recipe.json`` for ``scenes/beach.pbrt``)::

    {
      "recipe": 1,
      "assets": [
        {"name": "sky", "generator": "sky", "seed": 0, "out": "assets/beach/sky",
         "params": {"elevation_deg": 32, "resolution": 512}, "quick": {"resolution": 64}},
        {"name": "lights", "generator": "sky-lights", "out": "assets/beach/lights",
         "params": {"sky": "assets/beach/sky", "scale": 0.03}}
      ]
    }

``generator`` is an ``assets-gen`` subcommand (or one of the recipe's own small generators in
:data:`BUILTINS`); ``params`` are its options with ``_`` or ``-`` spelling (``true``/``false``
for on/off switches, lists for multi-value options); ``seed`` defaults to 0; ``out`` is the
output folder, relative to the recipe's folder and inside its ``assets/`` (git-ignored).
Entries build in order, with the recipe's folder as the working directory, so a parameter that
names a file written by an earlier entry (``"dunes": "assets/beach/dunes/dunes_height.exr"``)
just works. ``quick`` holds parameter overrides for fast, small builds (tests, previews).

An entry is rebuilt only when its stamp (``<out>/.recipe-stamp.json``) is missing, any output
the stamp lists is missing, or the stamp's hash differs from the entry's hash now. The hash
covers the generator, its effective parameters, seed and output folder, the ``assets_gen``
version, the source of the generator's module, and the bytes of every input file a parameter
names; so editing the recipe, a generator, or an upstream asset rebuilds exactly what depends
on it. Generators are pure functions of (parameters, seed), so a rebuild gives the same bytes.

    assets-gen recipe scenes/beach.recipe.json [--force] [--quick] [--only NAME ...]
"""
from __future__ import annotations

import argparse
import contextlib
import functools
import hashlib
import io
import json
import os
import re
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterator

from assets_gen import __version__
from assets_gen.common import GeneratorError, require, staged_output

try:
    from renderer.errors import RenderError as _RenderError
except ImportError:                                   # the generators also work without the renderer
    class _RenderError(Exception):  # type: ignore[no-redef]
        pass

RECIPE_FORMAT = 1
STAMP = ".recipe-stamp.json"
_ENTRY_KEYS = {"name", "generator", "seed", "out", "params", "quick", "comment"}


class RecipeError(GeneratorError):
    """A bad recipe or a failed entry; the message names the recipe file and the entry."""


@dataclass
class Entry:
    """One asset of a recipe, validated; ``params`` already has any ``quick`` overrides applied."""
    name: str
    generator: str
    seed: int
    out: str                      # relative to the recipe's folder, inside assets/
    params: dict[str, Any]
    index: int

    def label(self) -> str:
        return f"asset {self.index} {self.name!r} ({self.generator})"


@dataclass
class Result:
    entry: Entry
    built: bool                   # False: skipped, already up to date
    outputs: list[Path] = field(default_factory=list)


# --------------------------------------------------------------------------------------------
# Built-in generators: small steps that turn generated assets into scene text
# --------------------------------------------------------------------------------------------

def _fmt(v: float) -> str:
    return f"{float(v):.6g}"


def sky_lights(stage: Path, params: dict[str, Any], seed: int, out: Path) -> list[str]:
    """``lights.pbrt``: the generated sky as an ``infinite`` light plus the matching sun as a
    ``distant`` light with the sun's 0.27 degree disc, both multiplied by ``scale``.

    Parameters: ``sky`` (the ``assets-gen sky`` output folder), ``scale`` (one factor for sky and
    sun: the scene's exposure, since the sky is in kcd/m^2), ``layout`` (``latlong`` or
    ``equalarea``), ``sun`` (``rgb``: the sun's RGB irradiance from ``sky.json``; ``blackbody``:
    ``"blackbody L" [temperature]`` scaled to the same illuminance) and ``temperature`` (K).
    The distant light's ``L`` is irradiance at normal incidence (as in pbrt), so it takes
    ``sun.rgb_irradiance`` from ``sky.json``, not the disc's radiance.
    """
    allowed = {"sky", "scale", "layout", "sun", "temperature"}
    unknown = sorted(set(params) - allowed)
    require(not unknown, f"sky-lights: unknown parameter(s) {unknown}; known: {sorted(allowed)}")
    sky_dir = Path(str(params.get("sky", "")))
    meta_path = sky_dir / "sky.json"
    require(meta_path.is_file(), f"sky-lights: {meta_path} not found (build the sky entry first)")
    scale = float(params.get("scale", 1.0))
    require(scale > 0, "sky-lights: scale must be positive")
    layout = str(params.get("layout", "latlong"))
    require(layout in ("latlong", "equalarea"), "sky-lights: layout must be latlong or equalarea")
    sun_kind = str(params.get("sun", "rgb"))
    require(sun_kind in ("rgb", "blackbody"), "sky-lights: sun must be rgb or blackbody")
    temperature = float(params.get("temperature", 5800.0))
    require(1000 <= temperature <= 40000, "sky-lights: temperature must be 1000..40000 K")

    meta = json.loads(meta_path.read_text())
    sun = meta["params"]["sun"]
    env = sky_dir / ("sky_latlong.exr" if layout == "latlong" else "sky_equalarea.exr")
    require(env.is_file(), f"sky-lights: {env} not found (the sky entry's layout must include {layout})")
    d = sun["direction_world_y_up"]
    lines = [
        f"# Written by `assets-gen recipe` (sky-lights) from {meta_path.as_posix()}: do not edit.",
        f"# Sun elevation {_fmt(meta['params']['elevation_deg'])} deg, azimuth "
        f"{_fmt(meta['params']['azimuth_deg'])} deg, turbidity {_fmt(meta['params']['turbidity'])};",
        f"# sky and sun share the exposure scale {_fmt(scale)} (the map is in kcd/m^2).",
        "AttributeBegin",
        "  Rotate -90 1 0 0   # the sky's light frame is +z up; this scene is +y up",
        f'  LightSource "infinite" "string filename" ["{os.path.relpath(env, out).replace(os.sep, "/")}"]'
        f' "float scale" [{_fmt(scale)}]',
        "AttributeEnd",
    ]
    sun_line = (f'LightSource "distant" "point3 from" [{_fmt(d[0])} {_fmt(d[1])} {_fmt(d[2])}] '
                f'"point3 to" [0 0 0]')
    radius = _fmt(sun.get("angular_radius_deg", 0.27))
    if sun_kind == "rgb":
        irr = [v * scale for v in sun["rgb_irradiance"]]
        lines.append(f'{sun_line}\n    "rgb L" [{" ".join(_fmt(v) for v in irr)}] '
                     f'"float angularradius" [{radius}]')
    else:   # a blackbody L is normalised to luminance 1: scale carries the illuminance (klx)
        klx = float(sun["normal_illuminance_lux"]) / 1000.0
        lines.append(f'{sun_line}\n    "blackbody L" [{_fmt(temperature)}] "float scale" [{_fmt(klx * scale)}] '
                     f'"float angularradius" [{radius}]')
    (stage / "lights.pbrt").write_text("\n".join(lines) + "\n")
    return ["lights.pbrt"]


#: Recipe-only generators: name -> function(staging folder, params, seed, final output folder)
#: -> names written (paths written into files should be relative to the final folder).
BUILTINS: dict[str, Callable[[Path, dict[str, Any], int, Path], list[str]]] = {"sky-lights": sky_lights}


# --------------------------------------------------------------------------------------------
# Reading a recipe
# --------------------------------------------------------------------------------------------

def load(path: str | Path, quick: bool = False) -> list[Entry]:
    """The validated entries of the recipe at ``path`` (``quick``: with their quick overrides)."""
    path = Path(path)
    if not path.is_file():
        raise RecipeError(f"recipe {path} not found")
    try:
        doc = json.loads(path.read_text())
    except json.JSONDecodeError as e:
        raise RecipeError(f"{path}:{e.lineno}: not valid JSON: {e.msg}") from None

    def bad(msg: str) -> RecipeError:
        return RecipeError(f"{path}: {msg}")

    if not isinstance(doc, dict) or not isinstance(doc.get("assets"), list):
        raise bad('expected an object with an "assets" list')
    if doc.get("recipe", RECIPE_FORMAT) != RECIPE_FORMAT:
        raise bad(f'unsupported "recipe" format {doc.get("recipe")!r} (this version reads {RECIPE_FORMAT})')
    known = known_generators()
    entries: list[Entry] = []
    names: set[str] = set()
    outs: dict[str, str] = {}
    for i, raw in enumerate(doc["assets"]):
        where = f"asset {i}" + (f" {raw.get('name')!r}" if isinstance(raw, dict) and "name" in raw else "")
        if not isinstance(raw, dict):
            raise bad(f"{where}: expected an object")
        unknown = sorted(set(raw) - _ENTRY_KEYS)
        if unknown:
            raise bad(f"{where}: unknown key(s) {unknown}; allowed: {sorted(_ENTRY_KEYS)}")
        for key in ("name", "generator", "out"):
            if not isinstance(raw.get(key), str) or not raw[key]:
                raise bad(f'{where}: "{key}" must be a non-empty string')
        name, gen, out = raw["name"], raw["generator"], raw["out"]
        if name in names:
            raise bad(f"{where}: duplicate name {name!r}")
        if gen not in known:
            raise bad(f"{where}: unknown generator {gen!r}; known: {', '.join(sorted(known))}")
        seed = raw.get("seed", 0)
        if not isinstance(seed, int) or isinstance(seed, bool) or seed < 0:
            raise bad(f'{where}: "seed" must be a non-negative integer')
        norm = os.path.normpath(out).replace(os.sep, "/")
        if Path(out).is_absolute() or not norm.startswith("assets/") or ".." in Path(norm).parts:
            raise bad(f'{where}: "out" must be a folder inside assets/ beside the recipe, got {out!r}')
        if norm in outs:
            raise bad(f"{where}: output folder {norm!r} is already used by {outs[norm]!r} "
                      "(each asset needs its own folder: manifests would collide)")
        params = raw.get("params", {})
        overrides = raw.get("quick", {})
        for key, val in (("params", params), ("quick", overrides)):
            if not isinstance(val, dict):
                raise bad(f'{where}: "{key}" must be an object of option: value')
            for k in val:
                if k in ("seed", "out"):
                    raise bad(f'{where}: give "{k}" as a key of the entry, not in "{key}"')
        eff = {k.replace("-", "_"): v for k, v in params.items()}
        if quick:
            eff.update({k.replace("-", "_"): v for k, v in overrides.items()})
        names.add(name)
        outs[norm] = name
        entries.append(Entry(name, gen, seed, norm, eff, i))
    return entries


def known_generators() -> set[str]:
    return set(_subparsers().choices) | set(BUILTINS)


@functools.lru_cache(maxsize=None)
def _subparsers() -> argparse._SubParsersAction:
    from assets_gen import cli

    parser = cli.build_parser()
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return action
    raise RecipeError("assets-gen has no subcommands")


# --------------------------------------------------------------------------------------------
# Building
# --------------------------------------------------------------------------------------------

def to_argv(params: dict[str, Any]) -> list[str]:
    """Recipe parameters as command-line options: ``True``/``False`` become ``--x``/``--no-x``,
    lists become several values, ``None`` leaves the option at its default."""
    argv: list[str] = []
    for key, val in params.items():
        flag = "--" + key.replace("_", "-")
        if val is None:
            continue
        if isinstance(val, bool):
            argv.append(flag if val else "--no-" + key.replace("_", "-"))
        elif isinstance(val, (list, tuple)):
            argv += [flag, *(str(v) for v in val)]
        elif isinstance(val, (dict,)):
            raise RecipeError(f"parameter {key!r}: nested objects are not options")
        else:
            argv += [flag, str(val)]
    return argv


@contextlib.contextmanager
def _working_dir(path: Path) -> Iterator[None]:
    old = Path.cwd()
    os.chdir(path)
    try:
        yield
    finally:
        os.chdir(old)


def _sha256_file(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


_INCLUDE = re.compile(r'^\s*(?:Include|Import)\s+"([^"]+)"', re.MULTILINE)


def _with_includes(path: Path, seen: set[Path]) -> list[Path]:
    """``path`` and, for a .pbrt file, every file it includes (recursively): a generator that reads
    a scene's camera depends on the file that holds the camera."""
    if path in seen:
        return []
    seen.add(path)
    found = [path]
    if path.suffix == ".pbrt":
        for name in _INCLUDE.findall(path.read_text(errors="replace")):
            inc = Path(os.path.normpath(path.parent / name))
            if inc.is_file():
                found += _with_includes(inc, seen)
    return found


def _input_files(params: dict[str, Any]) -> list[Path]:
    """Files (relative to the working directory) that parameter values name: files, the files in
    named folders, and the files a named .pbrt scene includes."""
    found: list[Path] = []
    seen: set[Path] = set()
    for v in params.values():
        for s in (v if isinstance(v, (list, tuple)) else [v]):
            if isinstance(s, str) and s and len(s) < 1024:
                p = Path(s)
                if p.is_file():
                    found += _with_includes(p, seen)
                elif p.is_dir():
                    found += sorted(q for q in p.rglob("*") if q.is_file() and q.name != STAMP)
    return found


def entry_hash(entry: Entry) -> str:
    """What decides whether an entry's outputs are current (run in the recipe's folder)."""
    import inspect

    if entry.generator in BUILTINS:
        source = inspect.getsource(BUILTINS[entry.generator])
    else:
        run = _subparsers().choices[entry.generator].get_default("run")
        module = sys.modules.get(getattr(run, "__module__", ""), None)
        source = Path(module.__file__).read_text() if module and getattr(module, "__file__", None) else ""
    doc = {"generator": entry.generator, "params": entry.params, "seed": entry.seed, "out": entry.out,
           "version": __version__, "source": hashlib.sha256(source.encode()).hexdigest(),
           "inputs": {p.as_posix(): _sha256_file(p) for p in _input_files(entry.params)}}
    return hashlib.sha256(json.dumps(doc, sort_keys=True, default=str).encode()).hexdigest()


def read_stamp(out: Path) -> dict[str, Any] | None:
    try:
        return json.loads((out / STAMP).read_text())
    except (OSError, json.JSONDecodeError):
        return None


def is_current(entry: Entry, digest: str) -> bool:
    stamp = read_stamp(Path(entry.out))
    return (stamp is not None and stamp.get("hash") == digest
            and all((Path(entry.out) / n).is_file() for n in stamp.get("outputs", [])))


def run_generator(entry: Entry) -> list[str]:
    """Run one entry's generator in-process; return the names it wrote inside ``entry.out``."""
    out = Path(entry.out)
    if entry.generator in BUILTINS:
        with staged_output(out) as stage:
            names = BUILTINS[entry.generator](stage, entry.params, entry.seed, out)
        return sorted(names)
    sub = _subparsers()
    argv = [entry.generator, *to_argv(entry.params), "--seed", str(entry.seed), "--out", entry.out]
    parser = sub.choices[entry.generator]
    err = io.StringIO()
    try:
        with contextlib.redirect_stderr(err):
            args = parser.parse_args(argv[1:])
    except SystemExit:
        lines = [ln for ln in err.getvalue().strip().splitlines() if ln.strip()]
        msg = lines[-1] if lines else "bad parameters"
        msg = msg.split("error: ", 1)[-1]
        raise GeneratorError(f"bad parameter: {msg} (options: {' '.join(argv[1:])})") from None
    written = args.run(args)
    names = []
    for w in written:
        rel = os.path.relpath(Path(w).resolve(), out.resolve())
        require(not rel.startswith(".."), f"generator wrote {w} outside its output folder")
        names.append(rel.replace(os.sep, "/"))
    return sorted(names)


def build(recipe: str | Path, *, root: str | Path | None = None, force: bool = False, quick: bool = False,
          only: list[str] | None = None, log: Callable[[str], None] | None = print) -> list[Result]:
    """Build the recipe's out-of-date entries, in order. ``root``: the folder that ``out`` and
    relative parameters resolve against (default: the recipe's folder; tests point it elsewhere).
    ``force`` rebuilds everything, ``quick`` applies each entry's quick overrides, ``only``
    restricts the build to the named entries. Raises :class:`RecipeError` naming the entry."""
    recipe = Path(recipe).resolve() if Path(recipe).exists() else Path(recipe)
    entries = load(recipe, quick=quick)
    if only:
        missing = sorted(set(only) - {e.name for e in entries})
        if missing:
            raise RecipeError(f"{recipe}: no asset named {', '.join(missing)}")
        entries = [e for e in entries if e.name in only]
    root = Path(root).resolve() if root is not None else recipe.parent
    root.mkdir(parents=True, exist_ok=True)
    results: list[Result] = []
    with _working_dir(root):
        for e in entries:
            try:
                digest = entry_hash(e)
                if not force and is_current(e, digest):
                    results.append(Result(e, False, [root / e.out / n for n in read_stamp(Path(e.out))["outputs"]]))
                    if log:
                        log(f"recipe: {e.name}: up to date ({e.out})")
                    continue
                if log:
                    log(f"recipe: {e.name}: building with {e.generator} ...")
                out = Path(e.out)
                old = read_stamp(out)
                (out / STAMP).unlink(missing_ok=True)      # an interrupted build is rebuilt next time
                names = run_generator(e)
                for stale in (old or {}).get("outputs", []):   # outputs the new parameters no longer make
                    if stale not in names:
                        (out / stale).unlink(missing_ok=True)
                stamp = {"recipe": recipe.name, "name": e.name, "generator": e.generator, "seed": e.seed,
                         "params": e.params, "hash": digest, "outputs": names}
                (out / STAMP).write_text(json.dumps(stamp, indent=2, sort_keys=True, default=str) + "\n")
                results.append(Result(e, True, [root / e.out / n for n in names]))
            except GeneratorError as err:
                raise RecipeError(f"{recipe.name}: {e.label()}: {err}") from None
            except (OSError, _RenderError) as err:      # e.g. a scene the grain generator reads
                raise RecipeError(f"{recipe.name}: {e.label()}: {type(err).__name__}: {err}") from err
    return results


def recipe_for(scene: str | Path) -> Path | None:
    """``<scene>.recipe.json`` beside a ``.pbrt`` scene, if there is one."""
    p = Path(scene)
    cand = p.with_name(p.stem + ".recipe.json")
    return cand if cand.is_file() else None


# --------------------------------------------------------------------------------------------
# CLI: `assets-gen recipe FILE` (also `python -m assets_gen recipe FILE`)
# --------------------------------------------------------------------------------------------

def _add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("recipes", nargs="+", type=Path, metavar="RECIPE",
                   help="recipe JSON file(s), or a .pbrt scene whose <scene>.recipe.json to build "
                        "(a scene without one is skipped)")
    p.add_argument("--force", action="store_true", help="rebuild every entry")
    p.add_argument("--quick", action="store_true", help="apply each entry's quick (small, fast) overrides")
    p.add_argument("--only", action="append", metavar="NAME", help="build only this entry (repeatable)")


def _run(args: argparse.Namespace) -> list[str]:
    written: list[str] = []
    for r in args.recipes:
        if r.suffix == ".pbrt":
            found = recipe_for(r)
            if found is None:
                continue
            r = found
        for res in build(r, force=args.force, quick=args.quick, only=args.only,
                         log=lambda m: print(m, file=sys.stderr)):
            if res.built:
                written += [str(p) for p in res.outputs]
    return written


def register(subparsers: Any) -> None:
    p = subparsers.add_parser("recipe", help=__doc__.splitlines()[0], description=__doc__,
                              formatter_class=argparse.RawDescriptionHelpFormatter)
    _add_arguments(p)
    p.set_defaults(run=_run)
