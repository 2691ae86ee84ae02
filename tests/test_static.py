"""The static Newton solver: consistent tangents (blocks, return mapping, contact in
stick and slip), quadratic convergence, Prandtl's footing, honest statuses, and the same
solution on one and on two processes."""

from __future__ import annotations

import math
import sys
from pathlib import Path

from mpi4py import MPI

import numpy as np
import pytest

from masonry_fdem import Material, Model
from masonry_fdem.geometry import BlockLayout, arch_layout, rectangle
from masonry_fdem.interactions import BlockContact, ContactSettings
from masonry_fdem.solvers.limit_analysis import limit_analysis
from masonry_fdem.solvers.static import StaticSolver
from masonry_fdem.solvers.status import Status

sys.path.insert(0, str(Path(__file__).parent))
from test_footing import B2, C, footing_model  # noqa: E402

TOL = 1e-5  # tangent against central differences of the residual


def _rate(history: tuple[float, ...], ref: float, floor: float = 1e-10) -> float:
    """Order of convergence log(e₃/e₂)/log(e₂/e₁) from the last three residual norms
    (relative to ``ref``) above the round-off floor of the force evaluation."""
    e = np.asarray(history) / ref
    keep = np.flatnonzero(e > floor)
    e = e[: keep[-1] + 1][-3:]
    if e.size < 3:
        return math.nan
    return math.log(e[2] / e[1]) / math.log(e[1] / e[0])


def _cantilever(comm=MPI.COMM_SELF) -> Model:
    lay = BlockLayout((rectangle(0.0, 0.0, 2.0, 0.2),), ("brick",), ("beam",))
    model = Model(lay.mesh(0.1, comm), {"brick": Material(2000.0, 1e9, 0.2)}, comm=comm)
    model.fix(lambda X: np.isclose(X[0], 0.0), name="clamp")
    model.add_point_load((2.0, 0.2), (0.0, -1e4))
    return model


def test_a_solve_may_take_more_iterations_than_the_solvers_own():
    """``solve(..., max_it=)`` allows that many Newton iterations for one solve, then the
    solver's own again: the cantilever (3+ iterations to 1e-10) fails with one iteration
    allowed, converges with the one-off allowance, and fails again after it."""
    s = StaticSolver(_cantilever(), rtol=1e-10, max_it=1)
    assert s.solve(1.0).reason == "DIVERGED_MAX_IT"
    res = s.solve(1.0, max_it=20)
    assert res.converged and res.iterations > 1 and s.max_it == 1
    s.max_it = 1
    s.commit()
    assert not s.solve(2.0).converged
    with pytest.raises(ValueError, match="max_it"):
        s.solve(1.0, max_it=0)


def test_block_tangent_is_the_derivative_of_the_svk_internal_force():
    """St. Venant–Kirchhoff blocks: the UFL derivative matches central differences of
    the residual at a large, arbitrary displacement (geometric stiffness included)."""
    model = _cantilever()
    s = StaticSolver(model)
    rng = np.random.default_rng(1)
    model.u.x.array[:] = 0.05 * rng.standard_normal(model.u.x.array.size)
    err = s.check_tangent()
    print(f"\nSVK tangent: {err:.2e}")
    assert err < TOL


def test_elastic_block_converges_quadratically():
    """A 2 m × 0.2 m cantilever, tip load 10 kN (tip deflection ~4 cm: geometrically
    nonlinear): Newton's last iterations show an order of convergence near 2."""
    model = _cantilever()
    s = StaticSolver(model, rtol=1e-10)
    res = s.solve(1.0)
    print(f"\ncantilever: {res.iterations} iterations, |r| = "
          f"{[f'{h:.1e}' for h in res.history]}")
    assert res.converged
    assert res.iterations <= 6
    assert _rate(res.history, res.reference) > 1.7


def test_return_mapping_tangent_in_its_plastic_range():
    """Mohr–Coulomb (Tresca) soil under the footing, halfway through a plastic
    increment: the algorithmic tangent (central differences of the return mapping at
    the points) matches central differences of the residual."""
    m = footing_model(2, comm=MPI.COMM_SELF)
    s = StaticSolver(m)
    st, _ = s.advance(displacement={"footing": (None, -1.2e-4)}, steps=2)
    assert st.status is Status.LOAD_REACHED
    s0 = m.qstate.s0.copy()
    uc = s.sets[0].uc.copy()
    st, _ = s.advance(displacement={"footing": (None, -2.0e-4)}, steps=2)
    assert st.status is Status.LOAD_REACHED
    # back to the committed state of 0.12 mm, at the displacement of 0.2 mm
    m.qstate.s0[:] = s0
    s.sets[0].uc[:] = uc
    m.internal_force()
    grew = m.qstate.s1[:, 4] > s0[:, 4] + 1e-9
    assert grew.sum() >= 5  # points loading plastically in this increment
    err = s.check_tangent()
    print(f"\nreturn-mapping tangent ({grew.sum()} points yielding): {err:.2e}")
    assert err < TOL


