"""Numba kernels of the contact between rigid circular discrete elements (disks, 2D).

Normal law. The reference paper evaluates the disk–disk normal force "using the analytical
solution" of Hertz (1882) and of Taylor & Preece (1989), whose elements are spheres; its
fill is described as spherical discrete elements. We therefore use Hertz's sphere law

    F = K δ^{3/2},   K = (w / (2 r_min)) · (4/3) E* √R*,

with δ = r_i + r_j − |x_j − x_i| the overlap [m], R* = r_i r_j / (r_i + r_j),
1/E* = (1 − ν_i²)/E_i + (1 − ν_j²)/E_j and r_min = min(r_i, r_j). The exact Hertz line
contact of two cylinders has no closed force–indentation law (the approach carries a term
in ln(4R/a), and depends on where the far-field is taken), so it would need a Newton
solve per contact and offers no closed contact duration. The sphere form F ∝ δ^{3/2} is
what the cited analytical solution is, its impact has a closed contact duration
(t_c = 2.94328 δ_max/v, below) and hence a closed stable time step, it costs one square
root per contact, and it is the law of most 2D granular codes, so published 2D DEM
parameters carry over. The factor w/(2 r_min) makes the force proportional to the
out-of-plane thickness w like every other force of the 2D model: a disk of thickness w
stands for a row of w/(2 r_min) spheres of the smaller diameter across the thickness
(against a wall, r_min = r, the row of the disk's own spheres). The pair's force F is in
newtons for disks of thickness w [m] (mass ρ π r² w, inertia ½ m r²), and an assembly
compressed by a pressure p overlaps by δ/r ∝ (p/E*)^{2/3} whatever w.

Restitution is hysteretic, the Hertzian analogue of Walton & Braun (1986) used by the
block contact (``_kernels``): loading follows F = K δ^{3/2} while δ exceeds the largest
overlap δ_max of the current impact; below δ_max the force follows the steeper branch

    F = K ((δ − δ_0)/e²)^{3/2} = K δ_max^{3/2} ((δ − δ_0)/(δ_max − δ_0))^{3/2},
    δ_0 = δ_max (1 − e²),

which meets the loading curve at δ_max and returns ∫ F dδ = (2/5) K δ_max^{3/2}
(δ_max − δ_0) = e² (2/5) K δ_max^{5/2}, i.e. e² of the loading work: a binary impact
rebounds with e times its approach velocity, whatever the velocity. The force is zero
below δ_0 (never tensile), reloading retraces the unloading branch, and δ_max resets when
the disks separate (δ ≤ 0). Contact duration of an elastic impact (e = 1) at approach
speed v: t_c = 2 (δ_max/v) ∫_0^1 (1 − s^{5/2})^{-1/2} ds = (4/5) B(2/5, 1/2) δ_max/v
= 2.94328 δ_max/v, with (2/5) K δ_max^{5/2} = ½ m* v², i.e.
t_c = 3.21807 (m*/K)^{2/5} v^{-1/5}, m* = m_i m_j/(m_i + m_j).

Tangential law (Cundall & Strack 1979, with Mindlin's stiffness): an incremental elastic
spring on the relative tangential velocity of the contact point, capped by Coulomb's
μ F_n. The tangential stiffness is Mindlin's k_t = 8 G* a = κ k_n with k_n = dF/dδ
= (3/2) K √δ the tangent of the loading curve at the current overlap and
κ = 4 G*/E*, 1/G* = (2 − ν_i)/G_i + (2 − ν_j)/G_j (κ = 2(1 − ν)/(2 − ν) for one
material). In 2D the tangent plane is the line t = ẑ × n, so the history is a scalar:
the elastic tangential displacement s of j's contact point relative to i's along t.
Keeping s while n turns is exactly rotating the history vector s·t with the contact
normal, and it makes the law frame indifferent. When k_t changes with δ the spring keeps
its force if k_t grows (Mindlin's incremental law, dF_t = k_t ds) and its displacement if
k_t falls, so a stiffness change never creates energy; the (small) energy it removes is
counted as friction dissipation.

Rolling resistance (optional, μ_r > 0): the elastic–plastic rolling spring of Ai, Chen,
Rotter & Ooi (2011, Powder Technol. 206, "type C" without its dashpot): a torque
M = −k_r φ on the relative rotation φ = ∫(ω_i − ω_j) dt, k_r = 2.25 μ_r² R*² k_n, capped by
μ_r R* F_n; same stiffness-change rule.

The contact point is the middle of the overlap: arms a_i = r_i − δ/2 and a_j = r_j − δ/2
from the centres (a_i + a_j = |x_j − x_i|), so linear and angular momentum are conserved
exactly and a rigidly rotating pair has no tangential slip.

Use. Every k steps the caller rebuilds the candidate pairs with
:func:`disk_pairs_cell_list` and a margin the disks cannot close in k steps (≥ 2 v_max k dt),
then moves the history of the pairs that persist with :func:`carry_history` (both lists
sorted, persistent disk ids), or, when it has just reordered the disks in space
(:func:`cell_order`), with :func:`carry_history_renumbered`; every step it calls
:func:`disk_disk_forces` on the current list. The time step must satisfy dt < 2/ω with
ω² from :func:`pair_omega2` on the unloading stiffness :func:`hertz_stiffness_bound` at
the largest expected overlap, times the largest number of contacts of a disk.

Arrays (SI): x (n, 2) centres [m]; v (n, 2) velocities at the half step [m/s]; omega (n,)
angular velocities [rad/s]; r (n,) radii [m]; mat (n,) int64 material ids; pairs (k, 2)
int64 candidate pairs, i < j, sorted lexicographically; hist (k, N_HIST) history per pair
(columns H_*); f (n, 2) forces [N] and torque (n,) torques [N m], both ADDED to.
"""

