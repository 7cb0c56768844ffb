"""The material registry and the device material table.

A material is a module with ``NAME``, ``slots(builder) -> list[texture id]`` (which validates its
pbrt parameters and turns each into a texture id, constants included) and the Warp functions
``eval``, ``pdf`` and ``sample`` (see :mod:`renderer.materials.bsdf`). Registering a module here
is all it takes to add one; kernels are specialised to the materials a scene uses.
"""
from __future__ import annotations

from dataclasses import dataclass
from types import ModuleType

import numpy as np
import warp as wp

from renderer.errors import SceneError
from renderer.materials import conductor, dielectric, diffuse, disney, thinfilm
from renderer.materials.bsdf import MAX_SLOTS
from renderer.scene.description import MaterialDesc, TextureDesc
from renderer.scene.params import ParamSet
from renderer.textures import TextureTable

REGISTRY: dict[str, ModuleType] = {m.NAME: m for m in (diffuse, dielectric, conductor, thinfilm, disney)}


def kind_id(name: str) -> int:
    """A stable small integer per material type (its position in the registry)."""
    return list(REGISTRY).index(name)


def dispatch_table(names: tuple[str, ...]) -> tuple[list[ModuleType], list[int]]:
    """The modules and kind ids that a kernel specialised to the materials ``names`` switches over."""
    return [REGISTRY[n] for n in names], [kind_id(n) for n in names]


@wp.struct
class Materials:
    kind: wp.array(dtype=int)
    slots: wp.array2d(dtype=int)        # (n_materials, MAX_SLOTS) texture ids, -1 unused
    bump: wp.array(dtype=int)           # float displacement texture id, -1 for none


@dataclass
class SlotBuilder:
    """What a material's ``slots`` function uses to turn its parameters into texture ids, with
    range checks that name the file and line."""

    params: ParamSet
    table: TextureTable
    textures: dict[str, TextureDesc]
    loc: object

    def _tex(self, name: str, value_type: str) -> int:
        return self.table.lookup(name, value_type, self.textures, self.loc)

    def _check(self, name: str, v, lo, hi) -> None:
        a = np.asarray(v, dtype=np.float64)
        if (lo is not None and np.any(a < lo)) or (hi is not None and np.any(a > hi)):
            raise SceneError(f'parameter "{name}" = {a.tolist()} is outside [{lo}, {hi}]',
                             getattr(self.params.params.get(name), "loc", self.loc))

    def rgb(self, name: str, default, lo: float | None = None, hi: float | None = None) -> int:
        v = self.params.rgb_or_texture(name, default if not isinstance(default, str) else None)
        if v is None:
            v = default
        if isinstance(v, str):
            return self._tex(v, "spectrum")
        self._check(name, v, lo, hi)
        return self.table.add_constant(v)

    def float(self, name: str, default, lo: float | None = None, hi: float | None = None) -> int:
        v = self.params.float_or_texture(name, default if not isinstance(default, str) else None)
        if v is None:
            v = default
        if isinstance(v, str):
            return self._tex(v, "float")
        self._check(name, v, lo, hi)
        return self.table.add_constant(v)

    def const(self, value: float) -> int:
        return self.table.add_constant(value)


def build_materials(descs: list[MaterialDesc], textures: dict[str, TextureDesc], table: TextureTable,
                    warnings: list[str], device: str) -> tuple[Materials, list, set[str]]:
    """Validate every material against its module, returning the device table, the arrays that
    back it (keep them alive) and the set of material types in use (for kernel specialisation)."""
    n = max(1, len(descs))
    kinds = np.zeros(n, dtype=np.int32)
    slot_ids = -np.ones((n, MAX_SLOTS), dtype=np.int32)
    bump = -np.ones(n, dtype=np.int32)
    used: set[str] = set()
    for i, d in enumerate(descs):
        module = REGISTRY.get(d.kind)
        if module is None:
            raise SceneError(f'material "{d.kind}" is not supported (supported: {", ".join(REGISTRY)})', d.loc)
        b = SlotBuilder(d.params, table, textures, d.loc)
        ids = module.slots(b)
        slot_ids[i, : len(ids)] = ids
        kinds[i] = kind_id(d.kind)
        disp = d.params.texture("displacement")
        if disp is not None:
            bump[i] = table.lookup(disp, "float", textures, d.loc)
        for p in d.params.unused():
            warnings.append(f'{p.loc}: parameter "{p.name}" of material "{d.kind}" is not supported and was ignored')
        used.add(d.kind)
    M = Materials()
    M.kind = wp.array(kinds, dtype=int, device=device)
    M.slots = wp.array(slot_ids, dtype=int, device=device)
    M.bump = wp.array(bump, dtype=int, device=device)
    return M, [M.kind, M.slots, M.bump], used
