"""Alternating digital tree: the broad phase of the contact search.

Bonet & Peraire (1991), *An alternating digital tree (ADT) algorithm for 3D geometric
searching and intersection problems*, IJNME 31:1–17. Facet bounding boxes in d
dimensions are points in 2d-space; a binary tree bisects that space one coordinate per
level, cycling through the 2d coordinates; the box-intersection search visits only the
subtrees whose region can hold an overlapping box. Building costs O(N log N) and a query
O(log N + k) on average. Nothing here is specific to 2D: d = 3 works unchanged.

Items are inserted in a fixed pseudo-random order, which keeps the tree balanced for
sorted input (facets arrive block by block, in order along each boundary).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from masonry_fdem.contact import _adt_kernels as K

__all__ = ["ADTree", "build_adt", "query_adt", "self_pairs", "inflate", "brute_force_pairs"]


class ADTree(NamedTuple):
    """A built tree: flat arrays that the numba search walks.

    Attributes:
        points: (n, 2d) the boxes as points [m] (min_0.., max_0..), by item.
        node_box: (n, 2d) the box of the item held by each tree node.
        order: (n,) item held by each tree node (nodes numbered in depth-first order).
        left, right: (n,) children of each tree node (-1: none).
        lo, hi: (2d,) the root region.
        depth: number of levels.
        sub: (n, 2d) bounding box of the boxes in each node's subtree [m].
        size: (n,) number of nodes in each node's subtree.
    """

    points: np.ndarray
    node_box: np.ndarray
    order: np.ndarray
    left: np.ndarray
    right: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    depth: int
    sub: np.ndarray
    size: np.ndarray


def _check_boxes(boxes: np.ndarray, name: str = "boxes") -> np.ndarray:
    b = np.ascontiguousarray(boxes, dtype=np.float64)
    if b.ndim != 2 or b.shape[1] % 2 or b.shape[1] == 0:
        raise ValueError(f"{name} must have shape (n, 2*dim), got {b.shape}")
    if not np.all(np.isfinite(b)):
        raise ValueError(f"{name} must be finite")
    d = b.shape[1] // 2
    if np.any(b[:, :d] > b[:, d:]):
        raise ValueError(f"{name}: a box has min > max")
    return b


def build_adt(boxes: np.ndarray, seed: int = 12345) -> ADTree:
    """Build the tree of (n, 2d) boxes (min_0..min_{d-1}, max_0..max_{d-1}) [m]."""
    points = _check_boxes(boxes)
    n, m = points.shape
    order = np.random.default_rng(seed).permutation(n).astype(np.int64)
    if n:
        lo = points.min(axis=0)
        hi = points.max(axis=0)
    else:
        lo = np.zeros(m)
        hi = np.zeros(m)
    p_order = np.empty(n, dtype=np.int64)
    p_left = np.empty(n, dtype=np.int64)
    p_right = np.empty(n, dtype=np.int64)
    depth = K.adt_build(points, order, lo, hi, p_order, p_left, p_right)
    node_box = np.ascontiguousarray(points[p_order])
    sub = np.empty((n, m))
    size = np.empty(n, dtype=np.int64)
    K.adt_subtree_bounds(node_box, p_left, p_right, sub, size)
    return ADTree(points, node_box, p_order, p_left, p_right, lo, hi, int(depth), sub, size)


def _search(tree: ADTree, queries, qgroup, igroup, self_mode: bool):
    cap = max(16, 8 * queries.shape[0])
    while True:
        out_q = np.empty(cap, dtype=np.int64)
        out_i = np.empty(cap, dtype=np.int64)
        n = K.adt_search(tree.node_box, tree.order, tree.left, tree.right, tree.sub,
                         tree.size, tree.depth, queries, qgroup, igroup, self_mode, out_q,
                         out_i)
        if n <= cap:
            return out_q[:n], out_i[:n]
        cap = n


def query_adt(tree: ADTree, queries: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """All (query index, item index) pairs of meeting boxes (closed: touching counts),
    sorted by query then item."""
    q = _check_boxes(queries, "queries")
    if q.shape[1] != tree.points.shape[1]:
        raise ValueError("queries and tree boxes differ in dimension")
    none_q = np.full(q.shape[0], -1, dtype=np.int64)
    none_i = np.full(tree.points.shape[0], -1, dtype=np.int64)
    qi, it = _search(tree, q, none_q, none_i, False)
    o = np.lexsort((it, qi))
    return qi[o], it[o]


def self_pairs(boxes: np.ndarray, group: np.ndarray | None = None) -> np.ndarray:
    """All pairs (i, j), i < j, of meeting boxes, (m, 2) int64 sorted; pairs with
    group[i] == group[j] (e.g. two facets of one block) are left out."""
    tree = build_adt(boxes)
    n = tree.points.shape[0]
    g = (np.full(n, -1, dtype=np.int64) if group is None
         else np.ascontiguousarray(group, dtype=np.int64))
    if g.shape != (n,):
        raise ValueError(f"group must have shape ({n},)")
    i, j = _search(tree, tree.points, g, g, True)
    out = np.stack([np.minimum(i, j), np.maximum(i, j)], axis=1)
    return out[np.lexsort((out[:, 1], out[:, 0]))]


def inflate(boxes: np.ndarray, margin: float) -> np.ndarray:
    """The boxes grown by ``margin`` [m] on every side."""
    b = _check_boxes(boxes).copy()
    d = b.shape[1] // 2
    b[:, :d] -= margin
    b[:, d:] += margin
    return b


def brute_force_pairs(boxes: np.ndarray, group: np.ndarray | None = None) -> np.ndarray:
    """The O(N²) reference of :func:`self_pairs` (for tests and benchmarks)."""
    b = _check_boxes(boxes)
    n = b.shape[0]
    g = np.full(n, -1, dtype=np.int64) if group is None else np.asarray(group, np.int64)
    cap = max(16, 8 * n)
    while True:
        oi = np.empty(cap, dtype=np.int64)
        oj = np.empty(cap, dtype=np.int64)
        c = K.brute_pairs(b, g, oi, oj)
        if c <= cap:
            return np.stack([oi[:c], oj[:c]], axis=1)
        cap = c
