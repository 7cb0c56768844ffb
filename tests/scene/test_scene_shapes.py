"""Shapes as pbrt-v4 builds them (tessellated spheres, disks, bilinear patches, triangle and PLY
meshes) and object instancing, from scene text to SceneDescription (no Warp)."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from renderer.errors import Location, MissingFileError
from renderer.scene import load_description
from renderer.scene.params import Param, ParamSet
from renderer.scene.shapes import bilinear_mesh, disk, sphere
from scene_files import DATA, HEAD, error_at, load
from scenes_py import params


# --- shapes -----------------------------------------------------------------------------------------

def test_sphere_tessellation_is_radial_and_has_the_right_area():
    m = sphere(params(radius=2.0), Location("<t>", 1))
    P, N = m.positions.astype(float), m.normals.astype(float)
    np.testing.assert_allclose(np.linalg.norm(N, axis=1), 1.0, atol=1e-6)
    np.testing.assert_allclose(N, P / 2.0, atol=1e-6)
    tri = P[m.indices]
    cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    assert abs(0.5 * np.linalg.norm(cross, axis=1).sum() / (4 * math.pi * 4) - 1) < 0.01
    assert np.all(np.einsum("ij,ij->i", cross, tri.mean(1)) > 0)             # wound outwards
    # pbrt's UVs: u = phi / 2pi, v = 0 at z = -r and 1 at z = +r
    phi = np.mod(np.arctan2(P[:, 1], P[:, 0]), 2 * math.pi)
    side = np.abs(P[:, 2]) < 1.9
    ok = np.isclose(m.uvs[side, 0] * 2 * math.pi, phi[side], atol=1e-4) | np.isclose(m.uvs[side, 0], 1.0)
    assert ok.all()
    np.testing.assert_allclose(m.uvs[:, 1], (np.arccos(-P[:, 2] / 2).clip(0, math.pi)) / math.pi, atol=1e-3)


def test_partial_sphere_and_disk_conventions():
    m = sphere(params(radius=1.0, zmin=0.0, phimax=90.0), Location("<t>", 1))
    assert m.positions[:, 2].min() >= -1e-6 and m.positions[:, :2].min() >= -1e-6
    d = disk(params(radius=2.0, innerradius=1.0, height=0.5), Location("<t>", 1))
    P = d.positions.astype(float)
    r = np.linalg.norm(P[:, :2], axis=1)
    np.testing.assert_allclose(P[:, 2], 0.5)
    np.testing.assert_allclose(d.uvs[:, 1], (2.0 - r) / (2.0 - 1.0), atol=1e-6)   # v = 0 on the rim
    np.testing.assert_allclose(d.normals, np.tile([0, 0, 1], (len(P), 1)))
    tri = P[d.indices]
    cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    assert np.all(cross[:, 2] > 0)
    assert abs(0.5 * cross[:, 2].sum() / (math.pi * 3) - 1) < 0.01
    full = disk(params(radius=1.0), Location("<t>", 1))
    assert abs(0.5 * np.cross(*(full.positions[full.indices][:, 1:] - full.positions[full.indices][:, :1])
                              .transpose(1, 0, 2))[:, 2].sum() / math.pi - 1) < 0.01


def test_bilinear_mesh_planar_and_curved():
    loc = Location("<t>", 1)
    ps = ParamSet()
    ps.add(Param("point3", "P", [0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0], loc))
    flat = bilinear_mesh(ps, loc)
    assert len(flat.indices) == 2
    np.testing.assert_allclose(flat.normals, np.tile([0, 0, 1], (4, 1)))
    np.testing.assert_allclose(flat.uvs, flat.positions[:, :2])              # (u, v) where p = (u, v, 0)
    ps = ParamSet()
    ps.add(Param("point3", "P", [0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 1], loc))
    curved = bilinear_mesh(ps, loc)
    assert len(curved.indices) > 2
    u, v = curved.uvs[:, 0].astype(float), curved.uvs[:, 1].astype(float)
    np.testing.assert_allclose(curved.positions[:, 2], u * v, atol=1e-6)      # p(u, v) = (u, v, uv)
    n = np.stack([-v, -u, np.ones_like(u)], 1)                              # cross(dp/du, dp/dv)
    np.testing.assert_allclose(curved.normals, n / np.linalg.norm(n, axis=1, keepdims=True), atol=1e-3)


def test_trianglemesh_and_validation(tmp_path):
    s = load(tmp_path, HEAD + 'Shape "trianglemesh" "point3 P" [0 0 0 1 0 0 0 1 0] "float uv" [0 0 1 0 0 1]\n'
                              'Shape "trianglemesh" "point3 P" [0 0 0 1 0 0 0 1 0] "integer indices" []\n')
    assert s.meshes[0].indices.tolist() == [[0, 1, 2]] and s.meshes[0].uvs.shape == (3, 2)
    assert len(s.meshes) == 1 and s.warnings == [
        f'{tmp_path / "scene.pbrt"}:4: Shape "trianglemesh" has no triangles; skipped',
        f'{tmp_path / "scene.pbrt"}: scene has no lights: the image will be black']
    error_at(tmp_path, HEAD + '\nShape "trianglemesh" "point3 P" [0 0 0 1 0 0 0 1 0] "integer indices" [0 1 3]',
             4, "out of range")
    error_at(tmp_path, HEAD + 'Shape "trianglemesh" "point3 P" [0 0 0 1 0 0 0 1 0 1 1 1]', 3, "indices")
    error_at(tmp_path, HEAD + 'Shape "trianglemesh" "point3 P" [0 0 0 1 0 0 0 1 0] "normal N" [0 0 1]', 3,
             "N has 1 entries for 3 vertices")
    error_at(tmp_path, HEAD + 'Shape "trianglemesh" "point3 P" [0 0 0 1 0 0 0 1 0] "point3 uv" [0 0 1]', 3,
             "must be of type")
    error_at(tmp_path, HEAD + 'Shape "sphere" "float radius" 0', 3, "radius must be > 0")
    error_at(tmp_path, HEAD + 'Shape "trianglemesh" "point3 P" [0 0 0 1 0 0 0 1 1e39]', 3, "NaN or infinite")


def _ply(path: Path, header_props: str, vertices: str, faces: str, n_vertices: int, n_faces: int) -> None:
    path.write_text(f"ply\nformat ascii 1.0\nelement vertex {n_vertices}\n{header_props}"
                    f"element face {n_faces}\nproperty list uchar int vertex_indices\nend_header\n"
                    f"{vertices}{faces}")


def test_plymesh_normals_uvs_and_quads(tmp_path):
    s = load_description(DATA / "mini.pbrt")
    m = s.meshes[0]
    assert m.name == "plymesh quad.ply"
    assert m.indices.tolist() == [[0, 1, 2], [0, 2, 3], [1, 4, 2]]           # quad split, winding kept
    np.testing.assert_allclose(m.normals, np.tile([0, 0, 1], (5, 1)))
    np.testing.assert_allclose(m.uvs[:4], m.positions[:4, :2])
    np.testing.assert_allclose(m.uvs[4], [0.5, 0.5])

    xyz = "property float x\nproperty float y\nproperty float z\n"
    _ply(tmp_path / "uv.ply", xyz + "property float u\nproperty float v\n",
         "0 0 0 0 0\n1 0 0 1 0\n0 1 0 0 1\n", "3 0 1 2\n", 3, 1)
    _ply(tmp_path / "nan.ply", xyz, "0 0 0\nnan 0 0\n0 1 0\n", "3 0 1 2\n", 3, 1)
    _ply(tmp_path / "oob.ply", xyz, "0 0 0\n1 0 0\n0 1 0\n", "3 0 1 7\n", 3, 1)
    s = load(tmp_path, HEAD + 'Shape "plymesh" "string filename" "uv.ply" "float edgelength" 1\n')
    np.testing.assert_allclose(s.meshes[0].uvs, [[0, 0], [1, 0], [0, 1]])
    assert s.meshes[0].normals is None
    assert s.warnings[0].startswith(f"{tmp_path / 'scene.pbrt'}:3: ")
    error_at(tmp_path, HEAD + '\nShape "plymesh" "string filename" "nan.ply"', 4, "NaN")
    error_at(tmp_path, HEAD + 'Shape "plymesh" "string filename" "oob.ply"', 3, "out of range")
    error_at(tmp_path, HEAD + 'Shape "plymesh" "string filename" "none.ply"', 3, "not found", kind=MissingFileError)
    (tmp_path / "junk.ply").write_text("not a ply\n")
    error_at(tmp_path, HEAD + 'Shape "plymesh" "string filename" "junk.ply"', 3, "not a readable PLY")


# --- objects and instancing -------------------------------------------------------------------------

def test_object_instances_share_meshes(tmp_path):
    s = load(tmp_path, HEAD + 'AttributeBegin\nTranslate 10 0 0\nObjectBegin "grain"\n'
                              '  Translate 0 1 0\n  Shape "sphere" "float radius" 0.5\n  Shape "disk"\nObjectEnd\n'
                              'AttributeEnd\nObjectInstance "grain"\nTranslate 0 0 4\nObjectInstance "grain"\n'
                              'Scale -1 1 1\nObjectInstance "grain"\n')
    assert len(s.meshes) == 2
    plain = s.instance_sets[:2]
    assert [i.shapes for i in plain] == [[0, 1], [0, 1]]
    # world = ctm_instance @ ctm_shape, as pbrt-v4, where ctm_shape includes the CTM at ObjectBegin;
    # the stored mesh is relative to ObjectBegin, so its vertices stay near the object's origin
    sphere_top = s.meshes[0].positions[s.meshes[0].positions[:, 2].argmax()].astype(float)
    np.testing.assert_allclose(sphere_top, [0, 1, 0.5], atol=1e-6)
    for inst, offset in zip(plain, ([10, 1, 0], [10, 1, 4])):
        world = inst.transforms[0] @ [*sphere_top, 1]
        np.testing.assert_allclose(world[:3], np.array(offset) + [0, 0, 0.5], atol=1e-6)
    # a mirroring instance uses flipped copies of the shapes, still with the same meshes
    mirrored = s.instance_sets[2]
    assert [s.shapes[i].mesh for i in mirrored.shapes] == [0, 1]
    assert all(s.shapes[i].reverse_orientation for i in mirrored.shapes)
    assert len(s.shapes) == 4


def test_instance_transform_file(tmp_path):
    T = np.tile(np.eye(4), (3, 1, 1))
    T[:, 0, 3] = [0, 1, 2]
    np.savez(tmp_path / "grains.npz", transforms=T)
    np.save(tmp_path / "grains.npy", T[:2])
    s = load(tmp_path, HEAD + 'ObjectBegin "g"\nShape "sphere"\nObjectEnd\nTranslate 0 5 0\n'
                              'ObjectInstance "g" "string transforms" "grains.npz"\n'
                              'ObjectInstance "g" "string transforms" "grains.npy"\n')
    a, b = s.instance_sets
    assert len(s.meshes) == 1 and a.shapes == b.shapes == [0]
    np.testing.assert_allclose(a.transforms[:, :3, 3], [[0, 5, 0], [1, 5, 0], [2, 5, 0]])
    assert b.transforms.shape == (2, 4, 4)

    bad = np.zeros((2, 3, 4))
    np.savez(tmp_path / "bad.npz", transforms=bad)
    np.savez(tmp_path / "nokey.npz", other=T)
    T[1, 2, 2] = np.nan
    np.save(tmp_path / "nan.npy", T)
    obj = HEAD + 'ObjectBegin "g"\nShape "sphere"\nObjectEnd\n'
    error_at(tmp_path, obj + 'ObjectInstance "g" "string transforms" "bad.npz"', 6, r"shape \(N, 4, 4\)")
    error_at(tmp_path, obj + 'ObjectInstance "g" "string transforms" "nokey.npz"', 6, 'no array named "transforms"')
    error_at(tmp_path, obj + 'ObjectInstance "g" "string transforms" "nan.npy"', 6, "NaN")
    error_at(tmp_path, obj + 'ObjectInstance "g" "string transforms" "gone.npz"', 6, "not found",
             kind=MissingFileError)


@pytest.mark.parametrize("body, line, match", [
    ('ObjectBegin "a"\nAreaLightSource "diffuse"\nShape "sphere"\nObjectEnd', 5, "area lights inside"),
    ('ObjectBegin "a"\nObjectBegin "b"', 4, "inside another object"),
    ('ObjectBegin "a"\nObjectEnd\nObjectBegin "a"', 5, "defined twice"),
    ('ObjectInstance "ghost"', 3, 'no object named "ghost"'),
    ('ObjectBegin "a"\nObjectInstance "a"', 4, "inside an object definition"),
])
def test_object_errors_are_located(tmp_path, body, line, match):
    error_at(tmp_path, HEAD + body, line, match)


@pytest.mark.parametrize("polygons", [[[0, 1, 2], [0, 2, 3]], [[0, 1, 2, 3], [1, 4, 2]]], ids=["triangles", "quad"])
def test_binary_ply_reads_as_the_same_mesh_memory_mapped_or_face_by_face(tmp_path, polygons):
    """Binary triangle meshes are memory-mapped whole; a mesh with any other polygon is read face by
    face and fanned. Both give the triangles of the same polygons, in the file's order."""
    import plyfile

    from renderer.scene import plymesh

    vertex = np.array([(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (2, 1, 0)],
                      dtype=[("x", "f4"), ("y", "f4"), ("z", "f4")])
    face = np.empty(len(polygons), dtype=[("vertex_indices", "O")])
    face["vertex_indices"] = [np.array(p, dtype=np.int32) for p in polygons]
    path = tmp_path / "mesh.ply"
    plyfile.PlyData([plyfile.PlyElement.describe(vertex, "vertex"), plyfile.PlyElement.describe(face, "face")]).write(path)
    mapped = plymesh._read_triangles(path)
    assert (mapped is not None) == all(len(p) == 3 for p in polygons)
    mesh = plymesh.read_ply(path, Location(str(path), 1))
    fanned = [[p[0], p[i], p[i + 1]] for p in polygons for i in range(1, len(p) - 1)]
    assert mesh.indices.tolist() == fanned
    assert np.array_equal(mesh.positions, np.stack([vertex[k] for k in "xyz"], -1))
