"""Granular fill of an arch bridge as disks: a random packing of the fill region.

:func:`pack_polygon` packs any simple polygon (convex or not, e.g. the fill over the
extrados of an arch, whose lower boundary is concave): it packs the polygon's bounding
box with :func:`~masonry_fdem.interactions.disks.packing.pack_disks` (which needs a convex
region) and keeps the disks lying wholly inside the polygon, at least ``clearance`` [m]
clear of every edge. Along the boundary the kept packing is therefore looser than
inside (the disks cut by an edge are dropped: about half a diameter of extra voids along
the edges, so a region only some 10 diameters deep keeps 75-85 % of the disks that
:func:`radii_for_count` aims at, the 8.8 m² fill of a 6 m bridge at 5 000 disks about
94 %); it closes up when the fill settles under gravity.

:func:`fill_disks` packs the fill of :func:`~masonry_fdem.geometry.fill.fill_layout` over
an arch layout (between the extrados, the abutment tops, the two end walls and the road).
:func:`radii_for_count` gives a radius range for about a wanted number of disks.

Units SI (metres).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from masonry_fdem.geometry.polygons import polygon_area
from masonry_fdem.interactions.disks.packing import pack_disks

__all__ = ["fill_disks", "pack_polygon", "radii_for_count"]


@njit(cache=True)
def _inside_clear(x, r, poly, clearance, out):
    """out[i] = 1 if the disk (x_i, r_i) lies inside the simple polygon (crossing number)
    and its centre is at least r_i + clearance from every edge, else 0."""
    nv = poly.shape[0]
    for i in range(x.shape[0]):
        px = x[i, 0]
        py = x[i, 1]
        inside = False
        dmin = np.inf
        for e in range(nv):
            ax = poly[e, 0]
            ay = poly[e, 1]
            bx = poly[(e + 1) % nv, 0]
            by = poly[(e + 1) % nv, 1]
            if (ay > py) != (by > py):
                xc = ax + (py - ay) * (bx - ax) / (by - ay)
                if px < xc:
                    inside = not inside
            ex = bx - ax
            ey = by - ay
            t = ((px - ax) * ex + (py - ay) * ey) / (ex * ex + ey * ey)
            t = min(max(t, 0.0), 1.0)
            dx = px - (ax + t * ex)
            dy = py - (ay + t * ey)
            dmin = min(dmin, math.sqrt(dx * dx + dy * dy))
        out[i] = 1 if inside and dmin >= r[i] + clearance else 0


def _polygon(polygon) -> np.ndarray:
    poly = np.asarray(polygon, dtype=float)
    if poly.ndim != 2 or poly.shape[1] != 2 or poly.shape[0] < 3:
        raise ValueError(f"polygon must be (k >= 3, 2) vertices [m], got shape {poly.shape}")
    if not np.all(np.isfinite(poly)):
        raise ValueError("polygon vertices must be finite")
    if polygon_area(poly) <= 0:
        raise ValueError("polygon must be counter-clockwise with positive area")
    return np.ascontiguousarray(poly)


def radii_for_count(area: float, count: int, porosity: float = 0.2,
                    spread: float = 0.25) -> tuple[float, float]:
    """Radius range (r_min, r_max) [m], uniform about r̄ with r_max/r_min = (1 + s)/(1 − s),
    for about ``count`` disks filling ``area`` [m²] at ``porosity``: π E[r²] n = (1 − n_p) A.
    Disks dropped along the boundary (:func:`pack_polygon`) make the count a few per cent
    lower; ask for a little more.

    Raises:
        ValueError: area <= 0, count < 1, porosity outside (0, 1), spread outside [0, 1).
    """
    if not (math.isfinite(area) and area > 0):
        raise ValueError(f"area must be > 0 m², got {area}")
    if not (isinstance(count, (int, np.integer)) and count >= 1):
        raise ValueError(f"count must be an integer >= 1, got {count!r}")
    if not 0.0 < porosity < 1.0:
        raise ValueError(f"porosity must lie in (0, 1), got {porosity}")
    if not 0.0 <= spread < 1.0:
        raise ValueError(f"spread must lie in [0, 1), got {spread}")
    # r uniform in [r̄(1 − s), r̄(1 + s)]: E[r²] = r̄² (1 + s²/3)
    rbar = math.sqrt((1.0 - porosity) * area / (math.pi * count * (1.0 + spread**2 / 3.0)))
    return rbar * (1.0 - spread), rbar * (1.0 + spread)


def pack_polygon(polygon, r_min: float, r_max: float, porosity: float = 0.2, *,
                 clearance: float | None = None, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Centres (n, 2) [m] and radii (n,) [m] of a random packing of a simple polygon (see
    the module docstring): the bounding box packed at ``porosity`` by
    :func:`~masonry_fdem.interactions.disks.packing.pack_disks`, and the disks kept whose
    centre lies inside the polygon at least r + ``clearance`` from every edge.

    Args:
        polygon: (k, 2) vertices [m], counter-clockwise, convex or not.
        r_min, r_max: radius range [m] (uniform), 0 < r_min <= r_max.
        porosity: porosity of the box's packing (0.15 < n < 1; 0.2 is near the jammed
            2D value of 0.16-0.18, so the fill settles little).
        clearance: gap [m] kept between the disks and the polygon's edges (default
            0.01 r_min), >= 0.
        seed: random seed (the same packing on every rank).

    Raises:
        ValueError: bad polygon, radii, porosity or clearance, or no disk fits.
    """
    poly = _polygon(polygon)
    if not (math.isfinite(r_min) and math.isfinite(r_max) and 0 < r_min <= r_max):
        raise ValueError(f"need 0 < r_min <= r_max [m], got {r_min}, {r_max}")
    clearance = 0.01 * r_min if clearance is None else float(clearance)
    if not (math.isfinite(clearance) and clearance >= 0):
        raise ValueError(f"clearance must be >= 0 m, got {clearance}")
    lo, hi = poly.min(axis=0), poly.max(axis=0)
    if np.any(hi - lo < 2.0 * (r_max + clearance)):
        raise ValueError(f"the polygon ({hi[0] - lo[0]:.3g} x {hi[1] - lo[1]:.3g} m) is "
                         f"narrower than one disk of radius {r_max:g} m")
    box = np.array([[lo[0], lo[1]], [hi[0], lo[1]], [hi[0], hi[1]], [lo[0], hi[1]]])
    x, r = pack_disks(box, r_min, r_max, porosity, seed=seed)
    keep = np.zeros(r.size, dtype=np.int8)
    _inside_clear(x, r, poly, clearance, keep)
    keep = keep.astype(bool)
    if not keep.any():
        raise ValueError("no disk fits in the polygon: make the disks smaller")
    return np.ascontiguousarray(x[keep]), np.ascontiguousarray(r[keep])


