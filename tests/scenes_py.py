"""Scenes built directly as SceneDescriptions, so kernel tests do not depend on the parser."""
from __future__ import annotations

import numpy as np
import trimesh

from renderer.errors import Location
from renderer.scene.description import (CameraDesc, FilmDesc, InfiniteLightDesc, InstanceSetDesc, MaterialDesc,
                                        MeshDesc, SamplerDesc, SceneDescription, ShapeDesc)
from renderer.scene.params import Param, ParamSet

HERE = Location("<test>", 0)


def params(**kw) -> ParamSet:
    """A ParamSet from keyword arguments: floats, RGB triples or texture names (str)."""
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


def look_at(eye, target, up) -> np.ndarray:
    """pbrt's LookAt as a camera-to-world matrix (+z forward, +x = cross(up, dir))."""
    eye, target, up = (np.asarray(a, dtype=np.float64) for a in (eye, target, up))
    d = target - eye
    d /= np.linalg.norm(d)
    right = np.cross(up / np.linalg.norm(up), d)
    right /= np.linalg.norm(right)
    new_up = np.cross(d, right)
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = right, new_up, d, eye
    return m


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
    desc.infinite_lights.append(InfiniteLightDesc(light_to_world=np.eye(4), L=np.full(3, sky)))
    return desc
