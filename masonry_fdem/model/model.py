"""The assembled model: one dolfinx mesh of all blocks, materials, masses, loads, supports.

A :class:`Model` owns the state of the deformable blocks (displacement ``u`` as a dolfinx
function, velocity ``v`` as an array), the compiled internal-force form, the lumped mass and
the load and support definitions. Solvers (``masonry_fdem.solvers``) advance it in time.

Kinematics are total Lagrangian: the mesh stays in the reference configuration and the
current position is ``x = X + u``. The internal force ``f_int = ∫ P(F) : ∇v w dX`` (``w``
the out-of-plane width) is assembled by dolfinx from ONE compiled form into a preallocated
array; each material acts on its own tagged cells through ``dx(material_id)``.

Units are SI: lengths [m], forces [N], stresses [Pa], masses [kg], time [s].
"""

from __future__ import annotations

import fnmatch
import math
import logging
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

from mpi4py import MPI

import numpy as np

import masonry_fdem._compat  # noqa: F401  (imports dolfinx_solver before dolfinx)
import dolfinx
import dolfinx.fem
import dolfinx.mesh
import ufl
from dolfinx import cpp as _cpp

from masonry_fdem.constants import G
from masonry_fdem.materials import Hypothesis, Material, green_lagrange, lame_parameters
from masonry_fdem.materials.base import LawContext
from masonry_fdem.materials.plasticity import PLASTIC_WORK, ReturnMapping
from masonry_fdem.materials.quadrature import QuadratureState
from masonry_fdem.parallel import DistributedBlockMesh, create_block_mesh
from masonry_fdem.model import _kernels as K

if TYPE_CHECKING:
    from masonry_fdem.geometry import BlockMesh

__all__ = ["Model", "BlockSelection", "Prescription"]

log = logging.getLogger(__name__)

#: quadrature degree of the internal-force form: one point per P1 triangle
QUADRATURE_DEGREE = 1

#: A set of blocks: a name or glob pattern ("brick:*"), a block id, a sequence of those,
#: or a predicate on the block centroid (x, y) [m].
BlockSelection = str | int | Sequence[str | int] | Callable[[np.ndarray], bool]


@dataclass
class Prescription:
    """Prescribed velocity [m/s] on some dofs (zero for a fixed support).

    Attributes:
        name: label used in the history (its reaction force is reported).
        dofs: local dof indices (block size 2 flattened).
        components: (len(dofs),) component (0: x, 1: y) of each dof.
        velocity: (2,) velocity or a function of time t [s] returning it; a ``None``
            component is free.
    """

    name: str
    dofs: np.ndarray
    components: np.ndarray
    velocity: Callable[[float], Sequence[float]] | Sequence[float | None]

    def value(self, t: float) -> np.ndarray:
        vel = self.velocity(t) if callable(self.velocity) else self.velocity
        vel = np.array([0.0 if c is None else float(c) for c in vel])
        return vel[self.components]

    @property
    def time_dependent(self) -> bool:
        return callable(self.velocity)


