"""Kernel-level tests of the block plasticity (``masonry_fdem.materials._plastic_kernels``).

Every check is against a closed-form value derived in the test (SI units). Tolerances are
stated where they are used.
"""

import math

import numpy as np
import pytest

from masonry_fdem.materials import _plastic_kernels as pk

MU = 1.0e9  # shear modulus [Pa]
LAM = 1.5e9  # Lamé λ [Pa] (ν = 0.3)
C0 = 1.0e6  # cohesion [Pa]


def params(
    *,
    surface=0,
    plane_stress=False,
    c=C0,
    phi_deg=30.0,
    psi_deg=0.0,
    h=0.0,
    cmin=0.0,
    eta_visc=0.0,
    fit="plane_strain",
    lam=LAM,
    mu=MU,
):
    """Parameter vector; the DP constants are matched to MC with ``fit``."""
    prm = np.zeros(pk.N_PRM)
    sphi = math.sin(math.radians(phi_deg))
    spsi = math.sin(math.radians(psi_deg))
    prm[pk.P_LAM] = lam
    prm[pk.P_MU] = mu
    prm[pk.P_C] = c
    prm[pk.P_SINPHI] = sphi
    prm[pk.P_SINPSI] = spsi
    prm[pk.P_H] = h
    prm[pk.P_CMIN] = cmin
    prm[pk.P_ETA] = eta_visc
    prm[pk.P_PLANE_STRESS] = 1.0 if plane_stress else 0.0
    prm[pk.P_SURFACE] = float(surface)
    eta, xi, etab = pk.mc_matched_dp(c, sphi, spsi, fit)
    prm[pk.P_DP_ETA] = eta
    prm[pk.P_DP_XI] = xi
    prm[pk.P_DP_ETABAR] = etab
    return prm


class Points:
    """Arrays of the kernel for ``n`` points, with commit."""

    def __init__(self, n=1):
        self.strain = np.zeros((n, 3))
        self.state0 = np.zeros((n, pk.N_STATE))
        self.state1 = np.zeros((n, pk.N_STATE))
        self.stress = np.zeros((n, 4))
        self.energy = np.zeros(n)
        self.qps = np.arange(n, dtype=np.int64)

    def update(self, prm, dt=np.inf):
        pk.plastic_update(
            self.strain, self.state0, self.state1, self.stress, self.energy, self.qps, prm, dt
        )
        return self.stress

    def commit(self):
        self.state0[:] = self.state1


def uniaxial_step(pts, prm, exx, eyy_guess):
    """Set Exx and solve Eyy (secant) so that σyy = 0 at point 0; returns Eyy."""

    def syy(eyy):
        pts.strain[0] = exx, eyy, 0.0
        return pts.update(prm)[0, 1]

    e0, f0 = eyy_guess, syy(eyy_guess)
    e1 = e0 - f0 / (2.0 * prm[pk.P_MU])
    for _ in range(100):
        f1 = syy(e1)
        if abs(f1) <= 1e-13 * C0:
            return e1
        e0, e1, f0 = e1, e1 - f1 * (e1 - e0) / (f1 - f0), f1
    raise AssertionError("uniaxial secant did not converge")


# 1 ------------------------------------------------------------------------------------


