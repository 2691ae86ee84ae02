"""Numba kernels of the block plasticity: Mohr–Coulomb and Drucker–Prager return mappings.

Law (small-strain additive elasto-plasticity, SI units: Pa, m/m, Pa·s, s). At each point
the 3D strain is ``ε = [[Exx, Exy, 0], [Exy, Eyy, 0], [0, 0, Ezz]]`` (tensor shear), with
``Ezz = 0`` in plane strain and ``Ezz`` solved for ``σzz = 0`` in plane stress, and

    σ = λ tr(εe) I + 2μ εe,   εe = ε − εp,   c(α) = max(c0 + H α, c_min).

The caller hands in the Green–Lagrange strain and reads the result as the second
Piola–Kirchhoff stress; here they are simply ε and σ. Stresses are positive in tension.

Surfaces (de Souza Neto, Perić & Owen, *Computational Methods for Plasticity*, ch. 8):

* Mohr–Coulomb, ``f = (σ1 − σ3) + (σ1 + σ3) sinφ − 2 c(α) cosφ`` with σ1 ≥ σ2 ≥ σ3,
  flow potential with sinψ instead of sinφ (non-associated), ``dα = 2 cosφ Σ Δγ`` over the
  active planes (``dα = cosφ/sinψ Δεv`` at the apex). Return in principal stresses
  (isotropy: the trial eigenvectors are kept; in 2D the eigenvector of σzz is ez):
  main plane; if the principal order breaks, the right edge (σ2 = σ3, planes 1–3 and 1–2)
  or the left edge (σ1 = σ2, planes 1–3 and 2–3), chosen by the sign of
  ``(1 − sinψ)σ1 − 2σ2 + (1 + sinψ)σ3`` at the trial state; if the edge result has
  σ1 < σ3, the apex ``p = c cotφ``. Each return is linear in the multipliers on one
  linear piece of c(α); the kink at ``c = c_min`` is handled by solving on the piece of
  α_n and, if α_{n+1} crosses the kink (or that piece is ill-posed, e.g. snap-back
  softening), once more on the other piece.
  Rate dependence is NOT implemented for Mohr–Coulomb: ``P_ETA`` is ignored (rate
  independent); the Python side refuses that combination.
* Drucker–Prager, ``f = √J2(s) + η p − ξ c(α)``, ``g = √J2(s) + η̄ p``, ``p = tr σ / 3``,
  ``dα = ξ Δγ``: cone return ``Δγ = f_trial / (μ + K η η̄ + ξ² H + η_v/Δt)``; if it
  would overshoot the cone axis (√J2 < 0), the apex return in the volumetric plastic
  strain ``Δεv = η̄ Δγ``: ``η (p_tr − K Δεv) − ξ c(α_n + ξ/η̄ Δεv) = (η_v/Δt) Δεv/η̄``.
  Perzyna viscoplasticity (Simo & Hughes, ch. 2.7): ``ε̇p = ⟨f⟩/η_v ∂g/∂σ`` integrated by
  backward Euler, i.e. ``f(σ_{n+1}, α_{n+1}) = (η_v/Δt) Δγ``; ``Δt = inf`` gives the
  rate-independent limit.

Degenerate apexes: with ψ = 0 (MC) or η̄ = 0 (DP) the potential has no apex; the apex
return then uses sinφ (MC) or η (DP) in place of sinψ / η̄ (associated at the apex only).
With φ = 0 there is no apex (Tresca prism, von Mises cylinder).

Plane stress: Ezz is found by a safeguarded secant (Illinois once bracketed) on
``σzz(Ezz) = 0`` with the full return mapping inside, started at the elastic plane-stress
value (exact when the point stays elastic) and at the committed Ezz.

Every return starts from the COMMITTED state (backward Euler) and writes a TRIAL state;
the caller commits ``state1 → state0`` when a step/load increment is accepted. The
plastic strain increment is recovered as ``Δεp = C : (σ_trial − σ_{n+1})``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

# material parameters (entries of prm)
P_LAM, P_MU, P_C, P_SINPHI, P_SINPSI, P_H, P_CMIN, P_ETA = range(8)
P_PLANE_STRESS, P_SURFACE, P_DP_ETA, P_DP_XI, P_DP_ETABAR = 8, 9, 10, 11, 12
N_PRM = 13

# surfaces (values of prm[P_SURFACE])
MOHR_COULOMB, DRUCKER_PRAGER = 0, 1

# state per point (committed state0, trial state1)
S_EPXX, S_EPYY, S_EPZZ, S_EPXY, S_ALPHA, S_EZZ, S_WP = range(7)
N_STATE = 7

_MAX_IT_ZZ = 60  # iterations of the plane-stress σzz = 0 solve
_TOL_ZZ = 1e-12  # |σzz| ≤ _TOL_ZZ (|σ| + c)
_TOL_F = 1e-14  # trial f ≤ _TOL_F (|σ| + c) counts as elastic (round-off)


@njit(cache=True)
def cohesion(alpha, c0, h, cmin):
    """c(α) = max(c0 + H α, c_min) [Pa]."""
    return max(c0 + h * alpha, cmin)


@njit(cache=True)
def _pieces(alpha_n, c0, h, cmin):
    """The linear pieces of c(α) from α_n on: the one holding α_n first, then the next.

    Returns (c_a, h_a, c_b, h_b, α_kink, two): c_x is the piece's line evaluated at α_n,
    h_x its slope; ``two`` says whether a kink at α_kink > α_n lies ahead.
    """
    if h == 0.0:
        c = max(c0, cmin)
        return c, 0.0, c, 0.0, np.inf, False
    ak = (cmin - c0) / h
    lin = c0 + h * alpha_n
    if h < 0.0:  # softening: linear, then clamped at c_min
        if alpha_n < ak:
            return lin, h, cmin, 0.0, ak, True
        return cmin, 0.0, cmin, 0.0, np.inf, False
    if alpha_n < ak:  # hardening from below c_min: clamped, then linear
        return cmin, 0.0, lin, h, ak, True
    return lin, h, lin, h, np.inf, False


# ----------------------------------------------------------------------------------------
# Mohr–Coulomb in principal stresses
# ----------------------------------------------------------------------------------------


@njit(cache=True)
def _mc_solve(kind, s1, s2, s3, alpha_n, c, hs, lam, mu, sphi, spsi, cphi):
    """One MC return on one linear piece of c(α) (c: the piece at α_n, hs: its slope).

    kind 0 main plane, 1 right edge (σ2 = σ3), 2 left edge (σ1 = σ2), 3 apex.
    Returns (σ1, σ2, σ3, α_{n+1}, ok); ok is False when the piece is ill-posed.
    """
    ls = 2.0 * lam * spsi
    dn_hi = ls + 2.0 * mu * (1.0 + spsi)  # D:N on the major principal direction
    dn_lo = ls - 2.0 * mu * (1.0 - spsi)  # ... on the minor one
    a = 4.0 * mu * (1.0 + sphi * spsi) + 4.0 * lam * sphi * spsi
    h = 4.0 * cphi * cphi * hs
    f13 = (s1 - s3) + (s1 + s3) * sphi - 2.0 * c * cphi
    if kind == 0:
        den = a + h
        if not den > 0.0:
            return s1, s2, s3, alpha_n, False
        dg = f13 / den
        return (s1 - dg * dn_hi, s2 - dg * ls, s3 - dg * dn_lo, alpha_n + 2.0 * cphi * dg, True)
    if kind == 1 or kind == 2:
        if kind == 1:
            fb = (s1 - s2) + (s1 + s2) * sphi - 2.0 * c * cphi
            b = 4.0 * lam * sphi * spsi + 2.0 * mu * (1.0 + sphi) * (1.0 + spsi)
        else:
            fb = (s2 - s3) + (s2 + s3) * sphi - 2.0 * c * cphi
            b = 4.0 * lam * sphi * spsi + 2.0 * mu * (1.0 - sphi) * (1.0 - spsi)
        den = a + b + 2.0 * h
        if not den > 0.0:
            return s1, s2, s3, alpha_n, False
        tot = (f13 + fb) / den
        dif = (f13 - fb) / (a - b)  # a − b > 0 for φ, ψ < 90°
        ga = 0.5 * (tot + dif)
        gb = 0.5 * (tot - dif)
        if kind == 1:  # N_a = (hi, 0, lo), N_b = (hi, lo, 0)
            t1 = s1 - (ga + gb) * dn_hi
            t2 = s2 - ga * ls - gb * dn_lo
            t3 = s3 - ga * dn_lo - gb * ls
        else:  # N_a = (hi, 0, lo), N_b = (0, hi, lo)
            t1 = s1 - ga * dn_hi - gb * ls
            t2 = s2 - ga * ls - gb * dn_hi
            t3 = s3 - (ga + gb) * dn_lo
        return t1, t2, t3, alpha_n + 2.0 * cphi * (ga + gb), True
    # apex: p = c cotφ
    k = lam + 2.0 * mu / 3.0
    cot = cphi / sphi
    sp = spsi if spsi > 0.0 else sphi
    r = cphi / sp  # dα / dεv
    den = k + cot * r * hs
    if not den > 0.0:
        return s1, s2, s3, alpha_n, False
    ptr = (s1 + s2 + s3) / 3.0
    dev = (ptr - cot * c) / den
    p = ptr - k * dev
    return p, p, p, alpha_n + r * dev, True


@njit(cache=True)
def _mc_try(kind, s1, s2, s3, alpha_n, prm):
    """``_mc_solve`` on the piece of c(α) at α_n, redone on the next piece if crossed."""
    lam = prm[P_LAM]
    mu = prm[P_MU]
    sphi = prm[P_SINPHI]
    spsi = prm[P_SINPSI]
    cphi = math.sqrt(max(1.0 - sphi * sphi, 0.0))
    ca, ha, cb, hb, ak, two = _pieces(alpha_n, prm[P_C], prm[P_H], prm[P_CMIN])
    t1, t2, t3, a1, ok = _mc_solve(kind, s1, s2, s3, alpha_n, ca, ha, lam, mu, sphi, spsi, cphi)
    if two and (not ok or a1 > ak):
        t1, t2, t3, a1, ok = _mc_solve(kind, s1, s2, s3, alpha_n, cb, hb, lam, mu, sphi, spsi, cphi)
    return t1, t2, t3, a1


@njit(cache=True)
def _mc_return(sxx, syy, sxy, szz, alpha_n, prm):
    """Mohr–Coulomb return of a trial stress. Returns (sxx, syy, sxy, szz, α, plastic)."""
    sphi = prm[P_SINPHI]
    spsi = prm[P_SINPSI]
    cphi = math.sqrt(max(1.0 - sphi * sphi, 0.0))
    # in-plane eigen-decomposition; cos 2θ, sin 2θ of the major in-plane direction
    m = 0.5 * (sxx + syy)
    d = 0.5 * (sxx - syy)
    rad = math.hypot(d, sxy)
    if rad > 0.0:
        c2 = d / rad
        s2t = sxy / rad
    else:
        c2 = 1.0
        s2t = 0.0
    pa = m + rad
    pb = m - rad
    # order (σ1, σ2, σ3) and where σzz sits in it
    if szz >= pa:
        iz = 0
        s1, s2, s3 = szz, pa, pb
    elif szz >= pb:
        iz = 1
        s1, s2, s3 = pa, szz, pb
    else:
        iz = 2
        s1, s2, s3 = pa, pb, szz
    c = cohesion(alpha_n, prm[P_C], prm[P_H], prm[P_CMIN])
    f = (s1 - s3) + (s1 + s3) * sphi - 2.0 * c * cphi
    scale = abs(s1) + abs(s2) + abs(s3) + c
    if f <= _TOL_F * scale:
        return sxx, syy, sxy, szz, alpha_n, False
    t1, t2, t3, a1 = _mc_try(0, s1, s2, s3, alpha_n, prm)
    if not (t1 >= t2 and t2 >= t3):
        side = (1.0 - spsi) * s1 - 2.0 * s2 + (1.0 + spsi) * s3
        kind = 1 if side > 0.0 else 2
        t1, t2, t3, a1 = _mc_try(kind, s1, s2, s3, alpha_n, prm)
        if t1 < t3 and sphi > 0.0:
            t1, t2, t3, a1 = _mc_try(3, s1, s2, s3, alpha_n, prm)
    if iz == 0:
        nz, na, nb = t1, t2, t3
    elif iz == 1:
        na, nz, nb = t1, t2, t3
    else:
        na, nb, nz = t1, t2, t3
    m = 0.5 * (na + nb)
    r = 0.5 * (na - nb)
    return m + r * c2, m - r * c2, r * s2t, nz, a1, True


# ----------------------------------------------------------------------------------------
# Drucker–Prager (with Perzyna viscosity)
# ----------------------------------------------------------------------------------------


@njit(cache=True)
def _dp_solve(apex, q, p, alpha_n, c, hs, k, mu, eta, xi, etab, visc):
    """Cone (apex False: returns Δγ) or apex (returns Δεv) multiplier on one c(α) piece.

    Returns (multiplier, α_{n+1}, ok).
    """
    if not apex:
        den = mu + k * eta * etab + xi * xi * hs + visc
        if not den > 0.0:
            return 0.0, alpha_n, False
        dg = (q + eta * p - xi * c) / den
        return dg, alpha_n + xi * dg, True
    den = eta * k + (xi * xi * hs + visc) / etab
    if not den > 0.0:
        return 0.0, alpha_n, False
    dev = (eta * p - xi * c) / den
    return dev, alpha_n + xi / etab * dev, True


@njit(cache=True)
def _dp_try(apex, q, p, alpha_n, prm, visc, etab):
    """``_dp_solve`` on the piece of c(α) at α_n, redone on the next piece if crossed."""
    k = prm[P_LAM] + 2.0 * prm[P_MU] / 3.0
    mu = prm[P_MU]
    eta = prm[P_DP_ETA]
    xi = prm[P_DP_XI]
    ca, ha, cb, hb, ak, two = _pieces(alpha_n, prm[P_C], prm[P_H], prm[P_CMIN])
    g, a1, ok = _dp_solve(apex, q, p, alpha_n, ca, ha, k, mu, eta, xi, etab, visc)
    if two and (not ok or a1 > ak):
        g, a1, ok = _dp_solve(apex, q, p, alpha_n, cb, hb, k, mu, eta, xi, etab, visc)
    return g, a1


@njit(cache=True)
def _dp_return(sxx, syy, sxy, szz, alpha_n, prm, dt):
    """Drucker–Prager (Perzyna) return. Returns (sxx, syy, sxy, szz, α, plastic)."""
    mu = prm[P_MU]
    k = prm[P_LAM] + 2.0 * mu / 3.0
    eta = prm[P_DP_ETA]
    xi = prm[P_DP_XI]
    etab = prm[P_DP_ETABAR]
    p = (sxx + syy + szz) / 3.0
    dxx = sxx - p
    dyy = syy - p
    dzz = szz - p
    q = math.sqrt(0.5 * (dxx * dxx + dyy * dyy + dzz * dzz) + sxy * sxy)
    c = cohesion(alpha_n, prm[P_C], prm[P_H], prm[P_CMIN])
    f = q + eta * p - xi * c
    if f <= _TOL_F * (q + abs(p) + c):
        return sxx, syy, sxy, szz, alpha_n, False
    visc = 0.0
    if prm[P_ETA] > 0.0:
        if not dt > 0.0:  # no time, no viscous flow
            return sxx, syy, sxy, szz, alpha_n, False
        visc = prm[P_ETA] / dt  # 0 for dt = inf
    dg, a1 = _dp_try(False, q, p, alpha_n, prm, visc, etab)
    if q - mu * dg >= 0.0:
        fac = 1.0 - mu * dg / q
        pn = p - k * etab * dg
        return pn + fac * dxx, pn + fac * dyy, fac * sxy, pn + fac * dzz, a1, True
    if eta > 0.0:
        eb = etab if etab > 0.0 else eta
        dev, a1 = _dp_try(True, q, p, alpha_n, prm, visc, eb)
        pn = p - k * dev
    else:  # no apex (φ = 0): cannot happen with c ≥ 0; keep the axis
        pn = p
        a1 = alpha_n + xi * q / mu
    return pn, pn, 0.0, pn, a1, True


# ----------------------------------------------------------------------------------------
# one point
# ----------------------------------------------------------------------------------------


@njit(cache=True)
def _return_map(exx, eyy, exy, ezz, pxx, pyy, pzz, pxy, alpha_n, prm, dt):
    """Stress and trial state at one point for a given 3D strain (Ezz included).

    Returns (sxx, syy, sxy, szz, pxx, pyy, pzz, pxy, α, plastic).
    """
    lam = prm[P_LAM]
    mu = prm[P_MU]
    exe = exx - pxx
    eye = eyy - pyy
    eze = ezz - pzz
    exye = exy - pxy
    tr = exe + eye + eze
    txx = lam * tr + 2.0 * mu * exe
    tyy = lam * tr + 2.0 * mu * eye
    tzz = lam * tr + 2.0 * mu * eze
    txy = 2.0 * mu * exye
    if prm[P_SURFACE] == 1.0:
        sxx, syy, sxy, szz, a1, plastic = _dp_return(txx, tyy, txy, tzz, alpha_n, prm, dt)
    else:
        sxx, syy, sxy, szz, a1, plastic = _mc_return(txx, tyy, txy, tzz, alpha_n, prm)
    if not plastic:
        return txx, tyy, txy, tzz, pxx, pyy, pzz, pxy, alpha_n, False
    # Δεp = C : (σ_trial − σ)
    dxx = txx - sxx
    dyy = tyy - syy
    dzz = tzz - szz
    dtr = lam / (3.0 * lam + 2.0 * mu) * (dxx + dyy + dzz)
    inv = 0.5 / mu
    return (
        sxx,
        syy,
        sxy,
        szz,
        pxx + (dxx - dtr) * inv,
        pyy + (dyy - dtr) * inv,
        pzz + (dzz - dtr) * inv,
        pxy + (txy - sxy) * inv,
        a1,
        True,
    )


@njit(cache=True)
def _point_update(exx, eyy, exy, ezz_prev, pxx, pyy, pzz, pxy, alpha_n, prm, dt):
    """One point, plane strain (Ezz = 0) or plane stress (Ezz solved for σzz = 0).

    Returns (sxx, syy, sxy, szz, pxx, pyy, pzz, pxy, α, Ezz).
    """
    if prm[P_PLANE_STRESS] != 1.0:
        r = _return_map(exx, eyy, exy, 0.0, pxx, pyy, pzz, pxy, alpha_n, prm, dt)
        return r[0], r[1], r[2], r[3], r[4], r[5], r[6], r[7], r[8], 0.0
    lam = prm[P_LAM]
    kzz = lam + 2.0 * prm[P_MU]
    # elastic plane-stress value: exact if the point stays elastic
    x0 = pzz - lam * ((exx - pxx) + (eyy - pyy)) / kzz
    r = _return_map(exx, eyy, exy, x0, pxx, pyy, pzz, pxy, alpha_n, prm, dt)
    if not r[9]:
        return r[0], r[1], r[2], r[3], r[4], r[5], r[6], r[7], r[8], x0
    c = cohesion(alpha_n, prm[P_C], prm[P_H], prm[P_CMIN])
    f0 = r[3]
    best_x = x0
    best = r
    best_f = abs(f0)
    tol = _TOL_ZZ * (abs(r[0]) + abs(r[1]) + abs(r[2]) + c) + 1e-300
    if best_f <= tol:
        return r[0], r[1], r[2], r[3], r[4], r[5], r[6], r[7], r[8], x0
    # second point: the committed Ezz, or an elastic-slope step
    x1 = ezz_prev
    if not (abs(x1 - x0) > 1e-14 * (abs(x0) + abs(x1))) or not math.isfinite(x1):
        x1 = x0 - f0 / kzz
    # bracket: lo has σzz < 0, hi has σzz > 0
    has_lo = f0 < 0.0
    has_hi = f0 > 0.0
    lo = x0
    flo = f0
    hi = x0
    fhi = f0
    side = 0
    for _ in range(_MAX_IT_ZZ):
        r = _return_map(exx, eyy, exy, x1, pxx, pyy, pzz, pxy, alpha_n, prm, dt)
        f1 = r[3]
        if abs(f1) < best_f:
            best_f = abs(f1)
            best_x = x1
            best = r
            tol = _TOL_ZZ * (abs(r[0]) + abs(r[1]) + abs(r[2]) + c) + 1e-300
        if best_f <= tol:
            break
        if has_lo and has_hi:  # Illinois on the bracket
            if f1 < 0.0:
                lo = x1
                flo = f1
                if side == -1:
                    fhi *= 0.5
                side = -1
            else:
                hi = x1
                fhi = f1
                if side == 1:
                    flo *= 0.5
                side = 1
        else:
            if f1 < 0.0:
                lo = x1
                flo = f1
                has_lo = True
            elif f1 > 0.0:
                hi = x1
                fhi = f1
                has_hi = True
        if has_lo and has_hi:
            if abs(hi - lo) <= 4e-16 * (abs(hi) + abs(lo)):
                break
            xn = (lo * fhi - hi * flo) / (fhi - flo)
            if not (min(lo, hi) < xn < max(lo, hi)):
                xn = 0.5 * (lo + hi)
        else:  # secant towards the root (σzz grows with Ezz), widening on plateaus
            slope = (f1 - f0) / (x1 - x0) if x1 != x0 else kzz
            mag = abs(f1) / kzz
            if slope > 1e-8 * kzz and slope < 1e8 * kzz:
                mag = abs(f1) / slope
            if abs(f1) > 0.5 * abs(f0):  # slow progress (e.g. the flat MC apex)
                mag = max(mag, 2.0 * abs(x1 - x0))
            xn = x1 - mag if f1 > 0.0 else x1 + mag
        x0 = x1
        f0 = f1
        x1 = xn
    r = best
    return r[0], r[1], r[2], r[3], r[4], r[5], r[6], r[7], r[8], best_x


# ----------------------------------------------------------------------------------------
# public kernels
# ----------------------------------------------------------------------------------------


@njit(cache=True)
def plastic_update(strain, state0, state1, stress, energy, qps, prm, dt):
    """Return mapping at the points ``qps``.

    Args:
        strain: (nq, 3) total strain Exx, Eyy, Exy (tensor shear) [-].
        state0: (nq, N_STATE) committed state, read only.
        state1: (nq, N_STATE) trial state, written at ``qps``.
        stress: (nq, 4) written at ``qps``: Sxx, Syy, Sxy, Szz [Pa].
        energy: (nq,) written at ``qps``: elastic energy density ½ σ:(ε − εp) [J/m³].
        qps: (k,) int64 indices of the points to update; the others are untouched.
        prm: (N_PRM,) parameters (``P_*``).
        dt: time increment [s] for Perzyna; ``np.inf`` for the rate-independent limit.
    """
    for i in range(qps.shape[0]):
        q = qps[i]
        exx = strain[q, 0]
        eyy = strain[q, 1]
        exy = strain[q, 2]
        pxx = state0[q, S_EPXX]
        pyy = state0[q, S_EPYY]
        pzz = state0[q, S_EPZZ]
        pxy = state0[q, S_EPXY]
        sxx, syy, sxy, szz, nxx, nyy, nzz, nxy, a1, ezz = _point_update(
            exx, eyy, exy, state0[q, S_EZZ], pxx, pyy, pzz, pxy, state0[q, S_ALPHA], prm, dt
        )
        state1[q, S_EPXX] = nxx
        state1[q, S_EPYY] = nyy
        state1[q, S_EPZZ] = nzz
        state1[q, S_EPXY] = nxy
        state1[q, S_ALPHA] = a1
        state1[q, S_EZZ] = ezz
        state1[q, S_WP] = state0[q, S_WP] + (
            sxx * (nxx - pxx) + syy * (nyy - pyy) + szz * (nzz - pzz) + 2.0 * sxy * (nxy - pxy)
        )
        stress[q, 0] = sxx
        stress[q, 1] = syy
        stress[q, 2] = sxy
        stress[q, 3] = szz
        energy[q] = 0.5 * (
            sxx * (exx - nxx) + syy * (eyy - nyy) + szz * (ezz - nzz) + 2.0 * sxy * (exy - nxy)
        )


@njit(cache=True)
def yield_value(stress4, alpha, prm):
    """Yield function f(σ, α) [Pa] of the surface in ``prm``; stress4 = Sxx, Syy, Sxy, Szz."""
    sxx = stress4[0]
    syy = stress4[1]
    sxy = stress4[2]
    szz = stress4[3]
    c = cohesion(alpha, prm[P_C], prm[P_H], prm[P_CMIN])
    if prm[P_SURFACE] == 1.0:
        p = (sxx + syy + szz) / 3.0
        dxx = sxx - p
        dyy = syy - p
        dzz = szz - p
        q = math.sqrt(0.5 * (dxx * dxx + dyy * dyy + dzz * dzz) + sxy * sxy)
        return q + prm[P_DP_ETA] * p - prm[P_DP_XI] * c
    sphi = prm[P_SINPHI]
    cphi = math.sqrt(max(1.0 - sphi * sphi, 0.0))
    m = 0.5 * (sxx + syy)
    rad = math.hypot(0.5 * (sxx - syy), sxy)
    s1 = max(m + rad, szz)
    s3 = min(m - rad, szz)
    return (s1 - s3) + (s1 + s3) * sphi - 2.0 * c * cphi


def mc_matched_dp(c, sinphi, sinpsi, fit="plane_strain"):
    """Drucker–Prager constants (η, ξ, η̄) matched to Mohr–Coulomb (c, φ, ψ).

    de Souza Neto et al., section 8.3 (eqs. 8.86–8.89, table 8.1), for
    ``f = √J2 + η p − ξ c`` with the same cohesion c:

    * ``"plane_strain"``: same collapse loads in plane strain,
      ``η = 3 tanφ / √(9 + 12 tan²φ)``, ``ξ = 3 / √(9 + 12 tan²φ)``;
    * ``"outer"``: cone through the outer (compressive) edges,
      ``η = 6 sinφ / (√3 (3 − sinφ))``, ``ξ = 6 cosφ / (√3 (3 − sinφ))``;
    * ``"inner"``: cone through the inner (tensile) edges, with ``3 + sinφ``.

    η̄ is η's formula with ψ. The cohesion only enters through ξ c, so ``c`` is merely
    checked (c ≥ 0).
    """
    if not c >= 0.0:
        raise ValueError(f"cohesion must be >= 0, got {c}")
    for s in (sinphi, sinpsi):
        if not 0.0 <= s < 1.0:
            raise ValueError(f"sin of friction/dilatancy angle must be in [0, 1), got {s}")

    def pair(s):
        cs = math.sqrt(1.0 - s * s)
        if fit == "plane_strain":
            t = s / cs
            d = math.sqrt(9.0 + 12.0 * t * t)
            return 3.0 * t / d, 3.0 / d
        if fit == "outer":
            d = math.sqrt(3.0) * (3.0 - s)
        elif fit == "inner":
            d = math.sqrt(3.0) * (3.0 + s)
        else:
            raise ValueError(f"fit must be 'plane_strain', 'outer' or 'inner', got {fit!r}")
        return 6.0 * s / d, 6.0 * cs / d

    eta, xi = pair(sinphi)
    etab, _ = pair(sinpsi)
    return eta, xi, etab
