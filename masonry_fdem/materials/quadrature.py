"""Material state at the quadrature points of a model (history variables, return mapping).

One :class:`QuadratureState` per :class:`~masonry_fdem.model.Model`. It owns

* the quadrature space ``Q`` (scalar) of the internal-force form, one degree for all
  materials (for P1 triangles one point per cell, exact for every law since ∇u is
  constant on a cell);
* the COMMITTED history variables of UFL laws (functions in ``Q``) and the compiled
  expressions of their trial values, which :meth:`commit` evaluates at the quadrature
  points;
* for return-mapping laws: the displacement gradient evaluated at their points, the committed
  and trial state arrays, and the stress and elastic-energy functions the kernels write
  (``Q4``: Sxx, Syy, Sxy, Szz).

:meth:`update` computes trial states from the committed ones at the current displacement
(every internal-force evaluation); :meth:`commit` accepts them (the explicit solver every
step, dynamic relaxation when an increment has converged). Nothing is allocated in either.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

import masonry_fdem._compat  # noqa: F401
import basix
import basix.ufl
import dolfinx
import dolfinx.fem
import ufl

__all__ = ["QuadratureState"]


@njit(cache=True)
def scatter_rows(src, rows, dst):
    """dst[rows[i], :] = src[i, :] for 2D arrays (src flattened per row)."""
    w = dst.shape[1]
    for i in range(rows.size):
        r = rows[i]
        for j in range(w):
            dst[r, j] = src[i, j]


@njit(cache=True)
def p1_gradients(X, u, cell_nodes, cells, rows, out):
    """Displacement gradient H = ∇u (H00, H01, H10, H11) of P1 triangles ``cells`` into
    ``out[rows]`` (constant on a cell: its single quadrature point)."""
    for k in range(cells.size):
        c = cells[k]
        a = cell_nodes[c, 0]
        b = cell_nodes[c, 1]
        d = cell_nodes[c, 2]
        x1 = X[b, 0] - X[a, 0]
        y1 = X[b, 1] - X[a, 1]
        x2 = X[d, 0] - X[a, 0]
        y2 = X[d, 1] - X[a, 1]
        det = x1 * y2 - x2 * y1
        ux1 = u[2 * b] - u[2 * a]
        uy1 = u[2 * b + 1] - u[2 * a + 1]
        ux2 = u[2 * d] - u[2 * a]
        uy2 = u[2 * d + 1] - u[2 * a + 1]
        # [du/dx, du/dy] = [Δu1, Δu2] J⁻¹ with J = [[x1, x2], [y1, y2]]
        r = rows[k]
        out[r, 0] = (ux1 * y2 - ux2 * y1) / det
        out[r, 1] = (ux2 * x1 - ux1 * x2) / det
        out[r, 2] = (uy1 * y2 - uy2 * y1) / det
        out[r, 3] = (uy2 * x1 - uy1 * x2) / det


class QuadratureState:
    """History and return-mapping state of the materials of one model (see module doc)."""

    def __init__(self, mesh, cell_material: np.ndarray, degree: int, p1=None):
        self.mesh = mesh
        #: (X (n, 2), u array, cell_nodes (nc, 3)) of a P1 model: gradients by numba
        self.p1 = p1
        self.degree = int(degree)
        cell = mesh.basix_cell()
        self.Q = dolfinx.fem.functionspace(
            mesh, basix.ufl.quadrature_element(cell, value_shape=(), degree=self.degree))
        self.points = self.Q.element.interpolation_points
        self.nqp = self.points.shape[0]
        self.n_cells = mesh.topology.index_map(2).size_local
        self.cell_material = cell_material
        self.qdofs = np.ascontiguousarray(self.Q.dofmap.list, dtype=np.int64)
        self.n_q = self.Q.dofmap.index_map.size_local
        self.metadata = {"quadrature_degree": self.degree}
        self.t_rate = math.inf  # time increment [s] for rate-dependent laws
        self._history = []  # (function, expression, cells, rows, buffer)
        self._rm = []  # (material, prm, qps)
        self._rm_cells: list[np.ndarray] = []
        self.stress_fn = None
        self.energy_fn = None

    # ------------------------------------------------------------------ set-up
    def cells(self, mid: int) -> np.ndarray:
        return np.flatnonzero(self.cell_material == mid).astype(np.int32)

    def add_history(self, mid: int, material, k) -> None:
        """Create the committed history functions of a UFL law into ``k.state``."""
        init = material.history()
        cells = self.cells(mid)
        for name, value in init.items():
            fn = dolfinx.fem.Function(self.Q, name=f"{name}[{mid}]")
            fn.x.array[:] = float(value)
            k.state[name] = fn
        trial = material.trial_history(k)
        if set(trial) != set(init):
            raise ValueError(
                f"{type(material).__name__}: trial_history() gives {sorted(trial)} but "
                f"history() declares {sorted(init)}")
        for name, expr in trial.items():
            compiled = dolfinx.fem.Expression(expr, self.points)
            rows = self.qdofs[cells].ravel()
            buf = np.zeros((cells.size, self.nqp))
            self._history.append((k.state[name], compiled, cells, rows, buf, float(init[name])))

    def add_return_mapping(self, mid: int, material, k, hypothesis) -> None:
        """Stress and energy of a return-mapping law come from its kernel."""
        from masonry_fdem.materials.plasticity import N_STATE

        if self.stress_fn is None:
            el4 = basix.ufl.quadrature_element(self.mesh.basix_cell(), value_shape=(4,),
                                               degree=self.degree)
            Q4 = dolfinx.fem.functionspace(self.mesh, el4)
            if not np.array_equal(Q4.dofmap.list, self.Q.dofmap.list):
                raise RuntimeError("unexpected quadrature dof layout")
            self.stress_fn = dolfinx.fem.Function(Q4, name="stress_qp")
            self.energy_fn = dolfinx.fem.Function(self.Q, name="energy_qp")
            self.stress = self.stress_fn.x.array.reshape(-1, 4)
            self.energy = self.energy_fn.x.array
            self.s0 = np.zeros((self.n_q, N_STATE))
            self.s1 = np.zeros((self.n_q, N_STATE))
            self.strain = np.zeros((self.n_q, 4))  # displacement gradient H
            # algorithmic tangent ∂(Sxx, Syy, Sxy)/∂(H00, H01, H10, H11) for the static solver
            el12 = basix.ufl.quadrature_element(self.mesh.basix_cell(), value_shape=(12,),
                                                degree=self.degree)
            self.ct_fn = dolfinx.fem.Function(dolfinx.fem.functionspace(self.mesh, el12),
                                              name="tangent_qp")
            self.ct = self.ct_fn.x.array.reshape(-1, 3, 4)
            H = k.H
            self._strain_expr = dolfinx.fem.Expression(
                ufl.as_vector([H[0, 0], H[0, 1], H[1, 0], H[1, 1]]), self.points)
        cells = self.cells(mid)
        self._rm_cells.append(cells)
        qps = np.ascontiguousarray(self.qdofs[cells].ravel())
        self._rm.append((material, material.kernel_params(hypothesis), qps))
        s = self.stress_fn
        k.stress = ufl.as_matrix([[s[0], s[2]], [s[2], s[1]]])
        k.energy = self.energy_fn

    def finalise(self) -> None:
        if self._rm:
            self.rm_cells = np.ascontiguousarray(np.concatenate(self._rm_cells))
            self.rm_rows = np.ascontiguousarray(self.qdofs[self.rm_cells].ravel())
            self._strain_buf = np.zeros((self.rm_cells.size, self.nqp, 4))
            self.update()  # initial stress (zero strain) so that the form is consistent

    @property
    def has_return_mapping(self) -> bool:
        return bool(self._rm)

    # ------------------------------------------------------------------ per step
    def update(self) -> None:
        """Trial states and stresses of the return-mapping laws at the current u."""
        if not self._rm:
            return
        if self.rm_cells.size:
            if self.p1 is not None and self.nqp == 1:
                X, u, cell_nodes = self.p1
                p1_gradients(X, u, cell_nodes, self.rm_cells, self.rm_rows, self.strain)
            else:
                self._strain_expr.eval(self.mesh, self.rm_cells, values=self._strain_buf)
                scatter_rows(self._strain_buf.reshape(-1, 4), self.rm_rows, self.strain)
        for material, prm, qps in self._rm:
            material.return_map(self.strain, self.s0, self.s1, self.stress, self.energy, qps,
                                prm, self.t_rate)

    def stress_variation(self, gd):
        """UFL: the variation δS [Pa] of the return-mapped second Piola–Kirchhoff stress
        for a variation ``gd`` of the displacement gradient, ``δS = 𝔻 : gd``."""
        c = self.ct_fn
        g = [gd[0, 0], gd[0, 1], gd[1, 0], gd[1, 1]]
        comp = [sum(c[4 * i + j] * g[j] for j in range(4)) for i in range(3)]
        return ufl.as_matrix([[comp[0], comp[2]], [comp[2], comp[1]]])

    def tangent(self, rel_step: float = 1e-6, floor: float = 1e-5) -> None:
        """The algorithmic tangent 𝔻 = ∂S/∂H of the return mappings at the current
        displacement gradient (:meth:`update` first), by central differences of the
        return mapping itself at each point (Miehe 1996, *Comput. Methods Appl. Mech.
        Engrg.* 134: the numerical algorithmic tangent), from the committed state. The
        step in each component of H is ``rel_step · max(|H|_max, floor)``: small enough
        for the truncation error, large enough that round-off and the plane-stress
        inner solve (tolerance 1e-12 of the stress) stay below ~1e-6 of the stiffness.
        """
        if not self._rm:
            return
        if not hasattr(self, "_fd"):
            self._fd = (np.zeros_like(self.strain), np.zeros_like(self.s1),
                        np.zeros_like(self.stress), np.zeros_like(self.energy),
                        np.zeros((self.n_q, 3, 4)))
        g, s1, st, en, acc = self._fd
        rows = self.rm_rows
        h = rel_step * np.maximum(np.abs(self.strain[rows]).max(axis=1), floor)
        acc[rows] = 0.0
        for j in range(4):
            for sign in (1.0, -1.0):
                g[:] = self.strain
                g[rows, j] += sign * h
                for material, prm, qps in self._rm:
                    material.return_map(g, self.s0, s1, st, en, qps, prm, self.t_rate)
                acc[rows, :, j] += sign * st[rows, :3]
        self.ct[rows] = acc[rows] / (2.0 * h)[:, None, None]

    def commit(self, on_change=None) -> None:
        """Accept the trial state at the current displacement. ``on_change()``, if given,
        is called while the committed history is still in place when a trial value
        differs from its committed one (on this rank)."""
        changed = False
        for fn, expr, cells, rows, buf, _ in self._history:
            if cells.size:
                expr.eval(self.mesh, cells, values=buf)
                if on_change is not None and not changed:
                    changed = not np.array_equal(buf.ravel(), fn.x.array[rows])
        if changed:
            on_change()
        for fn, _, cells, rows, buf, _ in self._history:
            if cells.size:
                scatter_rows(buf.reshape(-1, 1), rows, fn.x.array.reshape(-1, 1))
        if self._rm:
            self.s0[:] = self.s1

    def reset(self) -> None:
        """Back to the virgin state (initial history values, no plastic strain)."""
        for fn, _, _, _, _, init in self._history:
            fn.x.array[:] = init
        if self._rm:
            self.s0[:] = 0.0
            self.s1[:] = 0.0
            self.update()
