"""Disk–disk contact kernels: Hertz impacts, Coulomb friction, rolling resistance, pair
lists and frame indifference against analytic values (tolerances stated in each test)."""

import math

import numpy as np
import pytest
from scipy.spatial import cKDTree

from masonry_fdem.interactions.disks import _kernels as D

RHO = 2600.0  # [kg/m³]
THICK = 0.1  # out-of-plane thickness w [m]
R = 0.05  # disk radius [m]
E, NU = 1e8, 0.25
G = 9.81


def _table(mu=0.0, e=1.0, mu_r=0.0):
    return D.pair_table(np.array([[E, NU, mu, e, mu_r]]))


def _mass(r):
    m = RHO * math.pi * np.asarray(r) ** 2 * THICK
    return m, 0.5 * m * np.asarray(r) ** 2


class Scene:
    """Disks advanced by central differences (x at steps, v and ω at half steps)."""

    def __init__(self, x, v, omega, r, table, fixed=(), gravity=0.0):
        self.x = np.array(x, dtype=float)
        self.v = np.array(v, dtype=float)
        self.omega = np.array(omega, dtype=float)
        self.r = np.array(r, dtype=float)
        self.m, self.I = _mass(self.r)
        self.mat = np.zeros(len(r), dtype=np.int64)
        self.table = table
        self.pairs = D.brute_force_disk_pairs(self.x, self.r, 1.0)  # all pairs
        self.hist = np.zeros((len(self.pairs), D.N_HIST))
        self.free = np.ones(len(r), dtype=bool)
        self.free[list(fixed)] = False
        self.gravity = gravity
        self.f = np.zeros_like(self.x)
        self.tq = np.zeros_like(self.omega)
        self.work = np.zeros(D.N_WORK)

    def step(self, dt):
        """One step; returns (v, ω) at the end of the step (half step n + 1/2)."""
        self.f[:] = 0.0
        self.tq[:] = 0.0
        self.x_force = self.x.copy()  # positions at which f was evaluated
        D.disk_disk_forces(self.x, self.v, self.omega, self.r, self.mat, self.table,
                           self.pairs, self.hist, THICK, dt, self.f, self.tq, self.work)
        a = self.f / self.m[:, None]
        a[:, 1] -= self.gravity
        fr = self.free
        self.v[fr] += dt * a[fr]
        self.omega[fr] += dt * self.tq[fr] / self.I[fr]
        self.x[fr] += dt * self.v[fr]

    def kinetic(self, v, omega):
        return 0.5 * np.sum(self.m * np.sum(v**2, axis=1) + self.I * omega**2)


def _hertz_k():
    e_star = D.pair_constants(np.array([[E, NU, 0, 1, 0]]), 0, 0)[0]
    return D.hertz_k(e_star, R, R, THICK)


def _crossing(t, y):
    """Times where the sampled y(t) crosses zero (linear interpolation)."""
    s = np.flatnonzero(np.sign(y[:-1]) != np.sign(y[1:]))
    return t[s] - y[s] * (t[s + 1] - t[s]) / (y[s + 1] - y[s])


def _head_on(e, v0=1.0, steps_per_tc=2000):
    """Equal disks approaching at relative speed v0; returns the measured figures."""
    k = _hertz_k()
    m, _ = _mass(R)
    m_star = 0.5 * m
    tc = 0.4 * 2.0 * math.gamma(0.4) * math.gamma(0.5) / math.gamma(0.9) * \
        (1.25 * m_star / k) ** 0.4 * v0 ** -0.2  # 2 δ_max/v ∫(1 − s^{5/2})^{-1/2} ds
    dt = tc / steps_per_tc
    gap = 20 * v0 * dt
    sc = Scene([[-R - gap / 2, 0.0], [R + gap / 2, 0.0]], [[0.5 * v0, 0], [-0.5 * v0, 0]],
               [0.0, 0.0], [R, R], _table(e=e))
    ke0 = sc.kinetic(sc.v, sc.omega)
    ts, deltas, balance = [], [], []
    n = 0
    touched = False
    while True:
        v_old = sc.v.copy()
        delta = 2 * R - (sc.x[1, 0] - sc.x[0, 0])
        sc.step(dt)
        ke = sc.kinetic(0.5 * (v_old + sc.v), sc.omega)  # KE at step n (mean of halves)
        balance.append(ke + sc.work[D.W_EN] + sc.work[D.W_HYST] - ke0)
        ts.append(n * dt)
        deltas.append(delta)
        n += 1
        touched = touched or delta > 0.0
        if touched and delta < -10 * v0 * dt:  # separated, both crossings sampled
            break
        assert n < 20 * steps_per_tc
    ts, deltas = np.array(ts), np.array(deltas)
    t0, t1 = _crossing(ts, deltas)[:2]
    e_meas = (sc.v[1, 0] - sc.v[0, 0]) / v0  # −(after)/(before), before = −v0
    ke1 = sc.kinetic(sc.v, sc.omega)
    dmax = (1.25 * m_star * v0**2 / k) ** 0.4
    return dict(e=e_meas, tc=t1 - t0, tc_exact=tc, ke_ratio=ke1 / ke0, dmax=deltas.max(),
                dmax_exact=dmax, balance=np.abs(balance).max() / ke0)


