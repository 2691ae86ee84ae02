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


def test_a_joint_whose_resultant_lies_far_outside_it_gives_no_thrust_point(monkeypatch):
    """JointThrust.lines from given resultants (block_pair_resultants replaced): a
    compression across each radial joint acting at a fraction t of the joint from its
    first end gives the point p0 + t d; t = 1.8 (the bonded mortar's bending, just outside)
    is kept; t = 5 and t = -3 (a small thrust against a large moment: the line drawn across
    the figure on the TRL arch) are left out; a joint in tension has no point."""
    import masonry_fdem.assessment.thrust as thrust
    from masonry_fdem.assessment.assess import build_model
    from masonry_fdem.assessment.case import load_case

    case = load_case({"arch": {"span": 2.0, "ring_thickness": 0.2, "voussoirs": 6,
                               "abutment_height": 0.3, "abutment_width": 0.4,
                               "mesh_size": 0.2},
                      "materials": {"brick": {"density": 2000.0, "E": 10e9, "nu": 0.2},
                                    "abutment": {"density": 2000.0, "E": 30e9, "nu": 0.2}},
                      "joints": {"mortar": {"tan_phi": 10.0}}}, name="six")
    model, _, _ = build_model(case, comm=comm)
    jt = thrust.JointThrust(case, model)
    ts = [0.5, 1.8, 5.0, -3.0, 0.2, None, 0.7]  # None: tension across the joint
    assert len(jt.rows) == len(ts)  # 5 joints between 6 voussoirs and 2 springings

    def resultants(_, pairs):
        out = []
        for (_, _, _, _, p0, d, n), t in zip(jt.rows, ts, strict=True):
            f = (-1.0 if t is None else 1.0) * 1e3 * n  # [N], along n: compression
            x = p0 + (0.5 if t is None else t) * d      # a point of its line of action
            out.append((f[0], f[1], x[0] * f[1] - x[1] * f[0]))
        return np.array(out)

    monkeypatch.setattr(thrust, "block_pair_resultants", resultants)
    got = [p for line in jt.lines(None) for p in line]
    want = [tuple(r[4] + t * r[5]) for r, t in sorted(zip(jt.rows, ts, strict=True),
                                                      key=lambda x: x[0][1])
            if t is not None and -1.0 <= t <= 2.0]
    print(f"\nthrust points kept: {len(got)} of {len(ts)}")
    assert len(got) == 4
    np.testing.assert_allclose(got, want, atol=1e-12)
