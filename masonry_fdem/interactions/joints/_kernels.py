"""Numba kernels of the bonded joints: the composite interface law and its forces.

The law is the composite interface model of Lourenço & Rots (1997, "Multisurface interface
model for analysis of masonry structures", J. Eng. Mech. 123(7)), written here in relative
displacements of a zero-thickness interface (SI: tractions in Pa, displacements in m,
stiffnesses in Pa/m, fracture energies in J/m² = N/m):

* elastic: σ = k_n (Δn − Δn_p), τ = k_s (Δs − Δs_p), σ > 0 in tension;
* tension cut-off  f1 = σ − f_t R,             R: softening factor (below);
* Coulomb friction f2 = |τ| + σ tan φ − c R,   flow g2 = |τ| + σ tan ψ (non-associated);
* compression cap  f3 = σ² + C_s τ² − σ̄_c(κ3)²  (associated, σ < 0);
* softening: R = min(exp(−f_t κ1 / G_fI), exp(−c κ2 / G_fII)), so tension and cohesion
  degrade together (the paper's coupled, isotropic softening), each mode driven by its
  own plastic displacement κ1 (opening) and κ2 (slip); with R → 0 the law is Coulomb
  friction without tension, i.e. frictional contact;
* cohesionless (f_t = c = 0: a sand layer, a dry joint): where the faces are not pressed
  (Δn ≥ Δn_p) they carry nothing and the opening is a gap, not plastic: they close again
  where they parted, and the tangential spring is relaxed while open (Δs_p follows Δs).
  (A plastic opening, as the tension cut-off returns, would put every open point exactly
  on the kink between contact and separation at every committed state.) So does a
  non-dilatant joint with strength once its bond is *spent*: its committed softening
  factor at or below ``R_SPENT`` (1e-3, 0.1 % of f_t and c left; κ1 ≈ 6.9 G_fI/f_t).
  Its faces, a crack's, meet where they met before the crack opened: at Δn = Δn_p − κ1
  (κ1 being the tension cut-off's share of Δn_p), as the block contact that takes a
  broken joint over has them; pressed there it takes the law with the strengths left;
* dilatancy tan ψ = tan ψ0 · ⟨1 − σ/σ_u⟩ · exp(−δ κ2): it vanishes under the confining
  stress σ_u < 0 and decays with slip;
* cap hardening/softening (Lourenço's three branches): σ̄_c = f_c/3 → f_c at κ3 = κ_p
  (elliptic), → f_c/2 at κ_m (parabolic), → f_c/7 exponentially. Here κ_m − κ_p =
  G_fc / (0.818 f_c), so that the area between the post-peak curve and the residual
  strength f_c/7 equals G_fc.

The return mapping starts from the COMMITTED state and the current total relative
displacement (backward Euler), and writes a TRIAL state: explicit runs commit every step,
dynamic relaxation commits at a converged load step. Surfaces are returned one after the
other (tension, shear, cap), repeated until all hold (corners).

Consistent tangent (static Newton solver): a numerical algorithmic tangent (Miehe 1996,
"Numerical computation of algorithmic (consistent) tangent moduli in large-strain
computational inelasticity", CMAME 134). :func:`point_forces` is the one kernel of an
integration point's forces; :func:`joint_forces` sums it over the points, and
:func:`joint_tangent` differentiates it by central differences in each of the point's 8
dofs (the nodes a0, a1, b0, b1), every evaluation returning from the committed state as
the forces do. Force and tangent thus come from the same discrete law — return mapping,
bisections, corner Newton, rotating joint frame — and cannot drift apart; the stiffness
of a softening branch or of a corner comes out as the return mapping makes it.

The step is h = FD_STEP · L with L the reference length of the point's side-A facet
(FD_STEP = 1e-8: h ≈ 5e-10 m on a 5 cm facet; FD_STEP · |u| for a dof displaced by more
than L, so that u ± h never rounds back to u). Within one branch of the law the force is
smooth, so the error of the central difference is the truncation, of relative size
(h/ℓ)² with ℓ the shortest length of the law (the softening length G_f/f_t, ~1e-5–1e-4
m; the facet length for the turning frame), ~1e-9 or less; plus round-off, relative
~ε·|Δ|/h: the relative displacement is formed from displacements alone (no X + u
cancellation; the frame's X + u only enters the small geometric terms), and the inner
bisections stop at 1e-15 of the trial plastic displacement, the corner Newton at 1e-12 of
the strengths, so this is ~1e-9 too. Measured against central differences of the
assembled forces (tests/test_tangent_joints_anchors.py), elastic, softening, corner, open
and sliding states agree to ~1e-10 of the largest entry (both larger and smaller steps by
a factor of 100 keep 1e-6). A point closer than h to a kink of the law (the elastic
limit, an unloading) gets a blend of the tangents of the two branches there.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

# material properties (columns of the props table)
P_KN, P_KS, P_FT, P_GF1, P_C, P_TANPHI, P_GF2, P_TANPSI, P_SIGU, P_DELTA = range(10)
P_FC, P_CS, P_KP, P_GFC = 10, 11, 12, 13
N_PROPS = 14

# state per integration point (committed and trial)
S_DNP, S_DSP, S_K1, S_K2, S_K3, S_STATUS, S_SN, S_TS, S_DISS, S_DN, S_DS = range(11)
N_STATE = 11

# status codes
INTACT, SOFTENING, OPEN, SLIDING, CRUSHED = 0, 1, 2, 3, 4
BROKEN_R = 1e-2  # softening factor below which a joint counts as broken
#: softening factor at or below which a point's bond is spent (0.1 % of its strengths
#: left): from then on it opens as a gap, as a cohesionless joint does (see interface_law)
R_SPENT = 1e-3

# energies returned
E_ELASTIC, E_DISSIPATED = 0, 1

#: finite-difference step of the tangent, as a fraction of the point's facet length
#: (see the module doc)
FD_STEP = 1e-8


@njit(cache=True, inline="always")
def softening_factor(p, k1, k2):
    """R = min(exp(−f_t κ1/G_fI), exp(−c κ2/G_fII)) (1 when a mode has no strength)."""
    r = 1.0  # exp(−0) = 1 exactly: an undamaged point skips the exponentials
    if k1 != 0.0 and p[P_FT] > 0.0 and p[P_GF1] > 0.0:
        r = min(r, math.exp(-p[P_FT] * k1 / p[P_GF1]))
    if k2 != 0.0 and p[P_C] > 0.0 and p[P_GF2] > 0.0:
        r = min(r, math.exp(-p[P_C] * k2 / p[P_GF2]))
    return r


@njit(cache=True, inline="always")
def is_spent(p, r):
    """Whether a point of softening factor ``r`` has its bond spent: a non-dilatant joint
    with at most ``R_SPENT`` of its strengths left (it then opens as a gap)."""
    return p[P_TANPSI] == 0.0 and r <= R_SPENT


@njit(cache=True, inline="always")
def cap_strength(p, k3):
    """σ̄_c(κ3) [Pa]: hardening to f_c at κ_p, then softening to f_c/7."""
    fc = p[P_FC]
    kp = p[P_KP]
    si = fc / 3.0
    sm = 0.5 * fc
    sr = fc / 7.0
    if k3 <= kp:
        x = k3 / kp
        return si + (fc - si) * math.sqrt(max(2.0 * x - x * x, 0.0))
    dm = p[P_GFC] / (0.818027210884 * fc)
    if k3 <= kp + dm:
        x = (k3 - kp) / dm
        return fc + (sm - fc) * x * x
    m = 2.0 * (sm - fc) / dm
    return sr + (sm - sr) * math.exp(m * (k3 - kp - dm) / (sm - sr))


@njit(cache=True)
def _tension_residual(p, sn_tr, lam, k1, k2):
    return sn_tr - p[P_KN] * lam - p[P_FT] * softening_factor(p, k1 + lam, k2)


@njit(cache=True)
def _shear_residual(p, at, sn, tpsi, lam, k1, k2):
    r = softening_factor(p, k1, k2 + lam)
    return at - p[P_KS] * lam + (sn - p[P_KN] * tpsi * lam) * p[P_TANPHI] - p[P_C] * r


@njit(cache=True)
def _cap_residual(p, sn, ts, lam, k3):
    s = sn / (1.0 + 2.0 * p[P_KN] * lam)
    t = ts / (1.0 + 2.0 * p[P_CS] * p[P_KS] * lam)
    dk = 2.0 * lam * math.sqrt(s * s + (p[P_CS] * t) ** 2)
    sc = cap_strength(p, k3 + dk)
    return s * s + p[P_CS] * t * t - sc * sc


@njit(cache=True)
def _bisect_tension(p, sn_tr, k1, k2):
    lo = 0.0
    hi = sn_tr / p[P_KN]
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        if _tension_residual(p, sn_tr, mid, k1, k2) > 0.0:
            lo = mid
        else:
            hi = mid
        if hi - lo <= 1e-15 * hi:
            break
    return 0.5 * (lo + hi)


@njit(cache=True)
def _bisect_shear(p, at, sn, tpsi, k1, k2):
    lo = 0.0
    hi = at / p[P_KS]
    if _shear_residual(p, at, sn, tpsi, hi, k1, k2) > 0.0:
        return hi  # even τ = 0 violates f2 (a tension corner): tension takes the rest
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        if _shear_residual(p, at, sn, tpsi, mid, k1, k2) > 0.0:
            lo = mid
        else:
            hi = mid
        if hi - lo <= 1e-15 * hi:
            break
    return 0.5 * (lo + hi)


@njit(cache=True)
def _bisect_cap(p, sn, ts, k3):
    lo = 0.0
    hi = 1.0 / p[P_KN]
    while _cap_residual(p, sn, ts, hi, k3) > 0.0:
        hi *= 2.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if _cap_residual(p, sn, ts, mid, k3) > 0.0:
            lo = mid
        else:
            hi = mid
        if hi - lo <= 1e-15 * hi:
            break
    return 0.5 * (lo + hi)


@njit(cache=True)
def _corner_residual(p, sn_tr, at, k1, k2, tpsi, l1, l2):
    """Residuals of f1 = 0 and f2 = 0 and their Jacobian (g0, g1, J00, J01, J10, J11)."""
    kn = p[P_KN]
    ks = p[P_KS]
    e1 = math.exp(-p[P_FT] * (k1 + l1) / p[P_GF1]) if p[P_FT] > 0.0 else 1.0
    e2 = math.exp(-p[P_C] * (k2 + l2) / p[P_GF2]) if p[P_C] > 0.0 else 1.0
    r1 = 0.0
    r2 = 0.0
    if e1 <= e2:
        r = e1
        if p[P_FT] > 0.0:
            r1 = -p[P_FT] / p[P_GF1] * e1
    else:
        r = e2
        r2 = -p[P_C] / p[P_GF2] * e2
    sn = sn_tr - kn * (l1 + tpsi * l2)
    return (sn - p[P_FT] * r,
            at - ks * l2 + sn * p[P_TANPHI] - p[P_C] * r,
            -kn - p[P_FT] * r1,
            -kn * tpsi - p[P_FT] * r2,
            -kn * p[P_TANPHI] - p[P_C] * r1,
            -ks - kn * tpsi * p[P_TANPHI] - p[P_C] * r2)


@njit(cache=True)
def _tension_shear_return(p, sn_tr, at, k1, k2, tpsi):
    """Plastic multipliers (λ1 opening, λ2 slip) that bring the trial tractions back onto
    the tension cut-off, the Coulomb surface or their corner."""
    scale = p[P_FT] + p[P_C] + abs(sn_tr) + at
    tol = 1e-12 * scale
    # tension alone
    if sn_tr > p[P_FT] * softening_factor(p, k1, k2):
        l1 = _bisect_tension(p, sn_tr, k1, k2)
        sn = sn_tr - p[P_KN] * l1
        if at + sn * p[P_TANPHI] - p[P_C] * softening_factor(p, k1 + l1, k2) <= tol:
            return l1, 0.0
    # shear alone
    if at > 0.0:
        l2 = _bisect_shear(p, at, sn_tr, tpsi, k1, k2)
        sn = sn_tr - p[P_KN] * tpsi * l2
        if sn - p[P_FT] * softening_factor(p, k1, k2 + l2) <= tol:
            return 0.0, l2
    # the corner: Newton on (λ1, λ2), kept non-negative
    l1 = 0.0
    l2 = 0.0
    for _ in range(100):
        g0, g1, j00, j01, j10, j11 = _corner_residual(p, sn_tr, at, k1, k2, tpsi, l1, l2)
        if abs(g0) <= tol and abs(g1) <= tol:
            break
        det = j00 * j11 - j01 * j10
        if det == 0.0:
            break
        d1 = -(j11 * g0 - j01 * g1) / det
        d2 = -(-j10 * g0 + j00 * g1) / det
        l1 = max(l1 + d1, 0.0)
        l2 = min(max(l2 + d2, 0.0), at / p[P_KS])
    return l1, l2


@njit(cache=True, inline="always")
def interface_law(p, dn, ds, s0, s1):
    """Return mapping at one integration point.

    Args:
        p: (N_PROPS,) material properties.
        dn, ds: relative normal (opening > 0) and tangential displacement [m].
        s0: (N_STATE,) committed state (read).
        s1: (N_STATE,) trial state (written): plastic displacements, κ's, status,
            tractions σ, τ [Pa], dissipated energy per unit area [J/m²], dn, ds.
    """
    kn = p[P_KN]
    ks = p[P_KS]
    dnp = s0[S_DNP]
    dsp = s0[S_DSP]
    k1 = s0[S_K1]
    k2 = s0[S_K2]
    k3 = s0[S_K3]
    diss = s0[S_DISS]
    r = softening_factor(p, k1, k2)  # (kept current as κ1, κ2 change below)
    gap = (p[P_FT] == 0.0 and p[P_C] == 0.0) or is_spent(p, r)
    crack = k1 if gap else 0.0
    if gap and dn - (dnp - crack) >= 0.0:
        # cohesionless (a sand layer, a dry joint) or spent (a cracked mortar joint
        # whose committed softening has left at most R_SPENT of its strengths; not a
        # dilatant one, whose opening under slip is its flow rule's) and not pressed: a
        # gap, not a plastic opening. The faces carry nothing and close where they
        # met before the gap opened: at dn = dnp for a cohesionless point, at
        # dn = dnp − κ1 for a spent one, whose tension cut-off's plastic opening κ1 is
        # its crack's width (closing a crack 0.8 mm open to 0.7 mm pressed it with
        # k_n × 0.1 mm = 8.2 MPa on the TRL mortar while its faces were still apart,
        # where the block contact that takes a broken joint over finds them first at
        # dn = 0). The tangential spring is relaxed (dsp follows ds),
        # so the point recloses without a stale shear. A plastic opening (dnp = dn, as
        # the tension cut-off of a joint with strength returns) would leave every open
        # point exactly on the kink between contact and separation at every committed
        # state — Newton then toggles such points from one iteration to the next (the
        # full TRL arch's hinges, 80 mm into its mechanism) — and would press a reopened
        # joint at once on any reversal of its opening. (A spent point gives up at most
        # R_SPENT f_t of tension on becoming a gap; pressed, it takes the law below.)
        s1[S_DNP] = dnp
        s1[S_DSP] = ds
        s1[S_K1] = k1
        s1[S_K2] = k2
        s1[S_K3] = k3
        s1[S_STATUS] = OPEN if dn > 0.0 else SLIDING
        s1[S_SN] = 0.0
        s1[S_TS] = 0.0
        s1[S_DISS] = diss
        s1[S_DN] = dn
        s1[S_DS] = ds
        return
    dnp -= crack  # (a spent point pressed: the law from where its faces meet)
    slid = False
    for _ in range(6):
        active = False
        sn = kn * (dn - dnp)
        ts = ks * (ds - dsp)
        # --- tension cut-off and Coulomb friction (with their corner)
        at = abs(ts)
        f1 = sn - p[P_FT] * r
        f2 = at + sn * p[P_TANPHI] - p[P_C] * r
        scale = p[P_FT] + p[P_C] + abs(sn) + at
        if f1 > 1e-14 * scale or (f2 > 1e-14 * scale and at > 0.0):
            tpsi = p[P_TANPSI]
            if tpsi > 0.0:
                if sn < 0.0 and p[P_SIGU] < 0.0:
                    tpsi *= max(0.0, 1.0 - sn / p[P_SIGU])
                tpsi *= math.exp(-p[P_DELTA] * k2)
            l1, l2 = _tension_shear_return(p, sn, at, k1, k2, tpsi)
            sg = 1.0 if ts > 0.0 else -1.0
            dnp += l1 + tpsi * l2
            dsp += sg * l2
            k1 += l1
            k2 += l2
            r = softening_factor(p, k1, k2)
            sn = kn * (dn - dnp)
            ts = ks * (ds - dsp)
            diss += sn * (l1 + tpsi * l2) + abs(ts) * l2
            if l2 > 0.0:
                slid = True
            active = True
        # --- compression cap
        if p[P_FC] > 0.0 and sn < 0.0:
            sc = cap_strength(p, k3)
            if sn * sn + p[P_CS] * ts * ts > sc * sc * (1.0 + 1e-12):
                lam = _bisect_cap(p, sn, ts, k3)
                s = sn / (1.0 + 2.0 * kn * lam)
                t = ts / (1.0 + 2.0 * p[P_CS] * ks * lam)
                ddn = 2.0 * lam * s
                dds = 2.0 * lam * p[P_CS] * t
                dnp += ddn
                dsp += dds
                k3 += math.sqrt(ddn * ddn + dds * dds)
                sn = kn * (dn - dnp)
                ts = ks * (ds - dsp)
                diss += sn * ddn + ts * dds
                active = True
        if not active:
            break
    if p[P_FC] > 0.0 and k3 > p[P_KP]:
        status = CRUSHED
    elif r <= BROKEN_R or (p[P_FT] == 0.0 and p[P_C] == 0.0):
        status = OPEN if sn >= 0.0 and dn > 0.0 else SLIDING
    elif r < 1.0 or k3 > 0.0:
        status = SOFTENING
    else:
        status = INTACT
    if slid and status < SOFTENING:
        status = SOFTENING
    s1[S_DNP] = dnp + crack
    s1[S_DSP] = dsp
    s1[S_K1] = k1
    s1[S_K2] = k2
    s1[S_K3] = k3
    s1[S_STATUS] = status
    s1[S_SN] = sn
    s1[S_TS] = ts
    s1[S_DISS] = diss
    s1[S_DN] = dn
    s1[S_DS] = ds


@njit(cache=True, inline="always")
def _frame(X, u, a0, a1, b0, b1):
    """The joint's tangent, unnormalised, and its length [m]: from the current facets,
    A's and B's reversed added (the two points of a segment share it)."""
    tx = (X[a1, 0] + u[2 * a1] - X[a0, 0] - u[2 * a0]) + (
        X[b0, 0] + u[2 * b0] - X[b1, 0] - u[2 * b1])
    ty = (X[a1, 1] + u[2 * a1 + 1] - X[a0, 1] - u[2 * a0 + 1]) + (
        X[b0, 1] + u[2 * b0 + 1] - X[b1, 1] - u[2 * b1 + 1])
    return tx, ty, math.sqrt(tx * tx + ty * ty)


@njit(cache=True, inline="always")
def _framed_point(u, a0, a1, b0, b1, ga, gb, wq, p, s0q, s1q, fl, tx, ty):
    """:func:`point_forces` in the unit tangent (tx, ty) of its joint's frame."""
    nx = ty
    ny = -tx
    dux = ((1.0 - gb) * u[2 * b0] + gb * u[2 * b1]) - ((1.0 - ga) * u[2 * a0] + ga * u[2 * a1])
    duy = ((1.0 - gb) * u[2 * b0 + 1] + gb * u[2 * b1 + 1]) - (
        (1.0 - ga) * u[2 * a0 + 1] + ga * u[2 * a1 + 1])
    dn = dux * nx + duy * ny
    ds = dux * tx + duy * ty
    interface_law(p, dn, ds, s0q, s1q)
    sn = s1q[S_SN]
    ts = s1q[S_TS]
    fx = wq * (sn * nx + ts * tx)
    fy = wq * (sn * ny + ts * ty)
    # the traction pulls B back towards A when the joint opens (σ > 0)
    fl[0] = (1.0 - ga) * fx
    fl[1] = (1.0 - ga) * fy
    fl[2] = ga * fx
    fl[3] = ga * fy
    fl[4] = -((1.0 - gb) * fx)
    fl[5] = -((1.0 - gb) * fy)
    fl[6] = -(gb * fx)
    fl[7] = -(gb * fy)


