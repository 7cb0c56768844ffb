"""Asset recipes: build every generated asset a scene needs, and only what is out of date.

A recipe is a JSON file beside a scene (``scenes/beach.recipe.json`` for ``scenes/beach.pbrt``)::

    {
      "recipe": 1,
      "assets": [
        {"name": "sky", "generator": "sky", "seed": 0, "out": "assets/beach/sky",
         "params": {"elevation_deg": 32, "resolution": 512}, "levels": {"quick": {"resolution": 64}}},
        {"name": "lights", "generator": "sky-lights", "out": "assets/beach/lights",
         "params": {"sky": "assets/beach/sky", "scale": 0.03}}
      ]
    }

``generator`` is an ``assets-gen`` subcommand; ``params`` are the fields of its parameter
dataclass (``_`` or ``-`` spelling; JSON numbers, strings, ``true``/``false`` and lists as the
field's type), plus ``preview`` for generators that write PNG previews; ``seed`` defaults to 0;
``out`` is the output folder, relative to the recipe's folder and inside its ``assets/``
(git-ignored). Entries build in order, each through its generator's ``build`` with the recipe's
folder as the base for relative input paths, so a parameter that names a file written by an
earlier entry (``"dunes": "assets/beach/dunes/dunes_height.exr"``) just works.

Detail levels: an entry's ``levels`` maps a level name to parameter overrides, applied over
``params`` when the recipe is built ``--level NAME`` (an entry without overrides for that level
builds as written, so ``"final": {}`` means the params themselves). A recipe may declare its
levels at the top, ``"levels": {"draft": "what it is for", ...}``; then every entry's level names
must be declared ones. The level ``quick`` (small, fast builds for tests) is always known, and an
entry's ``"quick": {...}`` is shorthand for ``"levels": {"quick": {...}}``. Every level of every
entry is validated on load, whichever is built. The level's name is not part of the rebuild hash,
only the parameters it gives, so a level whose parameters equal the defaults reuses their build.

An entry is rebuilt only when its stamp (``<out>/.recipe-stamp.json``) is missing, any output
the stamp lists is missing, or the stamp's hash differs from the entry's hash now. The hash
covers the generator, its effective parameters, seed and output folder, the ``assets_gen``
version, the source of every ``assets_gen`` and ``renderer`` module the generator imports
(transitively, at module level or inside functions), and the bytes of every input file its path
parameters name; so editing the recipe, a generator, a helper it uses, or an upstream asset
rebuilds exactly what depends on it. Generators are pure functions of (parameters, seed), so a
rebuild gives the same bytes.

    assets-gen recipe scenes/beach.recipe.json [--force] [--level NAME | --quick] [--only NAME ...]
"""
from __future__ import annotations

import argparse
import ast
import hashlib
import importlib.util
import json
import os
import re
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

from assets_gen import __version__, registry
from assets_gen.core import GeneratorError, Params
from renderer.errors import RenderError

RECIPE_FORMAT = 1
STAMP = ".recipe-stamp.json"
_ENTRY_KEYS = {"name", "generator", "seed", "out", "params", "levels", "quick", "comment"}
#: The level every recipe has, declared or not: small, fast builds for tests.
QUICK = "quick"
#: Packages whose modules' sources a rebuild hash covers.
_HASHED_PACKAGES = ("assets_gen", "renderer")


class RecipeError(GeneratorError):
    """A bad recipe or a failed entry; the message names the recipe file and the entry."""


@dataclass
class Entry:
    """One asset of a recipe, validated; ``params`` (as written, keys with ``_``) already has any
    level's overrides applied, and ``values`` is the generator's parameter dataclass made from it."""
    name: str
    generator: str
    seed: int
    out: str                      # relative to the recipe's folder, inside assets/
    params: dict[str, Any]
    index: int
    values: Params
    preview: bool = True
    level: str | None = None      # the detail level whose overrides these are; None: as written

    def label(self) -> str:
        return f"asset {self.index} {self.name!r} ({self.generator})"


@dataclass
class Result:
    entry: Entry
    built: bool                   # False: skipped, already up to date
    outputs: list[Path] = field(default_factory=list)


# --------------------------------------------------------------------------------------------
# Reading a recipe
# --------------------------------------------------------------------------------------------

