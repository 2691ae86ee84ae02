"""Plane polygons of masonry units: validation, orientation and small measures.

A block outline is an ``(k, 2)`` float64 array of vertex coordinates [m], listed in order
around the block, not closed (the last vertex is not a copy of the first). The builders
produce counter-clockwise outlines; :func:`as_polygon` accepts either orientation and
returns the counter-clockwise one, so every later stage can assume the block interior is
on the left of each edge.

Collinear vertices are allowed (an abutment's top face carries one vertex per arch ring so
that the facets of both bodies start and end at the same points); repeated vertices,
zero-area outlines and self-intersecting outlines are rejected.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "as_polygon",
    "polygon_area",
    "polygon_centroid",
    "polygon_diameter",
    "is_simple",
    "rectangle",
]

# Relative tolerance (to the polygon's size) under which two vertices are the same point.
_VERTEX_TOL = 1e-12
# Above this many vertices the O(k^2) self-intersection test is skipped.
_MAX_SIMPLE_CHECK = 512


def polygon_area(p: np.ndarray) -> float:
    """Signed area of a polygon [m^2] (shoelace formula), positive if counter-clockwise.

    Args:
        p: ``(k, 2)`` vertices [m].

    Returns:
        The signed area [m^2].
    """
    p = np.asarray(p, dtype=np.float64)
    x, y = p[:, 0], p[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


def polygon_centroid(p: np.ndarray) -> np.ndarray:
    """Area centroid of a simple polygon [m].

    Args:
        p: ``(k, 2)`` vertices [m], either orientation.

    Returns:
        ``(2,)`` centroid [m].
    """
    p = np.asarray(p, dtype=np.float64)
    q = np.roll(p, -1, axis=0)
    cross = p[:, 0] * q[:, 1] - q[:, 0] * p[:, 1]
    a = 0.5 * cross.sum()
    return np.array(
        [((p[:, 0] + q[:, 0]) * cross).sum(), ((p[:, 1] + q[:, 1]) * cross).sum()]
    ) / (6.0 * a)


def polygon_diameter(p: np.ndarray) -> float:
    """Largest distance between two vertices [m] (the size used to pick the coarsest mesh)."""
    p = np.asarray(p, dtype=np.float64)
    d = p[:, None, :] - p[None, :, :]
    return float(np.sqrt((d * d).sum(axis=2).max()))


def rectangle(x0: float, y0: float, x1: float, y1: float) -> np.ndarray:
    """Counter-clockwise rectangle ``[x0, x1] x [y0, y1]`` [m] as a ``(4, 2)`` array."""
    if not (x1 > x0 and y1 > y0):
        raise ValueError(f"empty rectangle [{x0}, {x1}] x [{y0}, {y1}]")
    return np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]], dtype=np.float64)


def _segments_cross(a: np.ndarray, b: np.ndarray, c: np.ndarray, d: np.ndarray, tol: float):
    """Whether segments a-b and c-d (arrays of segments, broadcast) properly intersect."""

    def orient(p, q, r):
        return (q[..., 0] - p[..., 0]) * (r[..., 1] - p[..., 1]) - (q[..., 1] - p[..., 1]) * (
            r[..., 0] - p[..., 0]
        )

    o1, o2 = orient(a, b, c), orient(a, b, d)
    o3, o4 = orient(c, d, a), orient(c, d, b)
    return (o1 * o2 < -tol) & (o3 * o4 < -tol)


def is_simple(p: np.ndarray) -> bool:
    """Whether no two non-adjacent edges of the polygon cross (O(k^2) test).

    Touching at a vertex or overlapping collinear edges is not detected; crossing edges
    (a bow-tie outline) are.

    Args:
        p: ``(k, 2)`` vertices [m].
    """
    p = np.asarray(p, dtype=np.float64)
    k = p.shape[0]
    if k < 4:
        return True
    a, b = p, np.roll(p, -1, axis=0)
    scale = float(np.ptp(p, axis=0).max())
    tol = (_VERTEX_TOL * scale) ** 2
    i, j = np.triu_indices(k, 2)
    keep = ~((i == 0) & (j == k - 1))  # first and last edges share a vertex
    i, j = i[keep], j[keep]
    return not bool(np.any(_segments_cross(a[i], b[i], a[j], b[j], tol)))


def as_polygon(p: np.ndarray, name: str = "polygon") -> np.ndarray:
    """Validate a block outline and return it counter-clockwise.

    Drops a closing vertex equal to the first and consecutive repeated vertices.

    Args:
        p: ``(k, 2)`` vertices [m] (or ``(k, 3)`` with zero z), either orientation.
        name: block name used in error messages.

    Returns:
        A new C-contiguous ``(k', 2)`` float64 array, counter-clockwise.

    Raises:
        ValueError: not an array of 2D points, non-finite or nonzero-z coordinates, fewer
            than 3 distinct vertices, zero area, or crossing edges.
    """
    q = np.array(p, dtype=np.float64, copy=True)
    if q.ndim != 2 or q.shape[1] not in (2, 3):
        raise ValueError(f"{name}: vertices must be an array of shape (k, 2), got {q.shape}")
    if not np.all(np.isfinite(q)):
        raise ValueError(f"{name}: vertex coordinates must be finite")
    if q.shape[1] == 3:
        if np.any(q[:, 2] != 0.0):
            raise ValueError(f"3D vertices in {name}: z must be 0 for a plane block")
        q = q[:, :2]
    if q.shape[0] < 3:
        raise ValueError(f"{name}: a polygon needs at least 3 vertices, got {q.shape[0]}")
    scale = float(np.ptp(q, axis=0).max())
    step = np.linalg.norm(np.roll(q, -1, axis=0) - q, axis=1)
    q = q[step > _VERTEX_TOL * max(scale, 1e-300)]
    if q.shape[0] < 3:
        raise ValueError(f"{name}: fewer than 3 distinct vertices")
    area = polygon_area(q)
    if abs(area) <= _VERTEX_TOL * scale * scale:
        raise ValueError(f"{name}: polygon has zero area")
    if area < 0.0:
        q = q[::-1]
    if q.shape[0] <= _MAX_SIMPLE_CHECK and not is_simple(q):
        raise ValueError(f"{name}: polygon edges cross each other (self-intersecting outline)")
    return np.ascontiguousarray(q)