import math

import numpy as np
from numba import njit

# material properties (columns of props, one row per material)
P_E = 0  # Young's modulus [Pa]
P_NU = 1  # Poisson's ratio [-]
P_MU = 2  # Coulomb friction coefficient [-]
P_REST = 3  # restitution coefficient e in (0, 1] [-]
P_MU_ROLL = 4  # rolling friction coefficient μ_r [-] (0: no rolling resistance)
N_DPROPS = 5

# constants of a material pair (last axis of the pair table)
T_ESTAR = 0  # effective modulus E* [Pa]
T_KAPPA = 1  # Mindlin ratio k_t/k_n = 4 G*/E* [-]
T_MU = 2  # friction coefficient [-]
T_REST = 3  # restitution coefficient [-]
T_MU_ROLL = 4  # rolling friction coefficient [-]
N_PAIR = 5

# history per pair
H_SLIP = 0  # elastic tangential displacement s along t = ẑ × n [m]
H_DMAX = 1  # largest overlap of the current impact [m]
H_KN = 2  # normal tangent stiffness k_n of the last step [N/m] (0: new contact)
H_ROLL = 3  # elastic relative rotation φ of the rolling spring [rad]
N_HIST = 4

# energies: W_EN..W_ER are the energies stored now (overwritten by each call),
# W_HYST..W_ROLL the dissipation accumulated over all calls [J]
W_EN = 0  # normal elastic energy recoverable on unloading
W_ET = 1  # tangential spring energy
W_ER = 2  # rolling spring energy
W_HYST = 3  # restitution (hysteresis) dissipation
W_FRIC = 4  # Coulomb friction dissipation
W_ROLL = 5  # rolling friction dissipation
N_WORK = 6

ROLL_STIFFNESS = 2.25  # k_r = 2.25 μ_r² R*² k_n (Ai et al. 2011, after Iwashita & Oda)
HERTZ_TC = 2.9432752  # t_c = HERTZ_TC · δ_max / v for F = K δ^{3/2}


def pair_constants(props, ma, mb):
    """Constants of the contact between materials ma and mb.

    Args:
        props: (n_mat, N_DPROPS) material table (columns P_*).
        ma, mb: material ids.

    Returns:
        (E* [Pa], κ = k_t/k_n, μ, e, μ_r). For dissimilar materials μ, e and μ_r take the
        smaller of the two values (the weaker surface governs); overwrite the entries of
        :func:`pair_table` for measured pair values.
    """
    pa = np.asarray(props[ma], dtype=float)
    pb = np.asarray(props[mb], dtype=float)
    for p, m in ((pa, ma), (pb, mb)):
        if not p[P_E] > 0.0:
            raise ValueError(f"material {m}: Young's modulus must be > 0, got {p[P_E]}")
        if not -1.0 < p[P_NU] < 0.5:
            raise ValueError(f"material {m}: Poisson's ratio must be in (-1, 0.5)")
        if not p[P_MU] >= 0.0 or not p[P_MU_ROLL] >= 0.0:
            raise ValueError(f"material {m}: friction coefficients must be >= 0")
        if not 0.0 < p[P_REST] <= 1.0:
            raise ValueError(f"material {m}: restitution must be in (0, 1], got {p[P_REST]}")
    ca = (1.0 - pa[P_NU] ** 2) / pa[P_E]
    cb = (1.0 - pb[P_NU] ** 2) / pb[P_E]
    e_star = 1.0 / (ca + cb)
    ga = pa[P_E] / (2.0 * (1.0 + pa[P_NU]))
    gb = pb[P_E] / (2.0 * (1.0 + pb[P_NU]))
    g_star = 1.0 / ((2.0 - pa[P_NU]) / ga + (2.0 - pb[P_NU]) / gb)
    return (e_star, 4.0 * g_star / e_star, min(pa[P_MU], pb[P_MU]),
            min(pa[P_REST], pb[P_REST]), min(pa[P_MU_ROLL], pb[P_MU_ROLL]))


def pair_table(props):
    """(n_mat, n_mat, N_PAIR) table of :func:`pair_constants` for every material pair."""
    props = np.atleast_2d(np.asarray(props, dtype=float))
    n = props.shape[0]
    table = np.zeros((n, n, N_PAIR))
    for a in range(n):
        for b in range(n):
            table[a, b] = pair_constants(props, a, b)
    return table