@njit(cache=True, inline="always")
def point_forces(X, u, a0, a1, b0, b1, ga, gb, wq, p, s0q, s1q, fl):
    """Forces of one integration point: the single source of forces and tangent.

    Args:
        X, u: reference coordinates (n, 2) [m] and displacements (2n,) [m].
        a0, a1, b0, b1: the end nodes of its facets on side A and side B.
        ga, gb: its position along each facet (0 at the first node).
        wq: its weight [m²].
        p: (N_PROPS,) its material properties.
        s0q, s1q: (N_STATE,) its committed state (read) and trial state (written).
        fl: (8,) its forces [N] on (a0x, a0y, a1x, a1y, b0x, b0y, b1x, b1y) (written).
    """
    # joint frame from the current facets (B reversed): t along A, n out of A
    tx, ty, ln = _frame(X, u, a0, a1, b0, b1)
    if not ln > 0.0:
        # the two facets turned into opposite directions (or collapsed): no frame. Only
        # a wild Newton iterate gets here; NaN forces make its residual reject it
        for k in range(8):
            fl[k] = math.nan
        s1q[:] = s0q
        return
    _framed_point(u, a0, a1, b0, b1, ga, gb, wq, p, s0q, s1q, fl, tx / ln, ty / ln)


@njit(cache=True)
def joint_forces(X, u, ipa, ipb, xia, xib, w, ipmat, props, alive, counted, s0, s1, fq,
                 energy):
    """Forces of all bonded integration points (trial state from the committed one).

    Args:
        X: (n, 2) reference node coordinates [m] (local + ghost nodes).
        u: (2n,) displacements [m].
        ipa, ipb: (m, 2) end nodes of the facet on side A and on side B of each point
            (A's interior lies to the left of a0→a1; B runs the other way).
        xia, xib: (m,) position of the point along each facet (0 at the first node).
        w: (m,) weight: tributary joint length × out-of-plane width [m²].
        ipmat: (m,) joint material row in ``props``.
        props: (k, N_PROPS) material properties.
        alive: (m,) int8, 0 for points handed over to contact.
        counted: (m,) weight of each point in ``energy`` (1; 0 for the copy of a point
            another rank counts).
        s0, s1: (m, N_STATE) committed and trial state.
        fq: (m, 8) forces of each point [N] on a0, a1, b0, b1 (x, y), written (summed
            into the nodes by :func:`masonry_fdem.interactions._sums.gather_rows`).
        energy: (2,) elastic energy stored and total dissipated energy [J] (written).
    """
    e_el = 0.0
    e_dis = 0.0
    # the frame of the last live point, reused by the next point on the same facets (the
    # other point of its segment): the same numbers as point_forces computes
    tx = 0.0
    ty = 0.0
    framed = -1
    for q in range(ipa.shape[0]):
        if alive[q] == 0:
            for j in range(8):
                fq[q, j] = 0.0
            e_dis += counted[q] * w[q] * s0[q, S_DISS]
            continue
        p = props[ipmat[q]]
        a0 = ipa[q, 0]
        a1 = ipa[q, 1]
        b0 = ipb[q, 0]
        b1 = ipb[q, 1]
        if (framed >= 0 and ipa[framed, 0] == a0 and ipa[framed, 1] == a1
                and ipb[framed, 0] == b0 and ipb[framed, 1] == b1):
            _framed_point(u, a0, a1, b0, b1, xia[q], xib[q], w[q], p, s0[q], s1[q], fq[q],
                          tx, ty)
        else:
            fx, fy, ln = _frame(X, u, a0, a1, b0, b1)
            if ln > 0.0:
                tx = fx / ln
                ty = fy / ln
                framed = q
                _framed_point(u, a0, a1, b0, b1, xia[q], xib[q], w[q], p, s0[q], s1[q],
                              fq[q], tx, ty)
            else:
                framed = -1
                point_forces(X, u, a0, a1, b0, b1, xia[q], xib[q], w[q], p, s0[q], s1[q],
                             fq[q])
        sn = s1[q, S_SN]
        ts = s1[q, S_TS]
        e_el += counted[q] * 0.5 * w[q] * (sn * sn / p[P_KN] + ts * ts / p[P_KS])
        e_dis += counted[q] * w[q] * s1[q, S_DISS]
    energy[E_ELASTIC] = e_el
    energy[E_DISSIPATED] = e_dis


