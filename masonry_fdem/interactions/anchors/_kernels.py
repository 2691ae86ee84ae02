"""Numba kernels of the embedded anchors (flat arrays, no allocation per call).

Conventions (see :mod:`masonry_fdem.interactions.anchors`): anchor node ``i`` has displacement
``ua[2i:2i+2]`` [m] and reference position ``xa[i]``; bar element ``e`` joins nodes
``conn[e, 0] → conn[e, 1]``. Forces are accumulated (``+=``) into the output arrays.

Element columns of ``ep`` (one row per bar element, ``count`` bars in the row):

* ``EP_AREA`` total steel area count·A [m²], ``EP_E`` Young's modulus [Pa],
  ``EP_FY`` yield stress [Pa], ``EP_H`` linear isotropic hardening modulus [Pa],
  ``EP_EPSU`` rupture strain [-], ``EP_JACK`` jacking force of the row [N].

Element state columns (committed ``es`` / trial ``et``): ``ES_EPSP`` plastic strain,
``ES_ALPHA`` accumulated plastic strain, ``ES_RUPT`` 1 once ruptured.

Bond points are the halves of the bonded bar elements (node ``hnode[h]`` of element
``helem[h]``, tributary length ℓ = L_e/2, host triangle of the block holding that half).
Their columns of ``npr``: ``NP_BOND`` bond area count·perimeter·ℓ [m²], ``NP_KT``
transverse (dowel) stiffness count·k_t·ℓ [N/m], ``NP_QY`` dowel strength count·q_y·ℓ
[N], ``NP_KP`` end-plate stiffness count·k_p [N/m], ``NP_PLATE`` +1 start plate, -1 end plate,
0 none, ``NP_LAW`` bond law index, ``NP_BONDED`` 1 if the bond acts (0 while jacking).

Bond-point state columns (``ns`` / ``nt``): ``NS_SP`` plastic slip [m], ``NS_KAPPA``
accumulated plastic slip [m], ``NS_WP`` plastic transverse displacement [m].

Bond-point output columns (``out``): ``NO_SLIP`` [m], ``NO_TAU`` bond stress [Pa], ``NO_W``
transverse relative displacement [m], ``NO_Q`` transverse force [N], ``NO_PLATE`` plate
force [N].

Joint dowels (:class:`~masonry_fdem.interactions.anchors.laws.JointDowel`): crossing ``c``
is bar element ``celem[c]`` bridging a joint, with the material point of the crossing in
each of the two blocks (side 0 and 1: host nodes ``chost[c, s]``, local numbers, −1 where
the block is another rank's; weights ``chw[c, s]``; shape-function gradients
``cgrad[c, s, m]`` = (∂N/∂x, ∂N/∂y) of the host triangle). ``uc[c]`` holds the two
material points' displacements and the host triangles' rotations ω = ½(∂u_y/∂x −
∂u_x/∂y) (side 0 x, y, side 1 x, y, ω0, ω1; summed over ranks). The bar's normal turns
with the blocks: n = R(θ) n0, θ = (ω0 + ω1)/2, n0 the reference normal ``cn0[c]`` (not
with the bridging element, whose chord would turn by slip/ℓ, ℓ a mesh length). The slip
across the bar w = (u₁ − u₀)·n; the force q = K (w − w_p) up to ±Q_y (``cprop[c]`` =
count·K [N/m], count·Q_y [N]), +q n on side 0 and −q n on side 1. A bar still jacked
(ungrouted) has no dowel: q = 0, w_p follows w. Committed plastic slip ``cw``, trial
``cwt``; outputs ``cout`` (``CO_W`` slip [m], ``CO_Q`` force [N], ``CO_PLASTIC`` 1 on
the plateau or jacked, ``CO_NX``, ``CO_NY`` the normal, ``CO_DT`` the relative
displacement along the bar [m]). Its tangent is analytic (:func:`dowel_tangent`), the
turning normal included.

Consistent tangent (static Newton solver): a numerical algorithmic tangent (Miehe 1996,
"Numerical computation of algorithmic (consistent) tangent moduli in large-strain
computational inelasticity", CMAME 134). :func:`bar_element` and :func:`bond_point` are
the one kernel of a bar element's and of a bond point's forces; :func:`bar_forces` and
:func:`bond_forces` sum them, :func:`bar_tangent` and :func:`bond_tangent` differentiate
them by central differences in each of the item's dofs (a bar: its 2 nodes; a bond
point: both nodes of its bar element, on which the bar direction depends, and its 3 host
nodes), every evaluation returning from the committed state as the forces do, into
scratch rows (the trial state is left as it is). Force and tangent thus come from the
same discrete laws — steel return with hardening and rupture, bond envelope with plastic
slip, dowel, plates, the turning bar — and cannot drift apart.

The step is h = FD_STEP · L0 of the item's bar element (FD_STEP = 1e-8: h = 2e-10 m on a
2 cm element; FD_STEP · |u| for a dof displaced by more than L0, so that u ± h never rounds
back to u); the perturbation actually applied, (u + h) − (u − h) in floating point, is
the divisor. Within one branch the laws are linear in the slip and strain, so the error
is the truncation of the geometry, (h/L0)², nil, and round-off: strains and relative
displacements are formed from displacements alone (no X + u cancellation), so it is
relative ~ε·|u|/h ~1e-9. Measured against central differences of the assembled forces
(tests/test_tangent_joints_anchors.py): ~1e-9 of the largest entry, elastic, yielding,
on the bond plateau and softening branch. An item closer than h to a kink (yield, the
envelope's corners, a plate touching) gets a blend of the two branches' tangents there.
"""

