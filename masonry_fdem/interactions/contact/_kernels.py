"""Numba kernels of the facet-to-facet penalty contact between deformable blocks (2D).

Arrays (local numbering):
    X: (n_nodes, 2) reference coordinates [m]; u, v: (2 n_nodes,) displacement [m] and
    velocity [m/s]; facets: (n_f, 2) node pairs, counter-clockwise around their block
    (block interior on the left, outward normal n = (t_y, -t_x)); pairs: (n_p, 2) facet
    indices; tau: (n_p, 2) tangential traction history [Pa] of the two passes of each pair.

A pair is evaluated in two passes, each facet in turn the *slave* whose points are
checked against the *master* facet's half-plane; each pass carries half the penalty
(the symmetric two-pass treatment). In a pass the penetration g(s) = (x_s(s) − p1)·n_m ≤ 0
is linear along the slave facet, so the contact zone (slave points projecting inside the
master facet, behind it, facing it) is an interval [s0, s1] found exactly, and the normal
traction ε_n (−g) is integrated exactly by two-point Gauss with the linear shape functions
of both facets (reference paper, eq. 4).

Restitution is hysteretic (a Walton–Braun-type unloading applied to the whole gap field):
each pass remembers its largest penetration p_max; while unloading from it the gap is
shifted by δ = (p_max − p)(1/e² − 1) towards separation, so the elastic force returns
the fraction e² of the loading work whatever the force–penetration law of the contact
(linear for flat contact, quadratic for a corner in 2D): the rebound velocity of a rigid
impact is e times the approach velocity, the force stays continuous, and e = 1 is
perfectly elastic.
"""

import math

import numpy as np
from numba import njit

GAUSS = 0.5 / math.sqrt(3.0)
# a pass acts fully when the facets are within 60° of facing each other (−cos ≥ 0.5)
# and fades linearly to nothing as they become perpendicular
FACING = 0.5
# sine of the smallest turn at a boundary vertex that makes it a corner (0.06°)
CONVEX = 1e-3

# results of one pass, in a small work array
Z_S0 = 0
Z_S1 = 1
Z_LEN = 2  # zone length [m]
Z_ACTIVE = 3
Z_PEN = 4  # largest penetration in the zone [m]
N_WORK = 5


@njit(cache=True)
def _pos(X, u, node, ox, oy):
    """Current position of ``node`` relative to the origin (ox, oy) [m]: the reference
    offset first, then the displacement. Every rule of a pass is translation invariant;
    with the origin at a reference node of the pair, the offsets between the nodes of a
    joint are exact (zero for coincident nodes) and the gaps keep the full precision of
    the displacements, instead of the ~1e-16 m of an absolute coordinate near 1 m (which
    times a stiff penalty gave a force round-off floor near 1e-7 of the loads)."""
    return (X[node, 0] - ox) + u[2 * node], (X[node, 1] - oy) + u[2 * node + 1]


@njit(cache=True)
def _clip(a, b, lim):
    """Restrict [lim[0], lim[1]] to {s : a + b s >= 0}; False when it becomes empty.

    ``lim`` is the work array of ``_zone`` (its first two entries are s0, s1).
    """
    if b == 0.0:
        return a >= 0.0
    if b > 0.0:
        lim[0] = max(lim[0], -a / b)
    else:
        lim[1] = min(lim[1], -a / b)
    return lim[1] > lim[0]


@njit(cache=True)
def _gap_line(qx, qy, ax, ay, bx, by):
    """Signed distance of q from the line a→b, negative behind it (block side) [m]."""
    lx = bx - ax
    ly = by - ay
    ln = math.hypot(lx, ly)
    return ((qx - ax) * ly - (qy - ay) * lx) / ln


