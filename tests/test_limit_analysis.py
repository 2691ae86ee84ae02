"""Rigid-block limit analysis (masonry_fdem.solvers.limit_analysis) against hand-derived values.

Every case is a small linear programme solved identically on every rank, so the file runs
unchanged under ``mpirun -n 2 python -m pytest``. Timing on the development machine: each
LP of the arch cases (26-42 blocks) takes ~0.01-0.02 s, a 103-block two-ring arch with 203
interfaces ~0.1 s (setup included).
"""

import math

import numpy as np
import pytest

from masonry_fdem.geometry import BlockLayout, arch_layout, rectangle
from masonry_fdem.geometry.polygons import polygon_area, polygon_centroid
from masonry_fdem.solvers.limit_analysis import (
    HingeKind,
    LimitStatus,
    find_interfaces,
    limit_analysis,
)

G = 9.81
RHO = 2000.0


def _block_on_base(b: float = 0.5, h: float = 1.0) -> BlockLayout:
    """A b x h block standing on the middle of a wider fixed base, bottom-left at (0, 0)."""
    return BlockLayout(
        (rectangle(-1.0, -0.5, b + 1.0, 0.0), rectangle(0.0, 0.0, b, h)),
        ("stone", "stone"),
        ("base", "block"),
    )


def test_single_block_overturning():
    """Block b x h, width w, weight W = ρ b h w g, horizontal P = 1 N (+x) at its top-left
    corner (0, h), friction μ = 10 or μ = inf (no sliding).

    Rotation about the bottom-right corner (b, 0): P λ h = W b / 2, so λ = W b / (2 h).
    With b = 0.5, h = 1, w = 0.3, ρ = 2000, g = 9.81: W = 2943 N, λ = 735.75.

    The same block under a horizontal body force λ·m·g (``live_acceleration=(g, 0)``):
    λ m g h / 2 = m g b / 2, so λ = b / h = 0.5 (the tilting-table value).
    """
    b, h, w = 0.5, 1.0, 0.3
    weight = RHO * b * h * w * G
    res = limit_analysis(_block_on_base(b, h), density=RHO, width=w, g=G, supports="base",
                         live_loads=[((0.0, h), (1.0, 0.0))], friction=10.0)
    assert res.status == LimitStatus.COLLAPSE
    assert res.load_factor == pytest.approx(weight * b / (2.0 * h), rel=1e-6)  # 735.75
    # statics: the whole weight acts at the pivot corner (b, 0), end 1 of the interface
    np.testing.assert_allclose(res.thrust_points[0], [b, 0.0], atol=1e-9)
    assert len(res.hinges) == 1
    hinge = res.hinges[0]
    assert hinge.kind == HingeKind.HINGE
    np.testing.assert_allclose(hinge.position, [b, 0.0], atol=1e-12)
    # mechanism: clockwise rotation about (b, 0); the top-left corner is the fastest vertex
    u, v, ω = res.block_velocities[1]
    assert ω < 0.0
    # centroid velocity ω ẑ × (c - pivot) with c - pivot = (-b/2, h/2)
    np.testing.assert_allclose([u, v], [-ω * h / 2, -ω * b / 2], atol=1e-9)
    assert abs(ω) * math.hypot(b, h) == pytest.approx(1.0, rel=1e-9)

    frictionless_limit = limit_analysis(
        _block_on_base(b, h), density=RHO, width=w, g=G, supports="base",
        live_loads=[((0.0, h), (1.0, 0.0))], friction=math.inf)
    assert frictionless_limit.load_factor == pytest.approx(weight * b / (2.0 * h), rel=1e-6)

    tilt = limit_analysis(_block_on_base(b, h), density=RHO, width=w, g=G, supports="base",
                          live_acceleration=(G, 0.0), friction=10.0)
    assert tilt.load_factor == pytest.approx(b / h, rel=1e-6)