@njit(cache=True, inline="always")
def hertz_k(e_star, r1, r2, thick):
    """Hertz constant K [N/m^{3/2}] of F = K δ^{3/2} for disks of radii r1, r2 [m] and
    thickness thick [m] (r2 = inf: a disk against a flat wall)."""
    if math.isinf(r2):
        r_star = r1
    else:
        r_star = r1 * r2 / (r1 + r2)
    return thick / (2.0 * min(r1, r2)) * (4.0 / 3.0) * e_star * math.sqrt(r_star)


@njit(cache=True)
def hertz_force(k, e, delta, delta_max):
    """Normal force [N] at overlap delta [m] of an impact whose largest overlap so far is
    delta_max [m] (loading branch when delta ≥ delta_max, else the unloading branch)."""
    if delta <= 0.0:
        return 0.0
    if delta >= delta_max:
        return k * delta * math.sqrt(delta)
    s = (delta - delta_max * (1.0 - e * e)) / (e * e)
    if s <= 0.0:
        return 0.0
    return k * s * math.sqrt(s)


@njit(cache=True)
def hertz_stiffness_bound(e_star, r1, r2, thick, delta_max, e):
    """Largest normal tangent stiffness dF/dδ [N/m] of a contact whose overlap stays
    below delta_max [m]: the top of the unloading branch, (3/2) K √δ_max / e²."""
    return 1.5 * hertz_k(e_star, r1, r2, thick) * math.sqrt(delta_max) / (e * e)


@njit(cache=True)
def pair_omega2(k_n, kappa, mu_r, r1, r2, m1, m2, i1, i2):
    """Upper bound of ω² [1/s²] of one contact with normal stiffness k_n [N/m].

    The contact stiffness is a sum of rank-one springs (normal; tangential on translation
    and rotation; rolling on rotation), so ω² ≤ max(k_n (1/m1 + 1/m2),
    k_t (1/m1 + 1/m2 + r1²/I1 + r2²/I2) + k_r (1/I1 + 1/I2)). For an assembly whose disks
    have at most z contacts, ω² ≤ z · max over contacts (each contact's quadratic form
    touches two disks); the central-difference step is stable for dt < 2/ω.

    Args:
        k_n: e.g. :func:`hertz_stiffness_bound` at the largest expected overlap.
        kappa, mu_r: T_KAPPA and T_MU_ROLL of the pair.
        r1, r2, m1, m2, i1, i2: radii [m], masses [kg], inertias [kg m²].
    """
    inv_m = 1.0 / m1 + 1.0 / m2
    r_star = r1 * r2 / (r1 + r2)
    k_r = ROLL_STIFFNESS * mu_r * mu_r * r_star * r_star * k_n
    w_t = kappa * k_n * (inv_m + r1 * r1 / i1 + r2 * r2 / i2) + k_r * (1.0 / i1 + 1.0 / i2)
    return max(k_n * inv_m, w_t)


@njit(cache=True, inline="always")
def _spring(u, k_old, k_new, du, cap):
    """One step of an elastic–perfectly plastic spring with elastic displacement u.

    Applies the stiffness change k_old → k_new (keep the force if stiffer, the displacement
    if softer), then the increment du, then the cap |k_new u| ≤ cap.
    Returns (new u, energy dissipated [J]).
    """
    loss = 0.0
    if k_old > 0.0 and k_new > k_old:
        u_s = u * (k_old / k_new)
        loss = 0.5 * (k_old * u * u - k_new * u_s * u_s)
        u = u_s
    elif k_new < k_old:
        loss = 0.5 * (k_old - k_new) * u * u
    u = u + du
    if k_new * abs(u) > cap:
        u_c = cap / k_new if u > 0.0 else -cap / k_new
        loss += cap * (abs(u) - abs(u_c))  # force × slip
        u = u_c
    return u, loss


@njit(cache=True)
def disk_disk_forces(x, v, omega, r, mat, table, pairs, hist, thick, dt, f, torque, work):
    """Hertz–Mindlin–Coulomb forces (with hysteretic restitution and optional rolling
    resistance) of all candidate pairs; see the module docstring for the laws and
    :func:`disk_disk_forces_range` for the arguments (here every disk is owned)."""
    disk_disk_forces_range(x, v, omega, r, mat, table, pairs, hist, thick, dt, f, torque,
                           work, None, None)


