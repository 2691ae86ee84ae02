"""Embedded anchors: bond–slip, steel, prestress, anchors across joints (issue #7).

Every test compares with a closed-form value: the bond law itself (a short, rigid anchor
slips uniformly), the shear-lag solution of a long elastic anchor, the steel law of the
bar, the equilibrium of a prestressed pair of blocks. Models are solved by dynamic
relaxation (quasi-static), in metres, newtons and pascals.
"""

import math

from mpi4py import MPI

import numpy as np
import pytest

from conftest import alternating_grid
from masonry_fdem import Material, Model
from masonry_fdem.anchors import (
    Anchor,
    Anchors,
    BondLaw,
    DowelLaw,
    SteelLaw,
    radial_anchors,
    intrados_stitch,
    straight_anchor,
    wall_ties,
)
from masonry_fdem.geometry import BlockMesh
from masonry_fdem.solvers import DynamicRelaxation, ExplicitSolver

RIGID_STEEL = SteelLaw(E=2e14, yield_stress=1e13, rupture_strain=1.0)
BRICK = Material(density=2000.0, E=5e9, nu=0.2)


def grid_blocks(boxes, h, material="brick", comm=MPI.COMM_WORLD):
    """Rectangular blocks (x0, y0, x1, y1) meshed on h × h grids, one block each."""
    xs, cells, cb = [], [], []
    n0 = 0
    for b, (x0, y0, x1, y1) in enumerate(boxes):
        x, c, _ = alternating_grid(x1 - x0, y1 - y0, h)
        xs.append(x + [x0, y0])
        cells.append(c + n0)
        cb.append(np.full(len(c), b))
        n0 += len(x)
    return BlockMesh.from_arrays(np.vstack(xs), np.vstack(cells), np.concatenate(cb),
                                 block_names=[f"block:{b}" for b in range(len(boxes))],
                                 material_names=[material])


def test_pull_out_of_a_short_anchor_follows_the_bond_law():
    """A short, (nearly) rigid anchor bonded over L = 0.2 m in a fixed block slips
    uniformly, so the pull-out force is F(s) = π d L τ(s) for the bond law τ: rising
    (k0 = 15 GPa/m), plateau, softening to a residual. Limit 1 % of the peak force."""
    blocks = grid_blocks([(0.0, 0.0, 0.3, 0.2)], 0.02)
    model = Model(blocks, {"brick": BRICK}, width=0.2, comm=MPI.COMM_SELF)
    model.fix_blocks("block:0")
    bond = BondLaw((2e-4, 1e-3, 3e-3), (3e6, 3e6, 0.5e6))
    d, L = 0.012, 0.2
    anchors = Anchors(model, [Anchor([[0.1, 0.1], [0.35, 0.1]], diameter=d, bond=bond,
                                     steel=RIGID_STEEL)])
    assert np.count_nonzero(anchors.bonded_element) * 0.02 == pytest.approx(L)
    anchors.prescribe("pull", 0, "end")
    dr = DynamicRelaxation(model, anchors=anchors, rtol=1e-9)
    peak = math.pi * d * L * bond.strength
    worst = 0.0
    for s in [5e-5, 1e-4, 2e-4, 4e-4, 1e-3, 1.5e-3, 2e-3, 2.5e-3, 3e-3, 4e-3]:
        res = dr.solve(0.0, displacement={"pull": (s, 0.0)})
        assert res.converged
        force = dr.reactions()["pull"][0]
        expected = math.pi * d * L * float(bond.envelope(s))
        worst = max(worst, abs(force - expected) / peak)
    print(f"pull-out: largest deviation from pi d L tau(s) = {worst:.2e} of the peak")
    assert worst < 0.01


