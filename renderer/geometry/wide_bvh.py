"""A 4-wide bounding volume hierarchy built on the host in numpy: a binary tree by a full-sweep
surface-area heuristic, collapsed so that each node holds four children whose boxes are stored
together (six float4 rows), which lets one node's four slab tests run as vector operations.

Why on the host: Warp does not expose its own BVH's nodes, and building here keeps the layout
(and the stack bound the traversal relies on) ours to check.

Experimental: measured against ``wp.Mesh``/``wp.Bvh`` in benchmarks/traversal.py and not used by
the renderer (docs/traversal.md has the numbers and why).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

WIDTH = 4               # 8 was measured too (benchmarks/traversal.py): no faster
#: The traversal's fixed local stack (entries); a tree that could need more is refused at build.
STACK_SIZE = 64
#: Most primitives in one leaf (the leaf code keeps the count in four bits).
MAX_LEAF = 8
#: The SAH's cost of visiting a node, in triangle tests (a node holds four box tests).
NODE_COST = 1.0         # 3.0 was measured too: slower closest hits
_EMPTY = 1.0e30          # an empty slot's box is inverted (lo > hi), so no slab test accepts it


@dataclass
class WideTree:
    """Nodes as rows of four children: ``lo``/``hi`` are (nodes, 3, 4) float32 boxes, ``child``
    (nodes, 4) int32 codes: >= 0 an inner node, < 0 a leaf ``-(1 + start * 16 + count - 1)`` over
    ``order``, the primitive indices in leaf order. ``stack_need`` is the most stack entries a
    traversal of this tree can hold."""

    lo: np.ndarray
    hi: np.ndarray
    child: np.ndarray
    order: np.ndarray
    stack_need: int


def leaf_code(start: int, count: int) -> int:
    """The child code of a leaf over ``order[start:start + count]``."""
    return -(1 + start * 16 + count - 1)


def _half_area(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    e = np.maximum(hi - lo, 0.0)
    return e[..., 0] * e[..., 1] + e[..., 1] * e[..., 2] + e[..., 2] * e[..., 0]


def _segment_scan(x: np.ndarray, seg: np.ndarray, op: np.ufunc, reverse: bool) -> np.ndarray:
    """Running ``op`` (minimum or maximum) of rows of ``x`` restarted at each segment, in one
    vectorised pass: each segment is shifted by a multiple of more than the data's range, so no
    value carries over from the previous segment. Only estimates costs; boxes are recomputed
    exactly."""
    span = 4.0 * (np.abs(x).max() + 1.0)
    sign = -1.0 if op is np.minimum else 1.0
    if reverse:
        sign = -sign
    shift = (sign * span * seg)[:, None]
    y = x + shift
    y = op.accumulate(y[::-1], axis=0)[::-1] if reverse else op.accumulate(y, axis=0)
    return y - shift


def _split_level(lo, hi, cen, ids, seg, first, m):
    """The cheapest SAH split of every segment at once: (cost, chosen axis, left size, the ids
    sorted along each axis); ties go to the split nearest the middle, so coincident centroids
    still give a balanced tree."""
    n_seg = len(m)
    local = np.arange(len(ids)) - first[seg]          # index within the segment
    k = local + 1                                      # left size when splitting after it
    last = local == m[seg] - 1
    best = (np.full(n_seg, np.inf), np.zeros(n_seg, dtype=np.int64), np.zeros(n_seg, dtype=np.int64))
    sorted_ids = []
    for axis in range(3):
        s = ids[np.lexsort((cen[ids, axis], seg))]
        sorted_ids.append(s)
        l, h = lo[s], hi[s]
        a_left = _half_area(_segment_scan(l, seg, np.minimum, False), _segment_scan(h, seg, np.maximum, False))
        a_right = _half_area(_segment_scan(l, seg, np.minimum, True), _segment_scan(h, seg, np.maximum, True))
        cost = np.full(len(ids), np.inf)
        cost[:-1] = a_left[:-1] * k[:-1] + a_right[1:] * (m[seg] - k)[:-1]
        cost[last] = np.inf
        c_min = np.minimum.reduceat(cost, first)
        score = np.where(cost <= c_min[seg] * (1.0 + 1e-9), np.abs(k - 0.5 * m[seg]), np.inf)
        s_min = np.minimum.reduceat(score, first)
        cand = np.flatnonzero(score == s_min[seg])
        _, at = np.unique(seg[cand], return_index=True)
        j = k[cand[at]]
        better = c_min < best[0]
        best[0][better], best[1][better], best[2][better] = c_min[better], axis, j[better]
    return best[0], best[1], best[2], np.stack(sorted_ids)


def _range_reduce(x: np.ndarray, op: np.ufunc, starts: np.ndarray, ends: np.ndarray) -> np.ndarray:
    """``op`` over rows ``x[s:e]`` for each (s, e) range, exactly."""
    padded = np.concatenate([x, x[:1]])
    return op.reduceat(padded, np.ravel(np.column_stack([starts, ends])), axis=0)[::2]


def _build_binary(lo: np.ndarray, hi: np.ndarray):
    """Binary SAH tree over boxes, built a level at a time (every node of a level in one set of
    array operations): per node its box, its first child (the second follows it; -1 for a
    leaf) and its range in the returned primitive order."""
    n = len(lo)
    cen = 0.5 * (lo + hi)
    order = np.arange(n)
    node_lo, node_hi = [lo.min(axis=0)[None]], [hi.max(axis=0)[None]]
    starts, ends = [np.array([0])], [np.array([n])]
    first_child = [np.array([-1])]
    act, s_act, e_act, n_nodes = np.array([0]), np.array([0]), np.array([n]), 1
    while True:
        keep = e_act - s_act > 2
        act, s_act, e_act = act[keep], s_act[keep], e_act[keep]
        if not len(act):
            break
        m = e_act - s_act
        first = np.cumsum(m) - m
        seg = np.repeat(np.arange(len(act)), m)
        pos = s_act[seg] + np.arange(len(seg)) - first[seg]
        ids = order[pos]
        cost, axis, j, sorted_ids = _split_level(lo, hi, cen, ids, seg, first, m)
        box = np.concatenate(node_lo)[act], np.concatenate(node_hi)[act]
        area = _half_area(*box)
        split_cost = NODE_COST + np.divide(cost, area, out=np.zeros_like(cost), where=area > 0)
        split = ~((m <= MAX_LEAF) & (m <= split_cost))
        order[pos] = np.where(split[seg], sorted_ids[axis[seg], np.arange(len(seg))], ids)
        act, s_act, e_act, j = act[split], s_act[split], e_act[split], j[split]
        kid = n_nodes + 2 * np.arange(len(act))
        n_nodes += 2 * len(act)
        fc = np.concatenate(first_child)
        fc[act] = kid
        first_child = [fc, np.full(2 * len(act), -1)]
        cs = np.ravel(np.column_stack([s_act, s_act + j]))
        ce = np.ravel(np.column_stack([s_act + j, e_act]))
        starts.append(cs)
        ends.append(ce)
        node_lo.append(_range_reduce(lo[order], np.minimum, cs, ce))
        node_hi.append(_range_reduce(hi[order], np.maximum, cs, ce))
        act, s_act, e_act = kid.repeat(2) + np.tile([0, 1], len(kid)), cs, ce
    fc = np.concatenate(first_child)
    boxes = list(zip(np.concatenate(node_lo), np.concatenate(node_hi)))
    kids = [(int(c), int(c) + 1) if c >= 0 else (-1, -1) for c in fc]
    ranges = list(zip(np.concatenate(starts).tolist(), np.concatenate(ends).tolist()))
    return boxes, kids, ranges, order


def _padded(lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A box grown by a few float32 ulps (and 1e-12 near zero), so a ray lying in a face's plane
    with a zero direction component is strictly inside that slab rather than on its edge."""
    pad_lo = np.abs(lo) * 2.0 ** -21 + 1e-12
    pad_hi = np.abs(hi) * 2.0 ** -21 + 1e-12
    return (lo - pad_lo).astype(np.float32), (hi + pad_hi).astype(np.float32)