@pytest.mark.parametrize("e", [0.5, 0.9])
def test_head_on_restitution(e):
    """Hysteretic Hertz: rebound/approach = e within 2 %; the energy balance (kinetic +
    stored + hysteresis) holds within 0.5 % of the impact energy at every step."""
    out = _head_on(e)
    print(f"\ne_in = {e}: measured e = {out['e']:.5f} "
          f"(rel. error {out['e'] / e - 1:+.2e}), energy balance error {out['balance']:.2e}")
    assert out["e"] == pytest.approx(e, rel=0.02)
    assert out["balance"] < 5e-3


def test_head_on_elastic():
    """e = 1: kinetic energy conserved within 0.5 %, contact duration within 2 % of
    t_c = 2.94328 δ_max/v and largest overlap within 1 % of (5 m* v²/(4K))^{2/5}."""
    out = _head_on(1.0)
    print(f"\ne = 1: KE after/before = {out['ke_ratio']:.6f}, "
          f"t_c = {out['tc'] * 1e3:.5f} ms vs {out['tc_exact'] * 1e3:.5f} ms analytic "
          f"({out['tc'] / out['tc_exact'] - 1:+.2e}), δ_max = {out['dmax'] * 1e3:.5f} mm vs "
          f"{out['dmax_exact'] * 1e3:.5f} mm, balance {out['balance']:.2e}")
    assert out["ke_ratio"] == pytest.approx(1.0, abs=5e-3)
    assert out["tc"] == pytest.approx(out["tc_exact"], rel=0.02)
    assert out["dmax"] == pytest.approx(out["dmax_exact"], rel=0.01)
    assert out["tc_exact"] == pytest.approx(D.HERTZ_TC * out["dmax_exact"], rel=1e-6)


def test_hysteresis_branches_and_stiffness_bound():
    """Unloading work = e² loading work (quadrature); no tension; the tangent stiffness
    never exceeds hertz_stiffness_bound (finite differences)."""
    k, e, dmax = 3.0e7, 0.6, 1e-3
    d = np.linspace(0.0, dmax, 200001)
    load = np.array([D.hertz_force(k, e, x, 0.0) for x in d])
    unload = np.array([D.hertz_force(k, e, x, dmax) for x in d])
    w_load = np.trapezoid(load, d)
    w_unload = np.trapezoid(unload, d)
    slope = np.max(np.diff(unload) / np.diff(d))
    e_star = D.pair_constants(np.array([[E, NU, 0, e, 0]]), 0, 0)[0]
    kh = D.hertz_k(e_star, R, R, THICK)
    bound = D.hertz_stiffness_bound(e_star, R, R, THICK, dmax, e)
    fd = (D.hertz_force(kh, e, dmax, dmax) - D.hertz_force(kh, e, dmax * (1 - 1e-7), dmax)) / (
        dmax * 1e-7)
    print(f"\nunloading/loading work = {w_unload / w_load:.6f} (e² = {e * e}); "
          f"unloading tangent at δ_max {fd:.6e} vs bound {bound:.6e}")
    assert w_unload / w_load == pytest.approx(e * e, rel=1e-4)
    assert unload.min() >= 0.0 and unload[: int(200000 * (1 - e * e))].max() == 0.0
    assert slope <= 1.5 * k * math.sqrt(dmax) / e**2 * (1 + 1e-9)
    assert fd == pytest.approx(bound, rel=1e-5)