@njit(cache=True, error_model="numpy")
def disk_disk_forces_range(x, v, omega, r, mat, table, pairs, hist, thick, dt, f, torque,
                           work, lo, hi):
    """Hertz–Mindlin–Coulomb forces (with hysteretic restitution and optional rolling
    resistance) of the candidate pairs that touch the disks lo ≤ k < hi (the disks a rank
    owns); see the module docstring for the laws.

    Only the owned disks' forces and torques are added to, each from its pairs in the
    order of the list, so that they are bitwise those of a call over every disk; a pair
    that touches no owned disk is skipped (its history row is left as it was); the
    energies count the pairs whose first disk is owned (each pair on one rank).

    Args:
        x: (n, 2) centres [m] at step n.
        v: (n, 2) velocities [m/s] at step n − 1/2.
        omega: (n,) angular velocities [rad/s] at step n − 1/2 (counter-clockwise).
        r: (n,) radii [m].
        mat: (n,) int64 material ids, rows of table.
        table: (n_mat, n_mat, N_PAIR) pair constants (:func:`pair_table`).
        pairs: (k, 2) int64 candidate pairs i < j.
        hist: (k, N_HIST) in/out history; the row of a pair that does not overlap is zeroed.
        thick: out-of-plane thickness w [m].
        dt: time step [s] (slip increment = relative velocity · dt).
        f: (n, 2) out, forces ADDED [N].
        torque: (n,) out, torques ADDED [N m].
        work: (N_WORK,) out: W_EN, W_ET, W_ER set to the energies stored now, W_HYST,
            W_FRIC, W_ROLL incremented by this step's dissipation [J].
        lo, hi: the owned disks (None, None: all; a version compiled without the
            ownership tests, which cost ~5 % of the loop on one rank).
    """
    # the energies and dissipations are summed in locals (a store to ``work`` per pair
    # was a memory round trip in the loop's critical path), the overlap is tested on the
    # squared distance before any square root, and one reciprocal gives the normal; no
    # division can be by zero (d > 0, k_t > 0 on contact, 0 < e ≤ 1), so numpy's error
    # model spares the checks
    e_n = 0.0
    e_t = 0.0
    e_r = 0.0
    w_hyst = 0.0
    w_fric = 0.0
    w_roll = 0.0
    for k in range(pairs.shape[0]):
        i = pairs[k, 0]
        j = pairs[k, 1]
        if lo is None:  # every disk owned: compiled apart, without the tests
            own_i = True
            own_j = True
        else:
            own_i = lo <= i < hi
            own_j = lo <= j < hi
            if not (own_i or own_j):
                continue
        dx = x[j, 0] - x[i, 0]
        dy = x[j, 1] - x[i, 1]
        ri = r[i]
        rj = r[j]
        rs = ri + rj
        d2 = dx * dx + dy * dy
        if d2 >= rs * rs or d2 <= 0.0:  # apart (or coincident: no normal): impact over
            for c in range(N_HIST):
                hist[k, c] = 0.0
            continue
        d = math.sqrt(d2)
        delta = rs - d
        inv_d = 1.0 / d
        nx = dx * inv_d
        ny = dy * inv_d
        tx = -ny
        ty = nx
        mi = mat[i]
        mj = mat[j]
        e = table[mi, mj, T_REST]
        kappa = table[mi, mj, T_KAPPA]
        kh = hertz_k(table[mi, mj, T_ESTAR], ri, rj, thick)
        sq = math.sqrt(delta)
        # --- normal: hysteretic Hertz
        dmax = hist[k, H_DMAX]
        fn = 0.0
        if delta >= dmax:  # loading (s = δ)
            if own_i:  # each pair's energies on one rank
                w_hyst += 0.4 * (1.0 - e * e) * kh * (
                    delta * delta * sq - dmax * dmax * math.sqrt(dmax))
            dmax = delta
            fn = kh * delta * sq
            if own_i:
                e_n += 0.4 * e * e * fn * delta
        else:
            s = (delta - dmax * (1.0 - e * e)) / (e * e)
            if s > 0.0:
                fn = kh * s * math.sqrt(s)
                if own_i:
                    e_n += 0.4 * e * e * fn * s
        # --- relative motion of the contact point (middle of the overlap)
        ai = ri - 0.5 * delta
        aj = rj - 0.5 * delta
        vt = (v[j, 0] - v[i, 0]) * tx + (v[j, 1] - v[i, 1]) * ty - ai * omega[i] - aj * omega[j]
        kn = 1.5 * kh * sq
        kn_old = hist[k, H_KN]
        # --- tangential: Mindlin spring, Coulomb cap
        kt = kappa * kn
        slip, loss = _spring(hist[k, H_SLIP], kappa * kn_old, kt, vt * dt,
                             table[mi, mj, T_MU] * fn)
        ft = -kt * slip  # tangential force on j along t
        if own_i:
            w_fric += loss
            e_t += 0.5 * kt * slip * slip
        # --- rolling: elastic–plastic rolling spring
        mr = 0.0
        phi = 0.0
        mu_r = table[mi, mj, T_MU_ROLL]
        if mu_r > 0.0:
            r_star = ri * rj / rs
            c = ROLL_STIFFNESS * mu_r * mu_r * r_star * r_star
            phi, loss = _spring(hist[k, H_ROLL], c * kn_old, c * kn,
                                (omega[i] - omega[j]) * dt, mu_r * r_star * fn)
            mr = -c * kn * phi  # rolling torque on i
            if own_i:
                w_roll += loss
                e_r += 0.5 * c * kn * phi * phi
        hist[k, H_SLIP] = slip
        hist[k, H_DMAX] = dmax
        hist[k, H_KN] = kn
        hist[k, H_ROLL] = phi
        # --- forces on j (−on i) and torques about each centre
        fx = fn * nx + ft * tx
        fy = fn * ny + ft * ty
        if own_j:
            f[j, 0] += fx
            f[j, 1] += fy
        if own_i:
            f[i, 0] -= fx
            f[i, 1] -= fy
            torque[i] += -ai * ft + mr
        if own_j:
            torque[j] += -aj * ft - mr
    work[W_EN] = e_n
    work[W_ET] = e_t
    work[W_ER] = e_r
    work[W_HYST] += w_hyst
    work[W_FRIC] += w_fric
    work[W_ROLL] += w_roll


