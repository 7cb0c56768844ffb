"""pbrt-v3 materials and textures read as pbrt-v4's ``--upgrade`` writes them (its parser.cpp:
upgradeMaterial, upgradeMaterialIndex and FormattingParserTarget::Texture), with a located warning
per rewritten type or parameter.

Materials: matte, plastic, uber, substrate, glass, metal, mirror, translucent, kdsubsurface, hair,
v3's mix, ``bumpmap`` -> ``displacement``, glass ``index`` -> ``eta``. What pbrt-v4's material has
no parameter for (a plastic's ``Ks``, a matte's ``sigma``, a translucent's ``reflect``, ...) is
dropped, as --upgrade drops it, and the warning says whether the image can differ. Textures: the
``color`` type, scale ``tex1``/``tex2``, imagemap ``trilinear`` and ``gamma``. What --upgrade
refuses (a non-opaque uber, a non-grey scale factor, ...) is a located SceneError.

Not rewritten: pbrt-v3's ``disney``, which --upgrade makes a diffuse, because this renderer reads
it as pbrt-v3 defines it (docs/disney.md); and --upgrade's renaming of textures and named
materials defined twice (pbrt-v4 refuses a second definition, and so does this renderer).
"""
from __future__ import annotations

from typing import Callable

import numpy as np

from renderer.errors import SceneError
from renderer.scene.params import Param
from renderer.scene.parser import Directive
from renderer.scene.upgrade_edits import Warn, add_param, drop, rename_param, what

#: Parameter types that --upgrade reads as a colour (its GetSpectrumArray).
SPECTRAL = ("rgb", "spectrum", "blackbody")


def _shortest(x: float) -> str:
    """``x`` as pbrt writes a float: the shortest text that reads back as the same float32."""
    return np.format_float_positional(np.float32(x), trim="-")


def _refuse(d: Directive, problem: str, p: Param | None = None) -> SceneError:
    return SceneError(f"{what(d)}: {problem}; pbrt-v4's --upgrade refuses it (edit the file)",
                      p.loc if p is not None else d.loc)


def _drop_unless(d: Directive, name: str, value: float, warn: Warn) -> bool:
    """--upgrade's removeParamSilentIfConstant: a colour or texture ``name`` is removed. True when
    it was an rgb of exactly ``value``, what pbrt-v4's material behaves as."""
    p = d.params.params.get(name)
    if p is None or p.type not in (*SPECTRAL, "texture"):
        return False
    del d.params.params[name]
    same = p.type == "rgb" and all(float(v) == value for v in p.values[:3])
    effect = f"pbrt-v4's material behaves as {value:g}" if same else \
        "pbrt-v4's material has no such parameter, so the image can differ"
    warn(p.loc, f'{what(d)}: "{name}" is pbrt-v3\'s; dropped, as --upgrade does ({effect})')
    return same


def _index(d: Directive) -> Param | None:
    """glass's and uber's ``index``, removed and returned (a float or a float texture)."""
    p = d.params.params.get("index")
    if p is None or p.type not in ("float", "texture"):
        return None
    if "eta" in d.params:
        raise _refuse(d, 'both "index" and "eta" are given', p)
    if len(p.values) != 1:
        raise _refuse(d, '"index" has more than one value', p)
    del d.params.params["index"]
    return p


def _coated(d: Directive, warn: Warn) -> str:
    """uber and plastic: a coateddiffuse, or a diffuse where the specular ``Ks`` is black (the
    coat's float ``roughness`` and ``eta`` go too)."""
    rename_param(d, "Kd", "reflectance", warn)
    if _drop_unless(d, "Ks", 0.0, warn):
        drop(d, ("eta", "roughness"), warn, ("float",))
        return "diffuse"
    return "coateddiffuse"


def _uber(d: Directive, warn: Warn) -> str:
    index = _index(d)
    if index is not None:                 # --upgrade computes the eta, then loses it for uber
        warn(index.loc, f'{what(d)}: "index" is pbrt-v3\'s; dropped, as --upgrade drops it for uber '
                        f"(pbrt-v4's default eta, 1.5, is used)")
    _drop_unless(d, "Kr", 0.0, warn)
    _drop_unless(d, "Kt", 0.0, warn)
    kind = _coated(d, warn)
    opacity = d.params.params.get("opacity")
    if opacity is not None and opacity.type == "texture":
        raise _refuse(d, 'pbrt-v4 has no material "opacity" (a texture here)', opacity)
    if opacity is not None and opacity.type in SPECTRAL:
        if opacity.type != "rgb" or any(float(v) != 1.0 for v in opacity.values[:3]):
            raise _refuse(d, 'pbrt-v4 has no material "opacity" (not 1 here)', opacity)
        drop(d, ("opacity",), warn)
    return kind


