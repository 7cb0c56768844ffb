"""The material registry, materials as plain values, and the device material table.

A material is a module with ``NAME``, ``PARAMS`` (its named parameters, pbrt-v4's names and
defaults: :class:`renderer.parameters.Parameters`), the Warp functions ``eval_pdf`` and ``sample``
(see :mod:`renderer.materials.bsdf`) and, where some values derive from others, an optional
``resolve(values, loc) -> (values, extra flag bits)``, and where it has per-layer data, an optional
``layer_rows(values, loc) -> (n, 4) array`` for the scene's layer table, and where it bakes a
table over the angle of incidence (:mod:`renderer.optics.angular_table`) or, a dispersive
dielectric, over the wavelength (:mod:`renderer.optics.dispersion`), an optional
``table_rows(values, loc, thin_film) -> ((n, 4) array, warning)`` (no rows: no table), and where
some lobes are rare, their absence can be compiled: see :func:`hooks`.
Registering the module in ``REGISTRY`` is all it takes to add one: parsing, validation, the device layout and the docs table follow from
``PARAMS``, and kernels are specialised to the materials a scene uses.
"""
from __future__ import annotations

import dataclasses
from types import ModuleType
from typing import Any

import numpy as np
import warp as wp

from renderer.errors import Location, SceneError, UnsupportedError
from renderer.materials import (coatedconductor, coateddiffuse, conductor, dielectric, diffuse, diffusetransmission, disney,
                                disney_film, energy, selection, subsurface, thindielectric, thinfilm)
from renderer.materials.film_body import has_film
from renderer.materials.bsdf import FIRST_DERIVED_FLAG, MAX_SLOTS
from renderer.parameters import Parameter, Parameters, TextureRef
from renderer.scene.description import MaterialDesc, SceneDescription, TextureDesc
from renderer.scene.params import ParamSet
from renderer.settings import THIN_FILM_MODE
from renderer.textures import TextureTable

#: The largest float32: the bound of a slot whose parameter declares none.
FLOAT_MAX = float(np.finfo(np.float32).max)

REGISTRY: dict[str, ModuleType] = {m.NAME: m for m in (diffuse, dielectric, conductor, thinfilm, disney,
                                                          coateddiffuse, coatedconductor, thindielectric,
                                                          diffusetransmission, subsurface)}
for _m in REGISTRY.values():
    if len(_m.PARAMS.slot_names) > MAX_SLOTS or (1 << len(_m.PARAMS.flag_names)) > FIRST_DERIVED_FLAG:
        raise ValueError(f"material {_m.NAME}: more parameters than the device table holds")

#: Parameters every material has (not part of any module's slot layout).
COMMON = Parameters(
    Parameter("displacement", "float", None, texture=True, doc="bump map: a float texture of heights"),
)


def kind_id(name: str) -> int:
    """A stable small integer per material type (its position in the registry)."""
    return list(REGISTRY).index(name)


def dispatch_table(names: tuple[str, ...]) -> tuple[list[ModuleType], list[int]]:
    """The modules and kind ids that a kernel specialised to the materials ``names`` switches over."""
    return [REGISTRY[n] for n in names], [kind_id(n) for n in names]


def module_of(kind: str, loc: Location | None = None) -> ModuleType:
    """The module of a BSDF material type; unknown types are refused."""
    module = REGISTRY.get(kind)
    if module is None:
        known = ", ".join([*REGISTRY, *selection.PARAMS])
        raise UnsupportedError(f'material "{kind}" is not supported (supported: {known})', loc)
    return module


def _selection_kind(kind: str) -> str | None:
    """"mix" or "interface" for pbrt-v4's materials that are not a BSDF ("" and "none" are its
    names for interface too), else None."""
    return selection.INTERFACE if kind in ("", "none") else kind if kind in selection.PARAMS else None


def _selection(kind: str, values: dict[str, Any], loc: Location | None, name: str) -> MaterialDesc:
    if kind == selection.MIX and len(values.get("materials", ())) != 2:
        raise SceneError('material "mix": "string materials" must name exactly two named materials', loc)
    return MaterialDesc(kind, values, loc, name)


