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
from masonry_fdem.interactions.anchors import (
    Anchor,
    Anchors,
    BondLaw,
    DowelLaw,
    JointDowel,
    SteelLaw,
    straight_anchor,
    wall_ties,
)
from masonry_fdem.interactions.anchors import _kernels as AK
from masonry_fdem.assessment.layouts import intrados_stitch, radial_anchors
from masonry_fdem.geometry import BlockMesh
from masonry_fdem.solvers import DynamicRelaxation, ExplicitSolver
from masonry_fdem.interactions.protocol import BLOCKS, State

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


@pytest.mark.parametrize("bond", [BondLaw.uniform(3e6, 2e-4),
                                  BondLaw((2e-4, 1e-3, 3e-3), (3e6, 3e6, 0.5e6))],
                         ids=["elastic-plastic", "softening"])
def test_pull_out_of_a_short_anchor_follows_the_bond_law(bond):
    """A short, (nearly) rigid anchor bonded over L = 0.2 m in a fixed block slips
    uniformly, so the pull-out force is F(s) = π d L τ(s) for the bond law τ: elastic
    (k0 = 15 GPa/m) then perfectly plastic; or rising, plateau, softening to a residual.
    Limit 1 % of the peak force."""
    blocks = grid_blocks([(0.0, 0.0, 0.3, 0.2)], 0.02)
    model = Model(blocks, {"brick": BRICK}, width=0.2, comm=MPI.COMM_SELF)
    model.fix_blocks("block:0")
    d, L = 0.012, 0.2
    anchors = Anchors(model, [Anchor([[0.1, 0.1], [0.35, 0.1]], diameter=d, bond=bond,
                                     steel=RIGID_STEEL)])
    assert np.count_nonzero(anchors.bonded_element) * 0.02 == pytest.approx(L)
    anchors.prescribe("pull", 0, "end")
    dr = DynamicRelaxation(model, interactions=anchors, rtol=1e-9)
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
    dr = DynamicRelaxation(model, interactions=anchors, rtol=1e-6)
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
    from masonry_fdem.interactions import BlockContact, ContactSettings

    blocks = grid_blocks([(0, 0, 0.3, 0.2), (0.3, 0, 0.6, 0.2)], 0.02)
    model = Model(blocks, {"brick": BRICK}, width=0.2, comm=comm)
    model.fix_blocks("block:0", name="A")
    model.fix_blocks("block:1", name="B")
    contact = BlockContact(model, ContactSettings(friction=0.6))
    anchors = Anchors(model, [Anchor([[0.11, 0.1], [0.49, 0.1]], diameter=0.012,
                                     segment=0.02, **anchor_kw)])
    dr = DynamicRelaxation(model, interactions=[contact, anchors], rtol=1e-8)
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


@pytest.mark.parametrize("comm", [MPI.COMM_SELF, MPI.COMM_WORLD], ids=["self", "world"])
def test_sliding_joint_is_held_by_the_dowel_of_the_bar_across_it(comm):
    """B slides along the dry joint (no normal force, so no friction) across a bar with a
    joint dowel K = 1e8 N/m, Q_y = 500 N: the force holding B is K δ, then Q_y on the
    plateau, and on unloading Q_y − K (δ_max − δ) (elastic-perfectly plastic, plastic slip
    kept); the dowel's own output agrees, and its slip is measured across the bar as laid
    (B translates) however far the bridging element's chord has turned. Without the dowel the bar (a truss) holds B
    by nothing but the kink of its crossing element: under 1 % of those forces. On one
    rank and on all (A and B on different ranks under mpirun)."""
    k, qy = 1e8, 500.0
    model, anchors, dr = two_blocks_across_a_dry_joint(
        {"shear": JointDowel(stiffness=k, strength=qy)}, comm=comm)
    assert anchors.n_cross == 1
    _, bare, dr0 = two_blocks_across_a_dry_joint({}, comm=comm)
    assert bare.n_cross == 0
    expected = {2e-6: k * 2e-6, 4e-6: k * 4e-6, 8e-6: qy, 1.2e-5: qy, 1e-5: qy - k * 2e-6,
                6e-6: qy - k * 6e-6}
    for delta, ref in expected.items():
        assert dr.solve(0.0, displacement={"B": (0.0, delta)}).converged
        force = dr.reactions()["B"][1]  # what holds B up against the dowel
        res = anchors.dowel_results()
        print(f"delta {delta * 1e6:.0f} um: holding force {force:.2f} N (expected {ref:.2f}), "
              f"dowel {res['force'][0]:.2f} N")
        assert force == pytest.approx(ref, rel=1e-3, abs=1e-3 * qy)
        assert abs(res["force"][0]) == pytest.approx(abs(ref), rel=1e-3, abs=1e-3 * qy)
        if delta == 1.2e-5:
            assert bool(res["plastic"][0])
        assert dr0.solve(0.0, displacement={"B": (0.0, delta)}).converged
        assert abs(dr0.reactions()["B"][1]) < 0.01 * qy
    # slid 0.1 mm, five times the bridging element's length / 200: the dowel acts across
    # the bar as laid (B only translates), not across the element's turned chord
    assert dr.solve(0.0, displacement={"B": (0.0, 1e-4)}).converged
    np.testing.assert_allclose(anchors.cout[0, [AK.CO_NX, AK.CO_NY]], [0.0, 1.0], atol=1e-12)
    assert anchors.dowel_results()["slip"][0] == pytest.approx(1e-4, rel=1e-9)