@njit(cache=True)
def joint_tangent(X, u, ipa, ipb, xia, xib, w, ipmat, props, alive, s0, rel_step, rows,
                  cols, vals):
    """Consistent tangent −∂f/∂u [N/m] of the live integration points, by central
    differences of :func:`point_forces` (the force kernel itself) in each of the point's
    8 dofs; a numerical algorithmic tangent (Miehe 1996, CMAME 134).

    Each evaluation returns from the committed state ``s0`` (backward Euler), so the
    perturbed states see the same history as the forces; their trial states go to a
    scratch row, so the trial state ``s1`` of :func:`joint_forces` is left as it is.
    The step of a point is ``rel_step`` times the reference length of its side-A facet
    (or of |u| if larger; see the module doc); the perturbation actually applied,
    (u + h) − (u − h) in floating point, is the divisor.

    Args:
        X, u, ipa, ipb, xia, xib, w, ipmat, props, alive, s0: as :func:`joint_forces`.
        rel_step: the step as a fraction of the facet length.
        rows, cols, vals: (64 m,) COO output: dof numbers of ``u`` (2 node + component)
            and values [N/m].

    Returns:
        The number of entries written (64 per live point).
    """
    uw = u.copy()
    scratch = np.empty(N_STATE)
    f0 = np.empty(8)
    fp = np.empty(8)
    fm = np.empty(8)
    dofs = np.empty(8, dtype=np.int64)
    nent = 0
    for q in range(ipa.shape[0]):
        if alive[q] == 0:
            continue
        p = props[ipmat[q]]
        a0, a1, b0, b1 = ipa[q, 0], ipa[q, 1], ipb[q, 0], ipb[q, 1]
        h = _point_dofs(X, a0, a1, b0, b1, rel_step, dofs)
        point_forces(X, uw, a0, a1, b0, b1, xia[q], xib[q], w[q], p, s0[q], scratch, f0)
        b_0 = _branch(s0[q], scratch)
        for j in range(8):
            k = dofs[j]
            u0 = uw[k]
            hk = max(h, rel_step * abs(u0))  # never lost in the round-off of u0 ± h
            up = u0 + hk
            um = u0 - hk
            uw[k] = up
            point_forces(X, uw, a0, a1, b0, b1, xia[q], xib[q], w[q], p, s0[q], scratch, fp)
            b_p = _branch(s0[q], scratch)
            uw[k] = um
            point_forces(X, uw, a0, a1, b0, b1, xia[q], xib[q], w[q], p, s0[q], scratch, fm)
            b_m = _branch(s0[q], scratch)
            uw[k] = u0
            # the derivative of the branch the point is on: one-sided where a step
            # crosses a kink of the law (a central difference there would blend the
            # two branches' stiffnesses, e.g. the elastic and the softening one)
            if b_p == b_0 and b_m != b_0:
                for i in range(8):
                    fm[i] = f0[i]
                um = u0
            elif b_m == b_0 and b_p != b_0:
                for i in range(8):
                    fp[i] = f0[i]
                up = u0
            den = up - um
            for i in range(8):
                rows[nent] = dofs[i]
                cols[nent] = k
                vals[nent] = -(fp[i] - fm[i]) / den
                nent += 1
    return nent


