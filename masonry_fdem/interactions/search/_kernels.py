"""Numba kernels of the alternating digital tree (ADT), after Bonet & Peraire (1991).

Location mapping: a box in d dimensions, (min_0..min_{d-1}, max_0..max_{d-1}), is a point
in 2d-space. Space bisection: the tree node at depth ``level`` splits its region of that
space at the midpoint of coordinate ``level mod 2d``; each node holds one item, its left
subtree the items of the lower half, its right subtree those of the upper half.
Box-intersection search: box B meets the query Q (closed) iff B.min_j <= Q.max_j and
B.max_j >= Q.min_j for every j, i.e. B's point lies in [-inf, Q.max] x [Q.min, +inf];
subtrees that cannot hold such a point are pruned, every visited item is tested exactly.

Variant (documented in :mod:`masonry_fdem.interactions.search.adt`): besides its bisection region,
which is only rebuilt while building, every node keeps the bounding box of the boxes stored
in its subtree (``sub``). Pruning with it is never weaker than pruning with the 2d-space
region (the subtree's minima are >= the region's lower bounds, its maxima <= the region's
upper bounds) and is much stronger for small boxes, whose max coordinates follow their min
coordinates closely.

Layout: nodes are numbered in depth-first preorder; node k's subtree is the node range
k .. k + size[k] - 1, its left child (if any) is k + 1. Array names and shapes:
``node_box`` (n, 2d) float64 [m], box of the item held by node k; ``item`` (n,) int64,
that item's index in the caller's box array; ``left``, ``right`` (n,) int64 child nodes
(-1: none); ``sub`` (n, 2d) float64 [m] subtree bounding boxes; ``size`` (n,) int64.

Only numpy and numba are imported; outputs are allocated by the callers in ``adt.py``.
"""

import math

import numpy as np
from numba import njit

_STACK0 = 64  # initial capacity of the build stack (one entry per level of the path)
_SMALL = 24  # segments up to this length are sorted by insertion sort


@njit(cache=True)
def _grow_int(a, cap):
    b = np.empty(cap, dtype=np.int64)
    b[: a.size] = a
    return b


@njit(cache=True)
def _grow_rows(a, cap):
    b = np.empty((cap, a.shape[1]))
    b[: a.shape[0]] = a
    return b


@njit(cache=True)
def root_region(points, lo, hi):
    """lo, hi (2d,) [m]: the bounding hyper-rectangle of the points (n, 2d), n >= 1."""
    lo[:] = points[0]
    hi[:] = points[0]
    for k in range(1, points.shape[0]):
        for j in range(points.shape[1]):
            lo[j] = min(lo[j], points[k, j])
            hi[j] = max(hi[j], points[k, j])


@njit(cache=True)
def _split(src, src_i, dst, dst_i, s0, e0, j, mid):
    """Stable split of rows s0 + 1 .. e0 − 1 of (src, src_i) into (dst, dst_i): those with
    coordinate j below ``mid`` first (branch-free destination). Returns their number."""
    m = src.shape[1]
    nl = 0
    for t in range(s0 + 1, e0):
        nl += src[t, j] < mid
    pl = s0 + 1
    pr = s0 + 1 + nl
    if m == 4:  # boxes in the plane: the row copied by four explicit moves
        for t in range(s0 + 1, e0):
            is_left = np.int64(src[t, j] < mid)
            q = pr + (pl - pr) * is_left
            dst[q, 0] = src[t, 0]
            dst[q, 1] = src[t, 1]
            dst[q, 2] = src[t, 2]
            dst[q, 3] = src[t, 3]
            dst_i[q] = src_i[t]
            pl += is_left
            pr += 1 - is_left
        return nl
    for t in range(s0 + 1, e0):
        is_left = np.int64(src[t, j] < mid)
        q = pr + (pl - pr) * is_left
        for jj in range(m):
            dst[q, jj] = src[t, jj]
        dst_i[q] = src_i[t]
        pl += is_left
        pr += 1 - is_left
    return nl