def test_joint_dowel_from_the_bar_and_its_bedding():
    """JointDowel.from_bar against the formulas it cites, evaluated here step by step for
    an M16 stainless bar (d = 14.1 mm, E = 200 GPa, f_y = 450 MPa) in 12 MPa masonry:
    Soroushian's subgrade coefficient 127·0.8·√12/14.1^(2/3) = 60.3 N/mm³, Hetényi's
    K = k/(4λ), and V_u = 1.3 d² √(f_c f_y) = 19.0 kN (below f_y A/√3 = 40.5 kN)."""
    d, E, fy, fc = 0.0141, 200e9, 450e6, 12e6
    j = JointDowel.from_bar(d, E, fy, fc)
    kc = 127 * 0.8 * math.sqrt(12.0) / 14.1 ** (2 / 3)  # N/mm³
    assert kc == pytest.approx(60.3, abs=0.1)
    k = kc * 1e9 * d
    lam = (k / (4 * E * math.pi * d**4 / 64)) ** 0.25
    assert j.stiffness == pytest.approx(k / (4 * lam), rel=1e-12)
    assert j.strength == pytest.approx(19.0e3, rel=2e-3)
    assert JointDowel.from_bar(d, E, 100e6, 500e6).strength == pytest.approx(
        100e6 * math.pi * d**2 / 4 / math.sqrt(3), rel=1e-12)  # the bar's shear yield
    with pytest.raises(ValueError):
        JointDowel.from_bar(d, E, fy, -1.0)
    with pytest.raises(TypeError):
        Anchor([[0, 0], [1, 0]], diameter=0.01, shear=DowelLaw(stiffness=1e9))


def test_prestressed_anchor_puts_the_blocks_in_compression():
    """An anchor with end plates through two blocks (A fixed, B free, dry joint between)
    jacked to P = 20 kN: the joint carries P in compression (1 %); after lock-off the bar
    holds P and the joint still carries it."""
    from masonry_fdem.interactions import BlockContact, ContactSettings

    comm = MPI.COMM_WORLD
    blocks = grid_blocks([(0, 0, 0.3, 0.2), (0.3, 0, 0.6, 0.2)], 0.02)
    model = Model(blocks, {"brick": BRICK}, width=0.2, comm=comm)
    model.fix_blocks("block:0", name="A")
    contact = BlockContact(model, ContactSettings(friction=0.6))
    P = 20e3
    anchors = Anchors(model, [Anchor([[0.02, 0.1], [0.58, 0.1]], diameter=0.012,
                                     prestress=P, plates="both", segment=0.02)])
    dr = DynamicRelaxation(model, interactions=[contact, anchors], rtol=1e-8)
    b_dofs = 2 * model._block_nodes("block:1")

    def joint_compression():
        f = np.zeros_like(model.f_int)
        contact.add_forces(State({BLOCKS: model.u.x.array}, {BLOCKS: np.zeros_like(f)},
                                 {BLOCKS: f}, 1.0, False))
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


