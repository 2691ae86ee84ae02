"""A four-triangle patch (a square with its centre node) driven by dynamic relaxation along
homogeneous strain paths, for single-element and patch tests of the block laws."""

from __future__ import annotations

from mpi4py import MPI

import numpy as np

from masonry_fdem import Model
from masonry_fdem.geometry import BlockMesh
from masonry_fdem.solvers import DynamicRelaxation

L = 0.1  # side of the patch [m]
W = 0.1  # out-of-plane width [m]


def patch_mesh(centre=(0.5, 0.5)) -> BlockMesh:
    """Unit square of side L split into four triangles around an interior node."""
    x = L * np.array([[0, 0], [1, 0], [1, 1], [0, 1], list(centre)], dtype=float)
    cells = np.array([[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]])
    return BlockMesh.from_arrays(x, cells, np.zeros(4, dtype=np.int64), block_names=["patch"],
                                 material_names=["m"])


def near(a, b):
    return np.isclose(a, b, atol=1e-9 * L)


class Patch:
    """Drives the patch in uniaxial stress (x) or in simple shear.

    uniaxial: left edge ux = 0, bottom edge uy = 0, right edge ux = δ; the rest is free.
    shear: bottom corners fixed, top corners at (γ L, 0); the centre node is free.
    The reaction of the driven edge over L W is the first Piola–Kirchhoff traction.
    """

    def __init__(self, material, mode, hypothesis="plane_stress", centre=(0.5, 0.5),
                 comm=MPI.COMM_SELF, rtol=1e-12):
        self.mode = mode
        self.model = Model(patch_mesh(centre), {"m": material}, hypothesis=hypothesis, width=W,
                           comm=comm)
        m = self.model
        if mode == "uniaxial":
            m.fix(lambda X: near(X[0], 0.0), components=(0,), name="left")
            m.fix(lambda X: near(X[1], 0.0), components=(1,), name="bottom")
            m.prescribe_nodes(lambda X: near(X[0], L), (0.0, None), name="drive")
        elif mode == "shear":
            m.fix(lambda X: near(X[1], 0.0), name="bottom")
            m.prescribe_nodes(lambda X: near(X[1], L), (0.0, 0.0), name="drive")
        elif mode == "affine":
            # every node follows u = H X (a softening law would localise otherwise)
            m.prescribe_nodes(lambda X: near(X[0], L), (0.0, 0.0), name="right")
            m.prescribe_nodes(lambda X: near(X[1], L) & ~near(X[0], L), (0.0, 0.0),
                              name="top")
            m.prescribe_nodes(lambda X: ~near(X[0], L) & ~near(X[1], L), (0.0, 0.0),
                              name="rest")
        else:
            raise ValueError(mode)
        self.dr = DynamicRelaxation(m, rtol=rtol, ke_tol=1e-24, max_iter=200_000)

    def affine(self, H: np.ndarray) -> np.ndarray:
        """Move every node by u = H X; return the traction P[:, 0] on the right edge [Pa]."""
        m = self.model
        u = m.u.x.array.reshape(-1, 2)
        u[:] = m.X @ np.asarray(H).T
        res = self.dr.solve(0.0)
        assert res.converged, res
        return self.dr.reactions()["right"] / (L * W)

    def step(self, value: float, dt: float | None = None) -> np.ndarray:
        """Go to strain ``value`` (δ/L or γ); return the traction (P_x, P_y) on the driven
        edge [Pa]."""
        d = value * L
        disp = {"drive": (d, None)} if self.mode == "uniaxial" else {"drive": (d, 0.0)}
        res = self.dr.solve(0.0, displacement=disp, dt=dt)
        assert res.converged, res
        return self.dr.reactions()["drive"] / (L * W)


def svk_uniaxial(lam, mu, e):
    """St. Venant–Kirchhoff in uniaxial stress: P11 for the stretch 1 + e (λ in-plane)."""
    E11 = e + 0.5 * e * e
    S11 = 4.0 * mu * (lam + mu) / (lam + 2.0 * mu) * E11
    return (1.0 + e) * S11
