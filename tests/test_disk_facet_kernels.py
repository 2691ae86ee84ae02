"""Disk–block contact kernels (area-split normal force, friction): analytic checks.

The overlap of a disk with a polygon is checked against an independent polygon clip
(Sutherland–Hodgman, written here) of an equal-area polygonal circle, and against the
signed triangle fan; forces against the closed-form circular segment.
"""

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from masonry_fdem.interactions.disks import _facet_kernels as D

RNG_SEED = 20240611


# ----------------------------------------------------------------------------- helpers
def _block(poly):
    """Arrays of one counter-clockwise polygon as a block boundary."""
    P = np.ascontiguousarray(poly, dtype=float)
    n = len(P)
    i = np.arange(n, dtype=np.int64)
    facets = np.column_stack([i, (i + 1) % n]).astype(np.int64)
    return P.copy(), np.zeros(2 * n), facets, (i - 1) % n, (i + 1) % n


def _clip(P, a, d):
    """Sutherland–Hodgman: keep the part of polygon P left of the line a + s d."""
    if len(P) == 0:
        return P
    s = d[0] * (P[:, 1] - a[1]) - d[1] * (P[:, 0] - a[0])
    Q = np.roll(P, -1, axis=0)
    sq = np.roll(s, -1)
    keep_q = sq >= 0.0
    cross = (s >= 0.0) != keep_q
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(cross, s / (s - sq), 0.0)
    inter = P + t[:, None] * (Q - P)
    out = np.stack([inter, Q], axis=1)
    mask = np.stack([cross, keep_q], axis=1)
    return out[mask]


def _clip_convex(P, poly):
    for k in range(len(poly)):
        P = _clip(P, poly[k], poly[(k + 1) % len(poly)] - poly[k])
    return P


def _area_moment(P):
    if len(P) < 3:
        return 0.0, np.zeros(2)
    x, y = P[:, 0], P[:, 1]
    xn, yn = np.roll(x, -1), np.roll(y, -1)
    cr = x * yn - xn * y
    return 0.5 * cr.sum(), np.array([((x + xn) * cr).sum(), ((y + yn) * cr).sum()]) / 6.0


def _circle_gon(r, n=20000, phase=0.0):
    """Polygon about the origin whose every edge triangle has its sector's area."""
    dth = 2.0 * math.pi / n
    rho = r * math.sqrt(dth / math.sin(dth))
    th = phase + dth * np.arange(n)
    return np.column_stack([rho * np.cos(th), rho * np.sin(th)])


def _seg_closed(r, h):
    """Circular segment beyond the chord at distance h: area, centroid distance."""
    a = r * r * math.acos(h / r) - h * math.sqrt(r * r - h * h)
    return a, 2.0 / 3.0 * (r * r - h * h) ** 1.5 / a


def _signed_fan(c, r, poly):
    a_tot, m_tot = 0.0, np.zeros(2)
    for k in range(len(poly)):
        a = poly[k] - c
        b = poly[(k + 1) % len(poly)] - c
        ar, mx, my = D.disk_triangle(r, a[0], a[1], b[0], b[1])
        a_tot += ar
        m_tot += (mx, my)
    return a_tot, m_tot


def _inside_convex(c, poly):
    e = np.roll(poly, -1, axis=0) - poly
    w = c - poly
    return bool(np.all(e[:, 0] * w[:, 1] - e[:, 1] * w[:, 0] > 0.0))


def _random_convex(rng, n=7):
    th = np.sort(rng.uniform(0.0, 2.0 * math.pi, n))
    while np.min(np.diff(np.r_[th, th[0] + 2 * math.pi])) < 0.3:
        th = np.sort(rng.uniform(0.0, 2.0 * math.pi, n))
    P = np.column_stack([1.0 * np.cos(th), 0.6 * np.sin(th)])
    g = rng.uniform(0.0, math.pi)
    R = np.array([[math.cos(g), -math.sin(g)], [math.sin(g), math.cos(g)]])
    return P @ R.T + rng.uniform(-1.0, 1.0, 2)


L_SHAPE = np.array([[0, 0], [2, 0], [2, 1], [1, 1], [1, 2], [0, 2]], dtype=float)
L_PARTS = (np.array([[0, 0], [2, 0], [2, 1], [0, 1]], float),
           np.array([[0, 1], [1, 1], [1, 2], [0, 2]], float))