@njit(cache=True)
def dissipation_gradient(X, u, ipa, ipb, xia, xib, w, ipmat, props, alive, s0, rel_step,
                         g):
    """The energy the live points dissipate from the committed state to ``u`` [J], and
    its gradient ∂D/∂u [J/m] into ``g`` (2n,) (+=), by central differences of the
    return mapping like :func:`joint_tangent` (a point at the elastic limit gets half its
    loading slope: the gradient only steers the dissipation constraint's Newton
    iterations, the dissipation itself is exact)."""
    uw = u.copy()
    scratch = np.empty(N_STATE)
    fl = np.empty(8)
    dofs = np.empty(8, dtype=np.int64)
    total = 0.0
    for q in range(ipa.shape[0]):
        if alive[q] == 0:
            continue
        p = props[ipmat[q]]
        a0, a1, b0, b1 = ipa[q, 0], ipa[q, 1], ipb[q, 0], ipb[q, 1]
        point_forces(X, uw, a0, a1, b0, b1, xia[q], xib[q], w[q], p, s0[q], scratch, fl)
        total += w[q] * (scratch[S_DISS] - s0[q, S_DISS])
        h = _point_dofs(X, a0, a1, b0, b1, rel_step, dofs)
        for j in range(8):
            k = dofs[j]
            u0 = uw[k]
            hk = max(h, rel_step * abs(u0))
            up = u0 + hk
            um = u0 - hk
            uw[k] = up
            point_forces(X, uw, a0, a1, b0, b1, xia[q], xib[q], w[q], p, s0[q], scratch, fl)
            dp = scratch[S_DISS]
            uw[k] = um
            point_forces(X, uw, a0, a1, b0, b1, xia[q], xib[q], w[q], p, s0[q], scratch, fl)
            dm = scratch[S_DISS]
            uw[k] = u0
            g[k] += w[q] * (dp - dm) / (up - um)
    return total


