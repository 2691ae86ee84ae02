"""The interaction protocol: a user's interaction written against it alone is honoured by
both solvers, and the explicit energy account covers blocks, disks and anchors."""

from __future__ import annotations

import inspect

from mpi4py import MPI

import numpy as np
import pytest

from masonry_fdem import Material, Model
from masonry_fdem.geometry import mesh_blocks, rectangle
from masonry_fdem.interactions import (
    Anchor,
    Anchors,
    DiskBlockContact,
    DiskMaterial,
    Disks,
)
from masonry_fdem.interactions.protocol import BLOCKS, Interaction
from masonry_fdem.solvers import DynamicRelaxation, ExplicitSolver, UnstableTimeStepError

STONE = Material(density=2000.0, E=1e8, nu=0.2)


class GroundSpring(Interaction):
    """A linear spring of stiffness k [N/m] from the block node nearest to ``point`` to
    where that node started."""

    name = "spring"

    def __init__(self, model, point, k):
        self.i, self.k, self.comm = model.nearest_node(point), float(k), model.comm
        self.m = model.mass[2 * self.i] if self.i >= 0 else np.inf
        self.d = np.zeros(2)

    def add_forces(self, state):
        if self.i >= 0:
            self.d[:] = state.u[BLOCKS][2 * self.i:2 * self.i + 2]
            state.f[BLOCKS][2 * self.i:2 * self.i + 2] -= self.k * self.d

    def stable_omega2(self):
        return {BLOCKS: self.comm.allreduce(self.k / self.m, op=MPI.MAX)}

    def add_rowsum(self, rows):
        if self.i >= 0:
            rows[BLOCKS][2 * self.i:2 * self.i + 2] += self.k

    def energies(self):
        return {"stored": self.comm.allreduce(0.5 * self.k * float(self.d @ self.d)),
                "dissipated": 0.0}


def test_the_user_interaction_is_short():
    lines = [ln for ln in inspect.getsource(GroundSpring).splitlines()
             if ln.strip() and not ln.strip().startswith(("#", '"""', "where"))]
    print(f"\nGroundSpring: {len(lines)} lines")
    assert len(lines) < 25


def cantilever(comm):
    """A 1 m x 0.1 m elastic cantilever (plane stress, 0.1 m wide), built in at x = 0."""
    blocks = mesh_blocks([rectangle(0.0, 0.0, 1.0, 0.1)], materials="stone", mesh_size=0.05,
                         comm=comm)
    model = Model(blocks, {"stone": STONE}, hypothesis="plane_stress", width=0.1, comm=comm)
    model.fix(lambda X: X[0] < 1e-9, name="wall")
    model.monitor("tip", (1.0, 0.05))
    return model


def tip_deflection(model, spring=None, load=10.0):
    model.add_point_load((1.0, 0.05), (0.0, -load))
    dr = DynamicRelaxation(model, rtol=1e-10, interactions=spring)
    res = dr.solve(1.0)
    assert res.converged
    return -float(model.monitor_values()["tip"][1]), dr.reactions()["wall"][1]


def test_dynamic_relaxation_honours_a_user_spring():
    """With a ground spring k at the tip (on the neutral axis, where the load acts), the
    tip deflection of a linear cantilever is
    P/(P/δ0 + k), and the wall plus the spring carry the load."""
    comm = MPI.COMM_WORLD
    d0, _ = tip_deflection(cantilever(comm))
    k = 10.0 / d0  # as stiff as the beam: halves the deflection
    model = cantilever(comm)
    spring = GroundSpring(model, (1.0, 0.05), k)
    d1, wall = tip_deflection(model, spring)
    f_spring = k * d1
    expected = 10.0 / (10.0 / d0 + k)
    print(f"\ntip: {d0 * 1e3:.5f} mm alone, {d1 * 1e3:.5f} mm with the spring (expected "
          f"{expected * 1e3:.5f} mm); wall {wall:.5f} N + spring {f_spring:.5f} N = 10 N")
    assert abs(d1 / expected - 1.0) < 1e-3
    assert abs(wall + f_spring - 10.0) < 1e-6 * 10.0


