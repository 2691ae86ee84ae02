"""Rigid-block limit analysis of masonry by linear programming (static, lower-bound form).

The blocks of a :class:`~masonry_fdem.geometry.BlockLayout` are rigid; the joints between
them carry no tension, have infinite compressive strength and Coulomb friction. The
largest multiplier ``λ`` of a live load that the structure can carry together with its
dead load is a linear programme (Livesley 1978; Gilbert & Melbourne 1994, the formulation
of LimitState:RING):

.. code-block:: text

    maximise   λ
    subject to B q + λ f_live = -f_dead        (equilibrium of every free block)
               N_k >= 0                          (no tension at each interface end)
               |S_k| <= μ N_k                    (Coulomb friction at each interface end)
               0 <= λ <= λ_max

Interfaces. :func:`find_interfaces` finds every straight segment shared by the outlines of
two blocks ``a < b`` (indices in the layout). Its unit tangent ``t`` runs along the edge of
``a`` (counter-clockwise around ``a``) from ``start`` to ``end``; its unit normal
``n = (t_y, -t_x)`` points out of ``a`` into ``b``. Each interface carries a normal force
``N_k`` and a shear force ``S_k`` at each of its two ends ``k = 1, 2``; block ``b`` receives
``N_k n + S_k t`` at end ``k`` and block ``a`` the opposite. ``N_k >= 0`` is compression. With
two non-negative end forces the resultant stays between the ends: a joint opens into a
hinge at one end instead of carrying tension.

Friction. ``μ`` may differ from interface to interface (e.g. mortar joints and the sand
between the rings of an arch). For finite ``μ`` the end force is written as
``f+ (n + μ t) + f- (n - μ t)`` with ``f+, f- >= 0`` (the two edges of the 2D friction
cone), so ``N = f+ + f-`` and ``S = μ (f+ - f-)``: the same constraints as above with no
inequality rows, which the simplex solves in far fewer iterations. ``μ = inf`` leaves
``S`` free.

Equilibrium. Unknowns are ``q = (N_1, S_1, N_2, S_2)`` per interface and ``λ``. Each block
that is not a support gives three rows, the force components ``F_x, F_y`` and the moment
``M`` (counter-clockwise positive) about its area centroid. Supports (abutments, bases) are
fixed and give no row. Self-weight ``ρ · area · width · g`` acts downward at the centroid.

Mechanism. The duals of the equilibrium rows are the virtual velocities ``(u, v, ω)`` of the
blocks' centroids in the collapse mechanism (the kinematic, upper-bound problem is the dual
of this one). They are scaled so that the fastest block vertex moves at speed 1 and the
live load does positive work. Interfaces across which the two blocks move relative to each
other are reported as hinges (relative rotation about one end), sliding (tangential
relative velocity) or separation (opening without rotation or slip).

Limitations. Friction is associative in the LP, so a sliding mechanism dilates; with
several joints near sliding the load factor can exceed that of a non-associative
(frictional, non-dilatant) analysis. Crushing is ignored (infinite compressive strength)
and joints have no cohesion or tensile strength. Interfaces are found only between
touching, non-overlapping outlines: the shared edges must be collinear within ``tol``.
When several mechanisms share the collapse load (degenerate duals, common in multi-ring
arches and walls) the one reported is the solver's basic solution, which may combine
them.

Infeasibility. If no ``λ >= 0`` is admissible, the dead load alone has no equilibrium
(if it had one, ``λ = 0`` would be admissible). Equilibrium is necessary whatever the flow
rule, so this holds for non-associative friction too: the structure as modelled cannot
stand as rigid blocks. The result then gives the proof, a mechanism in which the dead
load does positive work and no interface dissipates (a Farkas certificate of the LP, the
one with the least total velocity), and the factor on every friction coefficient with
which it would stand (bisection on feasibility, which grows with friction; a dozen small
LPs).

Everything runs in serial on each rank: under MPI every rank solves the same small LP.
"""

from __future__ import annotations

import fnmatch
import logging
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from enum import StrEnum
from typing import NamedTuple

import numpy as np
from scipy.optimize import linprog
from scipy.sparse import coo_matrix, csr_matrix, hstack, vstack
from scipy.spatial import cKDTree

from masonry_fdem.constants import G
from masonry_fdem.geometry.layout import BlockLayout
from masonry_fdem.geometry.polygons import polygon_area, polygon_centroid

__all__ = [
    "Hinge",
    "HingeKind",
    "Interfaces",
    "LimitResult",
    "LimitStatus",
    "find_interfaces",
    "limit_analysis",
]

log = logging.getLogger(__name__)

# Relative velocity (the fastest vertex moves at 1) under which two blocks move together.
_MOTION_TOL = 1e-6
# λ within this relative distance of λ_max counts as "no mechanism below the cap".
_CAP_TOL = 1e-9
# [s] for each HiGHS method but the last one tried (see _solve)
_LP_TIME_LIMIT = 30.0

Load = tuple[Sequence[float], Sequence[float]]
BoundedLoad = tuple[Sequence[float], Sequence[float], Sequence[float]]


class LimitStatus(StrEnum):
    """Outcome of :func:`limit_analysis`."""

    COLLAPSE = "collapse"  # a mechanism forms at λ < max_load_factor
    NO_MECHANISM = "no_mechanism"  # the structure carries max_load_factor times the live load
    INFEASIBLE = "infeasible"  # no λ >= 0 is admissible: the dead load alone collapses it