@njit(cache=True)
def adt_build(points, perm, lo, hi, node_box, item, left, right, scratch_box, scratch_item):
    """Build the ADT of the boxes ``points`` into preallocated arrays.

    Inserting the items one by one in the order ``perm`` puts, at every node, the first
    item (in that order) of the node's region, and sends the later ones to the half of
    the region holding their point. The same tree is built here top down: a segment of
    items, kept in insertion order, becomes a node holding its first item, and the rest
    is split stably at the midpoint of the region along coordinate ``level mod 2d``.
    The split copies rows with their item numbers between ``node_box`` and the scratch
    arrays (so memory is walked sequentially, without data-dependent branches), and a
    node's row is final in ``node_box`` once the node is made.

    Args:
        points: (n, 2d) float64 boxes [m], (min_0.., max_0..).
        perm: (n,) int64 insertion order.
        lo, hi: (2d,) float64 root region of 2d-space [m].
        node_box: (n, 2d) float64 output, box of each node's item [m].
        item: (n,) int64 output, item of each node.
        left, right: (n,) int64 output, children (-1: none).
        scratch_box: (n, 2d) float64 scratch; scratch_item: (n,) int64 scratch.

    Returns:
        The depth (number of levels; 0 for an empty tree).
    """
    n = perm.size
    m = points.shape[1]
    if n == 0:
        return 0
    for k in range(n):
        item[k] = perm[k]
        left[k] = -1
        right[k] = -1
        for j in range(m):
            node_box[k, j] = points[perm[k], j]
    # pending segments (start, end, level, buffer, region); depth-first, so the stack holds
    # at most one right sibling per level of the current path (grown for degenerate input)
    cap = _STACK0
    st_s = np.empty(cap, dtype=np.int64)
    st_e = np.empty(cap, dtype=np.int64)
    st_l = np.empty(cap, dtype=np.int64)
    st_lo = np.empty((cap, m))
    st_hi = np.empty((cap, m))
    rlo = np.empty(m)
    rhi = np.empty(m)
    top = 0
    st_s[0] = 0
    st_e[0] = n
    st_l[0] = 0  # level * 2 + buffer (0: node_box, 1: scratch)
    for jj in range(m):
        st_lo[0, jj] = lo[jj]
        st_hi[0, jj] = hi[jj]
    depth = 0
    while top >= 0:
        s0 = st_s[top]
        e0 = st_e[top]
        level = st_l[top] >> 1
        in_scratch = st_l[top] & 1
        for jj in range(m):
            rlo[jj] = st_lo[top, jj]
            rhi[jj] = st_hi[top, jj]
        top -= 1
        depth = max(depth, level + 1)
        if in_scratch:
            for jj in range(m):
                node_box[s0, jj] = scratch_box[s0, jj]
            item[s0] = scratch_item[s0]
        if e0 - s0 <= 1:
            continue
        j = level % m
        mid = 0.5 * (rlo[j] + rhi[j])
        # the split from one buffer into the other (called with the arrays in their
        # roles, not by swapping array variables in the loop, which numba pays for)
        if in_scratch:
            nl = _split(scratch_box, scratch_item, node_box, item, s0, e0, j, mid)
        else:
            nl = _split(node_box, item, scratch_box, scratch_item, s0, e0, j, mid)
        if top + 2 >= cap:
            cap *= 2
            st_s = _grow_int(st_s, cap)
            st_e = _grow_int(st_e, cap)
            st_l = _grow_int(st_l, cap)
            st_lo = _grow_rows(st_lo, cap)
            st_hi = _grow_rows(st_hi, cap)
        code = 2 * (level + 1) + (1 - in_scratch)
        a = s0 + 1 + nl
        if e0 - a == 1:  # a leaf: made here, not pushed
            right[s0] = a
            depth = max(depth, level + 2)
            if not in_scratch:
                for jj in range(m):
                    node_box[a, jj] = scratch_box[a, jj]
                item[a] = scratch_item[a]
        elif a < e0:
            right[s0] = a
            top += 1
            st_s[top] = a
            st_e[top] = e0
            st_l[top] = code
            for jj in range(m):
                st_lo[top, jj] = rlo[jj]
                st_hi[top, jj] = rhi[jj]
            st_lo[top, j] = mid
        if nl == 1:
            left[s0] = s0 + 1
            depth = max(depth, level + 2)
            if not in_scratch:
                for jj in range(m):
                    node_box[s0 + 1, jj] = scratch_box[s0 + 1, jj]
                item[s0 + 1] = scratch_item[s0 + 1]
        elif nl > 0:
            left[s0] = s0 + 1
            top += 1
            st_s[top] = s0 + 1
            st_e[top] = a
            st_l[top] = code
            for jj in range(m):
                st_lo[top, jj] = rlo[jj]
                st_hi[top, jj] = rhi[jj]
            st_hi[top, j] = mid
    return depth