@njit(cache=True)
def _neighbour_rule(q1x, q1y, q2x, q2y, ax, ay, bx, by, g1, g2, lim):
    """Clip the zone to slave points behind the neighbouring facet a→b and no nearer to
    the master facet's line than to its line (g ≥ h); False if the zone empties."""
    h1 = _gap_line(q1x, q1y, ax, ay, bx, by)
    h2 = _gap_line(q2x, q2y, ax, ay, bx, by)
    if not _clip(-h1, -(h2 - h1), lim):
        return False
    return _clip(g1 - h1, (g2 - h2) - (g1 - h1), lim)


@njit(cache=True)
def _zone(q1x, q1y, q2x, q2y, p0x, p0y, p1x, p1y, p2x, p2y, p3x, p3y, depth, shift, out):
    """Contact zone of slave segment q1→q2 on master facet p1→p2 (see module doc).

    p0→p1 and p2→p3 are the master's neighbouring facets. A slave point is in the zone
    when it lies behind the master facet (gap g + shift ≤ 0, g ≥ −depth), projects onto
    it, faces it, and — at a convex vertex — is also behind the neighbouring facet and no
    closer to it than to the master facet (so a point near a corner is assigned to the
    facet it is nearest to, and points under another face of the block are not counted).
    All conditions are linear in the slave parameter s, so the zone is an interval
    [s0, s1] found exactly.

    out: [s0, s1, zone length, active, largest penetration −g]; active = 0 when empty.
    """
    out[Z_ACTIVE] = 0.0
    lm = math.hypot(p2x - p1x, p2y - p1y)
    ls = math.hypot(q2x - q1x, q2y - q1y)
    if lm <= 0.0 or ls <= 0.0:
        return
    tx = (p2x - p1x) / lm
    ty = (p2y - p1y) / lm
    # the slave must face the master: outward normals opposed
    if (q2y - q1y) * ty + (q2x - q1x) * tx >= 0.0:
        return
    lim = out  # s0, s1 live in out[0], out[1] (Z_S0, Z_S1)
    lim[Z_S0] = 0.0
    lim[Z_S1] = 1.0
    xi1 = (q1x - p1x) * tx + (q1y - p1y) * ty
    xi2 = (q2x - p1x) * tx + (q2y - p1y) * ty
    g1 = _gap_line(q1x, q1y, p1x, p1y, p2x, p2y)
    g2 = _gap_line(q2x, q2y, p1x, p1y, p2x, p2y)
    if not _clip(xi1, xi2 - xi1, lim):
        return
    if not _clip(lm - xi1, -(xi2 - xi1), lim):
        return
    if not _clip(-(g1 + shift), -(g2 - g1), lim):
        return
    if not _clip(depth + g1, g2 - g1, lim):
        return
    # at a convex vertex (a left turn), the neighbouring facet's rule applies too; a
    # straight vertex (turn below CONVEX) is not a corner: there the two lines coincide
    # and "nearer to which facet" would be decided by round-off, switching the zone on
    # and off (seen: dynamic relaxation of an arch cycling for ever at a springing)
    l0 = math.hypot(p1x - p0x, p1y - p0y)
    if ((p1x - p0x) * (p2y - p1y) - (p1y - p0y) * (p2x - p1x)) > CONVEX * l0 * lm:
        if not _neighbour_rule(q1x, q1y, q2x, q2y, p0x, p0y, p1x, p1y, g1, g2, lim):
            return
    l3 = math.hypot(p3x - p2x, p3y - p2y)
    if ((p2x - p1x) * (p3y - p2y) - (p2y - p1y) * (p3x - p2x)) > CONVEX * lm * l3:
        if not _neighbour_rule(q1x, q1y, q2x, q2y, p2x, p2y, p3x, p3y, g1, g2, lim):
            return
    out[Z_LEN] = (lim[Z_S1] - lim[Z_S0]) * ls
    out[Z_PEN] = -min(g1 + lim[Z_S0] * (g2 - g1), g1 + lim[Z_S1] * (g2 - g1))
    out[Z_ACTIVE] = 1.0


