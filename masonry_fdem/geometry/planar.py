"""Planar queries on points, segments, polylines and polygons [m] (used to check case
files: a load point on a face, an anchor inside the masonry, anchors too close)."""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

__all__ = ["inside_any", "on_segments", "polyline_distance", "segment_distance"]


def on_segments(p0: np.ndarray, p1: np.ndarray, tol: float) -> Callable[[np.ndarray], bool]:
    """A test of whether a point lies within ``tol`` of one of the segments p0[i]–p1[i]."""
    p0, d = np.array(p0, dtype=float), np.array(p1, dtype=float) - np.array(p0, dtype=float)
    l2 = np.einsum("ij,ij->i", d, d)

    def on(x: np.ndarray) -> bool:
        x = np.asarray(x, dtype=float)[:2]
        t = np.clip(np.einsum("ij,ij->i", x - p0, d) / l2, 0.0, 1.0)
        return bool(np.min(np.linalg.norm(p0 + t[:, None] * d - x, axis=1)) <= tol)

    return on


def inside_any(polys: Sequence[np.ndarray], pts: np.ndarray, tol: float) -> np.ndarray:
    """Whether each point lies in (or within ``tol`` of) one of the polygons."""
    inside = np.zeros(len(pts), dtype=bool)
    x, y = pts[:, 0], pts[:, 1]
    for poly in polys:
        a, b = poly, np.roll(poly, -1, axis=0)
        # even-odd rule
        cross = ((a[None, :, 1] > y[:, None]) != (b[None, :, 1] > y[:, None]))
        with np.errstate(divide="ignore", invalid="ignore"):
            xc = a[None, :, 0] + (y[:, None] - a[None, :, 1]) * (b[None, :, 0] - a[None, :, 0]) \
                / (b[None, :, 1] - a[None, :, 1])
        inside |= (np.count_nonzero(cross & (x[:, None] < xc), axis=1) % 2) == 1
        # on an edge
        d = b - a
        t = np.clip(((pts[:, None, :] - a[None]) * d[None]).sum(-1) / (d * d).sum(-1), 0, 1)
        near = np.linalg.norm(a[None] + t[..., None] * d[None] - pts[:, None, :], axis=-1)
        inside |= near.min(axis=1) <= tol
    return inside


def segment_distance(p: np.ndarray, q: np.ndarray, r: np.ndarray, s: np.ndarray) -> float:
    """Distance between the segments pq and rs (0 if they cross)."""
    def orient(a, b, c):
        return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])

    d1, d2, d3, d4 = orient(r, s, p), orient(r, s, q), orient(p, q, r), orient(p, q, s)
    if d1 * d2 < 0 and d3 * d4 < 0:
        return 0.0

    def to_segment(x, a, b):
        ab = b - a
        t = float(np.clip(np.dot(x - a, ab) / np.dot(ab, ab), 0.0, 1.0))
        return float(np.linalg.norm(a + t * ab - x))

    return min(to_segment(p, r, s), to_segment(q, r, s), to_segment(r, p, q),
               to_segment(s, p, q))


def polyline_distance(a: np.ndarray, b: np.ndarray) -> float:
    """Smallest distance between two polylines [m]."""
    return min(segment_distance(a[i], a[i + 1], b[j], b[j + 1])
               for i in range(len(a) - 1) for j in range(len(b) - 1))