class HingeKind(StrEnum):
    """Relative motion of two blocks at an interface of the mechanism."""

    HINGE = "hinge"  # rotation about one end of the interface
    SLIDING = "sliding"  # tangential relative velocity (with dilatancy, see module doc)
    SEPARATION = "separation"  # the blocks move apart without rotating or sliding


class Interfaces(NamedTuple):
    """Straight contact segments between pairs of blocks (see the module doc for signs).

    Attributes:
        block_a: ``(n,)`` index of the first block (the lower index) in the layout.
        block_b: ``(n,)`` index of the second block.
        start: ``(n, 2)`` first end of each segment [m] (end 1).
        end: ``(n, 2)`` second end of each segment [m] (end 2).
    """

    block_a: np.ndarray
    block_b: np.ndarray
    start: np.ndarray
    end: np.ndarray

    @property
    def size(self) -> int:
        """Number of interfaces."""
        return int(self.block_a.shape[0])

    @property
    def length(self) -> np.ndarray:
        """``(n,)`` segment lengths [m]."""
        return np.linalg.norm(self.end - self.start, axis=1)

    @property
    def tangent(self) -> np.ndarray:
        """``(n, 2)`` unit tangents, from ``start`` to ``end``."""
        return (self.end - self.start) / self.length[:, None]

    @property
    def normal(self) -> np.ndarray:
        """``(n, 2)`` unit normals, out of block ``a`` into block ``b``."""
        t = self.tangent
        return np.column_stack([t[:, 1], -t[:, 0]])


@dataclass(frozen=True)
class Hinge:
    """An interface of the collapse mechanism.

    Attributes:
        interface: index into :attr:`LimitResult.interfaces`.
        blocks: names of the two blocks ``(a, b)``.
        position: ``(x, y)`` [m]: the end of the interface about which the blocks rotate
            (hinge), or its midpoint (sliding, separation).
        kind: relative motion.
        magnitude: relative angular velocity ``|ω_b - ω_a|`` [1/m] (hinge), or relative
            tangential (sliding) or normal (separation) velocity [-], on the scale where the
            fastest vertex of the mechanism moves at speed 1.
    """

    interface: int
    blocks: tuple[str, str]
    position: tuple[float, float]
    kind: HingeKind
    magnitude: float


@dataclass(frozen=True, eq=False)
class LimitResult:
    """Result of :func:`limit_analysis`.

    Attributes:
        load_factor: collapse load factor ``λ`` (multiplier of the live loads); ``λ_max``
            for ``no_mechanism``, NaN for ``infeasible``.
        status: "collapse", "no_mechanism" or "infeasible" (see :class:`LimitStatus`).
        interface_forces: ``(n_int, 4)`` forces ``(N_1, S_1, N_2, S_2)`` [N] at the two ends
            of each interface, in the equilibrium found at ``λ = load_factor`` (NaN if
            infeasible); ``N >= 0`` is compression, ``S`` acts on block ``b`` along the
            tangent.
        hinges: interfaces with relative motion in the mechanism (empty unless collapse).
        block_velocities: ``(n_blocks, 3)`` virtual velocities ``(u, v, ω)`` of the block
            centroids in the mechanism (``[-], [-], [1/m]``, fastest vertex at speed 1; zero
            for supports and for no_mechanism); for infeasible, those of
            ``dead_load_mechanism``.
        interfaces: the interfaces of the LP (those between two supports are left out).
        names: block names, in layout order.
        fixed: ``(n_blocks,)`` True for supports.
        dead_load_mechanism: infeasible only: the interfaces with relative motion in a
            mechanism in which the dead load does positive work while no interface
            dissipates (each end opens at least ``μ`` times as fast as it slides): the proof
            that the dead load has no equilibrium. Empty otherwise.
        friction_factor: infeasible only: the least factor on every interface's friction
            coefficient with which the dead load would have an equilibrium (to 0.1 %,
            rounded up); inf if none would (the blocks fail even with no sliding, e.g. an
            arch thinner than its minimum thickness). NaN otherwise.
        bounded_forces: the magnitude ``F`` [N] chosen for each of the ``bounded_loads``
            (empty if there are none or the LP is infeasible).
    """

    load_factor: float
    status: LimitStatus
    interface_forces: np.ndarray
    hinges: list[Hinge]
    block_velocities: np.ndarray
    interfaces: Interfaces
    names: tuple[str, ...]
    fixed: np.ndarray
    dead_load_mechanism: list[Hinge] = field(default_factory=list)
    friction_factor: float = float("nan")
    bounded_forces: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @property
    def explanation(self) -> str:
        """The outcome in one or two plain sentences (for reports and logs)."""
        if self.status == LimitStatus.NO_MECHANISM:
            return (f"no mechanism up to the load factor cap {self.load_factor:.6g}: the "
                    "rigid blocks carry it")
        if self.status == LimitStatus.COLLAPSE:
            return (f"collapse at the load factor {self.load_factor:.6g} by "
                    f"{_motion_text(self.hinges)}")
        text = ("no equilibrium even without the live load: the rigid blocks, with no "
                "tension, no bond and the friction given, cannot carry their own dead load")
        moving = int(np.count_nonzero(np.abs(self.block_velocities).max(axis=1) > _MOTION_TOL))
        if self.dead_load_mechanism:
            text += (f"; they collapse under it by {_motion_text(self.dead_load_mechanism)} "
                     f"({moving} of {int((~self.fixed).sum())} blocks move)")
        if np.isinf(self.friction_factor):
            text += ("; no friction coefficient would help: they fail even with no sliding "
                     "anywhere")
        elif np.isfinite(self.friction_factor):
            text += (f"; they would stand with every friction coefficient "
                     f"{self.friction_factor:.3g} times larger")
        return text

    @property
    def thrust_points(self) -> np.ndarray:
        """``(n_int, 2)`` point of each interface where its resultant acts [m].

        The points of the line of thrust; NaN where an interface carries no normal force.
        """
        n1, n2 = self.interface_forces[:, 0], self.interface_forces[:, 2]
        total = n1 + n2
        with np.errstate(invalid="ignore", divide="ignore"):
            w = np.where(total > 0.0, n2 / total, np.nan)
        return self.interfaces.start + w[:, None] * (self.interfaces.end - self.interfaces.start)


