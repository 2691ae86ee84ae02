"""The FDEM line of thrust (assessment/thrust.py): section resultants against statics.

A column 0.4 m wide, 1.2 m tall, fixed at its foot, carries a load F at eccentricity e0
on its top. Whatever the stress distribution, the free body above any horizontal
section is in equilibrium: the section's normal force is −F and its resultant acts at
e0 from the section's middle. The P1 stresses integrated across the section give that
to the discretisation error (1 %). Then the arch of the assessment tests: the FDEM
thrust line at the peak lies within the ring and touches its faces at the hinges.
"""

from mpi4py import MPI

import numpy as np
import pytest
from conftest import rectangle

from masonry_fdem import Material, Model
from masonry_fdem.assessment.thrust import SectionCuts
from masonry_fdem.geometry import mesh_blocks
from masonry_fdem.solvers import StaticSolver
from masonry_fdem.solvers.status import Status

comm = MPI.COMM_WORLD


@pytest.mark.parametrize("e0", [0.0, 0.05, -0.125])  # on nodes of the top edge
def test_section_resultant_of_an_eccentrically_loaded_column(e0):
    b, h, F = 0.4, 1.2, 2e5  # m, m, N
    blocks = mesh_blocks([rectangle(0, 0, b, h)], materials="stone", mesh_size=0.025,
                         comm=comm)
    model = Model(blocks, {"stone": Material(2400.0, 20e9, 0.2)}, width=0.5, comm=comm)
    model.fix(lambda X: np.isclose(X[1], 0.0))
    model.add_point_load((0.5 * b + e0, h), (0.0, -F))
    st = StaticSolver(model).solve(1.0)
    assert st.converged
    # horizontal sections at 1/3 and 1/2 of the height: "radial" cuts of a circle of
    # radius 1 m whose centre lies 1 m left of the column, at 90° (pointing along +x)
    out = []
    for y in (h / 3, h / 2):
        cuts = SectionCuts(model, (-1.0, y), 1.0, b, [0.5 * np.pi], samples=80)
        N, M = cuts.resultants()
        (px, py), = cuts.thrust_points()
        out.append((y, N[0], M[0] / N[0], px))
    if comm.rank == 0:
        print("\n" + "\n".join(f"e0 = {e0:+.3f} m, section at y = {y:.2f} m: N = {n / 1e3:.2f}"
                               f" kN (−F = {-F / 1e3:.2f}), e = {e:+.4f} m, x = {x:.4f} m"
                               for y, n, e, x in out))
    for y, n, e, x in out:
        assert n == pytest.approx(-F, rel=0.01)
        assert e == pytest.approx(e0, abs=0.01 * b)
        assert x == pytest.approx(0.5 * b + e0, abs=0.01 * b)