@njit(cache=True)
def _pair_less(a0, a1, b0, b1):
    return a0 < b0 or (a0 == b0 and a1 < b1)


@njit(cache=True)
def carry_history(old_pairs, old_hist, new_pairs, new_hist):
    """Copy the history of pairs present in both lists, zero the others.

    Both pair lists must be sorted lexicographically by (i, j) and use persistent disk
    ids (renumber them if the caller reorders disks); one merge, O(k_old + k_new).

    Args:
        old_pairs: (k_old, 2) int64; old_hist: (k_old, N_HIST).
        new_pairs: (k_new, 2) int64; new_hist: (k_new, N_HIST) out.

    Returns:
        The number of pairs whose history was carried over.
    """
    a = 0
    na = old_pairs.shape[0]
    carried = 0
    for b in range(new_pairs.shape[0]):
        i = new_pairs[b, 0]
        j = new_pairs[b, 1]
        while a < na and _pair_less(old_pairs[a, 0], old_pairs[a, 1], i, j):
            a += 1
        if a < na and old_pairs[a, 0] == i and old_pairs[a, 1] == j:
            for c in range(new_hist.shape[1]):
                new_hist[b, c] = old_hist[a, c]
            carried += 1
        else:
            for c in range(new_hist.shape[1]):
                new_hist[b, c] = 0.0
    return carried


@njit(cache=True, inline="always")
def _near(x, r, margin, xi, yi, ri, j):
    """Whether disk j is closer than r_i + r_j + margin to disk i (centre (xi, yi),
    radius ri, passed in: a loop over j keeps them in registers)."""
    dx = x[j, 0] - xi
    dy = x[j, 1] - yi
    s = ri + r[j] + margin
    return dx * dx + dy * dy < s * s


@njit(cache=True)
def brute_force_disk_pairs(x, r, margin):
    """All pairs (i < j) closer than r_i + r_j + margin, by testing every pair (tests)."""
    n = x.shape[0]
    cnt = 0
    for i in range(n):
        for j in range(i + 1, n):
            if _near(x, r, margin, x[i, 0], x[i, 1], r[i], j):
                cnt += 1
    out = np.empty((cnt, 2), dtype=np.int64)
    cnt = 0
    for i in range(n):
        for j in range(i + 1, n):
            if _near(x, r, margin, x[i, 0], x[i, 1], r[i], j):
                out[cnt, 0] = i
                out[cnt, 1] = j
                cnt += 1
    return out


@njit(cache=True)
def _grid(x, r, margin):
    """The cell-list grid of :func:`disk_pairs_cell_list`: origin (x0, y0) [m], cell size
    h ≥ 2 r_max + margin [m] (coarser for sparse sets: at most about 4 n cells), and
    nx × ny cells. A function of the set of disks, not of their order."""
    n = x.shape[0]
    x0 = x[0, 0]
    y0 = x[0, 1]
    x1 = x0
    y1 = y0
    rmax = 0.0
    for i in range(n):
        x0 = min(x0, x[i, 0])
        x1 = max(x1, x[i, 0])
        y0 = min(y0, x[i, 1])
        y1 = max(y1, x[i, 1])
        rmax = max(rmax, r[i])
    h = max(2.0 * rmax + margin, 1e-300)
    cells = ((x1 - x0) / h + 1.0) * ((y1 - y0) / h + 1.0)  # float: no overflow
    if cells > 4.0 * n + 16.0:
        h *= math.sqrt(cells / (4.0 * n + 16.0))
    nx = int((x1 - x0) / h) + 1
    ny = int((y1 - y0) / h) + 1
    return x0, y0, h, nx, ny


@njit(cache=True)
def _before(x, ids, a, b):
    """Disk a comes before disk b in a cell: by x, then y, then id (coincident centres)."""
    if x[a, 0] != x[b, 0]:
        return x[a, 0] < x[b, 0]
    if x[a, 1] != x[b, 1]:
        return x[a, 1] < x[b, 1]
    return ids[a] < ids[b]


@njit(cache=True)
def _sort_cell(perm, lo, hi, x, ids, tmp):
    """Sort perm[lo:hi] by :func:`_before`: insertion sort (a cell holds a handful of
    disks), bottom-up merge sort in tmp when it holds many (a clustered set)."""
    m = hi - lo
    if m <= 32:
        for a in range(lo + 1, hi):
            p = perm[a]
            b = a - 1
            while b >= lo and _before(x, ids, p, perm[b]):
                perm[b + 1] = perm[b]
                b -= 1
            perm[b + 1] = p
        return
    width = 1
    src = perm
    dst = tmp
    passes = 0
    while width < m:
        for left in range(lo, hi, 2 * width):
            mid = min(left + width, hi)
            right = min(left + 2 * width, hi)
            a = left
            b = mid
            for k in range(left, right):
                if a < mid and (b >= right or not _before(x, ids, src[b], src[a])):
                    dst[k] = src[a]
                    a += 1
                else:
                    dst[k] = src[b]
                    b += 1
        src, dst = dst, src
        width *= 2
        passes += 1
    if passes % 2 == 1:  # the sorted run is in tmp
        for k in range(lo, hi):
            perm[k] = tmp[k]


