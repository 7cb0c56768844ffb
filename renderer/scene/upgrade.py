"""pbrt-v3 syntax that pbrt-v4's ``--upgrade`` rewrites (its parser.cpp, FormattingParserTarget),
read as what ``--upgrade`` writes, with a located warning per upgraded construct. Each directive
is rewritten in place before the builder sees it, so everything after is pbrt-v4's.

Covered here: v3 sampler names, the ``directlighting`` integrator and ``rrthreshold``, light
``scale`` given as a colour, ``mapname``, two-value ``blackbody`` values, ``samples`` /
``nsamples``, ``AreaLightSource "area"``, and the shape parameters ``nlevels``,
``discarddegenerateUVs`` and ``shadowalpha``. Film, filter, camera and ``TransformBegin`` upgrades
are read where those directives are (imaging.py, the builder); materials and textures are not
upgraded (yet).
"""
from __future__ import annotations

from typing import Callable

from renderer.errors import SceneError
from renderer.scene.params import Param, ParamSet
from renderer.scene.parser import Directive

Warn = Callable[..., None]

#: pbrt-v3 sampler names and what --upgrade writes for them.
SAMPLERS = {"lowdiscrepancy": "paddedsobol", "02sequence": "paddedsobol", "maxmindist": "pmj02bn",
            "random": "independent"}


def _what(d: Directive) -> str:
    return f'{d.name} "{d.args[0]}"' if d.args else d.name


def _rename_type(d: Directive, names: dict[str, str], warn: Warn) -> None:
    old = str(d.args[0])
    if old in names:
        d.args[0] = names[old]
        warn(d.loc, f'{d.name} "{old}" is pbrt-v3\'s; read as --upgrade writes it, "{names[old]}"')


def _drop(d: Directive, names: tuple[str, ...], warn: Warn) -> None:
    for name in names:
        p = d.params.params.pop(name, None)
        if p is not None:
            warn(p.loc, f'{_what(d)}: "{name}" is pbrt-v3\'s; dropped, as --upgrade does')


def _rename_param(d: Directive, old: str, new: str, warn: Warn) -> None:
    p = d.params.params.pop(old, None)
    if p is not None and new not in d.params:
        d.params.params[new] = Param(p.type, new, p.values, p.loc)
        warn(p.loc, f'{_what(d)}: "{old}" is pbrt-v3\'s; read as "{new}"')


def _constant_colour(params: ParamSet, name: str, what: str) -> float:
    """The one value of a grey rgb ``name`` (removed from ``params``); 1 when absent."""
    p = params.params.get(name)
    if p is None or p.type == "float":
        return 1.0
    if p.type != "rgb" or len(p.values) != 3 or len({float(v) for v in p.values}) != 1:
        raise SceneError(f'{what}: pbrt-v4\'s "{name}" is one float here; --upgrade only converts a grey rgb '
                         f"(edit the file)", p.loc)
    del params.params[name]
    return float(p.values[0])


def _light_scale(d: Directive, warn: Warn) -> None:
    """pbrt-v3's colour ``scale``, two-value blackbodies and (with ``mapname``) a grey ``L`` or
    ``I``, folded into one float ``scale`` as --upgrade folds them."""
    what = _what(d)
    ps = d.params
    loc = ps.params["scale"].loc if "scale" in ps else d.loc
    factor = _constant_colour(ps, "scale", what)
    if "mapname" in ps and str(d.args[0]) in ("infinite", "projection"):
        colour = "L" if str(d.args[0]) == "infinite" else "I"
        if colour in ps:
            loc = ps.params[colour].loc
            factor *= _constant_colour(ps, colour, what)
    for name in ("L", "I"):
        p = ps.params.get(name)
        if p is not None and p.type == "blackbody" and len(p.values) == 2:
            factor *= float(p.values[1])
            ps.params[name] = Param(p.type, name, p.values[:1], p.loc)
            loc = p.loc
    if factor != 1.0:
        old = ps.params.get("scale")
        total = factor * (float(old.values[0]) if old is not None else 1.0)
        ps.params["scale"] = Param("float", "scale", [total], loc)
        warn(loc, f'{what}: pbrt-v3\'s colour scale, two-value blackbody or mapname colour; read as --upgrade '
                  f'writes it, "float scale" {total:g}')


def _light(d: Directive, warn: Warn) -> Directive:
    _light_scale(d, warn)
    _drop(d, ("samples",), warn)
    _rename_param(d, "mapname", "filename", warn)
    return d


def _area_light(d: Directive, warn: Warn) -> Directive:
    _rename_type(d, {"area": "diffuse"}, warn)
    _light_scale(d, warn)
    _drop(d, ("nsamples",), warn)
    return d


def _sampler(d: Directive, warn: Warn) -> Directive:
    _rename_type(d, SAMPLERS, warn)
    return d


def _integrator(d: Directive, warn: Warn) -> Directive:
    if d.args and d.args[0] == "directlighting":
        d.args[0] = "path"
        if "maxdepth" not in d.params:         # --upgrade writes maxdepth 1 before the file's own
            d.params.params["maxdepth"] = Param("integer", "maxdepth", [1], d.loc)
        warn(d.loc, 'Integrator "directlighting" is pbrt-v3\'s; read as --upgrade writes it, '
                    '"path" with "integer maxdepth" 1 unless the file gives one')
    _drop(d, ("rrthreshold",), warn)
    return d


def _shape(d: Directive, warn: Warn) -> Directive:
    if d.args and d.args[0] == "loopsubdiv":
        _rename_param(d, "nlevels", "levels", warn)
    if d.args and d.args[0] in ("trianglemesh", "plymesh"):
        _drop(d, ("discarddegenerateUVs", "shadowalpha"), warn)
    return d


UPGRADES: dict[str, Callable[[Directive, Warn], Directive]] = {
    "LightSource": _light, "AreaLightSource": _area_light, "Sampler": _sampler, "Integrator": _integrator,
    "Shape": _shape,
}


def upgraded(d: Directive, warn: Warn) -> Directive:
    """``d`` as pbrt-v4's --upgrade would write it (the same object, edited in place)."""
    fix = UPGRADES.get(d.name)
    return fix(d, warn) if fix is not None and d.args else d