def test_oblique_impact_sliding():
    """Oblique impact sliding throughout (μ = 0.1, v_t = v_n): |F_t| ≤ μ F_n at every
    step, tangential impulse = μ × normal impulse within 1 %, and the rigid-impact values
    J_n = m*(1 + e) v_n, ω = μ J_n r / I, Δv_t = 2 μ J_n / m within 1 %; the kinetic
    energy lost = hysteresis + friction dissipation within 1 %. Slow (1 cm/s)
    so the normal turns by ~1e-3 rad during the contact, as a rigid impact assumes."""
    mu, e, vn, vt = 0.1, 0.8, 0.01, 0.01
    m, inertia = _mass(R)
    dt = 3.21807 * (0.5 * m / _hertz_k()) ** 0.4 * vn**-0.2 / 2000
    gap = 20 * vn * dt
    sc = Scene([[-R - gap / 2, 0.0], [R + gap / 2, 0.0]],
               [[0.5 * vn, -0.5 * vt], [-0.5 * vn, 0.5 * vt]], [0.0, 0.0], [R, R],
               _table(mu=mu, e=e))
    jn = jt = 0.0
    worst = 0.0
    ke0 = sc.kinetic(sc.v, sc.omega)
    for _ in range(20000):
        sc.step(dt)
        d = sc.x_force[1] - sc.x_force[0]
        n = d / np.linalg.norm(d)
        t = np.array([-n[1], n[0]])
        fn, ft = sc.f[1] @ n, sc.f[1] @ t
        jn += fn * dt
        jt += abs(ft) * dt
        if fn > 0:
            worst = max(worst, abs(ft) / (mu * fn))
        if sc.hist[0, D.H_DMAX] == 0.0 and jn > 0:
            break
    jn_exact = 0.5 * m * (1 + e) * vn
    ke1 = sc.kinetic(sc.v, sc.omega)
    lost = (ke0 - ke1 - sc.work[D.W_HYST] - sc.work[D.W_FRIC]) / (ke0 - ke1)
    rel_vt = (sc.v[1] - sc.v[0]) @ np.array([0.0, 1.0])
    print(f"\nJ_t/(μ J_n) = {jt / (mu * jn):.5f}, max |F_t|/(μ F_n) = {worst:.15f}, "
          f"J_n = {jn:.6f} vs {jn_exact:.6f} N s, ω = {sc.omega} vs "
          f"{mu * jn * R / inertia:.5f} rad/s, v_t after {rel_vt:.5f} vs "
          f"{vt - 2 * mu * jn / m:.5f} m/s; KE lost {ke0 - ke1:.4e} J = hysteresis "
          f"{sc.work[D.W_HYST]:.4e} + friction {sc.work[D.W_FRIC]:.4e} J ({lost:+.1e})")
    assert worst <= 1 + 1e-12
    assert jt / (mu * jn) == pytest.approx(1.0, rel=0.01)
    assert jn == pytest.approx(jn_exact, rel=0.01)
    assert sc.omega == pytest.approx(mu * jn * R / inertia * np.ones(2), rel=0.01)
    assert abs(lost) < 0.01
    assert rel_vt == pytest.approx(vt - 2 * mu * jn / m, rel=0.01)


def _on_flat(v0, omega0, mu, mu_r=0.0):
    """A disk resting (static overlap) on a huge fixed disk, i.e. on a flat floor."""
    big = 1e4
    k = D.hertz_k(_table()[0, 0, D.T_ESTAR], big, R, THICK)
    m, inertia = _mass(R)
    d_eq = (m * G / k) ** (2 / 3)
    sc = Scene([[0.0, -big], [0.0, R - d_eq]], [[0.0, 0.0], [v0, 0.0]], [0.0, omega0],
               [big, R], _table(mu=mu, e=0.5, mu_r=mu_r), fixed=[0], gravity=G)
    sc.m[0] = sc.I[0] = 1.0  # fixed: never used
    return sc, R - 0.5 * d_eq, m, inertia


