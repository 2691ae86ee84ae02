"""Single-element and patch tests of the block laws against their analytic response in
uniaxial stress and in simple shear (dynamic relaxation on a four-triangle patch): 1e-8
relative for the elastic laws, 1 % for the inelastic ones."""

from __future__ import annotations

import math
import runpy
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
import ufl
from material_patch import L, Patch, svk_uniaxial
from scipy.optimize import brentq

from masonry_fdem import Material
from masonry_fdem.materials import (
    DruckerPrager,
    Hypothesis,
    MohrCoulomb,
    RankineDamage,
    lame_parameters,
)

ROOT = Path(__file__).resolve().parents[1]
DEMO = runpy.run_path(str(ROOT / "demos" / "materials.py"), run_name="materials_lib")

STEEL = dict(density=7850.0, E=200e9, nu=0.3)
STONE = dict(density=2400.0, E=20e9, nu=0.2)


def rel(a, b):
    return abs(a - b) / abs(b)


def svk_P(lam, mu, H):
    F = np.eye(2) + H
    E = 0.5 * (H + H.T + H.T @ H)
    S = lam * np.trace(E) * np.eye(2) + 2 * mu * E
    return F @ S


def shear_H(g):
    return np.array([[0.0, g], [0.0, 0.0]])


# ------------------------------------------------------------------ elastic laws
@pytest.mark.parametrize("hyp", ["plane_stress", "plane_strain"])
def test_svk_patch_uniaxial_and_shear(hyp):
    mat = Material(**STEEL)
    lam, mu = lame_parameters(mat, Hypothesis(hyp))
    up = Patch(mat, "uniaxial", hyp, centre=(0.37, 0.61))
    errs = []
    for e in (1e-3, 0.05):
        P = up.step(e)
        errs.append(rel(P[0], svk_uniaxial(lam, mu, e)))
        assert errs[-1] < 1e-8
    sp = Patch(mat, "shear", hyp, centre=(0.37, 0.61))
    for g in (1e-3, 0.04):
        P = sp.step(g)
        Pa = svk_P(lam, mu, shear_H(g))
        errs.append(np.linalg.norm(P - Pa[:, 1]) / np.linalg.norm(Pa[:, 1]))
        assert errs[-1] < 1e-8
    print(f"\nSt. Venant-Kirchhoff, {hyp}: largest relative error {max(errs):.1e}")
    # every cell of the patch carries the analytic Cauchy stress
    F = np.eye(2) + shear_H(0.04)
    sigma = svk_P(lam, mu, shear_H(0.04)) @ F.T / np.linalg.det(F)
    cells = sp.model.update_stress().x.array.reshape(-1, 2, 2)
    assert np.abs(cells - sigma).max() < 1e-8 * np.abs(sigma).max()


def neo_hooke_uniaxial(lam, mu, a):
    """Plane-strain compressible neo-Hookean, uniaxial stress: P11 at stretch a."""
    p22 = lambda b: mu * (b - 1 / b) + lam * math.log(a * b) / b  # noqa: E731
    b = brentq(p22, 0.5, 1.5, xtol=1e-15, rtol=1e-15)
    return mu * (a - 1 / a) + lam * math.log(a * b) / a


def test_user_defined_neo_hooke_law_patch():
    NeoHooke = DEMO["NeoHooke"]
    mat = NeoHooke(density=1100.0, E=5e6, nu=0.45)
    lam, mu = lame_parameters(mat, Hypothesis.PLANE_STRAIN)
    up = Patch(mat, "uniaxial", "plane_strain", centre=(0.44, 0.52))
    errs = []
    for e in (0.01, 0.3):
        P = up.step(e)
        errs.append(rel(P[0], neo_hooke_uniaxial(lam, mu, 1 + e)))
        assert errs[-1] < 1e-8
    sp = Patch(mat, "shear", "plane_strain", centre=(0.44, 0.52))
    g = 0.25
    P = sp.step(g)
    F = np.eye(2) + shear_H(g)
    Finv_T = np.linalg.inv(F).T
    Pa = mu * (F - Finv_T) + lam * math.log(np.linalg.det(F)) * Finv_T
    # the traction (P01, P11) on the top edge; P11 vanishes for this law (J = 1)
    errs.append(np.linalg.norm(P - Pa[:, 1]) / np.linalg.norm(Pa[:, 1]))
    print(f"\nneo-Hookean user law: largest relative error {max(errs):.1e}")
    assert errs[-1] < 1e-8


