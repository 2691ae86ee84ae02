"""Masonry arch bridges in a plane: one or more arch spans on piers and end abutments,
the fill over them up to the road with an optional surfacing layer, retaining end walls,
and an optional soil region under the piers and abutments.

Coordinates [m]: x along the road, the left springing of the first span's intrados at
``x = 0``; y up, the springing line of every span at ``y = 0``. The piers and abutments
stand on the foundation level ``y = −pier_height``; with ``soil_depth > 0`` a soil block
lies under it, wider than the bridge by ``soil_margin`` on each side.

Blocks (names): the voussoirs of span ``k`` are ``voussoir:<ring>:<j>@<k>`` (ring 0
innermost, ``j`` from the span's left springing); ``abutment:left``, ``abutment:right``;
``pier:<i>`` between spans ``i`` and ``i + 1``; ``fill``; ``surfacing`` (if any);
``wall:left``, ``wall:right`` (the fill's end walls, on the abutments' outer faces, from
the foundation level to the road, or to the surfacing, which runs over them); ``soil`` (if
any); ``spandrel:<k>`` (if any, below); ``backing:<i>`` (if any: the haunches' backing,
masonry on the piers and abutments against the ring's lower extrados up to ``backing``
above the springing line, under the fill; left to right).

Spandrel walls (``spandrel_thickness`` t > 0): the two masonry walls on the bridge's faces
that hold the fill between them, standing on the outer ring's extrados and the piers and
abutments, up to the road (or the surfacing). They lie out of this plane, beside the fill:
in the plane model they have the fill's outline, overlapping the fill and never touching
it, cut by vertical head joints into blocks ``spandrel:<k>`` (left to right) about
``spandrel_block`` long, so that the walls crack where their mortar gives (no bed joints
within a wall: the blocks are full height). The model
(:func:`~masonry_fdem.assessment.bridge.bridge_model`) is of the whole bridge width B:
the walls take the share 2t/B of it (their masonry's stiffness, weight and strengths
times that share), the fill the rest, 1 − 2t/B, and the interaction of the two (the
fill's outward push on the walls, their friction along the walls' inner faces) is left
out. A strip of the barrel away from the faces has no spandrel
walls: leave ``spandrel_thickness`` at 0 for it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from masonry_fdem.geometry.arches import ArchKind, arch_layout
from masonry_fdem.geometry.fill import _dedupe_points, crown_height, fill_layout
from masonry_fdem.geometry.layout import BlockLayout
from masonry_fdem.geometry.polygons import polygon_area

__all__ = ["Bridge", "BridgeError", "Span"]


class BridgeError(ValueError):
    """Bad bridge input; the message names the part."""


def _positive(value: float, what: str, zero: bool = False) -> float:
    v = float(value)
    if not np.isfinite(v) or v < 0.0 or (v == 0.0 and not zero):
        raise BridgeError(f"{what} must be {'>= 0' if zero else '> 0'} m, got {value}")
    return v


@dataclass(frozen=True)
class Span:
    """One arch span: clear ``span`` and intrados ``rise`` [m], ``rings`` of
    ``ring_thickness`` [m], ``voussoirs`` per ring, ``kind`` as
    :func:`~masonry_fdem.geometry.arch_layout` (semicircular, segmental, pointed)."""

    span: float
    rise: float
    ring_thickness: float
    voussoirs: int
    kind: str = "segmental"
    rings: int = 1

    def layout(self, k: int, x_left: float, material: str) -> BlockLayout:
        """The span's voussoirs, named with ``@k``, the left intrados springing at
        ``(x_left, 0)``."""
        try:
            arch = arch_layout(kind=ArchKind(self.kind), span=self.span, rise=self.rise,
                               rings=self.rings, ring_thickness=self.ring_thickness,
                               voussoirs=self.voussoirs, origin=(x_left + 0.5 * self.span, 0.0),
                               material=material)
        except ValueError as e:
            raise BridgeError(f"span {k}: {e}") from e
        return BlockLayout(arch.polygons, arch.materials, tuple(f"{n}@{k}" for n in arch.names))

    def skewback(self, k: int, side: str) -> np.ndarray:
        """``(rings + 1, 2)`` points of the springing joint on ``side`` ("left"/"right")
        relative to the span's own left intrados springing, intrados first."""
        try:
            arch = arch_layout(kind=ArchKind(self.kind), span=self.span, rise=self.rise,
                               rings=self.rings, ring_thickness=self.ring_thickness,
                               voussoirs=self.voussoirs, abutment_height=1.0,
                               origin=(0.5 * self.span, 0.0))
        except ValueError as e:
            raise BridgeError(f"span {k}: {e}") from e
        left = arch.polygons[arch.names.index("abutment:left")][2:2 + self.rings + 1]
        return left if side == "left" else left * np.array([-1.0, 1.0]) + [self.span, 0.0]