def resolve(desc: MaterialDesc) -> tuple[dict[str, Any], int]:
    """The values a material uploads (derived ones included) and its flag bits beyond the bools."""
    if desc.kind in selection.PARAMS:
        return dict(desc.values), 0
    module = module_of(desc.kind, desc.loc)
    hook = getattr(module, "resolve", None)
    return hook(dict(desc.values), desc.loc) if hook else (dict(desc.values), 0)


def _checked(desc: MaterialDesc) -> MaterialDesc:
    disp = desc.values.get("displacement")
    if disp is not None and not isinstance(disp, TextureRef):
        raise SceneError(f'material "{desc.kind}": "displacement" must be a float texture', desc.loc)
    resolve(desc)   # derived-value checks (e.g. thinfilm's clear substrate) fail here, at load time
    return desc


def material(kind: str, /, *, name: str = "", loc: Location | None = None, **values: Any) -> MaterialDesc:
    """A material from plain Python values, e.g. ``material("diffuse", reflectance=(0.8, 0.2, 0.2))``;
    a texture is ``TextureRef("name")``. Unknown parameter names and values out of range are errors."""
    chooser = _selection_kind(kind)
    if chooser is not None:
        values = selection.PARAMS[chooser].from_python(values, f'material "{chooser}"', loc)
        return _selection(chooser, values, loc, name)
    module = module_of(kind, loc)
    owner = f'material "{kind}"'
    common = {k: values.pop(k) for k in list(values) if k in COMMON.by_name}
    v = module.PARAMS.from_python(values, owner, loc) | COMMON.from_python(common, owner, loc)
    return _checked(MaterialDesc(kind, v, loc, name))


def from_pbrt(kind: str, params: ParamSet, loc: Location, name: str = "") -> MaterialDesc:
    """A material from a pbrt parameter list; what it does not declare stays unread in ``params``
    for the caller's "not supported and was ignored" warning."""
    chooser = _selection_kind(kind)
    if chooser is not None:
        return _selection(chooser, selection.PARAMS[chooser].from_pbrt(params, f'material "{chooser}"'), loc, name)
    module = module_of(kind, loc)
    owner = f'material "{kind}"'
    v = module.PARAMS.from_pbrt(params, owner) | COMMON.from_pbrt(params, owner)
    return _checked(MaterialDesc(kind, v, loc, name))


def parameter_tables() -> str:
    """The parameter table of every material, as docs/materials.md shows them."""
    parts = [f"### `{name}`\n\n{m.PARAMS.docs_table()}\n" for name, m in REGISTRY.items()]
    parts += [f"### `{name}`\n\n{p.docs_table()}\n" for name, p in selection.PARAMS.items() if len(p.by_name)]
    parts.append(f"### every material\n\n{COMMON.docs_table()}\n")
    return "\n".join(parts)


@wp.struct
class Materials:
    kind: wp.array(dtype=int)
    slots: wp.array2d(dtype=int)        # (n_materials, MAX_SLOTS) texture ids, -1 unused
    flags: wp.array(dtype=int)          # bool parameters (one bit each) and derived bits
    bump: wp.array(dtype=int)           # float displacement texture id, -1 for none
    layers: wp.array(dtype=wp.vec4)     # every material's layer rows (renderer.materials.stack; 1 dummy row if none)
    layer_first: wp.array(dtype=int)    # a material's first row in layers
    layer_count: wp.array(dtype=int)    # and its number of rows (0: no stack)
    table_first: wp.array(dtype=int)    # a material's baked table in layers (angle; wavelength: dispersion); 0: none
    bounds: wp.array2d(dtype=wp.vec2)   # (n_materials, MAX_SLOTS) each slot's declared [lo, hi]: textures are
                                        # clamped to it as pbrt clamps (a reflectance texture of 100 reflects 1)
    mix: wp.array(dtype=wp.vec3i)       # a mix's (first, second material, amount texture id)