def test_single_block_sliding():
    """The block of the overturning test with μ = 0.2 < b / (2 h) = 0.25: sliding governs.

    Horizontal equilibrium P λ = Σ S ≤ μ Σ N = μ W, so λ = μ W = 0.2 · 2943 = 588.6.
    """
    b, h, w, μ = 0.5, 1.0, 0.3, 0.2
    weight = RHO * b * h * w * G
    res = limit_analysis(_block_on_base(b, h), density=RHO, width=w, g=G, supports="base",
                         live_loads=[((0.0, h), (1.0, 0.0))], friction=μ)
    assert res.status == LimitStatus.COLLAPSE
    assert res.load_factor == pytest.approx(μ * weight, rel=1e-6)  # 588.6
    assert [hg.kind for hg in res.hinges] == [HingeKind.SLIDING]
    # an assessment draws and counts the rotations only (the sliding one in words)
    from masonry_fdem.assessment.assess import limit_rotation_hinges

    assert limit_rotation_hinges(res) == [] and "1 sliding interface" in res.explanation
    # associative friction: the block slides to +x and dilates by μ per unit slip
    u, v, ω = res.block_velocities[1]
    assert u > 0.0 and v == pytest.approx(μ * u, rel=1e-9) and abs(ω) < 1e-12


def test_bounded_load_resists_up_to_its_cap():
    """The block of the sliding test held on its far face by a force the LP may choose in
    [F_min, F_max] (a passive resistance): sliding needs P = μ W + F_max when the force
    resists it, and P = μ W − F_min when it pushes along (the LP takes the least it may).

    μ W = 588.6 N; overturning would need W b / (2 h) + F h_F / h ≥ 735.8 N, more."""
    b, h, w, μ = 0.5, 1.0, 0.3, 0.2
    weight = RHO * b * h * w * G
    common = dict(density=RHO, width=w, g=G, supports="base", friction=μ,
                  live_loads=[((0.0, h), (1.0, 0.0))])
    resist = limit_analysis(_block_on_base(b, h), bounded_loads=[
        ((b, 0.5 * h), (-2.0, 0.0), (0.0, 100.0))], **common)
    assert resist.status == LimitStatus.COLLAPSE
    assert resist.load_factor == pytest.approx(μ * weight + 100.0, rel=1e-6)  # 688.6
    assert resist.bounded_forces == pytest.approx([100.0], rel=1e-6)
    along = limit_analysis(_block_on_base(b, h), bounded_loads=[
        ((b, 0.5 * h), (1.0, 0.0), (50.0, 100.0))], **common)
    assert along.load_factor == pytest.approx(μ * weight - 50.0, rel=1e-6)  # 538.6
    assert along.bounded_forces == pytest.approx([50.0], rel=1e-6)
    for bad, match in [(((b, 0.5), (0.0, 0.0), (0.0, 1.0)), "non-zero direction"),
                       (((b, 0.5), (1.0, 0.0), (2.0, 1.0)), "F_min <= F_max"),
                       (((b, 0.5), (1.0, 0.0), (0.0, math.inf)), "F_min <= F_max"),
                       (((b, 0.5), (1.0, 0.0)), "bounded_loads must be")]:
        with pytest.raises(ValueError, match=match):
            limit_analysis(_block_on_base(b, h), bounded_loads=[bad], **common)


def _portal() -> BlockLayout:
    return BlockLayout(
        (
            rectangle(-0.2, -0.3, 2.0, 0.0),
            rectangle(0.0, 0.0, 0.4, 1.2),
            rectangle(1.4, 0.0, 1.8, 1.2),
            rectangle(0.0, 1.2, 1.8, 1.5),
        ),
        ("stone",) * 4,
        ("base", "pier:left", "pier:right", "lintel"),
    )