import math

import numpy as np
from numba import njit

EP_AREA, EP_E, EP_FY, EP_H, EP_EPSU, EP_JACK = range(6)
N_EP = 6
ES_EPSP, ES_ALPHA, ES_RUPT = range(3)
N_ES = 3
NP_BOND, NP_KT, NP_QY, NP_KP, NP_PLATE, NP_LAW, NP_BONDED = range(7)
N_NP = 7
NS_SP, NS_KAPPA, NS_WP = range(3)
N_NS = 3
NO_SLIP, NO_TAU, NO_W, NO_Q, NO_PLATE = range(5)
N_NO = 5
CO_W, CO_Q, CO_PLASTIC, CO_NX, CO_NY, CO_DT = range(6)
N_CO = 6

#: finite-difference step of the tangents, as a fraction of the bar element's length L0
#: (see the module doc)
FD_STEP = 1e-8


@njit(cache=True)
def envelope(law_s, law_t, nk, s):
    """Bond stress on the monotonic envelope at slip ``s`` >= 0 [Pa]: piecewise linear
    through (0, 0) and the ``nk`` table points; constant beyond the last point."""
    s0 = 0.0
    t0 = 0.0
    for k in range(nk):
        s1 = law_s[k]
        t1 = law_t[k]
        if s <= s1:
            return t0 + (t1 - t0) * (s - s0) / (s1 - s0)
        s0 = s1
        t0 = t1
    return t0


@njit(cache=True)
def bond_return(law_s, law_t, nk, k0, s, sp, kappa, res):
    """Bond stress at total slip ``s`` from the committed plastic slip ``sp`` and
    accumulated plastic slip ``kappa`` (elastic unloading with the initial stiffness
    ``k0``, loading on the envelope). res = (tau, sp_new, kappa_new).

    On the envelope the envelope coordinate is s_e = kappa + |tau|/k0; for a trial stress
    tau_tr = k0 (s - sp) it is s_e = kappa + |tau_tr|/k0, so the return is closed-form.
    Requires every envelope slope <= k0 (checked when the law is made).
    """
    ttr = k0 * (s - sp)
    a = abs(ttr)
    se = kappa + a / k0
    env = envelope(law_s, law_t, nk, se)
    if env >= a:
        res[0] = ttr
        res[1] = sp
        res[2] = kappa
        return
    sg = 1.0 if ttr >= 0.0 else -1.0
    tau = sg * env
    res[0] = tau
    res[1] = s - tau / k0
    res[2] = se - env / k0


