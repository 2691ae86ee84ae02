"""Finite-strain (Hencky) plasticity by the exponential map, around the small-strain
return mappings of :mod:`masonry_fdem.materials._plastic_kernels`.

Multiplicative split F = Fᵉ Fᵖ, stored as the inverse plastic metric Cᵖ⁻¹ = (FᵖᵀFᵖ)⁻¹.
At each point (Simo 1992; de Souza Neto, Perić & Owen 2008, ch. 14):

1. trial elastic left stretch bᵉ = F Cᵖ⁻¹ Fᵀ and trial Hencky strain εᵉ = ½ ln bᵉ;
2. the small-strain return mapping on εᵉ (Mohr–Coulomb or Drucker–Prager, same
   constants): Kirchhoff stress τ = λ tr εᵉ I + 2μ εᵉ and the plastic increment Δεᵖ —
   exact for isotropic laws, whose trial and final stresses are coaxial;
3. bᵉ ← exp(2 (εᵉ − Δεᵖ)), Cᵖ⁻¹ ← F⁻¹ bᵉ F⁻ᵀ; the second Piola–Kirchhoff stress
   S = F⁻¹ τ F⁻ᵀ enters the total-Lagrangian internal force.

Isochoric plastic flow stays isochoric at any strain (ln det bᵉ carries the volume), and
rigid rotations leave S unchanged. For small strains it reduces to the additive law.
Out of plane: plane strain F_zz = 1 (Cᵖ⁻¹_zz is tracked); plane stress solves the elastic
ε_zz for τ_zz = 0. Units SI (Pa, J/m³ per reference volume).
"""

from __future__ import annotations

import math

from numba import njit

from masonry_fdem.materials._plastic_kernels import N_STATE, P_PLANE_STRESS, _point_update

# state columns (N_STATE of them)
C_XX, C_YY, C_ZZ, C_XY = 0, 1, 2, 3  # Cᵖ⁻¹ − I (stored minus I: no cancellation)
S_ALPHA = 4  # accumulated equivalent plastic strain α
S_EZZ = 5  # plane stress: the last elastic Hencky ε_zz (starting guess)
S_WP = 6  # plastic work density ∫ τ:dεᵖ [J/m³ of reference volume]

__all__ = ["finite_plastic_update", "initial_state", "C_XX", "C_YY", "C_ZZ", "C_XY",
           "S_ALPHA", "S_EZZ", "S_WP", "N_STATE"]


@njit(cache=True)
def _sym_fun(a, b, c, kind):
    """Isotropic functions of the symmetric 2×2 [[a, c], [c, b]], without cancellation.

    kind 0: the argument is B − I; returns ½ ln B (log1p of the eigenvalues).
    kind 1: the argument is G; returns exp(2 G) − I (expm1 of the eigenvalues).
    """
    m = 0.5 * (a + b)
    d = 0.5 * (a - b)
    r = math.sqrt(d * d + c * c)
    l1 = m + r
    l2 = m - r
    if kind == 0:
        f1 = 0.5 * math.log1p(l1)
        f2 = 0.5 * math.log1p(l2)
    else:
        f1 = math.expm1(2.0 * l1)
        f2 = math.expm1(2.0 * l2)
    if r == 0.0:
        return f1, f1, 0.0
    # the eigenvector of l1 makes the angle θ with x: cos 2θ = d/r, sin 2θ = c/r
    fm = 0.5 * (f1 + f2)
    fd = 0.5 * (f1 - f2)
    return fm + fd * (d / r), fm - fd * (d / r), fd * (c / r)


def initial_state(n):
    """Virgin state rows: Cᵖ⁻¹ = I (stored as 0), α = 0: all zeros."""
    import numpy as np

    return np.zeros((n, N_STATE))