@njit(cache=True)
def cell_order(x, r, margin, ids):
    """The storage order of disks sorted by the cell of :func:`disk_pairs_cell_list`'s
    grid they lie in, cells row by row (y, then x), and within a cell by x, then y.

    Args:
        x: (n, 2) centres [m] (storage order); r: (n,) radii [m]; margin: [m] ≥ 0.
        ids: (n,) int64 original id of each stored disk (the last tie-break, for
            coincident centres only).

    Returns:
        (perm, same): perm (n,) int64, the storage position now of the disk to store at
        each position (``a[perm]`` is a in the new order); same is True when perm is the
        identity. The order is a function of the disks' positions and radii (the grid),
        not of their storage order nor of their numbering: the same disks given in any
        order get the same new order. One counting sort over the cells, O(n + cells),
        and an insertion sort of each cell's few disks.
    """
    n = x.shape[0]
    perm = np.empty(n, dtype=np.int64)
    if n < 2:
        for k in range(n):
            perm[k] = k
        return perm, True
    x0, y0, h, nx, ny = _grid(x, r, margin)
    cell = np.empty(n, dtype=np.int64)
    start = np.zeros(nx * ny + 1, dtype=np.int64)
    for i in range(n):
        cx = min(int((x[i, 0] - x0) / h), nx - 1)
        cy = min(int((x[i, 1] - y0) / h), ny - 1)
        cell[i] = cy * nx + cx
        start[cell[i] + 1] += 1
    for c in range(nx * ny):
        start[c + 1] += start[c]
    fill = start[:-1].copy()
    for i in range(n):
        c = cell[i]
        perm[fill[c]] = i
        fill[c] += 1
    tmp = np.empty(0, dtype=np.int64)
    for c in range(nx * ny):
        if start[c + 1] - start[c] > 32 and tmp.size == 0:
            tmp = np.empty(n, dtype=np.int64)
        if start[c + 1] - start[c] > 1:
            _sort_cell(perm, start[c], start[c + 1], x, ids, tmp)
    same = True
    for k in range(n):
        if perm[k] != k:
            same = False
            break
    return perm, same


@njit(cache=True)
def carry_history_renumbered(old_pairs, old_hist, perm, new_pairs, new_hist):
    """:func:`carry_history` across a renumbering of the disks: the new list is in the new
    storage order, the old one in the old, and ``perm[k]`` is the old position of the disk
    now at position k (:func:`cell_order`). Old pairs are sorted by (i, j); each new pair
    looks its disks up in the row of the smaller old number (a handful of entries).
    O(n + k_old + k_new). A pair whose disks swap roles (i < j in one numbering, j < i in
    the other) keeps its slip (the relative displacement and the tangent t = ẑ × n both
    change sign) and negates its rolling rotation φ = ∫(ω_i − ω_j) dt.

    Returns:
        The number of pairs whose history was carried over.
    """
    n = perm.size
    start = np.zeros(n + 1, dtype=np.int64)
    for a in range(old_pairs.shape[0]):
        start[old_pairs[a, 0] + 1] += 1
    for i in range(n):
        start[i + 1] += start[i]
    carried = 0
    for b in range(new_pairs.shape[0]):
        i = perm[new_pairs[b, 0]]
        j = perm[new_pairs[b, 1]]
        swapped = i > j
        if swapped:
            i, j = j, i
        hit = -1
        for a in range(start[i], start[i + 1]):
            if old_pairs[a, 1] == j:
                hit = a
                break
        if hit >= 0:
            for c in range(new_hist.shape[1]):
                new_hist[b, c] = old_hist[hit, c]
            if swapped:
                new_hist[b, H_ROLL] = -old_hist[hit, H_ROLL]
            carried += 1
        else:
            for c in range(new_hist.shape[1]):
                new_hist[b, c] = 0.0
    return carried


@njit(cache=True)
def _cell_sweep(x, r, margin, order, start, nx, ny, buf):
    """The candidate pairs (min id, max id) of :func:`disk_pairs_cell_list`'s cells into
    ``buf``: each disk against the disks after it in its own cell and against all of the
    four cells ahead (right; and left, straight, right in the row above). Returns their
    number, −1 if ``buf`` is too small (growing it here, in the loop, cost as much as the
    search: numba then counts references at every store)."""
    cnt = 0
    cap = buf.shape[0]
    for gy in range(ny):
        for gx in range(nx):
            c = gy * nx + gx
            for a in range(start[c], start[c + 1]):
                i = order[a]
                # disk i's centre and radius in locals: the stores into buf below could
                # alias x and r for the compiler, which would load them again per pair
                xi = x[i, 0]
                yi = x[i, 1]
                ri = r[i]
                for nb in range(5):
                    if nb == 0:
                        lo = a + 1
                        hi = start[c + 1]
                    else:
                        hx = gx + (1 if nb == 1 else nb - 3)
                        hy = gy + (0 if nb == 1 else 1)
                        if hx < 0 or hx >= nx or hy >= ny:
                            continue
                        h2 = hy * nx + hx
                        lo = start[h2]
                        hi = start[h2 + 1]
                    for q in range(lo, hi):
                        j = order[q]
                        if _near(x, r, margin, xi, yi, ri, j):
                            if cnt == cap:
                                return -1
                            buf[cnt, 0] = min(i, j)
                            buf[cnt, 1] = max(i, j)
                            cnt += 1
    return cnt