def _tied_pier(comm):
    """A pier of four blocks (0.3 × 0.15 m) on a fixed base with dry frictional joints,
    a vertical tie (bonded, 16 mm, with a dowel law) through the courses and a lateral
    load at the top; gravity. Solved by DR in two increments, then shaken by an
    explicit run (the lateral load removed)."""
    from masonry_fdem.interactions import BlockContact, ContactSettings

    boxes = [(0.0, -0.1, 0.3, 0.0)] + [(0.0, 0.15 * k, 0.3, 0.15 * (k + 1)) for k in range(4)]
    blocks = grid_blocks(boxes, 0.05)
    model = Model(blocks, {"brick": BRICK}, width=0.3, comm=comm)
    model.fix_blocks("block:0", name="base")
    model.add_gravity()
    model.add_point_load((0.0, 0.6), (800.0, 0.0), live=True)
    contact = BlockContact(model, ContactSettings(friction=0.7))
    steel = SteelLaw(E=200e9, yield_stress=500e6, hardening=1e9, rupture_strain=0.1)
    bond = BondLaw((1e-4, 1e-3, 3e-3), (2e6, 2e6, 0.2e6))
    tie = wall_ties([0.21], extent=(-0.08, 0.58), diameter=0.016, steel=steel, bond=bond,
                    dowel=DowelLaw(stiffness=2e9, strength=2e5), segment=0.05)
    anchors = Anchors(model, tie)
    dr = DynamicRelaxation(model, interactions=[contact, anchors], rtol=1e-7)
    out = []
    for lf in (0.5, 1.0):
        assert dr.solve(lf).converged
        out.append((model.displacement().copy(), anchors.axial_force().copy(),
                    anchors.node_results()["slip"].copy(), dr.reactions()["base"].copy()))
    ex = ExplicitSolver(model, interactions=[contact, anchors], damping=20.0)
    ex.run(steps=300)
    out.append((model.displacement().copy(), anchors.axial_force().copy(),
                anchors.node_results()["slip"].copy(), ex.reactions()["base"].copy()))
    hosts = set(model.block_ranks()[anchors.host_block].tolist())
    return out, hosts


def test_anchors_same_on_any_number_of_ranks():
    """The tied pier on all ranks (blocks, and so the tie's hosts, split between them
    under mpirun) equals the same model on one rank to 1e-10 (relative to the largest
    value of each quantity)."""
    world, hosts = _tied_pier(MPI.COMM_WORLD)
    alone, _ = _tied_pier(MPI.COMM_SELF)
    if MPI.COMM_WORLD.size > 1:
        assert len(hosts) > 1  # the tie crosses a rank boundary
    worst = 0.0
    for a, b in zip(world, alone, strict=True):
        for qa, qb in zip(a, b, strict=True):
            worst = max(worst, float(np.abs(qa - qb).max() / np.abs(qb).max()))
    forces = world[1][1]
    print(f"\ntied pier, {MPI.COMM_WORLD.size} rank(s) vs 1: largest relative difference "
          f"{worst:.2e}; tie force up to {forces.max():.1f} N")
    assert forces.max() > 100.0  # the tie works
    assert worst < 1e-10


def _pull_model(comm=MPI.COMM_SELF):
    blocks = grid_blocks([(0.0, 0.0, 0.3, 0.2)], 0.02)
    model = Model(blocks, {"brick": BRICK}, width=0.2, comm=comm)
    model.fix_blocks("block:0")
    bond = BondLaw((2e-4, 1e-3, 3e-3), (3e6, 3e6, 0.5e6))
    anchors = Anchors(model, [Anchor([[0.1, 0.1], [0.35, 0.1]], diameter=0.012, bond=bond)])
    return model, anchors


def test_explicit_pull_out_follows_the_quasi_static_curve():
    """The short anchor pulled slowly (5 mm/s, 1/1000 of the bar's wave speed, light mass
    damping) by the explicit solver carries the force dynamic relaxation finds at the
    same end displacements (2 % of the peak): the bar nodes, bond and steel state are
    advanced with the blocks."""
    model, anchors = _pull_model()
    anchors.prescribe("pull", 0, "end")
    dr = DynamicRelaxation(model, interactions=anchors, rtol=1e-8)
    marks = [1e-4, 3e-4, 6e-4]
    static = []
    for s in marks:
        assert dr.solve(0.0, displacement={"pull": (s, 0.0)}).converged
        static.append(dr.reactions()["pull"][0])
    model2, anchors2 = _pull_model()
    anchors2.prescribe("pull", 0, "end", velocity=(5e-3, 0.0))
    ex = ExplicitSolver(model2, interactions=anchors2, damping=200.0)
    dynamic = []
    for s in marks:
        ex.run(t_end=s / 5e-3)
        dynamic.append(ex.reactions()["pull"][0])
    peak = math.pi * 0.012 * 0.2 * 3e6
    print(f"explicit vs DR pull-out [N]: {np.round(dynamic, 1).tolist()} vs "
          f"{np.round(static, 1).tolist()} (dt = {ex.dt:.3g} s)")
    assert np.max(np.abs(np.array(dynamic) - static)) < 0.02 * peak