class Model:
    """Deformable blocks in ONE dolfinx mesh, with materials, loads and supports.

    Args:
        blocks: the block mesh (from ``masonry_fdem.geometry``), the same on every rank.
        materials: material of each material name used in ``blocks``.
        hypothesis: plane stress (with out-of-plane ``width``) or plane strain.
        hypotheses: per material name, a hypothesis other than ``hypothesis`` (e.g. the
            fill of a bridge in plane strain under a plane-stress arch barrel: a soil in
            plane stress squeezes out of the plane and has almost no bearing capacity).
        width: out-of-plane width [m] (arch barrel width, wall thickness); under plane
            strain it is the length of the slice the forces refer to.
        comm: MPI communicator; each block goes wholly to one rank.

    Raises:
        ValueError: a material is missing, or a constant is out of range.
    """

    def __init__(
        self,
        blocks: BlockMesh,
        materials: Mapping[str, Material],
        *,
        hypothesis: Hypothesis | str = Hypothesis.PLANE_STRESS,
        hypotheses: Mapping[str, Hypothesis | str] | None = None,
        width: float = 1.0,
        comm: MPI.Comm = MPI.COMM_WORLD,
    ):
        self.hypothesis = Hypothesis(hypothesis)
        unknown = sorted(set(hypotheses or {}) - set(blocks.material_names))
        if unknown:
            raise ValueError(f"hypotheses: no material {unknown} in the block mesh (it has "
                             f"{list(blocks.material_names)})")
        #: the hypothesis of each material name
        self.hypotheses = {n: Hypothesis((hypotheses or {}).get(n, self.hypothesis))
                           for n in blocks.material_names}
        if not (np.isfinite(width) and width > 0):
            raise ValueError(f"out-of-plane width must be > 0 m, got {width}")
        self.width = float(width)
        missing = [m for m in blocks.material_names if m not in materials]
        if missing:
            raise ValueError(
                f"no Material given for material name(s) {missing}; "
                f"the block mesh uses {list(blocks.material_names)}"
            )
        for name in blocks.material_names:
            if not isinstance(materials[name], Material):
                raise TypeError(f"materials[{name!r}] must be a Material")
        self.blocks = blocks
        self.materials = {name: materials[name] for name in blocks.material_names}
        self.comm = comm
        self.dmesh: DistributedBlockMesh = create_block_mesh(blocks, comm)
        self.mesh = self.dmesh.mesh
        self._setup_spaces()
        self._setup_forms()
        self._setup_mass()
        self.f_int = np.zeros_like(self.u.x.array)
        self.f_dead = np.zeros_like(self.u.x.array)
        self.f_live = np.zeros_like(self.u.x.array)
        self.prescriptions: list[Prescription] = []
        self.monitors: dict[str, tuple[int, int]] = {}

    @property
    def u(self) -> dolfinx.fem.Function:
        """The nodal displacement [m] (a dolfinx Function, P1, 2 dofs per node: x, y).

        Assignable like ``v``: ``model.u = values`` copies an array of the local dofs
        (``model.u.x.array``'s length, or the owned dofs only: the ghosts are then updated)
        or another Function's values into it; the Function itself stays (the forms use it).
        """
        return self._u

    @u.setter
    def u(self, values) -> None:
        if isinstance(values, dolfinx.fem.Function):
            values = values.x.array
        arr = np.asarray(values, dtype=self._u.x.array.dtype).ravel()
        n_all, n_owned = self._u.x.array.size, 2 * self.n_nodes
        if arr.size == n_all:
            self._u.x.array[:] = arr
        elif arr.size == n_owned:
            self._u.x.array[:n_owned] = arr
            self._u.x.scatter_forward()
        else:
            raise ValueError(f"model.u = ...: expected {n_all} values (2 per local node"
                             f"{'' if n_all == n_owned else f', or {n_owned} owned'}), got "
                             f"{arr.size}")

    # ------------------------------------------------------------------ set-up
    def _setup_spaces(self) -> None:
        mesh = self.mesh
        self.V = dolfinx.fem.functionspace(mesh, ("Lagrange", 1, (2,)))
        imap = self.V.dofmap.index_map
        if imap.num_ghosts != 0:
            raise RuntimeError("a block is split between ranks (ghost nodes found)")
        self.n_nodes = imap.size_local
        self._u = dolfinx.fem.Function(self.V, name="displacement")
        self.v = np.zeros_like(self._u.x.array)
        # local dof-node -> input node of the BlockMesh, through the geometry dofmap
        cell_dofs = self.V.dofmap.list
        geom = mesh.geometry.dofmaps[0]
        self.node_input = np.empty(self.n_nodes, dtype=np.int64)
        self.node_input[cell_dofs.ravel()] = self.dmesh.node_input[geom.ravel()]
        self.X = self.blocks.x[self.node_input]  # (n_nodes, 2) reference coordinates
        self.node_block = self.blocks.node_block[self.node_input].astype(np.int32)
        self.cell_nodes = np.ascontiguousarray(cell_dofs, dtype=np.int64)

    def _setup_forms(self) -> None:
        mesh = self.mesh
        mat_ids = self.dmesh.cell_tags_material
        self.dx = ufl.Measure("dx", domain=mesh, subdomain_data=mat_ids)
        self.ds = ufl.Measure("ds", domain=mesh)
        # the constitutive laws: one quadrature point per P1 cell (∇u is constant there)
        self.qstate = QuadratureState(
            mesh, self.dmesh.cell_material, QUADRATURE_DEGREE,
            p1=(np.ascontiguousarray(self.X), self.u.x.array, self.cell_nodes))
        dxq = ufl.Measure("dx", domain=mesh, subdomain_data=mat_ids,
                          metadata=self.qstate.metadata)
        u = self.u
        w = ufl.TestFunction(self.V)
        self.w_const = dolfinx.fem.Constant(mesh, self.width)
        self.lam: dict[int, dolfinx.fem.Constant] = {}
        self.mu: dict[int, dolfinx.fem.Constant] = {}
        self.rho: dict[int, dolfinx.fem.Constant] = {}
        self.law_context: dict[int, LawContext] = {}
        H = ufl.grad(u)
        F = ufl.Identity(2) + H
        E = green_lagrange(H)
        # the displacement at the last commit (kept only when a law dissipates at commits)
        self.u_committed = dolfinx.fem.Function(self.V, name="displacement_committed")
        E_committed = green_lagrange(ufl.grad(self.u_committed))
        h = ufl.sqrt(2.0 * ufl.CellVolume(mesh))
        h_cells = np.sqrt(2.0 * self.blocks.cell_area)
        f_int = 0
        energy = 0
        dissipation = 0
        self._dxq = dxq
        self._terms: list[tuple[int, Material, object]] = []  # (material id, law, P)
        for mid, name in enumerate(self.blocks.material_names):
            mat = self.materials[name]
            in_mat = self.blocks.cell_material == mid
            hyp = self.hypotheses[name]
            if np.any(in_mat):
                mat.check_mesh(float(h_cells[in_mat].max()), hyp)
            lam, mu = lame_parameters(mat, hyp)
            self.lam[mid] = dolfinx.fem.Constant(mesh, lam)
            self.mu[mid] = dolfinx.fem.Constant(mesh, mu)
            self.rho[mid] = dolfinx.fem.Constant(mesh, mat.density)
            k = LawContext(mesh, u, H, F, E, self.lam[mid], self.mu[mid], hyp, h,
                           E_committed=E_committed)
            if isinstance(mat, ReturnMapping):
                self.qstate.add_return_mapping(mid, mat, k, hyp)
            self.qstate.add_history(mid, mat, k)
            self.law_context[mid] = k
            P = mat.first_piola(k)
            if getattr(P, "ufl_shape", None) != (2, 2):
                raise ValueError(f"material {name!r}: first_piola() must give a 2x2 UFL tensor")
            f_int += ufl.inner(P, ufl.grad(w)) * self.w_const * dxq(mid)
            energy += mat.energy_density(k) * self.w_const * dxq(mid)
            inc = mat.dissipation_increment(k)
            if inc is not None:
                dissipation += inc * self.w_const * dxq(mid)
            self._terms.append((mid, mat, P))
        self.qstate.finalise()
        self.f_int_form = dolfinx.fem.form(f_int)
        self.energy_form = dolfinx.fem.form(energy)
        # the energy the history laws (damage) dissipate at a commit, and its sum on this
        # rank [J]
        self.dissipation_form = (None if isinstance(dissipation, int)
                                 else dolfinx.fem.form(dissipation))
        self._damage_dissipated = 0.0
        self._constants = dolfinx.fem.pack_constants(self.f_int_form)
        self._coeffs = dolfinx.fem.pack_coefficients(self.f_int_form)
        self._setup_packing(f_int)
        self._tangent = None  # compiled on first use (static solver only)
        # Cauchy stress per cell for output: one expression per material on its cells,
        # at the quadrature point (one per cell: the DG0 value)
        self.S_space = dolfinx.fem.functionspace(mesh, ("DG", 0, (2, 2)))
        self.stress = dolfinx.fem.Function(self.S_space, name="stress")
        self._stress_expr = []
        for mid, name in enumerate(self.blocks.material_names):
            cells = self.qstate.cells(mid)
            P = self.materials[name].first_piola(self.law_context[mid])
            expr = dolfinx.fem.Expression(P * F.T / ufl.det(F), self.qstate.points)
            self._stress_expr.append((cells, expr))

    def _setup_packing(self, ufl_form) -> None:
        """Index of each packed coefficient entry into its function's array.

        The form's coefficient functions (u, committed history, kernel stresses) are filled
        with disjoint ranges of integers and packed once; the packed numbers say where
        each entry comes from. Each evaluation then gathers the entries without dolfinx's
        per-call packing overhead.
        """
        functions = [c for c in ufl_form.coefficients() if hasattr(c, "x")]
        saved = [f.x.array.copy() for f in functions]
        offsets = [0]
        for f in functions:
            n = f.x.array.size
            f.x.array[:] = offsets[-1] + np.arange(n, dtype=np.float64)
            offsets.append(offsets[-1] + n)
        probe = dolfinx.fem.pack_coefficients(self.f_int_form)
        for f, a in zip(functions, saved, strict=True):
            f.x.array[:] = a
        offsets = np.asarray(offsets)
        self._gather = []
        for key, packed in probe.items():
            flat = packed.ravel()
            code = np.rint(flat).astype(np.int64)
            if not np.allclose(flat, code):
                raise RuntimeError("unexpected coefficient packing (non-permutation)")
            which = np.searchsorted(offsets, code, side="right") - 1
            for i, f in enumerate(functions):
                pos = np.flatnonzero(which == i).astype(np.int64)
                if pos.size:
                    idx = (code[pos] - offsets[i]).astype(np.int64)
                    self._gather.append((key, f.x.array, idx, pos))
        self._packed_flat = {key: packed.reshape(-1) for key, packed in self._coeffs.items()}

    def _setup_mass(self) -> None:
        w = ufl.TestFunction(self.V)
        ones = dolfinx.fem.Constant(self.mesh, np.ones(2))
        form = 0
        for mid in self.rho:
            form += self.rho[mid] * self.w_const * ufl.dot(ones, w) * self.dx(mid)
        # row sum of the consistent mass = the lumped mass (exact for P1 triangles)
        self.mass = self._assemble(form)
        if np.any(self.mass <= 0):
            raise ValueError("a node has zero lumped mass (degenerate element?)")
        self.minv = 1.0 / self.mass

    def scale_inertia(self, factor: float) -> None:
        """Density scaling for quasi-static explicit runs: multiply every block's inertia
        (the lumped mass, and the density in the elements' stable-step bound) by
        ``factor`` ≥ 1, leaving the loads as they are (self-weight already added keeps
        the true weight; gravity added afterwards would be scaled too). The critical
        time step grows by √factor; the equilibrium states do not change, only how the
        blocks get there. Not for dynamics.

        Raises:
            ValueError: ``factor`` not finite or below 1.
        """
        if not (math.isfinite(factor) and factor >= 1.0):
            raise ValueError(f"inertia scale factor must be finite and >= 1, got {factor}")
        for c in self.rho.values():
            c.value = c.value * factor
        self.mass *= factor
        self.minv /= factor

    def _assemble(self, form) -> np.ndarray:
        vec = dolfinx.fem.assemble_vector(dolfinx.fem.form(form))
        vec.scatter_reverse(dolfinx.la.InsertMode.add)
        vec.scatter_forward()
        return vec.array.copy()

    # ------------------------------------------------------------------ selection
    def select_blocks(self, sel: BlockSelection) -> np.ndarray:
        """Block ids of a selection (see :data:`BlockSelection`)."""
        names = self.blocks.block_names
        if callable(sel):
            ids = [b for b in range(len(names)) if sel(self.blocks.block_centroid[b])]
        else:
            items = [sel] if isinstance(sel, str | int | np.integer) else list(sel)
            ids = []
            for item in items:
                if isinstance(item, str):
                    hits = [b for b, n in enumerate(names) if fnmatch.fnmatchcase(n, item)]
                    if not hits:
                        raise ValueError(f"no block named {item!r}")
                    ids.extend(hits)
                else:
                    b = int(item)
                    if not 0 <= b < len(names):
                        raise ValueError(f"block id {b} out of range 0..{len(names) - 1}")
                    ids.append(b)
        if not ids:
            raise ValueError(f"selection {sel!r} matches no block")
        return np.unique(np.asarray(ids, dtype=np.int32))

    def _block_nodes(self, sel: BlockSelection) -> np.ndarray:
        ids = self.select_blocks(sel)
        return np.flatnonzero(np.isin(self.node_block, ids)).astype(np.int64)

    # ------------------------------------------------------------------ loads
    def add_gravity(self, g: Sequence[float] = (0.0, -G), *, live: bool = False) -> None:
        """Self-weight ρ g per unit volume; ``g`` [m/s²]. Dead load unless ``live``."""
        w = ufl.TestFunction(self.V)
        gc = dolfinx.fem.Constant(self.mesh, np.asarray(g, dtype=float))
        form = 0
        for mid in self.rho:
            form += self.rho[mid] * self.w_const * ufl.dot(gc, w) * self.dx(mid)
        self._add_load(self._assemble(form), live)

    def add_point_load(
        self, point: Sequence[float], force: Sequence[float], *, live: bool = True,
        blocks: BlockSelection | None = None,
    ) -> None:
        """A force [N] (whole width) at the node nearest to ``point`` [m].

        Args:
            point: (x, y) location [m].
            force: (Fx, Fy) [N].
            live: scaled by the load factor (dynamic relaxation) if True.
            blocks: restrict the search to these blocks.
        """
        node = self.nearest_node(point, blocks)
        f = np.zeros_like(self.f_int)
        if node >= 0:
            f[2 * node : 2 * node + 2] = np.asarray(force, dtype=float)
        self._add_load(f, live)

    def add_line_load(
        self, where: Callable[[np.ndarray], np.ndarray], q: Sequence[float], *,
        live: bool = True,
    ) -> None:
        """A distributed load q [N/m] (force per metre of block boundary, whole width).

        Args:
            where: ``where(x)`` with x of shape (2, n) facet midpoints → bool mask; block
                boundary facets selected by it carry the load.
            q: (qx, qy) [N/m].
            live: scaled by the load factor if True.
        """
        facets = self._boundary_facets(where)
        tags = dolfinx.mesh.meshtags(
            self.mesh, 1, facets, np.ones(facets.size, dtype=np.int32)
        )
        ds = ufl.Measure("ds", domain=self.mesh, subdomain_data=tags)
        qc = dolfinx.fem.Constant(self.mesh, np.asarray(q, dtype=float))
        w = ufl.TestFunction(self.V)
        self._add_load(self._assemble(ufl.dot(qc, w) * ds(1)), live)

    def add_pressure(
        self, where: Callable[[np.ndarray], np.ndarray], p: float, *, live: bool = True
    ) -> None:
        """A pressure p [Pa] on the selected boundary facets (acting against the outward
        reference normal, over the out-of-plane width)."""
        facets = self._boundary_facets(where)
        tags = dolfinx.mesh.meshtags(
            self.mesh, 1, facets, np.ones(facets.size, dtype=np.int32)
        )
        ds = ufl.Measure("ds", domain=self.mesh, subdomain_data=tags)
        n = ufl.FacetNormal(self.mesh)
        pc = dolfinx.fem.Constant(self.mesh, float(p))
        w = ufl.TestFunction(self.V)
        self._add_load(self._assemble(-pc * self.w_const * ufl.dot(n, w) * ds(1)), live)

    def _boundary_facets(self, where) -> np.ndarray:
        facets = dolfinx.mesh.locate_entities_boundary(
            self.mesh, 1, lambda x: np.asarray(where(x[:2]), dtype=bool)
        )
        n = self.comm.allreduce(facets.size)
        if n == 0:
            raise ValueError("the line-load locator selects no block boundary facet")
        return facets.astype(np.int32)

    def _add_load(self, f: np.ndarray, live: bool) -> None:
        if live:
            self.f_live += f
        else:
            self.f_dead += f

    def external_force(self, load_factor: float = 1.0, out: np.ndarray | None = None):
        """f_ext = f_dead + load_factor · f_live [N] (local dofs)."""
        if out is None:
            out = np.empty_like(self.f_dead)
        np.multiply(self.f_live, load_factor, out=out)
        out += self.f_dead
        return out

    # ------------------------------------------------------------------ supports
    def fix_blocks(self, sel: BlockSelection, name: str | None = None) -> Prescription:
        """Hold the selected blocks fixed (a support block, an abutment)."""
        return self.prescribe_velocity(sel, (0.0, 0.0), name=name or f"fixed:{sel}")

    def prescribe_velocity(
        self,
        sel: BlockSelection,
        velocity: Sequence[float | None] | Callable[[float], Sequence[float]],
        name: str | None = None,
    ) -> Prescription:
        """Move the selected blocks with a prescribed velocity [m/s] (a loading platen).

        ``velocity`` is (vx, vy) with ``None`` for a free component, or a function of time.
        The reaction force on the prescription is reported by the solvers.
        """
        return self._prescribe(self._block_nodes(sel), velocity, name or f"velocity:{sel}")

    def fix(
        self,
        where: Callable[[np.ndarray], np.ndarray],
        components: Sequence[int] = (0, 1),
        name: str = "fixed",
    ) -> Prescription:
        """Fix the given components of the nodes where ``where(X)`` is True (X: (2, n) [m])."""
        nodes = np.flatnonzero(np.asarray(where(self.X.T), dtype=bool))
        if self.comm.allreduce(nodes.size) == 0:
            raise ValueError(f"support {name!r}: the locator selects no node")
        vel = [None, None]
        for c in components:
            vel[c] = 0.0
        return self._prescribe(nodes.astype(np.int64), vel, name)

    def prescribe_nodes(
        self,
        where: Callable[[np.ndarray], np.ndarray],
        velocity: Sequence[float | None] | Callable[[float], Sequence[float]],
        name: str,
    ) -> Prescription:
        """Prescribe the velocity [m/s] of the nodes where ``where(X)`` is True (X: (2, n)
        [m]): a loading knife or a support point across the pieces of a fractured unit.
        ``velocity`` is as in :meth:`prescribe_velocity`."""
        nodes = np.flatnonzero(np.asarray(where(self.X.T), dtype=bool))
        if self.comm.allreduce(nodes.size) == 0:
            raise ValueError(f"prescription {name!r}: the locator selects no node")
        return self._prescribe(nodes.astype(np.int64), velocity, name)

    def _prescribe(self, nodes, velocity, name) -> Prescription:
        v0 = velocity(0.0) if callable(velocity) else velocity
        if len(v0) != 2:
            raise ValueError("a velocity has two components (vx, vy)")
        # a None component is free (for a function of time: None at t = 0)
        comps = [c for c in range(2) if v0[c] is not None]
        comps = np.asarray(comps, dtype=np.int64)
        dofs = (2 * nodes[:, None] + comps[None, :]).ravel()
        p = Prescription(name, dofs, np.tile(comps, nodes.size), velocity)
        self.prescriptions.append(p)
        return p

    def prescribed_arrays(self, t: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        """The int8 mask of prescribed dofs and their velocities [m/s] at time t."""
        mask = np.zeros(self.f_int.size, dtype=np.int8)
        vp = np.zeros(self.f_int.size)
        for p in self.prescriptions:
            mask[p.dofs] = 1
            vp[p.dofs] = p.value(t)
        return mask, vp

    # ------------------------------------------------------------------ monitors
    def monitor(self, name: str, point: Sequence[float], blocks=None) -> None:
        """Record the displacement [m] of the node nearest ``point`` in the history."""
        node = self.nearest_node(point, blocks)
        owner = self.comm.allreduce(self.comm.rank if node >= 0 else -1, op=MPI.MAX)
        self.monitors[name] = (owner, node)

    def monitor_values(self) -> dict[str, np.ndarray]:
        """Monitored displacements (ux, uy) [m], the same on every rank."""
        out = {}
        for name, (owner, node) in self.monitors.items():
            val = None
            if self.comm.rank == owner:
                val = self.u.x.array[2 * node : 2 * node + 2].copy()
            out[name] = self.comm.bcast(val, root=owner)
        return out

    def nearest_node(self, point, blocks=None) -> int:
        """Local index of the globally nearest node, or -1 if it lives on another rank."""
        p = np.asarray(point, dtype=float)
        cand = np.arange(self.n_nodes) if blocks is None else self._block_nodes(blocks)
        if cand.size:
            d = np.linalg.norm(self.X[cand] - p, axis=1)
            k = int(np.argmin(d))
            best = (float(d[k]), int(self.node_input[cand[k]]))
        else:
            best = (np.inf, -1)
        glob = self.comm.allreduce(best, op=MPI.MIN)
        if glob[1] < 0:
            raise ValueError(f"no node found near {tuple(p)}")
        hit = np.flatnonzero(self.node_input == glob[1])
        return int(hit[0]) if hit.size else -1

    # ------------------------------------------------------------------ physics
    def internal_force(self, out: np.ndarray | None = None) -> np.ndarray:
        """Assemble f_int(u) [N] into ``out`` (preallocated; local dofs, no ghosts)."""
        if out is None:
            out = self.f_int
        self.qstate.update()
        for key, arr, idx, pos in self._gather:
            K.gather_to(arr, idx, pos, self._packed_flat[key])
        out.fill(0.0)
        _cpp.fem.assemble_vector(out, self.f_int_form._cpp_object, self._constants, self._coeffs)
        return out

    def tangent_form(self):
        """The compiled consistent tangent ∂f_int/∂u (a bilinear dolfinx form).

        A law written in UFL is differentiated by UFL (``ufl.derivative`` of its term of
        the internal force: the algorithmic tangent of its history update included, as
        UFL sees the trial history as a function of u). A return-mapping law enters as
        ``∇δu S + F δS`` with ``δS = 𝔻 : ∇δu``, 𝔻 its algorithmic tangent at the quadrature
        points (:meth:`QuadratureState.tangent`). Compiled once, on first use.
        """
        if self._tangent is None:
            du = ufl.TrialFunction(self.V)
            w = ufl.TestFunction(self.V)
            a = 0
            for mid, mat, P in self._terms:
                term = ufl.inner(P, ufl.grad(w)) * self.w_const * self._dxq(mid)
                if isinstance(mat, ReturnMapping):
                    k = self.law_context[mid]
                    gd = ufl.grad(du)
                    dS = self.qstate.stress_variation(gd)
                    a += ufl.inner(gd * k.stress + k.F * dS, ufl.grad(w)) * self.w_const \
                        * self._dxq(mid)
                else:
                    a += ufl.derivative(term, self.u, du)
            self._tangent_form = dolfinx.fem.form(a)
            self._tangent = dolfinx.fem.create_matrix(
                self._tangent_form, block_mode=dolfinx.la.BlockMode.expanded)
            A = self._tangent
            nrows = A.index_map(0).size_local * A.block_size[0]
            self._tangent_rows = np.repeat(
                np.arange(nrows, dtype=np.int64), np.diff(A.indptr[: nrows + 1]))
            if A.index_map(1).num_ghosts:
                raise RuntimeError("a block is split between ranks (ghost columns)")
        return self._tangent_form

    def tangent(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The consistent tangent ∂f_int/∂u [N/m] at the current u, as local COO triplets
        (rows, columns, values) in local dof numbers (the blocks of a rank couple only
        its own dofs). Call :meth:`internal_force` at the same u first (it updates the
        return-mapping state)."""
        form = self.tangent_form()
        A = self._tangent
        if self.qstate.has_return_mapping:
            self.qstate.tangent()
        A.data[:] = 0.0
        dolfinx.fem.assemble_matrix(A, form)
        n = self._tangent_rows.size
        return self._tangent_rows, A.indices[:n].astype(np.int64), A.data[:n]

    def commit_state(self) -> None:
        """Accept the material state (history, plastic strain) at the current displacement.

        The solvers call it: the explicit solver every step, dynamic relaxation when a
        load increment has converged. Between commits, every internal-force evaluation
        recomputes the trial state from the committed one. The energy a history law
        dissipates in the commit (``Material.dissipation_increment``: damage) is added
        to :meth:`damage_dissipation` (assembled only when a history variable changes).
        """
        if self.dissipation_form is None:
            self.qstate.commit()
            return
        self.qstate.commit(self._add_dissipation)
        self.u_committed.x.array[:] = self.u.x.array

    def _add_dissipation(self) -> None:
        self._damage_dissipated += dolfinx.fem.assemble_scalar(self.dissipation_form)

    @property
    def rate_time_step(self) -> float:
        """Time increment [s] seen by rate-dependent (Perzyna) laws; inf: rate independent."""
        return self.qstate.t_rate

    @rate_time_step.setter
    def rate_time_step(self, dt: float) -> None:
        if not dt > 0:
            raise ValueError(f"time increment must be > 0 s, got {dt}")
        self.qstate.t_rate = float(dt)

    def history(self, name: str) -> np.ndarray:
        """Committed history variable ``name`` per local cell (NaN where a material does
        not have it), e.g. "kappa" of :class:`~masonry_fdem.materials.RankineDamage`."""
        out = np.full(self.qstate.n_cells, np.nan)
        found = False
        for mid, k in self.law_context.items():
            if name in k.state:
                found = True
                cells = self.qstate.cells(mid)
                vals = k.state[name].x.array[self.qstate.qdofs[cells]]
                out[cells] = vals.mean(axis=1)
        if not found:
            raise ValueError(f"no material of this model has a history variable {name!r}")
        return out

    def plastic_state(self) -> np.ndarray:
        """Committed return-mapping state per local cell, columns as in
        :mod:`masonry_fdem.materials._finite_plastic` (Cᵖ⁻¹ − I, α the accumulated
        equivalent plastic strain, the elastic ε_zz, plastic work density [J/m³]); rows of
        other materials are zero."""
        qs = self.qstate
        if not qs.has_return_mapping:
            raise ValueError("no material of this model has a return mapping")
        return qs.s0[qs.qdofs].mean(axis=1)

    def material_fields(self) -> dict[str, np.ndarray]:
        """Committed material state per local cell for output: each history variable
        (e.g. "kappa"), what the laws derive from it (e.g. "damage"), and for
        return-mapping laws "plastic_strain" (α) and "plastic_work_density" [J/m³].
        Cells of materials without a field hold 0."""
        out: dict[str, np.ndarray] = {}
        names = sorted({n for k in self.law_context.values() for n in k.state})
        h = np.sqrt(2.0 * np.abs(self.blocks.cell_area[self.dmesh.cell_input]))
        for n in names:
            out[n] = np.nan_to_num(self.history(n))
        for mid, name in enumerate(self.blocks.material_names):
            mat = self.materials[name]
            k = self.law_context[mid]
            if k.state:
                cells = self.qstate.cells(mid)
                hist = {n: out[n][cells] for n in k.state}
                for fname, vals in mat.output_fields(hist, h[cells]).items():
                    out.setdefault(fname, np.zeros(self.qstate.n_cells))[cells] = vals
        if self.qstate.has_return_mapping:
            st = self.plastic_state()
            out["plastic_strain"] = st[:, 4].copy()
            out["plastic_work_density"] = st[:, 6].copy()
        return out

    def plastic_work(self) -> float:
        """Plastic work ∫ σ:dεᵖ w dX [J] dissipated so far (collective)."""
        qs = self.qstate
        if not qs.has_return_mapping:
            return 0.0
        area = np.abs(self.blocks.cell_area[self.dmesh.cell_input])
        wp = qs.s0[qs.qdofs, PLASTIC_WORK].mean(axis=1)
        return self.comm.allreduce(float(np.dot(wp, area)) * self.width)

    def damage_dissipation(self) -> float:
        """Energy [J] the history laws have dissipated so far (damage: ∫ W̄ Δd w dX
        summed over the commits; collective)."""
        return self.comm.allreduce(self._damage_dissipated)

    def element_dissipation(self) -> float:
        """Energy [J] the blocks' materials have dissipated so far: plastic work and
        damage (collective)."""
        return self.plastic_work() + self.damage_dissipation()

    def strain_energy(self) -> float:
        """Exact stored strain energy ∫ W(E) w dX [J] (collective)."""
        local = dolfinx.fem.assemble_scalar(self.energy_form)
        return self.comm.allreduce(local)

    def kinetic_energy(self, v: np.ndarray | None = None) -> float:
        """½ Σ m v² [J] (collective)."""
        v = self.v if v is None else v
        return self.comm.allreduce(0.5 * float(np.dot(self.mass, v * v)))

    def total_mass(self) -> float:
        """Total mass [kg] (collective): Σ of the lumped mass of the x-dofs."""
        return self.comm.allreduce(float(self.mass[0::2].sum()))

    def update_stress(self) -> dolfinx.fem.Function:
        """Evaluate the Cauchy stress [Pa] per cell into ``self.stress``."""
        arr = self.stress.x.array.reshape(-1, 4)
        for cells, expr in self._stress_expr:
            if cells.size:
                arr[cells] = expr.eval(self.mesh, cells).reshape(cells.size, 4)
        return self.stress

    def element_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Per-cell largest ω² [1/s²] and per-dof Σ_j|K_ij| [N/m] of the linear stiffness."""
        nc = self.cell_nodes.shape[0]
        lam = np.empty(nc)
        mu = np.empty(nc)
        rho = np.empty(nc)
        for mid in self.lam:
            cells = self.dmesh.cell_material == mid
            lam[cells] = self.lam[mid].value
            mu[cells] = self.mu[mid].value
            rho[cells] = self.rho[mid].value
        omega2 = np.zeros(nc)
        rowsum = np.zeros(self.f_int.size)
        K.p1_element_bounds(
            np.ascontiguousarray(self.X), self.cell_nodes, lam, mu, rho, self.width, omega2,
            rowsum,
        )
        return omega2, rowsum

    def stable_omega2(self) -> float:
        """Bound of ω_max² [1/s²] of the elements (largest element eigenvalue of the
        linear stiffness with lumped mass; collective). Elements whose nodes are all
        fully prescribed (a fixed base, a platen) do not count: their motion is given,
        not integrated."""
        omega2, _ = self.element_bounds()
        mask, _ = self.prescribed_arrays(0.0)
        node_fixed = (mask[0::2] == 1) & (mask[1::2] == 1)
        omega2[np.all(node_fixed[self.cell_nodes], axis=1)] = 0.0
        return self.comm.allreduce(float(omega2.max()) if omega2.size else 0.0, op=MPI.MAX)

    def stable_time_step(self, extra_omega2: float = 0.0) -> float:
        """Critical explicit time step 2/ω_max [s] of the undamped blocks (collective).

        ``extra_omega2`` [1/s²] bounds what other springs (contact penalties) add: the
        largest eigenvalue of a sum is at most the sum of the largest eigenvalues.
        Elements whose nodes are all fully prescribed (a fixed base, a platen) do not
        limit the step: their motion is given, not integrated.
        """
        total = self.stable_omega2() + extra_omega2
        return 2.0 / np.sqrt(total) if total > 0 else np.inf

    # ------------------------------------------------------------------ results
    def gather_nodal(self, values: np.ndarray) -> np.ndarray:
        """A nodal vector (2 per node) in the BlockMesh node order, on every rank."""
        vals = values.reshape(-1, 2)[: self.n_nodes]
        parts = self.comm.allgather((self.node_input, vals))
        out = np.zeros((self.blocks.x.shape[0], 2))
        for idx, v in parts:
            out[idx] = v
        return out

    def displacement(self) -> np.ndarray:
        """Displacement (n_nodes, 2) [m] in BlockMesh node order, on every rank."""
        return self.gather_nodal(self.u.x.array)

    def block_ranks(self) -> np.ndarray:
        """Rank holding each block."""
        return self.dmesh.block_rank

    def reset(self) -> None:
        """Zero displacement and velocity; material state back to virgin."""
        self.u.x.array[:] = 0.0
        self.v[:] = 0.0
        self.qstate.reset()
        self._damage_dissipated = 0.0
        self.u_committed.x.array[:] = 0.0

    def __repr__(self) -> str:
        return (
            f"Model({self.blocks.n_blocks} blocks, {self.blocks.n_cells} cells, "
            f"{self.hypothesis.value}, width={self.width} m, ranks={self.comm.size})"
        )

