"""Numba kernels of the alternating digital tree (ADT), after Bonet & Peraire (1991).

Location mapping: a box in d dimensions, (min_0..min_{d-1}, max_0..max_{d-1}), is a
point in 2d-space. Space bisection: the tree splits the root hyper-rectangle of that
space at the midpoint of coordinate ``level mod 2d``, one coordinate per level; every
tree node holds one item and an item is inserted by walking down, into the half that
contains its point, until a free child slot. Box-intersection search: box B meets the
query Q (closed) iff B.min_j <= Q.max_j and B.max_j >= Q.min_j for every j, i.e. B's
point lies in [-inf, Q.max] x [Q.min, +inf]; subtrees whose region misses that set are
pruned and every visited item is tested exactly.

Arrays: ``points`` (n, 2d) float64 [m]; ``order`` (n,) item of tree node t; ``left``,
``right`` (n,) child tree nodes (-1: none); ``lo``, ``hi`` (2d,) root region. A node's
region is rebuilt on the way down; for the search each node also keeps the bounding
box of the boxes stored in its subtree (``sub``), the pruning test.
"""

import numpy as np
from numba import njit


@njit(cache=True)
def adt_build(points, order, lo, hi, left, right):
    """Insert item order[t] as tree node t (node 0 is the root). Returns the depth."""
    n = order.size
    m = points.shape[1]
    rlo = np.empty(m)
    rhi = np.empty(m)
    depth = 1 if n > 0 else 0
    for t in range(n):
        left[t] = -1
        right[t] = -1
    for t in range(1, n):
        p = order[t]
        for j in range(m):
            rlo[j] = lo[j]
            rhi[j] = hi[j]
        k = 0
        level = 0
        while True:
            j = level % m
            mid = 0.5 * (rlo[j] + rhi[j])
            if points[p, j] < mid:
                rhi[j] = mid
                if left[k] < 0:
                    left[k] = t
                    break
                k = left[k]
            else:
                rlo[j] = mid
                if right[k] < 0:
                    right[k] = t
                    break
                k = right[k]
            level += 1
        if level + 2 > depth:
            depth = level + 2
    return depth


@njit(cache=True)
def adt_subtree_bounds(points, order, left, right, sub):
    """sub[k] = (min of the box minima, max of the box maxima) over node k's subtree:
    the spatial bounding box of every box stored below k (children come after parents
    in insertion order, so one backward sweep suffices)."""
    n = order.size
    m = points.shape[1]
    d = m // 2
    for k in range(n - 1, -1, -1):
        it = order[k]
        for j in range(m):
            sub[k, j] = points[it, j]
        for c in (left[k], right[k]):
            if c >= 0:
                for j in range(d):
                    if sub[c, j] < sub[k, j]:
                        sub[k, j] = sub[c, j]
                    if sub[c, d + j] > sub[k, d + j]:
                        sub[k, d + j] = sub[c, d + j]


@njit(cache=True)
def adt_search(points, order, left, right, sub, depth, queries, qgroup, igroup, self_mode,
               out_q, out_i):
    """All (query, item) pairs whose boxes meet.

    The walk follows the alternating digital tree; a subtree is skipped when the query
    misses the bounding box of all boxes stored in it (``sub``), which prunes far better
    than the bisection region of 2d-space alone.

    Args:
        sub: (n, 2d) subtree bounds from :func:`adt_subtree_bounds`.
        depth: tree depth (bounds the stack).
        queries: (nq, 2d) query boxes.
        qgroup, igroup: group of each query / item; pairs within one group are skipped
            when the group is >= 0 (same block).
        self_mode: the queries are the items themselves: keep item > query only.
        out_q, out_i: output buffers; pairs beyond their size are counted, not written.

    Returns:
        The number of pairs (may exceed the buffer size: then call again, larger).
    """
    n = order.size
    d = points.shape[1] // 2
    cap = out_q.size
    count = 0
    if n == 0:
        return 0
    stack = np.empty(depth + 2, dtype=np.int64)
    for qi in range(queries.shape[0]):
        top = 0
        stack[0] = 0
        while top >= 0:
            k = stack[top]
            top -= 1
            miss = False
            for j in range(d):
                if sub[k, j] > queries[qi, d + j] or sub[k, d + j] < queries[qi, j]:
                    miss = True
                    break
            if miss:
                continue
            it = order[k]
            hit = True
            for j in range(d):
                if points[it, j] > queries[qi, d + j] or points[it, d + j] < queries[qi, j]:
                    hit = False
                    break
            if hit and self_mode and it <= qi:
                hit = False
            if hit and qgroup[qi] >= 0 and qgroup[qi] == igroup[it]:
                hit = False
            if hit:
                if count < cap:
                    out_q[count] = qi
                    out_i[count] = it
                count += 1
            if right[k] >= 0:
                top += 1
                stack[top] = right[k]
            if left[k] >= 0:
                top += 1
                stack[top] = left[k]
    return count


@njit(cache=True)
def brute_pairs(boxes, group, out_i, out_j):
    """O(N²) reference: all i < j with meeting boxes and different groups (group < 0:
    no exclusion). Returns the count (pairs past the buffers are counted, not written)."""
    n = boxes.shape[0]
    d = boxes.shape[1] // 2
    cap = out_i.size
    count = 0
    for i in range(n):
        for j in range(i + 1, n):
            if group[i] >= 0 and group[i] == group[j]:
                continue
            hit = True
            for a in range(d):
                if boxes[i, a] > boxes[j, d + a] or boxes[j, a] > boxes[i, d + a]:
                    hit = False
                    break
            if hit:
                if count < cap:
                    out_i[count] = i
                    out_j[count] = j
                count += 1
    return count
