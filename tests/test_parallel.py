"""The same answers on any number of ranks; no block is ever split.

Under ``mpirun -n 2`` each test runs the model on COMM_WORLD and again on COMM_SELF (the
serial reference, on every rank) and compares; run serially the two coincide trivially.
"""

from mpi4py import MPI

import numpy as np
import pytest
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


def _pushed_wall(comm):
    """A mortared running-bond wall (4 courses of 3 bricks) on a fixed base, its top
    thrown sideways at 3 m/s: joints soften and open, bricks slide and hit each other
    across the rank boundary."""
    from masonry_fdem.geometry import wall_layout
    from masonry_fdem.interactions import BlockContact, ContactSettings, JointMaterial, Joints

    wall = wall_layout(courses=4, bricks_per_course=3, brick_length=0.215,
                       brick_height=0.065)
    base = rectangle(-0.5, -0.2, 1.2, 0.0)
    blocks = mesh_blocks([base, *wall.polygons], materials=["stone", *wall.materials],
                         names=["base", *wall.names], comm=comm)
    model = Model(blocks, MATS, width=0.1025, comm=comm)
    model.fix_blocks("base")
    model.add_gravity()
    top = blocks.block_centroid[:, 1] > 0.13
    model.v[0::2] = np.where(top[model.node_block], 3.0, 0.0)
    contact = BlockContact(model, ContactSettings(friction=0.6, restitution=0.3))
    mortar = JointMaterial(ft=1e4, GfI=5.0, c=2e4, GfII=20.0)
    joints = Joints(model, {("brick", "brick"): mortar, ("brick", "stone"): mortar},
                    contact=contact)
    return model, ExplicitSolver(model, interactions=[contact, joints], damping=2.0), joints


def _by_node(model, values):
    """Nodal (n, k) values of every rank, in an order independent of the ranks."""
    rows = np.c_[model.node_block, model.X, values]
    rows = np.concatenate(model.comm.allgather(rows))
    return rows[np.lexsort((rows[:, 2], rows[:, 1], rows[:, 0]))]


def test_joints_and_contact_bitwise_same_on_any_rank_count():
    """Explicit dynamics with mortar joints and frictional contact: the displacements on
    all ranks equal those on one rank to the bit after 1 500 steps (each node's joint and
    contact forces summed over its terms in one global order), the joint states alike."""
    runs = []
    for comm in (MPI.COMM_WORLD, MPI.COMM_SELF):
        model, solver, joints = _pushed_wall(comm)
        solver.run(steps=1500)
        n = model.n_nodes
        u = model.u.x.array[: 2 * n].reshape(-1, 2)
        runs.append((_by_node(model, u), joints.counts(), solver.energies().kinetic,
                     model.comm.size > 1 and len(set(model.block_ranks().tolist())) > 1))
    (uw, cw, kw, split), (us, cs, ks, _) = runs
    if MPI.COMM_WORLD.size > 1:
        assert split  # the wall is shared between ranks
    print(f"\njoints and contact, {MPI.COMM_WORLD.size} rank(s) vs 1 after 1500 steps: "
          f"joints {cw}, largest displacement difference {np.abs(uw - us).max():.1e} m, "
          f"kinetic {kw:.6g} vs {ks:.6g} J")
    assert cw == cs and cw["open"] + cw["softening"] > 0
    assert np.array_equal(uw, us)
    assert kw == pytest.approx(ks, rel=1e-12)


def _wall_on_base(comm):
    """A dry running-bond wall (24 courses of 24 bricks) on a base block under its whole
    length: the rank holding the base spans the model."""
    from masonry_fdem.geometry import wall_layout
    from masonry_fdem.interactions import BlockContact, ContactSettings

    wall = wall_layout(courses=24, bricks_per_course=24, brick_length=0.215,
                       brick_height=0.065, joint=0.0)
    base = rectangle(-0.3, -0.2, 24 * 0.215 + 0.3, 0.0)
    blocks = mesh_blocks([base, *wall.polygons], materials=["stone", *wall.materials],
                         names=["base", *wall.names], comm=comm)
    model = Model(blocks, MATS, width=0.1025, comm=comm)
    model.fix_blocks("base")
    contact = BlockContact(model, ContactSettings(friction=0.6))
    contact.rebuild()
    return model, contact


def test_ghost_facets_follow_the_facets_not_the_ranks_box():
    """Each rank takes as ghosts only the other ranks' facets near its own (a coarse grid
    of cells, not its bounding box, which the base under the wall stretches over the whole
    model), and the pairs found on all ranks are those found on one."""
    comm = MPI.COMM_WORLD
    model, contact = _wall_on_base(comm)
    _, serial = _wall_on_base(MPI.COMM_SELF)
    mine = contact.keys[contact.counted > 0]
    keys = np.sort(np.concatenate(comm.allgather(mine)))
    assert np.array_equal(keys, serial.keys)
    ghosts = contact.n_candidates - contact.local_gid.size
    others = serial.local_gid.size - contact.local_gid.size
    print(f"\nrank {comm.rank}: {ghosts} ghost facets of {others} on the other ranks, "
          f"{keys.size} pairs as on one rank")
    if comm.size > 1:
        assert 0 < ghosts <= 0.3 * others