def _call(block, c, r, eps, w, *, vd=(0.0, 0.0), om=0.0, v=None, kt=0.0, mu=0.0, cn=0.0,
          hist=None, dt=1e-5):
    """One disk against all facets of one block."""
    X, u, facets, fprev, fnext = block
    nf = len(facets)
    xd = np.array([c], dtype=float)
    vdd = np.array([vd], dtype=float)
    omega = np.array([om], dtype=float)
    rd = np.array([r], dtype=float)
    pairs = np.array([[0, 0]], dtype=np.int64)
    ptr = np.array([0, nf], dtype=np.int64)
    cand = np.arange(nf, dtype=np.int64)
    params = np.zeros((1, D.N_PARAM))
    params[0, D.P_EPS_A] = eps
    params[0, D.P_WIDTH] = w
    params[0, D.P_KT] = kt
    params[0, D.P_MU] = mu
    params[0, D.P_CN] = cn
    if hist is None:
        hist = np.zeros((1, D.N_HIST))
    vv = np.zeros(2 * len(X)) if v is None else v
    f = np.zeros(2 * len(X))
    f_disk = np.zeros((1, 2))
    torque = np.zeros(1)
    work = np.zeros(D.N_WORK)
    out = np.zeros((1, D.N_OUT))
    parts = np.zeros((nf, D.N_PART))
    D.disk_block_forces(X, u, vv, facets, fprev, fnext, xd, vdd, omega, rd, pairs, ptr, cand,
                        params, hist, dt, f, f_disk, torque, work, out, parts)
    return dict(f=f, F=f_disk[0], torque=torque[0], work=work, out=out[0], parts=parts,
                hist=hist)


# disk of the granular fill: radius, density, thickness; the reference force is its weight
R_DISK = 0.05
WIDTH = 0.1
WEIGHT = 2000.0 * math.pi * R_DISK**2 * WIDTH * 9.81
DELTA_W = 3e-3 * R_DISK  # overlap of the disk resting on a flat facet under its weight
EPS_A = WEIGHT / (WIDTH * D.circular_segment(R_DISK, R_DISK - DELTA_W)[0])


# ---------------------------------------------------------------------------- geometry
def test_circular_segment_closed_form():
    r = 0.37
    err = 0.0
    for h in (0.9 * r, 0.5 * r, 0.1 * r, 0.0, -0.3 * r, -0.99 * r):
        a, g = D.circular_segment(r, h)
        a0, g0 = _seg_closed(r, h)
        err = max(err, abs(a - a0) / a0, abs(g - g0) / g0)
    a, g = D.circular_segment(r, 0.0)
    err = max(err, abs(a - 0.5 * math.pi * r * r) / a, abs(g - 4 * r / (3 * math.pi)) / g)
    # near tangency: A = (4/3) r² √(2ε) ε (1 − 3ε/20 + O(ε²)), centroid r − 3δ/5 + O(δ²/r)
    err_t = 0.0
    for eps in (1e-6, 1e-9, 1e-12):
        h = r * (1.0 - eps)
        eps = (r - h) / r  # the ε actually represented (r − h is exact)
        a, g = D.circular_segment(r, h)
        a0 = 4.0 / 3.0 * r * r * math.sqrt(2.0 * eps) * eps * (1.0 - 0.15 * eps)
        err_t = max(err_t, abs(a - a0) / a0, abs(g - (r - 0.6 * eps * r)) / (eps * r))
    assert D.circular_segment(r, r) == (0.0, r)
    assert D.circular_segment(r, -r)[0] == pytest.approx(math.pi * r * r, rel=1e-15)
    print(f"\ncircular segment: max rel. error {err:.2e} (closed form), "
          f"{err_t:.2e} (tangency series; centroid error / overlap)")
    assert err < 1e-13
    assert err_t < 1e-6


