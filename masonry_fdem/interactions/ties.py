"""A tie that makes a group of nodes move together in one direction (a loading beam that
stays level).

:class:`EqualDisplacement` holds one displacement component of every node of the
selected blocks equal to the group's mean, by a penalty spring of stiffness ``k`` [N/m]
from each node to that mean:

    E = ½ k Σ_i (u_i − ū)²,   ū = (1/n) Σ_j u_j,
    f_i = −∂E/∂u_i = −k (u_i − ū)   (Σ_i (u_i − ū) = 0 removes the ū terms),
    −∂f_i/∂u_j = k (δ_ij − 1/n).

The group's common motion (the mean) is free: the tie adds no force to it, so a steel
beam tied in the vertical component can still move up and down under the wall's
reaction and a held precompression, but cannot tilt (tilting it needs the nodes' vertical
displacements to differ). This is the boundary condition of the TU Eindhoven shear-wall
tests (Raijmakers & Vermeltfoort 1992; Lourenço & Rots 1997): the top beam kept
horizontal, free to move vertically. With the other component prescribed (the beam's
horizontal drive) the beam moves as a rigid body in translation only.

The tangent ``k (I − 11ᵀ/n)`` has eigenvalues k (n − 1 times) and 0 (the common mode),
so the tie bounds ω² by k / m_min of its nodes (explicit step) and adds
Σ_j |K_ij| = 2 k (1 − 1/n) to each node's row sum (dynamic relaxation).

Units: SI (m, N).
"""

from __future__ import annotations

from collections.abc import Mapping

from mpi4py import MPI

import numpy as np

from masonry_fdem.interactions.protocol import BLOCKS, Interaction, State, Tangent

__all__ = ["EqualDisplacement"]


class EqualDisplacement(Interaction):
    """Ties component ``component`` (0: x, 1: y) of the nodes of the selected blocks to
    their common mean by a penalty (see the module doc).

    Args:
        model: the :class:`~masonry_fdem.model.Model`.
        blocks: a block selection (name, pattern, ids; as ``Model.select_blocks``).
        component: the tied component, 0 (x) or 1 (y).
        stiffness: the penalty k [N/m] per node; default 1000 × the largest E [Pa] of the
            selected blocks' materials × the model's out-of-plane width [m] (a thousand
            times an element's own stiffness: a steel slab on a stiff joint, loaded off
            centre, tilts by ~1e-4 of what it would untied; tests/test_shear_wall.py).
        name: the interaction's name (energies, messages).

    Raises:
        ValueError: a bad component, a stiffness not > 0, or fewer than two nodes.
    """

    name = "tie"

    def __init__(self, model, blocks, *, component: int = 1, stiffness: float | None = None,
                 name: str = "tie"):
        if component not in (0, 1):
            raise ValueError(f"component must be 0 (x) or 1 (y), got {component}")
        self.model, self.comm, self.name = model, model.comm, str(name)
        self.component = int(component)
        ids = model.select_blocks(blocks)
        if stiffness is None:
            mats = {model.blocks.material_names[m]
                    for m in np.unique(model.blocks.block_material[ids])}
            stiffness = 1000.0 * max(model.materials[m].E for m in mats) * model.width
        if not (np.isfinite(stiffness) and stiffness > 0):
            raise ValueError(f"tie stiffness must be > 0 N/m, got {stiffness}")
        self.k = float(stiffness)
        nodes = np.flatnonzero(np.isin(model.node_block, ids)).astype(np.int64)
        self.dofs = 2 * nodes + self.component  # this rank's tied dofs (local numbers)
        self.n = self.comm.allreduce(int(nodes.size))
        if self.n < 2:
            raise ValueError(f"tie {self.name!r}: the selection {blocks!r} has {self.n} "
                             "node(s); a tie needs two or more")
        # every tied node by BlockMesh input id (every rank: rank 0 adds the tangent)
        self.input_ids = np.concatenate(self.comm.allgather(model.node_input[nodes]))
        mass = model.mass[self.dofs]
        self.m_min = self.comm.allreduce(float(mass.min()) if mass.size else np.inf,
                                         op=MPI.MIN)
        self._mean = 0.0
        self._energy = 0.0  # this rank's ½ k Σ (u_i − ū)² at the last evaluation [J]

    def _mean_of(self, u: np.ndarray) -> float:
        return self.comm.allreduce(float(u[self.dofs].sum())) / self.n

    def update(self, state: State) -> None:
        self._mean = self._mean_of(state.u[BLOCKS])

    def add_forces(self, state: State) -> None:
        u = state.u[BLOCKS]
        d = u[self.dofs] - self._mean
        state.f[BLOCKS][self.dofs] -= self.k * d
        self._energy = 0.5 * self.k * float(np.dot(d, d))

    def add_tangent(self, K: Tangent, state: State) -> None:
        if K.rank != 0:
            return
        g = K.node_dofs(self.input_ids).reshape(-1, 2)[:, self.component]
        rows = np.repeat(g, g.size)
        cols = np.tile(g, g.size)
        vals = np.full(g.size * g.size, -self.k / self.n)
        vals[:: g.size + 1] += self.k  # the diagonal: k (1 − 1/n)
        K.add(rows, cols, vals)

    def stable_omega2(self) -> dict[str, float]:
        return {BLOCKS: self.k / self.m_min}

    def add_rowsum(self, rows: Mapping[str, np.ndarray]) -> None:
        rows[BLOCKS][self.dofs] += 2.0 * self.k * (1.0 - 1.0 / self.n)

    def energies(self) -> dict[str, float]:
        """The energy of the springs [J] at the last evaluation of the forces, as every
        interaction reports it (collective)."""
        return {"stored": self.comm.allreduce(self._energy), "dissipated": 0.0}