def test_sliding_to_rolling():
    """A disk launched without spin on a flat slides under friction μ m g until its contact
    point stops: t* = v0/(μ g (1 + m a²/I)), v* = v0 (m a²/I)/(1 + m a²/I) (a = r − δ/2,
    2/3 v0 for a = r) within 1 %; while sliding |F_t| = μ F_n to 1e-12."""
    mu, v0, dt = 0.4, 1.0, 5e-5
    sc, a, m, inertia = _on_flat(v0, 0.0, mu)
    ts, slip, vs = [], [], []
    ratio = []
    for n in range(2500):
        sc.step(dt)
        ts.append((n + 0.5) * dt)
        slip.append(sc.v[1, 0] + a * sc.omega[1])
        vs.append(sc.v[1, 0])
        d = sc.x_force[1] - sc.x_force[0]
        nrm = d / np.linalg.norm(d)
        fn, ft = sc.f[1] @ nrm, sc.f[1] @ [-nrm[1], nrm[0]]
        if slip[-1] > 0.05 * v0 and n > 5:
            ratio.append(abs(ft) / (mu * fn))
    ts, slip, vs = map(np.array, (ts, slip, vs))
    t_star = _crossing(ts, slip)[0]
    v_star = np.interp(t_star, ts, vs)
    c = m * a * a / inertia
    t_exact = v0 / (mu * G * (1 + c))
    v_exact = v0 * c / (1 + c)
    print(f"\nt* = {t_star:.6f} s vs {t_exact:.6f} s, v* = {v_star:.6f} vs {v_exact:.6f} m/s"
          f" (2/3 v0 = {2 * v0 / 3:.6f}), |F_t|/(μ F_n) while sliding in "
          f"[{min(ratio):.14f}, {max(ratio):.14f}]")
    assert t_star == pytest.approx(t_exact, rel=0.01)
    assert v_star == pytest.approx(v_exact, rel=0.01)
    assert np.allclose(ratio, 1.0, rtol=0, atol=1e-12)


def test_rolling_resistance():
    """A disk rolling on a flat against the rolling torque μ_r R* F_n decelerates at
    μ_r R* g a/(a² + I/m) (= 2/3 μ_r g for a = R* = r) within 2 %; friction work and
    rolling dissipation are reported."""
    mu, mu_r, v0, dt = 0.5, 0.05, 0.5, 5e-5
    sc, a, m, inertia = _on_flat(v0, 0.0, mu, mu_r)
    sc.omega[1] = -v0 / a
    ts, vs = [], []
    for n in range(6000):
        sc.step(dt)
        ts.append((n + 0.5) * dt)
        vs.append(sc.v[1, 0])
    ts, vs = np.array(ts), np.array(vs)
    keep = ts > 0.02
    slope = np.polyfit(ts[keep], vs[keep], 1)[0]
    r_star = R * 1e4 / (R + 1e4)
    exact = -mu_r * r_star * G * a / (a * a + inertia / m)
    print(f"\nrolling deceleration {slope:.6f} vs {exact:.6f} m/s² "
          f"({slope / exact - 1:+.2e}); rolling dissipation {sc.work[D.W_ROLL]:.5f} J, "
          f"friction {sc.work[D.W_FRIC]:.2e} J")
    assert slope == pytest.approx(exact, rel=0.02)


def _random_disks(n, seed, box):
    rng = np.random.default_rng(seed)
    x = rng.uniform(0.0, box, (n, 2))
    r = rng.uniform(0.01, 0.05, n)
    return x, r


def test_cell_list_matches_brute_force():
    """Cell list = brute force = scipy cKDTree (filtered) on 2000 polydisperse disks, and
    on a sparse set (coarsened grid)."""
    for n, box, margin in ((2000, 2.5, 0.005), (2000, 1.5, 0.0), (300, 1e3, 0.01)):
        x, r = _random_disks(n, 7, box)
        if box > 100:
            x[:150] = x[:150] * 1e-3  # a dense cluster in a huge, mostly empty box
        cl = D.disk_pairs_cell_list(x, r, margin)
        bf = D.brute_force_disk_pairs(x, r, margin)
        kd = np.array(sorted(cKDTree(x).query_pairs(2 * r.max() + margin)), dtype=np.int64)
        keep = np.linalg.norm(x[kd[:, 0]] - x[kd[:, 1]], axis=1) < r[kd[:, 0]] + r[kd[:, 1]] \
            + margin
        kd = kd[keep]
        print(f"\n{n} disks in a {box} m box: {len(cl)} pairs (brute force {len(bf)}, "
              f"cKDTree {len(kd)})")
        assert len(cl) > 0
        np.testing.assert_array_equal(cl, bf)
        np.testing.assert_array_equal(cl, kd)
        assert np.all(cl[:, 0] < cl[:, 1])
    assert D.disk_pairs_cell_list(np.zeros((1, 2)), np.ones(1), 0.1).shape == (0, 2)


