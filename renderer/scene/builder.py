"""Directives -> :class:`SceneDescription`, following pbrt-v4's scene builder: a graphics state
(current transform, material, area light, orientation) saved and restored by attribute blocks,
named coordinate systems, materials, textures and object instances.

Transforms follow pbrt: the current transform matrix (CTM) maps the coordinates that follow
to world space and each transform directive post-multiplies it (``ctm = ctm @ m``), so the last
one written acts first on the geometry. At ``Camera`` the CTM is camera-from-world.
"""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import Callable, Iterable

import numpy as np

from renderer import lights, materials
from renderer.errors import Location, RenderError, SceneError, SceneErrors, UnsupportedError
from renderer.scene.description import (CameraDesc, InstanceSetDesc, IntegratorDesc, MeshDesc, SamplerDesc,
                                        SceneDescription, ShapeDesc, TextureDesc)
from renderer.scene.params import ParamSet
from renderer.scene.parser import Directive
from renderer.scene.imaging import read_camera, read_film, read_filter
from renderer.scene.loop_subdivision import loop_subdivision_surface
from renderer.scene.plymesh import ply_mesh
from renderer.scene.resolve import (NamedMaterials, drop_interface_lights, missing_mixed, missing_textures,
                                    texture_key)
from renderer.scene.shapes import MeshPool, bilinear_mesh, cylinder, disk, sphere, triangle_mesh
from renderer.scene.state import GraphicsState, ObjectDefinition, SavedState
from renderer.scene.support import KNOWN_NAMES, OPTIONS_ONLY, PBRT_V3_NAMES, UNSUPPORTED, WORLD_ONLY
from renderer.scene.texture_params import check_depth, read_texture
from renderer.sampling.sampler_spec import DEFAULT_SAMPLER, RANDOMIZATIONS
from renderer.settings import sampler_spec
from renderer.scene.upgrade import upgraded
from renderer.scene.transform import (check_single_precision, inverse, read_instance_transforms, swaps_handedness,
                                      transformed_mesh)
from renderer.scene.media_directives import MediaDirectives
from renderer.scene.transform_directives import TransformDirectives

#: Shapes we build, each from its parameters and the Shape directive's location.
SHAPES: dict[str, Callable[[ParamSet, Location], MeshDesc]] = {
    "trianglemesh": triangle_mesh, "plymesh": ply_mesh, "sphere": sphere, "disk": disk, "cylinder": cylinder,
    "bilinearmesh": bilinear_mesh, "loopsubdiv": loop_subdivision_surface}