def test_long_elastic_anchor_matches_the_shear_lag_solution():
    """A 2.5 m elastic bar (d = 12 mm, E = 200 GPa) bonded with a linear law τ = k s
    (k = 2 GPa/m) along the axis of an elastic prism (0.2 × 0.2 m, E = 10 GPa) held at
    the face where the bar is pulled. Two-bar shear lag (bar in tension, prism in
    compression, both free at the far end x = 0):

        s'' = λ² s,  λ² = p k (1/EA + 1/(E_h A_h)),  s(x) = P λ cosh(λx) / (p k sinh(λL))

    with P the pull-out force and p = π d. Slip and bond stress along the bar within 3 %
    of the loaded-end value."""
    Lb, H, W, d, k = 2.5, 0.2, 0.2, 0.012, 2e9
    Eh = 10e9
    blocks = grid_blocks([(0.0, 0.0, Lb, H)], 0.05)
    model = Model(blocks, {"brick": Material(density=2400.0, E=Eh, nu=0.2)}, width=W,
                  comm=MPI.COMM_SELF)
    model.fix(lambda X: np.isclose(X[0], Lb), components=(0,), name="face")
    model.fix(lambda X: np.isclose(X[0], Lb) & np.isclose(X[1], 0.0), components=(1,),
              name="pin")
    steel = SteelLaw(E=200e9, yield_stress=5e9, rupture_strain=1.0)
    anchor = Anchor([[0.0, H / 2], [Lb + 0.05, H / 2]], diameter=d, bond=BondLaw.linear(k),
                    steel=steel, segment=0.05)
    anchors = Anchors(model, [anchor])
    anchors.prescribe("pull", 0, "end")
    dr = DynamicRelaxation(model, anchors=anchors, rtol=1e-6)
    assert dr.solve(0.0, displacement={"pull": (1e-3, 0.0)}).converged
    P = dr.reactions()["pull"][0]
    p = math.pi * d
    lam = math.sqrt(p * k * (1 / (steel.E * anchor.area) + 1 / (Eh * H * W)))
    res = anchors.node_results()
    inside = res["bonded"]
    x = anchors.x[inside, 0]
    s_exact = P * lam * np.cosh(lam * x) / (p * k * math.sinh(lam * Lb))
    err_s = np.max(np.abs(res["slip"][inside] - s_exact)) / s_exact.max()
    err_t = np.max(np.abs(res["bond_stress"][inside] - k * s_exact)) / (k * s_exact.max())
    print(f"shear lag: lambda = {lam:.4f} 1/m, P = {P:.1f} N, slip error {err_s:.2e}, "
          f"bond stress error {err_t:.2e} of the loaded-end value")
    assert err_s < 0.03 and err_t < 0.03
    # and the slip really decays: the far end slips < 5 % of the loaded end
    assert s_exact.min() < 0.05 * s_exact.max()


def two_blocks_across_a_dry_joint(anchor_kw, comm=MPI.COMM_SELF):
    """Blocks A = [0, 0.3] × [0, 0.2] (fixed) and B = [0.3, 0.6] × [0, 0.2] (moved as a
    whole by the prescription "B") with a dry frictional joint (a broken mortar joint)
    between them and an anchor from x = 0.11 to 0.49 at mid-height across it."""
    from masonry_fdem.contact import BlockContact, ContactSettings

    blocks = grid_blocks([(0, 0, 0.3, 0.2), (0.3, 0, 0.6, 0.2)], 0.02)
    model = Model(blocks, {"brick": BRICK}, width=0.2, comm=comm)
    model.fix_blocks("block:0", name="A")
    model.fix_blocks("block:1", name="B")
    contact = BlockContact(model, ContactSettings(friction=0.6))
    anchors = Anchors(model, [Anchor([[0.11, 0.1], [0.49, 0.1]], diameter=0.012,
                                     segment=0.02, **anchor_kw)])
    dr = DynamicRelaxation(model, contact=contact, anchors=anchors, rtol=1e-8)
    return model, anchors, dr


@pytest.mark.parametrize("hardening", [0.0, 2e9])
def test_bar_past_yield_plateaus_hardens_and_ruptures(hardening):
    """The joint opens by δ; the bond (linear, 100 GPa/m) is much stronger than the bar
    (f_y = 500 MPa, rupture at 5 % strain), so the bar yields where it crosses the joint.
    The force F carried across the joint must equal A σ(ε) of the steel law at the strain
    of the yielding element (1e-6): f_y A on the plateau, f_y A + A E H/(E+H) (ε − ε_y)
    with hardening; and F = 0 once the bar has ruptured."""
    steel = SteelLaw(E=200e9, yield_stress=500e6, hardening=hardening, rupture_strain=0.05)
    model, anchors, dr = two_blocks_across_a_dry_joint(
        {"bond": BondLaw.linear(1e11), "steel": steel})
    area = anchors.anchors[0].area
    fy_a = steel.yield_stress * area
    forces = []
    for delta in [2e-5, 5e-5, 1e-4, 2e-4, 4e-4, 6e-4, 8e-4, 1e-3]:
        assert dr.solve(0.0, displacement={"B": (delta, 0.0)}).converged
        force = dr.reactions()["B"][0]
        e = int(np.argmax(anchors.strain))
        expected = area * float(steel.stress(anchors.strain[e]))
        assert force == pytest.approx(expected, rel=1e-6)
        forces.append(force)
    print(f"H = {hardening:g}: forces {np.round(forces, 1).tolist()} N, f_y A = {fy_a:.1f} N")
    assert np.any(anchors.plastic_strain() > 0)
    if hardening == 0.0:
        assert forces[-1] == pytest.approx(fy_a, rel=1e-6)  # the plateau
    else:
        assert forces[-1] > forces[-2] > fy_a  # hardening
    # open the joint until the yielding element passes the rupture strain
    for delta in [2e-3, 4e-3]:
        assert dr.solve(0.0, displacement={"B": (delta, 0.0)}).converged
    assert anchors.ruptured().any()
    assert abs(dr.reactions()["B"][0]) < 1e-6 * fy_a
    assert np.all(np.abs(anchors.axial_force()) < 1e-6 * fy_a)


