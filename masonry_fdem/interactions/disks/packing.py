"""Polydisperse disk packings of a polygonal region (granular fill).

:func:`pack_disks` fills a simple polygon [m] with disks whose radii follow a given
distribution and whose total area is exactly ``(1 − porosity) × region area``:

1. radii are drawn (uniform in [r_min, r_max], or uniform in area — more small grains),
   then scaled so that Σ π r² = (1 − n) A;
2. the disks are placed by random sequential addition at half their radii (largest
   first, a cell list for the overlap checks, centres at least r from every edge), which
   always succeeds at a quarter of the target solid fraction;
3. the radii grow back to full size in stages; after each stage overlaps between disks
   and with the polygon edges are relaxed by Jacobi sweeps (each overlap pushes both
   disks apart by half of it, a wall pushes the disk out), until the largest overlap is
   below ``tol`` × r_min.

Dense random 2D packings jam near a solid fraction of 0.82–0.84 (porosity 0.16–0.18), so
targets below about 0.2 may not relax fully; the largest remaining overlap is reported.
The disks are returned in a spatial (cell-by-cell) order, which keeps neighbours close
in memory. A packing is then typically settled under gravity by the explicit solver (the
fill then compacts a little further).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from masonry_fdem.interactions.disks._kernels import disk_pairs_cell_list

__all__ = ["pack_disks", "spatial_order"]


@njit(cache=True)
def _edge_push(px, py, ax, ay, bx, by, r):
    """Displacement pushing a disk at (px, py) of radius r out of the edge a→b (interior on
    the left of a counter-clockwise polygon); zero if clear."""
    ex = bx - ax
    ey = by - ay
    L2 = ex * ex + ey * ey
    t = ((px - ax) * ex + (py - ay) * ey) / L2
    t = min(max(t, 0.0), 1.0)
    qx = ax + t * ex
    qy = ay + t * ey
    dx = px - qx
    dy = py - qy
    d = math.sqrt(dx * dx + dy * dy)
    inside = (ex * (py - ay) - ey * (px - ax)) >= 0.0
    if inside:
        if d >= r or d == 0.0:
            return 0.0, 0.0
        s = (r - d) / d
        return dx * s, dy * s
    # outside: bring the centre back inside by r
    if d == 0.0:
        return 0.0, 0.0
    s = -(r + d) / d
    return dx * s, dy * s


@njit(cache=True)
def _relax(x, r, poly, pairs, sweeps, dx):
    """Jacobi overlap-removal sweeps; returns the largest overlap left [m]."""
    n = x.shape[0]
    nv = poly.shape[0]
    worst = 0.0
    for _ in range(sweeps):
        dx[:] = 0.0
        worst = 0.0
        for k in range(pairs.shape[0]):
            i = pairs[k, 0]
            j = pairs[k, 1]
            ux = x[j, 0] - x[i, 0]
            uy = x[j, 1] - x[i, 1]
            d = math.sqrt(ux * ux + uy * uy)
            ov = r[i] + r[j] - d
            if ov > 0.0 and d > 0.0:
                worst = max(worst, ov)
                s = 0.5 * ov / d
                wi = r[j] * r[j] / (r[i] * r[i] + r[j] * r[j])  # small disks move more
                dx[i, 0] -= 2.0 * wi * s * ux
                dx[i, 1] -= 2.0 * wi * s * uy
                dx[j, 0] += 2.0 * (1.0 - wi) * s * ux
                dx[j, 1] += 2.0 * (1.0 - wi) * s * uy
        for i in range(n):
            for e in range(nv):
                a = poly[e]
                b = poly[(e + 1) % nv]
                px, py = _edge_push(x[i, 0] + dx[i, 0], x[i, 1] + dx[i, 1], a[0], a[1], b[0],
                                    b[1], r[i])
                worst = max(worst, math.sqrt(px * px + py * py))
                dx[i, 0] += px
                dx[i, 1] += py
        for i in range(n):
            x[i, 0] += dx[i, 0]
            x[i, 1] += dx[i, 1]
        if worst == 0.0:
            break
    return worst


def _inside(poly, p, r):
    """Is the disk (p, r) inside the counter-clockwise polygon, clear of its edges?"""
    a = poly
    b = np.roll(poly, -1, axis=0)
    e = b - a
    cross = e[:, 0] * (p[1] - a[:, 1]) - e[:, 1] * (p[0] - a[:, 0])
    if np.any(cross < 0):
        return False
    t = np.clip(((p - a) * e).sum(axis=1) / (e * e).sum(axis=1), 0.0, 1.0)
    d = np.linalg.norm(a + t[:, None] * e - p, axis=1)
    return bool(np.all(d >= r))


def pack_disks(
    polygon,
    r_min: float,
    r_max: float,
    porosity: float,
    *,
    distribution: str = "uniform",
    seed: int = 0,
    tol: float = 1e-3,
    max_sweeps: int = 20_000,
) -> tuple[np.ndarray, np.ndarray]:
    """Centres (n, 2) [m] and radii (n,) [m] of a random packing of a convex or simple
    counter-clockwise polygon [m] at the given porosity (see the module docstring).

    Args:
        polygon: (k, 2) vertices, counter-clockwise.
        r_min, r_max: radius range [m], 0 < r_min ≤ r_max.
        porosity: void fraction of the region, 0.15 < n < 1.
        distribution: "uniform" (radii uniform) or "area" (grain areas uniform).
        seed: random seed (the same packing on every rank).
        tol: the largest overlap accepted, relative to r_min.

    Raises:
        ValueError: bad input, or the region cannot hold the disks at that porosity.
    """
    poly = np.asarray(polygon, dtype=float)
    if poly.ndim != 2 or poly.shape[1] != 2 or poly.shape[0] < 3:
        raise ValueError("polygon must be (k >= 3, 2) vertices")
    area2 = np.sum(poly[:, 0] * np.roll(poly[:, 1], -1) - np.roll(poly[:, 0], -1) * poly[:, 1])
    if area2 <= 0:
        raise ValueError("polygon must be counter-clockwise with positive area")
    if not (0 < r_min <= r_max):
        raise ValueError(f"need 0 < r_min <= r_max, got {r_min}, {r_max}")
    if not 0.15 < porosity < 1.0:
        raise ValueError(f"porosity must lie in (0.15, 1), got {porosity}")
    if distribution not in ("uniform", "area"):
        raise ValueError(f"distribution must be 'uniform' or 'area', got {distribution!r}")
    area = 0.5 * area2
    target = (1.0 - porosity) * area
    rng = np.random.default_rng(seed)
    radii = []
    total = 0.0
    while total < target:
        if distribution == "uniform":
            rr = rng.uniform(r_min, r_max)
        else:
            rr = math.sqrt(rng.uniform(r_min**2, r_max**2))
        radii.append(rr)
        total += math.pi * rr * rr
    r = np.sort(np.array(radii))[::-1].copy()
    r *= math.sqrt(target / (math.pi * np.sum(r * r)))
    # random sequential addition at half size
    lo, hi = poly.min(axis=0), poly.max(axis=0)
    half = 0.5 * r
    h = 2.0 * half.max()
    nx = max(1, int((hi[0] - lo[0]) / h) + 1)
    ny = max(1, int((hi[1] - lo[1]) / h) + 1)
    grid: dict[tuple[int, int], list[int]] = {}
    x = np.zeros((r.size, 2))
    for i, ri in enumerate(half):
        for _ in range(20_000):
            p = lo + rng.uniform(0, 1, 2) * (hi - lo)
            if not _inside(poly, p, ri):
                continue
            cx, cy = int((p[0] - lo[0]) / h), int((p[1] - lo[1]) / h)
            ok = True
            for gx in range(max(cx - 1, 0), min(cx + 2, nx)):
                for gy in range(max(cy - 1, 0), min(cy + 2, ny)):
                    for j in grid.get((gx, gy), ()):
                        if np.hypot(*(x[j] - p)) < ri + half[j]:
                            ok = False
                            break
            if ok:
                x[i] = p
                grid.setdefault((cx, cy), []).append(i)
                break
        else:
            raise ValueError("could not place the disks: the region is too small for them")
    # grow in stages and relax
    dx = np.zeros_like(x)
    worst = 0.0
    for s in np.linspace(0.5, 1.0, 11)[1:]:
        rs = s * r
        for _ in range(200):
            pairs = disk_pairs_cell_list(x, rs, 0.1 * r_min)
            worst = _relax(x, rs, poly, pairs, max(1, max_sweeps // 2000), dx)
            if worst <= tol * r_min:
                break
    if worst > tol * r_min:
        pairs = disk_pairs_cell_list(x, r, 0.1 * r_min)
        for _ in range(100):
            worst = _relax(x, r, poly, pairs, 100, dx)
            if worst <= tol * r_min:
                break
            pairs = disk_pairs_cell_list(x, r, 0.1 * r_min)
    if worst > tol * r_min:
        raise ValueError(
            f"packing at porosity {porosity} left overlaps of {worst / r_min:.3g} r_min "
            "(denser than the disks can pack: raise the porosity or widen the size range)")
    order = spatial_order(x, 2.0 * r_max)
    return x[order].copy(), r[order].copy()


def spatial_order(x: np.ndarray, h: float) -> np.ndarray:
    """A permutation putting points [m] in row-by-row order of cells of size h [m]
    (serpentine within a row): neighbours in space become neighbours in memory, which
    the contact kernels need at large numbers of disks (random order was 4-7x slower
    at 1e5-1e6 disks in ``benchmarks/disks.py``)."""
    x = np.asarray(x, dtype=float)
    c = np.floor((x - x.min(axis=0)) / h).astype(np.int64)
    row = c[:, 1]
    col = np.where(row % 2 == 0, c[:, 0], -c[:, 0])
    return np.lexsort((x[:, 0], col, row))
