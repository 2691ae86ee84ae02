"""Alternating digital tree (ADT): the broad phase of the contact search.

Bonet & Peraire (1991), *An alternating digital tree (ADT) algorithm for 3D geometric
searching and intersection problems*, IJNME 31:1-17.

* Location mapping: a box in d dimensions, (min_0..min_{d-1}, max_0..max_{d-1}), is a
  point of 2d-space.
* Space bisection: the root region of 2d-space (the bounding hyper-rectangle of all the
  points) is bisected by a binary tree, at depth ``level`` along coordinate
  ``level mod 2d``; every node holds one item (box), its children the items of the two
  halves of its region.
* Box-intersection search: B meets the query Q (closed: touching counts) iff B's point
  lies in [-inf, Q.max] x [Q.min, +inf]; the search walks the tree with an explicit
  stack, skipping subtrees that cannot hold such a point, and tests every visited item.

Implementation choices (measured with ``benchmarks/contact_search.py``):

* The tree is built top down, splitting segments of boxes stably (rows copied between two
  buffers, so memory is walked sequentially): the result is exactly the tree that
  inserting the items one by one in input order gives, as in the paper. Nodes are
  numbered in preorder (left child of k is k + 1, its subtree the nodes k .. k + size[k]
  - 1). The ADT is a digital tree: its shape is set by the positions of the points, hardly
  by the insertion order, so the input order is used (``seed`` shuffles it; measured depth
  the same, ~2 log2 N for small boxes, whose max coordinates follow their min coordinates
  so that every other bisection separates little). The depth is bounded by the resolution
  of the coordinates; only exact duplicates form a chain.
* Variant of the paper's search: every node also stores the bounding box of the boxes in
  its subtree, and subtrees are pruned with it instead of with their 2d-space region. It
  never prunes less (the subtree's minima are >= the region's lower bounds and its maxima
  <= the upper bounds) and prunes much better for small boxes.
* ``self_pairs`` queries node a only against nodes b > a in preorder (its own subtree and
  the right subtrees hanging off its path, found bottom up), so each pair is found once
  and the path from the root is never searched.

Everything is written for any d: 2D facet boxes have shape (n, 4), 3D ones (n, 6).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from masonry_fdem.interactions.search import _kernels as K

__all__ = ["ADTree", "brute_force_pairs", "build_adt", "inflate", "query_adt", "self_pairs"]


class ADTree(NamedTuple):
    """A built ADT: C-contiguous flat arrays walked by the numba search.

    Attributes:
        node_box: (n, 2d) float64 [m], box of the item held by each node (preorder).
        item: (n,) int64, index (in the boxes given to :func:`build_adt`) of each node's
            item.
        left: (n,) int64, left child of each node (k + 1, or -1: none).
        right: (n,) int64, right child of each node (-1: none).
        up: (n,) int64, nearest node on the path from each node to the root (itself
            included) that is a left child with a right sibling (-1: none); such a
            node x has parent x - 1. Used by :func:`self_pairs` to walk up the tree.
        sub: (n, 2d) float64 [m], bounding box of all boxes in each node's subtree.
        size: (n,) int64, number of nodes in each node's subtree.
        lo: (2d,) float64 [m], lower corner of the root region of 2d-space.
        hi: (2d,) float64 [m], upper corner of the root region of 2d-space.
        depth: number of levels (0 for an empty tree).
    """

    node_box: np.ndarray
    item: np.ndarray
    left: np.ndarray
    right: np.ndarray
    up: np.ndarray
    sub: np.ndarray
    size: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    depth: int

    @property
    def dim(self) -> int:
        """Spatial dimension d of the boxes."""
        return self.node_box.shape[1] // 2


def _check_boxes(boxes: np.ndarray, name: str = "boxes") -> np.ndarray:
    """(n, 2d) float64 C-contiguous boxes, finite, min <= max, or ValueError."""
    b = np.ascontiguousarray(boxes, dtype=np.float64)
    if b.ndim != 2 or b.shape[1] % 2 or b.shape[1] == 0:
        raise ValueError(f"{name} must have shape (n, 2*dim), got {b.shape}")
    if not np.isfinite(b).all():
        raise ValueError(f"{name} must be finite")
    d = b.shape[1] // 2
    if (b[:, :d] > b[:, d:]).any():
        raise ValueError(f"{name}: a box has min > max")
    return b


def _check_group(group: np.ndarray | None, n: int) -> np.ndarray:
    if group is None:
        return np.full(n, -1, dtype=np.int64)
    g = np.ascontiguousarray(group, dtype=np.int64)
    if g.shape != (n,):
        raise ValueError(f"group must have shape ({n},), got {g.shape}")
    return g


def build_adt(boxes: np.ndarray, *, seed: int | None = None) -> ADTree:
    """Build the alternating digital tree of a set of boxes.

    Args:
        boxes: (n, 2d) float64 [m], rows (min_0..min_{d-1}, max_0..max_{d-1}); finite,
            min <= max. Zero-size boxes, exact duplicates and n = 0 are allowed.
        seed: if given, the items are taken in a random order (from this seed) instead
            of the input order; this changes which item a node holds, hardly the shape.

    Returns:
        The tree. Cost O(N log N) on average.

    Raises:
        ValueError: on a bad shape, non-finite values or min > max.
    """
    points = _check_boxes(boxes)
    n, m = points.shape
    if seed is None:
        perm = np.arange(n, dtype=np.int64)
    else:
        perm = np.random.default_rng(seed).permutation(n).astype(np.int64)
    lo = np.zeros(m)
    hi = np.zeros(m)
    if n:
        K.root_region(points, lo, hi)
    node_box = np.empty((n, m))
    item = np.empty(n, dtype=np.int64)
    left = np.empty(n, dtype=np.int64)
    right = np.empty(n, dtype=np.int64)
    depth = K.adt_build(points, perm, lo, hi, node_box, item, left, right, np.empty((n, m)),
                        np.empty(n, dtype=np.int64))
    sub = np.empty((n, m))
    size = np.empty(n, dtype=np.int64)
    up = np.empty(n, dtype=np.int64)
    K.adt_subtree_bounds(node_box, left, right, sub, size, up)
    return ADTree(node_box, item, left, right, up, sub, size, lo, hi, int(depth))


def _grow(kernel, cap: int, *args) -> tuple[np.ndarray, np.ndarray]:
    """Run a pair kernel with output buffers of ``cap`` pairs, once more if too small."""
    while True:
        out_a = np.empty(cap, dtype=np.int64)
        out_b = np.empty(cap, dtype=np.int64)
        count = kernel(*args, out_a, out_b)
        if count <= cap:
            return out_a[:count], out_b[:count]
        cap = count


def query_adt(tree: ADTree, queries: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """All tree items meeting each query box (closed intersection: touching counts).

    Args:
        tree: from :func:`build_adt`.
        queries: (nq, 2d) float64 [m] query boxes, same layout and d as the tree's.

    Returns:
        ``(query_index, item_index)``, two (k,) int64 arrays, sorted by query then item.
    """
    q = _check_boxes(queries, "queries")
    if q.shape[1] != tree.node_box.shape[1]:
        raise ValueError(f"queries have {q.shape[1]} columns, the tree {tree.node_box.shape[1]}")
    qi, it = _grow(K.adt_query, max(16, 8 * q.shape[0]), tree.node_box, tree.item, tree.left,
                   tree.right, tree.sub, tree.depth, q)
    K.sort_within_groups(qi, it)
    return qi, it


def self_pairs(boxes: np.ndarray, group: np.ndarray | None = None) -> np.ndarray:
    """All pairs of meeting boxes (closed intersection: touching counts).

    Builds the ADT once and queries every box against the boxes after it in the tree.

    Args:
        boxes: (n, 2d) float64 [m], as for :func:`build_adt`.
        group: optional (n,) int, e.g. the block of each facet; pairs with
            ``group[i] == group[j]`` are left out (negative groups exclude nothing).

    Returns:
        (m, 2) int64 pairs (i, j) with i < j, lexicographically sorted.
    """
    tree = build_adt(boxes)
    n = tree.item.size
    g = _check_group(group, n)
    kernel = K.adt_self_2d if tree.node_box.shape[1] == 4 else K.adt_self
    pi, pj = _grow(kernel, max(16, 8 * n), tree.node_box, tree.item, tree.left, tree.right,
                   tree.up, tree.sub, tree.depth, g)
    out = np.empty((pi.size, 2), dtype=np.int64)
    K.sort_pairs(pi, pj, np.empty(n + 1, dtype=np.int64), np.empty(n, dtype=np.int64), out)
    return out


def inflate(boxes: np.ndarray, margin: float) -> np.ndarray:
    """The boxes grown by a travel margin on every side.

    Args:
        boxes: (n, 2d) float64 [m].
        margin: distance [m] >= 0 added on each side (the travel allowed between two
            searches).

    Returns:
        A new (n, 2d) float64 array [m].
    """
    if not margin >= 0.0:
        raise ValueError(f"margin must be >= 0, got {margin}")
    b = _check_boxes(boxes).copy()
    d = b.shape[1] // 2
    b[:, :d] -= margin
    b[:, d:] += margin
    return b


def brute_force_pairs(boxes: np.ndarray, group: np.ndarray | None = None) -> np.ndarray:
    """O(N²) reference of :func:`self_pairs` (tests and benchmarks): same output.

    Args:
        boxes: (n, 2d) float64 [m].
        group: optional (n,) int, as in :func:`self_pairs`.

    Returns:
        (m, 2) int64 pairs (i, j), i < j, lexicographically sorted.
    """
    b = _check_boxes(boxes)
    g = _check_group(group, b.shape[0])
    oi, oj = _grow(K._brute_pairs, max(16, 8 * b.shape[0]), np.ascontiguousarray(b.T), g)
    return np.stack([oi, oj], axis=1)
