"""The cross-check's scenes, built once for both renderers: ``ours(spec)`` is our
SceneDescription, ``mitsuba_scene(spec, tmp)`` Mitsuba 3's (conventions made to agree:
test_mitsuba_crosscheck.py's docstring). Imports stay inside the functions (trimesh, the
renderer, Mitsuba), so that a process rendering with one renderer, as
benchmarks/time_to_error.py's children do, pays only for that renderer's imports."""
from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from renderer.scene.description import SceneDescription

@dataclass
class Obj:
    positions: np.ndarray
    faces: np.ndarray
    normals: np.ndarray | None = None
    uvs: np.ndarray | None = None
    kind: str = "diffuse"                 # "diffuse" or "dielectric"
    rgb: tuple = (0.5, 0.5, 0.5)          # diffuse reflectance
    checker: tuple | None = None          # (tex1, tex2, pbrt uscale = vscale)
    eta: float = 1.5


@dataclass
class Spec:
    objects: list[Obj]
    eye: tuple
    target: tuple
    width: int = 32
    height: int = 24
    fov: float = 40.0
    sky: float | None = 1.0
    sun: tuple | None = None              # (direction towards the light, irradiance)
    max_depth: int = 5
    lens_radius: float = 0.0
    focal_distance: float = 1e6
    spp: int = 256
    tags: dict = field(default_factory=dict)


def sphere(center, radius, subdiv=3, **kw) -> Obj:
    import trimesh

    s = trimesh.creation.icosphere(subdivisions=subdiv, radius=radius)
    v = np.asarray(s.vertices)          # plain arrays (not trimesh's tracked ones): they pickle without trimesh
    n = v / np.linalg.norm(v, axis=1, keepdims=True)
    return Obj(positions=(v + np.asarray(center)).astype(np.float32), faces=np.asarray(s.faces).astype(np.int32),
               normals=n.astype(np.float32), **kw)


def quad(corners, **kw) -> Obj:
    """A quad (p00, p10, p11, p01) with uv (0,0), (1,0), (1,1), (0,1), wound so that its normal is
    (p10 - p00) x (p01 - p00)."""
    P = np.asarray(corners, np.float32)
    return Obj(positions=P, faces=np.array([[0, 1, 2], [0, 2, 3]], np.int32),
               uvs=np.array([[0, 0], [1, 0], [1, 1], [0, 1]], np.float32), **kw)


def ours(spec: Spec) -> SceneDescription:
    from renderer.lights import light
    from renderer.materials import material
    from renderer.scene.description import (CameraDesc, FilmDesc, InstanceSetDesc, MeshDesc, SamplerDesc,
                                            SceneDescription, ShapeDesc)
    from renderer.scene.transform import world_from_camera as look_at

    desc = SceneDescription(camera=CameraDesc(camera_to_world=look_at(spec.eye, spec.target, (0, 1, 0)),
                                              fov_deg=spec.fov, lens_radius=spec.lens_radius,
                                              focal_distance=spec.focal_distance),
                            film=FilmDesc(width=spec.width, height=spec.height), sampler=SamplerDesc(spp=spec.spp))
    desc.integrator.max_depth = spec.max_depth
    for i, o in enumerate(spec.objects):
        desc.meshes.append(MeshDesc(positions=o.positions, indices=o.faces, normals=o.normals, uvs=o.uvs))
        if o.kind == "dielectric":
            desc.materials.append(material("dielectric", eta=o.eta))
        elif o.checker is not None:
            from renderer.parameters import TextureRef
            from renderer.scene.description import TextureDesc
            from scenes_py import HERE, params

            t1, t2, scale = o.checker
            name = f"checks{i}"
            desc.textures[name] = TextureDesc(name, "spectrum", "checkerboard",
                                              params(tex1=t1, tex2=t2, uscale=scale, vscale=scale), Path("."), HERE)
            desc.materials.append(material("diffuse", reflectance=TextureRef(name)))
        else:
            desc.materials.append(material("diffuse", reflectance=o.rgb))
        desc.shapes.append(ShapeDesc(mesh=i, material=i))
        desc.instance_sets.append(InstanceSetDesc(shapes=[i], transforms=np.eye(4)[None]))
    if spec.sky is not None:
        desc.lights.append(light("infinite", L=spec.sky))
    if spec.sun is not None:
        desc.lights.append(light("distant", L=spec.sun[1], from_=spec.sun[0], to=(0, 0, 0)))
    return desc