@njit(cache=True)
def steel_return(eps, E, fy, H, epsu, epsp, alpha, rupt, res):
    """Uniaxial elasto-plastic steel with linear isotropic hardening and rupture.

    res = (stress [Pa], epsp, alpha, ruptured). A bar whose strain reaches ``epsu`` in
    tension ruptures and carries nothing from then on.
    """
    if rupt > 0.5 or eps >= epsu:
        res[0] = 0.0
        res[1] = epsp
        res[2] = alpha
        res[3] = 1.0
        return
    sig = E * (eps - epsp)
    f = abs(sig) - (fy + H * alpha)
    if f > 0.0:
        dg = f / (E + H)
        sg = 1.0 if sig >= 0.0 else -1.0
        sig -= sg * E * dg
        epsp += sg * dg
        alpha += dg
    res[0] = sig
    res[1] = epsp
    res[2] = alpha
    res[3] = 0.0


@njit(cache=True)
def bar_element(xa, ua, conn, L0, ep, jacking, es, e, et_e, res):
    """Axial force of bar element ``e``: the single source of its forces and tangent.

    Writes the trial state into ``et_e`` (N_ES,) (``res``: (4,) scratch). Returns
    (axial force N [N], strain, fx, fy, has_length): the force (fx, fy) [N] on its first
    node, the opposite one on its second (both 0 for an element of zero length).
    """
    a = conn[e, 0]
    b = conn[e, 1]
    X0 = xa[b, 0] - xa[a, 0]
    Y0 = xa[b, 1] - xa[a, 1]
    du = ua[2 * b] - ua[2 * a]
    dv = ua[2 * b + 1] - ua[2 * a + 1]
    dx = X0 + du
    dy = Y0 + dv
    ell = math.sqrt(dx * dx + dy * dy)
    # ℓ − L0 = (ℓ² − L0²)/(ℓ + L0), free of the cancellation of ℓ − L0 for a stiff bar
    eps = (2.0 * (X0 * du + Y0 * dv) + du * du + dv * dv) / ((ell + L0[e]) * L0[e])
    if jacking[e]:
        n = ep[e, EP_JACK]
        et_e[ES_EPSP] = es[e, ES_EPSP]
        et_e[ES_ALPHA] = es[e, ES_ALPHA]
        et_e[ES_RUPT] = es[e, ES_RUPT]
    else:
        steel_return(eps, ep[e, EP_E], ep[e, EP_FY], ep[e, EP_H], ep[e, EP_EPSU],
                     es[e, ES_EPSP], es[e, ES_ALPHA], es[e, ES_RUPT], res)
        n = res[0] * ep[e, EP_AREA]
        et_e[ES_EPSP] = res[1]
        et_e[ES_ALPHA] = res[2]
        et_e[ES_RUPT] = res[3]
    fx = 0.0
    fy = 0.0
    if ell > 0.0:
        fx = n * dx / ell
        fy = n * dy / ell
    return n, eps, fx, fy, ell > 0.0


@njit(cache=True)
def bar_forces(xa, ua, conn, L0, ep, jacking, es, et, axial, strain, fa):
    """Axial forces of the bar elements at the current node positions into ``fa`` (+=);
    trial element state into ``et``; row axial force [N] and strain into ``axial``,
    ``strain``. A jacking element carries its jacking force whatever its length."""
    res = np.empty(4)
    for e in range(conn.shape[0]):
        n, eps, fx, fy, ok = bar_element(xa, ua, conn, L0, ep, jacking, es, e, et[e], res)
        strain[e] = eps
        axial[e] = n
        if ok:
            a = conn[e, 0]
            b = conn[e, 1]
            fa[2 * a] += fx
            fa[2 * a + 1] += fy
            fa[2 * b] -= fx
            fa[2 * b + 1] -= fy