def fill_disks(structure, *, cover: float, r_min: float, r_max: float,
               porosity: float = 0.2, clearance: float | None = None, seed: int = 0,
               wall_thickness: float = 0.3):
    """The fill over an arch as disks: the region of
    :func:`~masonry_fdem.geometry.fill.fill_layout` (from the extrados and abutment tops
    up to the road, ``cover`` [m] over the crown, between the abutments' outer faces)
    packed by :func:`pack_polygon`.

    Args:
        structure: the arch with its abutments (:class:`~masonry_fdem.geometry.layout.BlockLayout`
            with voussoirs named ``voussoir:*``, e.g. ``case.layout()``).
        cover: fill depth over the crown's extrados [m], > 0.
        r_min, r_max, porosity, clearance, seed: as :func:`pack_polygon`.
        wall_thickness: thickness [m] of the two end walls returned.

    Returns:
        ``(x, r, walls)``: centres (n, 2) [m], radii (n,) [m], and the
        :class:`~masonry_fdem.geometry.layout.BlockLayout` of the two end walls
        (``wall:left``, ``wall:right``, material "abutment") to add to the structure.
        The fill polygon is ``fill_layout(...).polygons[0]``.

    Raises:
        ValueError: no voussoir, a bad cover (from ``fill_layout``), or bad packing input.
    """
    from masonry_fdem.geometry.fill import fill_layout
    from masonry_fdem.geometry.layout import BlockLayout

    if not isinstance(structure, BlockLayout):
        raise ValueError(f"structure must be a BlockLayout, got {type(structure).__name__}")
    fl = fill_layout(structure, cover=cover, wall_thickness=wall_thickness)
    x, r = pack_polygon(fl.polygons[0], r_min, r_max, porosity, clearance=clearance,
                        seed=seed)
    walls = BlockLayout(fl.polygons[1:3], fl.materials[1:3], fl.names[1:3])
    return x, r, walls