def _layout_size(layout: BlockLayout) -> float:
    b = layout.bounds
    return float(max(b[2] - b[0], b[3] - b[1]))


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def find_interfaces(layout: BlockLayout, tol: float = 1e-9) -> Interfaces:
    """Straight segments shared by the outlines of two blocks.

    Two edges of different blocks touch if both ends of one lie within ``tol`` of the
    other's line, they run in opposite directions (the blocks lie on opposite sides) and
    their projections overlap by more than ``tol``; the overlap is the interface. Collinear
    overlaps of the same two blocks that touch end to end are merged into one interface.

    Args:
        layout: the blocks.
        tol: distance tolerance relative to the layout size (largest side of its bounding
            box).

    Returns:
        The interfaces, sorted by ``(block_a, block_b)`` and position along the edge.
    """
    if not (np.isfinite(tol) and tol >= 0.0):
        raise ValueError(f"tol must be >= 0, got {tol}")
    eps = tol * _layout_size(layout)
    p = np.vstack(layout.polygons)
    q = np.vstack([np.roll(poly, -1, axis=0) for poly in layout.polygons])
    owner = np.repeat(np.arange(len(layout)), [len(poly) for poly in layout.polygons])
    d = q - p
    lengths = np.linalg.norm(d, axis=1)
    # two overlapping edges have their midpoints closer than the longer edge's length, so
    # searching around each edge as far as its own length finds every pair at least once
    mid = 0.5 * (p + q)
    near = cKDTree(mid).query_ball_point(mid, r=lengths + 2.0 * eps)
    i = np.repeat(np.arange(len(near)), [len(h) for h in near])
    j = np.concatenate(near).astype(np.int64)
    pairs = np.unique(np.column_stack([np.minimum(i, j), np.maximum(i, j)]), axis=0)
    empty = Interfaces(np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros((0, 2)),
                       np.zeros((0, 2)))
    i, j = pairs[:, 0], pairs[:, 1]
    # edge i belongs to the block with the lower index
    swap = owner[i] > owner[j]
    i, j = np.where(swap, j, i), np.where(swap, i, j)
    keep = owner[i] != owner[j]
    i, j = i[keep], j[keep]
    u = d[i] / lengths[i, None]
    off_a = _cross(u, p[j] - p[i])
    off_b = _cross(u, q[j] - p[i])
    opposite = np.einsum("ij,ij->i", u, d[j]) < 0.0
    ta = np.einsum("ij,ij->i", u, p[j] - p[i])
    tb = np.einsum("ij,ij->i", u, q[j] - p[i])
    lo = np.maximum(0.0, np.minimum(ta, tb))
    hi = np.minimum(lengths[i], np.maximum(ta, tb))
    ok = (np.abs(off_a) <= eps) & (np.abs(off_b) <= eps) & opposite & (hi - lo > eps)
    i, j, u, lo, hi = i[ok], j[ok], u[ok], lo[ok], hi[ok]
    start = p[i] + lo[:, None] * u
    end = p[i] + hi[:, None] * u
    blocks_a, blocks_b = owner[i], owner[j]

    merged: list[tuple[int, int, np.ndarray, np.ndarray]] = []
    order = np.lexsort((start[:, 1], start[:, 0], blocks_b, blocks_a))
    groups: dict[tuple[int, int], list[list[np.ndarray]]] = {}
    for k in order:
        groups.setdefault((int(blocks_a[k]), int(blocks_b[k])), []).append(
            [start[k].copy(), end[k].copy()]
        )
    for (a, b), segs in groups.items():
        changed = True
        while changed:  # join collinear segments that meet end to end
            changed = False
            for m in range(len(segs)):
                for k in range(len(segs)):
                    if m == k or np.linalg.norm(segs[m][1] - segs[k][0]) > eps:
                        continue
                    tm = segs[m][1] - segs[m][0]
                    tk = segs[k][1] - segs[k][0]
                    if abs(_cross(tm, tk)) > eps * (np.linalg.norm(tm) + np.linalg.norm(tk)):
                        continue
                    segs[m][1] = segs[k][1]
                    del segs[k]
                    changed = True
                    break
                if changed:
                    break
        merged += [(a, b, s0, s1) for s0, s1 in segs]
    if not merged:
        return empty
    return Interfaces(
        np.array([m[0] for m in merged], dtype=np.int64),
        np.array([m[1] for m in merged], dtype=np.int64),
        np.ascontiguousarray([m[2] for m in merged], dtype=np.float64),
        np.ascontiguousarray([m[3] for m in merged], dtype=np.float64),
    )