def test_portal_sway():
    """Portal: piers b x h = 0.4 x 1.2 at x in [0, 0.4] and [1.4, 1.8], lintel 1.8 x 0.3 on
    top, on a fixed base; width 0.5, P = 1 N (+x) at the lintel's top-left corner, μ = 1.5.

    Sway mechanism (upper bound): both piers rotate clockwise by θ about their bottom-right
    corners, hinges at their top-left corners, so the lintel translates by (θ h, θ b).
    Virtual work: λ θ h = 2 W_p θ b / 2 + W_l θ b, i.e. λ = b (W_p + W_l) / h, where
    W_p = ρ·0.4·1.2·0.5·g = 4708.8 N and W_l = ρ·1.8·0.3·0.5·g = 5297.4 N: λ = 3335.4.

    Statics (lower bound) at that λ, lintel resting on the piers' top-left corners:
    lintel moments about (0, 1.2): V_r = (0.3 λ + 0.9 W_l) / 1.4 = 4120.2 N, V_l = W_l - V_r
    = 1177.2 N >= 0; pier moments about their pivots: H = b (V + W_p / 2) / h gives
    H_l = 1177.2 N, H_r = 2158.2 N (sum λ); friction ratios <= 1.0 < μ. Both bounds agree,
    so λ is exact, and the LP must find exactly these interface forces.
    """
    b, h = 0.4, 1.2
    w_p = RHO * 0.4 * 1.2 * 0.5 * G
    w_l = RHO * 1.8 * 0.3 * 0.5 * G
    res = limit_analysis(_portal(), density=RHO, width=0.5, g=G, supports="base",
                         live_loads=[((0.0, 1.5), (1.0, 0.0))], friction=1.5)
    assert res.status == LimitStatus.COLLAPSE
    λ = b * (w_p + w_l) / h
    assert res.load_factor == pytest.approx(λ, rel=1e-6)  # 3335.4
    v_r = (0.3 * λ + 0.9 * w_l) / 1.4
    v_l = w_l - v_r
    h_l, h_r = b * (v_l + w_p / 2) / h, b * (v_r + w_p / 2) / h
    # (N_1 + N_2, S_1 + S_2) per interface; each tangent runs along -x (the top edge of the
    # lower block, counter-clockwise), so S = H resists the push of the load to +x
    itf = res.interfaces
    by_pair = {(res.names[a], res.names[b_]): k
               for k, (a, b_) in enumerate(zip(itf.block_a, itf.block_b, strict=True))}
    for pier, v_top, h_top in (("pier:left", v_l, h_l), ("pier:right", v_r, h_r)):
        top = by_pair[(pier, "lintel")]
        np.testing.assert_allclose(res.interface_forces[top].reshape(2, 2).sum(axis=0),
                                   [v_top, h_top], rtol=1e-6)
        base = by_pair[("base", pier)]
        np.testing.assert_allclose(res.interface_forces[base].reshape(2, 2).sum(axis=0),
                                   [v_top + w_p, h_top], rtol=1e-6)
    hinge_points = sorted(hg.position for hg in res.hinges)
    np.testing.assert_allclose(hinge_points, [(0.0, 1.2), (0.4, 0.0), (1.4, 1.2), (1.8, 0.0)],
                               atol=1e-9)
    assert all(hg.kind == HingeKind.HINGE for hg in res.hinges)


def _semicircle(ratio: float, voussoirs: int = 40) -> BlockLayout:
    """Semicircular arch, span 2 m, with t / R = ratio, R = 1 + t / 2 (centre line)."""
    t = ratio / (1.0 - 0.5 * ratio)
    return arch_layout(span=2.0, ring_thickness=t, voussoirs=voussoirs, abutment_height=0.5)


def _stands(ratio: float) -> bool:
    res = limit_analysis(_semicircle(ratio), density=RHO, width=1.0, g=G,
                         supports="abutment:*", friction=10.0)
    assert res.status in (LimitStatus.NO_MECHANISM, LimitStatus.INFEASIBLE)
    return res.status == LimitStatus.NO_MECHANISM


def test_semicircular_arch_minimum_thickness():
    """Heyman's minimum-thickness semicircular arch under self-weight with radial joints:
    t / R = 0.1075 (Milankovitch 1907; Ochsendorf 2002 for infinite friction), with
    hinges at the crown, at ~54.5° from the crown on the intrados and at the springings.

    With no live load the LP only asks whether the self-weight is carried: "no_mechanism"
    (stands) for t / R = 0.115, "infeasible" for t / R = 0.100. Bisection between them on
    the status locates the limit of the 40-voussoir arch; 40 discrete joints (4.5° apart,
    one at 54°) and chord-faced voussoirs put it within 0.5 % of the continuous value
    (0.10743 on the development machine).
    """
    assert _stands(0.115)
    assert not _stands(0.100)
    lo, hi = 0.100, 0.115
    for _ in range(18):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if _stands(mid) else (mid, hi)
    assert hi - lo < 1e-6
    assert 0.5 * (lo + hi) == pytest.approx(0.1075, rel=5e-3)