def device_layout(desc: MaterialDesc) -> tuple[list[tuple[Parameter, Any]], int]:
    """What a material puts in the device table: per slot (declaration order) its parameter and
    value (given, derived or default; None leaves the slot empty), and its flag bits."""
    params = module_of(desc.kind, desc.loc).PARAMS
    values, flags = resolve(desc)
    for name in params.flag_names:
        if params.value(values, name):
            flags |= getattr(params.flags, name)
    return params.slot_layout(values), flags


#: The parameter that turns on energy compensation (renderer.materials.energy) where a material has it.
MULTISCATTER = "multiscatter"


def multiscatters(desc: MaterialDesc) -> bool:
    """Whether this material counts the bounces between microfacets (its ``multiscatter``, given or default)."""
    if desc.kind in selection.PARAMS:
        return False
    params = module_of(desc.kind, desc.loc).PARAMS
    return MULTISCATTER in params.by_name and bool(params.value(desc.values, MULTISCATTER))


def with_multiscatter(scene: SceneDescription) -> SceneDescription:
    """The scene with ``multiscatter`` true on every material that has the parameter: what
    ``--multiscatter`` and ``render(multiscatter=True)`` do, so a pbrt-v4 file (which may not carry
    the parameter) can use it. The scene's content, and so a checkpoint's fingerprint, records it."""
    mats = []
    for d in scene.materials:
        has = d.kind not in selection.PARAMS and MULTISCATTER in module_of(d.kind, d.loc).PARAMS.by_name
        mats.append(dataclasses.replace(d, values=d.values | {MULTISCATTER: True}) if has else d)
    return dataclasses.replace(scene, materials=mats)


def may_be_rough(desc: MaterialDesc) -> bool:
    """Whether a material with pbrt's roughness parameters can have a rough (GGX) lobe: its
    ``uroughness`` or ``vroughness`` is a texture or a constant above 0. False for a smooth one
    (both a constant 0, so alpha is 0 at every point) and for materials without the parameters."""
    if desc.kind in selection.PARAMS or "uroughness" not in module_of(desc.kind, desc.loc).PARAMS.by_name:
        return False
    values = resolve(desc)[0]
    return any(isinstance(values[k], TextureRef) or values[k] > 0.0 for k in ("uroughness", "vroughness"))


def smooth_kinds(descs: list[MaterialDesc]) -> tuple[str, ...]:
    """The material types with roughness parameters of which every material in ``descs`` is smooth:
    a kernel needs none of their GGX lobes (``Features.smooth``)."""
    kinds = {d.kind for d in descs
             if d.kind not in selection.PARAMS and "uroughness" in module_of(d.kind, d.loc).PARAMS.by_name}
    return tuple(sorted(kinds - {d.kind for d in descs if may_be_rough(d)}))


def scatters_below(descs: list[MaterialDesc]) -> bool:
    """Whether some material carries light below its surface (``Features.subsurface``): a solid
    ``disney`` with a scatter distance, or pbrt-v4's ``subsurface``."""
    return any((d.kind == disney.NAME and disney.has_subsurface(d.values)) or d.kind == subsurface.NAME for d in descs)


def lobe_features(descs: list[MaterialDesc]) -> dict[str, Any]:
    """The fields of :class:`renderer.device.scene.Features` that say which lobes a scene of these
    materials can reach: ``multiscatter`` (some material that may be rough counts the bounces
    between microfacets), ``layered`` (some thinfilm takes the layered walk; coateddiffuse and
    coatedconductor always do), ``unlayered`` (some thinfilm does not), ``smooth``
    (:func:`smooth_kinds`), ``coated_body`` (some subsurface material has a film on its boundary)
    and ``coated_disney`` (some disney material has one)."""
    return {"multiscatter": any(multiscatters(d) and may_be_rough(d) for d in descs),
            "layered": any(d.kind == thinfilm.NAME and thinfilm.walks(d.values) for d in descs),
            "unlayered": any(d.kind == thinfilm.NAME and not thinfilm.walks(d.values) for d in descs),
            "smooth": smooth_kinds(descs),
            "coated_body": any(d.kind == subsurface.NAME and subsurface.has_coating(d.values) for d in descs),
            "coated_disney": any(d.kind == disney.NAME and has_film(d.values) for d in descs)}


