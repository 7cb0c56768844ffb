"""The builder's graphics state (what AttributeBegin saves), saved states, and object definitions."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from renderer.errors import Location
from renderer.scene.description import LightDesc


@dataclass
class GraphicsState:
    """What AttributeBegin saves and AttributeEnd restores."""

    ctm: np.ndarray = field(default_factory=lambda: np.eye(4))
    reverse_orientation: bool = False
    material: int | str | None = None    # None: the default diffuse material; str: a NamedMaterial's name
    material_loc: Location | None = None # where a NamedMaterial was set (for its error if never defined)
    area_light: LightDesc | None = None
    shutter_open_active: bool = True     # False after "ActiveTransform EndTime": transforms are skipped
    medium_inside: str = ""              # MediumInterface's names ("": vacuum)
    medium_outside: str = ""
    medium_loc: Location | None = None


@dataclass
class SavedState:
    kind: str                            # "AttributeBegin", "TransformBegin" or "ObjectBegin"
    state: GraphicsState
    loc: Location


@dataclass
class ObjectDefinition:
    """An ObjectBegin/ObjectEnd definition: its shapes, with meshes stored relative to ``ctm``."""

    ctm: np.ndarray                      # the CTM at ObjectBegin
    loc: Location
    shapes: list[int] = field(default_factory=list)
    mirrored: list[int] | None = None    # the same shapes with orientation flipped, made on demand
