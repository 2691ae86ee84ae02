"""Fracturable units: a beam cut into its triangles and rejoined by the cohesive crack law
cracks in three-point bending; peak load and dissipated energy must not depend on the mesh
(the crack stiffness scales as E/h and the softening is set by the fracture energy).

Both meshes are structured, so mid-span has a vertical line of element edges in each; the
supports and the loading knife sit on nodes the two meshes share. The loading is slow (the
run lasts about 23 periods of the beam's first bending mode) and lightly damped, so the
response is quasi-static.
"""

from __future__ import annotations

from mpi4py import MPI

import numpy as np
import pytest
from conftest import alternating_grid

from masonry_fdem import Material, Model
from masonry_fdem.interactions import JointMaterial, Joints
from masonry_fdem.geometry import BlockMesh
from masonry_fdem.solvers import ExplicitSolver

L, D, T = 0.4, 0.1, 0.1  # beam length, depth, thickness [m]
SUPPORTS = (0.02, 0.38)  # support points [m]
CRACK = JointMaterial(ft=1e6, GfI=50.0, c=1.5e6, GfII=500.0, tan_phi=0.8, penalty=10.0)


def beam(h: float) -> BlockMesh:
    """The beam as one unit on an nx × ny grid of alternating right triangles."""
    x, cells, _ = alternating_grid(L, D, h)
    return BlockMesh.from_arrays(x, cells, np.zeros(cells.shape[0], dtype=np.int64),
                                 block_names=["beam"], material_names=["unit"])


def bend(h: float, d_max: float = 3e-4, t_load: float = 0.03):
    """Peak load [N], dissipated energy [J] and crack state of the three-point bending test."""
    blocks = beam(h).fractured()
    model = Model(blocks, {"unit": Material(E=10e9, nu=0.2, density=2000.0)}, width=T)
    joints = Joints(model, cracks={"unit": CRACK})
    on = lambda x0, y0: lambda X: np.isclose(X[0], x0) & np.isclose(X[1], y0)  # noqa: E731
    model.fix(on(SUPPORTS[0], 0.0), components=(0, 1), name="pin")
    model.fix(on(SUPPORTS[1], 0.0), components=(1,), name="roller")
    t_r = 0.1 * t_load
    v0 = d_max / (t_load - 0.5 * t_r)
    model.prescribe_nodes(on(0.5 * L, D), lambda t: (None, -v0 * min(t / t_r, 1.0)),
                          name="knife")
    omega1 = 2 * np.pi * 780.0  # first bending mode, Euler–Bernoulli estimate [rad/s]
    solver = ExplicitSolver(model, interactions=joints, damping=0.1 * omega1)
    load, disp = [], []

    def record(s):
        load.append(-s.reactions()["knife"][1])
        t = s.t
        disp.append(v0 * (0.5 * t * t / t_r if t < t_r else 0.5 * t_r + t - t_r))

    solver.run(t_end=t_load, every=50, callback=record)
    return max(load), joints.energies()["joint_dissipated"], joints, np.array(disp)


@pytest.mark.skipif(MPI.COMM_WORLD.size > 1, reason="one process (the suite's budget: 12 s "
                    "under mpirun); the joints on two ranks are compared with one in "
                    "test_parallel.py::test_joints_and_contact_bitwise_same_on_any_rank_count")
def test_three_point_bending_is_mesh_objective():
    p1, e1, j1, _ = bend(0.02)
    p2, e2, j2, _ = bend(0.01)
    print(f"\nthree-point bending: h = 20 mm: peak {p1:.1f} N, dissipated {e1:.4f} J;"
          f" h = 10 mm: peak {p2:.1f} N, dissipated {e2:.4f} J;"
          f" changes {p2 / p1 - 1:+.2%}, {e2 / e1 - 1:+.2%}")
    assert abs(p2 / p1 - 1.0) < 0.10
    assert abs(e2 / e1 - 1.0) < 0.10
    # the beam cracked: energy of the order of G_fI over a good part of the section
    for e in (e1, e2):
        assert 0.3 * CRACK.GfI * D * T < e < 1.5 * CRACK.GfI * D * T
    # the crack opens on the mid-span line of edges; damage stays in the middle third
    for j in (j1, j2):
        st = j.status()
        opened = j.seg_mid[st == 2]
        assert opened.shape[0] >= 1
        assert np.all(np.abs(opened[:, 0] - 0.5 * L) < 1e-9)
        damaged = j.seg_mid[st >= 1]
        assert np.all(np.abs(damaged[:, 0] - 0.5 * L) < L / 6)