def test_anchor_output_history_and_picture(tmp_path):
    """The ParaView file holds every bar element with its force and every node with its
    slip; the history row and the picture are written."""
    import xml.etree.ElementTree as ET

    from masonry_fdem.io import AnchorOutput, History, plot_blocks

    model, anchors = _pull_model(MPI.COMM_WORLD)
    anchors.prescribe("pull", 0, "end")
    dr = DynamicRelaxation(model, interactions=anchors, rtol=1e-8)
    folder = tmp_path if MPI.COMM_WORLD.size == 1 else None
    folder = MPI.COMM_WORLD.bcast(folder if folder is not None else tmp_path, root=0)
    out = AnchorOutput(anchors, folder / "vtk")
    hist = History(folder / "history.csv", comm=MPI.COMM_WORLD)
    for k, s in enumerate([2e-4, 5e-4]):
        assert dr.solve(0.0, displacement={"pull": (s, 0.0)}).converged
        out.write(k)
        hist.append({"slip": s, **anchors.summary()})
    png = plot_blocks(model, folder / "anchors.png", anchors=anchors, scale=50.0)
    hist.close()
    if MPI.COMM_WORLD.rank == 0:
        assert png.stat().st_size > 10_000
        piece = ET.parse(folder / "vtk" / "anchors_00001.vtp").getroot().find(".//Piece")
        assert int(piece.get("NumberOfLines")) == anchors.n_elements
        assert int(piece.get("NumberOfPoints")) == anchors.n
        names = {d.get("Name") for d in piece.iter("DataArray")}
        assert {"axial_force", "slip", "bond_stress", "plastic_strain"} <= names
        assert (folder / "vtk" / "anchors.pvd").read_text().count("<DataSet") == 2
        assert hist.column("anchor_force_max")[-1] == pytest.approx(
            anchors.axial_force().max())
    assert anchors.summary()["anchor_slip_max"] > 4e-4


def test_layout_helpers_place_anchors_through_the_rings():
    """Radial anchors run along the radius from cover above the intrados to cover below
    the extrados; a stitch follows the intrados at its depth; wall ties are straight."""
    span, t, rings = 2.0, 0.1, 3
    anchors = radial_anchors([30.0, 90.0, 150.0], span=span, ring_thickness=t, rings=rings,
                             cover=0.02, diameter=0.016, origin=(1.0, 0.5))
    assert [a.name for a in anchors] == ["radial:0", "radial:1", "radial:2"]
    for a, ang in zip(anchors, [30.0, 90.0, 150.0], strict=True):
        r = np.linalg.norm(a.points - [1.0, 0.5], axis=1)
        assert r == pytest.approx([1.02, 1.28])
        d = a.points[1] - a.points[0]
        assert math.degrees(math.atan2(d[1], d[0])) == pytest.approx(ang)
    seg = radial_anchors([60.0], span=4.0, rise=1.0, kind="segmental", ring_thickness=0.2,
                         diameter=0.02)
    R = (4.0 + 1.0) / 2.0  # (span²/4 + rise²)/(2 rise)
    assert np.linalg.norm(seg[0].points[0] - [0.0, 1.0 - R]) == pytest.approx(R + 0.02)
    st = intrados_stitch(45.0, 135.0, span=span, depth=0.05, diameter=0.012)
    assert np.allclose(np.linalg.norm(st.points, axis=1), 1.05)
    assert st.length == pytest.approx(1.05 * math.pi / 2, rel=2e-3)
    ties = wall_ties([0.1, 0.5], extent=(0.0, 1.2), diameter=0.012)
    assert ties[1].points.tolist() == [[0.5, 0.0], [0.5, 1.2]]
    assert straight_anchor((0, 0), (1, 0), 0.01).length == 1.0
    with pytest.raises(ValueError, match="outside the arch"):
        radial_anchors([200.0], span=span, ring_thickness=t, diameter=0.016)
    with pytest.raises(ValueError, match="cover"):
        radial_anchors([90.0], span=span, ring_thickness=t, cover=0.06, diameter=0.016)


