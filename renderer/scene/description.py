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
from renderer.media.description import MediumDesc, MediumInterfaceDesc
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
    exposure_time: float = 1.0           # shutterclose - shutteropen: scales the image (pbrt's imaging ratio)
    projection: str = "perspective"      # "orthographic", "spherical equalarea", "spherical equirectangular"
    frame_aspect: float | None = None    # pbrt's frameaspectratio (None: the film's)
    screen_window: tuple[float, float, float, float] | None = None   # x0, x1, y0, y1 (None: from the aspect)


@dataclass
class FilterDesc:
    """A pbrt-v4 pixel filter (``PixelFilter``): its type, radii and shape parameters. The default
    is a box of radius 0.5, which samples the pixel uniformly (pbrt-v4's own default is
    gaussian; a scene naming no filter keeps this renderer's images as they were)."""

    kind: str = "box"                    # box, gaussian, mitchell, sinc, triangle
    radius: tuple[float, float] = (0.5, 0.5)
    sigma: float = 0.5                   # gaussian
    b: float = 1.0 / 3.0                 # mitchell B
    c: float = 1.0 / 3.0                 # mitchell C
    tau: float = 3.0                     # sinc (Lanczos) window


@dataclass
class FilmDesc:
    """The ``rgb`` film as pbrt-v4 reads it: full resolution, the region rendered (a crop window
    in [0, 1]^2 or pixel bounds; pbrt writes only that region), the cie1931 sensor's ISO and white
    balance, the per-sample clamp and the pixel filter."""

    width: int = 1280
    height: int = 720
    filename: str = "pbrt.exr"
    crop_window: tuple[float, float, float, float] | None = None   # x0, x1, y0, y1 in [0, 1]
    pixel_bounds: tuple[int, int, int, int] | None = None          # x0, x1, y0, y1 (end exclusive)
    iso: float = 100.0                   # imaging ratio = exposure time * iso / 100
    white_balance: float = 0.0           # kelvin; 0: none (pbrt's default for the cie1931 sensor)
    max_component_value: float = float("inf")
    filter: FilterDesc = field(default_factory=FilterDesc)


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
    """``path`` ignores media, as pbrt-v4's does; ``volpath`` (pbrt-v4's default) renders them."""

    kind: str = "volpath"
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
    #: a sphere's, disk's or cylinder's exact area in object space (pbrt-v4's Shape::Area, which
    #: an area light's ``power`` divides by); None for meshes, whose every triangle is a pbrt shape
    analytic_area: float | None = None
    #: how many pbrt-v4 shapes the triangles stand for (a bilinear mesh's patches); 0: one per triangle
    pbrt_shapes: int = 0


@dataclass
class TextureDesc:
    name: str
    value_type: str                      # "float" or "spectrum"
    kind: str                            # "constant", "imagemap", "checkerboard", "scale", ...
    params: ParamSet
    base_dir: Path                       # relative file names resolve against the defining file
    loc: Location
    ctm: np.ndarray | None = None        # (4, 4) world-from-texture: the CTM at the Texture directive


def find_texture(textures: dict[str, TextureDesc], name: str, value_type: str) -> TextureDesc | None:
    """The texture ``name`` of ``value_type``. pbrt-v4 keeps float and spectrum textures in two name
    spaces: the first texture of a name is stored under the name, a second one of the other type
    under "<type>:<name>". A look-up of the other type falls back to the one there is."""
    return textures.get(f"{value_type}:{name}") or textures.get(name)


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
    alpha: float | str = 1.0             # pbrt-v4's cut-out: a constant, or a float texture's name
    media: MediumInterfaceDesc = field(default_factory=MediumInterfaceDesc)   # MediumInterface at the shape


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
    media: list[MediumDesc] = field(default_factory=list)        # MakeNamedMedium, in file order
    camera_medium: int = -1                                      # the medium the camera sits in (-1: vacuum)
    warnings: list[str] = field(default_factory=list)
    path: Path | None = None