@dataclass(frozen=True)
class Orthotropic(Material):
    """A user law on the Green–Lagrange strain: orthotropic St. Venant–Kirchhoff in plane
    stress (homogenised masonry), E = E_x ≥ E_y, nu = ν_xy."""

    Ey: float = 1.0
    Gxy: float = 1.0

    def second_piola(self, k):
        d = 1.0 - self.nu**2 * self.Ey / self.E
        q11, q22, q12 = self.E / d, self.Ey / d, self.nu * self.Ey / d
        e = k.E
        return ufl.as_matrix([[q11 * e[0, 0] + q12 * e[1, 1], 2 * self.Gxy * e[0, 1]],
                              [2 * self.Gxy * e[0, 1], q12 * e[0, 0] + q22 * e[1, 1]]])


def test_user_defined_orthotropic_law_on_green_lagrange_strain():
    mat = Orthotropic(density=1800.0, E=6e9, nu=0.15, Ey=3e9, Gxy=1.5e9)
    up = Patch(mat, "uniaxial", centre=(0.4, 0.6))
    errs = []
    for e in (1e-3, 0.03):
        P = up.step(e)  # S_yy = 0 makes S_xx = E_x E_xx whatever E_y
        errs.append(rel(P[0], (1 + e) * mat.E * (e + 0.5 * e * e)))
        assert errs[-1] < 1e-8
    sp = Patch(mat, "shear", centre=(0.4, 0.6))
    g = 0.02
    P = sp.step(g)
    d = 1.0 - mat.nu**2 * mat.Ey / mat.E
    S = np.array([[mat.nu * mat.Ey / d * g * g / 2, mat.Gxy * g],
                  [mat.Gxy * g, mat.Ey / d * g * g / 2]])
    Pa = (np.eye(2) + shear_H(g)) @ S
    errs.append(np.linalg.norm(P - Pa[:, 1]) / np.linalg.norm(Pa[:, 1]))
    print(f"\northotropic user law: largest relative error {max(errs):.1e}")
    assert errs[-1] < 1e-8


# ------------------------------------------------------------------ damage
DAMAGE = RankineDamage(**STONE, ft=2e6, Gf=60.0)


def damage_P(mat, H, kappa_prev, h):
    """Analytic response of the Rankine damage law at displacement gradient H."""
    lam, mu = lame_parameters(mat, Hypothesis.PLANE_STRESS)
    F = np.eye(2) + H
    E = 0.5 * (H + H.T + H.T @ H)
    S0 = lam * np.trace(E) * np.eye(2) + 2 * mu * E
    s1 = max(np.linalg.eigvalsh(S0).max(), 0.0)
    kappa = max(kappa_prev, s1 / mat.E)
    e0 = mat.ft / mat.E
    es = mat.Gf / (mat.ft * h) - 0.5 * e0
    d = min(max(1 - e0 / kappa * math.exp(-(kappa - e0) / es), 0.0), mat.d_max)
    return F @ ((1 - d) * S0), kappa


@pytest.mark.parametrize("mode", ["uniaxial", "shear"])
def test_rankine_damage_softening_path(mode):
    """Single-element test: every node follows the homogeneous path (a softening patch
    with free nodes would localise), uniaxial stress or simple shear."""
    p = Patch(DAMAGE, "affine")  # centre node in the middle: four cells, h = L/sqrt(2)
    h = L / math.sqrt(2.0)
    lam, mu = lame_parameters(DAMAGE, Hypothesis.PLANE_STRESS)
    e0 = DAMAGE.eps0
    kappa = e0
    worst = 0.0
    peak = 0.0
    path = e0 * np.r_[np.linspace(0.2, 1.0, 5), np.linspace(1.2, 10.0, 23)]
    if mode == "shear":
        path = path * DAMAGE.E / mu  # the effective principal stress is about μ γ
    for v in path:
        if mode == "uniaxial":
            # uniaxial stress: the lateral effective stress vanishes (damage is isotropic)
            E11 = v + 0.5 * v * v
            E22 = -lam / (lam + 2 * mu) * E11
            H = np.diag([v, math.sqrt(1 + 2 * E22) - 1])
        else:
            H = shear_H(v)
        P = p.affine(H)
        Pa, kappa = damage_P(DAMAGE, H, kappa, h)
        peak = max(peak, np.linalg.norm(Pa[:, 0]))
        worst = max(worst, np.linalg.norm(P - Pa[:, 0]) / peak)
    final = np.linalg.norm(Pa[:, 0]) / peak
    print(f"\nRankine damage, {mode}: worst deviation {worst:.2e} of the peak; "
          f"final/peak {final:.3f}")
    assert worst < 0.01
    assert final < 0.25  # the path went well into softening


# ------------------------------------------------------------------ plasticity
MC = MohrCoulomb(**STONE, c=1.0e6, phi=30.0, psi=0.0)