def _write_ply(path: str, o: Obj) -> None:
    """Binary little-endian PLY with the vertex attributes Mitsuba's loader reads (nx.., u, v)."""
    cols, props = [o.positions], ["x", "y", "z"]
    if o.normals is not None:
        cols.append(o.normals)
        props += ["nx", "ny", "nz"]
    if o.uvs is not None:
        cols.append(o.uvs)
        props += ["u", "v"]
    V = np.ascontiguousarray(np.concatenate([np.asarray(c, np.float32) for c in cols], axis=1), dtype="<f4")
    F = np.zeros(len(o.faces), dtype=[("n", "u1"), ("i", "<i4", 3)])
    F["n"], F["i"] = 3, o.faces
    head = ["ply", "format binary_little_endian 1.0", f"element vertex {len(V)}",
            *[f"property float {p}" for p in props], f"element face {len(F)}",
            "property list uchar int vertex_indices", "end_header"]
    with open(path, "wb") as f:
        f.write(("\n".join(head) + "\n").encode("ascii"))
        f.write(V.tobytes())
        f.write(F.tobytes())


def rgb(v) -> dict:
    return {"type": "rgb", "value": [float(x) for x in np.broadcast_to(v, 3)]}


def mitsuba_scene(spec: Spec, tmp: str, sampler: str = "independent"):
    """Mitsuba's form of ``spec`` (meshes written as PLY into ``tmp``), with one of its samplers,
    in the variant the caller has set."""
    import mitsuba as mi

    sensor = {"type": "thinlens" if spec.lens_radius > 0 else "perspective", "fov": spec.fov, "fov_axis": "smaller",
              "to_world": mi.ScalarTransform4f().look_at(origin=list(spec.eye), target=list(spec.target), up=[0, 1, 0]),
              "film": {"type": "hdrfilm", "width": spec.width, "height": spec.height, "rfilter": {"type": "box"}},
              "sampler": {"type": sampler, "sample_count": spec.spp}}
    if spec.lens_radius > 0:
        sensor.update(aperture_radius=spec.lens_radius, focus_distance=spec.focal_distance)
    d = {"type": "scene", "integrator": {"type": "path", "max_depth": spec.max_depth + 1}, "sensor": sensor}
    for i, o in enumerate(spec.objects):
        path = os.path.join(tmp, f"obj{i}.ply")
        _write_ply(path, o)
        if o.kind == "dielectric":
            bsdf = {"type": "dielectric", "int_ior": o.eta, "ext_ior": 1.0}
        elif o.checker is not None:
            t1, t2, scale = o.checker
            bsdf = {"type": "diffuse", "reflectance": {"type": "checkerboard", "color0": rgb(t1), "color1": rgb(t2),
                                                       "to_uv": mi.ScalarTransform4f().scale([scale / 2, scale / 2, 1])}}
        else:
            bsdf = {"type": "diffuse", "reflectance": rgb(o.rgb)}
        d[f"obj{i}"] = {"type": "ply", "filename": path, "face_normals": o.normals is None, "bsdf": bsdf}
    if spec.sky is not None:
        d["sky"] = {"type": "constant", "radiance": rgb(spec.sky)}
    if spec.sun is not None:
        d["sun"] = {"type": "directional", "direction": [-float(x) for x in spec.sun[0]], "irradiance": rgb(spec.sun[1])}
    return mi.load_dict(d)


FLOOR_Y = -0.6


def floor(**kw) -> Obj:
    # normal (p10 - p00) x (p01 - p00) = (0, 0, 8) x (8, 0, 0) = +y: Mitsuba's diffuse is one-sided
    y = FLOOR_Y
    return quad([(-4, y, -4), (-4, y, 4), (4, y, 4), (4, y, -4)], **kw)