@njit(cache=True)
def adt_subtree_bounds(node_box, left, right, sub, size, up):
    """Fill ``sub`` (n, 2d) [m] with the bounding box of the boxes stored in each node's
    subtree, ``size`` (n,) with its number of nodes, and ``up`` (n,) with the nearest node
    of its path to the root (itself included) that is a left child with a right sibling
    (-1: none); the parent of such a node x is x - 1, its sibling right[x - 1]. Children
    follow their parent in preorder: one backward and one forward sweep."""
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
                    sub[k, j] = min(sub[k, j], sub[c, j])
                    sub[k, d + j] = max(sub[k, d + j], sub[c, d + j])
    if n > 0:
        up[0] = -1
    for k in range(n):
        if left[k] >= 0:
            up[left[k]] = left[k] if right[k] >= 0 else up[k]
        if right[k] >= 0:
            up[right[k]] = up[k]


@njit(cache=True)
def _meets(a, ka, b, kb, d):
    """Closed intersection of box row ka of a and box row kb of b, each (., 2d)."""
    for j in range(d):
        if a[ka, j] > b[kb, d + j] or b[kb, j] > a[ka, d + j]:
            return False
    return True


@njit(cache=True)
def adt_query(node_box, item, left, right, sub, depth, queries, out_q, out_i):
    """All (query, item) pairs of meeting boxes, grouped by query (ascending).

    Args:
        queries: (nq, 2d) float64 query boxes [m].
        out_q, out_i: (cap,) int64 output buffers; pairs past ``cap`` are counted only.

    Returns:
        The number of pairs (if larger than ``cap``, call again with larger buffers).
    """
    n = item.size
    d = node_box.shape[1] // 2
    cap = out_q.size
    count = 0
    if n == 0:
        return 0
    stack = np.empty(depth + 1, dtype=np.int64)
    for qi in range(queries.shape[0]):
        top = 0
        stack[0] = 0
        while top >= 0:
            k = stack[top]
            top -= 1
            if not _meets(sub, k, queries, qi, d):
                continue
            if _meets(node_box, k, queries, qi, d):
                if count < cap:
                    out_q[count] = qi
                    out_i[count] = item[k]
                count += 1
            if right[k] >= 0:
                top += 1
                stack[top] = right[k]
            if left[k] >= 0:
                top += 1
                stack[top] = left[k]
    return count


@njit(cache=True)
def adt_self(node_box, item, left, right, up, sub, depth, group, out_i, out_j):
    """All unordered pairs of meeting tree items, each once, different groups only.

    Node a (in preorder) is the query and is paired only with the nodes b > a: those of
    its own subtree and those of the right subtrees hanging off its ancestors on the
    left-to-right side of its path. They are found bottom up, jumping (``up``) from one
    such ancestor to the next, so the ancestors themselves are never searched.

    Args:
        up: (n,) int64 from :func:`adt_subtree_bounds`.
        group: (n,) int64 group of each item (by item index); pairs with equal groups
            >= 0 are left out (same block), groups < 0 exclude nothing.
        out_i, out_j: (cap,) int64 output buffers (item indices, unordered within a
            pair); pairs past ``cap`` are counted only.

    Returns:
        The number of pairs (if larger than ``cap``, call again with larger buffers).
    """
    n = item.size
    d = node_box.shape[1] // 2
    cap = out_i.size
    count = 0
    if n == 0:
        return 0
    # at most one sibling per ancestor plus the depth-first stack below one of them
    stack = np.empty(2 * depth + 2, dtype=np.int64)
    for a in range(n):
        ia = item[a]
        ga = group[ia]
        top = -1
        x = up[a]
        while x >= 0:
            r = right[x - 1]
            if _meets(sub, r, node_box, a, d):
                top += 1
                stack[top] = r
            x = up[x - 1]
        for c in (right[a], left[a]):
            if c >= 0 and _meets(sub, c, node_box, a, d):
                top += 1
                stack[top] = c
        while top >= 0:
            k = stack[top]
            top -= 1
            if _meets(node_box, k, node_box, a, d):
                ib = item[k]
                if ga < 0 or group[ib] != ga:
                    if count < cap:
                        out_i[count] = ia
                        out_j[count] = ib
                    count += 1
            for c in (right[k], left[k]):
                if c >= 0 and _meets(sub, c, node_box, a, d):
                    top += 1
                    stack[top] = c
    return count


@njit(cache=True, inline="always")
def _meets_2d(box, k, x0, y0, x1, y1):
    """Closed intersection of box row k of (., 4) ``box`` with [x0, x1] × [y0, y1]."""
    return not (box[k, 0] > x1 or x0 > box[k, 2] or box[k, 1] > y1 or y0 > box[k, 3])


