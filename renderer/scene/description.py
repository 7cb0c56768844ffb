"""The scene as plain Python: what the parser and builder produce and the device upload consumes.

Units and defaults are resolved here; nothing in this module knows about Warp. Materials and
textures keep their :class:`ParamSet` because each material module validates its own parameters
when the scene is uploaded (adding a material touches only that module).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from renderer.errors import Location
from renderer.scene.params import ParamSet


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
    kind: str = "independent"            # the only sampler so far
    spp: int = 16
    seed: int = 0


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
    kind: str                            # "diffuse", "dielectric", "conductor", ...
    params: ParamSet
    loc: Location
    name: str = ""


@dataclass
class AreaLightDesc:
    L: np.ndarray                        # (3,) linear sRGB radiance, scale applied
    two_sided: bool = False
    loc: Location | None = None


@dataclass
class ShapeDesc:
    """A mesh bound to a material (and maybe an area light), ready to be instanced."""

    mesh: int                            # index into SceneDescription.meshes
    material: int                        # index into SceneDescription.materials
    area_light: AreaLightDesc | None = None
    reverse_orientation: bool = False
    loc: Location | None = None


@dataclass
class InstanceSetDesc:
    """Shapes placed once per transform: a plain shape has one transform, an instanced object many."""

    shapes: list[int]                    # indices into SceneDescription.shapes
    transforms: np.ndarray               # (K, 4, 4) object-to-world
    loc: Location | None = None


@dataclass
class InfiniteLightDesc:
    light_to_world: np.ndarray           # (4, 4)
    L: np.ndarray                        # (3,) constant radiance (scale applied); multiplies the image
    filename: Path | None = None         # image: square = pbrt-v4 equal-area, 2:1 = lat-long
    loc: Location | None = None


@dataclass
class DistantLightDesc:
    direction: np.ndarray                # (3,) unit vector from the scene *towards* the light, world space
    L: np.ndarray                        # (3,) radiance-scaled irradiance, scale applied
    angular_radius_deg: float = 0.0      # > 0 makes a soft sun (uniform cone)
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
    infinite_lights: list[InfiniteLightDesc] = field(default_factory=list)
    distant_lights: list[DistantLightDesc] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    path: Path | None = None