def _arch_with_load(order=None):
    lay = arch_layout(span=2.0, ring_thickness=0.2, voussoirs=24, abutment_height=0.5)
    poly = lay.polygons[lay.names.index("voussoir:0:5")]
    point = poly[2:4].mean(axis=0)  # middle of the extrados chord of voussoir 5
    if order is not None:
        lay = BlockLayout(tuple(lay.polygons[i] for i in order),
                          tuple(lay.materials[i] for i in order),
                          tuple(lay.names[i] for i in order))
    res = limit_analysis(lay, density=RHO, width=1.0, g=G, supports="abutment:*",
                         live_loads=[(point, (0.0, -1.0))], friction=0.6)
    return lay, point, res


def _four_hinge_load(lay: BlockLayout, point: np.ndarray, hinges) -> float:
    """Collapse load of a four-hinge mechanism by instantaneous centres (virtual work).

    Bodies 1 and 3 rotate about the outer hinges H1 and H4; the middle body about the
    intersection C of lines H1-H2 and H3-H4. With ω1 = 1: ω2 = ω1 (H2-H1)·(H2-C)/|H2-C|²,
    ω3 = ω2 (H3-C)·(H3-H4)/|H3-H4|². A point x of a body turning by ω about c moves up by
    ω (x - c)_x, so λ P v_y(load) + Σ W v_y(centroid) = 0 with P = -1 N (downward).
    """
    n = sum(name.startswith("voussoir") for name in lay.names)

    def split(hg):  # index of the first voussoir after the hinge
        idx = [int(s.split(":")[2]) if s.startswith("voussoir") else None for s in hg.blocks]
        if None in idx:
            return 0 if "abutment:left" in hg.blocks else n
        return max(idx)

    hs = sorted(hinges, key=split)
    cuts = [split(hg) for hg in hs]
    p = [np.array(hg.position) for hg in hs]
    d1, d2 = p[1] - p[0], p[3] - p[2]
    s = np.linalg.solve(np.column_stack([d1, -d2]), p[2] - p[0])
    c = p[0] + s[0] * d1
    ω1 = 1.0
    ω2 = ω1 * np.dot(p[1] - p[0], p[1] - c) / np.dot(p[1] - c, p[1] - c)
    ω3 = ω2 * np.dot(p[2] - c, p[2] - p[3]) / np.dot(p[2] - p[3], p[2] - p[3])
    bodies = [(cuts[0], cuts[1], ω1, p[0]), (cuts[1], cuts[2], ω2, c),
              (cuts[2], cuts[3], ω3, p[3])]

    def up(j, x):  # upward velocity of point x moving with voussoir j
        for j0, j1, ω, centre in bodies:
            if j0 <= j < j1:
                return ω * (x[0] - centre[0])
        return 0.0

    work_dead = 0.0
    loaded = None
    for poly, name in zip(lay.polygons, lay.names, strict=True):
        if not name.startswith("voussoir"):
            continue
        j = int(name.split(":")[2])
        weight = RHO * polygon_area(poly) * 1.0 * G
        work_dead += -weight * up(j, polygon_centroid(poly))
        if name == "voussoir:0:5":
            loaded = j
    return -work_dead / (-1.0 * up(loaded, point))


def test_arch_point_load_four_hinges():
    """Semicircular arch, span 2 m, ring 0.2 m, 24 voussoirs, μ = 0.6, with a downward
    point load P = 1 N on the extrados of voussoir 5 (near the left quarter span).

    The LP must give a four-hinge mechanism. Its load factor must equal the one found by
    hand (virtual work with instantaneous centres, :func:`_four_hinge_load`) for the
    reported hinges (LP duality: the static optimum equals the kinematic one), and the
    thrust line must pass through every hinge. Listing the blocks in another order must
    give the same λ (to 1e-9) and the same hinges.
    """
    lay, point, res = _arch_with_load()
    assert res.status == LimitStatus.COLLAPSE
    assert res.load_factor > 0.0
    assert len(res.hinges) == 4
    assert all(hg.kind == HingeKind.HINGE for hg in res.hinges)
    hand = _four_hinge_load(lay, point, res.hinges)
    assert res.load_factor == pytest.approx(hand, rel=1e-6)  # 25061.63 N
    for hg in res.hinges:
        np.testing.assert_allclose(res.thrust_points[hg.interface], hg.position, atol=1e-9)

    order = np.random.default_rng(7).permutation(len(lay))
    _, _, shuffled = _arch_with_load(order)
    assert shuffled.load_factor == pytest.approx(res.load_factor, rel=1e-9)

    def key(r):
        return sorted((tuple(sorted(hg.blocks)), hg.position) for hg in r.hinges)

    for (ba, pa), (bb, pb) in zip(key(res), key(shuffled), strict=True):
        assert ba == bb
        np.testing.assert_allclose(pa, pb, atol=1e-9)