def test_footing_by_newton_reaches_prandtl():
    """Prandtl's strip footing under prescribed settlement (the DR test's model and
    steps) by Newton: q within 5 % of (2 + π) c, levelled off."""
    m = footing_model()
    s = StaticSolver(m)
    qu = (2.0 + math.pi) * C
    q, its = [], []
    for d in [0.05e-3, 0.10e-3, 0.13e-3, 0.16e-3, 0.20e-3]:
        st, rr = s.advance(displacement={"footing": (None, -d)})
        assert st.status is Status.LOAD_REACHED, st
        q.append(-s.reactions()["footing"][1] / B2)
        its += [r.iterations for r in rr if r.converged]
    q = np.array(q)
    print(f"\nNewton footing ({m.blocks.n_cells} cells): q/c = "
          f"{np.array2string(q / C, precision=4)}, final/Prandtl - 1 = {q[-1] / qu - 1:+.2%}"
          f"; Newton iterations {its}")
    assert abs(q[-1] / qu - 1.0) < 0.05
    assert abs(q[-1] / q[-2] - 1.0) < 0.01
    assert q[0] < 0.85 * qu
    assert m.plastic_work() > 0


def _sliding_block(friction: float, comm=MPI.COMM_SELF):
    """A 0.5 × 0.25 m block on a fixed base, its top nodes pushed sideways."""
    lay = BlockLayout((rectangle(-0.5, -0.2, 1.0, 0.0), rectangle(0.0, 0.0, 0.5, 0.25)),
                      ("base", "brick"), ("base", "block"))
    model = Model(lay.mesh(0.125, comm), {"brick": Material(600.0, 1e9, 0.2),
                                          "base": Material(600.0, 1e9, 0.2)}, comm=comm)
    model.fix_blocks("base")
    model.fix(lambda X: np.isclose(X[1], 0.25) & (X[0] > -1e-9), components=(0,),
              name="push")
    model.add_gravity()
    contact = BlockContact(model, ContactSettings(friction=friction))
    return model, contact


@pytest.mark.parametrize("push, friction, sliding", [(1e-7, 10.0, False), (2e-5, 0.3, True)])
def test_contact_tangent_in_stick_and_in_slip(push, friction, sliding):
    """Facet–facet penalty contact with Coulomb friction: the tangent (central
    differences of the pair kernel) matches central differences of the residual, in
    stick (μ = 10, a push of 0.1 µm from the self-weight state) and in slip (μ = 0.3,
    from 10 to 20 µm, past the ~0.06 µm of elastic stick); the slip tangent is not
    symmetric."""
    model, contact = _sliding_block(friction)
    s = StaticSolver(model, interactions=contact)
    assert s.solve(0.0).converged
    if sliding:
        assert s.advance(displacement={"push": (0.5 * push, None)}, steps=2)[0].status \
            is Status.LOAD_REACHED
    committed = contact.state()
    uc = s.sets[0].uc.copy()
    st, _ = s.advance(displacement={"push": (push, None)}, steps=2)
    assert st.status is Status.LOAD_REACHED
    contact.set_state(committed)
    s.sets[0].uc[:] = uc
    s._forces()
    slipped = contact.energy[2] > 0  # frictional work since the commit
    assert slipped == sliding
    err = s.check_tangent()
    A = s.J.convert("dense").getDenseArray()
    asym = np.abs(A - A.T).max() / np.abs(A).max()
    print(f"\ncontact tangent ({'slip' if sliding else 'stick'}): {err:.2e}, "
          f"asymmetry {asym:.1e}")
    assert err < TOL
    if sliding:
        assert asym > 1e-3