def _substrate(d: Directive, warn: Warn) -> str:
    _drop_unless(d, "Ks", 1.0, warn)
    rename_param(d, "Kd", "reflectance", warn)
    return "coateddiffuse"


def _glass(d: Directive, warn: Warn) -> str:
    index = _index(d)
    if index is not None:
        d.params.params["eta"] = Param(index.type, "eta", index.values, index.loc)
        warn(index.loc, f'{what(d)}: "index" is pbrt-v3\'s; read as "eta"')
    _drop_unless(d, "Kr", 1.0, warn)
    _drop_unless(d, "Kt", 1.0, warn)
    return "dielectric"


def _matte(d: Directive, warn: Warn) -> str:
    rename_param(d, "Kd", "reflectance", warn)
    drop(d, ("sigma",), warn, ("float", "texture"))          # Oren-Nayar's: pbrt-v4's diffuse is Lambertian
    return "diffuse"


def _metal(d: Directive, warn: Warn) -> str:
    _drop_unless(d, "Kr", 1.0, warn)
    return "conductor"


def _mirror(d: Directive, warn: Warn) -> str:
    add_param(d, "float", "roughness", [0.0])
    add_param(d, "spectrum", "eta", ["metal-Ag-eta"])
    add_param(d, "spectrum", "k", ["metal-Ag-k"])
    _drop_unless(d, "Kr", 0.0, warn)
    return "conductor"


def _translucent(d: Directive, warn: Warn) -> str:
    rename_param(d, "Kd", "transmittance", warn)
    _drop_unless(d, "reflect", 0.0, warn)
    _drop_unless(d, "transmit", 1.0, warn)
    _drop_unless(d, "Ks", 0.0, warn)
    drop(d, ("roughness",), warn, ("float",))
    return "diffusetransmission"


def _kdsubsurface(d: Directive, warn: Warn) -> str:
    rename_param(d, "Kd", "reflectance", warn)
    return "subsurface"


def _hair(d: Directive, warn: Warn) -> str:
    rename_param(d, "color", "reflectance", warn)
    return "hair"


def _mix(d: Directive, warn: Warn) -> str:
    """pbrt-v3's mix: a colour ``amount`` becomes one float (the mean of a non-grey one, as
    --upgrade averages it) and ``namedmaterial1``/``2`` become ``materials``, swapped: pbrt-v3
    weighted the first by the amount, pbrt-v4 weights the second."""
    ps = d.params.params
    amount = ps.get("amount")
    if amount is not None and amount.type in SPECTRAL:
        if amount.type != "rgb":
            raise _refuse(d, 'a spectrum "amount" is not one number', amount)
        rgb = [float(v) for v in amount.values[:3]]
        value = rgb[0] if len(set(rgb)) == 1 else float(_shortest(sum(rgb) / 3.0))
        ps["amount"] = Param("float", "amount", [value], amount.loc)
        mean = "" if len(set(rgb)) == 1 else ", the mean of the colour"
        warn(amount.loc, f'{what(d)}: a colour "amount" is pbrt-v3\'s; read as --upgrade writes it, '
                         f'"float amount" {value:g}{mean}')
    first, second = ps.get("namedmaterial1"), ps.get("namedmaterial2")
    if first is None and second is None:
        return "mix"
    if first is None or second is None:
        raise _refuse(d, 'pbrt-v3\'s mix needs both "namedmaterial1" and "namedmaterial2"', first or second)
    del ps["namedmaterial1"], ps["namedmaterial2"]
    names = [str(second.values[0]), str(first.values[0])]
    add_param(d, "string", "materials", names)
    warn(first.loc, f'{what(d)}: "namedmaterial1"/"namedmaterial2" are pbrt-v3\'s; read as --upgrade writes '
                    f'them, "string materials" ["{names[0]}" "{names[1]}"] (pbrt-v4 weights the second by '
                    f'"amount", pbrt-v3 the first)')
    return "mix"


#: pbrt-v3 material types and how --upgrade rewrites each (returning the pbrt-v4 type).
MATERIALS: dict[str, Callable[[Directive, Warn], str]] = {
    "uber": _uber, "plastic": _coated, "substrate": _substrate, "glass": _glass, "matte": _matte,
    "metal": _metal, "mirror": _mirror, "translucent": _translucent, "kdsubsurface": _kdsubsurface,
    "hair": _hair, "mix": _mix,
}