def load(path: str | Path, level: str | None = None) -> list[Entry]:
    """The validated entries of the recipe at ``path``, with the overrides of ``level`` (None: as written)."""
    path = Path(path)
    if not path.is_file():
        raise RecipeError(f"recipe {path} not found")
    try:
        doc = json.loads(path.read_bytes().decode("utf-8"))
    except UnicodeDecodeError as e:
        raise RecipeError(f"{path}: not UTF-8 text (byte {e.start})") from None
    except json.JSONDecodeError as e:
        raise RecipeError(f"{path}:{e.lineno}: not valid JSON: {e.msg}") from None
    except (ValueError, RecursionError) as e:   # a number over Python's digit limit; nesting too deep
        raise RecipeError(f"{path}: not a usable JSON document: {e}") from None
    if not isinstance(doc, dict) or not isinstance(doc.get("assets"), list):
        raise RecipeError(f'{path}: expected an object with an "assets" list')
    if doc.get("recipe", RECIPE_FORMAT) != RECIPE_FORMAT:
        raise RecipeError(f'{path}: unsupported "recipe" format {doc.get("recipe")!r} '
                          f"(this version reads {RECIPE_FORMAT})")
    declared = _declared_levels(doc, path)
    entries: list[Entry] = []
    outs: dict[str, str] = {}
    used: set[str] = {QUICK}
    for i, raw in enumerate(doc["assets"]):
        where = f"asset {i}" + (f" {raw.get('name')!r}" if isinstance(raw, dict) and "name" in raw else "")
        try:
            entry, names = _entry(raw, i, level, {e.name for e in entries}, declared)
        except GeneratorError as e:
            raise RecipeError(f"{path}: {where}: {e}") from None
        used |= names
        if entry.out in outs:
            raise RecipeError(f"{path}: {where}: output folder {entry.out!r} is already used by "
                              f"{outs[entry.out]!r} (each asset needs its own folder: manifests would collide)")
        outs[entry.out] = entry.name
        entries.append(entry)
    known = used if declared is None else declared | {QUICK}
    if level is not None and level not in known:
        raise RecipeError(f"{path}: no detail level {level!r}; its levels: {sorted(known)}")
    return entries


def _declared_levels(doc: dict, path: Path) -> set[str] | None:
    """The level names the recipe declares at its top, or None when it declares none."""
    if "levels" not in doc:
        return None
    decl = doc["levels"]
    if not isinstance(decl, dict) or not all(isinstance(v, str) for v in decl.values()):
        raise RecipeError(f'{path}: "levels" must be an object of level name: description')
    return set(decl)


def _entry(raw: Any, index: int, level: str | None, names: set[str],
           declared: set[str] | None) -> tuple[Entry, set[str]]:
    """One entry of a recipe and the level names it uses, or :class:`GeneratorError` saying what
    is wrong with it."""
    """One entry of a recipe, or :class:`GeneratorError` saying what is wrong with it."""
    if not isinstance(raw, dict):
        raise GeneratorError("expected an object")
    unknown = sorted(set(raw) - _ENTRY_KEYS)
    if unknown:
        raise GeneratorError(f"unknown key(s) {unknown}; allowed: {sorted(_ENTRY_KEYS)}")
    for key in ("name", "generator", "out"):
        if not isinstance(raw.get(key), str) or not raw[key]:
            raise GeneratorError(f'"{key}" must be a non-empty string')
    name, out = raw["name"], raw["out"]
    if name in names:
        raise GeneratorError(f"duplicate name {name!r}")
    gen = registry.get(raw["generator"])
    seed = raw.get("seed", 0)
    if not isinstance(seed, int) or isinstance(seed, bool) or seed < 0:
        raise GeneratorError('"seed" must be a non-negative integer')
    norm = os.path.normpath(out).replace(os.sep, "/")
    if Path(out).is_absolute() or not norm.startswith("assets/") or ".." in Path(norm).parts:
        raise GeneratorError(f'"out" must be a folder inside assets/ beside the recipe, got {out!r}')
    params = raw.get("params", {})
    overrides = _entry_levels(raw, declared)
    for key, val in (("params", params), *((f"levels.{k}", v) for k, v in overrides.items())):
        if not isinstance(val, dict):
            raise GeneratorError(f'"{key}" must be an object of parameter: value')
        for k in val:
            if k in ("seed", "out"):
                raise GeneratorError(f'give "{k}" as a key of the entry, not in "{key}"')
    base = {k.replace("-", "_"): v for k, v in params.items()}
    made: dict[str | None, Entry] = {}
    for lvl in [None, *overrides]:            # every level is checked, the one asked for is kept
        eff = {**base, **{k.replace("-", "_"): v for k, v in overrides.get(lvl, {}).items()}}
        try:
            values = {k: v for k, v in eff.items() if not (gen.previews and k == "preview")}
            preview = eff.get("preview", True) if gen.previews else True
            if not isinstance(preview, bool):
                raise GeneratorError(f"parameter 'preview': expected true or false, got {preview!r}")
            made[lvl] = Entry(name, gen.name, seed, norm, eff, index, gen.params.from_dict(values), preview, lvl)
        except GeneratorError as e:
            raise GeneratorError(f"level {lvl!r}: {e}" if lvl is not None else str(e)) from None
    return made[level if level in overrides else None], set(overrides)