def test_find_interfaces_portal():
    """The portal has four contact segments: the two pier feet on the base and the two pier
    heads under the lintel (the lintel's single bottom edge is split by the piers)."""
    itf = find_interfaces(_portal())
    assert itf.size == 4
    segs = sorted(tuple(sorted((tuple(s), tuple(e)))) for s, e in zip(itf.start, itf.end,
                                                                      strict=True))
    expected = sorted([((0.0, 0.0), (0.4, 0.0)), ((1.4, 0.0), (1.8, 0.0)),
                       ((0.0, 1.2), (0.4, 1.2)), ((1.4, 1.2), (1.8, 1.2))])
    np.testing.assert_allclose(np.array(segs), np.array(expected), atol=1e-12)
    # normals point out of the lower-index block into the other one
    assert np.all(itf.block_a < itf.block_b)
    np.testing.assert_allclose(itf.normal, [[0.0, 1.0]] * 4, atol=1e-12)


def test_limit_analysis_input_errors():
    """Bad inputs are rejected with a clear message."""
    lay = _block_on_base()
    kw = dict(density=RHO, width=0.3, supports="base", live_loads=[((0.0, 1.0), (1.0, 0.0))])
    with pytest.raises(ValueError, match="width"):
        limit_analysis(lay, **{**kw, "width": -1.0})
    with pytest.raises(ValueError, match="densit"):
        limit_analysis(lay, **{**kw, "density": -5.0})
    with pytest.raises(ValueError, match="no density"):
        limit_analysis(lay, **{**kw, "density": {"brick": 1.0}})
    with pytest.raises(ValueError, match="lies in no block"):
        limit_analysis(lay, **{**kw, "live_loads": [((5.0, 5.0), (1.0, 0.0))]})
    with pytest.raises(ValueError, match="matches no block"):
        limit_analysis(lay, **{**kw, "supports": "abutment:*"})
    apart = BlockLayout((rectangle(0, 0, 1, 1), rectangle(2, 0, 3, 1)), ("s", "s"), ("a", "b"))
    with pytest.raises(ValueError, match="no interfaces"):
        limit_analysis(apart, **{**kw, "supports": "a", "live_loads": []})
    with pytest.raises(ValueError, match="friction must be >= 0"):
        limit_analysis(lay, **{**kw, "friction": lambda a, b, mid: -0.1})


def _stack(mu_base: float, mu_top: float, b: float = 1.0, h: float = 0.25) -> BlockLayout:
    """Two b x h blocks stacked on a fixed base: "lower" on (0, 0), "upper" on (0, h)."""
    return BlockLayout(
        (rectangle(-1.0, -0.5, b + 1.0, 0.0), rectangle(0.0, 0.0, b, h),
         rectangle(0.0, h, b, 2.0 * h)),
        ("stone", "stone", "stone"), ("base", "lower", "upper"))