@njit(cache=True)
def _point_dofs(X, a0, a1, b0, b1, rel_step, dofs):
    """The 8 dofs of a point's facet nodes (a0, a1, b0, b1; x then y) into ``dofs``;
    returns the finite-difference step, ``rel_step`` × the side-A facet length [m]."""
    dofs[0] = 2 * a0
    dofs[2] = 2 * a1
    dofs[4] = 2 * b0
    dofs[6] = 2 * b1
    for j in range(0, 8, 2):
        dofs[j + 1] = dofs[j] + 1
    return rel_step * math.sqrt((X[a1, 0] - X[a0, 0]) ** 2 + (X[a1, 1] - X[a0, 1]) ** 2)


@njit(cache=True)
def _branch(s0q, s1q):
    """Which surfaces flowed in the return mapping from ``s0q`` to ``s1q`` (bits:
    tension, shear, cap): the branch of the law a point is on."""
    out = 0
    if s1q[S_K1] > s0q[S_K1]:
        out += 1
    if s1q[S_K2] > s0q[S_K2]:
        out += 2
    if s1q[S_K3] > s0q[S_K3]:
        out += 4
    return out


@njit(cache=True)
def hand_over_flags(X, u, ipa, ipb, ipmat, props, s0, seg, seg_length, release_ratio,
                    release_cos, done, turned):
    """Per segment (``seg[q]`` the local segment of point q): ``done`` the number of its
    points spent — open with a softening factor at or below ``release_ratio`` (or
    ``R_SPENT``, where the law opens it as a gap), or slid by
    more than half the segment's length [m] — and ``turned`` whether a point's facets have
    turned against each other beyond ``release_cos`` (B's facet reversed: parallel when
    bonded). Both are zeroed first."""
    done[:] = 0
    turned[:] = False
    for q in range(ipa.shape[0]):
        p = props[ipmat[q]]
        r = softening_factor(p, s0[q, S_K1], s0[q, S_K2])
        if ((s0[q, S_STATUS] == OPEN and (r <= release_ratio or is_spent(p, r)))
                or abs(s0[q, S_DS]) > 0.5 * seg_length[seg[q]]):
            done[seg[q]] += 1
        a0 = ipa[q, 0]
        a1 = ipa[q, 1]
        b0 = ipb[q, 0]
        b1 = ipb[q, 1]
        dax = (X[a1, 0] + u[2 * a1]) - (X[a0, 0] + u[2 * a0])
        day = (X[a1, 1] + u[2 * a1 + 1]) - (X[a0, 1] + u[2 * a0 + 1])
        dbx = (X[b0, 0] + u[2 * b0]) - (X[b1, 0] + u[2 * b1])
        dby = (X[b0, 1] + u[2 * b0 + 1]) - (X[b1, 1] + u[2 * b1 + 1])
        la = math.sqrt(dax * dax + day * day)
        lb = math.sqrt(dbx * dbx + dby * dby)
        if (dax * dbx + day * dby) < release_cos * la * lb:
            turned[seg[q]] = True