def _contains(poly: np.ndarray, x: np.ndarray, eps: float) -> bool:
    """Whether point ``x`` lies in polygon ``poly`` or within ``eps`` of its outline."""
    if np.any(x < poly.min(axis=0) - eps) or np.any(x > poly.max(axis=0) + eps):
        return False
    a, b = poly, np.roll(poly, -1, axis=0)
    d = b - a
    s = np.clip(np.einsum("ij,ij->i", x - a, d) / np.einsum("ij,ij->i", d, d), 0.0, 1.0)
    if np.min(np.linalg.norm(x - a - s[:, None] * d, axis=1)) <= eps:
        return True
    up = (a[:, 1] > x[1]) != (b[:, 1] > x[1])
    with np.errstate(divide="ignore", invalid="ignore"):
        xc = a[:, 0] + (x[1] - a[:, 1]) * d[:, 0] / d[:, 1]
    return bool(np.count_nonzero(up & (x[0] < xc)) % 2)


def _loaded_block(layout: BlockLayout, point: np.ndarray, force: np.ndarray,
                  eps: float) -> int:
    """The block a point load acts on (see :func:`limit_analysis`)."""
    hits = [b for b, poly in enumerate(layout.polygons) if _contains(poly, point, eps)]
    if not hits:
        raise ValueError(f"load point {tuple(point.tolist())} lies in no block")
    if len(hits) > 1:  # on a shared edge: the block the force pushes into
        f = np.linalg.norm(force)
        if f > 0.0:
            ahead = point + 1e3 * eps * force / f
            into = [b for b in hits if _contains(layout.polygons[b], ahead, 0.0)]
            hits = into or hits
    return min(hits, key=lambda b: layout.names[b])


def _parse_loads(loads: Sequence[Load], what: str) -> list[tuple[np.ndarray, np.ndarray]]:
    out = []
    for item in loads:
        try:
            x, f = item
            x = np.asarray(x, dtype=np.float64).reshape(2)
            f = np.asarray(f, dtype=np.float64).reshape(2)
        except (TypeError, ValueError) as err:
            raise ValueError(f"each of {what} must be ((x, y), (Fx, Fy)), got {item!r}") from err
        if not (np.all(np.isfinite(x)) and np.all(np.isfinite(f))):
            raise ValueError(f"{what}: non-finite point or force {item!r}")
        out.append((x, f))
    return out


def _parse_bounded(loads: Sequence[BoundedLoad]) -> list[tuple[np.ndarray, np.ndarray,
                                                                tuple[float, float]]]:
    out = []
    for item in loads:
        try:
            x, d, (lo, hi) = item
            x = np.asarray(x, dtype=np.float64).reshape(2)
            d = np.asarray(d, dtype=np.float64).reshape(2)
            lo, hi = float(lo), float(hi)
        except (TypeError, ValueError) as err:
            raise ValueError("each of bounded_loads must be ((x, y), (dx, dy), (F_min, F_max)),"
                             f" got {item!r}") from err
        norm = float(np.hypot(*d))
        if not (np.all(np.isfinite(x)) and np.isfinite(norm) and norm > 0.0):
            raise ValueError(f"bounded_loads: a finite point and a non-zero direction are "
                             f"needed, got {item!r}")
        if not (np.isfinite(lo) and np.isfinite(hi) and 0.0 <= lo <= hi):
            raise ValueError(f"bounded_loads: the bounds must satisfy 0 <= F_min <= F_max < inf,"
                             f" got {item!r}")
        out.append((x, d / norm, (lo, hi)))
    return out


def _block_densities(layout: BlockLayout, density: float | Mapping[str, float]) -> np.ndarray:
    if isinstance(density, Mapping):
        missing = sorted(set(layout.materials) - set(density))
        if missing:
            raise ValueError(f"no density given for materials {missing}")
        rho = np.array([float(density[m]) for m in layout.materials])
    else:
        rho = np.full(len(layout), float(density))
    if not np.all(np.isfinite(rho)) or np.any(rho < 0.0):
        raise ValueError(f"densities must be finite and >= 0, got {np.unique(rho).tolist()}")
    return rho


def _fixed_blocks(layout: BlockLayout, supports: str | Sequence[str]) -> np.ndarray:
    patterns = [supports] if isinstance(supports, str) else list(supports)
    if not patterns:
        raise ValueError("at least one support pattern is needed (e.g. 'abutment:*')")
    fixed = np.zeros(len(layout), dtype=bool)
    for pat in patterns:
        hit = np.array([fnmatch.fnmatchcase(n, pat) for n in layout.names])
        if not hit.any():
            raise ValueError(f"support pattern {pat!r} matches no block")
        fixed |= hit
    if fixed.all():
        raise ValueError("every block is a support: nothing can move")
    return fixed


def _interface_friction(friction: float | Callable[[str, str, np.ndarray], float],
                        itf: Interfaces, names: Sequence[str]) -> np.ndarray:
    """``(n_int,)`` friction coefficient of each interface (see :func:`limit_analysis`)."""
    if callable(friction):
        mid = 0.5 * (itf.start + itf.end)
        mu = np.array([float(friction(names[a], names[b], mid[i]))
                       for i, (a, b) in enumerate(zip(itf.block_a, itf.block_b, strict=True))])
    else:
        mu = np.full(itf.size, float(friction))
    bad = ~(mu >= 0.0)  # also NaN; inf is allowed
    if bad.any():
        k = int(np.flatnonzero(bad)[0])
        raise ValueError(f"friction must be >= 0, got {mu[k]} at the interface of "
                         f"{names[itf.block_a[k]]!r} and {names[itf.block_b[k]]!r}")
    return mu