def build_wide(lo: np.ndarray, hi: np.ndarray) -> WideTree:
    """A 4-wide tree over primitive boxes ``lo``, ``hi`` (N, 3), N >= 1. The root is always an
    inner node (a one-primitive tree has one leaf child)."""
    lo = np.asarray(lo, dtype=np.float32)
    hi = np.asarray(hi, dtype=np.float32)
    boxes, kids, ranges, order = _build_binary(lo.astype(np.float64), hi.astype(np.float64))
    areas = [float(_half_area(*b)) for b in boxes]
    w_lo, w_hi, w_child, w_stack = [], [], [], []

    def add_node(binary: int, base_stack: int) -> None:
        members = [binary] if kids[binary][0] < 0 else list(kids[binary])
        while len(members) < WIDTH:
            inner = [c for c in members if kids[c][0] >= 0]
            if not inner:
                break
            widest = max(inner, key=lambda c: areas[c])
            members.remove(widest)
            members += list(kids[widest])
        w_lo.append(np.full((3, WIDTH), _EMPTY, dtype=np.float32))
        w_hi.append(np.full((3, WIDTH), -_EMPTY, dtype=np.float32))
        w_child.append(np.zeros(WIDTH, dtype=np.int32))
        w_stack.append(base_stack + len(members))
        pending.append((len(w_child) - 1, members, base_stack + len(members) - 1))

    pending: list = []
    add_node(0, 0)
    while pending:
        row, members, base = pending.pop()
        for slot, c in enumerate(members):
            w_lo[row][:, slot], w_hi[row][:, slot] = _padded(*boxes[c])
            if kids[c][0] < 0:
                s, e = ranges[c]
                w_child[row][slot] = leaf_code(s, e - s)
            else:
                w_child[row][slot] = len(w_child)
                add_node(c, base)
    need = max(w_stack)
    if need > STACK_SIZE:
        raise ValueError(f"wide BVH over {len(lo)} boxes would need {need} stack entries (> {STACK_SIZE})")
    return WideTree(np.stack(w_lo), np.stack(w_hi), np.stack(w_child), order.astype(np.int32), need)
