"""The scene as plain Python: what the parser and builder produce and the device upload consumes.

Units and defaults are resolved here; nothing in this module knows about Warp. Materials hold
plain values, validated against their module's declared parameters when they are made
(:func:`renderer.materials.material`, or the builder from a pbrt file); textures still keep their
:class:`ParamSet`.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Union

import numpy as np

from renderer.errors import Location
from renderer.sampling.sampler_spec import DEFAULT_SAMPLER
from renderer.scene.params import ParamSet

if TYPE_CHECKING:
    from renderer.parameters import TextureRef

#: A material parameter's value: a float, an RGB triple, a bool, or a texture bound by name.
MaterialValue = Union[float, tuple, bool, "TextureRef"]


@dataclass
class CameraDesc:
    camera_to_world: np.ndarray          # (4, 4); camera looks down +z, +y up, pbrt's left-handed frame
    fov_deg: float = 90.0                # on the shorter image axis, as pbrt
    lens_radius: float = 0.0
    focal_distance: float = 1e6


@dataclass
class FilmDesc:
    width: int = 1280
    height: int = 720
    filename: str = "pbrt.exr"


@dataclass
class SamplerDesc:
    kind: str = DEFAULT_SAMPLER          # pbrt-v4's default when a scene names none
    spp: int = 16
    seed: int = 0
    randomize: str = ""                  # "" = the sampler's default randomisation
    jitter: bool = True                  # stratified only, as are the strata counts
    xsamples: int = 4
    ysamples: int = 4


@dataclass
class IntegratorDesc:
    kind: str = "path"
    max_depth: int = 5
    regularize: bool = False


@dataclass
class MeshDesc:
    """A triangle mesh in its own object space. Shapes (sphere, disk, bilinear patch) arrive tessellated."""

    positions: np.ndarray                # (V, 3) float32
    indices: np.ndarray                  # (F, 3) int32
    normals: np.ndarray | None = None    # (V, 3) float32, per-vertex shading normals
    uvs: np.ndarray | None = None        # (V, 2) float32
    loc: Location | None = None
    name: str = ""


@dataclass
class TextureDesc:
    name: str
    value_type: str                      # "float" or "spectrum"
    kind: str                            # "constant", "imagemap", "checkerboard", "scale", ...
    params: ParamSet
    base_dir: Path                       # relative file names resolve against the defining file
    loc: Location


@dataclass
class MaterialDesc:
    """Build with :func:`renderer.materials.material`, which validates the values."""

    kind: str                            # "diffuse", "dielectric", "conductor", ...
    values: dict[str, MaterialValue]     # the parameters given (defaults apply to the rest)
    loc: Location | None = None
    name: str = ""


@dataclass
class LightDesc:
    """A light: its type and plain parameter values. Build with :func:`renderer.lights.light`,
    which validates them against the light's declared parameters and fills in the defaults."""

    kind: str                            # a renderer.lights.REGISTRY name: "infinite", "distant", "point", ...
    values: dict[str, Any]               # every declared parameter (None: an optional one not given)
    light_to_world: np.ndarray = field(default_factory=lambda: np.eye(4))   # (4, 4): the CTM at the light
    loc: Location | None = None


@dataclass
class ShapeDesc:
    """A mesh bound to a material (and maybe an area light), ready to be instanced."""

    mesh: int                            # index into SceneDescription.meshes
    material: int                        # index into SceneDescription.materials
    area_light: LightDesc | None = None  # an area light ("diffuse") that every instance emits
    reverse_orientation: bool = False
    loc: Location | None = None


@dataclass
class InstanceSetDesc:
    """Shapes placed once per transform: a plain shape has one transform, an instanced object many."""

    shapes: list[int]                    # indices into SceneDescription.shapes
    transforms: np.ndarray               # (K, 4, 4) object-to-world
    loc: Location | None = None


@dataclass
class SceneDescription:
    camera: CameraDesc
    film: FilmDesc = field(default_factory=FilmDesc)
    sampler: SamplerDesc = field(default_factory=SamplerDesc)
    integrator: IntegratorDesc = field(default_factory=IntegratorDesc)
    meshes: list[MeshDesc] = field(default_factory=list)
    materials: list[MaterialDesc] = field(default_factory=list)
    textures: dict[str, TextureDesc] = field(default_factory=dict)
    shapes: list[ShapeDesc] = field(default_factory=list)
    instance_sets: list[InstanceSetDesc] = field(default_factory=list)
    lights: list[LightDesc] = field(default_factory=list)        # LightSource lights, in file order
    warnings: list[str] = field(default_factory=list)
    path: Path | None = None