#: Specialisers kept outside their material's module (the film lobes import the material).
SPECIALISED = {disney.NAME: disney_film.specialised}


def hooks(module: ModuleType, features: Any) -> tuple[wp.Function, wp.Function]:
    """A material's ``eval_pdf`` and ``sample`` for a kernel of ``features``
    (:class:`renderer.device.scene.Features`), leaving out the lobes no material of the scene can
    reach: the module's ``specialised(features)`` where it has one; its ``SMOOTH_LOBES`` where
    every material of its type is smooth, its ``SINGLE_LOBES`` where none counts the bounces
    between microfacets; else the functions that handle every case."""
    specialised = SPECIALISED.get(module.NAME, getattr(module, "specialised", None))
    if specialised is not None:
        return specialised(features)
    if module.NAME in features.smooth and hasattr(module, "SMOOTH_LOBES"):
        return module.SMOOTH_LOBES
    if not features.multiscatter and hasattr(module, "SINGLE_LOBES"):
        return module.SINGLE_LOBES
    return module.eval_pdf, module.sample


def first_rows(descs: list[MaterialDesc]) -> list[np.ndarray]:
    """The layer table's leading rows: the dummy row 0, then the energy tables at
    ``energy.ENERGY_FIRST`` when a material uses them (else nothing, so other scenes are unchanged)."""
    rows = [np.zeros((1, 4), np.float32)]
    if any(multiscatters(d) for d in descs):
        rows.append(energy.rows())
    return rows


def _texture_id(p: Parameter, v: Any, table: TextureTable, textures: dict[str, TextureDesc], loc) -> int:
    if v is None:
        return -1
    if isinstance(v, TextureRef):
        return table.lookup(v.name, "spectrum" if p.type == "rgb" else "float", textures, loc)
    return table.add_constant(v)


def _append_rows(rows: list[np.ndarray], mine: np.ndarray) -> int:
    """Appends a material's rows to the layer table; returns the index of the first."""
    first = sum(len(r) for r in rows)
    rows.append(np.asarray(mine, np.float32).reshape(-1, 4))
    return first


