"""The edits pbrt-v4's ``--upgrade`` makes to one directive (rename its type, rename, drop or add a
parameter), each done in place and warned about at the line it concerns. Shared by the v3 rewrites
of renderer.scene.upgrade (options, lights, shapes) and renderer.scene.upgrade_materials."""
from __future__ import annotations

from typing import Callable

from renderer.errors import Location, SceneError
from renderer.scene.params import Param, ParamSet
from renderer.scene.parser import Directive

Warn = Callable[[Location, str], None]


def what(d: Directive) -> str:
    """How a warning names the directive: ``Material "uber"``."""
    return f'{d.name} "{d.args[0]}"' if d.args else d.name


def rename_type(d: Directive, names: dict[str, str], warn: Warn) -> None:
    old = str(d.args[0])
    if old in names:
        d.args[0] = names[old]
        warn(d.loc, f'{d.name} "{old}" is pbrt-v3\'s; read as --upgrade writes it, "{names[old]}"')


def drop(d: Directive, names: tuple[str, ...], warn: Warn, types: tuple[str, ...] | None = None) -> None:
    """Remove each of ``names`` (only when its type is one of ``types``, if given), as --upgrade does."""
    for name in names:
        p = d.params.params.get(name)
        if p is not None and (types is None or p.type in types):
            del d.params.params[name]
            warn(p.loc, f'{what(d)}: "{name}" is pbrt-v3\'s; dropped, as --upgrade does')


def rename_param(d: Directive, old: str, new: str, warn: Warn) -> None:
    """``old`` read as ``new``; where the file gives both, pbrt-v4 reads the later, the file's ``new``."""
    p = d.params.params.pop(old, None)
    if p is None:
        return
    if new in d.params:
        warn(p.loc, f'{what(d)}: "{old}" is pbrt-v3\'s for "{new}", which is given too; dropped')
        return
    d.params.params[new] = Param(p.type, new, p.values, p.loc)
    warn(p.loc, f'{what(d)}: "{old}" is pbrt-v3\'s; read as "{new}"')


def add_param(d: Directive, ptype: str, name: str, values: list) -> None:
    """A parameter --upgrade writes before the file's own ones, so the file's wins where it gives
    one too (pbrt-v4 reads the later). The caller's warning says what was added."""
    if name not in d.params:
        d.params.params[name] = Param(ptype, name, values, d.loc)


def constant_colour(params: ParamSet, name: str, what: str) -> float:
    """The one value of a grey rgb ``name`` (removed from ``params``); 1 when absent."""
    p = params.params.get(name)
    if p is None or p.type == "float":
        return 1.0
    if p.type != "rgb" or len(p.values) != 3 or len({float(v) for v in p.values}) != 1:
        raise SceneError(f'{what}: pbrt-v4\'s "{name}" is one float here; --upgrade only converts a grey rgb '
                         f"(edit the file)", p.loc)
    del params.params[name]
    return float(p.values[0])