def bond_pull_reference(delta, EA, p, bond, Lb):
    """Force in a bar pulled out by δ/2 from each side of an opening joint: one side,
    x from the joint into the fixed block, s' = −N/EA, N' = −p τ(s), s(0) = δ/2,
    N(L_b) = 0 (scipy's collocation BVP solver on the same bar and bond laws)."""
    from scipy.integrate import solve_bvp

    x = np.linspace(0.0, Lb, 401)

    def rhs(_, y):
        return np.vstack([-y[1] / EA, -p * bond.envelope(y[0])])

    def bc(ya, yb):
        return np.array([ya[0] - 0.5 * delta, yb[1]])

    sol = solve_bvp(rhs, bc, x, np.vstack([np.full_like(x, 0.5 * delta), 0 * x]),
                    tol=1e-8, max_nodes=100_000)
    assert sol.success, sol.message
    return float(sol.sol(0.0)[1])


def test_open_joint_load_opening_curve_follows_the_bond_law():
    """The same broken joint with a weaker bond (3 MPa at 0.2 mm, rising to 3.5 MPa at
    2 mm) and an elastic bar: the joint carries no tension, the anchor carries it all, and
    the load–opening curve F(δ) equals that of the bar–bond equations solved
    independently (within 1 % of the peak). One bar element is centred on the joint, its
    halves bonded to A and to B."""
    steel = SteelLaw(E=200e9, yield_stress=5e9, rupture_strain=1.0)
    bond = BondLaw((2e-4, 2e-3), (3e6, 3.5e6))
    model, anchors, dr = two_blocks_across_a_dry_joint({"bond": bond, "steel": steel})
    mid = 0.5 * (anchors.x[anchors.conn[:, 0], 0] + anchors.x[anchors.conn[:, 1], 0])
    bridge = np.flatnonzero(np.isclose(mid, 0.3))
    assert bridge.size == 1
    assert set(anchors.host_block[anchors.helem == bridge[0]]) == {0, 1}
    a = anchors.anchors[0]
    peak = math.pi * a.diameter * 0.19 * bond.strength
    worst = 0.0
    for delta in [1e-4, 3e-4, 1e-3, 2e-3, 3e-3]:
        assert dr.solve(0.0, displacement={"B": (delta, 0.0)}).converged
        force = dr.reactions()["B"][0]
        ref = bond_pull_reference(delta, steel.E * a.area, math.pi * a.diameter, bond, 0.19)
        worst = max(worst, abs(force - ref) / peak)
        # nothing but the anchor holds B: the joint is open
        assert force == pytest.approx(anchors.axial_force().max(), rel=1e-3)
    print(f"load-opening curve within {worst:.2e} of the peak")
    assert worst < 0.01


def test_prestressed_anchor_puts_the_blocks_in_compression():
    """An anchor with end plates through two blocks (A fixed, B free, dry joint between)
    jacked to P = 20 kN: the joint carries P in compression (1 %); after lock-off the bar
    holds P and the joint still carries it."""
    from masonry_fdem.contact import BlockContact, ContactSettings

    comm = MPI.COMM_WORLD
    blocks = grid_blocks([(0, 0, 0.3, 0.2), (0.3, 0, 0.6, 0.2)], 0.02)
    model = Model(blocks, {"brick": BRICK}, width=0.2, comm=comm)
    model.fix_blocks("block:0", name="A")
    contact = BlockContact(model, ContactSettings(friction=0.6))
    P = 20e3
    anchors = Anchors(model, [Anchor([[0.02, 0.1], [0.58, 0.1]], diameter=0.012,
                                     prestress=P, plates="both", segment=0.02)])
    dr = DynamicRelaxation(model, contact=contact, anchors=anchors, rtol=1e-8)
    b_dofs = 2 * model._block_nodes("block:1")

    def joint_compression():
        f = np.zeros_like(model.f_int)
        contact.add_forces(f, np.zeros_like(f), 1.0, damping=False)
        return comm.allreduce(float(f[b_dofs].sum()))  # contact force of A on B along x

    assert dr.solve(0.0).converged
    jacked = joint_compression()
    assert jacked == pytest.approx(P, rel=0.01)
    assert np.allclose(anchors.axial_force(), P)
    anchors.lock_off()
    assert dr.solve(0.0).converged
    locked = joint_compression()
    print(f"prestress {P:.0f} N: joint compression {jacked:.3f} N jacking, "
          f"{locked:.3f} N after lock-off; bar {anchors.axial_force().min():.3f} N")
    assert locked == pytest.approx(P, rel=0.01)
    assert np.allclose(anchors.axial_force(), P, rtol=0.01)