def test_carry_history():
    """History of persisting pairs is carried over, new pairs start from zero."""
    rng = np.random.default_rng(3)
    x, r = _random_disks(500, 1, 1.0)
    old = D.disk_pairs_cell_list(x, r, 0.01)
    x2 = x + rng.normal(0.0, 0.01, x.shape)
    new = D.disk_pairs_cell_list(x2, r, 0.01)
    old_hist = rng.normal(size=(len(old), D.N_HIST))
    new_hist = np.full((len(new), D.N_HIST), np.nan)
    carried = D.carry_history(old, old_hist, new, new_hist)
    index = {(int(i), int(j)): k for k, (i, j) in enumerate(old)}
    common = 0
    for b, (i, j) in enumerate(new):
        a = index.get((int(i), int(j)))
        if a is None:
            assert np.all(new_hist[b] == 0.0)
        else:
            common += 1
            np.testing.assert_array_equal(new_hist[b], old_hist[a])
    print(f"\n{len(old)} old pairs, {len(new)} new, {carried} carried over")
    assert carried == common and 0 < common < len(new)


def _two_disk_eval(theta, hist, table):
    c, s = math.cos(theta), math.sin(theta)
    rot = np.array([[c, -s], [s, c]])
    x = np.array([[0.1, 0.2], [0.1 + 0.085, 0.2 + 0.03]]) @ rot.T + [0.3, -0.2]
    v = np.array([[0.4, -0.3], [-0.7, 0.5]]) @ rot.T
    omega = np.array([3.0, -2.0])
    r = np.array([0.05, 0.046])
    f = np.zeros((2, 2))
    tq = np.zeros(2)
    work = np.zeros(D.N_WORK)
    h = hist.copy()
    D.disk_disk_forces(x, v, omega, r, np.zeros(2, dtype=np.int64), table,
                       np.array([[0, 1]], dtype=np.int64), h, THICK, 1e-5, f, tq, work)
    return rot, f, tq, work, h, x


@pytest.mark.parametrize("mu", [10.0, 1e-3])
def test_frame_indifference_and_balance(mu):
    """Rotating the configuration rotates the forces and leaves torques, energies and
    history unchanged (1e-12 relative); forces and moments balance (stick and slip)."""
    table = D.pair_table(np.array([[E, NU, mu, 0.7, 0.1]]))
    hist = np.array([[2e-5, 2e-3, 1e6, 1e-3]])  # unloading branch, loaded springs
    _, f0, tq0, w0, h0, x0 = _two_disk_eval(0.0, hist, table)
    worst = 0.0
    for theta in (0.7, 2.5, -1.9):
        rot, f1, tq1, w1, h1, _ = _two_disk_eval(theta, hist, table)
        worst = max(worst, np.abs(f1 - f0 @ rot.T).max() / np.abs(f0).max(),
                    np.abs(tq1 - tq0).max() / np.abs(tq0).max(),
                    np.abs(w1 - w0).max() / np.abs(w0).max(),
                    np.abs(h1 - h0).max() / np.abs(h0).max())
    moment = np.sum(x0[:, 0] * f0[:, 1] - x0[:, 1] * f0[:, 0]) + tq0.sum()
    print(f"\nμ = {mu}: largest relative change under rotation {worst:.2e}; "
          f"|Σf| = {np.abs(f0.sum(axis=0)).max():.1e} N, Σ moments = {moment:.1e} N m, "
          f"F = {f0[1]} N, work = {w0}")
    assert w0[D.W_EN] > 0 and w0[D.W_ET] > 0 and w0[D.W_ER] > 0
    assert worst < 1e-12
    assert np.abs(f0.sum(axis=0)).max() < 1e-12 * np.abs(f0).max()
    assert abs(moment) < 1e-12 * np.abs(f0).max()
