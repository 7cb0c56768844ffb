"""pbrt-v4's ``loopsubdiv`` shape: Loop's subdivision scheme, ``levels`` times, then every vertex
moved to its limit position and given the limit surface's normal, as pbrt's LoopSubdivide does.

Rules (Loop 1987, with pbrt's boundary rules): a new edge point is 3/8 of each end plus 1/8 of
each opposite vertex (1/2 + 1/2 on a boundary edge); an old interior vertex of valence n keeps
1 - n beta of itself and beta of each neighbour, beta = 3/16 for n = 3 and 3/(8n) otherwise; an old
boundary vertex keeps 3/4 and takes 1/8 of each boundary neighbour. Limit points: gamma =
1/(n + 3/(8 beta)) per neighbour (1/5 per boundary neighbour on a boundary). Normals are the cross
product of the two limit tangents, built from the limit positions of the one-ring walked in pbrt's
order; pbrt orients a triangle's geometric normal by that shading normal, so the triangles are
wound to agree with it. Everything is vectorised over half-edges; only the walk around a vertex
loops, once per ring position."""
from __future__ import annotations

import numpy as np

from renderer.errors import Location, SceneError
from renderer.scene.description import MeshDesc
from renderer.scene.params import ParamSet
from renderer.scene.shapes import validated_mesh

#: More levels than this would make over 4^8 = 65536 triangles per control triangle.
MAX_LEVELS = 8