@njit(cache=True)
def adt_self_2d(node_box, item, left, right, up, sub, depth, group, out_i, out_j):
    """:func:`adt_self` for boxes in the plane (2d = 4 columns), the same pairs in the
    same order: the query box is held in scalars and each test is four comparisons
    (~18 % faster than the general loop over the dimensions at 1e6 boxes)."""
    n = item.size
    cap = out_i.size
    count = 0
    if n == 0:
        return 0
    stack = np.empty(2 * depth + 2, dtype=np.int64)
    for a in range(n):
        ia = item[a]
        ga = group[ia]
        x0 = node_box[a, 0]
        y0 = node_box[a, 1]
        x1 = node_box[a, 2]
        y1 = node_box[a, 3]
        top = -1
        x = up[a]
        while x >= 0:
            r = right[x - 1]
            if _meets_2d(sub, r, x0, y0, x1, y1):
                top += 1
                stack[top] = r
            x = up[x - 1]
        c = right[a]
        if c >= 0 and _meets_2d(sub, c, x0, y0, x1, y1):
            top += 1
            stack[top] = c
        c = left[a]
        if c >= 0 and _meets_2d(sub, c, x0, y0, x1, y1):
            top += 1
            stack[top] = c
        while top >= 0:
            k = stack[top]
            top -= 1
            if _meets_2d(node_box, k, x0, y0, x1, y1):
                ib = item[k]
                if ga < 0 or group[ib] != ga:
                    if count < cap:
                        out_i[count] = ia
                        out_j[count] = ib
                    count += 1
            c = right[k]
            if c >= 0 and _meets_2d(sub, c, x0, y0, x1, y1):
                top += 1
                stack[top] = c
            c = left[k]
            if c >= 0 and _meets_2d(sub, c, x0, y0, x1, y1):
                top += 1
                stack[top] = c
    return count


@njit(cache=True)
def _sort_segment(v, s, e):
    """Sort v[s:e] in place: insertion sort when short (the usual few neighbours)."""
    if e - s > _SMALL:
        v[s:e].sort()
        return
    for t in range(s + 1, e):
        x = v[t]
        u = t - 1
        while u >= s and v[u] > x:
            v[u + 1] = v[u]
            u -= 1
        v[u + 1] = x


@njit(cache=True)
def sort_within_groups(key, val):
    """Sort ``val`` (m,) in place within each run of equal ``key`` (m,) (key is grouped,
    e.g. query indices in the order the search wrote them)."""
    m = key.size
    s = 0
    while s < m:
        e = s + 1
        while e < m and key[e] == key[s]:
            e += 1
        _sort_segment(val, s, e)
        s = e


@njit(cache=True)
def sort_pairs(pi, pj, start, fill, out):
    """Lexicographically sorted (min, max) pairs, by a counting sort on the smaller index
    and a sort of each row's (few) partners: O(m + n).

    Args:
        pi, pj: (m,) int64 unordered pairs of indices < n.
        start: (n + 1,) int64 output, row r of the result is out[start[r]:start[r+1]].
        fill: (n,) int64 scratch.
        out: (m, 2) int64 output.
    """
    m = pi.size
    n = fill.size
    start[:] = 0
    for t in range(m):
        start[min(pi[t], pj[t]) + 1] += 1
    for r in range(n):
        start[r + 1] += start[r]
    col = out[:, 1]
    fill[:] = start[:n]
    for t in range(m):
        r = min(pi[t], pj[t])
        col[fill[r]] = max(pi[t], pj[t])
        fill[r] += 1
    for r in range(n):
        out[start[r] : start[r + 1], 0] = r
        _sort_segment(col, start[r], start[r + 1])