def _add_point_load(rows: np.ndarray, slot: np.ndarray, centroids: np.ndarray, block: int,
                    x: np.ndarray, f: np.ndarray) -> None:
    """Add force ``f`` at ``x`` to the (F_x, F_y, M) rows of ``block`` (if it is free)."""
    r = slot[block]
    if r < 0:
        return
    arm = x - centroids[block]
    rows[3 * r: 3 * r + 3] += [f[0], f[1], arm[0] * f[1] - arm[1] * f[0]]


def limit_analysis(
    layout: BlockLayout,
    *,
    density: float | Mapping[str, float],
    width: float,
    supports: str | Sequence[str],
    live_loads: Sequence[Load] = (),
    dead_loads: Sequence[Load] = (),
    live_acceleration: Sequence[float] | None = None,
    bounded_loads: Sequence[BoundedLoad] = (),
    friction: float | Callable[[str, str, np.ndarray], float] = 0.6,
    g: float = G,
    max_load_factor: float = 1e6,
    tol: float = 1e-9,
) -> LimitResult:
    """Collapse load factor of a rigid-block structure by linear programming.

    Maximises ``λ`` such that the dead loads plus ``λ`` times the live loads are in
    equilibrium with no-tension, frictional interface forces (see the module doc).

    A point load acts on the block whose outline contains its point (points on the outline
    count). A point on the edge shared by two blocks loads the block the force pushes into;
    if that is still ambiguous, the block whose name sorts first. Loads on supports are
    carried by the ground and have no effect.

    Args:
        layout: the blocks.
        density: density [kg/m^3], one value or one per material name.
        width: out-of-plane thickness of all blocks [m].
        supports: shell pattern(s) (``fnmatch``) of the names of fixed blocks, e.g.
            ``"abutment:*"`` or ``["base", "pier:*"]``; each must match a block.
        live_loads: ``((x, y), (F_x, F_y))`` point loads [m], [N] multiplied by ``λ``.
        dead_loads: extra point loads of the same form, carried at their full value.
        live_acceleration: ``(a_x, a_y)`` [m/s^2]: adds the body force ``mass · a`` of every
            free block, at its centroid, to the live load (e.g. ``(g, 0)`` makes ``λ`` the
            horizontal acceleration at collapse in units of g, as on a tilting table).
        bounded_loads: ``((x, y), (d_x, d_y), (F_min, F_max))``: a force ``F d`` at the
            point whose magnitude the LP chooses within ``F_min <= F <= F_max`` [N] (``d``
            is normalised): a resistance that is mobilised only as far as needed, such as
            the passive pressure of a fill on an arch that sways into it (RING's way; see
            :func:`~masonry_fdem.geometry.fill.fill_passive`). In the mechanism (the dual)
            each one dissipates ``F_max`` times the speed against ``d`` and does the work
            ``F_min`` times the speed along it.
        friction: Coulomb coefficient ``μ`` of every interface, ``>= 0`` (``inf``: no
            sliding); or a function ``friction(name_a, name_b, midpoint)`` of the names of
            the two blocks of an interface (``a`` first in the layout) and its midpoint
            ``(x, y)`` [m] returning its ``μ``: joints of different materials (e.g. the sand
            between the rings of a multi-ring arch).
        g: gravitational acceleration [m/s^2], acting in ``-y``.
        max_load_factor: upper bound on ``λ``; reaching it gives status "no_mechanism".
        tol: geometric tolerance relative to the layout size (interfaces, load points).

    Returns:
        The load factor, status, interface forces and the mechanism; for "infeasible" the
        mechanism by which the dead load alone collapses and the factor on the friction
        that would let it stand (see :class:`LimitResult`, ``explanation``).

    Raises:
        ValueError: bad parameters, a support pattern matching no block, a load point in no
            block, no interfaces, or a free block touching no other block.
        RuntimeError: HiGHS finds neither a solution nor infeasibility (by the dual
            simplex, then by the interior-point method).
    """
    if not (np.isfinite(width) and width > 0.0):
        raise ValueError(f"width must be positive, got {width}")
    if not (np.isfinite(g) and g >= 0.0):
        raise ValueError(f"g must be >= 0, got {g}")
    if not callable(friction) and not (friction >= 0.0):  # also rejects NaN; inf is allowed
        raise ValueError(f"friction must be >= 0, got {friction}")
    if not (np.isfinite(max_load_factor) and max_load_factor > 0.0):
        raise ValueError(f"max_load_factor must be positive, got {max_load_factor}")
    t0 = time.perf_counter()
    nb = len(layout)
    rho = _block_densities(layout, density)
    fixed = _fixed_blocks(layout, supports)
    live = _parse_loads(live_loads, "live_loads")
    dead = _parse_loads(dead_loads, "dead_loads")
    bounded = _parse_bounded(bounded_loads)
    acc = None
    if live_acceleration is not None:
        acc = np.asarray(live_acceleration, dtype=np.float64).reshape(2)
        if not np.all(np.isfinite(acc)):
            raise ValueError(f"live_acceleration must be finite, got {live_acceleration}")

    size = _layout_size(layout)
    eps = tol * size
    found = find_interfaces(layout, tol)
    if found.size == 0:
        raise ValueError("no interfaces: no two blocks share an edge")
    used = ~(fixed[found.block_a] & fixed[found.block_b])
    itf = Interfaces(*(np.ascontiguousarray(arr[used]) for arr in found))
    if itf.size == 0:
        raise ValueError("no interfaces: only supports touch each other")
    touched = np.zeros(nb, dtype=bool)
    touched[itf.block_a] = touched[itf.block_b] = True
    lonely = [layout.names[b] for b in np.flatnonzero(~fixed & ~touched)]
    if lonely:
        raise ValueError(f"blocks touching no other block: {lonely[:5]}")

    free = np.flatnonzero(~fixed)
    slot = np.full(nb, -1, dtype=np.int64)
    slot[free] = np.arange(free.size)
    centroids = np.array([polygon_centroid(poly) for poly in layout.polygons])
    mass = rho * np.array([polygon_area(poly) for poly in layout.polygons]) * width

    # load vectors: (F_x, F_y, M about the centroid) per free block
    f_dead = np.zeros(3 * free.size)
    f_live = np.zeros(3 * free.size)
    f_dead[1::3] = -mass[free] * g
    if acc is not None:
        f_live[0::3] += mass[free] * acc[0]
        f_live[1::3] += mass[free] * acc[1]
    for x, f in dead:
        _add_point_load(f_dead, slot, centroids, _loaded_block(layout, x, f, eps), x, f)
    for x, f in live:
        _add_point_load(f_live, slot, centroids, _loaded_block(layout, x, f, eps), x, f)
    if not np.any(f_live):
        log.info("the live load is zero: only feasibility of the dead load is tested")

    # scaling: lengths by the layout size, forces by the largest dead/live load component
    scale_dead = float(np.abs(f_dead).max()) or 1.0
    scale_live = float(np.abs(f_live).max()) or 1.0
    moment_rows = np.tile([1.0, 1.0, 1.0 / size], free.size)
    b_eq = -f_dead * moment_rows / scale_dead
    live_col = f_live * moment_rows / scale_live

    # equilibrium matrix (see _equilibrium_matrix) and the λ column
    n_int = itf.size
    mu = _interface_friction(friction, itf, layout.names)
    n_rows = 3 * free.size
    a_dead, col_bounds = _equilibrium_matrix(itf, mu, slot, centroids, size, n_rows)
    # bounded loads: one column each, in units of scale_dead like the interface forces
    b_cols = np.zeros((3 * free.size, len(bounded)))
    b_bounds = []
    for j, (x, d, (lo, hi)) in enumerate(bounded):
        col = np.zeros(3 * free.size)
        _add_point_load(col, slot, centroids, _loaded_block(layout, x, d, eps), x, d)
        b_cols[:, j] = col * moment_rows
        b_bounds.append((lo / scale_dead, hi / scale_dead))
    col_bounds = col_bounds + b_bounds
    a_dead = hstack([a_dead, csr_matrix(b_cols)], format="csr")
    a_eq = hstack([a_dead, coo_matrix(live_col[:, None])], format="csr")
    n_var = 4 * n_int + len(bounded) + 1

    lam_cap = max_load_factor * scale_live / scale_dead
    bounds = col_bounds + [(0.0, lam_cap)]
    c = np.zeros(n_var)
    c[-1] = -1.0
    res = _solve(c, A_eq=a_eq, b_eq=b_eq, bounds=bounds)
    log.debug("limit analysis: %d free blocks, %d interfaces, LP %s in %.3g s", free.size,
              n_int, res.status, time.perf_counter() - t0)

    names = layout.names
    velocities = np.zeros((nb, 3))
    if res.status == 2:
        # the dead load alone has no equilibrium (if it had one, λ = 0 would be
        # admissible): the mechanism that proves it, and how much more friction would let
        # the structure stand
        y = _dead_load_mechanism(a_dead, b_eq, col_bounds)
        mechanism: list[Hinge] = []
        if y is None:
            log.warning("limit analysis: the LP is infeasible but no collapse mechanism of "
                        "the dead load was found (numerical trouble?)")
        else:
            velocities[free] = y.reshape(free.size, 3) * [1.0, 1.0, 1.0 / size]
            velocities /= _fastest_vertex(layout, centroids, velocities, free) or 1.0
            mechanism = _mechanism(itf, centroids, velocities, names)
        factor = _friction_factor(itf, mu, slot, centroids, size, n_rows, b_eq,
                                  extra=(csr_matrix(b_cols), b_bounds))
        log.debug("limit analysis: infeasible; %d interfaces move in the dead-load mechanism,"
                  " friction factor needed %.4g (%.3g s)", len(mechanism), factor,
                  time.perf_counter() - t0)
        return LimitResult(float("nan"), LimitStatus.INFEASIBLE, np.full((n_int, 4), np.nan),
                           [], velocities, itf, names, fixed, dead_load_mechanism=mechanism,
                           friction_factor=factor)
    if res.status != 0:
        from masonry_fdem.checks import NumericalError

        raise NumericalError(
            f"the limit analysis failed: HiGHS found no verdict on its linear program "
            f"(status {res.status}: {res.message}); likely cause: a badly scaled problem "
            "(a span in millimetres, a density or load far off, blocks of very different "
            "sizes) or a structure without supports")

    lam = float(res.x[-1]) * scale_dead / scale_live
    bounded_forces = res.x[4 * n_int:-1] * scale_dead
    x = res.x[:4 * n_int].reshape(n_int, 2, 2) * scale_dead  # (interface, end, column)
    # finite μ: (f+, f-) -> (N, S) = (f+ + f-, μ (f+ - f-)); μ = inf: the columns are (N, S)
    finite = np.isfinite(mu)
    cone = np.stack([x[..., 0] + x[..., 1],
                     np.where(finite, mu, 0.0)[:, None] * (x[..., 0] - x[..., 1])], axis=-1)
    x = np.where(finite[:, None, None], cone, x)
    forces = x.reshape(n_int, 4)
    if res.x[-1] >= lam_cap * (1.0 - _CAP_TOL):
        return LimitResult(max_load_factor, LimitStatus.NO_MECHANISM, forces, [], velocities,
                           itf, names, fixed, bounded_forces=bounded_forces)

    y = np.asarray(res.eqlin.marginals, dtype=np.float64).reshape(free.size, 3)
    velocities[free] = y * [1.0, 1.0, 1.0 / size]
    if np.dot(live_col, y.ravel()) < 0.0:  # live loads do positive work
        velocities = -velocities
    speed = _fastest_vertex(layout, centroids, velocities, free)
    if speed > 0.0:
        velocities /= speed
    hinges = _mechanism(itf, centroids, velocities, names)
    return LimitResult(lam, LimitStatus.COLLAPSE, forces, hinges, velocities, itf, names, fixed,
                       bounded_forces=bounded_forces)