class HalfEdges:
    """Connectivity of a manifold triangle mesh: half-edge h = 3 f + k runs from F[f, k] to
    F[f, k+1]; ``twin[h]`` is the opposite half-edge, -1 on a boundary; ``edge[h]`` numbers the
    undirected edges, whose endpoints are ``ends[e]``."""

    def __init__(self, F: np.ndarray, n_vertices: int, loc: Location):
        self.F = F
        tail = F.ravel()
        head = F[:, [1, 2, 0]].ravel()
        key = np.minimum(tail, head) * n_vertices + np.maximum(tail, head)
        uniq, self.edge, count = np.unique(key, return_inverse=True, return_counts=True)
        if count.max(initial=0) > 2:
            raise SceneError("loopsubdiv: an edge is shared by more than two triangles (the mesh must be "
                             "manifold)", loc)
        self.ends = np.stack([uniq // n_vertices, uniq % n_vertices], 1)
        order = np.argsort(self.edge, kind="stable")
        first = np.searchsorted(self.edge[order], np.arange(len(uniq)))
        self.twin = np.full(len(tail), -1, dtype=np.int64)
        pair = count == 2
        h0, h1 = order[first[pair]], order[first[pair] + 1]
        if np.any(tail[h0] == tail[h1]):
            raise SceneError("loopsubdiv: neighbouring triangles are wound in opposite directions", loc)
        self.twin[h0], self.twin[h1] = h1, h0
        self.boundary_edge = count == 1
        self.tail = tail
        self.n_vertices = n_vertices
        ends_b = self.ends[self.boundary_edge]
        nb = np.bincount(ends_b.ravel(), minlength=n_vertices)
        if np.any(nb > 2):
            raise SceneError("loopsubdiv: a vertex lies on more than one boundary loop (the mesh must be "
                             "manifold)", loc)
        self.boundary = nb > 0
        self.valence = np.bincount(self.ends.ravel(), minlength=n_vertices)

    def neighbour_sum(self, P: np.ndarray, boundary_only: bool = False) -> np.ndarray:
        """Sum over each vertex's neighbours (or boundary neighbours) of their positions."""
        ends = self.ends[self.boundary_edge] if boundary_only else self.ends
        out = np.zeros((self.n_vertices, 3))
        for j in range(3):
            out[:, j] = (np.bincount(ends[:, 0], P[ends[:, 1], j], self.n_vertices)
                         + np.bincount(ends[:, 1], P[ends[:, 0], j], self.n_vertices))
        return out

    def prev_corner(self, c: np.ndarray) -> np.ndarray:
        """The corner of the same vertex in the face across the half-edge that ends at corner c
        (pbrt's prevFace), -1 past a boundary."""
        return self.twin[3 * (c // 3) + (c + 2) % 3]

    def next_corner(self, c: np.ndarray) -> np.ndarray:
        """The corner of the same vertex in the face across the half-edge that leaves corner c
        (pbrt's nextFace), -1 past a boundary."""
        t = self.twin[c]
        return np.where(t >= 0, 3 * (t // 3) + (t + 1) % 3, -1)


def beta(n: np.ndarray) -> np.ndarray:
    return np.where(n == 3, 3.0 / 16.0, 3.0 / (8.0 * np.maximum(n, 1)))


def _refine(P: np.ndarray, F: np.ndarray, he: HalfEdges) -> tuple[np.ndarray, np.ndarray]:
    """One level: the moved old vertices first, then one new vertex per edge; four faces per face."""
    n = he.valence
    b = beta(n)[:, None]
    even = (1.0 - n[:, None] * b) * P + b * he.neighbour_sum(P)
    even_b = 0.75 * P + 0.125 * he.neighbour_sum(P, boundary_only=True)
    even = np.where(he.boundary[:, None], even_b, even)
    opposite = F[:, [2, 0, 1]].ravel()                 # the vertex across half-edge 3f + k
    far = np.zeros((len(he.ends), 3))
    for j in range(3):
        far[:, j] = np.bincount(he.edge, P[opposite, j], len(he.ends))
    ends_sum = P[he.ends[:, 0]] + P[he.ends[:, 1]]
    odd = np.where(he.boundary_edge[:, None], 0.5 * ends_sum, 0.375 * ends_sum + 0.125 * far)
    e = len(P) + he.edge.reshape(-1, 3)                # e[:, k]: new vertex on edge (k, k+1)
    a, bb, c = F[:, 0], F[:, 1], F[:, 2]
    e01, e12, e20 = e[:, 0], e[:, 1], e[:, 2]
    children = np.stack([np.stack([a, e01, e20], 1), np.stack([e01, bb, e12], 1),
                         np.stack([e20, e12, c], 1), np.stack([e01, e12, e20], 1)], 1)
    return np.concatenate([even, odd]), children.reshape(-1, 3)


def _limit(P: np.ndarray, he: HalfEdges) -> np.ndarray:
    n = he.valence
    g = (1.0 / (n + 3.0 / (8.0 * beta(n))))[:, None]
    inner = (1.0 - n[:, None] * g) * P + g * he.neighbour_sum(P)
    edge = 0.6 * P + 0.2 * he.neighbour_sum(P, boundary_only=True)
    return np.where(he.boundary[:, None], edge, inner)


def _start_corners(he: HalfEdges) -> np.ndarray:
    """Each vertex's first corner for pbrt's ring walk: any corner inside, and on a boundary the
    corner whose outgoing half-edge is the boundary (pbrt walks nextFace until it runs out)."""
    start = np.full(he.n_vertices, -1, dtype=np.int64)
    corners = np.arange(len(he.tail))
    start[he.tail[::-1]] = corners[::-1]
    open_ = corners[he.twin < 0]
    start[he.tail[open_]] = open_
    return start


def _limit_normals(P: np.ndarray, he: HalfEdges) -> np.ndarray:
    """cross(S, T) of pbrt's limit tangents from the limit positions P of the one-rings."""
    V, n, bnd = he.n_vertices, he.valence, he.boundary
    F = he.F.ravel()
    nxt = lambda c: F[3 * (c // 3) + (c + 1) % 3]
    prv = lambda c: F[3 * (c // 3) + (c + 2) % 3]
    c = _start_corners(he)
    # ring[j] of each vertex, walked as pbrt's oneRing: inside, the next vertex of each corner,
    # stepping by nextFace; on a boundary, the far end first, then the previous vertex of each
    # corner, stepping by prevFace to the other end
    ring = np.zeros((max(int(n.max(initial=0)), 1), V, 3))
    ring[0] = P[nxt(np.maximum(c, 0))]
    for j in range(1, len(ring)):
        cs = np.maximum(c, 0)
        on_edge = P[prv(cs)]
        c = np.where(c >= 0, np.where(bnd, he.prev_corner(cs), he.next_corner(cs)), -1)
        ring[j] = np.where(bnd[:, None], on_edge, P[nxt(np.maximum(c, 0))])
    j = np.arange(ring.shape[0])[:, None]
    live = (j < n[None, :])[..., None]
    angle = 2.0 * np.pi * j / np.maximum(n, 1)[None, :]
    S = (np.cos(angle)[..., None] * ring * live).sum(0)
    T = (np.sin(angle)[..., None] * ring * live).sum(0)
    Sb, Tb = _boundary_tangents(P, ring, n)
    S = np.where(bnd[:, None], Sb, S)
    T = np.where(bnd[:, None], Tb, T)
    return np.cross(S, T)


def _boundary_tangents(P: np.ndarray, ring: np.ndarray, n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """pbrt's boundary tangents: across (from one boundary neighbour to the other) and inward,
    with its weights for 2, 3, 4 (regular) and more ring vertices."""
    last = ring[np.maximum(n - 1, 0), np.arange(len(P))]
    S = last - ring[0]
    T2 = ring[0] + ring[1 % len(ring)] - 2.0 * P
    T3 = ring[min(1, len(ring) - 1)] - P
    T4 = (-ring[0] + 2.0 * ring[min(1, len(ring) - 1)] + 2.0 * ring[min(2, len(ring) - 1)]
          - ring[min(3, len(ring) - 1)] - 2.0 * P)
    theta = np.pi / np.maximum(n - 1, 1)
    k = np.arange(len(ring))[:, None]
    w = (2.0 * np.cos(theta) - 2.0)[None, :] * np.sin(k * theta[None, :])
    mid = ((k >= 1) & (k < (n - 1)[None, :]))[..., None]
    Tn = -(np.sin(theta)[:, None] * (ring[0] + last) + (w[..., None] * ring * mid).sum(0))
    T = np.select([n[:, None] == 2, n[:, None] == 3, n[:, None] == 4], [T2, T3, T4], Tn)
    return S, T


def loop_subdivide(P: np.ndarray, F: np.ndarray, levels: int, loc: Location) -> tuple[np.ndarray, ...]:
    """Positions, triangles (wound along the normals) and limit normals after ``levels`` levels."""
    P = np.asarray(P, dtype=np.float64).reshape(-1, 3)
    F = np.asarray(F, dtype=np.int64).reshape(-1, 3)
    he = HalfEdges(F, len(P), loc)
    for _ in range(levels):
        P, F = _refine(P, F, he)
        he = HalfEdges(F, len(P), loc)
    P = _limit(P, he)
    N = _limit_normals(P, he)
    # pbrt's rings run clockwise about the winding, so cross(S, T) points against it: wind the
    # triangles the other way so that the geometric normal is on the normals' side, as in pbrt
    return P, F[:, [0, 2, 1]], N


def loop_subdivision_surface(params: ParamSet, loc: Location) -> MeshDesc:
    """``Shape "loopsubdiv"``: ``integer levels`` (default 3), ``integer indices``, ``point3 P``."""
    levels = params.int("levels", 3)
    params.string("scheme", "loop")              # pbrt reads it and, as here, only has Loop's
    if not 0 <= levels <= MAX_LEVELS:
        raise SceneError(f"loopsubdiv: levels {levels} outside 0..{MAX_LEVELS}", loc)
    P = params.floats("P", ("point3",))
    idx = params.ints("indices")
    if P is None or idx is None:
        raise SceneError('loopsubdiv: "point3 P" and "integer indices" are required', loc)
    checked = validated_mesh(P, idx, None, None, loc, "loopsubdiv")
    V, F, N = loop_subdivide(checked.positions, checked.indices, levels, loc)
    N = N / np.maximum(np.linalg.norm(N, axis=1, keepdims=True), 1e-300)
    return validated_mesh(V, F, N, None, loc, "loopsubdiv")
