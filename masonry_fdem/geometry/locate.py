"""Point location in a block mesh: the host triangle of a point and its barycentric
coordinates (used to tie embedded bars to the blocks and to place monitors). Units SI."""

from __future__ import annotations

import numpy as np

__all__ = ["in_triangles", "locate_in_block", "locate_points"]


def in_triangles(tri: np.ndarray, q: np.ndarray, tol: float):
    """Index of the first triangle of ``tri`` (k, 3, 2) holding ``q`` and its barycentric
    coordinates, or (-1, None)."""
    a, e1, e2 = tri[:, 0], tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]
    det = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    d = q - a
    s = (d[:, 0] * e2[:, 1] - d[:, 1] * e2[:, 0]) / det
    t = (e1[:, 0] * d[:, 1] - e1[:, 1] * d[:, 0]) / det
    inside = np.flatnonzero((s >= -tol) & (t >= -tol) & (s + t <= 1.0 + tol))
    if inside.size == 0:
        return -1, None
    k = inside[0]
    w = np.clip(np.array([1.0 - s[k] - t[k], s[k], t[k]]), 0.0, None)
    return int(k), w / w.sum()


def locate_in_block(blocks, b: int, q: np.ndarray, tol: float = 1e-6):
    """Global cell of block ``b`` holding (or, within ``tol``, touching) point ``q`` and
    its barycentric coordinates; the nearest cell if none does (a bar node on the
    block's boundary)."""
    c0, c1 = blocks.cell_offsets[b], blocks.cell_offsets[b + 1]
    tri = blocks.x[blocks.cells[c0:c1]]
    k, w = in_triangles(tri, q, tol)
    if k < 0:  # nearest centroid, coordinates clipped onto that triangle
        k = int(np.argmin(np.linalg.norm(tri.mean(axis=1) - q, axis=1)))
        _, w = in_triangles(tri[k:k + 1], q, np.inf)
    return c0 + k, w


def locate_points(blocks, pts: np.ndarray, tol: float = 1e-9):
    """Global host cell (-1 if none) and barycentric coordinates of each point; a point
    on the common edge of two blocks goes to the lower block id."""
    n = pts.shape[0]
    cell = np.full(n, -1, dtype=np.int64)
    bary = np.zeros((n, 3))
    bb = blocks.block_bounds
    pad = tol * max(float(np.ptp(blocks.x, axis=0).max()), 1.0)
    for i, q in enumerate(pts):
        cand = np.flatnonzero((bb[:, 0] - pad <= q[0]) & (q[0] <= bb[:, 2] + pad)
                              & (bb[:, 1] - pad <= q[1]) & (q[1] <= bb[:, 3] + pad))
        for b in cand:
            c0, c1 = blocks.cell_offsets[b], blocks.cell_offsets[b + 1]
            k, w = in_triangles(blocks.x[blocks.cells[c0:c1]], q, tol)
            if k >= 0:
                cell[i] = c0 + k
                bary[i] = w
                break
    return cell, bary