def test_contact_tangent_holds_the_friction_branch_at_the_coulomb_limit():
    """A contact that slides, or sticks, closer to the Coulomb limit than the tangent's
    finite-difference step reaches (ε_t h, h = 1e-10 of a facet) gets the tangent of its
    own branch, not the mean of the stick and slip stiffnesses its central differences
    straddle (a hinge's contact that has just stopped sliding sits there, and Newton
    orbited on it: the full TRL arch, docs/design.md). The block slides at μ = 0.3; from
    its committed state the last increment's direction is taken on by f of it: 1e-6
    (a slip of ~1e-12 m, a tenth of h) and 1e-3 (well within the slip branch) give one
    tangent; -1e-6 and -1e-3 (turning back: stick) another."""
    model, contact = _sliding_block(0.3)
    s = StaticSolver(model, interactions=contact)
    assert s.solve(0.0).converged
    assert s.advance(displacement={"push": (1e-5, None)}, steps=2)[0].status \
        is Status.LOAD_REACHED
    u0 = s.sets[0].u.copy()
    assert s.advance(displacement={"push": (1.1e-5, None)})[0].status \
        is Status.LOAD_REACHED
    uc = s.sets[0].u.copy()
    du = uc - u0

    def tangent(f):
        s.sets[0].u[:] = uc + f * du
        s._forces()
        return s.assemble_tangent().convert("dense").getDenseArray().copy()

    slip_near, slip_far = tangent(1e-6), tangent(1e-3)
    stick_near, stick_far = tangent(-1e-6), tangent(-1e-3)
    s.sets[0].u[:] = uc
    s._forces()
    scale = np.abs(stick_far).max()
    apart = np.abs(stick_far - slip_far).max() / scale  # the two branches differ
    d_slip = np.abs(slip_near - slip_far).max() / scale
    d_stick = np.abs(stick_near - stick_far).max() / scale
    print(f"\nbranches apart {apart:.2e}; near the limit against within the branch: "
          f"slip {d_slip:.2e}, stick {d_stick:.2e}")
    assert apart > 1e-2
    assert d_slip < 1e-4 * apart
    assert d_stick < 1e-4 * apart


def test_a_rebuild_at_a_failed_iterate_keeps_the_committed_friction_history():
    """A Newton iterate far from the committed state (a failed increment) may trigger a
    contact search there that loses the pairs in contact; back at the committed state
    the pairs are found again with their committed tangential history (elastic stick),
    not with zero — else the friction state depends on how an increment failed, and one
    process and two end up 5e-4 apart (measured on the arch of test_path.py before)."""
    model, contact = _sliding_block(10.0)
    s = StaticSolver(model, interactions=contact)
    assert s.solve(0.0).converged
    st, _ = s.advance(displacement={"push": (1e-7, None)})
    assert st.status is Status.LOAD_REACHED
    keys, tau = contact.keys.copy(), contact.tau_c.copy()
    assert np.abs(tau).max() > 0  # stuck, with a tangential history
    r0 = s.reactions()["push"][0]
    # the iterate: the block lifted 1 m off its base, where it touches nothing
    y = model.blocks.x[model.node_input, 1]
    lowest = {b: y[model.node_block == b].min() for b in np.unique(model.node_block)}
    on_brick = np.array([lowest[b] > -1e-9 for b in model.node_block])
    lift = np.zeros_like(s.sets[0].u)
    lift[1::2][on_brick] = 1.0
    s.sets[0].u[:] += lift
    contact.rebuild()
    assert not np.isin(keys, contact.keys).any()  # the pairs are lost there
    s.restore()  # back at the committed state: found again, with their history
    assert np.isin(keys, contact.keys).all()
    pos = np.searchsorted(contact.keys, keys)
    assert np.array_equal(contact.tau_c[pos], tau)
    assert s.reactions()["push"][0] == pytest.approx(r0, rel=1e-12)


def _arch(comm, point=None, E=10e9):
    """20 dry voussoirs, R = 1 m, t/R = 0.15, μ = 0.8, a downward unit point load at
    ``point`` (default: the extrados at 135°), voussoirs of Young's modulus ``E`` [Pa]
    (the abutments 3 E). Returns (model, contact, LP load [N])."""
    t = 0.15
    lay = arch_layout(span=2.0, ring_thickness=t, voussoirs=20, abutment_height=0.3,
                      abutment_width=0.4)
    if point is None:
        r = 1.0 + t
        point = (r * math.cos(math.radians(135.0)), r * math.sin(math.radians(135.0)))
    mats = {"voussoir": Material(2000.0, E, 0.2), "abutment": Material(2000.0, 3.0 * E, 0.2)}
    model = Model(lay.mesh(0.1, comm), mats, width=1.0, comm=comm)
    model.fix_blocks("abutment:*")
    model.add_gravity()
    model.add_point_load(point, (0.0, -1.0), blocks="voussoir:*")
    contact = BlockContact(model, ContactSettings(friction=0.8, penalty_factor=20.0))
    la = limit_analysis(lay, density=2000.0, width=1.0, supports="abutment:*",
                        live_loads=[(point, (0.0, -1.0))], friction=0.8)
    return model, contact, float(la.load_factor)


