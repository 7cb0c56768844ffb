"""Names resolved when the scene is complete, as pbrt-v4 does when it creates the scene's objects:
a ``NamedMaterial`` may come before its ``MakeNamedMaterial``, and a material may name a texture
that is defined further down the file (pbrt creates every texture before any material). Shapes
made while their named material is still unknown carry a placeholder (a negative index) until
:meth:`NamedMaterials.resolve` sets it."""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Callable

from renderer.errors import Location, SceneError
from renderer.parameters import TextureRef
from renderer.scene.description import SceneDescription, TextureDesc


@dataclass
class NamedMaterials:
    """``MakeNamedMaterial`` definitions (name -> material index) and the names used before them."""

    index: dict[str, int] = field(default_factory=dict)
    refused: set[str] = field(default_factory=set)       # defined with an unsupported type (already reported)
    pending: list[tuple[str, Location]] = field(default_factory=list)

    def define(self, name: str, material: int | None, loc: Location) -> None:
        """Record a definition; ``material`` None: its type was refused (reported elsewhere)."""
        if name in self.index or name in self.refused:
            raise SceneError(f'named material "{name}" is defined twice', loc)
        if material is None:
            self.refused.add(name)
        else:
            self.index[name] = material

    def material_for(self, name: str, loc: Location) -> int:
        """The index of ``name`` if defined by now, else a placeholder resolved at the end."""
        if name in self.index:
            return self.index[name]
        self.pending.append((name, loc))
        return -len(self.pending)

    def resolve(self, scene: SceneDescription, default_material: Callable[[], int]) -> list[SceneError]:
        """Replace every placeholder; a name never defined is an error at the shape that used it
        (pbrt-v4: "no named material defined"), a refused one falls back to ``default_material()``."""
        errors: list[SceneError] = []
        for i, s in enumerate(scene.shapes):
            if s.material >= 0:
                continue
            name, loc = self.pending[-s.material - 1]
            if name in self.index:
                scene.shapes[i] = replace(s, material=self.index[name])
                continue
            if name not in self.refused:
                errors.append(SceneError(f'no material named "{name}" (NamedMaterial at {loc}; no '
                                         'MakeNamedMaterial defines it anywhere in the scene)', s.loc))
            scene.shapes[i] = replace(s, material=default_material())
        return errors


def texture_key(textures: dict[str, TextureDesc], name: str, value_type: str, loc: Location) -> str:
    """Where a new texture is stored (see :func:`renderer.scene.description.find_texture`: float and spectrum textures have
    two name spaces, as in pbrt-v4); a second texture of one name and type is an error."""
    key = name if name not in textures else f"{value_type}:{name}"
    first = textures.get(key) or (textures[name] if textures.get(name, None) is not None and
                                  textures[name].value_type == value_type else None)
    if first is not None:
        raise SceneError(f'{value_type} texture "{name}" is defined twice (first at {first.loc})', loc)
    return key


def missing_textures(scene: SceneDescription, refused: set[str]) -> list[SceneError]:
    """Every material parameter and shape alpha naming a texture the scene never defines, one error
    each (a texture whose class was refused has been reported already)."""
    missing = [SceneError(f'material "{m.kind}": parameter "{key}" names texture "{v.name}", which is not defined',
                          m.loc)
               for m in scene.materials for key, v in m.values.items()
               if isinstance(v, TextureRef) and v.name not in scene.textures and v.name not in refused]
    return missing + [SceneError(f'shape "alpha" names texture "{s.alpha}", which is not defined', s.loc)
                      for s in scene.shapes
                      if isinstance(s.alpha, str) and s.alpha not in scene.textures and s.alpha not in refused]


def missing_mixed(scene: SceneDescription, named: NamedMaterials) -> list[SceneError]:
    """Every material a mix names that no MakeNamedMaterial defines (pbrt-v4 resolves them when the
    scene is complete, so they may come later in the file)."""
    return [SceneError(f'material "mix": no named material "{n}" (no MakeNamedMaterial defines it anywhere '
                       'in the scene)', m.loc)
            for m in scene.materials if m.kind == "mix" for n in m.values.get("materials", ())
            if n not in named.index and n not in named.refused]


def drop_interface_lights(scene: SceneDescription, warn: Callable[[Location, str], None]) -> None:
    """pbrt-v4 ignores an area light on a shape with the interface material (with a warning): the
    shape is not there to emit."""
    for i, s in enumerate(scene.shapes):
        if s.area_light is not None and scene.materials[s.material].kind == "interface":
            warn(s.loc, 'ignoring the area light of a shape with the "interface" material (as pbrt-v4 does)')
            scene.shapes[i] = replace(s, area_light=None)
