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
def _grow_int(a, cap):
    b = np.empty(cap, dtype=np.int64)
    b[: a.size] = a
    return b


@njit(cache=True)
def _grow_float(a, cap):
    b = np.empty((cap, a.shape[1]))
    b[: a.shape[0]] = a
    return b


@njit(cache=True)
def adt_build(points, perm, lo, hi, order, left, right):
    """Build the tree that inserting the items one by one in the order ``perm`` gives.

    Sequential insertion puts, at every node, the earliest-inserted item of the node's
    region, and sends the later ones to the half of the region holding their point. The
    same tree is built top-down here: a segment of items (kept in insertion order by
    stable partitioning) becomes a node holding its first item, and the rest is split at
    the region's midpoint along coordinate ``level mod 2d``. Memory is then walked
    sequentially, and the nodes come out numbered in depth-first preorder: node k holds
    item order[k], its left subtree follows it, then its right subtree.

    Returns:
        The depth (number of levels).
    """
    n = perm.size
    m = points.shape[1]
    if n == 0:
        return 0
    for k in range(n):
        order[k] = perm[k]
        left[k] = -1
        right[k] = -1
    tmp = np.empty(n, dtype=np.int64)
    rlo = np.empty(m)
    rhi = np.empty(m)
    # stack of pending segments (start, end, level, region): at most one right sibling
    # per level of the current path; grown if a degenerate set makes the tree deep
    cap = 64
    st_s = np.empty(cap, dtype=np.int64)
    st_e = np.empty(cap, dtype=np.int64)
    st_l = np.empty(cap, dtype=np.int64)
    st_lo = np.empty((cap, m))
    st_hi = np.empty((cap, m))
    top = 0
    st_s[0] = 0
    st_e[0] = n
    st_l[0] = 0
    for j in range(m):
        st_lo[0, j] = lo[j]
        st_hi[0, j] = hi[j]
    depth = 0
    while top >= 0:
        s0 = st_s[top]
        e0 = st_e[top]
        level = st_l[top]
        for jj in range(m):
            rlo[jj] = st_lo[top, jj]
            rhi[jj] = st_hi[top, jj]
        top -= 1
        if level + 1 > depth:
            depth = level + 1
        if e0 - s0 <= 1:
            continue
        j = level % m
        mid = 0.5 * (rlo[j] + rhi[j])
        # stable partition of order[s0+1:e0] by points[., j] < mid
        nl = 0
        for t in range(s0 + 1, e0):
            if points[order[t], j] < mid:
                tmp[nl] = order[t]
                nl += 1
        nr = 0
        for t in range(s0 + 1, e0):
            if not points[order[t], j] < mid:
                tmp[nl + nr] = order[t]
                nr += 1
        for t in range(nl + nr):
            order[s0 + 1 + t] = tmp[t]
        if top + 2 >= cap:
            cap *= 2
            st_s = _grow_int(st_s, cap)
            st_e = _grow_int(st_e, cap)
            st_l = _grow_int(st_l, cap)
            st_lo = _grow_float(st_lo, cap)
            st_hi = _grow_float(st_hi, cap)
        if nr > 0:
            right[s0] = s0 + 1 + nl
            top += 1
            st_s[top] = s0 + 1 + nl
            st_e[top] = e0
            st_l[top] = level + 1
            for jj in range(m):
                st_lo[top, jj] = rlo[jj]
                st_hi[top, jj] = rhi[jj]
            st_lo[top, j] = mid
        if nl > 0:
            left[s0] = s0 + 1
            top += 1
            st_s[top] = s0 + 1
            st_e[top] = s0 + 1 + nl
            st_l[top] = level + 1
            for jj in range(m):
                st_lo[top, jj] = rlo[jj]
                st_hi[top, jj] = rhi[jj]
            st_hi[top, j] = mid
    return depth


@njit(cache=True)
def adt_subtree_bounds(node_box, left, right, sub, size):
    """sub[k] = (min of the box minima, max of the box maxima) over node k's subtree:
    the spatial bounding box of every box stored below k (children come after parents
    in preorder, so one backward sweep suffices). node_box[k] is node k's own box;
    size[k] is the number of nodes of the subtree (nodes k .. k + size[k] - 1)."""
    n = node_box.shape[0]
    m = node_box.shape[1]
    d = m // 2
    for k in range(n - 1, -1, -1):
        size[k] = 1
        for j in range(m):
            sub[k, j] = node_box[k, j]
        for c in (left[k], right[k]):
            if c >= 0:
                size[k] += size[c]
                for j in range(d):
                    if sub[c, j] < sub[k, j]:
                        sub[k, j] = sub[c, j]
                    if sub[c, d + j] > sub[k, d + j]:
                        sub[k, d + j] = sub[c, d + j]


@njit(cache=True)
def adt_search(node_box, order, left, right, sub, size, depth, queries, qgroup, igroup,
               self_mode, out_q, out_i):
    """All (query, item) pairs whose boxes meet.

    The walk follows the alternating digital tree; a subtree is skipped when the query
    misses the bounding box of all boxes stored in it (``sub``), which prunes far better
    than the bisection region of 2d-space alone.

    Args:
        node_box: (n, 2d) box of the item of each tree node.
        sub: (n, 2d) subtree bounds from :func:`adt_subtree_bounds`.
        depth: tree depth (bounds the stack).
        queries: (nq, 2d) query boxes.
        qgroup, igroup: group of each query / item; pairs within one group are skipped
            when the group is >= 0 (same block).
        size: (n,) subtree sizes (preorder ranges).
        self_mode: the queries are the items themselves (``queries`` is ignored): node a
            is paired only with nodes b > a in preorder, so each pair is found once and
            subtrees lying wholly before a are skipped; output (item a, item b).
        out_q, out_i: output buffers; pairs beyond their size are counted, not written.

    Returns:
        The number of pairs (may exceed the buffer size: then call again, larger).
    """
    n = order.size
    d = node_box.shape[1] // 2
    cap = out_q.size
    count = 0
    if n == 0:
        return 0
    stack = np.empty(depth + 2, dtype=np.int64)
    q = np.empty(2 * d)
    nq = n if self_mode else queries.shape[0]
    for a in range(nq):
        if self_mode:
            qi = order[a]
            for j in range(2 * d):
                q[j] = node_box[a, j]
        else:
            qi = a
            for j in range(2 * d):
                q[j] = queries[a, j]
        top = 0
        stack[0] = 0
        while top >= 0:
            k = stack[top]
            top -= 1
            if self_mode and k + size[k] <= a:
                continue
            miss = False
            for j in range(d):
                if sub[k, j] > q[d + j] or sub[k, d + j] < q[j]:
                    miss = True
                    break
            if miss:
                continue
            it = order[k]
            hit = True
            for j in range(d):
                if node_box[k, j] > q[d + j] or node_box[k, d + j] < q[j]:
                    hit = False
                    break
            if hit and self_mode and k <= a:
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
