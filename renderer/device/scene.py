"""Upload: a :class:`SceneDescription` becomes one Warp struct of device arrays, plus the set of
features (material types, light types, bump maps) the integrator kernel is specialised to."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import warp as wp

from renderer.camera import Camera, build_camera
from renderer.errors import SceneError
from renderer.geometry.instances import Geometry, GeometryData, build_geometry
from renderer.lights import build_light_table, kinds_in
from renderer.lights.table import Lights
from renderer.materials import (Materials, build_materials, dielectric, lobe_features, scatters_below, selection,
                                subsurface, thinfilm)
from renderer.media.device import Media, upload_media
from renderer.color.rgb_weights import RgbWeightTable, make_rgb_weight_table
from renderer.scene.description import SceneDescription
from renderer.settings import THIN_FILM_MODE, thin_film_samples
from renderer.textures import Textures, TextureTable


@wp.struct
class Scene:
    geo: Geometry
    tex: Textures
    mat: Materials
    lights: Lights
    cam: Camera
    shape_material: wp.array(dtype=int)
    shape_light: wp.array(dtype=int)
    shape_flip: wp.array(dtype=int)
    shape_alpha: wp.array(dtype=int)    # alpha texture id, -1 opaque (see renderer.integrators.visibility)
    spectral: RgbWeightTable    # the thin-film BSDF's spectrum → RGB weights (1 dummy entry if unused)
    spectral_n: int             # its wavelengths per evaluation, 0 for rgb3
    media: wp.array(dtype=Media)    # participating media: one struct (a stand-in unless Features.media), in an
                                    # array: by value, every CPU thread's copy of the arguments took it (demo 8 %)
    shape_media: wp.array(dtype=wp.vec2i)   # per shape its MediumInterface (inside, outside); -1 vacuum
    camera_medium: int          # the medium camera rays start in, -1 vacuum


@dataclass(frozen=True)
class Features:
    """What a scene needs from the integrator; each distinct value compiles one kernel."""

    materials: tuple[str, ...]
    bump: bool
    lights: tuple[str, ...]     # the light kinds in the scene (next-event estimation samples these)
    escaping: tuple[str, ...]   # the kinds a ray leaving the scene can see (an environment, a soft sun)
    nee: bool = True
    subsurface: bool = False    # a disney material scatters below its surface, or a subsurface material is used
    alpha: bool = False         # some shape has an alpha cut-out or the interface material
    mix: bool = False           # some material is a mix (chosen per hit before shading)
    dispersion: bool = False    # some dielectric's eta varies with the wavelength (renderer.optics.dispersion),
                                # or a subsurface body is spectral: paths may have a negative channel
    media: bool = False         # volpath with participating media (renderer.media); interface shapes are then
                                # medium boundaries the path crosses, not alpha cut-outs
    thin_slabs: bool = False    # shadow rays cross thin slabs' faces (renderer.integrators.thin_slab; not with media)
    # Which lobes the materials can reach (renderer.materials.lobe_features); the defaults compile every lobe.
    multiscatter: bool = True   # some material that may be rough counts the bounces between microfacets
    layered: bool = True        # some thinfilm takes the layered random walk (coated* always do)
    unlayered: bool = True      # some thinfilm does not (the wavefront then shades the two apart)
    smooth: tuple[str, ...] = ()    # types whose every material is smooth: no GGX lobes compiled for them
    coated_body: bool = True    # some subsurface material has a film on its boundary (renderer.materials.film_body)
    coated_disney: bool = True  # some disney material has a film over its subsurface body (.disney_film)


@dataclass
class DeviceScene:
    struct: Scene
    features: Features
    device: str
    width: int
    height: int
    keep: list = field(default_factory=list)     # every Warp object the struct points into
    geometry: GeometryData | None = None
    warnings: list[str] = field(default_factory=list)   # the upload's own (a table the thin-film mode could not bake)


def _spectral_table(needed: bool, dispersion: bool, thin_film: str, device: str) -> tuple[RgbWeightTable, int]:
    """The colour-matching table the thin-film BSDF integrates with, uploaded only when a thinfilm
    material is in the scene and the mode samples wavelengths, or when a dielectric disperses
    (its paths' wavelength weights); otherwise a one-entry stand-in."""
    n = thin_film_samples(thin_film)
    if (needed and n > 0) or dispersion:
        return make_rgb_weight_table(device), n
    table = RgbWeightTable()
    table.w = wp.zeros(1, dtype=wp.vec3, device=device)
    table.step = 1.0
    return table, n


def flatten_instances(desc: SceneDescription) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The instance sets as one instance list: mesh index, shape index, (K, 4, 4) object-to-world."""
    inst_mesh, inst_shape, xforms = [], [], []
    for s in desc.instance_sets:
        k = len(s.transforms)
        for shape in s.shapes:
            inst_mesh.append(np.full(k, desc.shapes[shape].mesh, dtype=np.int32))
            inst_shape.append(np.full(k, shape, dtype=np.int32))
            xforms.append(np.asarray(s.transforms, dtype=np.float64).reshape(k, 4, 4))
    return np.concatenate(inst_mesh), np.concatenate(inst_shape), np.concatenate(xforms)


def upload(desc: SceneDescription, device: str, width: int | None = None, height: int | None = None,
           nee: bool = True, thin_film: str = THIN_FILM_MODE) -> DeviceScene:
    width = width or desc.film.width
    height = height or desc.film.height
    if not desc.instance_sets:
        raise SceneError("the scene contains no shapes", None)
    table = TextureTable()
    mats, mat_keep, used, warnings = build_materials(desc.materials, desc.textures, table, device, thin_film)

    inst_mesh_a, inst_shape_a, xform_a = flatten_instances(desc)

    lights, shape_light = build_light_table(desc, inst_shape_a, xform_a)

    geo = build_geometry([(m.positions, m.indices, m.normals, m.uvs) for m in desc.meshes],
                         inst_mesh_a, inst_shape_a, xform_a, device)
    media = uses_media(desc)
    alpha = shape_alpha_ids(desc, table, media)
    tex, tex_keep = table.upload(device)
    L, light_keep = lights.upload(device)

    S = Scene()
    S.geo = geo.struct
    S.tex = tex
    S.mat = mats
    S.lights = L
    S.cam, cam_keep = build_camera(desc.camera, desc.film, width, height, device)
    width, height = S.cam.width, S.cam.height       # the rendered region
    S.shape_material = wp.array(np.array([s.material for s in desc.shapes] or [0], np.int32), dtype=int, device=device)
    S.shape_light = wp.array(shape_light, dtype=int, device=device)
    # normals come from world-space winding; the builder's reverse_orientation already includes
    # pbrt's handedness swap, so together they orient normals as pbrt does
    flip = [int(s.reverse_orientation) for s in desc.shapes] or [0]
    S.shape_flip = wp.array(np.array(flip, np.int32), dtype=int, device=device)
    S.shape_alpha = wp.array(alpha, dtype=int, device=device)
    dispersion = any(m.kind == dielectric.NAME and dielectric.disperses(m.values) for m in desc.materials)
    # the subsurface material's spectral bodies weigh their wavelengths with the same table
    spectral_sss = bool(np.any((mats.flags.numpy() & subsurface.SPECTRAL) != 0))
    lobes = lobe_features(desc.materials)
    films = thinfilm.NAME in used or lobes["coated_body"] or lobes["coated_disney"]    # films integrated over the wavelength
    S.spectral, S.spectral_n = _spectral_table(films, dispersion or spectral_sss, thin_film, device)
    media_up = upload_media(desc.media if media else [], device)
    S.media = wp.array([media_up.struct], dtype=Media, device=device)
    pairs = [(s.media.inside, s.media.outside) for s in desc.shapes] if media else []
    S.shape_media = wp.array(np.array(pairs or [(-1, -1)], np.int32), dtype=wp.vec2i, device=device)
    S.camera_medium = desc.camera_medium if media else -1

    light_kinds, escaping = kinds_in(lights)
    feats = Features(
        materials=tuple(sorted(used)),
        bump=bool(np.any(mats.bump.numpy() >= 0)),
        lights=light_kinds,
        escaping=escaping,
        nee=nee,
        subsurface=scatters_below(desc.materials),
        alpha=bool(np.any(alpha >= 0)),
        mix=any(m.kind == selection.MIX for m in desc.materials),
        dispersion=dispersion or spectral_sss,
        media=media,
        thin_slabs=not media and any(desc.materials[s.material].kind == thinfilm.NAME
                                     and bool(desc.materials[s.material].values.get("thinslab")) for s in desc.shapes),
        **lobes,
    )
    keep = [geo, mat_keep, tex_keep, light_keep, cam_keep, S.shape_material, S.shape_light, S.shape_flip,
            S.shape_alpha, S.spectral.w, media_up.keep, S.shape_media]
    return DeviceScene(struct=S, features=feats, device=device, width=width, height=height, keep=keep, geometry=geo,
                       warnings=warnings)


def uses_media(desc: SceneDescription) -> bool:
    """Whether the render goes through media: the volpath integrator (pbrt-v4's path ignores
    media) and some medium that a camera ray or a shape's MediumInterface puts a path into."""
    return desc.integrator.kind == "volpath" and bool(desc.media) and (
        desc.camera_medium >= 0 or any(s.media.transition for s in desc.shapes))


def shape_alpha_ids(desc: SceneDescription, table: TextureTable, media: bool = False) -> np.ndarray:
    """Per shape the texture id of its alpha (a constant 0 for the interface material unless the
    kernel crosses it as a medium boundary), -1 where the shape is opaque (alpha 1, pbrt-v4's default)."""
    ids = -np.ones(max(1, len(desc.shapes)), np.int32)
    for i, s in enumerate(desc.shapes):
        if desc.materials[s.material].kind == selection.INTERFACE and not media:
            ids[i] = table.add_constant(0.0)
        elif isinstance(s.alpha, str):
            ids[i] = table.lookup(s.alpha, "float", desc.textures, s.loc)
        elif s.alpha < 1.0:
            ids[i] = table.add_constant(s.alpha)
    return ids
