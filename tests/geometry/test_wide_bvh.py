"""The experimental 4-wide BVH (renderer/geometry/wide_*.py, measured in benchmarks/traversal.py
and not used by the renderer) returns brute force's closest hits and shadow answers: random
instanced meshes, rays through shared edges and vertices, degenerate and empty meshes, one
triangle, grains next to dunes, and coincident boxes that must still fit the fixed stack."""
from __future__ import annotations

import numpy as np
import pytest
import trimesh
from test_geometry import random_transforms

from renderer.geometry.raycast import cast_rays_instanced, occluded_rays_instanced
from renderer.geometry.wide_bvh import STACK_SIZE, build_wide


def world_triangles(meshes, inst_mesh, xf) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every instance's triangles in world space, float64, with their (instance, face)."""
    tris, inst, face = [], [], []
    for i, (m, x) in enumerate(zip(inst_mesh, xf)):
        v, f = meshes[m]
        f = np.asarray(f).reshape(-1, 3)
        tris.append((np.asarray(v, np.float64) @ x[:3, :3].T + x[:3, 3])[f])
        inst.append(np.full(len(f), i))
        face.append(np.arange(len(f)))
    return np.concatenate(tris), np.concatenate(inst), np.concatenate(face)


def all_distances(tris: np.ndarray, o: np.ndarray, d: np.ndarray) -> np.ndarray:
    """(rays, triangles) hit distances by Möller–Trumbore in float64, inf where a pair misses."""
    p0, e1, e2 = tris[:, 0], tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0]
    h = np.cross(d[:, None], e2[None])                                     # (R, T, 3)
    a = np.einsum("tj,rtj->rt", e1, h)
    s = o[:, None] - p0[None]
    q = np.cross(s, e1[None])
    with np.errstate(all="ignore"):
        f = 1.0 / a
        u = f * np.einsum("rtj,rtj->rt", s, h)
        v = f * np.einsum("rtj,rj->rt", q, d)
        t = f * np.einsum("tj,rtj->rt", e2, q)
    ok = (np.abs(a) > 1e-300) & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 0)
    return np.where(ok, t, np.inf)