@njit(cache=True)
def disk_pairs_cell_list(x, r, margin):
    """Candidate pairs of disks closer than r_i + r_j + margin [m], on a uniform grid.

    The cell size h ≥ 2 r_max + margin, so a pair lies in neighbouring cells; disks are
    counting-sorted by cell, and each pair of neighbouring cells is tested once. The grid
    is coarsened when it would have more than 4 n cells (sparse, spread-out disks).

    Args:
        x: (n, 2) centres [m]; r: (n,) radii [m]; margin: travel allowance [m] ≥ 0.

    Returns:
        (k, 2) int64 pairs i < j, sorted lexicographically and unique.
    """
    empty = np.empty((0, 2), dtype=np.int64)
    cnt, _, out = cell_list_pairs_grow(x, r, margin, empty, empty)
    return out[:cnt]


@njit(cache=True)
def cell_list_pairs_grow(x, r, margin, buf, out):
    """:func:`cell_list_pairs_into`, with the scratch ``buf`` and the output ``out``
    replaced by larger ones as long as one is too small. Returns (k, buf, out), the
    pairs in ``out[:k]`` (the buffers may be kept for the next search)."""
    while True:
        cnt = cell_list_pairs_into(x, r, margin, buf, out)
        if cnt == -1:
            buf = np.empty((max(2 * buf.shape[0], 4 * x.shape[0], 16), 2), dtype=np.int64)
        elif cnt < -1:
            out = np.empty((int(1.25 * (-cnt - 2)) + 16, 2), dtype=np.int64)
        else:
            return cnt, buf, out


@njit(cache=True)
def cell_list_pairs_into(x, r, margin, buf, out):
    """:func:`disk_pairs_cell_list` into buffers the caller keeps (a rebuild then
    allocates and first-touches no pair-sized memory: at 1e6 disks that was a fifth of a
    rebuild). ``buf`` (m, 2) int64 is scratch, ``out`` (k', 2) int64 receives the sorted
    pairs in its first rows.

    Returns:
        k, the number of pairs (in ``out[:k]``); −1 if ``buf`` is too small (try again
        with a larger one); −(k + 2) if ``out`` is (nothing written there).
    """
    n = x.shape[0]
    if n < 2:
        return 0
    x0, y0, h, nx, ny = _grid(x, r, margin)
    cx = np.empty(n, dtype=np.int64)
    cy = np.empty(n, dtype=np.int64)
    start = np.zeros(nx * ny + 1, dtype=np.int64)
    for i in range(n):
        cx[i] = min(int((x[i, 0] - x0) / h), nx - 1)
        cy[i] = min(int((x[i, 1] - y0) / h), ny - 1)
        start[cy[i] * nx + cx[i] + 1] += 1
    for c in range(nx * ny):
        start[c + 1] += start[c]
    fill = start[:-1].copy()
    order = np.empty(n, dtype=np.int64)
    for i in range(n):
        c = cy[i] * nx + cx[i]
        order[fill[c]] = i
        fill[c] += 1
    # one sweep over the cells, each pair met once, into the buffer (a dense packing
    # has ~3 candidates per disk)
    cnt = _cell_sweep(x, r, margin, order, start, nx, ny, buf)
    if cnt < 0:
        return -1
    if cnt > out.shape[0]:
        return -(cnt + 2)
    # sorted by (i, j): counted into rows by i, each row's few j by insertion
    offs = np.zeros(n + 1, dtype=np.int64)
    for k in range(cnt):
        offs[buf[k, 0] + 1] += 1
    for i in range(n):
        offs[i + 1] += offs[i]
    for k in range(cnt):
        i = buf[k, 0]
        out[offs[i], 0] = i
        out[offs[i], 1] = buf[k, 1]
        offs[i] += 1
    lo = 0
    for i in range(n):
        hi = offs[i]  # the end of row i now
        for a in range(lo + 1, hi):
            jj = out[a, 1]
            b = a - 1
            while b >= lo and out[b, 1] > jj:
                out[b + 1, 1] = out[b, 1]
                b -= 1
            out[b + 1, 1] = jj
        lo = hi
    return cnt


@njit(cache=True)
def max_move(x, x_ref):
    """Largest distance [m] of a disk from its position at the last rebuild."""
    m2 = 0.0
    for i in range(x.shape[0]):
        dx = x[i, 0] - x_ref[i, 0]
        dy = x[i, 1] - x_ref[i, 1]
        m2 = max(m2, dx * dx + dy * dy)
    return math.sqrt(m2)


@njit(cache=True)
def max_node_move(u, u_ref, nodes):
    """Largest displacement [m] of the given block nodes since ``u_ref``."""
    m2 = 0.0
    for k in range(nodes.size):
        i = nodes[k]
        dx = u[2 * i] - u_ref[2 * i]
        dy = u[2 * i + 1] - u_ref[2 * i + 1]
        m2 = max(m2, dx * dx + dy * dy)
    return math.sqrt(m2)