@njit(cache=True)
def _pass_zone(X, u, facets, fprev, fnext, fs, fm, depth, shift, work):
    """Zone of slave facet fs on master facet fm; returns the four facet end points
    relative to the reference position of the master's first node."""
    ox = X[facets[fm, 0], 0]
    oy = X[facets[fm, 0], 1]
    q1x, q1y = _pos(X, u, facets[fs, 0], ox, oy)
    q2x, q2y = _pos(X, u, facets[fs, 1], ox, oy)
    p1x, p1y = _pos(X, u, facets[fm, 0], ox, oy)
    p2x, p2y = _pos(X, u, facets[fm, 1], ox, oy)
    p0x, p0y = _pos(X, u, facets[fprev[fm], 0], ox, oy)
    p3x, p3y = _pos(X, u, facets[fnext[fm], 1], ox, oy)
    _zone(q1x, q1y, q2x, q2y, p0x, p0y, p1x, p1y, p2x, p2y, p3x, p3y, depth, shift, work)
    return q1x, q1y, q2x, q2y, p1x, p1y, p2x, p2y


@njit(cache=True)
def _pair_forces(k, X, u, v, facets, fprev, fnext, pairs, eps_n, eps_t, mu, hyst, depth,
                 width, dt, tau, pmax, f, work, stick):
    """Forces of candidate pair ``k`` added into ``f`` (see :func:`facet_facet_forces`).

    ``stick``: no Coulomb return (the tangent at the apex of the friction cone, below).

    Returns (normal penalty energy, tangential elastic energy, frictional dissipation
    [J], whether a pass is active, the largest penetration of an active pass [m], −1 if
    none).
    """
    e_n = 0.0
    e_t = 0.0
    d_f = 0.0
    active = False
    apex = -1.0
    fa = pairs[k, 0]
    fb = pairs[k, 1]
    # cheap rejection: facets whose boxes are further apart than the largest
    # penetration considered cannot be in contact
    ox = X[facets[fa, 0], 0]
    oy = X[facets[fa, 0], 1]
    ax1, ay1 = _pos(X, u, facets[fa, 0], ox, oy)
    ax2, ay2 = _pos(X, u, facets[fa, 1], ox, oy)
    bx1, by1 = _pos(X, u, facets[fb, 0], ox, oy)
    bx2, by2 = _pos(X, u, facets[fb, 1], ox, oy)
    dk = depth[k]
    if (min(ax1, ax2) > max(bx1, bx2) + dk or min(bx1, bx2) > max(ax1, ax2) + dk
            or min(ay1, ay2) > max(by1, by2) + dk or min(by1, by2) > max(ay1, ay2) + dk):
        tau[k, 0] = 0.0
        tau[k, 1] = 0.0
        pmax[k, 0] = 0.0
        pmax[k, 1] = 0.0
        return e_n, e_t, d_f, active, apex
    for p in range(2):
        fs = fb if p == 0 else fa
        fm = fa if p == 0 else fb
        s1n = facets[fs, 0]
        s2n = facets[fs, 1]
        m1n = facets[fm, 0]
        m2n = facets[fm, 1]
        q1x, q1y, q2x, q2y, p1x, p1y, p2x, p2y = _pass_zone(
            X, u, facets, fprev, fnext, fs, fm, depth[k], 0.0, work
        )
        if work[Z_ACTIVE] == 0.0:  # separated: the impact is over
            tau[k, p] = 0.0
            pmax[k, p] = 0.0
            continue
        shift = 0.0
        if hyst[k] > 0.0:
            pen = work[Z_PEN]
            if pen > pmax[k, p]:
                pmax[k, p] = pen  # loading
            else:
                shift = (pmax[k, p] - pen) * hyst[k]  # unloading
                _pass_zone(X, u, facets, fprev, fnext, fs, fm, depth[k], shift, work)
                if work[Z_ACTIVE] == 0.0:
                    tau[k, p] = 0.0
                    continue
        active = True
        s0 = work[Z_S0]
        s1 = work[Z_S1]
        zlen = work[Z_LEN]
        lm = math.hypot(p2x - p1x, p2y - p1y)
        tx = (p2x - p1x) / lm
        ty = (p2y - p1y) / lm
        nx = ty
        ny = -tx
        # each pass carries half of the pair's traction, faded out smoothly as the two
        # facets turn from facing each other (within FACING of anti-parallel) to
        # perpendicular, so a pass never switches on or off with a jump in force
        ls = math.hypot(q2x - q1x, q2y - q1y)
        cosf = ((q2x - q1x) * tx + (q2y - q1y) * ty) / ls  # < 0 when facing
        half = 0.5 * min(1.0, -cosf / FACING)
        # --- normal: exact integration of eps_n (−g − shift) N_i over the zone
        fs1 = 0.0  # slave node 1, 2 normal force magnitudes (along +n_m)
        fs2 = 0.0
        fm1 = 0.0  # master node 1, 2
        fm2 = 0.0
        pot = 0.0
        pbar = 0.0
        for gp in range(2):
            s = 0.5 * (s0 + s1) + (GAUSS if gp == 0 else -GAUSS) * (s1 - s0)
            qx = q1x + s * (q2x - q1x)
            qy = q1y + s * (q2y - q1y)
            g = (qx - p1x) * nx + (qy - p1y) * ny + shift
            xi = ((qx - p1x) * tx + (qy - p1y) * ty) / lm
            wgt = 0.5 * zlen * width * half  # Gauss weight x length x width x pass
            tr = -eps_n[k] * g  # >= 0
            fs1 += wgt * tr * (1.0 - s)
            fs2 += wgt * tr * s
            fm1 += wgt * tr * (1.0 - xi)
            fm2 += wgt * tr * xi
            pot += wgt * 0.5 * eps_n[k] * g * g
            pbar += 0.5 * tr
        # --- relative tangential velocity at the zone centre
        sc = 0.5 * (s0 + s1)
        qcx = q1x + sc * (q2x - q1x)
        qcy = q1y + sc * (q2y - q1y)
        xic = ((qcx - p1x) * tx + (qcy - p1y) * ty) / lm
        vt = ((1.0 - sc) * v[2 * s1n] + sc * v[2 * s2n]
              - (1.0 - xic) * v[2 * m1n] - xic * v[2 * m2n]) * tx + (
            (1.0 - sc) * v[2 * s1n + 1] + sc * v[2 * s2n + 1]
            - (1.0 - xic) * v[2 * m1n + 1] - xic * v[2 * m2n + 1]) * ty
        # --- friction: elastic predictor, Coulomb return on the mean normal traction
        t_trial = tau[k, p] + eps_t[k] * vt * dt
        t_max = mu[k] * pbar
        apex = max(apex, work[Z_PEN])
        if abs(t_trial) > t_max and not stick:
            t_new = t_max if t_trial > 0.0 else -t_max
            d_f += t_max * (abs(t_trial) - t_max) / eps_t[k] * zlen * width * half
        else:
            t_new = t_trial
        tau[k, p] = t_new
        e_t += 0.5 * t_new * t_new / eps_t[k] * zlen * width * half
        e_n += pot
        # friction traction, uniform over the zone, opposes the slave's slip
        a = zlen * width * half * t_new
        f[2 * s1n] += fs1 * nx - (1.0 - sc) * a * tx
        f[2 * s1n + 1] += fs1 * ny - (1.0 - sc) * a * ty
        f[2 * s2n] += fs2 * nx - sc * a * tx
        f[2 * s2n + 1] += fs2 * ny - sc * a * ty
        f[2 * m1n] -= fm1 * nx - (1.0 - xic) * a * tx
        f[2 * m1n + 1] -= fm1 * ny - (1.0 - xic) * a * ty
        f[2 * m2n] -= fm2 * nx - xic * a * tx
        f[2 * m2n + 1] -= fm2 * ny - xic * a * ty
    return e_n, e_t, d_f, active, apex


