"""Structured triangulations of rectangles for continuum regions (soil, test specimens).

:func:`crossed_grid` splits each cell of a tensor-product grid into four triangles by its
diagonals (a "union-jack" or crossed-triangle mesh). Linear (P1) triangles lock in
isochoric plastic flow on general meshes, but not on crossed ones: the four triangles of
a quadrilateral share its centre node, which leaves one incompressibility constraint per
quadrilateral instead of four, and collapse loads of undrained (Tresca, von Mises) soil
come out right (Nagtegaal, Parks & Rice 1974). Use it for Mohr–Coulomb soil at φ = 0 or
with isochoric flow (ψ = 0). Coordinates in metres.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

__all__ = ["crossed_grid", "graded"]


def graded(a: float, b: float, n: int, ratio: float = 1.0) -> np.ndarray:
    """``n + 1`` coordinates from a to b [m]; the last interval is ``ratio`` times the first
    (geometric grading; ratio < 1 refines towards b)."""
    if n < 1:
        raise ValueError(f"need at least one interval, got n={n}")
    if not ratio > 0:
        raise ValueError(f"grading ratio must be > 0, got {ratio}")
    if n == 1 or ratio == 1.0:
        return np.linspace(a, b, n + 1)
    q = ratio ** (1.0 / (n - 1))
    steps = q ** np.arange(n)
    return a + (b - a) * np.r_[0.0, np.cumsum(steps)] / steps.sum()


def crossed_grid(xs: Sequence[float], ys: Sequence[float]) -> tuple[np.ndarray, np.ndarray]:
    """Nodes (n, 2) [m] and counter-clockwise triangles (4 per grid cell) of the crossed
    triangulation of the grid with strictly increasing coordinates ``xs`` × ``ys``."""
    xs = np.asarray(xs, dtype=float)
    ys = np.asarray(ys, dtype=float)
    for name, c in (("xs", xs), ("ys", ys)):
        if c.ndim != 1 or c.size < 2 or np.any(np.diff(c) <= 0):
            raise ValueError(f"{name} must be at least two strictly increasing coordinates")
    nx, ny = xs.size - 1, ys.size - 1
    X, Y = np.meshgrid(xs, ys, indexing="ij")
    corners = np.c_[X.ravel(), Y.ravel()]
    xc = 0.5 * (xs[:-1] + xs[1:])
    yc = 0.5 * (ys[:-1] + ys[1:])
    XC, YC = np.meshgrid(xc, yc, indexing="ij")
    x = np.concatenate([corners, np.c_[XC.ravel(), YC.ravel()]])
    i, j = np.meshgrid(np.arange(nx), np.arange(ny), indexing="ij")
    i, j = i.ravel(), j.ravel()
    a = i * (ny + 1) + j  # lower left
    b = (i + 1) * (ny + 1) + j  # lower right
    c = b + 1  # upper right
    d = a + 1  # upper left
    m = corners.shape[0] + i * ny + j  # centre
    cells = np.concatenate([np.c_[a, b, m], np.c_[b, c, m], np.c_[c, d, m], np.c_[d, a, m]])
    return x, cells.astype(np.int64)