def test_radial_anchor_in_a_meshed_arch_is_cut_at_every_ring_interface():
    """A radial anchor through a three-ring arch gets one bar element centred on each
    ring interface it crosses, so each side bonds to its own ring."""
    from masonry_fdem.geometry import build_arch

    blocks = build_arch(span=2.0, ring_thickness=0.1, rings=3, voussoirs=12,
                        mesh_size=0.05, comm=MPI.COMM_SELF)
    model = Model(blocks, {"voussoir": BRICK}, width=1.0, comm=MPI.COMM_SELF)
    (a,) = radial_anchors([80.0], span=2.0, ring_thickness=0.1, rings=3, cover=0.02,
                          diameter=0.016)
    anchors = Anchors(model, [a])
    r = np.linalg.norm(anchors.x, axis=1)
    mid = 0.5 * (r[anchors.conn[:, 0]] + r[anchors.conn[:, 1]])
    bridging = [e for e in range(anchors.n_elements)
                if len(set(anchors.host_block[anchors.helem == e].tolist())) == 2]
    assert len(bridging) == 2
    # the ring faces are chords of 30° voussoirs: within the sagitta r (1 − cos 15°)
    assert mid[bridging] == pytest.approx([1.1, 1.2], abs=0.045)
    rings = {int(blocks.block_names[b].split(":")[1]) for b in anchors.host_block}
    assert rings == {0, 1, 2}
    assert anchors.total_length == pytest.approx(0.26)


@pytest.mark.parametrize("kw, message", [
    ({"points": [[0, 0]]}, "shape"),
    ({"diameter": -0.01}, "diameter"),
    ({"prestress": 1e4}, "plates='both'"),
    ({"prestress": 1e6, "plates": "both"}, "yield force"),
    ({"plates": "middle"}, "plates must be one of"),
    ({"points": [[0, 0], [0, 0], [1, 0]]}, "coincide"),
])
def test_bad_anchor_definitions_are_refused(kw, message):
    args = {"points": [[0.1, 0.1], [0.2, 0.1]], "diameter": 0.012} | kw
    with pytest.raises(ValueError, match=message):
        Anchor(**args)


def test_bad_laws_and_placements_are_refused():
    with pytest.raises(ValueError, match="increasing"):
        BondLaw((1e-3, 5e-4), (1e6, 2e6))
    with pytest.raises(ValueError, match="steeper"):
        BondLaw((1e-3, 1.1e-3), (1e6, 5e6))
    with pytest.raises(ValueError, match="rupture_strain"):
        SteelLaw(rupture_strain=1e-3)
    with pytest.raises(ValueError, match="dowel stiffness"):
        DowelLaw(stiffness=0.0)
    blocks = grid_blocks([(0.0, 0.0, 0.3, 0.2)], 0.05)
    model = Model(blocks, {"brick": BRICK}, comm=MPI.COMM_SELF)
    with pytest.raises(ValueError, match="wholly outside"):
        Anchors(model, [Anchor([[1.0, 1.0], [2.0, 1.0]], diameter=0.01)])
    with pytest.raises(ValueError, match="end plate is outside"):
        Anchors(model, [Anchor([[0.1, 0.1], [0.5, 0.1]], diameter=0.01, plates="both")])
    anchors = Anchors(model, [Anchor([[0.1, 0.1], [0.2, 0.1]], diameter=0.01)])
    anchors.prescribe("pull", 0, "end")
    with pytest.raises(ValueError, match="exists already"):
        anchors.prescribe("pull", 0, "start")
    with pytest.raises(ValueError, match="out of range"):
        anchors.prescribe("other", 3)


def test_bond_law_return_unloads_with_plastic_slip():
    """Kernel check: loading past the peak then unloading follows the initial stiffness
    from the envelope point reached; reverse loading meets the envelope at −τ_env of
    the accumulated slip."""
    law = BondLaw((1e-4, 1e-3, 2e-3), (2e6, 2e6, 0.5e6))
    ls, lt = np.array(law.slip), np.array(law.stress)
    res = np.zeros(3)
    AK.bond_return(ls, lt, 3, law.k0, 1.5e-3, 0.0, 0.0, res)
    tau, sp, kappa = res
    assert tau == pytest.approx(float(law.envelope(1.5e-3)))  # on the softening branch
    AK.bond_return(ls, lt, 3, law.k0, 1.4e-3, sp, kappa, res)
    assert res[0] == pytest.approx(tau - law.k0 * 1e-4)  # elastic unloading
    AK.bond_return(ls, lt, 3, law.k0, -5e-3, sp, kappa, res)
    assert res[0] == pytest.approx(-0.5e6)  # the residual, reversed