def _entry_levels(raw: dict, declared: set[str] | None) -> dict[str, Any]:
    """An entry's level overrides by level name (``quick`` folded in), names checked."""
    found = raw.get("levels", {})
    if not isinstance(found, dict):
        raise GeneratorError('"levels" must be an object of level name: {parameter: value}')
    if "quick" in raw:
        if QUICK in found:
            raise GeneratorError('"quick" given twice: as a key of the entry and in "levels"')
        found = {**found, QUICK: raw["quick"]}
    if declared is not None:
        stray = sorted(set(found) - declared - {QUICK})
        if stray:
            raise GeneratorError(f"level(s) {stray} not declared in the recipe's \"levels\": "
                                 f"{sorted(declared | {QUICK})}")
    return found


# --------------------------------------------------------------------------------------------
# What an entry depends on
# --------------------------------------------------------------------------------------------

def _module_file(name: str) -> Path | None:
    """The source file of module ``name`` of a hashed package, or None if there is none (the name
    of a class, say). Found on disk, without importing anything."""
    top, *rest = name.split(".")
    spec = importlib.util.find_spec(top)
    if spec is None or not spec.submodule_search_locations:
        return None
    for root in spec.submodule_search_locations:
        for path in (Path(root, *rest).with_suffix(".py") if rest else None, Path(root, *rest, "__init__.py")):
            if path is not None and path.is_file():
                return path
    return None


def _imported(tree: ast.Module, module: str, is_package: bool) -> set[str]:
    """Names of the hashed-package modules (and their parent packages) a module imports: anywhere in
    a module, but only at the top level of a package's ``__init__``, whose function-level imports
    are lazy attribute hooks (``renderer.render``) that importing a submodule never runs."""
    found: set[str] = set()
    top = [n for n in tree.body if not isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef))]
    for node in (n for t in top for n in ast.walk(t)) if is_package else ast.walk(tree):
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parts = module.split(".") if is_package else module.split(".")[:-1]
                base = ".".join(parts[:len(parts) - node.level + 1] + ([base] if base else []))
            names = [base] + [f"{base}.{a.name}" for a in node.names]
        else:
            continue
        for n in names:
            parts = n.split(".")
            if parts[0] in _HASHED_PACKAGES:
                found.update(".".join(parts[:k]) for k in range(1, len(parts) + 1))
    return found


def module_sources(module: str, memo: dict[str, tuple[str, set[str]]] | None = None) -> dict[str, str]:
    """sha256 of the source of ``module`` and of every module of :data:`_HASHED_PACKAGES` it imports,
    transitively, found by reading the files (so imports inside functions count too)."""
    memo = {} if memo is None else memo
    digests: dict[str, str] = {}
    todo = [module]
    while todo:
        name = todo.pop()
        if name in digests:
            continue
        if name not in memo:
            path = _module_file(name)
            if path is None:
                memo[name] = ("", set())
            else:
                source = path.read_bytes()
                memo[name] = (hashlib.sha256(source).hexdigest(),
                              _imported(ast.parse(source), name, path.name == "__init__.py"))
        digest, imports = memo[name]
        if digest:
            digests[name] = digest
            todo += sorted(imports - set(digests))
    return digests


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


def input_files(values: Params, base: Path) -> list[Path]:
    """The files that the path parameters name (relative ones against ``base``): files, the files
    in named folders, and the files a named .pbrt scene includes."""
    found: list[Path] = []
    seen: set[Path] = set()
    for v in values.input_paths():
        p = Path(base) / v
        if p.is_file():
            found += _with_includes(p, seen)
        elif p.is_dir():
            found += sorted(q for q in p.rglob("*") if q.is_file() and q.name != STAMP)
    return found