def free_block(comm):
    """A free 0.2 m square block (plane stress, 0.1 m wide) moving right at 0.1 m/s."""
    blocks = mesh_blocks([rectangle(0.0, 0.0, 0.2, 0.2)], materials="stone", mesh_size=0.05,
                         comm=comm)
    model = Model(blocks, {"stone": STONE}, hypothesis="plane_stress", width=0.1, comm=comm)
    model.v[0::2] = 0.1
    i = model.nearest_node((0.2, 0.1))
    m_node = comm.allreduce(model.mass[2 * i] if i >= 0 else np.inf, op=MPI.MIN)
    return model, m_node, ExplicitSolver(model).dt_critical


def test_explicit_step_honours_a_user_spring_bound():
    """A ground spring 50 times stiffer than the block at its node sets the stable step:
    2/sqrt(ω²_blocks + k/m); the step of the block alone is refused, and the run at the
    default safety factor stays bounded."""
    comm = MPI.COMM_WORLD
    model, m_node, alone = free_block(comm)
    k = 50.0 * m_node * (2.0 / alone) ** 2
    spring = GroundSpring(model, (0.2, 0.1), k)
    with pytest.raises(UnstableTimeStepError):
        ExplicitSolver(model, dt=alone, interactions=spring)
    s = ExplicitSolver(model, interactions=spring)
    expected = model.stable_time_step(extra_omega2=k / m_node)
    s.run(steps=4000, every=100)
    e = s.energies()
    ke0 = 0.5 * model.total_mass() * 0.1**2
    print(f"\nstable step {alone:.3e} s alone, {s.dt_critical:.3e} s with the spring "
          f"(expected {expected:.3e} s); after 4000 steps kinetic + strain "
          f"{e.kinetic + e.internal:.4e} J of K0 {ke0:.4e} J, balance {e.balance:.1e} J")
    assert s.dt_critical == pytest.approx(expected, rel=1e-12)
    assert s.dt_critical < 0.2 * alone
    assert e.kinetic + e.internal < 1.2 * ke0
    assert abs(e.balance) < 1e-9 * ke0


def test_explicit_energy_account_holds_a_user_spring():
    """A softer ground spring (its frequency well resolved by the step) stops the block:
    the work of its force is minus the energy it reports stored, and kinetic + strain +
    stored stays the initial kinetic energy."""
    comm = MPI.COMM_WORLD
    model, m_node, alone = free_block(comm)
    k = 2.0  # [N/m]: the block (8 kg) swings back in a period of about 12 s
    spring = GroundSpring(model, (0.2, 0.1), k)
    s = ExplicitSolver(model, interactions=spring, damping=0.0)
    s.run(t_end=3.0, every=5000)
    e = s.energies()
    sp = e.interactions["spring"]
    ke0 = 0.5 * model.total_mass() * 0.1**2
    print(f"\nspring work {sp['work']:.6e} J, stored {sp['stored']:.6e} J; kinetic "
          f"{e.kinetic:.6e} J, strain {e.internal:.2e} J, K0 {ke0:.6e} J; unaccounted "
          f"{e.unaccounted:.1e} J, residual of the account {e.residual:.1e} J")
    assert sp["stored"] > 0.2 * ke0
    assert sp["work"] == pytest.approx(-sp["stored"], rel=1e-4)
    assert e.kinetic + e.internal + sp["stored"] == pytest.approx(ke0, rel=1e-4)
    assert abs(e.unaccounted) < 1e-4 * ke0
    # a linear spring and elastic elements: the account closes to round-off (its stores
    # carried to the half step, where central difference conserves energy)
    assert e.initial == pytest.approx(ke0, rel=1e-12)
    assert abs(e.residual) < 1e-12 * ke0