@pytest.mark.parametrize("surface", [0, 1])
@pytest.mark.parametrize("plane_stress", [False, True])
def test_elastic_range(surface, plane_stress):
    rng = np.random.default_rng(1)
    n = 50
    prm = params(surface=surface, plane_stress=plane_stress, c=1e12)  # never yields
    pts = Points(n)
    pts.strain[:] = rng.uniform(-1e-3, 1e-3, (n, 3))
    pts.state0[:, pk.S_EZZ] = rng.uniform(-1e-3, 1e-3, n)  # a starting guess only
    s = pts.update(prm).copy()
    exx, eyy, exy = pts.strain.T
    lam = 2 * LAM * MU / (LAM + 2 * MU) if plane_stress else LAM  # λ* = 2λμ/(λ+2μ)
    sxx = lam * (exx + eyy) + 2 * MU * exx
    syy = lam * (exx + eyy) + 2 * MU * eyy
    sxy = 2 * MU * exy
    szz = np.zeros(n) if plane_stress else LAM * (exx + eyy)
    scale = np.abs(sxx) + np.abs(syy) + np.abs(sxy)
    for got, want in ((s[:, 0], sxx), (s[:, 1], syy), (s[:, 2], sxy), (s[:, 3], szz)):
        assert np.all(np.abs(got - want) <= 1e-12 * scale)
    ezz = -LAM * (exx + eyy) / (LAM + 2 * MU) if plane_stress else 0.0
    assert np.allclose(pts.state1[:, pk.S_EZZ], ezz, rtol=1e-12, atol=0)
    w = 0.5 * (sxx * exx + syy * eyy + 2 * sxy * exy)  # σzz εzz = 0 in both cases
    assert np.allclose(pts.energy, w, rtol=1e-12, atol=0)
    assert np.all(pts.state1[:, : pk.S_ALPHA + 1] == 0.0)
    assert np.all(pts.state1[:, pk.S_WP] == 0.0)


# 2 ------------------------------------------------------------------------------------


@pytest.mark.parametrize("phi_deg", [0.0, 30.0])
def test_mc_plane_strain_pure_shear_plateau(phi_deg):
    # ψ = 0, Exx = Eyy = 0: principal (τ, 0, −τ), f = 2τ − 2c cosφ → τ = c cosφ
    prm = params(surface=0, phi_deg=phi_deg, psi_deg=0.0)
    tau_y = C0 * math.cos(math.radians(phi_deg))
    pts = Points()
    exys = np.linspace(0.0, 5 * tau_y / (2 * MU), 41)[1:]
    for exy in exys:
        pts.strain[0] = 0.0, 0.0, exy
        s = pts.update(prm)[0]
        pts.commit()
        tau = min(2 * MU * exy, tau_y)
        assert abs(s[2] - tau) <= 1e-8 * tau
        assert np.all(np.abs(s[[0, 1, 3]]) <= 1e-12 * tau_y)
    # plastic work of perfect plasticity: τ · 2 εp_xy
    epxy = pts.state0[0, pk.S_EPXY]
    assert epxy == pytest.approx(exys[-1] - tau_y / (2 * MU), rel=1e-10)
    assert pts.state0[0, pk.S_WP] == pytest.approx(2 * tau_y * epxy, rel=1e-10)
    cphi = math.cos(math.radians(phi_deg))
    assert pts.state0[0, pk.S_ALPHA] == pytest.approx(2 * cphi * epxy, rel=1e-10)


@pytest.mark.parametrize("h", [0.05 * MU, -0.01 * MU])
def test_mc_pure_shear_hardening_with_floor(h):
    # ψ = 0 pure shear: εp_xy = Δγ, α = 2 cosφ εp_xy, τ = c(α) cosφ = 2μ (Exy − εp_xy)
    phi = math.radians(30.0)
    cmin = 0.4 * C0
    prm = params(surface=0, phi_deg=30.0, h=h, cmin=cmin)
    pts = Points()
    for exy in np.linspace(0.0, 40 * C0 / MU, 200)[1:]:
        pts.strain[0] = 0.0, 0.0, exy
        tau = pts.update(prm)[0, 2]
        pts.commit()
        if 2 * MU * exy <= C0 * math.cos(phi):
            want = 2 * MU * exy
        else:
            ep = (2 * MU * exy - C0 * math.cos(phi)) / (2 * MU + 2 * h * math.cos(phi) ** 2)
            if C0 + h * 2 * math.cos(phi) * ep < cmin:  # on the floor
                ep = exy - cmin * math.cos(phi) / (2 * MU)
            want = 2 * MU * (exy - ep)
        assert tau == pytest.approx(want, rel=1e-10)
    if h < 0:
        assert tau == pytest.approx(cmin * math.cos(phi), rel=1e-12)


