"""Masonry arches: semicircular, segmental and pointed, with one or more rings of voussoirs.

Geometry (all lengths in metres, ``origin`` is the middle of the span on the springing
line, i.e. the intrados springing points are ``origin ± (span/2, 0)``):

* **semicircular**: one centre at the origin, intrados radius ``span/2``, rise ``span/2``.
* **segmental**: one centre below the springing line, intrados radius
  ``R = (span²/4 + rise²) / (2 rise)`` for ``rise < span/2``; the springing joints
  (skewbacks) are radial, hence inclined.
* **pointed** (two-centred): each half is an arc whose centre lies on the springing line
  in the other half, at distance ``c = (rise² - span²/4) / span`` from the axis; radius
  ``span/2 + c``; needs ``rise > span/2`` (``rise = span·√3/2`` is the equilateral arch).
  The crown is a corner on the axis.

Every ring has thickness ``ring_thickness``; ring ``k`` lies between the offsets
``k·t`` and ``(k+1)·t`` from the intrados, measured along the radius.

Voussoirs are polygons. A position along the arch is a parameter ``s`` in ``[0, 1]`` (left
springing to right springing, 0.5 at the crown); for circular arches ``s`` is proportional to
the angle, so joints are radial. For a pointed arch ``s`` is proportional to the angle of
each half measured up to the axis at the same radius, so the joint near the crown
leans slightly off radial and the crown stays on the axis for every ring.

Ring ``k`` has ``n_k`` voussoirs with joints at ``s = j / n_k``; its joints are shifted by
``stagger·k`` of a voussoir (modulo one voussoir). A shifted ring has ``n_k - 1`` full
voussoirs and two part voussoirs at the springings (``n_k + 1`` blocks), like the half bricks
of a running-bond wall.

Curved faces are polylines: each full voussoir's intrados and extrados are split into
``segments`` equal steps of ``s`` (part voussoirs proportionally, at least one), with
vertices on the exact curves. The faces of two neighbouring rings share the same vertices
(the union of both rings' vertices), so rings neither overlap nor leave gaps. For a circle
of radius ``r`` the area between a chord of angle ``δ`` and its arc is ``r²(δ - sin δ)/2 <
r² δ³ / 12``, so the relative area error of a ring made of chords is below ``δ_max² / 6``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from enum import Enum
from typing import Any

import numpy as np

from masonry_fdem.checks import check_magnitude, check_ratio
from masonry_fdem.geometry.blockmesh import BlockMesh
from masonry_fdem.geometry.layout import BlockLayout

__all__ = ["ArchKind", "arch_centre", "arch_circle", "arch_layout", "arch_curve",
           "arch_parameter", "build_arch", "pointed_offset", "ring_pieces"]

# parameters closer than this are the same vertex
_S_TOL = 1e-10


class ArchKind(Enum):
    """Shape of the intrados."""

    SEMICIRCULAR = "semicircular"
    SEGMENTAL = "segmental"
    POINTED = "pointed"


def _check_span_rise(kind: ArchKind, span: float, rise: float | None) -> None:
    if not (np.isfinite(span) and span > 0.0):
        raise ValueError(f"span must be positive, got {span}")
    half = 0.5 * span
    if kind is ArchKind.SEMICIRCULAR:
        if rise is not None and abs(rise - half) > 1e-12 * span:
            raise ValueError(f"a semicircular arch has rise span/2 = {half}, got {rise}; "
                             "use kind='segmental' or 'pointed'")
    elif rise is None or not (np.isfinite(rise) and rise > 0.0):
        raise ValueError(f"a {kind.value} arch needs a positive rise, got {rise}")
    elif kind is ArchKind.SEGMENTAL and rise >= half:
        raise ValueError(f"a segmental arch needs rise < span/2 = {half}, got {rise}")


def arch_circle(kind: ArchKind | str, span: float, rise: float | None = None
                ) -> tuple[float, float, float]:
    """Intrados circle of a semicircular or segmental arch.

    Args:
        kind: "semicircular" or "segmental" (a pointed arch has two centres: refused).
        span: clear span [m]; rise: intrados rise [m] (span/2 or None if semicircular).

    Returns:
        ``(radius, yc, alpha)``: intrados radius [m], height of the centre above the
        springing line [m] (≤ 0), half the opening angle [rad]; origin at mid-span.
    """
    kind = ArchKind(kind)
    if kind is ArchKind.POINTED:
        raise ValueError("a pointed arch has no single centre: this needs a circular "
                         "(semicircular or segmental) arch")
    _check_span_rise(kind, span, rise)
    half = 0.5 * span
    if kind is ArchKind.SEMICIRCULAR:
        return half, 0.0, 0.5 * math.pi
    radius = (half * half + rise * rise) / (2.0 * rise)
    return radius, rise - radius, math.asin(half / radius)


def arch_curve(
    kind: ArchKind | str, span: float, rise: float | None = None
) -> Callable[[np.ndarray, float], np.ndarray]:
    """The arch's curves as a function ``point(s, d)``.

    Args:
        kind: arch shape.
        span: clear span between the intrados springings [m].
        rise: intrados rise above the springing line [m]; required for segmental and
            pointed arches, must be ``span/2`` (or None) for a semicircular one.

    Returns:
        ``point(s, d)``: ``(len(s), 2)`` points [m] at positions ``s`` in ``[0, 1]`` on the
        curve at offset ``d`` [m] outward from the intrados, origin at mid-span on the
        springing line.
    """
    kind = ArchKind(kind)
    if kind is not ArchKind.POINTED:
        radius, yc, alpha = arch_circle(kind, span, rise)
        kind = ArchKind.SEGMENTAL
    else:
        _check_span_rise(kind, span, rise)
        half = 0.5 * span
    if kind is ArchKind.SEGMENTAL:

        def circular(s: np.ndarray, d: float) -> np.ndarray:
            theta = 0.5 * math.pi + alpha - 2.0 * alpha * np.asarray(s, dtype=np.float64)
            r = radius + d
            return np.column_stack([r * np.cos(theta), yc + r * np.sin(theta)])

        return circular

    if rise <= half:
        raise ValueError(f"a pointed arch needs rise > span/2 = {half}, got {rise}")
    c = pointed_offset(span, rise)

    def pointed(s: np.ndarray, d: float) -> np.ndarray:
        s = np.asarray(s, dtype=np.float64)
        r = half + c + d
        theta_crown = math.atan2(math.sqrt(r * r - c * c), -c)
        left = s <= 0.5
        u = np.where(left, s, 1.0 - s)  # position in the half, mirrored on the right
        theta = math.pi - 2.0 * u * (math.pi - theta_crown)
        px = c + r * np.cos(theta)
        py = r * np.sin(theta)
        px = np.where(u == 0.5, 0.0, px)  # the crown lies on the axis exactly
        return np.column_stack([np.where(left, px, -px), py])

    return pointed


def pointed_offset(span: float, rise: float) -> float:
    """Distance [m] of each centre of a pointed arch from the axis, on the springing line
    (the left half's centre is at +c, the right half's at −c)."""
    half = 0.5 * span
    return (rise * rise - half * half) / span


def arch_centre(kind: ArchKind | str, span: float, rise: float | None,
                x: float) -> np.ndarray:
    """Centre of curvature [m] of the intrados on the side of abscissa ``x`` [m]."""
    kind = ArchKind(kind)
    if kind is ArchKind.POINTED:
        c = pointed_offset(span, rise)
        return np.array([c if x < 0 else -c, 0.0])
    return np.array([0.0, arch_circle(kind, span, rise)[1]])


def arch_parameter(kind: ArchKind | str, span: float, rise: float | None,
                   p: np.ndarray) -> float:
    """Position s in [0, 1] along the arch of point ``p`` [m] (the inverse of
    :func:`arch_curve` at any offset from the intrados; origin at mid-span)."""
    kind = ArchKind(kind)
    x, y = float(p[0]), float(p[1])
    if kind is ArchKind.POINTED:
        c = pointed_offset(span, rise)
        xl = -abs(x)
        r = math.hypot(xl - c, y)
        theta = math.atan2(y, xl - c)
        crown = math.atan2(math.sqrt(max(r * r - c * c, 0.0)), -c)
        u = (math.pi - theta) / (2.0 * (math.pi - crown))
        return u if x <= 0.0 else 1.0 - u
    _, yc, alpha = arch_circle(kind, span, rise)
    theta = math.atan2(y - yc, x)
    return (0.5 * math.pi + alpha - theta) / (2.0 * alpha)


def ring_pieces(n: int, shift: float) -> list[tuple[float, float]]:
    """Parameter intervals (s0, s1) in [0, 1] of the ``n`` voussoirs of a ring whose radial
    joints are shifted by ``shift`` voussoirs (a staggered ring: one more piece)."""
    shift = shift % 1.0
    if shift < _S_TOL or shift > 1.0 - _S_TOL:
        joints = [j / n for j in range(1, n)]
    else:
        joints = [(j + shift) / n for j in range(n)]
    bounds = [0.0, *joints, 1.0]
    return list(zip(bounds[:-1], bounds[1:], strict=True))


def _piece_params(pieces, n: int, segments: int) -> np.ndarray:
    out = []
    for sa, sb in pieces:
        m = max(1, math.ceil(segments * (sb - sa) * n - 1e-9))
        out.append(np.linspace(sa, sb, m + 1))
    return np.concatenate(out)


def _merge(*params: np.ndarray) -> np.ndarray:
    v = np.sort(np.concatenate(params))
    keep = np.concatenate([[True], np.diff(v) > _S_TOL])
    return v[keep]


def arch_layout(
    *,
    span: float,
    ring_thickness: float,
    voussoirs: int | Sequence[int],
    kind: ArchKind | str = ArchKind.SEMICIRCULAR,
    rise: float | None = None,
    rings: int = 1,
    stagger: float = 0.5,
    segments: int = 1,
    abutment_height: float = 0.0,
    abutment_width: float | None = None,
    origin: Sequence[float] = (0.0, 0.0),
    material: str = "voussoir",
    abutment_material: str = "abutment",
) -> BlockLayout:
    """Voussoirs of a (multi-ring) arch and, optionally, its two abutment blocks.

    Args:
        span: clear span between the intrados springings [m].
        ring_thickness: radial thickness of each ring [m].
        voussoirs: voussoirs per ring (one value for all rings, or one per ring).
        kind: "semicircular", "segmental" or "pointed".
        rise: intrados rise [m] (segmental: < span/2; pointed: > span/2).
        rings: number of concentric rings.
        stagger: joint shift of ring ``k`` is ``stagger·k`` voussoir (0: aligned joints,
            0.5: joints over the middle of the voussoirs of the ring below).
        segments: straight segments per full voussoir along each curved face (1: chords).
        abutment_height: height [m] of an abutment block under each springing, from the
            springing line down; 0 for none.
        abutment_width: horizontal width [m] of each abutment, from the intrados springing
            outward; None: just wide enough for the springing joint.
        origin: mid-span point on the springing line [m].
        material: material of the voussoirs.
        abutment_material: material of the abutments.

    Returns:
        Blocks ``"voussoir:<ring>:<j>"`` (ring 0 innermost, ``j`` from the left springing),
        then ``"abutment:left"``, ``"abutment:right"`` if requested.
    """
    kind = ArchKind(kind)
    point = arch_curve(kind, span, rise)
    if not (np.isfinite(ring_thickness) and ring_thickness > 0.0):
        raise ValueError(f"ring_thickness must be positive, got {ring_thickness}")
    if rings < 1:
        raise ValueError(f"rings must be >= 1, got {rings}")
    counts = [int(voussoirs)] * rings if np.isscalar(voussoirs) else [int(v) for v in voussoirs]
    if len(counts) != rings or min(counts) < 1:
        raise ValueError(f"voussoirs must be >= 1, one value or one per ring ({rings})")
    if segments < 1:
        raise ValueError(f"segments must be >= 1, got {segments}")
    # magnitudes, after the hard checks (off inside masonry_fdem.checks.expert())
    check_magnitude("span", span, "span", "arch_layout")
    if rise is not None:
        check_magnitude("rise", rise, "rise", "arch_layout")
    check_magnitude("ring_thickness", ring_thickness, "ring_thickness", "arch_layout")
    check_ratio("ring_thickness", ring_thickness, span, 1e-3, 1.0, "m", "the span",
                "arch_layout")
    t = float(ring_thickness)
    pieces = [ring_pieces(counts[k], stagger * k) for k in range(rings)]
    params = [_piece_params(pieces[k], counts[k], segments) for k in range(rings)]
    crown = [np.array([0.5])] if kind is ArchKind.POINTED else []
    faces = [_merge(params[0], *crown)]
    faces += [_merge(params[k - 1], params[k], *crown) for k in range(1, rings)]
    faces.append(_merge(params[-1], *crown))

    polys, names = [], []
    for k in range(rings):
        inner, outer = faces[k], faces[k + 1]
        for j, (sa, sb) in enumerate(pieces[k]):
            si = inner[(inner > sa - _S_TOL) & (inner < sb + _S_TOL)]
            so = outer[(outer > sa - _S_TOL) & (outer < sb + _S_TOL)]
            polys.append(np.vstack([point(si, k * t), point(so[::-1], (k + 1) * t)]))
            names.append(f"voussoir:{k}:{j}")
    mats = [material] * len(polys)

    if abutment_height < 0.0:
        raise ValueError(f"abutment_height must be >= 0, got {abutment_height}")
    if abutment_height > 0.0:
        skew = np.vstack([point(np.zeros(1), i * t) for i in range(rings + 1)])
        x_in, x_out_joint = skew[0, 0], skew[-1, 0]
        x_out = x_out_joint if abutment_width is None else x_in - float(abutment_width)
        if x_out > x_out_joint + 1e-12 * span:
            raise ValueError(
                f"abutment_width {abutment_width} m is narrower than the springing joint "
                f"({x_in - x_out_joint:.6g} m)"
            )
        y_bot = skew[0, 1] - abutment_height
        left = [[x_out, y_bot], [x_in, y_bot], *skew.tolist()]
        if x_out < x_out_joint - 1e-12 * span:
            left.append([x_out, skew[-1, 1]])
        left = np.array(left)
        polys += [left, left * np.array([-1.0, 1.0])]
        names += ["abutment:left", "abutment:right"]
        mats += [abutment_material] * 2
    shift = np.asarray(origin, dtype=np.float64)
    return BlockLayout(tuple(p + shift for p in polys), tuple(mats), tuple(names))


def build_arch(*, mesh_size: float | None = None, comm: Any | None = None,
               **layout: Any) -> BlockMesh:
    """Mesh :func:`arch_layout` (same keyword arguments); see :func:`mesh_blocks`.
    A ``mesh_size`` [m] outside 1/100 to 2 ring thicknesses is refused as implausible
    (:func:`masonry_fdem.checks.expert` allows it)."""
    if mesh_size is not None and "ring_thickness" in layout:
        check_ratio("mesh_size", mesh_size, layout["ring_thickness"], 0.01, 2.0, "m",
                    "the ring thickness", "build_arch")
    return arch_layout(**layout).mesh(mesh_size, comm)