def _half_collapse(comm):
    model, contact, p_la = _arch(comm)
    s = StaticSolver(model, interactions=contact)
    first = s.solve(0.0)
    st, rr = s.advance(0.5 * p_la, steps=5)
    return model, s, first, st, rr, p_la


def test_dry_arch_at_half_its_collapse_load_converges_quadratically():
    """The dry arch under self-weight and then half its limit-analysis load in five
    increments: every increment converges, and the last iterations of each converge
    at an order near 2."""
    model, s, first, st, rr, p_la = _half_collapse(MPI.COMM_WORLD)
    print(f"\narch: LP load {p_la:.1f} N; self-weight {first.iterations} iterations; "
          f"increments {[r.iterations for r in rr]}")
    assert first.converged and st.status is Status.LOAD_REACHED
    assert all(r.converged for r in rr) and len(rr) == 5
    assert max(r.iterations for r in rr) <= 15
    rates = [_rate(r.history, r.reference) for r in [first, *rr]]
    print(f"orders of convergence: {np.round(rates, 2)}")
    assert np.median(rates) > 1.6


def test_parallel_newton_solution_is_that_of_one_process():
    """The half-collapse arch on all ranks and on one: the displacements agree to 1e-8
    relative (run under mpirun -n 2)."""
    world = MPI.COMM_WORLD
    model, s, _, st, _, _ = _half_collapse(world)
    assert st.status is Status.LOAD_REACHED
    u_par = model.displacement()
    if world.size == 1:
        pytest.skip("one process: nothing to compare (run under mpirun -n 2)")
    solo, _, _, st1, _, _ = _half_collapse(MPI.COMM_SELF)
    assert st1.status is Status.LOAD_REACHED
    u_one = solo.displacement()
    diff = np.abs(u_par - u_one).max() / np.abs(u_one).max()
    print(f"\n-n {world.size} against -n 1: max |Δu| / max |u| = {diff:.1e}")
    assert diff < 1e-8


def test_newton_starved_of_iterations_is_not_converged_and_gives_no_collapse_load():
    """Load control with Newton allowed two iterations: the run ends *not converged*
    (never a collapse), its last converged load a lower bound."""
    model, contact, p_la = _arch(MPI.COMM_WORLD)
    s = StaticSolver(model, interactions=contact, max_it=2)
    run = s.load_to_collapse(0.2 * p_la, max_load=2 * p_la, min_increment=0.05 * p_la)
    print(f"\nstarved Newton: {run.status.describe('N')}")
    assert run.status.status is Status.NOT_CONVERGED
    assert run.status.collapse_load is None
    assert run.collapse_load_factor is None
    assert run.status.lower_bound == max(run.load_factors)
    assert "not converged" in run.status.describe()


def test_settle_resumed_from_a_partial_weight_reaches_the_same_state():
    """``settle(resume=True)`` goes on from the dead-load fraction committed last (as
    ``assess`` does after releasing a fill's interfaces where a settle stopped): a
    cantilever under its own weight, settled from half of it, ends where a settle from
    zero ends (elastic: one equilibrium), to 1e-5 of the tip deflection (each settle
    stops at rtol = 1e-6 of the forces: measured 9e-7 apart), with the half weight's
    deflection half the full one's."""
    def model():
        lay = BlockLayout((rectangle(0.0, 0.0, 2.0, 0.2),), ("brick",), ("beam",))
        m = Model(lay.mesh(0.1, MPI.COMM_SELF), {"brick": Material(2000.0, 1e9, 0.2)},
                  comm=MPI.COMM_SELF)
        m.fix(lambda X: np.isclose(X[0], 0.0), name="clamp")
        m.add_gravity()
        return m

    m0 = model()
    s0 = StaticSolver(m0)
    assert s0.settle().status is Status.LOAD_REACHED
    m1 = model()
    s1 = StaticSolver(m1)
    s1.dead_factor = 0.5
    assert s1.solve(0.0).converged
    tip = int(np.argmin(np.hypot(m1.X[:, 0] - 2.0, m1.X[:, 1] - 0.2)))
    half = float(m1.u.x.array[2 * tip + 1])
    st = s1.settle(resume=True)
    assert st.status is Status.LOAD_REACHED and s1.dead_factor == 1.0
    full = float(m0.u.x.array[2 * tip + 1])
    assert full < 0 and half == pytest.approx(0.5 * full, rel=1e-2)
    assert np.allclose(m1.u.x.array, m0.u.x.array, rtol=0, atol=1e-5 * abs(full))
