"""Load to collapse by dynamic relaxation with restored, halved increments."""

import math

from mpi4py import MPI

import numpy as np
import pytest

from masonry_fdem import Material, Model
from masonry_fdem.interactions import BlockContact, ContactSettings
from masonry_fdem.geometry import BlockLayout, rectangle
from masonry_fdem.solvers.limit_analysis import limit_analysis
from masonry_fdem.solvers import DynamicRelaxation, Status


@pytest.mark.skipif(MPI.COMM_WORLD.size > 1, reason="one process: two blocks on COMM_SELF "
                    "(each rank ran the same alone; the suite's budget)")
def test_rocking_block_collapses_at_the_overturning_load():
    """A 0.5 × 1 m block (600 kg/m³, 1 m wide) on a fixed base, pushed sideways at its top
    corner: it overturns about its toe at P = W b / (2 h) = 735.50 N (the rigid-block limit
    analysis gives the same). Dynamic relaxation in increments of 0.2 P, each failed
    increment restored and halved four times, stalls within 5 % below it (elastic blocks,
    penalty contact: the toe is not a perfect point) and never above. A stall proves no
    collapse: the run ends *not converged* at the load tried, with no collapse load and
    the last load carried a lower bound."""
    lay = BlockLayout((rectangle(-0.5, -0.2, 1.0, 0.0), rectangle(0.0, 0.0, 0.5, 1.0)),
                      ("base", "brick"), ("base", "block"))
    W = 600.0 * 0.5 * 1.0 * 1.0 * 9.80665
    exact = W * 0.5 / (2 * 1.0)
    la = limit_analysis(lay, density=600.0, width=1.0, supports="base",
                        live_loads=[((0.0, 1.0), (1.0, 0.0))], friction=10.0)
    assert la.load_factor == pytest.approx(exact, rel=1e-9)
    # two blocks: one process is enough (the parallel load_to_collapse is exercised by
    # tests/test_assess.py)
    blocks = lay.mesh(0.1, MPI.COMM_SELF)
    model = Model(blocks, {"brick": Material(600.0, 1e9, 0.2), "base": Material(600.0, 1e9, 0.2)},
                  width=1.0, comm=MPI.COMM_SELF)
    model.fix_blocks("base")
    model.add_gravity()
    model.add_point_load((0.0, 1.0), (1.0, 0.0))
    contact = BlockContact(model, ContactSettings(friction=10.0))
    dr = DynamicRelaxation(model, interactions=contact, rtol=1e-6, ke_tol=math.inf,
                           max_iter=40_000)
    assert dr.solve(0.0).converged
    res = dr.load_to_collapse(0.2 * exact, refinements=4)
    print(f"\nrocking block: {res.status.describe('N')}; {res.load_factor:.2f} N "
          f"(+{res.resolution:.2f}) against {exact:.2f} N: {res.load_factor / exact:.4f}; "
          f"{len(dr.results)} solves")
    st = res.status
    assert st.status is Status.NOT_CONVERGED and not res.collapsed
    assert st.collapse_load is None and res.collapse_load_factor is None
    assert st.lower_bound == res.load_factor == st.load
    assert st.at == pytest.approx(res.load_factor + res.resolution)
    assert 0.95 * exact <= res.load_factor <= exact
    assert res.resolution == pytest.approx(0.2 * exact / 16)
    # the state was restored after the failed increment: the last load holds at once
    u = model.displacement().copy()
    again = dr.solve(res.load_factor)
    assert again.converged
    assert np.abs(model.displacement() - u).max() < 1e-3 * np.abs(u).max()
    # a load it carries is "load reached", no collapse load either
    res = dr.load_to_collapse(0.2 * exact, start=0.0, max_load=0.5 * exact)
    assert res.status.status is Status.LOAD_REACHED and not res.collapsed
    assert res.load_factor == pytest.approx(0.5 * exact) and res.status.collapse_load is None


def test_damping_estimates_reach_the_same_equilibrium():
    """A 2 m × 0.2 m cantilever (E = 1 GPa, plane stress) whose tip is pushed down 1 mm by
    displacement control: both damping estimates converge to the tip reaction of the
    Timoshenko beam, P = δ / (L³/(3EI) + L/(κGA)), within 15 % above it (four linear
    triangles through the depth are stiff in bending: +10 %), and to each other's
    reaction within 1e-5; the velocity quotient in fewer iterations."""
    lay = BlockLayout((rectangle(0.0, 0.0, 2.0, 0.2),), ("beam",), ("beam",))
    E, nu, L, h = 1e9, 0.0, 2.0, 0.2
    model = Model(lay.mesh(0.05, MPI.COMM_WORLD), {"beam": Material(1000.0, E, nu)},
                  width=1.0)
    model.fix(lambda X: X[0] < 1e-9, name="wall")
    model.prescribe_nodes(lambda X: np.abs(X[0] - L) < 1e-9, (None, 0.0), "tip")
    runs = {}
    for d in ("displacement", "velocity"):
        model.reset()
        dr = DynamicRelaxation(model, rtol=1e-8, ke_tol=math.inf, max_iter=200_000, damping=d)
        res = dr.solve(0.0, displacement={"tip": (None, -1e-3)})
        assert res.converged
        runs[d] = (-dr.reactions()["tip"][1], res.iterations)
    I, A, G = h**3 / 12, h, E / 2
    exact = 1e-3 / (L**3 / (3 * E * I) + L / (5 / 6 * G * A))
    for d, (P, its) in runs.items():
        print(f"\n{d}: tip force {P:.2f} N vs beam {exact:.2f} N, {its} iterations")
        assert exact < P < 1.15 * exact
    assert runs["velocity"][0] == pytest.approx(runs["displacement"][0], rel=1e-5)
    assert runs["velocity"][1] < runs["displacement"][1]
    with pytest.raises(ValueError, match="damping"):
        DynamicRelaxation(model, damping="kinetic")
