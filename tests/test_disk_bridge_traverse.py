"""A bridge of the bridge builder with its fill as disks, a vehicle traversing it at a
fixed load (issue #22; :mod:`masonry_fdem.assessment.disk_bridge`): the small two-span
bridge of ``tests/test_bridge_builder.py`` (2 m spans on a 0.5 m pier founded on soil,
0.3 m of cover with 0.05 m of surfacing), its fill packed with about 220 disks."""

from __future__ import annotations

from mpi4py import MPI

import numpy as np
import pytest

from masonry_fdem.assessment.bridge import Vehicle
from masonry_fdem.assessment.disk_bridge import DiskBridge
from masonry_fdem.geometry.bridge import BridgeError
from masonry_fdem.solvers.status import Status

from test_bridge_builder import ITF, MATS, MORTAR, two_span

SIZES = {"masonry": 0.1, "pier": 0.15, "wall": 0.15, "surfacing": 0.05, "soil": 0.2}
LOAD = 10e3  # [N], both axles


def _reactions(b):
    return {k: v[1] for k, v in b.solver.reactions().items()}


@pytest.mark.skipif(MPI.COMM_WORLD.size > 1, reason="one process (the suite's budget: 45 s "
                    "under mpirun); the parallel part of the traverse, the tyres' nodal "
                    "forces, is checked on any number of ranks below")
def test_disk_filled_bridge_carries_a_vehicle_driven_across_it():
    """Under self-weight and with the vehicle at each position, the supports carry the
    weight of the blocks and disks (and the vehicle) within 2 %; the vehicle over the
    first span loads the first span's supports, over the second the second's (the far
    abutment takes less than a tenth of it); the road settles under each axle."""
    comm = MPI.COMM_WORLD
    b = DiskBridge(two_span(soil_depth=0.6, soil_extent=(1.5, 3.0)), MATS, MORTAR, ITF,
                   count=220, mesh_size=SIZES, comm=comm)
    assert b.settle()
    weight = -comm.allreduce(float(b.model.f_dead[1::2].sum())) + b.disks.weight
    dead = _reactions(b)
    seen = {}

    def at(br, x):
        seen[x] = _reactions(br)

    veh = Vehicle((0.0, -0.6), (1.0, 1.0), 0.2)
    run = b.traverse(veh, [1.3, 3.8], LOAD, ramp=1, callback=at)
    print(f"\ntwo spans, {b.disks.n} disks (inertia ×{b.inertia_scale:.0f}): {run.line()}; "
          f"steps {run.steps}; settlements {np.round(np.array(run.settlements) * 1e3, 2)} mm;"
          f" self-weight reactions / weight {sum(dead.values()) / weight:.4f}; " + "; ".join(
              f"x = {x}: " + ", ".join(f"{k} {(v - dead[k]) / LOAD:+.3f}" for k, v in r.items())
              for x, r in seen.items()))
    assert sum(dead.values()) == pytest.approx(weight, rel=0.02)
    assert run.status.status is Status.LOAD_REACHED and run.positions == [1.3, 3.8]
    for x, r in seen.items():
        assert sum(r.values()) == pytest.approx(weight + LOAD, rel=0.02), x
    added = {x: {k: (v - dead[k]) / LOAD for k, v in r.items()} for x, r in seen.items()}
    assert abs(added[1.3]["abutment:right"]) < 0.1 < added[1.3]["abutment:left"]
    assert abs(added[3.8]["abutment:left"]) < 0.1 < added[3.8]["abutment:right"]
    assert np.all(np.array(run.settlements) > 0)


def test_tyre_pressures_sum_to_the_axle_loads_on_any_rank_count():
    """The vehicle's consistent nodal forces on the surfacing's top (its nodes spread over
    the ranks): each axle's sum to its share of the load, the whole to the load, none
    outside the patches; the same on one rank as on several."""
    veh = Vehicle((0.0, -0.6), (2.0, 1.0), 0.2)
    out = {}
    for comm in (MPI.COMM_WORLD, MPI.COMM_SELF):
        b = DiskBridge(two_span(), MATS, MORTAR, ITF, count=220, mesh_size=SIZES, comm=comm)
        b.put_vehicle(veh, 1.37, LOAD)
        m = b.model
        n = m.n_nodes
        fy = LOAD * m.f_live[1:2 * n:2]
        x = m.X[:n, 0]
        # (a patch's end inside an element loads both its nodes: one element more,
        # the surfacing's 0.05 m, on each side)
        sums = [comm.allreduce(float(fy[np.abs(x - xa) <= 0.1 + 0.05 + 1e-9].sum()))
                for xa in (1.37, 0.77)]
        total = comm.allreduce(float(fy.sum()))
        out[comm.size] = (sums, total)
        assert sums == pytest.approx([-LOAD * 2 / 3, -LOAD / 3], rel=1e-12)
        assert total == pytest.approx(-LOAD, rel=1e-12)
        assert [p for _, p in b.axles] == pytest.approx([LOAD * 2 / 3, LOAD / 3])
    if MPI.COMM_WORLD.size > 1:
        assert out[MPI.COMM_WORLD.size][0] == pytest.approx(out[1][0], rel=1e-12)


def test_disk_filled_bridge_bad_input():
    comm = MPI.COMM_SELF
    with pytest.raises(BridgeError, match="needs a surfacing"):
        DiskBridge(two_span(surfacing=0.0), MATS, MORTAR, ITF, count=220, mesh_size=SIZES,
                   comm=comm)
    b = DiskBridge(two_span(), MATS, MORTAR, ITF, count=220, mesh_size=SIZES, comm=comm)
    with pytest.raises(RuntimeError, match="not settled"):
        b.traverse(Vehicle(patch=0.2), [1.0], LOAD)
    b.settled = True  # (the checks below come before any step)
    with pytest.raises(BridgeError, match="axle 1 of the vehicle .* off the deck"):
        b.traverse(Vehicle((0.0, -1.0), (1.0, 1.0), 0.2), [1.0, 0.3], LOAD)
    with pytest.raises(ValueError, match="no positions"):
        b.traverse(Vehicle(patch=0.2), [], LOAD)
    with pytest.raises(ValueError, match="load must be > 0"):
        b.put_vehicle(Vehicle(patch=0.2), 1.0, -1.0)
