"""The same answers on any number of ranks; no block is ever split.

Under ``mpirun -n 2`` each test runs the model on COMM_WORLD and again on COMM_SELF (the
serial reference, on every rank) and compares; run serially the two coincide trivially.
"""

from mpi4py import MPI

import numpy as np
from conftest import rectangle

from masonry_fdem import Material, Model
from masonry_fdem.geometry import mesh_blocks
from masonry_fdem.solvers import DynamicRelaxation, ExplicitSolver

MATS = {"brick": Material(1800.0, 5e9, 0.2), "stone": Material(2500.0, 20e9, 0.25)}


def _stack(comm):
    polys = [rectangle(0, 0.3 * k, 1.2 - 0.1 * k, 0.3 * k + 0.25) for k in range(6)]
    mats = ["brick", "stone"] * 3
    return mesh_blocks(polys, materials=mats, mesh_size=0.08, comm=comm)


def _build(comm):
    model = Model(_stack(comm), MATS, width=0.3, comm=comm)
    model.fix(lambda X: X[0] < 1e-9)  # every block built in at x = 0
    model.add_gravity()
    model.add_point_load((0.9, 0.55), (0.0, -2e4))
    return model


def test_blocks_are_whole_on_a_rank():
    comm = MPI.COMM_WORLD
    model = _build(comm)
    ranks = model.block_ranks()
    assert set(ranks.tolist()) == set(range(comm.size))  # every rank has blocks
    # every local cell belongs to a block owned here, and all of the block's cells are here
    assert np.all(ranks[model.dmesh.cell_block] == comm.rank)
    n_local = np.bincount(model.dmesh.cell_block, minlength=model.blocks.n_blocks)
    owned = ranks == comm.rank
    assert np.array_equal(n_local[owned], np.diff(model.blocks.cell_offsets)[owned])
    assert np.all(n_local[~owned] == 0)


def test_explicit_same_on_any_rank_count():
    world = _build(MPI.COMM_WORLD)
    serial = _build(MPI.COMM_SELF)
    for m in (world, serial):
        s = ExplicitSolver(m, dt=0.5 * serial.stable_time_step(), damping=5.0)
        s.run(steps=400)
    uw, us = world.displacement(), serial.displacement()
    print(f"explicit, {MPI.COMM_WORLD.size} ranks vs 1: "
          f"{np.abs(uw - us).max() / np.abs(us).max():.1e} relative")
    assert np.abs(us).max() > 1e-7
    assert np.abs(uw - us).max() <= 1e-10 * np.abs(us).max()


def test_dynamic_relaxation_same_on_any_rank_count():
    world = _build(MPI.COMM_WORLD)
    serial = _build(MPI.COMM_SELF)
    res = [DynamicRelaxation(m, rtol=1e-7).solve(1.0) for m in (world, serial)]
    assert res[0].converged and res[1].converged
    uw, us = world.displacement(), serial.displacement()
    print(f"DR, {MPI.COMM_WORLD.size} ranks vs 1: {res[0].iterations} vs {res[1].iterations} "
          f"iterations, {np.abs(uw - us).max() / np.abs(us).max():.1e} relative")
    assert np.abs(uw - us).max() <= 1e-10 * np.abs(us).max()