def brute_hits(tris: np.ndarray, o: np.ndarray, d: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Closest t, index of the closest triangle and the gap to the next triangle's t."""
    first, k, gap = [], [], []
    for c in range(0, len(o), 32):
        t_all = all_distances(tris, o[c:c + 32], d[c:c + 32])
        order = np.argsort(t_all, axis=1)[:, :2]
        best = np.take_along_axis(t_all, order, axis=1)
        second = best[:, 1] if best.shape[1] > 1 else np.full(len(best), np.inf)
        first.append(best[:, 0])
        k.append(order[:, 0])
        with np.errstate(invalid="ignore"):                               # inf - inf: no hit at all
            gap.append(second - best[:, 0])
    return np.concatenate(first), np.concatenate(k), np.concatenate(gap)


def rays_at(rng, n: int, spread: float, aim: float) -> tuple[np.ndarray, np.ndarray]:
    o = rng.uniform(-spread, spread, size=(n, 3))
    d = rng.uniform(-aim, aim, size=(n, 3)) - o
    return o, d / np.linalg.norm(d, axis=1, keepdims=True)


def check_against_brute_force(meshes, inst_mesh, xf, o, d) -> int:
    """Closest hits and shadow answers of the wide BVH equal brute force's; returns the number of
    rays that hit. (Instance, face) are compared where the next triangle is clearly farther, and
    shadow answers where the hit is clearly off the shadow ray's end."""
    t, inst, face = cast_rays_instanced(meshes, inst_mesh, xf, o, d, traversal="wide")
    tris, tri_inst, tri_face = world_triangles(meshes, inst_mesh, xf)
    ref, k, gap = brute_hits(tris, o, d)
    hit = np.isfinite(ref)
    scale = np.maximum(np.abs(o).max(axis=1), np.where(hit, ref, 0.0))
    np.testing.assert_array_equal(np.isfinite(t), hit)
    assert np.all(np.abs(t[hit] - ref[hit]) <= 1e-5 * scale[hit])
    clear = hit & (gap > 1e-4 * scale)
    np.testing.assert_array_equal(inst[clear], tri_inst[k[clear]])
    np.testing.assert_array_equal(face[clear], tri_face[k[clear]])
    if hit.any():
        t_max = float(np.median(ref[hit]))
        blocked = occluded_rays_instanced(meshes, inst_mesh, xf, o, d, t_max, traversal="wide")
        sure = np.abs(np.where(hit, ref, np.inf) - t_max) > 1e-4 * scale
        np.testing.assert_array_equal(blocked[sure], (ref < t_max)[sure])
    return int(hit.sum())


def mesh(m: trimesh.Trimesh) -> tuple[np.ndarray, np.ndarray]:
    return np.asarray(m.vertices, np.float32), np.asarray(m.faces, np.int32)


def test_instanced_meshes_match_brute_force():
    rng = np.random.default_rng(1)
    meshes = [mesh(trimesh.creation.icosphere(2)), mesh(trimesh.creation.box(extents=(1, 2, 0.5))),
              mesh(trimesh.creation.torus(1, 0.3))]
    inst_mesh = rng.integers(0, 3, size=30)
    xf = random_transforms(rng, 30)
    o, d = rays_at(rng, 400, 8, 4)
    assert check_against_brute_force(meshes, inst_mesh, xf, o, d) > 150


def test_random_triangle_soup_matches_brute_force():
    """Overlapping, intersecting triangles of every size: the SAH build and the near-to-far walk
    must still return the nearest."""
    rng = np.random.default_rng(2)
    centres = rng.uniform(-3, 3, size=(300, 1, 3))
    tris = (centres + rng.normal(scale=rng.uniform(0.05, 1.0, size=(300, 1, 1)), size=(300, 3, 3))).astype(np.float32)
    meshes = [(tris.reshape(-1, 3), np.arange(900, dtype=np.int32).reshape(-1, 3))]
    o, d = rays_at(rng, 400, 6, 3)
    assert check_against_brute_force(meshes, np.array([0]), np.eye(4)[None], o, d) > 200


def test_rays_through_shared_edges_and_vertices_hit():
    """Watertight: rays aimed exactly at the vertices and edge midpoints of a closed mesh, from
    outside, all hit it at the point they were aimed at."""
    sphere = trimesh.creation.icosphere(2)
    v, f = mesh(sphere)
    edges = sphere.edges_unique
    targets = np.concatenate([v, 0.5 * (v[edges[:, 0]] + v[edges[:, 1]])]).astype(np.float64)
    rng = np.random.default_rng(3)
    o = targets * 3.0 + rng.normal(scale=0.2, size=targets.shape)
    d = targets - o
    dist = np.linalg.norm(d, axis=1)
    d /= dist[:, None]
    t, inst, _ = cast_rays_instanced([(v, f)], np.array([0]), np.eye(4)[None], o, d, traversal="wide")
    assert np.all(inst == 0)
    # the hit is the aimed-at point, or a point of a neighbouring face just before it
    assert np.all(t <= dist * (1 + 1e-5)) and np.all(t >= dist - 0.05)
    blocked = occluded_rays_instanced([(v, f)], np.array([0]), np.eye(4)[None], o, d, 1e30, traversal="wide")
    assert blocked.all()


def test_axis_aligned_rays_graze_a_cube_edge():
    """Rays parallel to an axis (zero direction components) along a box's faces and edges."""
    v, f = mesh(trimesh.creation.box(extents=(2, 2, 2)))
    ys = np.array([-1.0, -0.5, 0.0, 0.5, 1.0])
    o = np.array([[-5.0, y, z] for y in ys for z in ys])
    d = np.tile([1.0, 0.0, 0.0], (len(o), 1))
    t, inst, _ = cast_rays_instanced([(v, f)], np.array([0]), np.eye(4)[None], o, d, traversal="wide")
    assert np.all(inst == 0)
    np.testing.assert_allclose(t, 4.0, rtol=1e-6)


def test_degenerate_triangles_are_never_hit():
    """Zero-area triangles (repeated and collinear vertices) beside a real one: no hit on them,
    no NaN, and the real triangle is still found behind them."""
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [2, 2, 0], [0.25, 0.25, -1], [0.25, 0.25, 1],
                  [-1, -1, 0], [3, 3, 0]], np.float32)
    f = np.array([[0, 0, 0], [0, 1, 1], [0, 3, 6], [4, 5, 5], [6, 0, 7], [0, 1, 2]], np.int32)
    rng = np.random.default_rng(4)
    o = np.column_stack([rng.uniform(-1, 3, 300), rng.uniform(-1, 3, 300), np.full(300, 2.0)])
    d = np.tile([0.0, 0.0, -1.0], (300, 1))
    t, inst, face = cast_rays_instanced([(v, f)], np.array([0]), np.eye(4)[None], o, d, traversal="wide")
    inside = (o[:, 0] > 1e-3) & (o[:, 1] > 1e-3) & (o[:, 0] + o[:, 1] < 1 - 1e-3)
    assert np.all(face[inside] == 5) and np.all(inst[~inside] == -1)
    np.testing.assert_allclose(t[inside], 2.0, rtol=1e-6)


