"""Fill as a Mohr–Coulomb continuum against its classical cases.

Rankine: a smooth rigid wall retaining a horizontal layer of cohesive-frictional soil
(c, φ) under self-weight. Moved away from the soil, the wall's thrust falls to the active
value P_a = ½ K_a γ H² − 2 c √K_a H; pushed into it, it rises to the passive value
P_p = ½ K_p γ H² + 2 c √K_p H, K_a = 1/K_p = (1 − sin φ)/(1 + sin φ) (Rankine 1857; with
cohesion, Bell 1915). The wall is a separate stiff block pressing on the fill through the
frictionless penalty contact, as the fill will press on an arch; the base and the far side
are smooth (rollers), so every depth reaches the Rankine state. Newton (the static solver)
traces it: self-weight first, then the wall's displacement.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from masonry_fdem import Material, Model
from masonry_fdem.geometry import BlockMesh, crossed_grid
from masonry_fdem.interactions import BlockContact, ContactSettings
from masonry_fdem.materials import MohrCoulomb
from masonry_fdem.materials.elastic import Hypothesis
from masonry_fdem.solvers import StaticSolver
from masonry_fdem.solvers.status import Status

H, L = 2.0, 4.0  # fill height and length [m]
SOIL = MohrCoulomb(density=1800.0, E=20e6, nu=0.3, c=2e3, phi=30.0, psi=0.0)


def retained_fill(n: int = 8) -> tuple[Model, BlockContact]:
    """Fill [0, L] × [0, H] (crossed triangles: no locking in isochoric flow) and a
    0.2 m steel wall left of it, taller than the fill (its nodes miss the base line)."""
    xf, cf = crossed_grid(np.linspace(0.0, L, n + 1), np.linspace(0.0, H, n + 1))
    xw, cw = crossed_grid(np.array([-0.2, 0.0]), np.linspace(-0.2, H + 0.2, n + 2))
    x = np.r_[xf, xw]
    cells = np.r_[cf, cw + len(xf)]
    cell_block = np.r_[np.zeros(len(cf), dtype=np.int64), np.ones(len(cw), dtype=np.int64)]
    blocks = BlockMesh.from_arrays(x, cells, cell_block, block_names=["fill", "wall"],
                                   material_names=["soil", "steel"], block_material=[0, 1])
    model = Model(blocks, {"soil": SOIL, "steel": Material(density=7850.0, E=210e9, nu=0.3)},
                  hypothesis="plane_strain", width=1.0)
    tol = 1e-9
    model.fix(lambda X: np.isclose(X[1], 0.0, atol=tol), components=(1,), name="base")
    model.fix(lambda X: np.isclose(X[0], L, atol=tol), components=(0,), name="far side")
    model.prescribe_velocity("wall", (0.0, 0.0), name="wall")
    model.add_gravity()
    return model, BlockContact(model, ContactSettings(friction=0.0))


def rankine_thrusts() -> tuple[float, float]:
    """(P_a, P_p) [N per m of wall] of SOIL over the height H."""
    gamma = SOIL.density * 9.81
    s = math.sin(math.radians(SOIL.phi))
    ka = (1.0 - s) / (1.0 + s)
    kp = 1.0 / ka
    pa = 0.5 * ka * gamma * H**2 - 2.0 * SOIL.c * math.sqrt(ka) * H
    pp = 0.5 * kp * gamma * H**2 + 2.0 * SOIL.c * math.sqrt(kp) * H
    return pa, pp


def test_rankine_active_and_passive_thrust_on_a_smooth_rigid_wall():
    pa, pp = rankine_thrusts()
    k0 = 0.5 * SOIL.nu / (1.0 - SOIL.nu) * SOIL.density * 9.81 * H**2  # elastic, at rest
    out = {}
    for mode, sign, path in (("active", -1.0, [0.5e-3, 1e-3, 2e-3, 4e-3]),
                             ("passive", 1.0, [4e-3, 8e-3, 16e-3, 18e-3, 20e-3])):
        model, contact = retained_fill()
        solver = StaticSolver(model, interactions=[contact])
        st = solver.settle()
        assert st.status is Status.LOAD_REACHED, st
        rest = solver.reactions()["wall"][0]
        thrust = []
        for d in path:
            st, _ = solver.advance(displacement={"wall": (sign * d, 0.0)}, steps=4)
            assert st.status is Status.LOAD_REACHED, (mode, d, st)
            thrust.append(solver.reactions()["wall"][0])
        out[mode] = (rest, np.array(thrust))
        print(f"\n{mode}: at rest {rest:.0f} N/m (elastic K0 {k0:.0f}); thrust "
              f"{np.array2string(np.array(thrust), precision=0)} N/m at "
              f"{np.array2string(np.array(path) * 1e3)} mm; Rankine {pa if sign < 0 else pp:.0f}")
    rest_a, act = out["active"]
    rest_p, pas = out["passive"]
    # settled at rest near the elastic K0 state (the penalty contact gives a little)
    assert abs(rest_a / k0 - 1.0) < 0.15
    assert abs(act[-1] / pa - 1.0) < 0.10
    assert abs(pas[-1] / pp - 1.0) < 0.10
    # limit states, not points on the way: the thrust has levelled off
    assert abs(act[-1] / act[-2] - 1.0) < 0.01 and abs(pas[-1] / pas[-2] - 1.0) < 0.01
    # and the elastic start was well away from them
    assert act[0] > 1.1 * pa and pas[0] < 0.6 * pp


def test_fill_in_plane_strain_beside_blocks_in_plane_stress():
    """Per-material hypotheses: two unit squares of the same elastic law, laterally
    confined and pressed by ε = 1e-6, carry σ_yy = (λ + 2μ) ε with the plane-strain λ for
    the one named in ``hypotheses`` and the plane-stress λ* = 2λμ/(λ + 2μ) for the other."""
    from masonry_fdem.solvers.status import Status

    law = Material(density=2000.0, E=50e6, nu=0.3)
    xs, cs = crossed_grid(np.linspace(0.0, 1.0, 3), np.linspace(0.0, 1.0, 3))
    x = np.r_[xs, xs + [2.0, 0.0]]
    cells = np.r_[cs, cs + len(xs)]
    blocks = BlockMesh.from_arrays(x, cells, np.r_[np.zeros(len(cs), dtype=np.int64),
                                                   np.ones(len(cs), dtype=np.int64)],
                                   block_names=["fill", "pier"], material_names=["soil", "stone"],
                                   block_material=[0, 1])
    model = Model(blocks, {"soil": law, "stone": law}, hypotheses={"soil": "plane_strain"})
    model.fix(lambda X: np.isclose(X[1], 0.0), components=(1,), name="base")
    model.fix(lambda X: np.isclose(X[0] % 2.0, 0.0) | np.isclose(X[0] % 2.0, 1.0),
              components=(0,), name="sides")
    eps = 1e-6
    for name, lo in (("fill top", 0.0), ("pier top", 2.0)):
        model.prescribe_nodes(lambda X, lo=lo: np.isclose(X[1], 1.0) & (X[0] >= lo - 1e-9)
                              & (X[0] <= lo + 1.0 + 1e-9), (None, 0.0), name=name)
    solver = StaticSolver(model)
    st, _ = solver.advance(displacement={"fill top": (None, -eps), "pier top": (None, -eps)})
    assert st.status is Status.LOAD_REACHED
    r = solver.reactions()
    mu = law.E / (2 * (1 + law.nu))
    lam = law.E * law.nu / ((1 + law.nu) * (1 - 2 * law.nu))
    lam_star = 2 * lam * mu / (lam + 2 * mu)
    strain_side, stress_side = -r["fill top"][1] / eps, -r["pier top"][1] / eps
    print(f"\nconfined moduli: plane strain {strain_side:.6e} Pa (λ+2μ = {lam + 2 * mu:.6e}), "
          f"plane stress {stress_side:.6e} Pa (λ*+2μ = {lam_star + 2 * mu:.6e})")
    assert abs(strain_side / (lam + 2 * mu) - 1.0) < 1e-4
    assert abs(stress_side / (lam_star + 2 * mu) - 1.0) < 1e-4
    assert model.hypotheses == {"soil": Hypothesis.PLANE_STRAIN, "stone": Hypothesis.PLANE_STRESS}
    with pytest.raises(ValueError, match="no material"):
        Model(blocks, {"soil": law, "stone": law}, hypotheses={"sand": "plane_strain"})