# 3 ------------------------------------------------------------------------------------


@pytest.mark.parametrize("psi_deg", [0.0, 10.0, 30.0])
def test_mc_plane_stress_uniaxial(psi_deg):
    phi = math.radians(30.0)
    prm = params(surface=0, plane_stress=True, phi_deg=30.0, psi_deg=psi_deg)
    fc = 2 * C0 * math.cos(phi) / (1 - math.sin(phi))
    ft = 2 * C0 * math.cos(phi) / (1 + math.sin(phi))
    e_mod = MU * (3 * LAM + 2 * MU) / (LAM + MU)
    for sign, strength in ((-1.0, fc), (1.0, ft)):
        pts = Points()
        eyy = 0.0
        for exx in np.linspace(0.0, sign * 4 * strength / e_mod, 13)[1:]:
            eyy = uniaxial_step(pts, prm, exx, eyy)
            pts.commit()
        s = pts.stress[0]
        assert s[0] == pytest.approx(sign * strength, rel=1e-8)
        assert abs(s[2]) <= 1e-12 * strength and abs(s[3]) <= 1e-9 * C0


# 4 ------------------------------------------------------------------------------------


def test_dp_von_mises_pure_shear():
    # φ = 0 plane-strain fit: η = 0, ξ = 1 → √J2 = |τ| ≤ c
    prm = params(surface=1, phi_deg=0.0)
    assert (prm[pk.P_DP_ETA], prm[pk.P_DP_XI], prm[pk.P_DP_ETABAR]) == (0.0, 1.0, 0.0)
    pts = Points()
    for exy in np.linspace(0.0, 3 * C0 / MU, 31)[1:]:
        pts.strain[0] = 0.0, 0.0, exy
        s = pts.update(prm)[0]
        pts.commit()
        assert s[2] == pytest.approx(min(2 * MU * exy, C0), rel=1e-8)
        assert np.all(np.abs(s[[0, 1, 3]]) <= 1e-12 * C0)


@pytest.mark.parametrize("fit", ["plane_strain", "outer", "inner"])
def test_dp_plane_stress_uniaxial(fit):
    # σ = (−σc, 0, 0): p = −σc/3, √J2 = σc/√3 → σc = ξc/(1/√3 − η/3);
    # tension σt = ξc/(1/√3 + η/3)
    prm = params(surface=1, plane_stress=True, phi_deg=30.0, psi_deg=10.0, fit=fit)
    eta, xi = prm[pk.P_DP_ETA], prm[pk.P_DP_XI]
    fc = xi * C0 / (1 / math.sqrt(3) - eta / 3)
    ft = xi * C0 / (1 / math.sqrt(3) + eta / 3)
    e_mod = MU * (3 * LAM + 2 * MU) / (LAM + MU)
    for sign, strength in ((-1.0, fc), (1.0, ft)):
        pts = Points()
        eyy = 0.0
        for exx in np.linspace(0.0, sign * 4 * strength / e_mod, 13)[1:]:
            eyy = uniaxial_step(pts, prm, exx, eyy)
            pts.commit()
        assert pts.stress[0, 0] == pytest.approx(sign * strength, rel=1e-8)
        assert abs(pts.stress[0, 3]) <= 1e-9 * C0