def test_empty_and_one_triangle_meshes():
    tri = (np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32), np.array([[0, 1, 2]], np.int32))
    empty = (np.zeros((0, 3), np.float32), np.zeros((0, 3), np.int32))
    xf = np.stack([np.eye(4)] * 3)
    xf[1, :3, 3] = (0, 0, 1)
    o = np.array([[0.2, 0.2, 5.0], [0.9, 0.9, 5.0]])
    d = np.tile([0.0, 0.0, -1.0], (2, 1))
    t, inst, face = cast_rays_instanced([empty, tri], np.array([0, 1, 1]), xf, o, d, traversal="wide")
    np.testing.assert_allclose(t[0], 4.0, rtol=1e-6)
    assert inst[0] == 1 and face[0] == 0 and inst[1] == -1
    t, inst, _ = cast_rays_instanced([empty], np.array([0, 0]), xf[:2], o, d, traversal="wide")
    assert np.all(inst == -1) and np.all(np.isinf(t))
    assert not occluded_rays_instanced([empty], np.array([0]), xf[:1], o, d, 1e30, traversal="wide").any()


def test_tiny_grains_next_to_large_dunes():
    """0.3 mm grains (instances scaled 3e-4) on a 1 km ground: float32 scale extremes in one tree."""
    rng = np.random.default_rng(5)
    grain = mesh(trimesh.creation.icosphere(1))
    ground = (np.array([[-500, 0, -500], [500, 0, -500], [500, 0, 500], [-500, 0, 500]], np.float32),
              np.array([[0, 2, 1], [0, 3, 2]], np.int32))
    k = 60
    xf = np.stack([np.eye(4)] * (k + 1))
    xf[1:, :3, :3] *= 3e-4
    xf[1:, :3, 3] = np.column_stack([rng.uniform(0, 0.02, k), np.full(k, 3e-4), rng.uniform(0, 0.02, k)]) + (40, 0, 40)
    inst_mesh = np.array([1] + [0] * k)
    aim = xf[1 + rng.integers(0, k, 200), :3, 3] + rng.normal(scale=3e-4, size=(200, 3))
    o = aim + np.array([0.01, 0.03, -0.02])
    d = aim - o
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    assert check_against_brute_force([grain, ground], inst_mesh, xf, o, d) == 200


def test_coincident_boxes_stay_within_the_stack():
    """Ten thousand identical boxes: the build splits ties at the middle, so the tree stays
    balanced and its stack need within the traversal's fixed stack."""
    lo = np.zeros((10000, 3), np.float32)
    tree = build_wide(lo, lo + 1)
    assert tree.stack_need <= STACK_SIZE
    assert sorted(tree.order) == list(range(10000))
    codes = tree.child[tree.child < 0]
    counts = ((-codes - 1) & 15) + 1
    assert counts.sum() == 10000


def test_unknown_traversal_is_refused():
    with pytest.raises(ValueError, match="traversal"):
        cast_rays_instanced([mesh(trimesh.creation.box())], np.array([0]), np.eye(4)[None],
                            np.zeros((1, 3)), np.array([[1.0, 0, 0]]), traversal="embree")