@njit(cache=True)
def bar_tangent(xa, ua, conn, L0, ep, jacking, es, rel_step, rows, cols, vals):
    """Consistent tangent −∂f/∂u_a [N/m] of the bar elements, by central differences of
    :func:`bar_element` (the force kernel itself) in each of an element's 4 dofs; each
    evaluation returns from the committed state ``es`` into a scratch row (the trial
    state of :func:`bar_forces` is left as it is). Step: ``rel_step`` × L0 of the element
    (× |u| if larger).

    Returns the number of COO entries written into ``rows``, ``cols`` (anchor dof
    numbers) and ``vals`` (16 per element).
    """
    uw = ua.copy()
    res = np.empty(4)
    scratch = np.empty(N_ES)
    dofs = np.empty(4, dtype=np.int64)
    nent = 0
    for e in range(conn.shape[0]):
        dofs[0] = 2 * conn[e, 0]
        dofs[1] = dofs[0] + 1
        dofs[2] = 2 * conn[e, 1]
        dofs[3] = dofs[2] + 1
        h = rel_step * L0[e]
        _, _, fx0, fy0, _ = bar_element(xa, uw, conn, L0, ep, jacking, es, e, scratch, res)
        b0 = _bar_branch(es[e], scratch)
        for j in range(4):
            k = dofs[j]
            u0 = uw[k]
            hk = max(h, rel_step * abs(u0))  # never lost in the round-off of u0 ± h
            up = u0 + hk
            um = u0 - hk
            uw[k] = up
            _, _, fxp, fyp, _ = bar_element(xa, uw, conn, L0, ep, jacking, es, e, scratch, res)
            bp = _bar_branch(es[e], scratch)
            uw[k] = um
            _, _, fxm, fym, _ = bar_element(xa, uw, conn, L0, ep, jacking, es, e, scratch, res)
            bm = _bar_branch(es[e], scratch)
            uw[k] = u0
            # one-sided on the element's own branch where a step crosses yield
            if bp == b0 and bm != b0:
                fxm, fym, um = fx0, fy0, u0
            elif bm == b0 and bp != b0:
                fxp, fyp, up = fx0, fy0, u0
            den = up - um
            gx = -(fxp - fxm) / den
            gy = -(fyp - fym) / den
            for i in range(4):
                rows[nent + i] = dofs[i]
                cols[nent + i] = k
            vals[nent] = gx
            vals[nent + 1] = gy
            vals[nent + 2] = -gx
            vals[nent + 3] = -gy
            nent += 4
    return nent


@njit(cache=True)
def element_tangent(xa, ua, conn, e, t):
    """Unit vector of bar element ``e`` from its first to its second node (current)."""
    a = conn[e, 0]
    b = conn[e, 1]
    dx = xa[b, 0] + ua[2 * b] - xa[a, 0] - ua[2 * a]
    dy = xa[b, 1] + ua[2 * b + 1] - xa[a, 1] - ua[2 * a + 1]
    ell = math.sqrt(dx * dx + dy * dy)
    if ell == 0.0:
        t[0] = 1.0
        t[1] = 0.0
    else:
        t[0] = dx / ell
        t[1] = dy / ell


@njit(cache=True)
def relative_displacement(ua, ub, hnode, hosts, hw, h, d):
    """Displacement of the bar node of bond point ``h`` relative to its host material
    point [m]."""
    hx = 0.0
    hy = 0.0
    for k in range(3):
        j = hosts[h, k]
        hx += hw[h, k] * ub[2 * j]
        hy += hw[h, k] * ub[2 * j + 1]
    i = hnode[h]
    d[0] = ua[2 * i] - hx
    d[1] = ua[2 * i + 1] - hy