@njit(cache=True)
def finite_plastic_update(grad, state0, state1, stress, energy, qps, prm, dt):
    """Exponential-map return at the points ``qps``.

    Args:
        grad: (nq, 4) displacement gradient H00, H01, H10, H11 (F = I + H).
        state0: (nq, N_STATE) committed state (read only); state1: trial state (written).
        stress: (nq, 4) written: second Piola–Kirchhoff Sxx, Syy, Sxy [Pa] and τ_zz.
        energy: (nq,) written: Hencky elastic energy ½ τ:εᵉ [J/m³].
        qps: (k,) int64 points to update. prm: the return-mapping parameters.
        dt: time increment [s] for Perzyna (inf: rate independent).
    """
    plane_stress = prm[P_PLANE_STRESS] == 1.0
    for i in range(qps.shape[0]):
        q = qps[i]
        f00 = 1.0 + grad[q, 0]
        f01 = grad[q, 1]
        f10 = grad[q, 2]
        f11 = 1.0 + grad[q, 3]
        dxx = state0[q, C_XX]  # D = Cᵖ⁻¹ − I
        dyy = state0[q, C_YY]
        dxy = state0[q, C_XY]
        dzz = state0[q, C_ZZ]
        h00 = grad[q, 0]
        h01 = grad[q, 1]
        h10 = grad[q, 2]
        h11 = grad[q, 3]
        # bᵉ − I = H + Hᵀ + H Hᵀ + F D Fᵀ
        t00 = f00 * dxx + f01 * dxy
        t01 = f00 * dxy + f01 * dyy
        t10 = f10 * dxx + f11 * dxy
        t11 = f10 * dxy + f11 * dyy
        det = f00 * f11 - f01 * f10
        if not det > 0.0:
            # an inverted (or flattened) element, as a Newton iterate may try: no stress
            # exists; NaN tells the solver (a failed iterate, not a crash)
            for j in range(N_STATE):
                state1[q, j] = state0[q, j]
            for j in range(4):
                stress[q, j] = math.nan
            energy[q] = math.nan
            continue
        bxx = 2.0 * h00 + h00 * h00 + h01 * h01 + t00 * f00 + t01 * f01
        byy = 2.0 * h11 + h10 * h10 + h11 * h11 + t10 * f10 + t11 * f11
        bxy = h01 + h10 + h00 * h10 + h01 * h11 + t00 * f10 + t01 * f11
        exx, eyy, exy = _sym_fun(bxx, byy, bxy, 0)
        if plane_stress:
            pzz0 = 0.0
            ezz_prev = state0[q, S_EZZ]
        else:
            pzz0 = -0.5 * math.log1p(dzz)  # εᵉ_zz = 0 − pzz0 = ½ ln Cᵖ⁻¹_zz
            ezz_prev = 0.0
        sxx, syy, sxy, szz, nxx, nyy, nzz, nxy, a1, ezz = _point_update(
            exx, eyy, exy, ezz_prev, 0.0, 0.0, pzz0, 0.0, state0[q, S_ALPHA], prm, dt)
        i00 = f11 / det
        i01 = -f01 / det
        i10 = -f10 / det
        i11 = f00 / det
        if nxx == 0.0 and nyy == 0.0 and nxy == 0.0 and nzz == pzz0:
            # elastic: the plastic metric stays
            for j in range(N_STATE):
                state1[q, j] = state0[q, j]
            state1[q, S_EZZ] = ezz
            gzz = ezz - nzz
            energy[q] = 0.5 * (sxx * exx + syy * eyy + szz * gzz + 2.0 * sxy * exy)
        else:
            _plastic_state(state0, state1, q, exx, eyy, exy, ezz, nxx, nyy, nzz, nxy, pzz0,
                           a1, sxx, syy, sxy, szz, h00, h01, h10, h11, i00, i01, i10, i11,
                           energy, plane_stress)
        v00 = i00 * sxx + i01 * sxy
        v01 = i00 * sxy + i01 * syy
        v10 = i10 * sxx + i11 * sxy
        v11 = i10 * sxy + i11 * syy
        stress[q, 0] = v00 * i00 + v01 * i01
        stress[q, 1] = v10 * i10 + v11 * i11
        stress[q, 2] = v00 * i10 + v01 * i11
        stress[q, 3] = szz


@njit(cache=True)
def _plastic_state(state0, state1, q, exx, eyy, exy, ezz, nxx, nyy, nzz, nxy, pzz0, a1, sxx,
                   syy, sxy, szz, h00, h01, h10, h11, i00, i01, i10, i11, energy,
                   plane_stress):
    """Trial state after a plastic return: Cᵖ⁻¹ from the new elastic strain, α, work."""
    # new elastic Hencky strain G and bᵉ − I = exp(2G) − I
    gxx = exx - nxx
    gyy = eyy - nyy
    gxy = exy - nxy
    gzz = ezz - nzz
    bxx, byy, bxy = _sym_fun(gxx, gyy, gxy, 1)
    # D = F⁻¹ (bᵉ − I) F⁻ᵀ + (C⁻¹ − I),  C⁻¹ − I = −C⁻¹ (H + Hᵀ + HᵀH)
    u00 = i00 * bxx + i01 * bxy
    u01 = i00 * bxy + i01 * byy
    u10 = i10 * bxx + i11 * bxy
    u11 = i10 * bxy + i11 * byy
    e00 = 2.0 * h00 + h00 * h00 + h10 * h10  # 2E = H + Hᵀ + HᵀH
    e11 = 2.0 * h11 + h01 * h01 + h11 * h11
    e01 = h01 + h10 + h00 * h01 + h10 * h11
    c00 = i00 * i00 + i01 * i01  # C⁻¹ = F⁻¹ F⁻ᵀ
    c11 = i10 * i10 + i11 * i11
    c01 = i00 * i10 + i01 * i11
    state1[q, C_XX] = u00 * i00 + u01 * i01 - (c00 * e00 + c01 * e01)
    state1[q, C_YY] = u10 * i10 + u11 * i11 - (c01 * e01 + c11 * e11)
    state1[q, C_XY] = u00 * i10 + u01 * i11 - (c00 * e01 + c01 * e11)
    state1[q, C_ZZ] = 0.0 if plane_stress else math.expm1(2.0 * gzz)
    state1[q, S_ALPHA] = a1
    state1[q, S_EZZ] = ezz
    dpzz = nzz - pzz0
    state1[q, S_WP] = state0[q, S_WP] + (
        sxx * nxx + syy * nyy + szz * dpzz + 2.0 * sxy * nxy)
    energy[q] = 0.5 * (sxx * gxx + syy * gyy + szz * gzz + 2.0 * sxy * gxy)
