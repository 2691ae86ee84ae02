"""Loads, supports and masses of the model against hand values."""

from mpi4py import MPI

import numpy as np
import pytest
from conftest import rectangle

from masonry_fdem import Material, Model
from masonry_fdem.constants import G
from masonry_fdem.geometry import build_wall, mesh_blocks
from masonry_fdem.solvers import ExplicitSolver

comm = MPI.COMM_WORLD
BRICK = Material(1800.0, 5e9, 0.2)


def _total(model, f):
    return comm.allreduce(np.array([f[0::2].sum(), f[1::2].sum()]))


def test_gravity_line_load_pressure_totals():
    blocks = mesh_blocks([rectangle(0, 0, 2.0, 0.5), rectangle(3, 0, 4, 1)], materials="brick",
                         mesh_size=0.1, comm=comm)
    model = Model(blocks, {"brick": BRICK}, width=0.3, comm=comm)
    model.add_gravity()
    weight = 1800.0 * 0.3 * (1.0 + 1.0) * G
    assert _total(model, model.f_dead) == pytest.approx([0.0, -weight], rel=1e-12, abs=1e-9)
    # q [N/m] along the 2 m top edge of block 0
    model.add_line_load(lambda x: np.isclose(x[1], 0.5) & (x[0] < 2.5), (100.0, -2000.0))
    assert _total(model, model.f_live) == pytest.approx([200.0, -4000.0], rel=1e-12)
    # p [Pa] on the 1 m right face of block 1, over the 0.3 m width, pushing in -x
    model.f_live[:] = 0.0
    model.add_pressure(lambda x: np.isclose(x[0], 4.0), 1e4)
    assert _total(model, model.f_live) == pytest.approx([-3000.0, 0.0], rel=1e-12, abs=1e-9)
    # point load goes to one node
    model.f_live[:] = 0.0
    model.add_point_load((2.0, 0.5), (0.0, -7.0))
    assert comm.allreduce(int(np.count_nonzero(model.f_live))) == 1
    assert _total(model, model.f_live) == pytest.approx([0.0, -7.0])


def test_platen_moves_with_prescribed_velocity_and_reports_reaction():
    """A wall of free bricks with one brick driven as a platen: the platen moves exactly
    with its velocity, fixed bricks stay put, and the platen's reaction is m·a = 0 when
    it moves uniformly (no contact yet: nothing resists it)."""
    blocks = build_wall(courses=3, bricks_per_course=3, brick_length=0.2, brick_height=0.1,
                        mesh_size=0.05, comm=comm)
    model = Model(blocks, {"brick": BRICK}, comm=comm)
    top = [n for n in blocks.block_names if n.startswith("brick:2")][0]
    bottom = [n for n in blocks.block_names if n.startswith(("brick:0", "half:0"))]
    model.fix_blocks(bottom, name="base")
    v_platen = -0.01  # m/s
    model.prescribe_velocity(top, (0.0, v_platen), name="platen")
    model.add_gravity()
    solver = ExplicitSolver(model)
    solver.run(steps=200)
    u = model.displacement()
    b_top = blocks.block_names.index(top)
    nodes = slice(blocks.node_offsets[b_top], blocks.node_offsets[b_top + 1])
    assert u[nodes, 1] == pytest.approx(v_platen * solver.t, rel=1e-12)
    assert u[nodes, 0] == pytest.approx(0.0, abs=1e-15)
    ids = [blocks.block_names.index(n) for n in bottom]
    for b in ids:
        assert np.all(u[blocks.node_offsets[b] : blocks.node_offsets[b + 1]] == 0.0)
    reactions = solver.reactions()
    # the base carries the weight of its own bricks (they are held against gravity)
    base_weight = 1800.0 * blocks.block_area[ids].sum() * G
    assert reactions["base"][1] == pytest.approx(base_weight, rel=1e-9)
    # the platen holds its own brick against gravity
    assert reactions["platen"][1] == pytest.approx(1800.0 * blocks.block_area[b_top] * G,
                                                   rel=1e-9)


def test_energy_account_balances_with_damping_and_supports():
    blocks = mesh_blocks([rectangle(0, 0, 1.0, 0.2)], materials="brick", mesh_size=0.05,
                         comm=comm)
    model = Model(blocks, {"brick": BRICK}, comm=comm)
    model.fix(lambda X: X[0] < 1e-9)
    model.add_gravity()
    solver = ExplicitSolver(model, damping=20.0)
    solver.run(steps=3000)
    e = solver.energies()
    assert e.external > 0 and e.damping > 0 and e.internal > 0
    assert abs(e.balance) < 1e-9 * e.external
    # the work of the internal forces matches the stored strain energy (elastic body)
    assert e.internal == pytest.approx(model.strain_energy(), rel=0.01)