@njit(cache=True)
def bond_point(xa, ua, ub, conn, hnode, helem, hosts, hw, npr, laws_s, laws_t, laws_n,
               laws_k0, dref, ns, h, nt_h, out_h, t, d, res):
    """Bond, dowel and plate force of bond point ``h`` (with a local host): the single
    source of its forces and tangent.

    Writes its trial state into ``nt_h`` (N_NS,) and its outputs into ``out_h`` (N_NO,)
    (``t``, ``d``: (2,), ``res``: (3,) scratch). Returns the force (gx, gy) [N] on its bar
    node; its host triangle's nodes take −hw[h, k] (gx, gy).
    """
    element_tangent(xa, ua, conn, helem[h], t)
    relative_displacement(ua, ub, hnode, hosts, hw, h, d)
    nx = -t[1]
    ny = t[0]
    # bond along the bar
    s = (d[0] - dref[h, 0]) * t[0] + (d[1] - dref[h, 1]) * t[1]
    tau = 0.0
    if npr[h, NP_BONDED] > 0.5 and npr[h, NP_BOND] > 0.0:
        law = int(npr[h, NP_LAW])
        bond_return(laws_s[law], laws_t[law], laws_n[law], laws_k0[law], s,
                    ns[h, NS_SP], ns[h, NS_KAPPA], res)
        tau = res[0]
        nt_h[NS_SP] = res[1]
        nt_h[NS_KAPPA] = res[2]
    else:
        nt_h[NS_SP] = ns[h, NS_SP]
        nt_h[NS_KAPPA] = ns[h, NS_KAPPA]
    fs = -npr[h, NP_BOND] * tau  # along t, on the bar node
    # transverse tie (elastic, or elastic-perfectly plastic dowel)
    w = d[0] * nx + d[1] * ny
    q = 0.0
    wp = ns[h, NS_WP]
    kt = npr[h, NP_KT]
    if kt > 0.0:
        q = kt * (w - wp)
        qy = npr[h, NP_QY]
        if abs(q) > qy:
            q = qy if q > 0.0 else -qy
            wp = w - q / kt
    nt_h[NS_WP] = wp
    # end plate: bears when the bar pulls its end into the block
    fp = 0.0
    side = npr[h, NP_PLATE]
    if side != 0.0:
        sp = d[0] * t[0] + d[1] * t[1]
        if side * sp > 0.0:
            fp = npr[h, NP_KP] * sp
    gx = (fs - fp) * t[0] - q * nx
    gy = (fs - fp) * t[1] - q * ny
    out_h[NO_SLIP] = s
    out_h[NO_TAU] = tau
    out_h[NO_W] = w
    out_h[NO_Q] = q
    out_h[NO_PLATE] = fp
    return gx, gy


@njit(cache=True)
def bond_forces(xa, ua, ub, conn, hnode, helem, hosts, hw, npr, laws_s, laws_t, laws_n,
                laws_k0, dref, ns, nt, out, fa, fb):
    """Bond, dowel and end-plate forces of the bond points with a host on this rank.

    A bond point is one half of a bonded bar element: its bar node, the tributary half
    length, and the host triangle (of the block holding that half) in which the node
    lies. Slip s = (d − d_ref)·t and transverse displacement w = d·n, with d the
    displacement of the node relative to its host material point, t the element's unit
    vector and n = (−t_y, t_x). Forces on the bar node go to ``fa``, the opposite forces
    to the host triangle's nodes in ``fb`` (+=). Points without a local host
    (``hosts[h, 0] < 0``) are skipped and their outputs zeroed.
    """
    t = np.empty(2)
    d = np.empty(2)
    res = np.empty(3)
    for h in range(hnode.size):
        if hosts[h, 0] < 0:
            for c in range(out.shape[1]):
                out[h, c] = 0.0
            continue
        gx, gy = bond_point(xa, ua, ub, conn, hnode, helem, hosts, hw, npr, laws_s, laws_t,
                            laws_n, laws_k0, dref, ns, h, nt[h], out[h], t, d, res)
        i = hnode[h]
        fa[2 * i] += gx
        fa[2 * i + 1] += gy
        for k in range(3):
            j = hosts[h, k]
            fb[2 * j] -= hw[h, k] * gx
            fb[2 * j + 1] -= hw[h, k] * gy