def test_disk_triangle_against_clip():
    rng = np.random.default_rng(RNG_SEED)
    r = 0.8
    circ = _circle_gon(r, phase=0.123)
    err = 0.0
    for _ in range(40):
        a, b = rng.uniform(-1.5, 1.5, (2, 2))
        ar, mx, my = D.disk_triangle(r, a[0], a[1], b[0], b[1])
        tri = np.array([[0.0, 0.0], a, b])
        sgn = 1.0
        if a[0] * b[1] - a[1] * b[0] < 0:
            tri = tri[::-1]
            sgn = -1.0
        a0, m0 = _area_moment(_clip_convex(circ, tri))
        err = max(err, abs(ar - sgn * a0) / (math.pi * r * r),
                  np.hypot(mx - sgn * m0[0], my - sgn * m0[1]) / (math.pi * r**3))
    print(f"\ndisk ∩ triangle vs clipped polygon: max error {err:.2e} (of πr², πr³)")
    assert err < 1e-8


def _check_polygon(poly, convex_parts, rng, n_cases, check_pieces):
    X, u, facets, fprev, fnext = _block(poly)
    cand = np.arange(len(poly), dtype=np.int64)
    lo = poly.min(axis=0)
    hi = poly.max(axis=0)
    e_clip = e_fan = e_piece = 0.0
    n = n_pieces = 0
    while n < n_cases:
        r = rng.uniform(0.05, 0.7)
        c = rng.uniform(lo - r, hi + r)
        circ = _circle_gon(r, phase=rng.uniform(0, 1)) + c
        a_ref = 0.0
        for part in convex_parts:
            a_ref += _area_moment(_clip_convex(circ - c, part - c))[0]
        if a_ref < 1e-4 * math.pi * r * r:
            continue
        n += 1
        A, pieces = D.disk_overlap_pieces(c[0], c[1], r, X, u, facets, fprev, fnext, cand)
        assert np.all(pieces[:, 0] >= -1e-15 * r * r)
        e_clip = max(e_clip, abs(pieces[:, 0].sum() - a_ref) / a_ref)
        a_fan, m_fan = _signed_fan(c, r, poly)
        m = (pieces[:, 0, None] * (pieces[:, 1:] - c)).sum(axis=0)
        e_fan = max(e_fan, abs(A - a_fan) / A, np.hypot(*(m - m_fan)) / (A * r))
        if not check_pieces or _inside_convex(c, poly):
            continue
        # convex polygon, centre outside: facet j's part is disk ∩ polygon ∩ its sector
        for j in range(len(poly)):
            a = poly[j] - c
            b = poly[(j + 1) % len(poly)] - c
            if a[0] * b[1] - a[1] * b[0] >= 0.0:  # centre inside the facet's half-plane
                e_piece = max(e_piece, abs(pieces[j, 0]) / A)
                continue
            P = _clip(_clip(circ - c, np.zeros(2), b), np.zeros(2), -a)
            aj, mj = _area_moment(_clip_convex(P, poly - c))
            e_piece = max(e_piece, abs(pieces[j, 0] - aj) / A)
            if aj > 1e-6 * A:
                n_pieces += 1
                e_piece = max(e_piece, np.hypot(*(pieces[j, 1:] - c - mj / aj)) / r)
    return e_clip, e_fan, e_piece, n_pieces


def test_split_sums_to_overlap_convex():
    rng = np.random.default_rng(RNG_SEED)
    poly = _random_convex(rng)
    e_clip, e_fan, _, _ = _check_polygon(poly, [poly], rng, 120, False)
    print(f"\nconvex polygon, 120 disks: Σ A_i vs clip {e_clip:.2e}, vs signed fan {e_fan:.2e}")
    assert e_clip < 1e-6
    assert e_fan < 1e-11


def test_split_pieces_are_sectors_of_the_overlap():
    """Centre outside a convex polygon: each facet's part is disk ∩ polygon within the
    facet's angular sector seen from the centre (area and centroid)."""
    rng = np.random.default_rng(RNG_SEED + 1)
    poly = _random_convex(rng)
    X, u, facets, fprev, fnext = _block(poly)
    e_max = 0.0
    n_tot = 0
    for _ in range(6):
        e_clip, _, e_piece, n_p = _check_polygon(poly, [poly], rng, 15, True)
        e_max = max(e_max, e_clip, e_piece)
        n_tot += n_p
    print(f"\nper-facet parts vs clipped sectors: max error {e_max:.2e} "
          f"(areas of A, centroids of r), {n_tot} parts")
    assert n_tot > 40
    assert e_max < 1e-6