# ---------------------------------------------------------------------- measurements
@njit(cache=True)
def pair_forces(x, r, mat, table, pairs, hist, thick, fc):
    """Contact force on j [N] of every candidate pair (i, j) at the centres x, from the
    history of the last :func:`disk_disk_forces` call (not updated): the Hertz normal
    force on the branch that δ_max selects, and the tangential spring force
    −κ k_n s of that call. Rows of pairs apart are zero.

    Args:
        x: (n, 2) centres [m]; r: (n,) radii [m]; mat, table, pairs, hist, thick: as
            :func:`disk_disk_forces`.
        fc: (k, 2) out, force on disk j of pair k (minus that on disk i) [N].
    """
    for k in range(pairs.shape[0]):
        i = pairs[k, 0]
        j = pairs[k, 1]
        dx = x[j, 0] - x[i, 0]
        dy = x[j, 1] - x[i, 1]
        d = math.sqrt(dx * dx + dy * dy)
        fc[k, 0] = 0.0
        fc[k, 1] = 0.0
        if r[i] + r[j] - d <= 0.0 or d <= 0.0:
            continue
        nx = dx / d
        ny = dy / d
        tab = table[mat[i], mat[j]]
        fn = hertz_force(hertz_k(tab[T_ESTAR], r[i], r[j], thick), tab[T_REST],
                         r[i] + r[j] - d, hist[k, H_DMAX])
        ft = -tab[T_KAPPA] * hist[k, H_KN] * hist[k, H_SLIP]
        fc[k, 0] = fn * nx - ft * ny
        fc[k, 1] = fn * ny + ft * nx


@njit(cache=True)
def _in_cell(x, y, lo0, lo1, hi0, hi1):
    return lo0 <= x < hi0 and lo1 <= y < hi1


@njit(cache=True)
def love_sum_pairs(x, r, pairs, fc, lo0, lo1, hi0, hi1, out):
    """Add Σ f ⊗ (x_c − x_p) over the disk–disk contacts of the disks p whose centre lies
    in the cell [lo0, hi0) × [lo1, hi1) [m]: f the force on p [N], x_c the contact point
    (the middle of the overlap, as :func:`disk_disk_forces`).

    Args:
        x: (n, 2) centres [m]; r: (n,) radii [m]; pairs: (k, 2); fc: (k, 2) forces on j
            (:func:`pair_forces`).
        out: (2, 2) in/out [N m], out[a, b] += f_a (x_c − x_p)_b.
    """
    for k in range(pairs.shape[0]):
        fx = fc[k, 0]
        fy = fc[k, 1]
        if fx == 0.0 and fy == 0.0:
            continue
        i = pairs[k, 0]
        j = pairs[k, 1]
        dx = x[j, 0] - x[i, 0]
        dy = x[j, 1] - x[i, 1]
        d = math.sqrt(dx * dx + dy * dy)
        nx = dx / d
        ny = dy / d
        half = 0.5 * (r[i] + r[j] - d)
        if _in_cell(x[i, 0], x[i, 1], lo0, lo1, hi0, hi1):  # −f at a_i n from x_i
            a = r[i] - half
            out[0, 0] -= fx * a * nx
            out[0, 1] -= fx * a * ny
            out[1, 0] -= fy * a * nx
            out[1, 1] -= fy * a * ny
        if _in_cell(x[j, 0], x[j, 1], lo0, lo1, hi0, hi1):  # f at −a_j n from x_j
            a = r[j] - half
            out[0, 0] -= fx * a * nx
            out[0, 1] -= fx * a * ny
            out[1, 0] -= fy * a * nx
            out[1, 1] -= fy * a * ny


@njit(cache=True)
def love_sum_points(x, disk, f, xc, lo0, lo1, hi0, hi1, out):
    """Add Σ f ⊗ (x_c − x_p) over contacts given by point (e.g. disk–block), for the
    disks p = disk[k] whose centre lies in the cell [lo0, hi0) × [lo1, hi1) [m].

    Args:
        x: (n, 2) centres [m]; disk: (k,) int64 disk of each contact; f: (k, 2) force on
            the disk [N]; xc: (k, 2) contact points [m]; out: (2, 2) in/out [N m].
    """
    for k in range(disk.size):
        p = disk[k]
        if not _in_cell(x[p, 0], x[p, 1], lo0, lo1, hi0, hi1):
            continue
        lx = xc[k, 0] - x[p, 0]
        ly = xc[k, 1] - x[p, 1]
        out[0, 0] += f[k, 0] * lx
        out[0, 1] += f[k, 0] * ly
        out[1, 0] += f[k, 1] * lx
        out[1, 1] += f[k, 1] * ly


@njit(cache=True)
def count_contacts(pairs, fc, count):
    """Add to count (n,) int64 the number of pairs of each disk with a non-zero force."""
    for k in range(pairs.shape[0]):
        if fc[k, 0] != 0.0 or fc[k, 1] != 0.0:
            count[pairs[k, 0]] += 1
            count[pairs[k, 1]] += 1