def _equilibrium_matrix(itf: Interfaces, mu: np.ndarray, slot: np.ndarray,
                        centroids: np.ndarray, size: float,
                        n_rows: int) -> tuple[csr_matrix, list[tuple[float | None, None]]]:
    """The equilibrium rows of the interface forces and the bounds of their columns.

    Columns ``4 i + 2 k + j``: interface ``i``, end ``k``. With finite friction each end
    force is a non-negative combination ``f+ (n + μ t) + f- (n - μ t)`` of the two edges of
    its friction cone, so ``N = f+ + f-``, ``S = μ (f+ - f-)`` and the LP has no inequality
    rows (far fewer simplex iterations); with ``μ = inf`` the columns are ``N n`` (``N >=
    0``) and ``S t`` (``S`` free). Rows: ``(F_x, F_y, M / size)`` of each free block.
    """
    n_int = itf.size
    finite = np.isfinite(mu)
    mu_t = np.where(finite, mu, 0.0)[:, None] * itf.tangent
    generators = (itf.normal + mu_t, np.where(finite[:, None], itf.normal - mu_t, itf.tangent))
    rows, cols, vals = [], [], []
    for k, ends in enumerate((itf.start, itf.end)):
        for sign, blocks in ((1.0, itf.block_b), (-1.0, itf.block_a)):
            r = slot[blocks]
            on = r >= 0
            arm = (ends - centroids[blocks]) / size
            for j, direction in enumerate(generators):
                col = 4 * np.arange(n_int) + 2 * k + j
                comp = (direction[:, 0], direction[:, 1], _cross(arm, direction))
                for c in range(3):
                    rows.append(3 * r[on] + c)
                    cols.append(col[on])
                    vals.append(sign * comp[c][on])
    a = coo_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                   shape=(n_rows, 4 * n_int)).tocsr()
    bounds = [b for f in finite for b in [(0.0, None), (0.0, None) if f else (None, None)] * 2]
    return a, bounds