def test_mohr_coulomb_shear_plane_strain():
    p = Patch(MC, "shear", "plane_strain")
    mu = MC.E / (2 * (1 + MC.nu))
    g_y = MC.c * math.cos(math.radians(MC.phi)) / mu
    errs = []
    for g in (0.5 * g_y, 2 * g_y, 5 * g_y):
        P = p.step(g)
        tau = min(mu * g, MC.c * math.cos(math.radians(MC.phi)))
        errs.append(rel(P[0], tau))
        assert errs[-1] < 0.01, (g / g_y, P[0], tau)
    print(f"\nMohr-Coulomb shear, plane strain: largest relative error {max(errs):.1e}")


@pytest.mark.parametrize("sign", [-1.0, 1.0])
def test_mohr_coulomb_uniaxial_plane_stress(sign):
    p = Patch(MC, "uniaxial", "plane_stress")
    strength = MC.fc if sign < 0 else MC.ft
    e_y = strength / MC.E
    errs = []
    for f in (0.5, 1.5, 4.0):
        e = sign * f * e_y
        P = p.step(e)
        # Hencky: Kirchhoff stress E ln(1 + e) up to the strength, P = τ / (1 + e)
        want = sign * min(MC.E * abs(math.log1p(e)), strength) / (1 + e)
        errs.append(rel(P[0], want))
        assert errs[-1] < 0.01, (f, P[0], want)
    print(f"\nMohr-Coulomb uniaxial {'compression' if sign < 0 else 'tension'}, plane "
          f"stress: largest relative error {max(errs):.1e}")


def test_drucker_prager_matched_shear_and_uniaxial():
    dp0 = DruckerPrager(**STONE, c=1.0e6, phi=0.0)
    p = Patch(dp0, "shear", "plane_strain")
    mu = dp0.E / (2 * (1 + dp0.nu))
    P = p.step(4 * dp0.c / mu)
    e_shear = rel(P[0], dp0.c)
    assert e_shear < 0.01  # plane-strain fit with φ = 0: √J₂ ≤ c
    dp = DruckerPrager(**STONE, c=1.0e6, phi=30.0, psi=10.0)
    eta, xi, _ = dp.cone()
    # uniaxial compression σ: √J₂ = σ/√3, p = −σ/3 → σ (1/√3 − η/3) = ξ c
    sigma = xi * dp.c / (1 / math.sqrt(3) - eta / 3)
    p = Patch(dp, "uniaxial", "plane_stress")
    e = -3 * sigma / dp.E
    P = p.step(e)
    e_uni = rel(P[0], -sigma / (1 + e))  # Kirchhoff −σ, P = τ / (1 + e)
    print(f"\nDrucker-Prager: shear error {e_shear:.1e}, uniaxial compression error {e_uni:.1e}")
    assert e_uni < 0.01


def test_perzyna_shear_at_constant_rate():
    """Von Mises (DP, φ = 0) with Perzyna viscosity η_v sheared at the rate γ̇:
    τ = c + η_v γ̇ (1 − exp(−μ (t − t_y)/η_v)) after yield at t_y = c/(μ γ̇)."""
    eta_v = 2.0e6  # [Pa s]
    mat = DruckerPrager(**STONE, c=1.0e6, phi=0.0, viscosity=eta_v)
    mu = mat.E / (2 * (1 + mat.nu))
    rate = 0.5  # [1/s]
    t_y = mat.c / (mu * rate)
    tau_rel = eta_v / mu  # relaxation time [s]
    p = Patch(mat, "shear", "plane_strain")
    t_end = t_y + 4 * tau_rel
    n = 400
    dt = t_end / n
    worst = 0.0
    for i in range(1, n + 1):
        t = i * dt
        P = p.step(rate * t, dt=dt)
        want = mu * rate * t if t <= t_y else mat.c + eta_v * rate * (
            1 - math.exp(-(t - t_y) / tau_rel))
        worst = max(worst, abs(P[0] - want) / (mat.c + eta_v * rate))
    print(f"\nPerzyna shear: worst deviation {worst:.2e} of the viscous plateau")
    assert worst < 0.01
    # the overstress is real: well above the rate-independent strength at the end
    assert P[0] > mat.c + 0.9 * eta_v * rate


def test_perzyna_uniaxial_stress_at_constant_rate():
    """Von Mises (DP, φ = 0: √J₂ ≤ c) with Perzyna viscosity, pulled in uniaxial stress
    (plane stress) at the strain rate ε̇: σ̇ = E ε̇ − E (σ − √3 c)/(3 η_v) gives
    σ = √3 c + 3 η_v ε̇ (1 − exp(−E (t − t_y)/(3 η_v))) after t_y = √3 c/(E ε̇)."""
    eta_v = 2.0e6  # [Pa s]
    mat = DruckerPrager(**STONE, c=1.0e6, phi=0.0, viscosity=eta_v)
    rate = 0.5  # [1/s]
    s_y = math.sqrt(3.0) * mat.c
    t_y = s_y / (mat.E * rate)
    tau_rel = 3.0 * eta_v / mat.E
    p = Patch(mat, "uniaxial", "plane_stress")
    n = 600
    dt = (t_y + 4 * tau_rel) / n
    worst = 0.0
    for i in range(1, n + 1):
        t = i * dt
        e = rate * t
        P = p.step(e, dt=dt)
        sigma = mat.E * e if t <= t_y else s_y + 3 * eta_v * rate * (
            1 - math.exp(-(t - t_y) / tau_rel))
        worst = max(worst, abs(P[0] - sigma) / (s_y + 3 * eta_v * rate))
    print(f"\nPerzyna uniaxial: worst deviation {worst:.2e} of the viscous plateau")
    assert worst < 0.01
    assert P[0] > s_y + 0.9 * 3 * eta_v * rate