@njit(cache=True)
def commit(alive, s0, s1):
    """Copy the trial state of live points into the committed state."""
    for q in range(alive.shape[0]):
        if alive[q]:
            for j in range(s0.shape[1]):
                s0[q, j] = s1[q, j]


@njit(cache=True)
def explicit_softening_props(props, ipmat, s0, kprev, rho, out):
    """Per-point properties with the softening frozen at extrapolated values (the
    implicit–explicit, IMEX, integration of Oliver, Huespe & Cante 2008, "An
    implicit/explicit integration scheme to increase computability of non-linear
    material and contact/friction problems", CMAME 197, applied to the softening
    variables): κ̃ = κ_n + ρ (κ_n − κ_{n−1}) from the last two committed states, and
    the strengths of the increment are those at κ̃ — f_t R(κ̃), c R(κ̃) and σ̄_c(κ̃3) —
    held fixed: within an increment the law is perfectly plastic, so no point can
    switch between a softening branch and its elastic unloading from one Newton
    iteration to the next. (The committed state is then written by the implicit
    return mapping at the converged displacement, see ``Joints.commit``.)

    Args:
        props: (k, N_PROPS) the materials; ipmat: (m,) each point's row.
        s0: (m, N_STATE) committed state; kprev: (m, 3) κ1, κ2, κ3 one commit before.
        rho: the extrapolation factor, Δt_{n+1}/Δt_n (≥ 0).
        out: (m, N_PROPS) written: each point's row, softening frozen (G_fI, G_fII and
            κ_p infinite, so the law's own softening is off; f_c is 3 σ̄_c(κ̃3), the
            cap's initial strength being f_c/3).
    """
    for q in range(ipmat.shape[0]):
        p = props[ipmat[q]]
        for j in range(N_PROPS):
            out[q, j] = p[j]
        k1 = s0[q, S_K1] + rho * max(s0[q, S_K1] - kprev[q, 0], 0.0)
        k2 = s0[q, S_K2] + rho * max(s0[q, S_K2] - kprev[q, 1], 0.0)
        k3 = s0[q, S_K3] + rho * max(s0[q, S_K3] - kprev[q, 2], 0.0)
        if p[P_FT] > 0.0 or p[P_C] > 0.0:
            # a point spent at its committed state (interface_law) has no strength left
            # in the increment: it opens as a gap; else the extrapolated strengths
            # (never exactly 0 then)
            r = (0.0 if is_spent(p, softening_factor(p, s0[q, S_K1], s0[q, S_K2]))
                 else max(softening_factor(p, k1, k2), 1e-200))
            out[q, P_FT] = p[P_FT] * r
            out[q, P_C] = p[P_C] * r
        out[q, P_GF1] = math.inf
        out[q, P_GF2] = math.inf
        if p[P_FC] > 0.0:
            out[q, P_FC] = 3.0 * cap_strength(p, k3)
            out[q, P_KP] = math.inf