def test_friction_per_interface():
    """Two blocks (b = 1, h = 0.25, w = 0.3, weight W = ρ b h w g = 1471.5 N each) stacked
    on a base; a horizontal load P = 1 N on the upper block at mid-height of its left side.
    Overturning needs P = W b / h = 4 W or more, so sliding governs: of the upper block
    on the lower one, λ = μ_top W, or of both on the base, λ = μ_base · 2 W.

    μ given per interface by a function of the block names and the midpoint:
    μ_base = 0.2, μ_top = 0.5: base sliding, λ = 0.4 W = 588.6; μ_base = 0.5, μ_top = 0.2:
    top sliding, λ = 0.2 W = 294.3. The midpoints passed are those of the two interfaces.
    """
    b, h, w = 1.0, 0.25, 0.3
    weight = RHO * b * h * w * G
    for mu_base, mu_top, expected, sliding in ((0.2, 0.5, 0.4 * weight, ("base", "lower")),
                                               (0.5, 0.2, 0.2 * weight, ("lower", "upper"))):
        seen = {}

        def mu(a, bb, mid, mu_base=mu_base, mu_top=mu_top, seen=seen):
            seen[(a, bb)] = tuple(mid)
            return mu_base if "base" in (a, bb) else mu_top

        res = limit_analysis(_stack(mu_base, mu_top), density=RHO, width=w, g=G,
                             supports="base", friction=mu,
                             live_loads=[((0.0, 1.5 * h), (1.0, 0.0))])
        assert res.status == LimitStatus.COLLAPSE
        assert res.load_factor == pytest.approx(expected, rel=1e-6)
        assert [hg.blocks for hg in res.hinges if hg.kind == HingeKind.SLIDING] == [sliding]
        assert seen == {("base", "lower"): pytest.approx((0.5 * b, 0.0)),
                        ("lower", "upper"): pytest.approx((0.5 * b, h))}


# The reference case of masonry_fdem.assessment.examples: semicircular, span 3 m, three
# rings of 0.11 m (intrados radius 1.5 m), voussoirs [26, 28, 30] with half-voussoir
# stagger, abutments 0.5 x 0.6 m; brick 2000 kg/m^3; the spreader ends at quarter span.
def _three_ring(**kw) -> BlockLayout:
    args = dict(span=3.0, ring_thickness=0.11, voussoirs=[26, 28, 30], rings=3, stagger=0.5,
                abutment_height=0.5, abutment_width=0.6)
    return arch_layout(**{**args, **kw})


def _ring_friction(mu_joint: float, mu_ring: float):
    """μ of the radial joints (springings included) and of the interfaces between rings."""

    def mu(a: str, b: str, mid) -> float:
        ra, rb = (n.split(":")[1] if n.startswith("voussoir") else None for n in (a, b))
        return mu_ring if None not in (ra, rb) and ra != rb else mu_joint

    return mu


def _extrados(lay: BlockLayout, x: float) -> np.ndarray:
    """The highest point of the voussoirs' outlines on the vertical line through x."""
    best = -math.inf
    for poly, name in zip(lay.polygons, lay.names, strict=True):
        a, b = poly, np.roll(poly, -1, axis=0)
        for (x0, y0), (x1, y1) in zip(a, b, strict=True):
            if name.startswith("voussoir") and min(x0, x1) <= x <= max(x0, x1) and x0 != x1:
                best = max(best, y0 + (x - x0) * (y1 - y0) / (x1 - x0))
    return np.array([x, best])


def _la(lay: BlockLayout, friction, live: bool = True):
    """Self-weight and 1 N shared by the ends of a 0.1 m spreader at quarter span."""
    loads = [(_extrados(lay, x), (0.0, -0.5)) for x in (-0.8, -0.7)]
    return limit_analysis(lay, density=RHO, width=1.0, g=G, supports="abutment:*",
                          live_loads=loads if live else [], friction=friction,
                          max_load_factor=490332.5)