def test_history_committed_only_at_converged_increment():
    p = Patch(DAMAGE, "uniaxial", centre=(0.45, 0.5))
    p.step(0.5 * DAMAGE.eps0)
    kappa0 = p.model.history("kappa").copy()
    p.dr.max_iter = 3  # this increment cannot converge
    res = p.dr.solve(0.0, displacement={"drive": (3 * DAMAGE.eps0 * L, None)})
    assert not res.converged
    assert np.array_equal(p.model.history("kappa"), kappa0)  # nothing committed
    p.dr.max_iter = 200_000
    p.step(3 * DAMAGE.eps0)
    # committed now: the patch cracked in this increment (localised in one cell)
    assert p.model.history("kappa").max() > 2.5 * DAMAGE.eps0


def test_explicit_solver_commits_the_plastic_state_every_step():
    """The patch sheared slowly by the explicit solver (plane strain, Mohr–Coulomb):
    the shear traction levels off at c cos φ as under dynamic relaxation."""
    from material_patch import W, near, patch_mesh

    from masonry_fdem import Model
    from masonry_fdem.solvers import ExplicitSolver

    m = Model(patch_mesh((0.4, 0.55)), {"m": MC}, hypothesis="plane_strain", width=W)
    mu = MC.E / (2 * (1 + MC.nu))
    tau_y = MC.c * math.cos(math.radians(MC.phi))
    g_end = 5 * tau_y / mu
    t_end = 4e-3  # ≈ 100 periods of the patch's lowest mode: quasi-static
    v = g_end * L / t_end
    m.fix(lambda X: near(X[1], 0.0), name="bottom")
    m.prescribe_nodes(lambda X: near(X[1], L), (v, 0.0), name="drive")
    s = ExplicitSolver(m, damping=5e3)
    s.run(t_end=t_end)
    # the stress in the cells (the reaction of the driven nodes also carries their
    # damping force)
    tau = m.update_stress().x.array.reshape(-1, 2, 2)[:, 0, 1]
    print(f"\nexplicit MC shear: tau = {np.array2string(tau, precision=6)} Pa, "
          f"c cos(phi) = {tau_y:.6g} Pa")
    assert np.all(np.abs(tau / tau_y - 1.0) < 0.01)
    assert np.all(m.plastic_state()[:, 4] > 0)  # α committed in every cell


def test_bad_material_input_is_refused_with_a_clear_message():
    with pytest.raises(ValueError, match="ft must be"):
        RankineDamage(**STONE, ft=-1.0, Gf=60.0)
    with pytest.raises(ValueError, match="dilatancy angle"):
        MohrCoulomb(**STONE, c=1e6, phi=20.0, psi=30.0)
    with pytest.raises(ValueError, match="no strength"):
        MohrCoulomb(**STONE, c=0.0, phi=0.0)
    with pytest.raises(ValueError, match="fit must be"):
        DruckerPrager(**STONE, c=1e6, phi=20.0, fit="middle")
    brick = MohrCoulomb.from_strengths(**STONE, fc=12e6, ft=1.2e6)
    assert brick.fc == pytest.approx(12e6, rel=1e-12) and brick.ft == pytest.approx(1.2e6,
                                                                                  rel=1e-12)
    with pytest.raises(ValueError, match="0 < ft <= fc"):
        MohrCoulomb.from_strengths(**STONE, fc=1e6, ft=2e6)
    with pytest.raises(ValueError, match="viscosity"):
        DruckerPrager(**STONE, c=1e6, phi=20.0, viscosity=-1.0)
    # a softening law on elements too large for its fracture energy (snap-back)
    brittle = RankineDamage(**STONE, ft=5e6, Gf=1.0)  # 2 E Gf / ft^2 = 1.6 mm
    with pytest.raises(ValueError, match="snaps back"):
        Patch(brittle, "uniaxial")

    class Broken(Material):
        def first_piola(self, k):
            return ufl.tr(k.E)  # a scalar, not a stress

    with pytest.raises(ValueError, match="2x2 UFL tensor"):
        Patch(Broken(**STONE), "uniaxial")
