"""Fill over an arch: the block of backfill between the extrados, the abutments, two
retaining end walls and the road, for a continuum (Mohr–Coulomb) fill model.

In a plane (2-D) model of an arch bridge the fill is retained at its two ends; here by two
rigid walls (``wall:left``, ``wall:right``) standing on the outer faces of the abutments
from their base to the road, which the caller fixes with the abutments. The spandrel walls
of a real bridge lie outside the plane and are not modelled. Units: metres.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from masonry_fdem.geometry.layout import BlockLayout

__all__ = [
    "crown_height",
    "extrados_vertices",
    "fill_layout",
    "fill_loads",
    "fill_passive",
    "passive_coefficient",
    "upper_envelope",
]


def upper_envelope(layout: BlockLayout, x: np.ndarray,
                   names: str | tuple[str, ...] | None = None) -> np.ndarray:
    """Highest y [m] of the block outlines on each vertical line x [m] (-inf where no
    block, or none whose name starts with ``names``, spans x)."""
    x = np.atleast_1d(np.asarray(x, dtype=float))
    best = np.full(x.shape, -np.inf)
    for poly, name in zip(layout.polygons, layout.names, strict=True):
        if names is not None and not name.startswith(names):
            continue
        a, b = poly, np.roll(poly, -1, axis=0)
        sloped = b[:, 0] != a[:, 0]
        a, b = a[sloped], b[sloped]
        lo, hi = np.minimum(a[:, 0], b[:, 0]), np.maximum(a[:, 0], b[:, 0])
        inside = (lo[None, :] <= x[:, None]) & (x[:, None] <= hi[None, :])
        t = (x[:, None] - a[None, :, 0]) / (b[None, :, 0] - a[None, :, 0])
        y = np.where(inside, a[None, :, 1] + t * (b[None, :, 1] - a[None, :, 1]), -np.inf)
        if y.size:
            best = np.maximum(best, y.max(axis=1))
    return best


def extrados_vertices(structure: BlockLayout,
                       names: str | tuple[str, ...] = "voussoir:") -> np.ndarray:
    """``(k, 2)`` vertices [m] of the voussoirs that lie on their upper envelope (the
    extrados), in increasing x; ``names``: the prefix(es) of the blocks taken (with
    ``("voussoir:", "backing:")`` the extrados above the haunches' backing and the
    backing's top)."""
    vs = np.vstack([p for p, n in zip(structure.polygons, structure.names, strict=True)
                    if n.startswith(names)])
    top = upper_envelope(structure, vs[:, 0], names)
    on = vs[vs[:, 1] >= top - 1e-9 * np.ptp(vs[:, 0])]
    _, first = np.unique(on[:, 0], return_index=True)
    return on[first]


def crown_height(structure: BlockLayout) -> float:
    """y [m] of the highest extrados vertex (the crown's extrados)."""
    return float(extrados_vertices(structure)[:, 1].max())


def fill_layout(
    structure: BlockLayout,
    *,
    cover: float,
    wall_thickness: float = 0.3,
    road_points: Sequence[float] = (),
    material: str = "fill",
    wall_material: str = "abutment",
    backing: float = 0.0,
    backing_material: str | None = None,
) -> BlockLayout:
    """The fill over the arch of ``structure`` and its two retaining end walls.

    The fill spans the structure's width (the outer faces of its abutments); it lies on
    the upper envelope of the voussoirs and abutments (the extrados and the abutment
    tops), and its top, the road, is ``cover`` above the highest point of the extrados
    (the crown). Its outline has every vertex of the envelope, so the fill's mesh meets
    the extrados node to node at the start.

    Args:
        structure: the arch with its abutments (e.g. :func:`arch_layout` with
            ``abutment_height > 0``); voussoirs are named ``voussoir:*``.
        cover: fill depth over the crown's extrados [m], > 0.
        wall_thickness: thickness [m] of each end wall.
        road_points: x [m] that get a vertex on the road (where loads bear).
        material: material name of the fill.
        wall_material: material name of the end walls.
        backing: height [m] of the haunches' backing above the intrados springing (the
            lowest voussoir vertex); 0: none. The backing is the masonry (or concrete)
            built on the abutments and piers against the ring's lower extrados, up to a
            level top: each stretch where the fill's bed lies below that level becomes a
            block ``backing:<i>`` (left to right), and the fill lies on its top. The top
            meets the extrados at least a quarter of a chord from the chord's ends.
        backing_material: material name of the backing (default ``wall_material``).

    Returns:
        The blocks ``fill``, ``wall:left``, ``wall:right``, then ``backing:<i>`` if any
        (the structure not included).

    Raises:
        ValueError: no voussoir in ``structure``, a cover or wall thickness <= 0, a
            backing < 0 or reaching the crown's extrados, or a road point off the fill.
    """
    if not (np.isfinite(cover) and cover > 0.0):
        raise ValueError(f"fill cover must be > 0 m, got {cover}")
    if not (np.isfinite(wall_thickness) and wall_thickness > 0.0):
        raise ValueError(f"wall_thickness must be > 0 m, got {wall_thickness}")
    if not any(n.startswith("voussoir:") for n in structure.names):
        raise ValueError("no voussoir in the structure: the fill needs an arch under it")
    xmin, ymin, xmax, _ = structure.bounds
    span = xmax - xmin
    tol = 1e-9 * span
    # the x of the vertices on the envelope (those of lower faces would put needless
    # vertices, and needle triangles, on the extrados' chords)
    allv = np.vstack(structure.polygons)
    on_top = allv[:, 1] >= upper_envelope(structure, allv[:, 0]) - tol
    verts = np.unique(allv[on_top, 0])
    # the envelope at each vertex, from both sides where it jumps (a vertical face)
    left = upper_envelope(structure, np.clip(verts - tol, xmin, xmax))
    right = upper_envelope(structure, np.clip(verts + tol, xmin, xmax))
    here = upper_envelope(structure, verts)
    bottom = []
    near = 1e-6 * span  # a jump or a new vertex: farther than this [m]
    for x, yl, y0, yr in zip(verts, left, here, right, strict=True):
        for y in ((yl, y0, yr) if abs(yl - yr) > near else (y0,)):
            if np.isfinite(y) and (not bottom or np.hypot(x - bottom[-1][0],
                                                          y - bottom[-1][1]) > near):
                bottom.append((x, y))
    bottom = np.array(bottom)
    if not np.all(np.isfinite(bottom)):
        raise ValueError("the structure has a gap under the fill")
    crown = crown_height(structure)
    road = crown + float(cover)
    if bottom[:, 1].max() >= road - tol:
        raise ValueError(f"the abutments reach the road (cover {cover} m over the crown)")
    backs = []
    if backing != 0.0:
        if not (np.isfinite(backing) and backing > 0.0):
            raise ValueError(f"backing must be >= 0 m above the springing, got {backing}")
        vs = np.vstack([p for p, n in zip(structure.polygons, structure.names, strict=True)
                        if n.startswith("voussoir:")])
        level = float(vs[:, 1].min()) + float(backing)
        crown = crown_height(structure)
        if level >= crown - near:
            raise ValueError(f"the backing ({backing:g} m above the springing, up to y = "
                             f"{level:g} m) reaches the crown's extrados (y = {crown:g} m): "
                             "there would be no arch left above it")
        bottom, backs = _cut_backing(bottom, level, near)
    pts = sorted({float(x) for x in road_points}, reverse=True)
    for x in pts:
        if not xmin < x < xmax:
            raise ValueError(f"road point x = {x:g} m is off the fill ({xmin:g} to {xmax:g} m)")
    top = [(x, road) for x in pts if tol < x - xmin and tol < xmax - x]
    fill = np.vstack([bottom, [(xmax, road)], np.array(top).reshape(-1, 2), [(xmin, road)]])
    t = float(wall_thickness)
    walls = [np.array([(xmin - t, ymin), (xmin, ymin), (xmin, road), (xmin - t, road)]),
             np.array([(xmax, ymin), (xmax + t, ymin), (xmax + t, road), (xmax, road)])]
    bm = wall_material if backing_material is None else backing_material
    return BlockLayout((fill, *walls, *backs),
                       (material, wall_material, wall_material, *[bm] * len(backs)),
                       ("fill", "wall:left", "wall:right",
                        *[f"backing:{i}" for i in range(len(backs))]))


def _crossing(q: np.ndarray, p: np.ndarray, level: float) -> tuple[float, float]:
    """Where the backing's top meets the bed's chord q–p, which crosses y = ``level``:
    there, but at least a quarter of the chord from either end, so that no sliver of fill
    or backing is left and the backing's corner is not at a joint of the ring (where the
    joint opens; the top then rises or dips there by a fraction of the chord's
    height)."""
    t = min(max((level - q[1]) / (p[1] - q[1]), 0.25), 0.75)
    return (float(q[0] + t * (p[0] - q[0])), float(q[1] + t * (p[1] - q[1])))


def _cut_backing(bottom: np.ndarray, level: float, near: float):
    """Split the fill's bed (a polyline in increasing x) at y = ``level``: ``(new bed,
    backing polygons)``. Every stretch of the bed below the level becomes a polygon (the
    bed, counter-clockwise, closed by the level), and the new bed runs along the level
    over it (from its crossings of the bed, :func:`_crossing`)."""
    below = bottom[:, 1] < level - near
    bed, backs = [], []
    run: list = []
    for i, p in enumerate(bottom):
        if below[i]:
            if not run:
                run = [(p[0], level) if i == 0 else _crossing(bottom[i - 1], p, level)]
                bed.append(run[0])
            run.append(tuple(p))
            continue
        if run:
            end = _crossing(bottom[i - 1], p, level)
            backs.append(_dedupe_points(run[1:] + [end, run[0]], near))
            bed.append(end)
            run = []
        bed.append(tuple(p))
    if run:  # the bed ends below the level (at the end wall)
        end = (bottom[-1][0], level)
        backs.append(_dedupe_points(run[1:] + [end, run[0]], near))
        bed.append(end)
    return _dedupe_points(bed, near), backs


def _dedupe_points(points, near: float) -> np.ndarray:
    """The points without consecutive ones closer than ``near`` (nor a last one at the
    first)."""
    keep = [np.asarray(points[0], dtype=float)]
    for p in points[1:]:
        p = np.asarray(p, dtype=float)
        if np.hypot(*(p - keep[-1])) > near:
            keep.append(p)
    if len(keep) > 2 and np.hypot(*(keep[-1] - keep[0])) <= near:
        keep.pop()
    return np.array(keep)


def fill_loads(
    structure: BlockLayout,
    *,
    road: float,
    unit_weight: float,
    patch: tuple[float, float],
    spread: float = 0.5,
    interface_friction: float | None = None,
) -> tuple[list, list]:
    """The fill as loads on a rigid-block arch, for limit analysis (the way RING treats
    fill without its passive resistance): the weight of the fill column over each chord of
    the extrados, and a unit live load on the road dispersed down to the extrados.

    Args:
        structure: the arch and its abutments (voussoirs named ``voussoir:*``), and the
            backing (``backing:*``, :func:`fill_layout`) if any: the fill then lies on the
            extrados above the backing and on the backing's top, whose loads go to it.
        road: y of the road [m].
        unit_weight: γ w, the fill's weight per unit volume times the barrel width [N/m³·m].
        patch: (x centre, width) [m] of the load on the road (width > 0).
        spread: horizontal spread per unit depth on each side (0.5: the 2:1 rule, a
            dispersion angle of 26.6° from the vertical).
        interface_friction: tan δ of the fill on the extrados, or None (RING: every load
            vertical). Given, a chord steeper than δ (inclined at θ > δ) takes its loads
            inclined by θ − δ from the vertical, uphill (towards the crown): the fill's
            traction on it can lean at most δ from its normal. The vertical parts are
            unchanged.

    Returns:
        ``(dead, live)``: ``((x, y), (Fx, −F))`` point loads [N] on the extrados, the dead
        ones the fill's weight, the live ones' vertical parts summing to 1 N (Fx = 0 unless
        ``interface_friction`` is given).
    """
    x0, b = float(patch[0]), float(patch[1])
    if not b > 0:
        raise ValueError(f"the load patch needs a width > 0 m, got {b}")
    bed = ("voussoir:", "backing:")
    xs = extrados_vertices(structure, bed)[:, 0]
    dead, live = [], []
    weights = []
    lean = []  # per chord with live load: Fx / |Fy|
    delta = None if interface_friction is None else math.atan(float(interface_friction))
    for xa, xb in zip(xs[:-1], xs[1:], strict=True):
        t = np.linspace(xa, xb, 9)
        y = upper_envelope(structure, t, bed)
        depth = road - y
        area = np.trapezoid(depth, t)
        xc = float(np.trapezoid(depth * t, t) / area) if area > 0 else 0.5 * (xa + xb)
        yc = float(upper_envelope(structure, np.array([xc]), bed)[0])
        tilt = 0.0
        if delta is not None:
            rise = float(y[-1] - y[0])  # the chord's ends (t runs from xa to xb)
            theta = math.atan(abs(rise) / (xb - xa))
            tilt = math.copysign(math.tan(max(0.0, theta - delta)), rise)
        if area > 0:
            dead.append(((xc, yc), (tilt * unit_weight * area, -unit_weight * area)))
        # the dispersed patch at this chord's depth: [x0 - b/2 - s h, x0 + b/2 + s h]
        h = float(road - yc)
        half = 0.5 * b + spread * h
        lo, hi = max(xa, x0 - half), min(xb, x0 + half)
        if hi > lo:
            weights.append(((xc, yc), (hi - lo) / (2.0 * half)))
            lean.append(tilt)
    total = sum(w for _, w in weights)
    if total <= 0:
        raise ValueError(f"the load patch at x = {x0:g} m disperses onto no voussoir")
    live = [(p, (t * w / total, -w / total)) for (p, w), t in zip(weights, lean, strict=True)]
    return dead, live


def passive_coefficient(phi: float) -> float:
    """Rankine's passive earth pressure coefficient ``K_p = (1 + sin φ) / (1 − sin φ)`` of
    a friction angle ``phi`` [degrees] (a smooth vertical wall, a level surface)."""
    if not (np.isfinite(phi) and 0.0 <= phi < 90.0):
        raise ValueError(f"the friction angle must be in [0, 90) degrees, got {phi}")
    s = np.sin(np.radians(phi))
    return float((1.0 + s) / (1.0 - s))


def fill_passive(
    structure: BlockLayout,
    *,
    road: float,
    unit_weight: float,
    phi: float,
    cohesion: float = 0.0,
    width: float = 1.0,
    mobilisation: float = 1.0,
) -> list:
    """The passive resistance of the fill to an arch that sways into it, as bounded
    horizontal forces for limit analysis (the way LimitState:RING models it): on each chord
    of the extrados, a horizontal force pushing the ring away from the fill whose magnitude
    the LP may choose between 0 and the passive thrust on the chord's vertical projection,

    .. math:: F_{max} = m \\int (K_p\\, γ z + 2 c \\sqrt{K_p})\\, w\\, dy,

    ``z = road − y`` the depth, ``m`` the mobilisation factor (the part of Rankine's passive
    pressure the small sway of an arch mobilises; 1 is the full passive state).

    Args:
        structure: the arch and its abutments (voussoirs named ``voussoir:*``), and the
            backing (``backing:*``) if any.
        road: y of the road [m].
        unit_weight: γ w, the fill's unit weight times the barrel width [N/m³·m].
        phi: the fill's friction angle [degrees].
        cohesion: its cohesion c [Pa].
        width: the barrel width w [m] (for the cohesion's part).
        mobilisation: m, in [0, 1].

    Returns:
        ``((x, y), (±1, 0), (0, F_max))`` per chord with a vertical extent: the force acts
        at the resultant of the pressure on the chord, towards the span's inside (+x where
        the extrados rises with x, the fill's side being its upper left).
    """
    if not (np.isfinite(mobilisation) and 0.0 <= mobilisation <= 1.0):
        raise ValueError(f"the passive mobilisation factor must be in [0, 1], got {mobilisation}")
    if not (np.isfinite(cohesion) and cohesion >= 0.0):
        raise ValueError(f"the fill's cohesion must be >= 0 Pa, got {cohesion}")
    kp = passive_coefficient(phi)
    v = extrados_vertices(structure, ("voussoir:", "backing:"))
    out = []
    for (xa, ya), (xb, yb) in zip(v[:-1], v[1:], strict=True):
        dy = yb - ya
        if abs(dy) <= 1e-12 * max(1.0, abs(road)):
            continue
        t = np.linspace(0.0, 1.0, 9)
        z = np.clip(road - (ya + t * dy), 0.0, None)
        p = mobilisation * (kp * unit_weight * z + 2.0 * cohesion * np.sqrt(kp) * width)
        force = float(np.trapezoid(p, t)) * abs(dy)
        if force <= 0.0:
            continue
        tc = float(np.trapezoid(p * t, t) / np.trapezoid(p, t))
        point = (float(xa + tc * (xb - xa)), float(ya + tc * dy))
        out.append((point, (float(np.sign(dy)), 0.0), (0.0, force)))
    return out