def test_split_sums_to_overlap_l_shape():
    rng = np.random.default_rng(RNG_SEED + 2)
    e_clip, e_fan, _, _ = _check_polygon(L_SHAPE, L_PARTS, rng, 120, False)
    print(f"\nL-shaped polygon, 120 disks: Σ A_i vs clip {e_clip:.2e}, vs fan {e_fan:.2e}")
    assert e_clip < 1e-6
    assert e_fan < 1e-11


def test_special_positions():
    """Centre on a facet, on a convex and on a reflex vertex, tangent, near tangency."""
    r = 0.2
    X, u, facets, fprev, fnext = _block(L_SHAPE)
    cand = np.arange(6, dtype=np.int64)
    cases = [((0.5, 0.0), 0.5), ((0.0, 0.0), 0.25), ((2.0, 0.0), 0.25),
             ((1.0, 1.0), 0.75), ((1.5, 1.0), 0.5)]
    err = 0.0
    for c, frac in cases:
        A, _ = D.disk_overlap_pieces(c[0], c[1], r, X, u, facets, fprev, fnext, cand)
        err = max(err, abs(A - frac * math.pi * r * r) / (math.pi * r * r))
    A, _ = D.disk_overlap_pieces(0.5, -r, r, X, u, facets, fprev, fnext, cand)
    assert A == 0.0
    dlt = 1e-9
    A, p = D.disk_overlap_pieces(0.5, -r + dlt, r, X, u, facets, fprev, fnext, cand)
    a0 = 4.0 / 3.0 * math.sqrt(2.0 * r) * dlt**1.5
    e_t = abs(A - a0) / a0
    print(f"\nspecial positions: error {err:.2e} of πr²; overlap 1e-9 m: rel. error {e_t:.2e}")
    assert err < 1e-10
    assert e_t < 1e-5
    assert p[0, 0] == A


# ------------------------------------------------------------------- rolling continuity
def _surface(kind, half=0.5, turn_deg=10.0):
    """Block whose top is two facets meeting at the origin with a turn of turn_deg:
    a ridge (interior angle 170°) or a valley (190°)."""
    s = math.tan(math.radians(0.5 * turn_deg)) * half
    y = -s if kind == "ridge" else s
    return np.array([[-half, -half], [half, -half], [half, y], [0.0, 0.0], [-half, y]])


@pytest.mark.parametrize("kind", ["ridge", "valley"])
def test_rolling_over_vertex_is_continuous(kind):
    """The disk, supported against its weight, moves across the vertex in steps of
    r/1000: force magnitude and direction have no jump, each part is along its centroid."""
    block = _block(_surface(kind))
    r = R_DISK
    xs = np.linspace(-0.3 * r, 0.3 * r, 601)
    F = np.zeros((len(xs), 2))
    ang_err = 0.0
    n_split = 0

    def fy(x, y):
        return _call(block, (x, y), r, EPS_A, WIDTH)["F"][1] - WEIGHT

    for k, x in enumerate(xs):
        y = brentq(lambda yy, x=x: fy(x, yy), 0.5 * r, 1.3 * r, xtol=1e-15, rtol=1e-15)
        res = _call(block, (x, y), r, EPS_A, WIDTH)
        F[k] = res["F"]
        parts = res["parts"]
        on = parts[:, D.PT_AREA] > 0.0
        n_split += int(on.sum() >= 2)
        for p in parts[on]:
            fx, fy_ = p[D.PT_FX], p[D.PT_FY]
            dx, dy = x - p[D.PT_GX], y - p[D.PT_GY]
            cr = abs(fx * dy - fy_ * dx) / (math.hypot(fx, fy_) * math.hypot(dx, dy))
            ang_err = max(ang_err, cr)
            assert fx * dx + fy_ * dy > 0.0
    jump = np.max(np.linalg.norm(np.diff(F, axis=0), axis=1)) / WEIGHT
    dmag = np.max(np.abs(np.diff(np.linalg.norm(F, axis=1)))) / WEIGHT
    turn = math.degrees(math.atan2(F[-1, 0], F[-1, 1]) - math.atan2(F[0, 0], F[0, 1]))
    print(f"\n{kind}: largest step change of the force {jump:.2e} W (magnitude {dmag:.2e} W), "
          f"force turns {turn:+.3f}°, {n_split} positions on both facets, "
          f"part direction error {ang_err:.1e} rad")
    assert abs(abs(turn) - 10.0) < 1e-6
    assert n_split > 10
    assert jump < 0.01
    assert ang_err < 1e-9


