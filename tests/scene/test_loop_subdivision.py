"""Loop subdivision as pbrt-v4's loopsubdiv shape (renderer/scene/loop_subdivision.py): topology,
limit points against the eigen-analysis of Loop's subdivision matrix, pbrt's boundary rules and
normal orientation. The images are compared with pbrt-v4's in test_pbrt_references.py."""
from __future__ import annotations

import numpy as np
import pytest

from renderer.errors import Location, SceneError
from renderer.scene.loop_subdivision import beta, loop_subdivide

LOC = Location("test.pbrt", 1)
T = (1 + 5 ** 0.5) / 2
ICO_P = np.array([[-1, T, 0], [1, T, 0], [-1, -T, 0], [1, -T, 0], [0, -1, T], [0, 1, T], [0, -1, -T], [0, 1, -T],
                  [T, 0, -1], [T, 0, 1], [-T, 0, -1], [-T, 0, 1]], float)
ICO_F = np.array([[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4], [11, 10, 2],
                  [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8], [3, 8, 9], [4, 9, 5],
                  [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]])
CUBE_P = np.array([[x, y, z] for z in (0, 1) for y in (0, 1) for x in (0, 1)], float)
OPEN_BOX_F = np.array([f for q in ([0, 2, 3, 1], [0, 1, 5, 4], [1, 3, 7, 5], [3, 2, 6, 7], [2, 0, 4, 6])
                       for f in ([q[0], q[1], q[2]], [q[0], q[2], q[3]])])
CUBE_F = np.concatenate([OPEN_BOX_F, [[4, 5, 7], [4, 7, 6]]])


def edge_counts(F: np.ndarray) -> np.ndarray:
    e = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), 1)
    return np.unique(e, axis=0, return_counts=True)[1]


def perturbed(P: np.ndarray, seed: int) -> np.ndarray:
    """Irregular positions, so that no symmetry hides a wrong weight."""
    return P + 0.15 * np.random.default_rng(seed).standard_normal(P.shape)


@pytest.mark.parametrize("levels", [0, 1, 2, 3])
def test_closed_mesh_stays_closed_with_four_times_the_faces(levels):
    for P, F in ((ICO_P, ICO_F), (CUBE_P, CUBE_F)):
        V, G, _ = loop_subdivide(P, F, levels, LOC)
        assert len(G) == 4 ** levels * len(F)
        assert np.all(edge_counts(G) == 2)                       # watertight, every edge twice
        assert len(V) - len(edge_counts(G)) + len(G) == 2        # Euler characteristic of a sphere


def loop_limit_weight(n: int) -> float:
    """The ring weight of Loop's limit point, independently: the left eigenvector for eigenvalue 1
    of the subdivision matrix acting on (centre, ring of n), normalised to sum 1."""
    S = np.zeros((2 * n + 1, 2 * n + 1))      # centre, n ring vertices, and the n edge points that matter
    b = float(beta(np.array([n]))[0])
    S[0, 0], S[0, 1:n + 1] = 1 - n * b, b
    for i in range(n):                        # new edge point on spoke i
        S[1 + i, 0] = S[1 + i, 1 + i] = 3 / 8
        S[1 + i, 1 + (i + 1) % n] += 1 / 8
        S[1 + i, 1 + (i - 1) % n] += 1 / 8
    M = S[:n + 1, :n + 1]                     # the new centre and new ring from the old ones
    w, vl = np.linalg.eig(M.T)
    v = np.real(vl[:, np.argmin(abs(w - 1.0))])
    v /= v.sum()
    return float(v[1])


@pytest.mark.parametrize("P,F", [(ICO_P, ICO_F), (CUBE_P, CUBE_F)])
def test_limit_points_are_loops_and_do_not_move_with_more_levels(P, F):
    """Each control vertex's limit point: the eigenvector mask (valences 3..6 here), and the same
    point after three levels of refinement (the limit of a vertex does not depend on the level)."""
    P = perturbed(P, 3)
    L0, _, _ = loop_subdivide(P, F, 0, LOC)
    L3, _, _ = loop_subdivide(P, F, 3, LOC)
    np.testing.assert_allclose(L3[:len(P)], L0, atol=1e-12)
    for v in range(len(P)):
        ring = np.unique(F[np.any(F == v, axis=1)])
        ring = ring[ring != v]
        g = loop_limit_weight(len(ring))
        np.testing.assert_allclose(L0[v], (1 - len(ring) * g) * P[v] + g * P[ring].sum(0), atol=1e-12)


def test_limit_normals_point_against_the_control_winding_as_pbrt():
    """pbrt's one-rings run clockwise, so its normals point inward on an outward-wound mesh (its
    render of an icosahedral emitter, shape_loopsubdiv.pbrt, is dark outside); the triangles are
    wound along them. On the symmetric icosahedron the limit normals are radial."""
    V, G, N = loop_subdivide(ICO_P, ICO_F, 2, LOC)
    n = N / np.linalg.norm(N, axis=1, keepdims=True)
    radial = V / np.linalg.norm(V, axis=1, keepdims=True)
    np.testing.assert_allclose(n[:12], -radial[:12], atol=1e-12)
    assert np.all(np.einsum("ij,ij->i", n, radial) < -0.95)
    face = np.cross(V[G[:, 1]] - V[G[:, 0]], V[G[:, 2]] - V[G[:, 0]])
    assert np.all(np.einsum("ij,ij->i", face, n[G].sum(1)) > 0.0)


def test_open_box_rim_follows_the_boundary_rules():
    """The rim (z = 1) is a boundary: its points are made from rim points only (3/4, 1/8, 1/8 and
    edge midpoints), so it stays in the plane z = 1; pbrt's boundary limit mask is 1/5, 3/5, 1/5
    (not the cubic B-spline's 1/6, 2/3, 1/6); the boundary normals agree with the winding too."""
    P = CUBE_P.copy()
    V, G, N = loop_subdivide(P, OPEN_BOX_F, 2, LOC)
    counts = edge_counts(G)
    assert len(G) == 16 * len(OPEN_BOX_F) and np.sum(counts == 1) == 4 * 4 and np.all(counts <= 2)
    rim = np.unique(np.sort(np.concatenate([G[:, [0, 1]], G[:, [1, 2]], G[:, [2, 0]]]), 1), axis=0,
                    return_counts=True)
    rim_vertices = np.unique(rim[0][rim[1] == 1])
    np.testing.assert_allclose(V[rim_vertices, 2], 1.0, atol=1e-12)
    L0, _, _ = loop_subdivide(P, OPEN_BOX_F, 0, LOC)
    np.testing.assert_allclose(L0[4], 0.6 * P[4] + 0.2 * (P[5] + P[6]))      # corner 4's rim neighbours: 5, 6
    face = np.cross(V[G[:, 1]] - V[G[:, 0]], V[G[:, 2]] - V[G[:, 0]])
    assert np.all(np.einsum("ij,ij->i", face, N[G].sum(1)) > 0.0)


def test_non_manifold_and_inconsistent_meshes_are_refused_with_the_location():
    with pytest.raises(SceneError, match="more than two triangles") as e:
        loop_subdivide(ICO_P, np.concatenate([ICO_F, ICO_F[:1]]), 1, LOC)
    assert "test.pbrt:1" in str(e.value)
    flipped = ICO_F.copy()
    flipped[0] = flipped[0, [0, 2, 1]]
    with pytest.raises(SceneError, match="opposite directions"):
        loop_subdivide(ICO_P, flipped, 1, LOC)
