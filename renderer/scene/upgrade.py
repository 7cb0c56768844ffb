"""pbrt-v3 syntax that pbrt-v4's ``--upgrade`` rewrites (its parser.cpp, FormattingParserTarget),
read as what ``--upgrade`` writes, with a located warning per upgraded construct. Each directive
is rewritten in place before the builder sees it, so everything after is pbrt-v4's.

Covered here: v3 sampler names, the ``directlighting`` integrator and ``rrthreshold``, light
``scale`` given as a colour, ``mapname``, two-value ``blackbody`` values, ``samples`` /
``nsamples``, ``AreaLightSource "area"``, and the shape parameters ``nlevels``,
``discarddegenerateUVs`` and ``shadowalpha``; materials and textures in
renderer.scene.upgrade_materials. Film, filter, camera and ``TransformBegin`` upgrades are read
where those directives are (imaging.py, the builder).
"""
from __future__ import annotations

from typing import Callable

from renderer.scene.params import Param
from renderer.scene.parser import Directive
from renderer.scene.upgrade_edits import Warn, constant_colour, drop, rename_param, rename_type, what
from renderer.scene.upgrade_materials import MATERIAL_UPGRADES

#: pbrt-v3 sampler names and what --upgrade writes for them.
SAMPLERS = {"lowdiscrepancy": "paddedsobol", "02sequence": "paddedsobol", "maxmindist": "pmj02bn",
            "random": "independent"}


def _light_scale(d: Directive, warn: Warn) -> None:
    """pbrt-v3's colour ``scale``, two-value blackbodies and (with ``mapname``) a grey ``L`` or
    ``I``, folded into one float ``scale`` as --upgrade folds them."""
    where = what(d)
    ps = d.params
    loc = ps.params["scale"].loc if "scale" in ps else d.loc
    factor = constant_colour(ps, "scale", where)
    if "mapname" in ps and str(d.args[0]) in ("infinite", "projection"):
        colour = "L" if str(d.args[0]) == "infinite" else "I"
        if colour in ps:
            loc = ps.params[colour].loc
            factor *= constant_colour(ps, colour, where)
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
        warn(loc, f'{where}: pbrt-v3\'s colour scale, two-value blackbody or mapname colour; read as --upgrade '
                  f'writes it, "float scale" {total:g}')


def _light(d: Directive, warn: Warn) -> Directive:
    _light_scale(d, warn)
    drop(d, ("samples",), warn)
    rename_param(d, "mapname", "filename", warn)
    return d


def _area_light(d: Directive, warn: Warn) -> Directive:
    rename_type(d, {"area": "diffuse"}, warn)
    _light_scale(d, warn)
    drop(d, ("nsamples",), warn)
    return d


def _sampler(d: Directive, warn: Warn) -> Directive:
    rename_type(d, SAMPLERS, warn)
    return d


def _integrator(d: Directive, warn: Warn) -> Directive:
    if d.args and d.args[0] == "directlighting":
        d.args[0] = "path"
        if "maxdepth" not in d.params:         # --upgrade writes maxdepth 1 before the file's own
            d.params.params["maxdepth"] = Param("integer", "maxdepth", [1], d.loc)
        warn(d.loc, 'Integrator "directlighting" is pbrt-v3\'s; read as --upgrade writes it, '
                    '"path" with "integer maxdepth" 1 unless the file gives one')
    drop(d, ("rrthreshold",), warn)
    return d


def _shape(d: Directive, warn: Warn) -> Directive:
    if d.args and d.args[0] == "loopsubdiv":
        rename_param(d, "nlevels", "levels", warn)
    if d.args and d.args[0] in ("trianglemesh", "plymesh"):
        drop(d, ("discarddegenerateUVs", "shadowalpha"), warn)
    return d


UPGRADES: dict[str, Callable[[Directive, Warn], Directive]] = {
    "LightSource": _light, "AreaLightSource": _area_light, "Sampler": _sampler, "Integrator": _integrator,
    "Shape": _shape, **MATERIAL_UPGRADES,
}


def upgraded(d: Directive, warn: Warn) -> Directive:
    """``d`` as pbrt-v4's --upgrade would write it (the same object, edited in place)."""
    fix = UPGRADES.get(d.name)
    return fix(d, warn) if fix is not None and d.args else d
