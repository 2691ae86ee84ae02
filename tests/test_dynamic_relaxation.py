"""Dynamic relaxation converges to the static solution of a direct linear solve."""

from mpi4py import MPI

import numpy as np
import pytest
from conftest import rectangle
from naive import linear_static_solution

from masonry_fdem import Material, Model
from masonry_fdem.geometry import mesh_blocks
from masonry_fdem.solvers import DynamicRelaxation

comm = MPI.COMM_WORLD


def _compare(model, dr_rtol=1e-9):
    dr = DynamicRelaxation(model, rtol=dr_rtol)
    res = dr.solve(1.0)
    print(f"DR iterations: {res.iterations} (|r|/|f| = {res.relative_residual:.2e})")
    assert res.converged
    u_dr = model.displacement()
    u_lin = linear_static_solution(model)
    err = np.abs(u_dr - u_lin).max() / np.abs(u_lin).max()
    print(f"max |u_DR - u_linear| / max |u_linear| = {err:.2e}")
    assert err < 0.005
    return dr, res


def test_cantilever_block_matches_linear_solve():
    """A 4 m x 0.4 m cantilever under self-weight and a tip load (small: δ/L ~ 1e-3)."""
    blocks = mesh_blocks([rectangle(0, 0, 4.0, 0.4)], materials="b", mesh_size=0.1, comm=comm)
    model = Model(blocks, {"b": Material(2000.0, 10e9, 0.2)}, comm=comm)
    model.fix(lambda X: X[0] < 1e-9)
    model.add_gravity()
    model.add_point_load((4.0, 0.4), (0.0, -5e3))
    dr, res = _compare(model)
    # the support carries the whole load
    reaction = dr.reactions()["fixed"]
    total = 2000.0 * 4.0 * 0.4 * 9.80665 + 5e3
    assert reaction[1] == pytest.approx(total, rel=1e-6)


def test_wall_panel_self_weight_matches_linear_solve():
    """A 3 m x 2 m wall panel, 0.2 m thick, plane stress, built in at its base."""
    blocks = mesh_blocks([rectangle(0, 0, 3.0, 2.0)], materials="m", mesh_size=0.2, comm=comm)
    model = Model(blocks, {"m": Material(1900.0, 3e9, 0.15)}, width=0.2, comm=comm)
    model.fix(lambda X: X[1] < 1e-9)
    model.add_gravity()
    _compare(model)


def test_load_increments_scale_live_loads():
    """Live loads scale with the load factor; the dead load does not."""
    blocks = mesh_blocks([rectangle(0, 0, 2.0, 0.4)], materials="b", mesh_size=0.2, comm=comm)
    model = Model(blocks, {"b": Material(2000.0, 10e9, 0.2)}, comm=comm)
    model.fix(lambda X: X[0] < 1e-9)
    model.add_gravity()
    model.add_point_load((2.0, 0.4), (0.0, -1e4))
    dr = DynamicRelaxation(model, rtol=1e-8)
    results = dr.load_steps([1.0, 2.0, 3.0])
    assert [r.converged for r in results] == [True, True, True]
    weight = 2000.0 * 0.8 * 9.80665
    assert dr.reactions()["fixed"][1] == pytest.approx(weight + 3e4, rel=1e-6)
