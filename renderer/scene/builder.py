"""Directives -> :class:`SceneDescription`, following pbrt-v4's scene builder: a graphics state
(current transform, material, area light, orientation) saved and restored by attribute blocks,
named coordinate systems, materials, textures and object instances.

Transforms follow pbrt: the current transform matrix (CTM) maps the coordinates that follow
to world space and each transform directive post-multiplies it (``ctm = ctm @ m``), so the last
one written acts first on the geometry. At ``Camera`` the CTM is camera-from-world.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Callable, Iterable

import numpy as np

from renderer.errors import Location, MissingFileError, SceneError
from renderer.scene.description import (AreaLightDesc, CameraDesc, DistantLightDesc, FilmDesc, InfiniteLightDesc,
                                        InstanceSetDesc, IntegratorDesc, MaterialDesc, MeshDesc, SamplerDesc,
                                        SceneDescription, ShapeDesc, TextureDesc)
from renderer.scene.params import Param, ParamSet
from renderer.scene.parser import Directive
from renderer.scene.plymesh import ply_mesh
from renderer.scene.shapes import bilinear_mesh, disk, sphere, triangle_mesh
from renderer.scene.transform import (from_pbrt_matrix, inverse, look_at, rotate, scale, swaps_handedness,
                                      transformed_mesh, translate)

#: pbrt-v4 features this renderer does not implement. "warn": ignored with a located warning,
#: because the picture stays essentially right; "error": refused, because ignoring them would
#: change the picture badly. ``"*"`` stands for any name not listed (or for a directive without
#: a name). Parameters of supported directives that are not implemented (or misspelt) always warn.
UNSUPPORTED: dict[tuple[str, str], tuple[str, str]] = {
    ("Camera", "orthographic"): ("error", "only the perspective camera is implemented"),
    ("Camera", "realistic"): ("error", "only the perspective camera is implemented"),
    ("Camera", "spherical"): ("error", "only the perspective camera is implemented"),
    ("Shape", "curve"): ("error", "curves are not implemented"),
    ("Shape", "cylinder"): ("error", "cylinders are not implemented"),
    ("Shape", "loopsubdiv"): ("error", "subdivision surfaces are not implemented"),
    ("LightSource", "point"): ("error", "only infinite, distant and area lights are implemented"),
    ("LightSource", "spot"): ("error", "only infinite, distant and area lights are implemented"),
    ("LightSource", "goniometric"): ("error", "only infinite, distant and area lights are implemented"),
    ("LightSource", "projection"): ("error", "only infinite, distant and area lights are implemented"),
    ("Material", "measured"): ("error", "measured BSDFs are not implemented"),
    ("MediumInterface", "*"): ("error", "participating media are not implemented"),
    ("MakeNamedMedium", "*"): ("warn", "participating media are not implemented; the medium is ignored "
                                       "(using it in a MediumInterface is an error)"),
    ("Film", "gbuffer"): ("warn", 'rendered as an "rgb" film'),
    ("Film", "spectral"): ("warn", 'rendered as an "rgb" film'),
    ("Sampler", "*"): ("warn", "rendered with the independent sampler (low-discrepancy samplers are not implemented)"),
    ("Integrator", "*"): ("warn", 'rendered with the "path" integrator'),
    ("PixelFilter", "*"): ("warn", "pixel filters are not implemented; samples are box-filtered"),
    ("Accelerator", "*"): ("warn", "the BVH is this renderer's own"),
    ("Attribute", "*"): ("warn", "default parameters set by Attribute are ignored"),
    ("ColorSpace", "*"): ("warn", "colours are always linear sRGB"),
    ("Option", "*"): ("warn", "options are ignored"),
    ("ActiveTransform", "*"): ("warn", "motion blur is not implemented; the shutter-open transforms are used"),
    ("TransformTimes", "*"): ("warn", "motion blur is not implemented; the shutter-open transforms are used"),
    ("WorldEnd", "*"): ("warn", "a pbrt-v3 directive; ignored"),
}

#: The names pbrt-v4 knows for each kind of object; a name outside these is an error.
KNOWN_NAMES: dict[str, frozenset[str]] = {
    "Camera": frozenset({"perspective", "orthographic", "realistic", "spherical"}),
    "Film": frozenset({"rgb", "gbuffer", "spectral"}),
    "Sampler": frozenset({"independent", "sobol", "zsobol", "halton", "pmj02bn", "paddedsobol", "stratified"}),
    "Integrator": frozenset({"path", "volpath", "ambientocclusion", "bdpt", "lightpath", "mlt", "randomwalk",
                             "simplepath", "simplevolpath", "sppm", "aov"}),
    "PixelFilter": frozenset({"box", "gaussian", "mitchell", "sinc", "triangle"}),
    "Accelerator": frozenset({"bvh", "kdtree"}),
    "Shape": frozenset({"trianglemesh", "plymesh", "sphere", "disk", "bilinearmesh", "curve", "cylinder",
                        "loopsubdiv"}),
    "LightSource": frozenset({"infinite", "distant", "point", "spot", "goniometric", "projection"}),
    "AreaLightSource": frozenset({"diffuse"}),
}

#: Shapes we build, each from its parameters and the Shape directive's location.
SHAPES: dict[str, Callable[[ParamSet, Location], MeshDesc]] = {
    "trianglemesh": triangle_mesh, "plymesh": ply_mesh, "sphere": sphere, "disk": disk,
    "bilinearmesh": bilinear_mesh,
}

#: As in pbrt-v4: rendering options come before WorldBegin, scene contents after it.
OPTIONS_ONLY = frozenset({"Camera", "Film", "Sampler", "Integrator", "PixelFilter", "Accelerator"})
WORLD_ONLY = frozenset({"AttributeBegin", "AttributeEnd", "Attribute", "Shape", "ReverseOrientation", "ObjectBegin",
                        "ObjectEnd", "ObjectInstance", "LightSource", "AreaLightSource", "Material",
                        "MakeNamedMaterial", "NamedMaterial", "Texture"})















# --- graphics state ----------------------------------------------------------------------------

@dataclass
class GraphicsState:
    """What AttributeBegin saves and AttributeEnd restores."""

    ctm: np.ndarray = field(default_factory=lambda: np.eye(4))
    reverse_orientation: bool = False
    material: int | None = None          # None: the default diffuse material
    area_light: AreaLightDesc | None = None
    shutter_open_active: bool = True     # False after "ActiveTransform EndTime": transforms are skipped


@dataclass
class _Saved:
    kind: str                            # "AttributeBegin", "TransformBegin" or "ObjectBegin"
    state: GraphicsState
    loc: Location


@dataclass
class _Object:
    """An ObjectBegin/ObjectEnd definition: its shapes, with meshes stored relative to ``ctm``."""

    ctm: np.ndarray                      # the CTM at ObjectBegin
    loc: Location
    shapes: list[int] = field(default_factory=list)
    mirrored: list[int] | None = None    # the same shapes with orientation flipped, made on demand


class Builder:
    """Consumes directives one by one; one method per directive, named as the directive, except
    the ones UNSUPPORTED ignores outright."""

    def __init__(self, source: str) -> None:
        self.source = source             # the top-level file, for errors that belong to no line
        self.scene = SceneDescription(camera=CameraDesc(camera_to_world=np.eye(4)))
        self.state = GraphicsState()
        self.saved: list[_Saved] = []
        self.named_coordinate_systems: dict[str, np.ndarray] = {}
        self.named_materials: dict[str, int] = {}
        self.objects: dict[str, _Object] = {}
        self.current_object: _Object | None = None
        self.default_material: int | None = None
        self.world_begun = False

    # -- driver

    def build(self, directives: Iterable[Directive]) -> SceneDescription:
        for d in directives:
            if self.world_begun and d.name in OPTIONS_ONLY:
                raise SceneError(f"{d.name} must come before WorldBegin", d.loc)
            if not self.world_begun and d.name in WORLD_ONLY:
                raise SceneError(f"{d.name} must come after WorldBegin", d.loc)
            handler = getattr(self, d.name, None)
            if handler is None:                  # a directive we only warn about (UNSUPPORTED)
                self.unsupported(d.name, "*", d.loc)
            else:
                handler(d)
        if not self.world_begun:
            raise SceneError(f"{self.source}: no WorldBegin, so the file describes no scene", None)
        if self.saved:
            s = self.saved[-1]
            raise SceneError(f"{s.kind} is never closed", s.loc)
        return self.scene

    # -- reporting

    def warn(self, loc: Location, message: str) -> None:
        self.scene.warnings.append(f"{loc}: {message}")

    def unsupported(self, directive: str, name: str, loc: Location) -> None:
        """Warn or refuse, as UNSUPPORTED says."""
        action, reason = UNSUPPORTED.get((directive, name)) or UNSUPPORTED[(directive, "*")]
        what = f'{directive} "{name}"' if name != "*" else directive
        if action == "error":
            raise SceneError(f"{what} is not supported: {reason}", loc)
        self.warn(loc, f"{what}: {reason}")

    def check_known(self, d: Directive) -> str:
        name = str(d.args[0])
        if name not in KNOWN_NAMES[d.name]:
            raise SceneError(f'unknown {d.name} "{name}" (pbrt-v4 knows {", ".join(sorted(KNOWN_NAMES[d.name]))})',
                             d.loc)
        return name

    def warn_unused(self, d: Directive) -> None:
        what = f'{d.name} "{d.args[0]}"' if d.args else d.name
        for p in d.params.unused():
            self.warn(p.loc, f'{what}: parameter "{p.type} {p.name}" is not supported and was ignored')

    # -- transforms

    def _set_ctm(self, m: np.ndarray) -> None:
        """Only the shutter-open transform is kept (motion blur is not implemented)."""
        if self.state.shutter_open_active:
            self.state.ctm = m

    def _concat(self, m: np.ndarray) -> None:
        self._set_ctm(self.state.ctm @ m)

    def Identity(self, d: Directive) -> None:
        self._set_ctm(np.eye(4))

    def Translate(self, d: Directive) -> None:
        self._concat(translate(np.asarray(d.args)))

    def Scale(self, d: Directive) -> None:
        self._concat(scale(np.asarray(d.args)))

    def Rotate(self, d: Directive) -> None:
        self._concat(rotate(float(d.args[0]), np.asarray(d.args[1:]), d.loc))

    def LookAt(self, d: Directive) -> None:
        eye, target, up = np.asarray(d.args, dtype=np.float64).reshape(3, 3)
        self._concat(look_at(eye, target, up, d.loc))

    def ConcatTransform(self, d: Directive) -> None:
        self._concat(from_pbrt_matrix(d.args))

    def Transform(self, d: Directive) -> None:
        self._set_ctm(from_pbrt_matrix(d.args))

    def CoordinateSystem(self, d: Directive) -> None:
        self.named_coordinate_systems[str(d.args[0])] = self.state.ctm

    def CoordSysTransform(self, d: Directive) -> None:
        name = str(d.args[0])
        if name not in self.named_coordinate_systems:
            self.warn(d.loc, f'CoordSysTransform: no coordinate system named "{name}"; ignored (as pbrt does)')
        else:
            self._set_ctm(self.named_coordinate_systems[name])

    def ActiveTransform(self, d: Directive) -> None:
        which = str(d.args[0])
        if which not in ("StartTime", "EndTime", "All"):
            raise SceneError(f'ActiveTransform expects StartTime, EndTime or All, not "{which}"', d.loc)
        self.unsupported(d.name, "*", d.loc)
        self.state.shutter_open_active = which != "EndTime"

    # -- rendering options

    def Camera(self, d: Directive) -> None:
        name = self.check_known(d)
        if name != "perspective":
            self.unsupported(d.name, name, d.loc)
        p = d.params
        fov = p.float("fov", 90.0)
        if not 0.0 < fov < 180.0:
            raise SceneError(f'Camera: "fov" must be between 0 and 180 degrees, got {fov}', p.get("fov").loc)
        lens_radius = p.float("lensradius", 0.0, min=0.0)
        focal_distance = p.float("focaldistance", 1e6)
        if focal_distance <= 0.0:
            raise SceneError(f'Camera: "focaldistance" must be > 0, got {focal_distance}', d.loc)
        world_from_camera = inverse(self.state.ctm, "Camera", d.loc)
        self.named_coordinate_systems["camera"] = world_from_camera
        self.scene.camera = CameraDesc(world_from_camera, fov, lens_radius, focal_distance)
        self.warn_unused(d)

    def Film(self, d: Directive) -> None:
        name = self.check_known(d)
        if name != "rgb":
            self.unsupported(d.name, name, d.loc)
        p = d.params
        self.scene.film = FilmDesc(p.int("xresolution", 1280, min=1), p.int("yresolution", 720, min=1),
                                   p.string("filename", "pbrt.exr"))
        self.warn_unused(d)

    def Sampler(self, d: Directive) -> None:
        name = self.check_known(d)
        p = d.params
        if name == "stratified":
            spp = p.int("xsamples", 4, min=1) * p.int("ysamples", 4, min=1)
        else:
            spp = p.int("pixelsamples", 16, min=1)
        if name != "independent":
            self.unsupported(d.name, name, d.loc)
        self.scene.sampler = SamplerDesc("independent", spp, p.int("seed", 0))
        self.warn_unused(d)

    def Integrator(self, d: Directive) -> None:
        name = self.check_known(d)
        if name not in ("path", "volpath"):
            self.unsupported(d.name, name, d.loc)
        p = d.params
        self.scene.integrator = IntegratorDesc("path", p.int("maxdepth", 5, min=0), p.bool("regularize", False))
        self.warn_unused(d)

    def PixelFilter(self, d: Directive) -> None:
        self.unsupported(d.name, self.check_known(d), d.loc)

    def Accelerator(self, d: Directive) -> None:
        self.unsupported(d.name, self.check_known(d), d.loc)

    def MediumInterface(self, d: Directive) -> None:
        if any(d.args):
            self.unsupported(d.name, "*", d.loc)

    def WorldBegin(self, d: Directive) -> None:
        if self.world_begun:
            raise SceneError("WorldBegin appears twice", d.loc)
        self.world_begun = True
        self.state.ctm = np.eye(4)
        self.named_coordinate_systems["world"] = self.state.ctm

    # -- blocks

    def _push(self, d: Directive) -> None:
        self.saved.append(_Saved(d.name, replace(self.state), d.loc))

    def _pop(self, d: Directive, opened_by: str) -> _Saved:
        if not self.saved:
            raise SceneError(f"{d.name} without a matching {opened_by}", d.loc)
        top = self.saved[-1]
        if top.kind != opened_by:
            raise SceneError(f"{d.name} closes the {top.kind} at {top.loc}", d.loc)
        return self.saved.pop()

    def AttributeBegin(self, d: Directive) -> None:
        self._push(d)

    def AttributeEnd(self, d: Directive) -> None:
        self.state = self._pop(d, "AttributeBegin").state

    def TransformBegin(self, d: Directive) -> None:
        self._push(d)

    def TransformEnd(self, d: Directive) -> None:
        saved = self._pop(d, "TransformBegin").state
        self.state.ctm, self.state.shutter_open_active = saved.ctm, saved.shutter_open_active

    def ReverseOrientation(self, d: Directive) -> None:
        self.state.reverse_orientation = not self.state.reverse_orientation

    # -- materials and textures

    def _add_material(self, kind: str, params: ParamSet, loc: Location, name: str = "") -> int:
        """Material parameters are left unmarked: the device stage validates them per material."""
        if kind == "measured":
            self.unsupported("Material", kind, loc)
        kind = "interface" if kind in ("", "none", "interface") else kind
        self.scene.materials.append(MaterialDesc(kind, params, loc, name))
        return len(self.scene.materials) - 1

    def Material(self, d: Directive) -> None:
        self.state.material = self._add_material(str(d.args[0]), d.params, d.loc)

    def MakeNamedMaterial(self, d: Directive) -> None:
        name = str(d.args[0])
        if name in self.named_materials:
            raise SceneError(f'named material "{name}" is defined twice', d.loc)
        kind = d.params.string("type")
        if kind is None:
            raise SceneError(f'MakeNamedMaterial "{name}": "string type" is required', d.loc)
        self.named_materials[name] = self._add_material(kind, d.params, d.loc, name)

    def NamedMaterial(self, d: Directive) -> None:
        name = str(d.args[0])
        if name not in self.named_materials:
            raise SceneError(f'no material named "{name}" (define it with MakeNamedMaterial first)', d.loc)
        self.state.material = self.named_materials[name]

    def _current_material(self, loc: Location) -> int:
        """The current material; before any Material directive pbrt's default, diffuse 0.5."""
        if self.state.material is not None:
            return self.state.material
        if self.default_material is None:
            params = ParamSet(loc=loc)
            params.add(Param("rgb", "reflectance", [0.5, 0.5, 0.5], loc))
            self.default_material = self._add_material("diffuse", params, loc, "default")
        return self.default_material

    def Texture(self, d: Directive) -> None:
        name, value_type, kind = (str(a) for a in d.args)
        if value_type not in ("float", "spectrum"):
            raise SceneError(f'Texture "{name}": type must be "float" or "spectrum", not "{value_type}"', d.loc)
        if name in self.scene.textures:
            raise SceneError(f'texture "{name}" is defined twice (first at {self.scene.textures[name].loc})', d.loc)
        self.scene.textures[name] = TextureDesc(name, value_type, kind, d.params, Path(d.loc.file).parent, d.loc)

    # -- lights

    def AreaLightSource(self, d: Directive) -> None:
        self.check_known(d)
        p = d.params
        L = p.rgb("L", [1.0, 1.0, 1.0]) * p.float("scale", 1.0)
        self.state.area_light = AreaLightDesc(L, p.bool("twosided", False), d.loc)
        self.warn_unused(d)

    def LightSource(self, d: Directive) -> None:
        name = self.check_known(d)
        if name == "infinite":
            self.scene.infinite_lights.append(self._infinite(d))
        elif name == "distant":
            self.scene.distant_lights.append(self._distant(d))
        else:
            self.unsupported(d.name, name, d.loc)
        self.warn_unused(d)

    def _infinite(self, d: Directive) -> InfiniteLightDesc:
        p = d.params
        filename = p.string("filename")
        L = p.rgb("L")
        if filename is not None and L is not None:
            raise SceneError('LightSource "infinite": give either "L" or "filename", not both', d.loc)
        path = None
        if filename is not None:
            path = Path(d.loc.file).parent / filename
            if not path.is_file():
                raise MissingFileError(path, d.loc, "environment image")
        L = (np.ones(3) if L is None else L) * p.float("scale", 1.0)
        return InfiniteLightDesc(self.state.ctm.copy(), L, path, d.loc)

    def _distant(self, d: Directive) -> DistantLightDesc:
        p = d.params
        src = p.floats("from", ("point3",))
        dst = p.floats("to", ("point3",))
        src = np.zeros(3) if src is None else src
        dst = np.array([0.0, 0.0, 1.0]) if dst is None else dst
        if src.size != 3 or dst.size != 3:
            raise SceneError('LightSource "distant": "from" and "to" take one point each', d.loc)
        w = self.state.ctm[:3, :3] @ (src - dst)
        if not np.linalg.norm(w) > 0.0:
            raise SceneError('LightSource "distant": "from" and "to" give no direction', d.loc)
        L = p.rgb("L", [1.0, 1.0, 1.0]) * p.float("scale", 1.0)
        return DistantLightDesc(w / np.linalg.norm(w), L, p.float("angularradius", 0.0, min=0.0, max=90.0), d.loc)

    # -- shapes and objects

    def Shape(self, d: Directive) -> None:
        name = self.check_known(d)
        make = SHAPES.get(name)
        if make is None:
            self.unsupported(d.name, name, d.loc)
            return
        mesh = make(d.params, d.loc)
        self.warn_unused(d)
        if len(mesh.indices) == 0:
            self.warn(d.loc, f'Shape "{name}" has no triangles; skipped')
            return
        ctm = self.state.ctm
        obj = self.current_object
        if obj is not None:
            if self.state.area_light is not None:
                raise SceneError("area lights inside ObjectBegin/ObjectEnd are not supported (nor by pbrt-v4)",
                                 d.loc)
            mesh = transformed_mesh(mesh, inverse(obj.ctm, "ObjectBegin", obj.loc) @ ctm)
        self.scene.meshes.append(mesh)
        self.scene.shapes.append(ShapeDesc(
            mesh=len(self.scene.meshes) - 1, material=self._current_material(d.loc),
            area_light=self.state.area_light,
            reverse_orientation=self.state.reverse_orientation ^ swaps_handedness(ctm), loc=d.loc))
        index = len(self.scene.shapes) - 1
        if obj is not None:
            obj.shapes.append(index)
        else:
            self.scene.instance_sets.append(InstanceSetDesc([index], ctm[None].copy(), d.loc))

    def ObjectBegin(self, d: Directive) -> None:
        """Like pbrt-v4, ObjectBegin also saves the graphics state, which ObjectEnd restores."""
        name = str(d.args[0])
        if self.current_object is not None:
            raise SceneError(f'ObjectBegin "{name}" inside another object definition', d.loc)
        if name in self.objects:
            raise SceneError(f'object "{name}" is defined twice (first at {self.objects[name].loc})', d.loc)
        self._push(d)
        self.current_object = self.objects[name] = _Object(self.state.ctm, d.loc)

    def ObjectEnd(self, d: Directive) -> None:
        if self.current_object is None:
            raise SceneError("ObjectEnd without a matching ObjectBegin", d.loc)
        self.state = self._pop(d, "ObjectBegin").state
        self.current_object = None

    def ObjectInstance(self, d: Directive) -> None:
        """One instance at the CTM, or (extension) one per matrix of ``"string transforms"``.

        pbrt-v4 places an instance's shapes at ctm_instance @ ctm_shape. The meshes are stored
        relative to the CTM at ObjectBegin (o), so each instance transform is ctm_instance @ o:
        the same world placement, with vertices kept near the object's own origin.
        Orientation: pbrt flips normals for a shape's own handedness swap but not for the
        instance's, while the device orients normals by world-space winding; instances whose
        transform mirrors therefore use copies of the shapes (same meshes) with the flag flipped."""
        name = str(d.args[0])
        if self.current_object is not None:
            raise SceneError("ObjectInstance inside an object definition", d.loc)
        obj = self.objects.get(name)
        if obj is None:
            raise SceneError(f'no object named "{name}" (define it with ObjectBegin first)', d.loc)
        placements = self._instance_placements(d)
        self.warn_unused(d)
        if not obj.shapes or not len(placements):
            self.warn(d.loc, f'ObjectInstance "{name}" places nothing (no shapes or no transforms)')
            return
        mirrored = np.linalg.det(placements[:, :3, :3]) < 0.0
        for flip in (False, True):
            group = placements[mirrored == flip]
            if len(group):
                shapes = self._mirrored_shapes(obj) if flip else obj.shapes
                self.scene.instance_sets.append(InstanceSetDesc(list(shapes), group @ obj.ctm, d.loc))

    def _mirrored_shapes(self, obj: _Object) -> list[int]:
        if obj.mirrored is None:
            obj.mirrored = []
            for i in obj.shapes:
                s = self.scene.shapes[i]
                self.scene.shapes.append(replace(s, reverse_orientation=not s.reverse_orientation))
                obj.mirrored.append(len(self.scene.shapes) - 1)
        return obj.mirrored

    def _instance_placements(self, d: Directive) -> np.ndarray:
        """(N, 4, 4) world-from-instance matrices: the CTM, times each matrix of the file if given."""
        name = d.params.string("transforms")
        ctm = self.state.ctm
        if name is None:
            return ctm[None].copy()
        path = Path(d.loc.file).parent / name
        if not path.is_file():
            raise MissingFileError(path, d.loc, "instance transforms")
        try:
            data = np.load(path, allow_pickle=False)
            if isinstance(data, np.ndarray):             # .npy: the array itself
                T = data
            else:                                        # .npz: the array named "transforms"
                with data:
                    if "transforms" not in data.files:
                        raise SceneError(f'{path}: no array named "transforms" (has {", ".join(data.files)})',
                                         d.loc)
                    T = data["transforms"]
            T = np.asarray(T, dtype=np.float64)
        except (OSError, ValueError) as e:
            raise SceneError(f"{path}: cannot read instance transforms ({e})", d.loc) from e
        if T.ndim != 3 or T.shape[1:] != (4, 4):
            raise SceneError(f"{path}: instance transforms must have shape (N, 4, 4), not {T.shape}", d.loc)
        if not np.all(np.isfinite(T)):
            raise SceneError(f"{path}: instance transforms contain NaN or infinite values", d.loc)
        return ctm @ T