def test_mc_matched_dp_tables():
    s = math.sin(math.radians(30.0))
    t = math.tan(math.radians(30.0))
    eta, xi, etab = pk.mc_matched_dp(C0, s, 0.0, "plane_strain")
    assert eta == pytest.approx(3 * t / math.sqrt(9 + 12 * t * t))
    assert xi == pytest.approx(3 / math.sqrt(9 + 12 * t * t))
    assert etab == 0.0
    # outer cone through the compressive meridian: same uniaxial compression strength
    eta, xi, _ = pk.mc_matched_dp(C0, s, s, "outer")
    fc_mc = 2 * math.cos(math.radians(30.0)) / (1 - s)
    assert xi / (1 / math.sqrt(3) - eta / 3) == pytest.approx(fc_mc)
    # inner cone through the tensile meridian: same uniaxial tension strength
    eta, xi, _ = pk.mc_matched_dp(C0, s, s, "inner")
    ft_mc = 2 * math.cos(math.radians(30.0)) / (1 + s)
    assert xi / (1 / math.sqrt(3) + eta / 3) == pytest.approx(ft_mc)
    with pytest.raises(ValueError):
        pk.mc_matched_dp(C0, s, s, "middle")


@pytest.mark.parametrize("surface", [0, 1])
def test_apex_hydrostatic_tension(surface):
    # equibiaxial stretch in plane strain far beyond yield ends at the apex:
    # MC p = c cotφ, DP p = ξc/η; all three normal stresses equal, no shear
    prm = params(surface=surface, phi_deg=30.0, psi_deg=20.0)
    pts = Points()
    pts.strain[0] = 1e-2, 1e-2, 0.0
    s = pts.update(prm)[0]
    p = (
        C0 / math.tan(math.radians(30.0))
        if surface == 0
        else (prm[pk.P_DP_XI] * C0 / prm[pk.P_DP_ETA])
    )
    for k in (0, 1, 3):
        assert s[k] == pytest.approx(p, rel=1e-10)
    assert abs(s[2]) <= 1e-12 * p


# 5 ------------------------------------------------------------------------------------


def test_perzyna_von_mises_pure_shear():
    # Plane strain pure shear at a constant tensor shear-strain rate ė = dExy/dt.
    # With k = c (φ = 0, η = 0, ξ = 1): √J2 = τ, ε̇p_xy = (τ − k)/(2 η_v) for τ > k, so
    # τ̇ = 2μ(ė − ε̇p_xy) = 2μė − (μ/η_v)(τ − k), i.e. for t ≥ t_y = k/(2μė):
    # τ(t) = k + 2 η_v ė (1 − exp(−μ (t − t_y)/η_v)).
    eta_v = 2e8  # [Pa·s], relaxation time η_v/μ = 0.2 s
    rate = 1e-3  # ė [1/s]
    dt = 1e-3  # [s]
    prm = params(surface=1, phi_deg=0.0, eta_visc=eta_v)
    t_y = C0 / (2 * MU * rate)
    over = 2 * eta_v * rate  # saturated overstress
    pts = Points()
    worst = 0.0
    for n in range(1, 1501):
        t = n * dt
        pts.strain[0] = 0.0, 0.0, rate * t
        tau = pts.update(prm, dt)[0, 2]
        pts.commit()
        exact = (
            2 * MU * rate * t if t <= t_y else (C0 + over * (1 - math.exp(-MU * (t - t_y) / eta_v)))
        )
        worst = max(worst, abs(tau - exact))
    assert worst <= 0.01 * over  # 1 % of the overstress (0.3 % of τ)
    assert tau == pytest.approx(C0 + over * (1 - math.exp(-5.0)), rel=1e-2)
    # dt → ∞: the rate-independent plateau τ = k, exactly
    pts = Points()
    for n in range(1, 31):
        pts.strain[0] = 0.0, 0.0, n * 0.1 * C0 / MU
        tau = pts.update(prm, np.inf)[0, 2]
        pts.commit()
    assert tau == pytest.approx(C0, rel=1e-12)


# 6, 7 ---------------------------------------------------------------------------------