@njit(cache=True)
def bond_tangent(xa, ua, ub, conn, L0, hnode, helem, hosts, hw, npr, laws_s, laws_t,
                 laws_n, laws_k0, dref, ns, rel_step, rows, cols, vals):
    """Consistent tangent −∂f/∂u [N/m] of the bond points with a local host, by central
    differences of :func:`bond_point` (the force kernel itself) in each of a point's 10
    dofs: both nodes of its bar element (the bar direction t depends on them, the bar
    node is one of them) and its 3 host nodes. Each evaluation returns from the
    committed state ``ns`` into scratch rows (the trial state and outputs of
    :func:`bond_forces` are left as they are). Step: ``rel_step`` × L0 of the element
    (× |u| if larger).

    Dof numbers of the output: anchor dof k → k, block dof j → ``ua.size + j``.
    Returns the number of COO entries written into ``rows``, ``cols`` and ``vals``
    (80 per point: 8 rows, the bar node's and the hosts', × 10 columns).
    """
    uw = ua.copy()
    bw = ub.copy()
    na = ua.size
    t = np.empty(2)
    d = np.empty(2)
    res = np.empty(3)
    nt_s = np.empty(N_NS)
    out_s = np.empty(N_NO)
    dofs = np.empty(10, dtype=np.int64)  # extended numbering: anchors, then blocks
    fl = np.empty(8)  # force differences on the bar node and the host nodes
    nent = 0
    for h in range(hnode.size):
        if hosts[h, 0] < 0:
            continue
        e = helem[h]
        dofs[0] = 2 * conn[e, 0]
        dofs[2] = 2 * conn[e, 1]
        dofs[4] = na + 2 * hosts[h, 0]
        dofs[6] = na + 2 * hosts[h, 1]
        dofs[8] = na + 2 * hosts[h, 2]
        for j in range(0, 10, 2):
            dofs[j + 1] = dofs[j] + 1
        i = hnode[h]
        step = rel_step * L0[e]
        gx0, gy0 = bond_point(xa, uw, bw, conn, hnode, helem, hosts, hw, npr, laws_s,
                              laws_t, laws_n, laws_k0, dref, ns, h, nt_s, out_s, t, d, res)
        b0 = _bond_branch(ns[h], nt_s, out_s)
        for j in range(10):
            k = dofs[j]
            arr = uw if k < na else bw
            kk = k if k < na else k - na
            u0 = arr[kk]
            hk = max(step, rel_step * abs(u0))  # never lost in the round-off of u0 ± h
            up = u0 + hk
            um = u0 - hk
            arr[kk] = up
            gxp, gyp = bond_point(xa, uw, bw, conn, hnode, helem, hosts, hw, npr, laws_s,
                                  laws_t, laws_n, laws_k0, dref, ns, h, nt_s, out_s, t, d,
                                  res)
            bp = _bond_branch(ns[h], nt_s, out_s)
            arr[kk] = um
            gxm, gym = bond_point(xa, uw, bw, conn, hnode, helem, hosts, hw, npr, laws_s,
                                  laws_t, laws_n, laws_k0, dref, ns, h, nt_s, out_s, t, d,
                                  res)
            bm = _bond_branch(ns[h], nt_s, out_s)
            arr[kk] = u0
            # one-sided on the point's own branch where a step crosses a kink
            if bp == b0 and bm != b0:
                gxm, gym, um = gx0, gy0, u0
            elif bm == b0 and bp != b0:
                gxp, gyp, up = gx0, gy0, u0
            den = up - um
            gx = -(gxp - gxm) / den
            gy = -(gyp - gym) / den
            fl[0] = gx
            fl[1] = gy
            for m in range(3):
                fl[2 + 2 * m] = -hw[h, m] * gx
                fl[3 + 2 * m] = -hw[h, m] * gy
            rows[nent] = 2 * i
            rows[nent + 1] = 2 * i + 1
            for m in range(6):
                rows[nent + 2 + m] = dofs[4 + m]
            for m in range(8):
                cols[nent + m] = k
                vals[nent + m] = fl[m]
            nent += 8
    return nent


@njit(cache=True)
def _bar_branch(es_e, et_e):
    """1 if the trial state yielded (or ruptured) from the committed one, else 0."""
    return 1 if (et_e[ES_ALPHA] > es_e[ES_ALPHA] or et_e[ES_RUPT] != es_e[ES_RUPT]) else 0


@njit(cache=True)
def _bond_branch(ns_h, nt_h, out_h):
    """The branch of a bond point's laws (bits: bond slipping on its envelope, dowel
    yielding, end plate bearing)."""
    out = 0
    if nt_h[NS_KAPPA] > ns_h[NS_KAPPA]:
        out += 1
    if nt_h[NS_WP] != ns_h[NS_WP]:
        out += 2
    if out_h[NO_PLATE] != 0.0:
        out += 4
    return out