@dataclass(frozen=True)
class Bridge:
    """A plane masonry arch bridge (see the module doc for the layout and the names).

    Args:
        spans: the arch spans, left to right.
        piers: width [m] of each pier (one fewer than the spans), between the intrados
            springings of the two spans it carries.
        pier_height: height [m] of the piers and abutments from the foundation to the
            springing line.
        abutment_width: width [m] of each end abutment, from the intrados springing
            outward.
        cover: fill and surfacing over the highest crown's extrados [m].
        surfacing: thickness [m] of the surfacing on top of the fill (0: none); part of
            ``cover``.
        soil_depth: depth [m] of the soil under the foundation level (0: the piers and
            abutments stand on rigid ground).
        soil_margin: soil beyond each end wall [m] (default: ``soil_depth``).
        soil_extent: ``(x_min, x_max)`` [m] of the soil instead; the piers and abutments
            (and the end walls) off it stand on rigid ground, none may straddle its edge.
        wall_thickness: thickness [m] of the fill's end walls.
        width: barrel width [m] (out of plane).
        spandrel_thickness: thickness [m] of each of the two spandrel walls (0: none; see
            the module doc); the two together must be narrower than ``width``.
        spandrel_block: length [m] of the spandrel walls' blocks (about: the deck is cut
            into equal lengths).
        backing: height [m] of the haunches' backing above the springing line (0: none);
            below every span's crown.
        materials: material name per part: "masonry" (voussoirs), "pier" (piers and
            abutments), "wall", "fill", "surfacing", "soil", "spandrel" (the spandrel
            walls; default: the piers' material) and "backing" (default: the piers').
    """

    spans: tuple[Span, ...]
    piers: tuple[float, ...] = ()
    pier_height: float = 1.0
    abutment_width: float = 1.0
    cover: float = 0.4
    surfacing: float = 0.0
    soil_depth: float = 0.0
    soil_margin: float | None = None
    soil_extent: tuple[float, float] | None = None
    wall_thickness: float = 0.3
    width: float = 1.0
    spandrel_thickness: float = 0.0
    spandrel_block: float = 0.5
    backing: float = 0.0
    materials: dict = field(default_factory=lambda: dict(
        masonry="masonry", pier="pier", wall="pier", fill="fill", surfacing="surfacing",
        soil="soil"))

    def __post_init__(self) -> None:
        object.__setattr__(self, "spans", tuple(self.spans))
        object.__setattr__(self, "piers", tuple(float(w) for w in self.piers))
        if not self.spans:
            raise BridgeError("a bridge needs at least one span: the fill would lie above "
                              "no arch")
        for k, s in enumerate(self.spans):
            if not isinstance(s, Span):
                raise BridgeError(f"span {k}: a Span is needed, got {s!r}")
        if len(self.piers) != len(self.spans) - 1:
            raise BridgeError(f"{len(self.spans)} spans need {len(self.spans) - 1} pier "
                              f"width(s), got {len(self.piers)}")
        for i, w in enumerate(self.piers):
            _positive(w, f"pier {i} width")
        _positive(self.pier_height, "pier_height")
        _positive(self.cover, "cover")
        _positive(self.surfacing, "surfacing", zero=True)
        if self.surfacing >= self.cover:
            raise BridgeError(f"the surfacing ({self.surfacing} m) must be thinner than the "
                              f"cover ({self.cover} m): there would be no fill under it")
        _positive(self.soil_depth, "soil_depth", zero=True)
        _positive(self.wall_thickness, "wall_thickness")
        _positive(self.width, "width")
        _positive(self.spandrel_thickness, "spandrel_thickness", zero=True)
        _positive(self.spandrel_block, "spandrel_block")
        _positive(self.backing, "backing", zero=True)
        for k, s in enumerate(self.spans):
            if self.backing >= s.rise + s.rings * s.ring_thickness:
                raise BridgeError(f"the backing ({self.backing:g} m above the springings) "
                                  f"reaches span {k}'s crown")
        if 2.0 * self.spandrel_thickness >= self.width:
            raise BridgeError(f"the two spandrel walls (2 × {self.spandrel_thickness:g} m) are "
                              f"as wide as the bridge (width {self.width:g} m) or wider: "
                              "there would be no fill between them")
        missing = {"masonry", "pier", "wall", "fill", "surfacing", "soil"} - set(self.materials)
        if missing:
            raise BridgeError(f"materials: no name for {sorted(missing)}")
        # the springing joints of neighbouring spans must fit on their pier
        xs = self.springings()
        for i, w in enumerate(self.piers):
            right = self.spans[i].skewback(i, "right")
            left = self.spans[i + 1].skewback(i + 1, "left")
            need = (right[:, 0].max() - self.spans[i].span) + (-left[:, 0].min())
            if w < need - 1e-9:
                raise BridgeError(
                    f"spans {i} and {i + 1} overlap above pier {i}: its width {w:g} m is "
                    f"less than their two springing joints need ({need:.4g} m)")
        margin = self.wall_thickness + (self.soil_depth if self.soil_margin is None
                                        else _positive(self.soil_margin, "soil_margin", True))
        if self.soil_extent is not None and self.soil_depth > 0.0:
            lo, hi = (float(v) for v in self.soil_extent)
            if not hi > lo:
                raise BridgeError(f"soil_extent must be (x_min, x_max) with x_max > x_min, "
                                  f"got {self.soil_extent}")
            object.__setattr__(self, "soil_extent", (lo, hi))
            bases = self.foundations()
            x0, x1 = self.deck()
            bases["wall:left"] = (x0 - self.wall_thickness, x0)
            bases["wall:right"] = (x1, x1 + self.wall_thickness)
            for name, (a, b) in bases.items():
                inside = lo - 1e-9 <= a and b <= hi + 1e-9
                outside = b <= lo + 1e-9 or a >= hi - 1e-9
                if not (inside or outside):
                    raise BridgeError(f"{name} stands partly off the foundation soil: its base "
                                      f"spans x = {a:g} to {b:g} m, the soil {lo:g} to {hi:g} m"
                                      " (a base stands wholly on the soil or wholly on rigid "
                                      "ground)")
            if not any(self.on_soil(n) for n in self.foundations()):
                raise BridgeError(f"no pier or abutment stands on the soil ({lo:g} to {hi:g} m)")
        elif self.soil_depth > 0.0:
            x0, x1 = xs[0][0] - self.abutment_width, xs[-1][1] + self.abutment_width
            object.__setattr__(self, "soil_extent", (x0 - margin, x1 + margin))
        road = self.road_level()
        for name, poly in self._supports():
            if poly[:, 1].max() >= road - self.surfacing - 1e-9:
                raise BridgeError(f"{name} reaches the road: the cover {self.cover} m over "
                                  "the highest crown leaves no fill over it")

    @property
    def spandrel_share(self) -> float:
        """The spandrel walls' share 2t/B of the bridge width (0: none)."""
        return 2.0 * float(self.spandrel_thickness) / float(self.width)

    @property
    def spandrel_material(self) -> str:
        """The material name of the spandrel walls (default: the piers')."""
        return self.materials.get("spandrel", self.materials["pier"])

    @property
    def backing_material(self) -> str:
        """The material name of the backing (default: the piers')."""
        return self.materials.get("backing", self.materials["pier"])

    @staticmethod
    def part_of(block: str) -> str | None:
        """The part ("masonry", "pier", "wall", "fill", "surfacing", "soil", "spandrel") a
        block of :meth:`layout` belongs to, by its name (None: not a bridge part; the
        backing is meshed as the piers, "pier"). By name,
        not by material: parts may share a material (the stone of the ring and the
        piers) and still have their own mesh sizes."""
        head = block.split(":", 1)[0]
        return {"voussoir": "masonry", "pier": "pier", "abutment": "pier", "wall": "wall",
                "fill": "fill", "surfacing": "surfacing", "soil": "soil",
                "spandrel": "spandrel", "backing": "pier"}.get(head)

    # ------------------------------------------------------------------ geometry
    def springings(self) -> list[tuple[float, float]]:
        """``(x_left, x_right)`` [m] of each span's intrados springings."""
        out, x = [], 0.0
        for k, s in enumerate(self.spans):
            _positive(s.span, f"span {k} span")
            out.append((x, x + s.span))
            x += s.span + (self.piers[k] if k < len(self.piers) else 0.0)
        return out

    def foundations(self) -> dict[str, tuple[float, float]]:
        """Base ``(x_min, x_max)`` [m] of each pier and abutment."""
        xs = self.springings()
        out = {"abutment:left": (xs[0][0] - self.abutment_width, xs[0][0])}
        for i in range(len(self.piers)):
            out[f"pier:{i}"] = (xs[i][1], xs[i + 1][0])
        out["abutment:right"] = (xs[-1][1], xs[-1][1] + self.abutment_width)
        return out

    def on_soil(self, name: str) -> bool:
        """Whether the pier or abutment ``name`` stands on the soil (else on rigid
        ground)."""
        if self.soil_depth <= 0.0 or self.soil_extent is None:
            return False
        a, b = self.foundations()[name]
        lo, hi = self.soil_extent
        return lo - 1e-9 <= a and b <= hi + 1e-9

    @property
    def foundation_level(self) -> float:
        """y [m] of the bases of the piers and abutments."""
        return -float(self.pier_height)

    def _supports(self) -> list[tuple[str, np.ndarray]]:
        """The abutments and piers as polygons (counter-clockwise)."""
        xs = self.springings()
        yb = self.foundation_level
        out = []
        sk = self.spans[0].skewback(0, "left") + [xs[0][0], 0.0]
        x_out = xs[0][0] - self.abutment_width
        if x_out > sk[:, 0].min() + 1e-9:
            raise BridgeError(f"abutment_width {self.abutment_width} m is narrower than span "
                              "0's springing joint")
        out.append(("abutment:left", np.array([[x_out, yb], [xs[0][0], yb], *sk.tolist(),
                                               [x_out, sk[-1, 1]]])))
        for i in range(len(self.piers)):
            a, b = xs[i][1], xs[i + 1][0]
            right = self.spans[i].skewback(i, "right") + [xs[i][0], 0.0]  # span i, a side
            left = self.spans[i + 1].skewback(i + 1, "left") + [b, 0.0]
            # the top runs straight from one extrados springing to the other
            pts = [[a, yb], [b, yb], *left.tolist(), *right[::-1].tolist()]
            out.append((f"pier:{i}", _dedupe_points(np.array(pts), 1e-12)))
        sk = self.spans[-1].skewback(len(self.spans) - 1, "right") + [xs[-1][0], 0.0]
        x_out = xs[-1][1] + self.abutment_width
        if x_out < sk[:, 0].max() - 1e-9:
            raise BridgeError(f"abutment_width {self.abutment_width} m is narrower than the "
                              "last span's springing joint")
        out.append(("abutment:right", np.array([[xs[-1][1], yb], [x_out, yb], [x_out, sk[-1, 1]],
                                                *sk[::-1].tolist()])))
        return out

    def structure(self) -> BlockLayout:
        """The arch rings, piers and abutments."""
        m = self.materials
        parts = [s.layout(k, x0, m["masonry"])
                 for k, (s, (x0, _)) in enumerate(zip(self.spans, self.springings(), strict=True))]
        polys, mats, names = [], [], []
        for p in parts:
            polys += list(p.polygons)
            mats += list(p.materials)
            names += list(p.names)
        for name, poly in self._supports():
            polys.append(poly)
            mats.append(m["pier"])
            names.append(name)
        return BlockLayout(tuple(polys), tuple(mats), tuple(names))

    def crown_height(self) -> float:
        """y [m] of the highest crown's extrados."""
        return crown_height(self.structure())

    def road_level(self) -> float:
        """y [m] of the road."""
        return self.crown_height() + self.cover

    def deck(self) -> tuple[float, float]:
        """``(x_min, x_max)`` [m] of the road between the end walls."""
        f = self.foundations()
        return f["abutment:left"][0], f["abutment:right"][1]

    def check_on_deck(self, x: float, half_width: float, what: str = "the load") -> None:
        """A load patch of half width ``half_width`` centred at ``x`` [m] must lie on the
        road between the end walls."""
        lo, hi = self.deck()
        if not (np.isfinite(x) and lo <= x - half_width and x + half_width <= hi):
            raise BridgeError(f"{what} at x = {x:g} m (patch ±{half_width:g} m) is off the "
                              f"deck, which runs from x = {lo:g} to {hi:g} m")

    def layout(self, road_points: Sequence[float] = ()) -> BlockLayout:
        """Every block of the bridge; ``road_points``: x [m] that get a vertex on the road
        (where loading beams bear)."""
        st = self.structure()
        m = self.materials
        for x in road_points:
            self.check_on_deck(float(x), 0.0, "a road point")
        road = self.road_level()
        s = self.surfacing
        fl = fill_layout(st, cover=self.cover - s, wall_thickness=self.wall_thickness,
                         road_points=() if s > 0 else road_points, material=m["fill"],
                         wall_material=m["wall"], backing=self.backing,
                         backing_material=self.backing_material)
        fill = fl.polygons[fl.names.index("fill")]
        polys, mats, names = [fill], [m["fill"]], ["fill"]
        for p, mat, n in zip(fl.polygons, fl.materials, fl.names, strict=True):
            if n.startswith("backing:"):
                polys.append(p)
                mats.append(mat)
                names.append(n)
        if self.spandrel_thickness > 0.0:
            # beside the fill, out of the plane: the same outline, cut into blocks
            x0, x1 = self.deck()
            n = max(1, math.ceil((x1 - x0) / self.spandrel_block - 1e-9))
            cuts = np.linspace(x0, x1, n + 1)
            for k in range(n):
                piece = _dedupe_points(_slab(fill, cuts[k], cuts[k + 1]), 1e-12)
                polys.append(piece)
                mats.append(self.spandrel_material)
                names.append(f"spandrel:{k}")
        x0, x1 = self.deck()
        t = self.wall_thickness
        if s > 0.0:
            # the surfacing runs over the fill and the tops of the end walls
            top = sorted({float(x) for x in road_points if x0 < x < x1}, reverse=True)
            surf = np.vstack([[(x0 - t, road - s), (x0, road - s), (x1, road - s),
                               (x1 + t, road - s), (x1 + t, road)],
                              np.array([(x, road) for x in top]).reshape(-1, 2),
                              [(x0 - t, road)]])
            polys.append(surf)
            mats.append(m["surfacing"])
            names.append("surfacing")
        yb = self.foundation_level
        yw = road - s
        polys += [np.array([(x0 - t, yb), (x0, yb), (x0, yw), (x0 - t, yw)]),
                  np.array([(x1, yb), (x1 + t, yb), (x1 + t, yw), (x1, yw)])]
        mats += [m["wall"]] * 2
        names += ["wall:left", "wall:right"]
        if self.soil_depth > 0.0:
            lo, hi = self.soil_extent
            yd = yb - self.soil_depth
            # vertices at the corners of every base on the soil, so the meshes meet
            xs = sorted({v for a, b in self.foundations().values() for v in (a, b)}
                        | {x0 - t, x1 + t} | {lo, hi})
            xs = [x for x in xs if lo <= x <= hi]
            soil = np.vstack([[(lo, yd), (hi, yd)], [(x, yb) for x in xs[::-1]]])
            polys.append(_dedupe_points(soil, 1e-12))
            mats.append(m["soil"])
            names.append("soil")
        out = st + BlockLayout(tuple(polys), tuple(mats), tuple(names))
        for p, n in zip(out.polygons, out.names, strict=True):
            if polygon_area(p) <= 0.0:
                raise BridgeError(f"block {n} has no area (or is clockwise)")
        return out


def _slab(poly: np.ndarray, xa: float, xb: float) -> np.ndarray:
    """The part of the polygon between x = xa and x = xb (Sutherland–Hodgman against the
    two half planes; one piece for an outline whose vertical sections are intervals, as
    the fill's are)."""
    out = np.asarray(poly, dtype=float)
    for keep in (lambda p: p[0] - xa, lambda p: xb - p[0]):
        pts = []
        for i in range(len(out)):
            p, q = out[i - 1], out[i]
            dp, dq = keep(p), keep(q)
            if dq >= 0.0:
                if dp < 0.0:
                    pts.append(p + dp / (dp - dq) * (q - p))
                pts.append(q)
            elif dp >= 0.0:
                pts.append(p + dp / (dp - dq) * (q - p))
        out = np.array(pts)
    return out

