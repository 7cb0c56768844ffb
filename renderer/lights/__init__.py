"""The light registry: one module per light, each registered by one line below.

A light module has ``NAME`` (its pbrt-v4 type name), ``DIRECTIVE`` (``"LightSource"``, or
``"AreaLightSource"`` for lights that shapes carry), ``PARAMS`` (its named parameters, pbrt-v4's
names and defaults), optionally ``check(given, light_to_world, loc, base_dir) -> given`` (load-time
validation that needs more than one parameter), ``ROW`` (:class:`~renderer.lights.table.Row`, the
names of its table entries), the host function ``entry(light, tris) -> LightEntry | None`` (an area
light's also takes the pbrt-v4 shape's exact area, or None for a mesh) and the
device functions ``sample(lights, i, p, u) -> LightSample`` and, where a path can reach the light,
``escaped(lights, i, p, d) -> LightEval`` (rays leaving the scene from p) or ``emitted(lights, i, p_ref, p,
n, w_out) -> LightEval`` (rays hitting an emissive surface). Kernels are specialised to the kinds
a scene uses and call them through ``wp.static``, so the integrator names no kind of light.
"""
from __future__ import annotations

import os
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np

from renderer.errors import Location, SceneError, UnsupportedError
from renderer.lights import area, distant, goniometric, infinite, point, projection, spot
from renderer.lights.table import LightTable
from renderer.scene.description import LightDesc, MeshDesc, SceneDescription
from renderer.scene.params import ParamSet

REGISTRY: dict[str, ModuleType] = {m.NAME: m for m in (
    infinite,
    distant,
    area,
    point,
    spot,
    goniometric,
    projection,
)}


def kind_id(name: str) -> int:
    """A stable small integer per light type (its position in the registry)."""
    return list(REGISTRY).index(name)


def dispatch(names: tuple[str, ...], hook: str) -> tuple[tuple[ModuleType, ...], tuple[int, ...]]:
    """The modules among ``names`` that define device function ``hook``, and their kind ids."""
    mods = tuple(REGISTRY[n] for n in names if hasattr(REGISTRY[n], hook))
    return mods, tuple(kind_id(m.NAME) for m in mods)


def _module(directive: str, name: str, loc: Location | None) -> ModuleType:
    module = REGISTRY.get(name)
    if module is None or module.DIRECTIVE != directive:
        known = ", ".join(f'"{n}"' for n, m in REGISTRY.items() if m.DIRECTIVE == directive)
        raise UnsupportedError(f'{directive} "{name}" is not supported (supported: {known})', loc)
    return module


def _describe(module: ModuleType, given: dict[str, Any], light_to_world: np.ndarray, loc: Location | None,
              base_dir: Path | None) -> LightDesc:
    check = getattr(module, "check", None)
    if check is not None:
        given = check(given, light_to_world, loc, base_dir)
    values = {p.name: module.PARAMS.value(given, p.name) for p in module.PARAMS}
    return LightDesc(module.NAME, values, np.array(light_to_world, dtype=np.float64), loc)


def describe(directive: str, name: str, params: ParamSet, light_to_world: np.ndarray, loc: Location) -> LightDesc:
    """A ``LightSource`` or ``AreaLightSource`` directive as a :class:`LightDesc`; the parameters it
    does not declare stay unread in ``params`` for the builder's unused-parameter warning."""
    module = _module(directive, name, loc)
    given = module.PARAMS.from_pbrt(params, f'{directive} "{name}"')
    return _describe(module, given, light_to_world, loc, Path(loc.file).parent)


def light(kind: str, light_to_world: np.ndarray | None = None, **values: Any) -> LightDesc:
    """A light for a :class:`SceneDescription` built in Python, from plain values under pbrt-v4's
    parameter names; a trailing underscore is dropped, so ``from_=`` sets ``from``. Example:
    ``light("distant", L=(3, 3, 3), from_=(0, 1, 0), angularradius=0.27)``. ``"diffuse"`` is the
    area light, which goes into :attr:`ShapeDesc.area_light`; the others go into
    :attr:`SceneDescription.lights`. Relative file names are relative to the working directory."""
    module = _module(REGISTRY[kind].DIRECTIVE if kind in REGISTRY else "LightSource", kind, None)
    plain = {k[:-1] if k.endswith("_") else k: os.fspath(v) if isinstance(v, os.PathLike) else v
             for k, v in values.items()}
    given = module.PARAMS.from_python(plain, f'light "{kind}"')
    return _describe(module, given, np.eye(4) if light_to_world is None else light_to_world, None, None)