def _solve(c: np.ndarray, methods: Sequence[str] = ("highs", "highs-ipm"), **lp: object):
    """``linprog`` by the HiGHS methods in turn until one reaches a verdict (optimal or
    infeasible). Near the friction at which a structure just stands (multi-ring arches) the
    dual simplex may end with "model status unknown" (status 4) or cycle, so every method
    but the last has the time limit :data:`_LP_TIME_LIMIT`; the interior-point method
    decides those LPs in milliseconds."""
    res = None
    for k, method in enumerate(methods):
        options = {"time_limit": _LP_TIME_LIMIT} if k < len(methods) - 1 else {}
        res = linprog(c, method=method, options=options, **lp)
        if res.status in (0, 2):
            break
        log.debug("limit analysis: HiGHS (%s): %s", method, res.message)
    return res


def _dead_load_mechanism(a: csr_matrix, b: np.ndarray, bounds: list) -> np.ndarray | None:
    """The velocities ``y`` (scaled as the rows of ``a``) of a mechanism in which the dead
    load does positive work and no interface dissipates: a Farkas certificate that
    ``a x = b`` has no solution within ``bounds``.

    ``a_j · y >= 0`` for each column with ``x_j >= 0`` and ``a_j · y = 0`` for each free
    column say that every interface end opens at least ``μ`` times as fast as it slides
    (associative friction: no dissipation), and ``b · y <= -1`` that the dead load does
    positive work (``b`` is minus the dead load). Of these, the one with the least
    ``Σ |y|`` (few moving blocks). None if there is none (the LP is feasible after all).
    """
    m = a.shape[0]
    at = a.T.tocsr()
    nonneg = np.array([lo is not None for lo, _ in bounds])
    signed = hstack([at, -at], format="csr")  # y = y+ - y-, y+, y- >= 0
    a_ub = vstack([-signed[np.flatnonzero(nonneg)], csr_matrix(np.r_[b, -b][None, :])],
                  format="csr")
    b_ub = np.r_[np.zeros(int(nonneg.sum())), -1.0]
    free_cols = np.flatnonzero(~nonneg)
    a_eq = signed[free_cols] if free_cols.size else None
    b_eq = np.zeros(free_cols.size) if free_cols.size else None
    res = _solve(np.ones(2 * m), A_ub=a_ub, b_ub=b_ub, A_eq=a_eq, b_eq=b_eq,
                 bounds=(0.0, None))
    if res.status != 0:
        return None
    return res.x[:m] - res.x[m:]