@njit(cache=True)
def facet_facet_forces(X, u, v, facets, fprev, fnext, pairs, eps_n, eps_t, mu, hyst, depth,
                       width, dt, tau, pmax, f, energy, work):
    """Penalty normal and Coulomb friction forces of all candidate pairs.

    Args:
        eps_n, eps_t, mu, depth: (n_p,) normal and tangential penalty [Pa/m], friction
            coefficient and largest penetration considered [m] of each pair.
        hyst: (n_p,) 1/e² − 1 from the restitution coefficient e (0: elastic).
        width: out-of-plane width [m].
        dt: time step [s] (tangential slip increment = relative velocity · dt).
        tau: (n_p, 2) in/out tangential traction history [Pa] of the two passes.
        pmax: (n_p, 2) in/out largest penetration [m] of the current impact of each pass.
        f: (2 n_nodes,) out, contact forces are ADDED [N].
        energy: (3,) out: [normal penalty energy, tangential elastic energy,
            frictional dissipation this step] [J].
        work: (N_WORK,) scratch.
    """
    e_n = 0.0
    e_t = 0.0
    d_f = 0.0
    for k in range(pairs.shape[0]):
        a, b, c, _, _ = _pair_forces(k, X, u, v, facets, fprev, fnext, pairs, eps_n, eps_t,
                                     mu, hyst, depth, width, dt, tau, pmax, f, work, False)
        e_n += a
        e_t += b
        d_f += c
    energy[0] = e_n
    energy[1] = e_t
    energy[2] = d_f