def _shape_triangles(desc: SceneDescription, shape: int, inst_shape: np.ndarray, xforms: np.ndarray) -> np.ndarray:
    """(T, 3, 3) world-space triangles of every instance of a shape, wound outwards."""
    s = desc.shapes[shape]
    mesh = desc.meshes[s.mesh]
    tris = []
    for m in xforms[inst_shape == shape]:
        t = (mesh.positions.astype(np.float64) @ m[:3, :3].T + m[:3, 3])[mesh.indices]
        tris.append(t[:, ::-1] if s.reverse_orientation else t)
    return np.concatenate(tris) if tris else np.zeros((0, 3, 3))


def _pbrt_shape_area(mesh: MeshDesc, tris: np.ndarray) -> float:
    """The area of one of the pbrt-v4 shapes an emissive shape stands for, which an area light's
    ``power`` divides by: a sphere's, disk's or cylinder's exact object-space area, else the mean
    world-space area of a triangle (or of a bilinear patch) over every instance."""
    if mesh.analytic_area is not None:
        return mesh.analytic_area
    total = 0.5 * float(np.linalg.norm(np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0]), axis=1).sum())
    instances = len(tris) / len(mesh.indices)
    return total / (instances * (mesh.pbrt_shapes or len(mesh.indices)))


def build_light_table(desc: SceneDescription, inst_shape: np.ndarray, xforms: np.ndarray
                      ) -> tuple[LightTable, np.ndarray]:
    """Every light's table row: the shapes' area lights first (in shape order), then the scene's
    lights in file order. Also the light index of each shape (-1: not emissive)."""
    table = LightTable()
    shape_light = -np.ones(max(1, len(desc.shapes)), dtype=np.int32)
    placed = [(s.area_light, i) for i, s in enumerate(desc.shapes) if s.area_light is not None]
    for light_desc, shape in placed + [(d, None) for d in desc.lights]:
        module = REGISTRY[light_desc.kind]
        if (module.DIRECTIVE == "AreaLightSource") != (shape is not None):
            where = "ShapeDesc.area_light" if shape is None else "SceneDescription.lights"
            raise SceneError(f'a "{light_desc.kind}" light belongs in {where}', light_desc.loc)
        tris = None if shape is None else _shape_triangles(desc, shape, inst_shape, xforms)
        if tris is not None and not len(tris):
            continue                                # an emissive shape nobody places
        e = module.entry(light_desc, tris) if shape is None else \
            module.entry(light_desc, tris, _pbrt_shape_area(desc.meshes[desc.shapes[shape].mesh], tris))
        if e is not None:
            index = table.add(kind_id(module.NAME), module.ROW, e)
            if shape is not None:
                shape_light[shape] = index
    return table, shape_light


def kinds_in(table: LightTable) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """The light kinds in a table (registry order), and those that escaping rays can see: what a
    kernel is specialised to."""
    names = list(REGISTRY)
    used = sorted(set(table.kinds))
    seen = sorted({k for k, e in zip(table.kinds, table.entries) if e.escapes})
    return tuple(names[k] for k in used), tuple(names[k] for k in seen)


def has_lights(desc: SceneDescription) -> bool:
    """Whether anything in the scene emits (else the image is black: the builder warns)."""
    return bool(desc.lights) or any(s.area_light is not None for s in desc.shapes)


def parameter_tables() -> str:
    """Every light's description and parameter table, as docs/lights.md shows them."""
    return "\n".join(f'### `{m.DIRECTIVE} "{name}"`\n\n{" ".join(m.__doc__.split())}\n\n{m.PARAMS.docs_table()}\n'
                     for name, m in REGISTRY.items())


__all__ = ["REGISTRY", "build_light_table", "describe", "dispatch", "has_lights", "kind_id", "kinds_in", "light",
           "parameter_tables"]