# --------------------------------------------------------------------- flat contact
@pytest.mark.parametrize("split_node", [False, True])
def test_pressed_on_flat_facet(split_node):
    """Force = ε_a w × segment area, normal to the facet; reactions balance it.

    With a boundary node under the disk (two collinear facets) the paper's rule gives
    each facet's part its own centroid direction; those are not parallel, so the
    resultant is slightly shorter than P_n and tilted, by O(δ/r): bounded here.
    """
    top = [[0.5, 0.0], [0.005, 0.0], [-0.5, 0.0]] if split_node else [[0.5, 0.0], [-0.5, 0.0]]
    poly = np.array([[-0.5, -0.3], [0.5, -0.3]] + top)
    block = _block(poly)
    r = R_DISK
    dl = 5e-3 * r
    c = np.array([0.003, r - dl])
    res = _call(block, c, r, EPS_A, WIDTH)
    a0, _ = _seg_closed(r, r - dl)
    F0 = EPS_A * WIDTH * a0
    F = res["F"]
    fn = res["f"].reshape(-1, 2)
    x = block[0]
    moment = np.sum((x[:, 0] - c[0]) * fn[:, 1] - (x[:, 1] - c[1]) * fn[:, 0])
    e_mag = abs(F[1] - F0) / F0
    e_dir = abs(F[0]) / F0
    e_sum = np.hypot(*(fn.sum(axis=0) + F)) / F0
    e_mom = abs(moment) / (F0 * r)
    print(f"\nflat facet{' (node under the disk)' if split_node else ''}: "
          f"F = {F[1]:.6f} N vs ε_a w A_seg = {F0:.6f} N (rel. {e_mag:.1e}), "
          f"tangential {e_dir:.1e}, Σ reactions + F {e_sum:.1e}, moment about c {e_mom:.1e}")
    if split_node:
        assert e_mag < 0.2 * dl / r
        assert e_dir < 0.01 * dl / r
    else:
        assert e_mag < 1e-10
        assert e_dir < 1e-12
    assert e_sum < 1e-12
    assert e_mom < 1e-12
    assert res["torque"] == 0.0
    # potential energy ε_a w ∫ A dδ by the trapezoidal rule over the approach
    ds = np.linspace(0.0, dl, 4001)
    A = np.array([D.circular_segment(r, r - s)[0] for s in ds])
    e_pot = EPS_A * WIDTH * np.sum(0.5 * (A[1:] + A[:-1]) * np.diff(ds))
    assert res["work"][D.W_NORMAL] == pytest.approx(e_pot, rel=1e-6)


def test_flat_stiffness_and_bound():
    """dP_n/dδ = 2 ε_a w √(δ(2r − δ)) on a flat facet; |dF/dc| ≤ 2 ε_a w r anywhere."""
    r = R_DISK
    flat = _block(np.array([[-0.5, -0.3], [0.5, -0.3], [0.5, 0.0], [-0.5, 0.0]]))
    dl = 4e-3 * r
    h = 1e-7 * r
    k_fd = (_call(flat, (0.0, r - dl - h), r, EPS_A, WIDTH)["F"][1]
            - _call(flat, (0.0, r - dl + h), r, EPS_A, WIDTH)["F"][1]) / (2 * h)
    k0 = 2.0 * EPS_A * WIDTH * math.sqrt(dl * (2 * r - dl))
    bound = D.stiffness_bound(EPS_A, WIDTH, r)
    worst = 0.0
    rng = np.random.default_rng(RNG_SEED + 3)
    block = _block(L_SHAPE * 0.2)
    for _ in range(40):
        c = np.array([0.2, 0.2]) + rng.uniform(0.95, 1.02, 2) * r
        J = np.zeros((2, 2))
        for j in range(2):
            e = np.zeros(2)
            e[j] = 1e-8 * r
            J[:, j] = (_call(block, c + e, r, EPS_A, WIDTH)["F"]
                       - _call(block, c - e, r, EPS_A, WIDTH)["F"]) / (2e-8 * r)
        worst = max(worst, np.linalg.norm(J, 2) / bound)
    print(f"\nflat tangent stiffness: FD {k_fd:.6e} vs 2 ε_a w √(δ(2r−δ)) {k0:.6e} N/m; "
          f"largest |dF/dc| near a reflex vertex = {worst:.3f} × 2 ε_a w r")
    assert k_fd == pytest.approx(k0, rel=1e-5)
    assert 0.1 < worst < 1.05