@njit(cache=True)
def relative_displacements(ua, ub, hnode, hosts, hw, d):
    """d[h] = displacement of bond point h's node relative to its host (local hosts)."""
    tmp = np.empty(2)
    for h in range(hosts.shape[0]):
        if hosts[h, 0] < 0:
            d[h, 0] = 0.0
            d[h, 1] = 0.0
            continue
        relative_displacement(ua, ub, hnode, hosts, hw, h, tmp)
        d[h, 0] = tmp[0]
        d[h, 1] = tmp[1]


@njit(cache=True)
def crossing_displacements(ub, chost, chw, cgrad, uc):
    """uc[c] = displacements of the crossing's material points and rotations of their host
    triangles on the local sides (0 on another rank's side)."""
    for c in range(chost.shape[0]):
        for s in range(2):
            ux = 0.0
            uy = 0.0
            om = 0.0
            if chost[c, s, 0] >= 0:
                for k in range(3):
                    j = chost[c, s, k]
                    ux += chw[c, s, k] * ub[2 * j]
                    uy += chw[c, s, k] * ub[2 * j + 1]
                    om += 0.5 * (cgrad[c, s, k, 0] * ub[2 * j + 1]
                                 - cgrad[c, s, k, 1] * ub[2 * j])
            uc[c, 2 * s] = ux
            uc[c, 2 * s + 1] = uy
            uc[c, 4 + s] = om


@njit(cache=True)
def dowel_forces(celem, jacking, cn0, uc, cprop, cw, cwt, cout, chost, chw, fb):
    """Joint dowel forces (see the module doc): trial plastic slips into ``cwt``, outputs
    into ``cout`` (every crossing), forces added to ``fb`` at the local sides' nodes."""
    for c in range(celem.shape[0]):
        th = 0.5 * (uc[c, 4] + uc[c, 5])
        cs = math.cos(th)
        sn = math.sin(th)
        nx = cs * cn0[c, 0] - sn * cn0[c, 1]
        ny = sn * cn0[c, 0] + cs * cn0[c, 1]
        dx = uc[c, 2] - uc[c, 0]
        dy = uc[c, 3] - uc[c, 1]
        w = dx * nx + dy * ny
        k = cprop[c, 0]
        qy = cprop[c, 1]
        wp = cw[c]
        q = k * (w - wp)
        plastic = 0.0
        if jacking[celem[c]]:  # ungrouted: no dowel, its slip counted from the grouting
            q = 0.0
            wp = w
            plastic = 1.0
        elif abs(q) > qy:
            q = qy if q > 0.0 else -qy
            wp = w - q / k
            plastic = 1.0
        cwt[c] = wp
        cout[c, CO_W] = w
        cout[c, CO_Q] = q
        cout[c, CO_PLASTIC] = plastic
        cout[c, CO_NX] = nx
        cout[c, CO_NY] = ny
        cout[c, CO_DT] = dx * ny - dy * nx
        for s in range(2):
            if chost[c, s, 0] < 0:
                continue
            sg = 1.0 if s == 0 else -1.0
            for m in range(3):
                j = chost[c, s, m]
                fb[2 * j] += sg * q * nx * chw[c, s, m]
                fb[2 * j + 1] += sg * q * ny * chw[c, s, m]