@njit(cache=True)
def node_spring_bound(ipa, ipb, xia, xib, w, ipmat, props, alive, k):
    """Per node Σ_ip max(k_n, k_s) w N_i [N/m] (k: (n,), added to)."""
    for q in range(ipa.shape[0]):
        if alive[q] == 0:
            continue
        p = props[ipmat[q]]
        kk = max(p[P_KN], p[P_KS]) * w[q]
        k[ipa[q, 0]] += (1.0 - xia[q]) * kk
        k[ipa[q, 1]] += xia[q] * kk
        k[ipb[q, 0]] += (1.0 - xib[q]) * kk
        k[ipb[q, 1]] += xib[q] * kk


def empty_state(m: int) -> np.ndarray:
    return np.zeros((m, N_STATE))


def precompile() -> None:
    """Compile the joint kernels on one integration-point pair."""
    X = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    u = np.zeros(8)
    props = np.zeros((1, N_PROPS))
    props[0, [P_FT, P_GF1, P_C, P_GF2, P_FC, P_KP, P_GFC]] = 1.0
    props[0, [P_KN, P_KS]] = 10.0
    ip = np.array([[0, 1]], dtype=np.int64)
    half = np.full(1, 0.5)
    s0 = empty_state(1)
    s1 = empty_state(1)
    alive = np.ones(1, dtype=np.int8)
    joint_forces(X, u, ip, ip[:, ::-1].copy(), half, half, half, np.zeros(1, np.int64),
                 props, alive, np.ones(1), s0, s1, np.zeros((1, 8)), np.zeros(2))
    joint_tangent(X, u, ip, ip[:, ::-1].copy(), half, half, half, np.zeros(1, np.int64),
                  props, alive, s0, FD_STEP, np.zeros(64, np.int64), np.zeros(64, np.int64),
                  np.zeros(64))
    commit(alive, s0, s1)
    hand_over_flags(X, u, ip, ip[:, ::-1].copy(), np.zeros(1, np.int64), props, s0,
                    np.zeros(1, np.int64), half, 0.01, 0.9, np.zeros(1, np.int64),
                    np.zeros(1, np.bool_))
    node_spring_bound(ip, ip, half, half, half, np.zeros(1, np.int64), props, alive,
                      np.zeros(4))
    out = np.zeros((1, N_PROPS))
    explicit_softening_props(props, np.zeros(1, np.int64), s0, np.zeros((1, 3)), 1.0, out)
    interface_law(props[0], 2.0, 1.0, s0[0], s1[0])
    interface_law(props[0], -2.0, 0.5, s0[0], s1[0])