@pytest.mark.parametrize("surface", [0, 1])
@pytest.mark.parametrize("plane_stress", [False, True])
@pytest.mark.parametrize("h", [0.0, 0.05 * MU, -0.02 * MU])
def test_consistency_random(surface, plane_stress, h):
    rng = np.random.default_rng(7)
    n = 600
    ey = C0 / MU
    cmin = 0.3 * C0
    pts = Points(n)
    pts.state0[:, : pk.S_EPXY + 1] = rng.uniform(-5 * ey, 5 * ey, (n, 4))
    if not plane_stress:
        pts.state0[:, pk.S_EPZZ] = -(pts.state0[:, pk.S_EPXX] + pts.state0[:, pk.S_EPYY])
    # elastic strain of random direction, from well inside to far outside the surface
    size = ey * 10.0 ** rng.uniform(-1.5, 1.5, (n, 1))
    direction = rng.normal(size=(n, 3))
    direction /= np.linalg.norm(direction, axis=1, keepdims=True)
    pts.strain[:] = pts.state0[:, [pk.S_EPXX, pk.S_EPYY, pk.S_EPXY]] + size * direction
    pts.state0[:, pk.S_ALPHA] = rng.uniform(0.0, 40 * ey, n)
    pts.state0[:, pk.S_EZZ] = rng.uniform(-5 * ey, 5 * ey, n)
    pts.qps = np.arange(0, n, 2, dtype=np.int64)  # every other point only
    pts.state1[:] = np.nan
    pts.stress[:] = np.nan
    before = pts.state0.copy()
    for fit, psi in (("plane_strain", 0.0), ("outer", 10.0), ("inner", 30.0)):
        prm = params(
            surface=surface,
            plane_stress=plane_stress,
            phi_deg=30.0,
            psi_deg=psi,
            h=h,
            cmin=cmin,
            fit=fit,
        )
        s = pts.update(prm)
        assert np.array_equal(pts.state0, before)  # committed state untouched
        assert np.all(np.isnan(pts.stress[1::2])) and np.all(np.isnan(pts.state1[1::2]))
        q = pts.qps
        alpha1 = pts.state1[q, pk.S_ALPHA]
        f = np.array([pk.yield_value(s[i], pts.state1[i, pk.S_ALPHA], prm) for i in q])
        plastic = alpha1 > before[q, pk.S_ALPHA]
        assert plastic.sum() > 0.3 * q.size and (~plastic).sum() > 0.1 * q.size
        assert np.all(f <= 1e-9 * C0)
        assert np.all(np.abs(f[plastic]) <= 1e-9 * C0)
        assert np.all(np.isfinite(pts.state1[q])) and np.all(np.isfinite(pts.energy[q]))
        assert np.all(pts.state1[q, pk.S_WP] >= before[q, pk.S_WP] - 1e-9 * C0 * ey)
        c = np.maximum(C0 + h * alpha1, cmin)
        assert np.all(c >= cmin)
        if plane_stress:  # 7: σzz = 0 by the solved Ezz
            assert np.all(np.abs(s[q, 3]) < 1e-9 * C0)
        else:
            assert np.all(pts.state1[q, pk.S_EZZ] == 0.0)
        # the stored strain decomposition reproduces the stress (elastic law on ε − εp)
        st = pts.state1[q]
        ezz = st[:, pk.S_EZZ] if plane_stress else 0.0
        exe = pts.strain[q, 0] - st[:, pk.S_EPXX]
        eye = pts.strain[q, 1] - st[:, pk.S_EPYY]
        eze = ezz - st[:, pk.S_EPZZ]
        tr = exe + eye + eze
        assert np.allclose(s[q, 0], LAM * tr + 2 * MU * exe, rtol=0, atol=1e-8 * C0)
        assert np.allclose(s[q, 3], LAM * tr + 2 * MU * eze, rtol=0, atol=1e-8 * C0)
        assert np.allclose(
            s[q, 2], 2 * MU * (pts.strain[q, 2] - st[:, pk.S_EPXY]), rtol=0, atol=1e-8 * C0
        )
