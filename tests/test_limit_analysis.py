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
    # associative friction: the block slides to +x and dilates by μ per unit slip
    u, v, ω = res.block_velocities[1]
    assert u > 0.0 and v == pytest.approx(μ * u, rel=1e-9) and abs(ω) < 1e-12


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
