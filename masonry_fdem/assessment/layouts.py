"""Anchor layouts for arches: radial anchors, stitches along the barrel and anchors
drilled from the intrados at an inclination (the repair options the assessment and the
layout search try). Lengths in metres, angles as stated per function."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from masonry_fdem.checks import check_positive
from masonry_fdem.geometry.arches import arch_circle
from masonry_fdem.interactions.anchors import Anchor

__all__ = ["radial_anchors", "intrados_stitch", "inclined_anchors"]


def radial_anchors(
    angles: Sequence[float],
    *,
    span: float,
    ring_thickness: float,
    rings: int = 1,
    kind: str = "semicircular",
    rise: float | None = None,
    origin: Sequence[float] = (0.0, 0.0),
    cover: float = 0.02,
    diameter: float,
    **kw,
) -> list[Anchor]:
    """Radial anchors through all rings of a circular arch, one per angle.

    Args:
        angles: polar angles [degrees] of the anchors about the intrados centre (90: the
            crown; 0/180: the springings of a semicircular arch).
        span, ring_thickness, rings, kind, rise, origin: the arch, as in
            :func:`~masonry_fdem.geometry.arch_layout`.
        cover: distance [m] from the intrados and from the extrados to the anchor ends.
        diameter: bar diameter [m]; other keywords go to :class:`Anchor`.

    Raises:
        ValueError: an angle outside the arch, or a cover leaving no anchor.
    """
    radius, yc, alpha = arch_circle(kind, span, rise)
    depth = rings * ring_thickness
    if not 0 <= cover < 0.5 * depth:
        raise ValueError(f"cover must be in [0, {0.5 * depth:g}) m, got {cover}")
    lo, hi = 90.0 - math.degrees(alpha), 90.0 + math.degrees(alpha)
    out = []
    o = np.asarray(origin, dtype=float)
    name = kw.pop("name", "radial")
    for k, ang in enumerate(angles):
        if not lo - 1e-9 <= ang <= hi + 1e-9:
            raise ValueError(f"anchor angle {ang} deg is outside the arch ({lo:g}..{hi:g} deg)")
        th = math.radians(ang)
        e = np.array([math.cos(th), math.sin(th)])
        c = o + np.array([0.0, yc])
        p0 = c + (radius + cover) * e
        p1 = c + (radius + depth - cover) * e
        out.append(Anchor(np.array([p0, p1]), diameter, name=f"{name}:{k}", **kw))
    return out


def intrados_stitch(
    start_angle: float,
    end_angle: float,
    *,
    span: float,
    depth: float,
    kind: str = "semicircular",
    rise: float | None = None,
    origin: Sequence[float] = (0.0, 0.0),
    pieces: int | None = None,
    diameter: float,
    **kw,
) -> Anchor:
    """A curved stitch following the intrados at ``depth`` [m] above it, from
    ``start_angle`` to ``end_angle`` (polar angles in degrees about the intrados centre,
    90 = crown). The arc is a polyline of ``pieces`` chords (default one per 5°)."""
    radius, yc, alpha = arch_circle(kind, span, rise)
    lo, hi = 90.0 - math.degrees(alpha), 90.0 + math.degrees(alpha)
    for ang in (start_angle, end_angle):
        if not lo - 1e-9 <= ang <= hi + 1e-9:
            raise ValueError(f"stitch angle {ang} deg is outside the arch ({lo:g}..{hi:g} deg)")
    if start_angle == end_angle:
        raise ValueError("a stitch needs start_angle != end_angle")
    check_positive("stitch depth", depth)
    if pieces is None:
        pieces = max(2, math.ceil(abs(end_angle - start_angle) / 5.0))
    th = np.radians(np.linspace(start_angle, end_angle, pieces + 1))
    r = radius + depth
    c = np.asarray(origin, dtype=float) + np.array([0.0, yc])
    pts = c + r * np.c_[np.cos(th), np.sin(th)]
    return Anchor(pts, diameter, name=kw.pop("name", "stitch"), **kw)


def inclined_anchors(
    positions: Sequence[float],
    *,
    inclination: float = 90.0,
    length: float | None = None,
    span: float,
    ring_thickness: float,
    rings: int = 1,
    kind: str = "semicircular",
    rise: float | None = None,
    origin: Sequence[float] = (0.0, 0.0),
    cover: float = 0.02,
    diameter: float,
    **kw,
) -> list[Anchor]:
    """Straight anchors drilled from the intrados of a circular arch, one per position.

    Each anchor starts ``cover`` [m] above the intrados at the arch position ``s``
    (0: left springing, 0.5: crown, 1: right springing; proportional to the angle) and
    runs at ``inclination`` [degrees] to the intrados tangent: 90 is radial, below 90 it
    leans towards the right springing (s increasing), above 90 towards the left. A
    shallow anchor crosses the ring interfaces and several radial joints (a stitch).

    Args:
        positions: s of the entry points, each in [0, 1].
        inclination: angle [deg] to the intrados tangent, in (0, 180).
        length: anchor length [m]; default: as far as ``cover`` below the extrados.
        span, ring_thickness, rings, kind, rise, origin: the arch, as in
            :func:`~masonry_fdem.geometry.arch_layout`.
        cover: distance [m] of the start from the intrados and of the end from the
            extrados.
        diameter: bar diameter [m]; other keywords go to :class:`Anchor`.

    Raises:
        ValueError: a position outside the arch, an inclination outside (0, 180), or an
            anchor that would leave the masonry through the extrados (the message gives
            the longest length that fits).
    """
    radius, yc, alpha = arch_circle(kind, span, rise)
    depth = rings * ring_thickness
    if not 0 <= cover < 0.5 * depth:
        raise ValueError(f"cover must be in [0, {0.5 * depth:g}) m, got {cover}")
    if not 0.0 < inclination < 180.0:
        raise ValueError(f"inclination must be in (0, 180) degrees, got {inclination}")
    if length is not None:
        check_positive("anchor length", length)
    c = np.asarray(origin, dtype=float) + np.array([0.0, yc])
    name = kw.pop("name", "inclined")
    r0, r1 = radius + cover, radius + depth - cover
    beta = math.radians(inclination)
    out = []
    for k, s in enumerate(positions):
        if not -1e-12 <= s <= 1.0 + 1e-12:
            raise ValueError(f"anchor position s = {s} is outside the arch (0..1)")
        th = 0.5 * math.pi + alpha - 2.0 * alpha * s
        e = np.array([math.cos(th), math.sin(th)])
        t = np.array([math.sin(th), -math.cos(th)])  # towards increasing s
        u = math.cos(beta) * t + math.sin(beta) * e
        # |r0 e + L u| = r1:  L^2 + 2 r0 sin(beta) L + r0^2 - r1^2 = 0
        b = r0 * math.sin(beta)
        fits = -b + math.sqrt(b * b + r1 * r1 - r0 * r0)
        ell = fits if length is None else float(length)
        if ell > fits * (1.0 + 1e-9):
            raise ValueError(
                f"anchor at s = {s:g}, {inclination:g} deg, {ell:g} m long leaves the "
                f"masonry through the extrados: at most {fits:.3f} m fits with "
                f"{cover:g} m cover")
        p0 = c + r0 * e
        out.append(Anchor(np.array([p0, p0 + ell * u]), diameter, name=f"{name}:{k}", **kw))
    return out
