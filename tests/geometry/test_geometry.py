"""The BVH and instancing return the same closest hits as brute force; spawned rays escape
surfaces at every scale; the thin lens focuses."""
from __future__ import annotations

import numpy as np
import trimesh

import renderer
from renderer.geometry.raycast import cast_rays_instanced
from renderer.materials import material
from renderer.parameters import TextureRef
from scenes_py import HERE, params, single_object_scene


def brute_force(tris: np.ndarray, o: np.ndarray, d: np.ndarray) -> np.ndarray:
    """Möller–Trumbore over every triangle (world space), float64."""
    p0, p1, p2 = tris[:, 0], tris[:, 1], tris[:, 2]
    e1, e2 = p1 - p0, p2 - p0
    out = np.full(len(o), np.inf)
    for i in range(len(o)):
        h = np.cross(d[i], e2)
        a = np.einsum("ij,ij->i", e1, h)
        with np.errstate(all="ignore"):
            f = 1.0 / a
            s = o[i] - p0
            u = f * np.einsum("ij,ij->i", s, h)
            q = np.cross(s, e1)
            v = f * (q @ d[i])
            t = f * np.einsum("ij,ij->i", e2, q)
        ok = (np.abs(a) > 1e-12) & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 1e-9)
        if ok.any():
            out[i] = t[ok].min()
    return out


def random_transforms(rng, k: int) -> np.ndarray:
    m = np.zeros((k, 4, 4))
    for i in range(k):
        q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        m[i, :3, :3] = q * rng.uniform(0.2, 1.5)
        m[i, :3, 3] = rng.uniform(-4, 4, size=3)
        m[i, 3, 3] = 1
    return m


def test_instanced_hits_match_brute_force():
    rng = np.random.default_rng(0)
    meshes = [trimesh.creation.icosphere(2), trimesh.creation.box(extents=(1, 2, 0.5)), trimesh.creation.torus(1, 0.3)]
    inst_mesh = rng.integers(0, 3, size=40)
    xf = random_transforms(rng, 40)
    tris = np.concatenate([(meshes[m].vertices @ x[:3, :3].T + x[:3, 3])[meshes[m].faces] for m, x in zip(inst_mesh, xf)])
    o = rng.uniform(-8, 8, size=(600, 3))
    target = rng.uniform(-4, 4, size=(600, 3))
    d = target - o
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    t, inst, face = cast_rays_instanced([(m.vertices, m.faces) for m in meshes], inst_mesh, xf, o, d)
    ref = brute_force(tris, o, d)
    assert np.isfinite(ref).sum() > 300
    np.testing.assert_array_equal(np.isfinite(t), np.isfinite(ref))
    hit = np.isfinite(ref)
    np.testing.assert_allclose(t[hit], ref[hit], rtol=1e-4, atol=1e-5)
    assert np.all(inst[~hit] == -1)


def test_tiny_grains_next_to_huge_dunes():
    """A 0.1 mm sphere 1 km from the origin is still hit and rays leaving it don't self-intersect."""
    grain = trimesh.creation.icosphere(2, radius=1e-4)
    ground = trimesh.creation.box(extents=(4000, 1, 4000))
    xg = np.eye(4)
    xg[:3, 3] = (1000.0, 0.5 + 1e-4, 1000.0)
    xb = np.eye(4)
    o = np.array([[1000.0, 0.5 + 1e-4, 999.9]])
    d = np.array([[0.0, 0.0, 1.0]])
    t, inst, _ = cast_rays_instanced([(grain.vertices, grain.faces), (ground.vertices, ground.faces)],
                                     np.array([0, 1]), np.stack([xg, xb]), o, d)
    assert inst[0] == 0
    np.testing.assert_allclose(t[0], 0.1 - 1e-4, rtol=1e-3)


def test_thin_lens_focus_plane_is_sharp():
    """A checker plane at the focal distance stays sharp with a wide lens; off focus it blurs."""
    from renderer.scene.description import MeshDesc

    quad = MeshDesc(positions=np.array([[-2, -2, 0], [2, -2, 0], [2, 2, 0], [-2, 2, 0]], np.float32),
                    indices=np.array([[0, 1, 2], [0, 2, 3]], np.int32),
                    uvs=np.array([[0, 0], [1, 0], [1, 1], [0, 1]], np.float32))
    from renderer.scene.description import TextureDesc
    from pathlib import Path

    def render_at(focus: float) -> np.ndarray:
        desc = single_object_scene(material("diffuse", reflectance=TextureRef("checks")), mesh=quad, res=32,
                                   fov=40, distance=4.0)
        desc.textures["checks"] = TextureDesc("checks", "spectrum", "checkerboard",
                                              params(uscale=8.0, vscale=8.0, tex1=(1, 1, 1), tex2=(0, 0, 0)),
                                              Path("."), HERE)
        desc.camera.lens_radius = 0.2
        desc.camera.focal_distance = focus
        return renderer.render(desc, spp=64)[..., 0]

    sharp, blurred = render_at(4.0), render_at(1.5)
    contrast = lambda im: np.abs(np.diff(im, axis=1)).mean()
    assert contrast(sharp) > 1.5 * contrast(blurred)