def _sha256_file(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def _key(path: Path, base: Path) -> str:
    """A path for the hash that does not depend on where the recipe's folder is."""
    try:
        return path.resolve().relative_to(base.resolve()).as_posix()
    except ValueError:
        return path.resolve().as_posix()


def entry_hash(entry: Entry, base: str | Path, memo: dict[str, tuple[str, set[str]]] | None = None) -> str:
    """What decides whether an entry's outputs are current (``base``: the recipe's folder)."""
    base = Path(base)
    doc = {"generator": entry.generator, "params": entry.params, "seed": entry.seed, "out": entry.out,
           "version": __version__, "sources": module_sources(registry.get(entry.generator).module, memo),
           "inputs": {_key(p, base): _sha256_file(p) for p in input_files(entry.values, base)}}
    return hashlib.sha256(json.dumps(doc, sort_keys=True, default=str).encode()).hexdigest()


# --------------------------------------------------------------------------------------------
# Building
# --------------------------------------------------------------------------------------------

def read_stamp(out: Path) -> dict[str, Any] | None:
    try:
        return json.loads((out / STAMP).read_text())
    except (OSError, json.JSONDecodeError):
        return None


def is_current(out: Path, digest: str) -> bool:
    stamp = read_stamp(out)
    return (stamp is not None and stamp.get("hash") == digest
            and all((out / n).is_file() for n in stamp.get("outputs", [])))


def build(recipe: str | Path, *, root: str | Path | None = None, force: bool = False, quick: bool = False,
          level: str | None = None, only: list[str] | None = None,
          log: Callable[[str], None] | None = print) -> list[Result]:
    """Build the recipe's out-of-date entries, in order. ``root``: the folder that ``out`` and
    relative parameters resolve against (default: the recipe's folder; tests point it elsewhere).
    ``force`` rebuilds everything, ``level`` applies each entry's overrides for that detail level
    (``quick``: the same as ``level="quick"``), ``only`` restricts the build to the named entries.
    Raises :class:`RecipeError` naming the entry."""
    recipe = Path(recipe).resolve() if Path(recipe).exists() else Path(recipe)
    if quick and level not in (None, QUICK):
        raise RecipeError(f"{recipe}: quick and level {level!r} both asked for; give one")
    entries = load(recipe, level=QUICK if quick else level)
    if only:
        missing = sorted(set(only) - {e.name for e in entries})
        if missing:
            raise RecipeError(f"{recipe}: no asset named {', '.join(missing)}")
        entries = [e for e in entries if e.name in only]
    root = Path(root).resolve() if root is not None else recipe.parent
    root.mkdir(parents=True, exist_ok=True)
    memo: dict[str, tuple[str, set[str]]] = {}
    results: list[Result] = []
    for e in entries:
        out = root / e.out
        try:
            digest = entry_hash(e, root, memo)
            if not force and is_current(out, digest):
                results.append(Result(e, False, [out / n for n in read_stamp(out)["outputs"]]))
                if log:
                    log(f"recipe: {e.name}: up to date ({e.out})")
                continue
            if log:
                log(f"recipe: {e.name}: building with {e.generator} ...")
            old = read_stamp(out)
            (out / STAMP).unlink(missing_ok=True)          # an interrupted build is rebuilt next time
            written = registry.get(e.generator).build(e.values, e.seed, out, base=root, preview=e.preview)
            names = sorted(Path(w).relative_to(out).as_posix() for w in written)
            for stale in (old or {}).get("outputs", []):   # outputs the new parameters no longer make
                if stale not in names:
                    (out / stale).unlink(missing_ok=True)
            stamp = {"recipe": recipe.name, "name": e.name, "generator": e.generator, "seed": e.seed,
                     "params": e.params, "hash": digest, "outputs": names}
            if e.level is not None:
                stamp["level"] = e.level
            (out / STAMP).write_text(json.dumps(stamp, indent=2, sort_keys=True, default=str) + "\n")
            results.append(Result(e, True, [out / n for n in names]))
        except GeneratorError as err:
            raise RecipeError(f"{recipe.name}: {e.label()}: {err}") from None
        except (OSError, RenderError) as err:          # e.g. a scene the grain generator reads
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

def _run(args: argparse.Namespace) -> list[str]:
    written: list[str] = []
    for r in args.recipes:
        if r.suffix == ".pbrt":
            found = recipe_for(r)
            if found is None:
                continue
            r = found
        for res in build(r, force=args.force, level=QUICK if args.quick else args.level, only=args.only,
                         log=lambda m: print(m, file=sys.stderr)):
            if res.built:
                written += [str(p) for p in res.outputs]
    return written


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    p = subparsers.add_parser("recipe", help=__doc__.splitlines()[0], description=__doc__,
                              formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("recipes", nargs="+", type=Path, metavar="RECIPE",
                   help="recipe JSON file(s), or a .pbrt scene whose <scene>.recipe.json to build "
                        "(a scene without one is skipped)")
    p.add_argument("--force", action="store_true", help="rebuild every entry")
    lv = p.add_mutually_exclusive_group()
    lv.add_argument("--level", metavar="NAME", help="apply each entry's overrides for this detail level "
                    "(the beach's: draft, preview, final; docs/assets.md)")
    lv.add_argument("--quick", action="store_true", help="the same as --level quick: small, fast assets for tests")
    p.add_argument("--only", action="append", metavar="NAME", help="build only this entry (repeatable)")
    p.set_defaults(run=_run)
    return p