def _upgraded_kind(d: Directive, kind: str, warn: Warn) -> str:
    """The pbrt-v4 type of a material of pbrt-v3 type ``kind`` (``d``'s parameters rewritten)."""
    rename_param(d, "bumpmap", "displacement", warn)
    rule = MATERIALS.get(kind)
    new = kind if rule is None else rule(d, warn)
    if new != kind:
        extra = ' with "roughness" 0 and silver\'s "eta" and "k"' if kind == "mirror" else ""
        which = f'Material "{kind}"' if d.name == "Material" else f'{what(d)}: "string type" "{kind}"'
        warn(d.loc, f'{which} is pbrt-v3\'s; read as --upgrade writes it, "{new}"{extra}')
    return new


def _material(d: Directive, warn: Warn) -> Directive:
    d.args[0] = _upgraded_kind(d, str(d.args[0]), warn)
    return d


def _named_material(d: Directive, warn: Warn) -> Directive:
    p = d.params.params.get("type")
    if p is not None and p.type == "string" and p.values:
        d.params.params["type"] = Param("string", "type", [_upgraded_kind(d, str(p.values[0]), warn)], p.loc)
    return d


def _scale_inputs(d: Directive, warn: Warn) -> None:
    """A scale texture's ``tex1``/``tex2``: a float one's become ``tex`` and ``scale``; of a colour
    one, the grey rgb becomes the float ``scale`` and the other input ``tex``."""
    if str(d.args[1]) == "float":
        rename_param(d, "tex1", "tex", warn)
        rename_param(d, "tex2", "scale", warn)
        return
    rgb_seen = tex_seen = False
    for p in [p for p in d.params.params.values() if p.name in ("tex1", "tex2")]:
        if p.type != "rgb":
            if tex_seen:
                raise _refuse(d, 'both scale inputs are textures or spectra; one must be a grey "rgb"', p)
            tex_seen = True
            rename_param(d, p.name, "tex", warn)
            continue
        if rgb_seen:
            raise _refuse(d, 'both scale inputs are "rgb"; pbrt-v4 takes a texture and one float "scale"', p)
        if len(p.values) != 3 or len({float(v) for v in p.values}) != 1:
            raise _refuse(d, f'"{p.name}" is not a grey "rgb", and pbrt-v4\'s "scale" is one float', p)
        rgb_seen = True
        del d.params.params[p.name]
        d.params.params["scale"] = Param("float", "scale", [float(p.values[0])], p.loc)
        warn(p.loc, f'{what(d)}: "rgb {p.name}" is pbrt-v3\'s; read as --upgrade writes it, '
                    f'"float scale" {p.values[0]}')


def _image_options(d: Directive, warn: Warn) -> None:
    """imagemap ``bool trilinear`` -> ``filter``; imagemap or ptex ``float gamma`` G (not 0) ->
    encoding "gamma G", ``bool gamma`` -> "sRGB" or "linear"."""
    ps = d.params.params
    tri = ps.get("trilinear")
    if str(d.args[2]) == "imagemap" and tri is not None and tri.type == "bool" and len(tri.values) == 1:
        del ps["trilinear"]
        add_param(d, "string", "filter", ["trilinear" if tri.values[0] else "bilinear"])
        warn(tri.loc, f'{what(d)}: "bool trilinear" is pbrt-v3\'s; read as "string filter" "{ps["filter"].values[0]}"')
    gamma = ps.get("gamma")
    if gamma is None or len(gamma.values) != 1:
        return
    if gamma.type == "float" and float(gamma.values[0]) != 0.0:
        encoding = "gamma " + _shortest(float(gamma.values[0]))
    elif gamma.type == "bool":
        encoding = "sRGB" if gamma.values[0] else "linear"
    else:
        return
    del ps["gamma"]
    add_param(d, "string", "encoding", [encoding])
    warn(gamma.loc, f'{what(d)}: "{gamma.type} gamma" is pbrt-v3\'s; read as "string encoding" '
                    f'"{ps["encoding"].values[0]}"')


def _texture(d: Directive, warn: Warn) -> Directive:
    if len(d.args) != 3:
        return d
    if str(d.args[2]) == "scale" and ("tex1" in d.params or "tex2" in d.params):
        _scale_inputs(d, warn)
    if str(d.args[2]) in ("imagemap", "ptex"):
        _image_options(d, warn)
    if str(d.args[1]) == "color":
        d.args[1] = "spectrum"
        warn(d.loc, f'Texture "{d.args[0]}": the type "color" is pbrt-v3\'s; read as "spectrum"')
    return d


#: The directives this module rewrites (renderer.scene.upgrade dispatches to them).
MATERIAL_UPGRADES: dict[str, Callable[[Directive, Warn], Directive]] = {
    "Material": _material, "MakeNamedMaterial": _named_material, "Texture": _texture,
}