@njit(cache=True)
def facet_facet_tangent(X, u, v, facets, fprev, fnext, pairs, eps_n, eps_t, mu, hyst, depth,
                        width, tau_c, pmax_c, tau, pmax, h, fbuf, work, rows, cols, vals):
    """Consistent tangent −∂f/∂u of the pairs in contact, by central differences of
    :func:`_pair_forces` in each dof the pair's force depends on (its two facets' nodes
    and, through the corner rules, the far nodes of their neighbouring facets).

    Static solver convention: ``v`` is the displacement since the last commit (dt = 1),
    so a perturbation of u perturbs v alike, and each evaluation starts from the
    committed history ``tau_c``, ``pmax_c``; ``tau``, ``pmax`` are left as they were.
    ``fbuf`` (2 n) must be zero on entry and is zero on exit.

    At the apex of the friction cone — facets touching with no normal traction, as the
    joints of a dry structure at its unloaded start — the force is not differentiable:
    any slip slides, so the one-sided derivatives give no shear stiffness and the
    tangent of a structure on such joints is singular. There the tangent takes the stick
    branch, the limit of the tangents of the nearby compressed states that stick (an
    element of Clarke's generalised Jacobian, as a semismooth Newton method allows).

    Returns the number of COO entries written into ``rows``, ``cols`` (local extended dof
    numbers) and ``vals`` (each needs 128 entries per pair).
    """
    nodes = np.empty(8, dtype=np.int64)
    fp = np.empty(8)
    nent = 0
    for k in range(pairs.shape[0]):
        t0 = tau[k, 0]
        t1 = tau[k, 1]
        q0 = pmax[k, 0]
        q1 = pmax[k, 1]
        tau[k, 0] = tau_c[k, 0]
        tau[k, 1] = tau_c[k, 1]
        pmax[k, 0] = pmax_c[k, 0]
        pmax[k, 1] = pmax_c[k, 1]
        _, _, _, active, apex = _pair_forces(k, X, u, v, facets, fprev, fnext, pairs,
                                             eps_n, eps_t, mu, hyst, depth, width, 1.0, tau,
                                             pmax, fbuf, work, False)
        fa = pairs[k, 0]
        fb = pairs[k, 1]
        nodes[0] = facets[fa, 0]
        nodes[1] = facets[fa, 1]
        nodes[2] = facets[fb, 0]
        nodes[3] = facets[fb, 1]
        for j in range(4):
            fbuf[2 * nodes[j]] = 0.0
            fbuf[2 * nodes[j] + 1] = 0.0
        # a pair out of reach of the perturbations has no tangent; one that is not in
        # contact but within reach (touching, up to round-off) is treated as at the apex
        ox = X[nodes[0], 0]
        oy = X[nodes[0], 1]
        ax1, ay1 = _pos(X, u, nodes[0], ox, oy)
        ax2, ay2 = _pos(X, u, nodes[1], ox, oy)
        bx1, by1 = _pos(X, u, nodes[2], ox, oy)
        bx2, by2 = _pos(X, u, nodes[3], ox, oy)
        dk = depth[k] + 4.0 * h
        near = not (min(ax1, ax2) > max(bx1, bx2) + dk or min(bx1, bx2) > max(ax1, ax2) + dk
                    or min(ay1, ay2) > max(by1, by2) + dk
                    or min(by1, by2) > max(ay1, ay2) + dk)
        stick = apex < 2.0 * h  # touching within the step, or not touching
        if near:
            nodes[4] = facets[fprev[fa], 0]
            nodes[5] = facets[fnext[fa], 1]
            nodes[6] = facets[fprev[fb], 0]
            nodes[7] = facets[fnext[fb], 1]
            nn = 4
            for j in range(4, 8):  # the distinct far nodes
                dup = False
                for i in range(nn):
                    if nodes[i] == nodes[j]:
                        dup = True
                if not dup:
                    nodes[nn] = nodes[j]
                    nn += 1
            for jc in range(nn):
                for c in range(2):
                    d = 2 * nodes[jc] + c
                    u0 = u[d]
                    v0 = v[d]
                    for side in range(2):
                        sg = 1.0 if side == 0 else -1.0
                        u[d] = u0 + sg * h
                        v[d] = v0 + sg * h
                        tau[k, 0] = tau_c[k, 0]
                        tau[k, 1] = tau_c[k, 1]
                        pmax[k, 0] = pmax_c[k, 0]
                        pmax[k, 1] = pmax_c[k, 1]
                        _pair_forces(k, X, u, v, facets, fprev, fnext, pairs, eps_n, eps_t,
                                     mu, hyst, depth, width, 1.0, tau, pmax, fbuf, work, stick)
                        for i in range(4):
                            for ci in range(2):
                                di = 2 * nodes[i] + ci
                                if side == 0:
                                    fp[2 * i + ci] = fbuf[di]
                                else:
                                    fp[2 * i + ci] -= fbuf[di]
                                fbuf[di] = 0.0
                    u[d] = u0
                    v[d] = v0
                    for i in range(4):
                        for ci in range(2):
                            rows[nent] = 2 * nodes[i] + ci
                            cols[nent] = d
                            vals[nent] = -fp[2 * i + ci] / (2.0 * h)
                            nent += 1
        tau[k, 0] = t0
        tau[k, 1] = t1
        pmax[k, 0] = q0
        pmax[k, 1] = q1
    return nent


def precompile() -> None:
    """Compile the facet–facet kernel on a unit square facing itself."""
    X = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    u = np.zeros(8)
    facets = np.array([[0, 1], [1, 2], [2, 3], [3, 0]], dtype=np.int64)
    fnext = np.array([1, 2, 3, 0], dtype=np.int64)
    fprev = np.array([3, 0, 1, 2], dtype=np.int64)
    p1 = np.ones(1)
    facet_facet_forces(X, u, u, facets, fprev, fnext, np.array([[0, 2]], dtype=np.int64), p1,
                       p1, p1, p1, p1, 1.0, 1e-3, np.zeros((1, 2)), np.zeros((1, 2)),
                       np.zeros(8), np.zeros(3), np.zeros(N_WORK))
    z = np.zeros((1, 2))
    facet_facet_tangent(X, u, u.copy(), facets, fprev, fnext, np.array([[0, 2]], dtype=np.int64),
                        p1, p1, p1, p1, p1, 1.0, z, z.copy(), z.copy(), z.copy(), 1e-6,
                        np.zeros(8), np.zeros(N_WORK), np.zeros(128, dtype=np.int64),
                        np.zeros(128, dtype=np.int64), np.zeros(128))