class Builder(TransformDirectives, MediaDirectives):
    """Consumes directives one by one; one method per directive, named as the directive, except
    the ones UNSUPPORTED ignores outright."""

    def __init__(self, source: str) -> None:
        self.source = source             # the top-level file, for errors that belong to no line
        self.scene = SceneDescription(camera=CameraDesc(camera_to_world=np.eye(4)))
        self.mesh_pool = MeshPool(self.scene.meshes)
        self.state = GraphicsState()
        self.saved: list[SavedState] = []
        self.named_coordinate_systems: dict[str, np.ndarray] = {}
        self.named_materials = NamedMaterials()
        self.refused_textures: set[str] = set()
        self.objects: dict[str, ObjectDefinition] = {}
        self.current_object: ObjectDefinition | None = None
        self.default_material: int | None = None
        self.world_begun = False
        self.path_integrator: Location | None = None    # where pbrt-v4's "path" (not volpath) was named
        self._init_media()

    # -- driver

    def build(self, directives: Iterable[Directive]) -> SceneDescription:
        """Every directive in order. An unsupported type does not stop the build: all of them are
        reported together at the end (with any error that follows from them), each with file:line."""
        refused: list[SceneError] = []
        try:
            for d in directives:
                try:
                    self._directive(d)
                except UnsupportedError as e:
                    refused.append(e)
            refused.extend(self._finish())
        except SceneError as e:
            if not refused:
                raise
            refused.append(e)
        if len(refused) == 1:
            raise refused[0]
        if refused:
            raise SceneErrors(refused)
        return self.scene

    def _directive(self, d: Directive) -> None:
        d = upgraded(d, self.warn)                     # pbrt-v3 syntax, read as pbrt-v4's --upgrade writes it
        if self.world_begun and d.name in OPTIONS_ONLY:
            raise SceneError(f"{d.name} must come before WorldBegin", d.loc)
        if not self.world_begun and d.name in WORLD_ONLY:
            raise SceneError(f"{d.name} must come after WorldBegin", d.loc)
        handler = getattr(self, d.name, None)
        if handler is None:                  # a directive we only warn about (UNSUPPORTED)
            self.unsupported(d.name, "*", d.loc)
        else:
            handler(d)

    def _finish(self) -> list[SceneError]:
        """Structural errors raise; names that never resolve are returned, to be reported with the rest."""
        if not self.world_begun:
            raise SceneError(f"{self.source}: no WorldBegin, so the file describes no scene", None)
        if self.saved:
            s = self.saved[-1]
            raise SceneError(f"{s.kind} is never closed", s.loc)
        if not lights.has_lights(self.scene):
            self.scene.warnings.append(f"{self.source}: scene has no lights: the image will be black")
        unresolved = self.named_materials.resolve(self.scene, lambda: self._current_material(None))
        self._resolve_media()
        drop_interface_lights(self.scene, self.warn)
        if self.path_integrator and any(m.kind == "subsurface" for m in self.scene.materials):
            self.warn(self.path_integrator, 'pbrt-v4\'s "path" integrator ignores the "subsurface" material\'s '
                      'BSSRDF (its bodies render as clear dielectrics); rendered with subsurface scattering, '
                      'as "volpath" renders it')
        return (unresolved + missing_textures(self.scene, self.refused_textures)
                + missing_mixed(self.scene, self.named_materials))

    # -- reporting

    def warn(self, loc: Location, message: str) -> None:
        self.scene.warnings.append(f"{loc}: {message}")

    def unsupported(self, directive: str, name: str, loc: Location) -> None:
        """Warn or refuse, as UNSUPPORTED says."""
        action, reason = UNSUPPORTED.get((directive, name)) or UNSUPPORTED[(directive, "*")]
        what = f'{directive} "{name}"' if name != "*" else directive
        if action == "error":
            raise UnsupportedError(f"{what} is not supported: {reason}", loc)
        self.warn(loc, f"{what}: {reason}")

    def check_known(self, d: Directive) -> str:
        name = str(d.args[0])
        if (d.name, name) in PBRT_V3_NAMES:
            self.warn(d.loc, f'{d.name} "{name}" is pbrt-v3\'s; read as --upgrade writes it, '
                             f'{PBRT_V3_NAMES[d.name, name]}')
            return name
        if name not in KNOWN_NAMES[d.name]:
            known = ", ".join(sorted(KNOWN_NAMES[d.name]))
            raise UnsupportedError(f'unknown {d.name} "{name}" (pbrt-v4 knows {known})', d.loc)
        return name

    def warn_unused(self, d: Directive) -> None:
        what = f'{d.name} "{d.args[0]}"' if d.args else d.name
        for p in d.params.unused():
            self.warn(p.loc, f'{what}: parameter "{p.type} {p.name}" is not supported and was ignored')
        self.warn_shadowed(d.params, what)

    def warn_shadowed(self, params: ParamSet, what: str) -> None:
        """Earlier copies of a parameter given twice (pbrt-v4 uses the last)."""
        for p in params.shadowed:
            self.warn(p.loc, f'{what}: parameter "{p.name}" is given again later; the later value is used (as pbrt-v4)')

    # -- rendering options

    def Camera(self, d: Directive) -> None:
        name = self.check_known(d)
        if name == "realistic":
            self.unsupported(d.name, name, d.loc)
        world_from_camera = inverse(self.state.ctm, "Camera", d.loc)
        self.named_coordinate_systems["camera"] = world_from_camera
        self.scene.camera = read_camera(name, d.params, world_from_camera, d.loc)
        self._camera_medium(d.loc)
        self.warn_unused(d)

    def Film(self, d: Directive) -> None:
        name = self.check_known(d)
        if name not in ("rgb", "image"):
            self.unsupported(d.name, name, d.loc)
        self.scene.film = replace(read_film(d.params, d.loc, self.warn), filter=self.scene.film.filter)
        self.warn_unused(d)

    def Sampler(self, d: Directive) -> None:
        name = self.check_known(d)
        p = d.params
        if name not in RANDOMIZATIONS:
            self.unsupported(d.name, name, d.loc)
            name = DEFAULT_SAMPLER
        strata = name == "stratified"
        xs, ys = (p.int("xsamples", 4, min=1), p.int("ysamples", 4, min=1)) if strata else (4, 4)
        desc = SamplerDesc(name, xs * ys if strata else p.int("pixelsamples", 16, min=1), p.int("seed", 0),
                           p.string("randomize", "") if len(RANDOMIZATIONS[name]) > 1 else "",
                           p.bool("jitter", True) if strata else True, xs, ys)
        try:
            sampler_spec(desc)
        except RenderError as e:
            raise SceneError(f"Sampler: {e}", d.loc) from None
        self.scene.sampler = desc
        self.warn_unused(d)

    def Integrator(self, d: Directive) -> None:
        name = self.check_known(d)
        if name not in ("path", "volpath"):
            self.unsupported(d.name, name, d.loc)
        self.path_integrator = d.loc if name == "path" else None
        p = d.params
        kind = "path" if name == "path" else "volpath"      # what else we render with volpath, which is path without media
        self.scene.integrator = IntegratorDesc(kind, p.int("maxdepth", 5, min=0), p.bool("regularize", False))
        self.warn_unused(d)

    def PixelFilter(self, d: Directive) -> None:
        self.scene.film.filter = read_filter(self.check_known(d), d.params, d.loc, self.warn)
        self.warn_unused(d)

    def Accelerator(self, d: Directive) -> None:
        self.unsupported(d.name, self.check_known(d), d.loc)

    def WorldBegin(self, d: Directive) -> None:
        if self.world_begun:
            raise SceneError("WorldBegin appears twice", d.loc)
        self.world_begun = True
        self.state.ctm = np.eye(4)
        self.named_coordinate_systems["world"] = self.state.ctm

    # -- blocks

    def _push(self, d: Directive) -> None:
        self.saved.append(SavedState(d.name, replace(self.state), d.loc))

    def _pop(self, d: Directive, opened_by: str) -> SavedState:
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
        """Parameters are read, typed and range-checked by the material's declaration, here, so
        every error and warning names its file and line; what it does not declare is warned about."""
        if kind == "measured":
            self.unsupported("Material", kind, loc)
        self.scene.materials.append(materials.from_pbrt(kind, params, loc, name))
        for p in params.unused():
            self.warn(p.loc, f'parameter "{p.name}" of material "{kind}" is not supported and was ignored')
        self.warn_shadowed(params, f'material "{kind}"')
        return len(self.scene.materials) - 1

    def Material(self, d: Directive) -> None:
        self.state.material = self._add_material(str(d.args[0]), d.params, d.loc)

    def MakeNamedMaterial(self, d: Directive) -> None:
        name = str(d.args[0])
        kind = d.params.string("type")
        if kind is None:
            raise SceneError(f'MakeNamedMaterial "{name}": "string type" is required', d.loc)
        try:
            index = self._add_material(kind, d.params, d.loc, name)
        except UnsupportedError:
            self.named_materials.define(name, None, d.loc)
            raise
        self.named_materials.define(name, index, d.loc)

    def NamedMaterial(self, d: Directive) -> None:
        """Resolved when the scene is complete, as pbrt-v4 does (see renderer.scene.resolve)."""
        self.state.material = str(d.args[0])
        self.state.material_loc = d.loc

    def _current_material(self, loc: Location | None) -> int:
        """The current material; before any Material directive pbrt's default, diffuse 0.5; a
        named one not yet defined gets a placeholder that the end of the scene resolves."""
        if isinstance(self.state.material, str):
            return self.named_materials.material_for(self.state.material, self.state.material_loc or loc)
        if self.state.material is not None:
            return self.state.material
        if self.default_material is None:
            self.scene.materials.append(materials.material("diffuse", name="default", loc=loc))
            self.default_material = len(self.scene.materials) - 1
        return self.default_material

    def Texture(self, d: Directive) -> None:
        name, value_type, kind = (str(a) for a in d.args)
        if value_type not in ("float", "spectrum"):
            raise SceneError(f'Texture "{name}": type must be "float" or "spectrum", not "{value_type}"', d.loc)
        key = texture_key(self.scene.textures, name, value_type, d.loc)
        desc = TextureDesc(name, value_type, kind, d.params, Path(d.loc.file).parent, d.loc, self.state.ctm.copy())
        try:
            spec = read_texture(desc)
        except UnsupportedError:
            self.refused_textures.add(name)
            raise
        for ref in spec.refs:
            if ref not in self.scene.textures and ref not in self.refused_textures:     # either type, as pbrt
                raise SceneError(f'Texture "{name}": no texture named "{ref}" is defined before it', d.loc)
        check_depth(spec, desc, self.scene.textures)
        self.warn_unused(d)
        self.scene.textures[key] = desc

    # -- lights: each light module reads its own parameters (renderer.lights)

    def AreaLightSource(self, d: Directive) -> None:
        inverse(self.state.ctm, d.name, d.loc)
        self.state.area_light = lights.describe(d.name, str(d.args[0]), d.params, self.state.ctm, d.loc)
        self.warn_unused(d)

    def LightSource(self, d: Directive) -> None:
        inverse(self.state.ctm, d.name, d.loc)
        self.scene.lights.append(lights.describe(d.name, str(d.args[0]), d.params, self.state.ctm, d.loc))
        self.warn_unused(d)

    # -- shapes and objects

    def Shape(self, d: Directive) -> None:
        name = self.check_known(d)
        make = SHAPES.get(name)
        if make is None:
            self.unsupported(d.name, name, d.loc)
            return
        alpha = d.params.float_or_texture("alpha", 1.0)
        if self.state.area_light is not None and alpha != 1.0:
            raise UnsupportedError(f'Shape "{name}": "alpha" on an area light is not supported', d.loc)
        mesh = self.mesh_pool.shape(name, make, d.params, d.loc)
        self.warn_unused(d)
        if len(mesh.indices) == 0:
            self.warn(d.loc, f'Shape "{name}" has no triangles; skipped')
            return
        ctm = self.state.ctm
        inverse(ctm, f'Shape "{name}"', d.loc)
        check_single_precision(mesh, ctm, name, d.loc)
        obj = self.current_object
        if obj is not None:
            if self.state.area_light is not None:
                raise SceneError("area lights inside ObjectBegin/ObjectEnd are not supported (nor by pbrt-v4)",
                                 d.loc)
            mesh = transformed_mesh(mesh, inverse(obj.ctm, "ObjectBegin", obj.loc) @ ctm)
        self.scene.shapes.append(ShapeDesc(
            mesh=self.mesh_pool.add(mesh), material=self._current_material(d.loc),
            area_light=self.state.area_light,
            reverse_orientation=self.state.reverse_orientation ^ swaps_handedness(ctm), loc=d.loc, alpha=alpha))
        index = len(self.scene.shapes) - 1
        self._shape_media(index)
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
        self.current_object = self.objects[name] = ObjectDefinition(self.state.ctm, d.loc)

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

    def _mirrored_shapes(self, obj: ObjectDefinition) -> list[int]:
        if obj.mirrored is None:
            obj.mirrored = []
            for i in obj.shapes:
                s = self.scene.shapes[i]
                self.scene.shapes.append(replace(s, reverse_orientation=not s.reverse_orientation))
                obj.mirrored.append(len(self.scene.shapes) - 1)
            self._copy_media(dict(zip(obj.shapes, obj.mirrored)))
        return obj.mirrored

    def _instance_placements(self, d: Directive) -> np.ndarray:
        """(N, 4, 4) world-from-instance matrices: the CTM, times each matrix of the file if given."""
        name = d.params.string("transforms")
        ctm = self.state.ctm
        if name is None:
            return ctm[None].copy()
        return ctm @ read_instance_transforms(Path(d.loc.file).parent / name, d.loc)