def test_three_ring_arch_cannot_carry_its_weight_with_friction_06():
    """Issue #21: the LP of the reference case is infeasible at μ = 0.6. That is the
    answer, not a bug: each 0.11 m ring alone is thinner than the minimum for a
    semicircular arch under self-weight (t / R = 0.11 / 1.555 = 0.071 at the inner ring's
    centre line, Heyman's minimum 0.1075), so the rings stand only by acting together,
    which needs shear across the ring interfaces, and with no bond the friction needed
    there is more than 0.6.

    * one ring of 0.11 m alone: infeasible even with μ = inf (friction factor inf);
    * one ring of 0.33 m at μ = 0.6: collapses under a live load (it stands);
    * the three rings at μ = 0.6 with no sliding between the rings (μ = inf there): stand;
    * the three rings at μ = 0.6 everywhere: infeasible. The mechanism returned is the
      proof, checked here independently of the LP: at both ends of every interface the
      blocks separate at least μ times as fast as they slide (no dissipation) while the
      self-weight does positive work, so by virtual work no equilibrium with
      ``N >= 0, |S| <= μ N`` exists (whatever the flow rule). The friction factor
      ~1.227 (μ ≈ 0.736) is bracketed by a feasible and an infeasible LP;
    * radial joints at 0.7, sand 0.5 between the rings: infeasible (HiGHS' simplex ends
      there with "model status unknown"; the interior-point method decides it).
    """
    inner = arch_layout(span=3.0, ring_thickness=0.11, voussoirs=26, abutment_height=0.5)
    res = _la(inner, math.inf, live=False)
    assert res.status == LimitStatus.INFEASIBLE and math.isinf(res.friction_factor)
    assert "no friction coefficient would help" in res.explanation

    one = arch_layout(span=3.0, ring_thickness=0.33, voussoirs=28, abutment_height=0.5,
                      abutment_width=0.6)
    res = _la(one, 0.6)
    assert res.status == LimitStatus.COLLAPSE and 5e3 < res.load_factor < 5e4  # 14.4 kN

    lay = _three_ring()
    assert _la(lay, _ring_friction(0.6, math.inf)).status != LimitStatus.INFEASIBLE

    res = _la(lay, 0.6)
    assert res.status == LimitStatus.INFEASIBLE
    assert math.isnan(res.load_factor) and not res.hinges
    assert len(res.dead_load_mechanism) > 0
    # the proof, by hand: relative velocities at the interface ends, work of the weight
    vel, itf = res.block_velocities, res.interfaces
    cent = np.array([polygon_centroid(p) for p in lay.polygons])
    weight = np.array([RHO * polygon_area(p) * G for p in lay.polygons])

    def moving(blk, x):
        (u, v, om), c = vel[blk], cent[blk]
        return np.array([u - om * (x[1] - c[1]), v + om * (x[0] - c[0])])

    for a, b, start, end in zip(itf.block_a, itf.block_b, itf.start, itf.end, strict=True):
        t = (end - start) / np.linalg.norm(end - start)
        n = np.array([t[1], -t[0]])
        for x in (start, end):
            rel = moving(b, x) - moving(a, x)
            assert rel @ n >= 0.6 * abs(rel @ t) - 1e-9
    assert np.all(vel[res.fixed] == 0.0)
    assert -np.dot(weight, vel[:, 1]) > 100.0  # [W] at a fastest vertex speed of 1 m/s
    assert res.friction_factor == pytest.approx(1.227, abs=0.005)
    assert _la(lay, 0.6 * res.friction_factor, live=False).status != LimitStatus.INFEASIBLE
    assert _la(lay, 0.6 * res.friction_factor / 1.01,
               live=False).status == LimitStatus.INFEASIBLE
    assert "cannot carry their own dead load" in res.explanation
    assert f"{res.friction_factor:.3g} times larger" in res.explanation

    res = _la(lay, _ring_friction(0.7, 0.5))
    assert res.status == LimitStatus.INFEASIBLE
    assert res.friction_factor == pytest.approx(1.254, abs=0.01)


def test_bonded_rings_act_as_one_ring():
    """Three 0.11 m rings with aligned radial joints (stagger 0, 28 voussoirs each) and no
    sliding between the rings (μ = inf there, 0.6 elsewhere) carry the quarter-span load of
    one 0.33 m ring with the same 28 joints: the ring interfaces are found and oriented
    right. Not more (the blocks of a radial section are the monolithic voussoir cut in
    three), and at most a little less: the rings may still separate (no tension).
    """
    one = arch_layout(span=3.0, ring_thickness=0.33, voussoirs=28, abutment_height=0.5,
                      abutment_width=0.6)
    three = _three_ring(voussoirs=28, stagger=0.0)
    mono = _la(one, 0.6)
    rings = _la(three, _ring_friction(0.6, math.inf))
    assert mono.status == rings.status == LimitStatus.COLLAPSE
    assert rings.load_factor <= mono.load_factor * (1.0 + 1e-6)
    assert rings.load_factor == pytest.approx(mono.load_factor, rel=0.01)