def build_materials(descs: list[MaterialDesc], textures: dict[str, TextureDesc], table: TextureTable,
                    device: str, thin_film: str = THIN_FILM_MODE) -> tuple[Materials, list, set[str], list[str]]:
    """The device table: per material one texture id per slot parameter (constants included),
    its flags and bump map, its layers and baked tables (``thin_film``: the render's colour mode).
    Returns the table, the arrays that back it (keep them alive), the set of material types in
    use (for kernel specialisation) and the warnings of the bakes (one per material a table
    could not describe)."""
    n = max(1, len(descs))
    kinds = np.zeros(n, dtype=np.int32)
    slot_ids = -np.ones((n, MAX_SLOTS), dtype=np.int32)
    flags = np.zeros(n, dtype=np.int32)
    bump = -np.ones(n, dtype=np.int32)
    first = np.zeros(n, dtype=np.int32)
    count = np.zeros(n, dtype=np.int32)
    tables = np.zeros(n, dtype=np.int32)
    rows = first_rows(descs)
    warnings: list[str] = []
    bounds = np.tile(np.array([-FLOAT_MAX, FLOAT_MAX], np.float32), (n, MAX_SLOTS, 1))
    mix = mix_table(descs, table, textures)
    for i, d in enumerate(descs):
        if d.kind in selection.PARAMS:
            kinds[i] = selection.MIX_KIND if d.kind == selection.MIX else selection.INTERFACE_KIND
            continue
        module = module_of(d.kind, d.loc)
        rows_of = getattr(module, "layer_rows", None)
        if rows_of is not None:
            mine = rows_of(resolve(d)[0], d.loc)
            first[i], count[i] = _append_rows(rows, mine), len(mine)
        table_of = getattr(module, "table_rows", None)
        if table_of is not None:
            baked, warning = table_of(resolve(d)[0], d.loc, thin_film)
            if len(baked):
                tables[i] = _append_rows(rows, baked)
            if warning:
                warnings.append(f"{d.loc}: {warning}" if d.loc else warning)
        layout, flags[i] = device_layout(d)
        for j, (p, v) in enumerate(layout):
            slot_ids[i, j] = _texture_id(p, v, table, textures, d.loc)
            bounds[i, j] = (-FLOAT_MAX if p.lo is None else p.lo, FLOAT_MAX if p.hi is None else p.hi)
        bump[i] = _texture_id(COMMON.by_name["displacement"], d.values.get("displacement"), table, textures, d.loc)
        kinds[i] = kind_id(d.kind)
    M = Materials()
    M.kind = wp.array(kinds, dtype=int, device=device)
    M.slots = wp.array(slot_ids, dtype=int, device=device)
    M.flags = wp.array(flags, dtype=int, device=device)
    M.bump = wp.array(bump, dtype=int, device=device)
    M.layers = wp.array(np.concatenate(rows), dtype=wp.vec4, device=device)
    M.layer_first = wp.array(first, dtype=int, device=device)
    M.layer_count = wp.array(count, dtype=int, device=device)
    M.table_first = wp.array(tables, dtype=int, device=device)
    M.bounds = wp.array(bounds, dtype=wp.vec2, device=device)
    M.mix = wp.array(mix, dtype=wp.vec3i, device=device)
    keep = [M.kind, M.slots, M.flags, M.bump, M.layers, M.layer_first, M.layer_count, M.table_first, M.bounds, M.mix]
    return M, keep, {d.kind for d in descs} - set(selection.PARAMS), warnings


def mix_table(descs: list[MaterialDesc], table: TextureTable, textures: dict[str, TextureDesc]) -> np.ndarray:
    """(n, 3) per mix material its two materials' indices (named materials, by name) and its amount
    texture; zeros elsewhere. A mix of the interface material or of a thin slab's face
    (renderer.integrators.thin_slab), a chain of mixes deeper than
    selection.MAX_DEPTH and a cycle are refused."""
    out = np.zeros((max(1, len(descs)), 3), np.int32)
    named = {d.name: i for i, d in enumerate(descs) if d.name}
    for i, d in enumerate(descs):
        if d.kind != selection.MIX:
            continue
        for j, child in enumerate(d.values["materials"]):
            if child not in named:
                raise SceneError(f'material "mix": no named material "{child}"', d.loc)
            if descs[named[child]].kind == selection.INTERFACE:
                raise UnsupportedError(f'material "mix": a mix of the interface material ("{child}") is not supported',
                                       d.loc)
            if descs[named[child]].values.get("thinslab"):     # shadow rays see a shape's own material only
                raise UnsupportedError(f'material "mix": a mix of a "thinslab" face ("{child}") is not supported',
                                       d.loc)
            out[i, j] = named[child]
        p = selection.PARAMS[selection.MIX].by_name["amount"]
        out[i, 2] = _texture_id(p, selection.PARAMS[selection.MIX].value(d.values, "amount"), table, textures, d.loc)
    def depth(m: int, chain: frozenset[int]) -> int:
        if descs[m].kind != selection.MIX:
            return 0
        if m in chain or len(chain) >= selection.MAX_DEPTH:
            raise UnsupportedError(f'material "mix": mixes of mixes nest deeper than {selection.MAX_DEPTH} '
                                   "(or form a cycle)", descs[m].loc)
        return 1 + max(depth(int(c), chain | {m}) for c in out[m, :2])

    for i in range(len(descs)):
        depth(i, frozenset())
    return out