def test_energy_account_includes_blocks_disks_and_anchors():
    """Disks falling on an anchored block: kinetic energy and the work of gravity in the
    account are those of all three dof sets, and the balance closes."""
    comm = MPI.COMM_WORLD
    blocks = mesh_blocks([rectangle(0.0, 0.0, 0.4, 0.1)], materials="stone", mesh_size=0.025,
                         comm=comm)
    model = Model(blocks, {"stone": STONE}, hypothesis="plane_stress", width=0.05, comm=comm)
    model.fix(lambda X: X[1] < 1e-9, name="base")
    model.add_gravity()
    rng = np.random.default_rng(1)
    x = np.c_[np.linspace(0.05, 0.35, 6), 0.13 + 0.01 * rng.random(6)]
    disks = Disks(x, np.full(6, 0.012), {"g": DiskMaterial(density=2600.0, E=1e8, nu=0.25)},
                  "g", width=0.05, comm=comm)
    disks.add_gravity()
    disks.v[:, 0] = 0.2
    anchors = Anchors(model, [Anchor([[0.05, 0.05], [0.35, 0.05]], diameter=0.01)])
    anchors.v[0::2] = 0.05  # the bar starts moving in its duct
    y0 = disks.x[:, 1].copy()
    s = ExplicitSolver(model, damping=0.0, interactions=[disks, DiskBlockContact(disks, model),
                                                         anchors])
    s.run(steps=3000, every=500)
    e = s.energies()
    # independent sums over the three sets, at the half step as the account's
    ke = (model.kinetic_energy() + disks.kinetic_energy()
          + 0.5 * float(np.dot(anchors.mass, anchors.v**2)))
    w_disks = float(np.sum(disks.m * 9.80665 * (y0 - disks.x[:, 1])))
    print(f"\nblocks + disks + anchors: kinetic {e.kinetic:.6e} J (sum of the sets "
          f"{ke:.6e} J), external {e.external:.5e} J (disks' weight alone {w_disks:.5e} J), "
          f"interactions {sorted(e.interactions)}, balance {e.balance:.2e} J")
    assert e.kinetic == pytest.approx(ke, rel=1e-10)
    assert disks.kinetic_energy() > 0.1 * e.kinetic
    assert e.external == pytest.approx(w_disks, rel=0.05)  # the fixed block's load does no work
    assert sorted(e.interactions) == ["anchors", "disk_block", "disks"]
    assert abs(e.balance) < 1e-9 * max(e.kinetic, e.external, 0.5 * disks.m.sum() * 0.04)


def run_and_replay(solver, steps=150):
    """Positions after ``steps`` explicit steps, from a saved state, twice: straight on,
    and again after every interaction's set_state and the dof sets put back."""
    saved = [(s.u.copy(), s.v.copy()) for s in solver.sets]
    states = [c.state() for c in solver.interactions]
    solver.run(steps=steps, every=steps)
    first = [s.u.copy() for s in solver.sets]
    for s, (u, v) in zip(solver.sets, saved, strict=True):
        s.u[:] = u
        s.v[:] = v
    for c, st in zip(solver.interactions, states, strict=True):
        c.set_state(st)
    solver.run(steps=steps, every=steps)
    return first, [s.u.copy() for s in solver.sets]


def test_state_and_set_state_replay_a_run():
    """Contact, disks, disk-block contact and anchors mid-run: taking every interaction's
    state and giving it back replays the next steps (to round-off: the candidate lists are
    found again at the restored positions)."""
    comm = MPI.COMM_WORLD
    blocks = mesh_blocks([rectangle(0.0, 0.0, 0.4, 0.1), rectangle(0.1, 0.1, 0.3, 0.2)],
                         materials="stone", mesh_size=0.05, comm=comm)
    model = Model(blocks, {"stone": STONE}, hypothesis="plane_stress", width=0.05, comm=comm)
    model.fix_blocks(0, name="base")
    model.add_gravity()
    model.v[0::2] = np.where(model.node_block == 1, 0.3, 0.0)  # the top block slides
    from masonry_fdem.interactions import BlockContact

    x = np.c_[[0.1, 0.1235, 0.26, 0.36], np.full(4, 0.2121)]  # 3 on the top, 2 touching
    disks = Disks(x, np.full(4, 0.012), {"g": DiskMaterial(density=2600.0, E=1e8, nu=0.25)},
                  "g", width=0.05, comm=comm)
    disks.add_gravity()
    disks.v[:, 1] = -0.2
    anchors = Anchors(model, [Anchor([[0.12, 0.15], [0.28, 0.15]], diameter=0.01)])
    s = ExplicitSolver(model, interactions=[BlockContact(model), disks,
                                            DiskBlockContact(disks, model), anchors])
    s.run(steps=300, every=300)
    first, again = run_and_replay(s)
    e = s.energies().interactions
    print({k: f"{v['work']:.2e} J" for k, v in e.items()}, f"dt {s.dt:.1e} s")
    assert min(abs(v["work"]) for v in e.values()) > 0  # every one of them acted
    worst = max(float(np.abs(a - b).max()) for a, b in zip(first, again, strict=True))
    moved = max(float(np.abs(a).max()) for a in first)
    print(f"\nreplay after set_state: largest difference {worst:.1e} m of {moved:.3e} m")
    assert worst <= 1e-12 * moved