@njit(cache=True)
def dowel_tangent(cout, cprop, chost, chw, cgrad, glob, rows, cols, vals):
    """−∂f/∂u of the joint dowels, rows of the local sides' nodes, columns of both sides'
    nodes (``glob[c, s, m]``: global x dof of node m of side s), at the last
    :func:`dowel_forces`. Returns the number of entries written (144 per crossing with
    a local side).

    With Δ the two material points' relative displacement, t = (n_y, −n_x) along the bar,
    f = ±q n w_m, ∂n/∂θ = −t and ∂θ/∂u_p = ¼(−∂N_p/∂y, ∂N_p/∂x) on either side's
    triangle: −∂f_m/∂u_p = K_el s s' w_m w_p n nᵀ + s w_m (K_el (Δ·t) n + q t) g_pᵀ
    (K_el = K, or 0 on the plateau; s = ±1 by side).
    """
    nent = 0
    for c in range(cout.shape[0]):
        kel = 0.0 if cout[c, CO_PLASTIC] > 0.5 else cprop[c, 0]
        nx = cout[c, CO_NX]
        ny = cout[c, CO_NY]
        n = (nx, ny)
        v = (kel * cout[c, CO_DT] * nx + cout[c, CO_Q] * ny,
             kel * cout[c, CO_DT] * ny - cout[c, CO_Q] * nx)
        for s in range(2):
            if chost[c, s, 0] < 0:
                continue
            ss = 1.0 if s == 0 else -1.0
            for m in range(3):
                wm = ss * chw[c, s, m]
                for r in range(2):
                    sr = 1.0 if r == 0 else -1.0
                    for p in range(3):
                        kk = kel * wm * sr * chw[c, r, p]
                        g = (-0.25 * cgrad[c, r, p, 1], 0.25 * cgrad[c, r, p, 0])
                        for ia in range(2):
                            for ib in range(2):
                                rows[nent] = glob[c, s, m] + ia
                                cols[nent] = glob[c, r, p] + ib
                                vals[nent] = kk * n[ia] * n[ib] + wm * v[ia] * g[ib]
                                nent += 1
    return nent


def precompile() -> None:
    """Compile the bar and bond kernels on one bar element in one triangle."""
    xa = np.array([[0.0, 0.5], [0.5, 0.5]])
    ua = np.zeros(4)
    ub = np.zeros(8)
    conn = np.array([[0, 1]], dtype=np.int64)
    ep = np.ones((1, N_EP))
    es = np.zeros((1, N_ES))
    bar_forces(xa, ua, conn, np.full(1, 0.5), ep, np.zeros(1, np.int8), es, es.copy(),
               np.zeros(1), np.zeros(1), np.zeros(4))
    hn = np.array([0, 1], dtype=np.int64)
    he = np.zeros(2, dtype=np.int64)
    hosts = np.array([[0, 1, 2], [-1, -1, -1]], dtype=np.int64)
    hw = np.full((2, 3), 1.0 / 3.0)
    npr = np.ones((2, N_NP))
    npr[:, NP_LAW] = 0.0
    ns = np.zeros((2, N_NS))
    bond_forces(xa, ua, ub, conn, hn, he, hosts, hw, npr, np.ones((1, 1)), np.ones((1, 1)),
                np.ones(1, dtype=np.int64), np.ones(1), np.zeros((2, 2)), ns, ns.copy(),
                np.zeros((2, N_NO)), np.zeros(4), np.zeros(8))
    relative_displacements(ua, ub, hn, hosts, hw, np.zeros((2, 2)))
    ch = np.array([[[0, 1, 2], [-1, -1, -1]]], dtype=np.int64)
    cw3 = np.full((1, 2, 3), 1.0 / 3.0)
    cg = np.ones((1, 2, 3, 2))
    uc = np.zeros((1, 6))
    crossing_displacements(ub, ch, cw3, cg, uc)
    co = np.zeros((1, N_CO))
    dowel_forces(np.zeros(1, np.int64), np.zeros(1, np.int8), np.ones((1, 2)), uc,
                 np.ones((1, 2)), np.zeros(1), np.zeros(1), co, ch, cw3, np.zeros(8))
    dowel_tangent(co, np.ones((1, 2)), ch, cw3, cg, np.zeros((1, 2, 3), np.int64),
                  np.zeros(144, np.int64), np.zeros(144, np.int64), np.zeros(144))
    bar_tangent(xa, ua, conn, np.full(1, 0.5), ep, np.zeros(1, np.int8), es, FD_STEP,
                np.zeros(16, np.int64), np.zeros(16, np.int64), np.zeros(16))
    bond_tangent(xa, ua, ub, conn, np.full(1, 0.5), hn, he, hosts, hw, npr, np.ones((1, 1)),
                 np.ones((1, 1)), np.ones(1, dtype=np.int64), np.ones(1), np.zeros((2, 2)),
                 ns, FD_STEP, np.zeros(160, np.int64), np.zeros(160, np.int64),
                 np.zeros(160))