@njit(cache=True)
def _brute_pairs(cols, group, out_i, out_j):
    """O(N²) reference: all i < j with meeting boxes and different groups (group < 0:
    no exclusion), in lexicographic order.

    Args:
        cols: (2d, n) float64 boxes by column [m] (min_0.., max_0..).
        group: (n,) int64.
        out_i, out_j: (cap,) int64 buffers; pairs past ``cap`` are counted only.

    Returns:
        The number of pairs.
    """
    m, n = cols.shape
    d = m // 2
    cap = out_i.size
    count = 0
    blk = 64
    e = 1 % d  # second axis (the first again if d = 1)
    for i in range(n):
        lo0 = cols[0, i]
        hi0 = cols[d, i]
        lo1 = cols[e, i]
        hi1 = cols[d + e, i]
        for j0 in range(i + 1, n, blk):
            j1 = min(j0 + blk, n)
            # branch-free count on two axes (vectorised) before the full test of the block
            c = 0
            for j in range(j0, j1):
                c += ((cols[0, j] <= hi0) & (lo0 <= cols[d, j])
                      & (cols[e, j] <= hi1) & (lo1 <= cols[d + e, j]))
            if c == 0:
                continue
            for j in range(j0, j1):
                hit = True
                for a in range(d):
                    hit &= (cols[a, j] <= cols[d + a, i]) & (cols[a, i] <= cols[d + a, j])
                if hit and not (group[i] >= 0 and group[i] == group[j]):
                    if count < cap:
                        out_i[count] = i
                        out_j[count] = j
                    count += 1
    return count


@njit(cache=True)
def facet_boxes(X, u, facets, margin, boxes):
    """Axis-aligned boxes (xmin, ymin, xmax, ymax) [m] of the facets, inflated by margin."""
    for k in range(facets.shape[0]):
        a, b = facets[k, 0], facets[k, 1]
        ax, ay = X[a, 0] + u[2 * a], X[a, 1] + u[2 * a + 1]
        bx, by = X[b, 0] + u[2 * b], X[b, 1] + u[2 * b + 1]
        boxes[k, 0] = min(ax, bx) - margin
        boxes[k, 1] = min(ay, by) - margin
        boxes[k, 2] = max(ax, bx) + margin
        boxes[k, 3] = max(ay, by) + margin


@njit(cache=True, inline="always")
def _cell_range(a, b, lo, inv_h, g):
    """The cells [i0, i1] a coordinate interval [a, b] [m] overlaps on a grid of g cells
    from lo, clipped to the grid (closed: a point on a cell edge is in both cells)."""
    i0 = int(math.floor((a - lo) * inv_h))
    i1 = int(math.floor((b - lo) * inv_h))
    return max(i0, 0), min(i1, g - 1)


@njit(cache=True)
def mark_cells(boxes, n, lo, inv_h, gx, gy, grow, occ):
    """occ[j, i] = 1 for every cell of a (gy, gx) grid from ``lo`` (cell size 1/inv_h [m])
    that the first n boxes, grown by ``grow`` [m] on every side, overlap."""
    for k in range(n):
        i0, i1 = _cell_range(boxes[k, 0] - grow, boxes[k, 2] + grow, lo[0], inv_h, gx)
        j0, j1 = _cell_range(boxes[k, 1] - grow, boxes[k, 3] + grow, lo[1], inv_h, gy)
        for j in range(j0, j1 + 1):
            for i in range(i0, i1 + 1):
                occ[j, i] = 1


@njit(cache=True)
def boxes_on_cells(boxes, n, lo, inv_h, gx, gy, occ, out):
    """out[k] = True when box k (of the first n) overlaps a marked cell of ``occ``."""
    for k in range(n):
        i0, i1 = _cell_range(boxes[k, 0], boxes[k, 2], lo[0], inv_h, gx)
        j0, j1 = _cell_range(boxes[k, 1], boxes[k, 3], lo[1], inv_h, gy)
        hit = False
        for j in range(j0, j1 + 1):
            for i in range(i0, i1 + 1):
                if occ[j, i]:
                    hit = True
                    break
            if hit:
                break
        out[k] = hit


@njit(cache=True)
def max_speed(v):
    """Largest nodal speed [m/s] of a flat (2 n,) velocity array."""
    best = 0.0
    for i in range(v.size // 2):
        s = v[2 * i] * v[2 * i] + v[2 * i + 1] * v[2 * i + 1]
        if s > best:
            best = s
    return math.sqrt(best)


def precompile() -> None:
    """Compile the box and speed kernels (the tree's are compiled by a search)."""
    X = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    facets = np.array([[0, 1], [1, 2], [2, 3], [3, 0]], dtype=np.int64)
    facet_boxes(X, np.zeros(8), facets, 0.1, np.zeros((4, 4)))
    max_speed(np.zeros(8))
    occ = np.zeros((2, 2), dtype=np.uint8)
    lo = np.zeros(2)
    mark_cells(np.array([[0.0, 0.0, 0.5, 0.5]]), 1, lo, 1.0, 2, 2, 0.1, occ)
    boxes_on_cells(np.array([[0.0, 0.0, 0.5, 0.5]]), 1, lo, 1.0, 2, 2, occ,
                   np.zeros(1, dtype=np.bool_))
