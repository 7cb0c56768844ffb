"""Scenes built directly as SceneDescriptions, so kernel tests do not depend on the parser."""
from __future__ import annotations

import numpy as np
import trimesh

from renderer.errors import Location
from renderer.lights import light
from renderer.scene.description import (CameraDesc, FilmDesc, InstanceSetDesc, MaterialDesc,
                                        MeshDesc, SamplerDesc, SceneDescription, ShapeDesc)
from renderer.scene.params import Param, ParamSet
from renderer.scene.transform import world_from_camera

HERE = Location("<test>", 0)
#: pbrt's LookAt as a camera-to-world matrix, for scenes built in tests
look_at = world_from_camera


def params(**kw) -> ParamSet:
    """A pbrt ParamSet from keyword arguments (floats, RGB triples or texture names as str), for
    TextureDesc, which still takes pbrt parameter lists; materials take plain values instead
    (``renderer.materials.material("diffuse", reflectance=(0.8, 0.2, 0.2))``)."""
    ps = ParamSet()
    for k, v in kw.items():
        if isinstance(v, str):
            ps.add(Param("texture", k, [v], HERE))
        elif isinstance(v, bool):
            ps.add(Param("bool", k, [v], HERE))
        elif np.ndim(v) == 0:
            ps.add(Param("float", k, [float(v)], HERE))
        else:
            ps.add(Param("rgb", k, [float(x) for x in v], HERE))
    return ps


def sphere_mesh(radius: float = 1.0, subdivisions: int = 4) -> MeshDesc:
    s = trimesh.creation.icosphere(subdivisions=subdivisions, radius=radius)
    v = s.vertices.astype(np.float32)
    return MeshDesc(positions=v, indices=s.faces.astype(np.int32), normals=v / np.linalg.norm(v, axis=1, keepdims=True))


def single_object_scene(material: MaterialDesc, mesh: MeshDesc | None = None, sky: float = 1.0,
                        res: int = 16, fov: float = 30.0, distance: float = 5.0) -> SceneDescription:
    """One object at the origin under a uniform sky, seen from -z."""
    desc = SceneDescription(camera=CameraDesc(camera_to_world=look_at((0, 0, -distance), (0, 0, 0), (0, 1, 0)),
                                              fov_deg=fov),
                            film=FilmDesc(width=res, height=res), sampler=SamplerDesc(spp=16, seed=1))
    desc.meshes.append(mesh or sphere_mesh())
    desc.materials.append(material)
    desc.shapes.append(ShapeDesc(mesh=0, material=0))
    desc.instance_sets.append(InstanceSetDesc(shapes=[0], transforms=np.eye(4)[None]))
    desc.lights.append(light("infinite", L=(sky, sky, sky)))
    return desc


def flat_body_scene(kind: str, material_params: str, integrator: str = "volpath") -> str:
    """pbrt-v4 text of a wide flat slab of material ``kind`` under a white sky, seen from straight
    above by a 4x4 orthographic camera: the flat-body closed forms of the subsurface tests."""
    return f"""LookAt 0 5 0  0 0 0  0 0 1
Camera "orthographic" "float screenwindow" [-0.5 0.5 -0.5 0.5]
Film "rgb" "integer xresolution" [4] "integer yresolution" [4] "string filename" "x.exr"
Sampler "independent" "integer pixelsamples" [64]
Integrator "{integrator}" "integer maxdepth" [3]
WorldBegin
LightSource "infinite" "rgb L" [1 1 1]
Material "{kind}" {material_params}
Shape "trianglemesh" "point3 P" [-40 0 -40  40 0 -40  40 0 40  -40 0 40] "integer indices" [0 2 1 0 3 2]
"""