def _friction_factor(itf: Interfaces, mu: np.ndarray, slot: np.ndarray,
                     centroids: np.ndarray, size: float, n_rows: int, b: np.ndarray,
                     rtol: float = 1e-3,
                     extra: tuple[csr_matrix, list] | None = None) -> float:
    """The least factor on every interface's friction coefficient with which the dead load
    has an equilibrium (to ``rtol``, rounded up); inf if none has (not even with no
    sliding anywhere). Equilibrium exists for every larger factor: the friction cones
    grow with it. The factor returned is one at which an equilibrium was found: an LP
    that no method decides counts as infeasible. ``extra``: more columns (the bounded
    loads) and their bounds, unchanged by the factor."""

    def stands(factor: float) -> bool:
        scaled = np.where(mu > 0.0, mu * factor, 0.0)
        a, bounds = _equilibrium_matrix(itf, scaled, slot, centroids, size, n_rows)
        if extra is not None and extra[0].shape[1]:
            a, bounds = hstack([a, extra[0]], format="csr"), bounds + list(extra[1])
        # close to the critical factor the LPs are nearly degenerate: interior point first
        res = _solve(np.zeros(a.shape[1]), ("highs-ipm", "highs"), A_eq=a, b_eq=b,
                     bounds=bounds)
        return res.status == 0

    if not np.any(mu[np.isfinite(mu)] > 0.0) or not stands(np.inf):
        return float("inf")
    lo, hi = 1.0, 2.0
    while not stands(hi):
        lo, hi = hi, 2.0 * hi
        if hi > 1e6:  # only at μ = inf: practically no friction suffices
            return float("inf")
    while hi > lo * (1.0 + rtol):
        mid = np.sqrt(lo * hi)
        lo, hi = (lo, mid) if stands(mid) else (mid, hi)
    return float(hi)


def _fastest_vertex(layout: BlockLayout, centroids: np.ndarray, velocities: np.ndarray,
                    free: np.ndarray) -> float:
    return max(float(np.linalg.norm(_vertex_velocities(layout, centroids, velocities, b),
                                    axis=1).max()) for b in free)


def _point_velocity(centroids: np.ndarray, velocities: np.ndarray, blocks: np.ndarray,
                    x: np.ndarray) -> np.ndarray:
    """``(n, 2)`` velocity of the points ``x`` moving with ``blocks``."""
    arm = x - centroids[blocks]
    v = velocities[blocks]
    return np.column_stack([v[:, 0] - v[:, 2] * arm[:, 1], v[:, 1] + v[:, 2] * arm[:, 0]])


def _vertex_velocities(layout: BlockLayout, centroids: np.ndarray, velocities: np.ndarray,
                       b: int) -> np.ndarray:
    poly = layout.polygons[b]
    return _point_velocity(centroids, velocities, np.full(len(poly), b), poly)


def _mechanism(itf: Interfaces, centroids: np.ndarray, velocities: np.ndarray,
               names: tuple[str, ...]) -> list[Hinge]:
    """Classify the relative motion of the blocks at every interface."""
    rel = [
        _point_velocity(centroids, velocities, itf.block_b, x)
        - _point_velocity(centroids, velocities, itf.block_a, x)
        for x in (itf.start, itf.end)
    ]
    normal, tangent = itf.normal, itf.tangent
    gap = np.column_stack([np.einsum("ij,ij->i", w, normal) for w in rel])
    slip = np.column_stack([np.einsum("ij,ij->i", w, tangent) for w in rel])
    spin = velocities[itf.block_b, 2] - velocities[itf.block_a, 2]
    mid = 0.5 * (itf.start + itf.end)
    length = itf.length
    hinges = []
    for i in range(itf.size):
        a, b = int(itf.block_a[i]), int(itf.block_b[i])
        if np.abs(slip[i]).max() > _MOTION_TOL:
            kind, where, size = HingeKind.SLIDING, mid[i], float(np.abs(slip[i]).mean())
        elif abs(spin[i]) * length[i] > _MOTION_TOL:
            end = int(np.argmin(gap[i]))
            kind, where, size = HingeKind.HINGE, (itf.start, itf.end)[end][i], abs(spin[i])
        elif np.abs(gap[i]).max() > _MOTION_TOL:
            kind, where, size = HingeKind.SEPARATION, mid[i], float(np.abs(gap[i]).mean())
        else:
            continue
        hinges.append(Hinge(i, (names[a], names[b]), (float(where[0]), float(where[1])),
                            kind, float(size)))
    return hinges


def _motion_text(hinges: Sequence[Hinge]) -> str:
    """E.g. "a mechanism with 4 hinges, 2 sliding interfaces"."""
    count = {kind: sum(h.kind == kind for h in hinges) for kind in HingeKind}
    words = {HingeKind.HINGE: ("hinge", "hinges"),
             HingeKind.SLIDING: ("sliding interface", "sliding interfaces"),
             HingeKind.SEPARATION: ("separating interface", "separating interfaces")}
    parts = [f"{n} {words[k][n != 1]}" for k, n in count.items() if n]
    return "a mechanism with " + (", ".join(parts) if parts else "no relative motion")