# -------------------------------------------------------------------------- friction
def test_friction_saturates_and_reverses():
    r = R_DISK
    block = _block(np.array([[-0.5, -0.3], [0.5, -0.3], [0.5, 0.0], [-0.5, 0.0]]))
    dl = 5e-3 * r
    c = (0.0, r - dl)
    mu, kt, v, dt = 0.5, 5e5, 0.2, 1e-5
    pn = EPS_A * WIDTH * _seg_closed(r, r - dl)[0]
    hist = np.zeros((1, D.N_HIST))
    fx = []
    diss = []
    for k in range(120):
        vel = v if k < 60 else -v
        res = _call(block, c, r, EPS_A, WIDTH, vd=(vel, 0.0), kt=kt, mu=mu, hist=hist, dt=dt)
        fx.append(res["F"][0])
        diss.append(res["work"][D.W_FRICTION])
        if k == 59:
            torque = res["torque"]
    fx = np.array(fx)
    cap = mu * pn
    e_lin = abs(fx[0] + kt * v * dt) / (kt * v * dt)
    e_fwd = abs(fx[59] + cap) / cap
    e_rev = abs(fx[-1] - cap) / cap
    e_dis = abs(diss[59] - cap * v * dt) / (cap * v * dt)
    e_tq = abs(torque - (r - dl) * fx[59]) / (cap * r)
    print(f"\nfriction: μ P_n = {cap:.4f} N; forward {fx[59]:.4f} N (rel. {e_fwd:.1e}), "
          f"reversed {fx[-1]:.4f} N (rel. {e_rev:.1e}); first step {e_lin:.1e}; "
          f"slip dissipation {e_dis:.1e}; torque {e_tq:.1e}")
    assert e_lin < 1e-9
    assert np.all(np.diff(fx[:60]) <= 1e-12 * cap)  # monotone loading to the cap
    assert e_fwd < 1e-12 and e_rev < 1e-12
    assert np.any(np.abs(fx[60:]) < cap)  # passes through the elastic range on reversal
    assert e_dis < 1e-9
    assert e_tq < 1e-12
    # rolling without slip (v = −ω d at the contact point) builds no tangential force
    res = _call(block, c, r, EPS_A, WIDTH, vd=(v, 0.0), om=-v / (r - dl), kt=kt, mu=mu,
                dt=dt)
    assert abs(res["out"][D.O_FT]) < 1e-9 * cap


def test_momentum_balance_at_a_corner():
    """Random corner contacts with friction, damping and moving nodes: forces on disk and
    block are equal and opposite with the same moment."""
    rng = np.random.default_rng(RNG_SEED + 4)
    poly = _random_convex(rng, 5) * 0.3
    block = _block(poly)
    r = R_DISK
    worst_f = worst_m = 0.0
    n = 0
    for _ in range(200):
        k = rng.integers(len(poly))
        c = poly[k] + rng.uniform(-1, 1, 2) * r
        if _inside_convex(c, poly):
            continue
        v = rng.normal(size=2 * len(poly))
        hist = np.array([[rng.normal() * 5.0, 0.0]])
        res = _call(block, c, r, EPS_A, WIDTH, vd=rng.normal(size=2), om=rng.normal() * 10,
                    v=v, kt=1e5, mu=0.6, cn=50.0, hist=hist)
        if res["out"][D.O_AREA] == 0.0:
            continue
        n += 1
        fn = res["f"].reshape(-1, 2)
        F = res["F"]
        s = np.linalg.norm(F) + 1e-300
        x = block[0]
        m = np.sum(x[:, 0] * fn[:, 1] - x[:, 1] * fn[:, 0]) + c[0] * F[1] - c[1] * F[0]
        worst_f = max(worst_f, np.hypot(*(fn.sum(axis=0) + F)) / s)
        worst_m = max(worst_m, abs(m + res["torque"]) / (s * np.abs(poly).max()))
    print(f"\nmomentum balance over {n} corner contacts: force {worst_f:.1e}, "
          f"moment {worst_m:.1e}")
    assert n > 50
    assert worst_f < 1e-12
    assert worst_m < 1e-12
