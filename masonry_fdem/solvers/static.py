"""Static equilibrium by Newton's method on PETSc SNES, with consistent tangents.

The residual of the whole problem,

    r(u, λ) = f_int(u) − f_interactions(u) − f_dead − λ f_live,

and its consistent tangent ``K = ∂r/∂u`` are assembled into PETSc objects with one dof
numbering across ranks (the block nodes of each rank, then the dof sets the interactions
own, such as anchor bar nodes, numbered after rank 0's block dofs): the blocks by dolfinx
(the UFL derivative of the internal force, with the algorithmic tangent of return-mapped
laws, :meth:`~masonry_fdem.model.Model.tangent`), every interaction through
``add_tangent`` (:class:`~masonry_fdem.interactions.protocol.Tangent`). The matrix is an
AIJ matrix preallocated from the entries' coordinates (PETSc's COO assembly: an entry a
rank adds for a row another rank owns is sent there), re-preallocated whenever the set
of entries changes (new contact candidates, a joint handed over to contact).

Each load increment is solved by SNES (Newton with a line search; LU by MUMPS, in
parallel too). The options are PETSc's, under a prefix (``static_`` by default), so a
user may change the line search or the linear solver from the command line, e.g.
``-static_snes_linesearch_type bt -static_pc_factor_mat_solver_type superlu_dist
-static_snes_monitor``. Convergence: the residual norm over the free dofs below
``rtol`` times the norm of the applied forces (dead, live and support reactions).

Prescribed dofs (supports, a loading platen, a pulled anchor end) hold their values: their
residual rows are zero and their rows and columns of K are those of the identity.
History — plastic strain, damage, joint softening, friction, anchor bond and steel — is
committed only when an increment has converged: every force evaluation starts from the
committed history and the current displacement (backward Euler), so a failed increment is
undone by going back to the committed displacement, and cut back.

Units: SI (N, m).
"""

from __future__ import annotations

import dataclasses
import logging
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

from mpi4py import MPI

import numpy as np

import masonry_fdem._compat  # noqa: F401  (dolfinx_solver before petsc4py)
from petsc4py import PETSc

from masonry_fdem.interactions.protocol import BLOCKS, Interaction, State, Tangent
from masonry_fdem.solvers._setup import as_interactions, owned_dofsets, prescribe_displacements
from masonry_fdem.solvers.restart import (
    interactions_state,
    model_state,
    set_solver_sets_state,
)
from masonry_fdem.solvers.status import RunStatus, Status

__all__ = ["StaticSolver", "NewtonResult", "PathPoint", "StaticRun"]

log = logging.getLogger(__name__)

#: PETSc options set under the solver's prefix unless the user set them
DEFAULT_OPTIONS = {
    "snes_type": "newtonls",
    "snes_linesearch_type": "cp",
    "ksp_type": "preonly",
    "pc_type": "lu",
    "pc_factor_mat_solver_type": "mumps",
}


@dataclass(frozen=True)
class NewtonResult:
    """Outcome of one load increment.

    Attributes:
        load_factor: factor on the live loads.
        converged: equilibrium found (SNES converged).
        iterations: Newton iterations.
        residual: final residual norm over the free dofs [N].
        reference: the force norm it is compared to [N].
        reason: SNES's converged/diverged reason (name).
        history: the residual norm [N] at each iteration (the first: before any step).
    """

    load_factor: float
    converged: bool
    iterations: int
    residual: float
    reference: float
    reason: str
    history: tuple[float, ...] = ()

    @property
    def relative_residual(self) -> float:
        return self.residual / self.reference if self.reference > 0 else self.residual


@dataclass
class StaticRun:
    """Outcome of :meth:`StaticSolver.load_to_collapse` or :meth:`StaticSolver.follow`.

    Attributes:
        status: the run's :class:`~masonry_fdem.solvers.status.RunStatus`.
        load_factors: the converged load factors, in order (the start first).
        loads, displacements: (:meth:`~StaticSolver.follow`) the load (λ, or a
            platen's reaction [N]) and the displacement measure [m] of each converged
            step, from the start.
        iterations: Newton iterations of each converged increment.
        results: every increment tried (converged or not).
    """

    status: RunStatus
    load_factors: list[float] = field(default_factory=list)
    iterations: list[int] = field(default_factory=list)
    results: list[NewtonResult] = field(default_factory=list)
    loads: list[float] = field(default_factory=list)
    displacements: list[float] = field(default_factory=list)

    @property
    def collapse_load_factor(self) -> float | None:
        """The collapse load factor if the run proved one (else None)."""
        return self.status.collapse_load


@dataclass(frozen=True)
class PathPoint:
    """A converged step of :meth:`StaticSolver.follow`: the load (λ or a reaction [N]),
    the displacement measure [m], the live-load factor and the Newton iterations."""

    load: float
    displacement: float
    load_factor: float
    iterations: int


class _Set:
    """The static solver's view of one dof set: unknowns, committed values, forces."""

    def __init__(self, name, u, f, f_ext, presc, prescriptions, start, size):
        self.name, self.u, self.f, self.f_ext = name, u, f, f_ext
        self.presc = presc
        self.prescriptions = prescriptions
        self.sl = slice(start, start + size)  # its block of the local PETSc vector
        self.uc = u.copy()  # committed
        self.v = np.zeros_like(u)  # u − uc


class StaticSolver:
    """Newton's method on PETSc SNES for the equilibrium of a model (see module doc).

    Args:
        model: the :class:`~masonry_fdem.model.Model` (its ``u`` is the unknown).
        interactions: the interactions (contact, joints, anchors, a user's); each must
            implement ``add_tangent``. Disks are not supported (granular fill: use
            :class:`~masonry_fdem.solvers.DynamicRelaxation`).
        rtol: residual tolerance relative to the applied force norm (the force
            evaluation has a round-off floor of ~k·1e-16 m per node, k its penalty
            stiffness: ~1e-7 of the load for a stiff dry arch under self-weight).
        max_it: Newton iterations per increment.
        relaxed_rtol: off by default (None). If given (> ``rtol``), an arc-length
            increment whose Newton iterations stall above ``rtol`` without converging (a
            point of a joint's law at its kink flipping branch from one iterate to the
            next; on a mortar joint cracking this floor is 2-5e-6 of the force norm) is
            accepted at its best iterate if that is within ``relaxed_rtol`` and meets
            the path constraint; :meth:`follow` counts such increments in its status.
            It changes the path: see docs/design.md ("Relaxed acceptance") for a run it
            lets pass its peak and one it makes stall.
        options_prefix: the PETSc options prefix of the SNES (and its KSP/PC).
        options: PETSc options to set under the prefix (override the defaults; the
            command line overrides both).

    Raises:
        ValueError: an interaction's dof set is distributed over ranks (disks).
    """

    def __init__(
        self,
        model,
        *,
        interactions: Interaction | Sequence[Interaction] | None = None,
        rtol: float = 1e-6,
        max_it: int = 25,
        relaxed_rtol: float | None = None,
        options_prefix: str = "static_",
        options: Mapping[str, object] | None = None,
    ):
        if not rtol > 0:
            raise ValueError(f"rtol must be > 0, got {rtol}")
        if max_it < 1:
            raise ValueError(f"max_it must be >= 1, got {max_it}")
        self.model = model
        self.comm = comm = model.comm
        self.rtol = float(rtol)
        self.max_it = int(max_it)
        self.interactions = as_interactions(interactions)
        owned = owned_dofsets(self.interactions)
        for name, ds in owned.items():
            if not ds.replicated:
                raise ValueError(
                    f"dof set {name!r} is distributed over ranks (disks): the static "
                    "Newton solver does not take it; use DynamicRelaxation")
        # ---- numbering: this rank's block dofs, then (rank 0) the replicated sets
        nb = model.f_int.size
        n_sets = sum(ds.u.size for ds in owned.values())
        nloc = nb + (n_sets if comm.rank == 0 else 0)
        start = comm.exscan(nloc) or 0
        self.n_local, self.start = nloc, start
        self.n_global = comm.allreduce(nloc)
        nb0 = comm.bcast(nb if comm.rank == 0 else None, root=0)
        index = {BLOCKS: start + np.arange(nb, dtype=np.int64)}
        self.f_ext = np.zeros(nb)
        self.f_b = np.zeros(nb)  # interaction forces on the blocks
        self.presc, _ = model.prescribed_arrays(0.0)
        self.sets = [_Set(BLOCKS, model.u.x.array[:nb], self.f_b, self.f_ext, self.presc,
                          {}, 0, nb)]
        off = nb0
        for name, ds in owned.items():
            index[name] = off + np.arange(ds.u.size, dtype=np.int64)
            self.sets.append(_Set(name, ds.u, ds.f, ds.f_ext, ds.presc, ds.prescriptions,
                                  nb + (off - nb0), ds.u.size))
            off += ds.u.size
        parts = comm.allgather((model.node_input, index[BLOCKS][0::2]))
        node_dof = np.full(model.blocks.n_nodes, -1, dtype=np.int64)
        for ids, dofs in parts:
            node_dof[ids] = dofs
        self.tangent_collector = Tangent(index, node_dof, comm.rank)
        self.index = index
        # global numbers of this rank's prescribed dofs (rows and columns of the identity)
        pg = [index[BLOCKS][self.presc != 0]]
        if comm.rank == 0:
            pg += [index[s.name][s.presc != 0] for s in self.sets[1:]]
        self._presc_global = np.concatenate(pg).astype(PETSc.IntType)
        self._state = State({s.name: s.u for s in self.sets}, {s.name: s.v for s in self.sets},
                            {s.name: s.f for s in self.sets}, 1.0, False, static=True)
        # ---- PETSc objects
        self.x = PETSc.Vec().createMPI((nloc, self.n_global), comm=comm)
        self.F = self.x.duplicate()
        self.J = PETSc.Mat().create(comm=comm)
        self.J.setSizes(((nloc, self.n_global), (nloc, self.n_global)))
        self.J.setType(PETSc.Mat.Type.AIJ)
        self._pattern: tuple[np.ndarray, np.ndarray] | None = None
        self.pattern_builds = 0
        opts = PETSc.Options()
        self._prefix = options_prefix
        chosen = {**DEFAULT_OPTIONS, **(options or {})}
        for key, value in chosen.items():
            if options and key in options or not opts.hasName(options_prefix + key):
                opts[options_prefix + key] = value
        self.snes: PETSc.SNES | None = None
        self._make_snes()
        self._x_at_forces = np.full(nloc, np.nan)
        self._load_factor = 0.0
        #: the load factor of the committed state
        self.load_factor = 0.0
        #: the factor on the dead loads (1 once :meth:`settle` has applied them)
        self.dead_factor = 1.0
        self._ref = 1.0
        self._moved = False
        self._work: tuple[PETSc.Vec, PETSc.Vec] | None = None  # rhs, solution of K x = b
        self._dvec: PETSc.Vec | None = None  # a diagonal added to the tangent
        self._history: list[float] = []
        self.results: list[NewtonResult] = []
        self.u_committed = self.sets[0].uc
        #: the tolerance (relative, as ``rtol``) at which an arc-length increment whose
        #: Newton iterations stall above ``rtol`` is still accepted (its best iterate;
        #: 0, or any value not above ``rtol``: off)
        self.relaxed_rtol = float(relaxed_rtol) if relaxed_rtol is not None else 0.0
        #: arc-length increments accepted at ``relaxed_rtol``
        self.relaxed = 0

    # ------------------------------------------------------------------ state <-> vector
    def _gather(self, out: np.ndarray) -> None:
        """The dofs of every set into a local PETSc array."""
        for s in self.sets:
            if s.name == BLOCKS or self.comm.rank == 0:
                out[s.sl] = s.u

    def _scatter(self, xa: np.ndarray) -> None:
        """A local PETSc array into the dofs of every set (the replicated sets from
        rank 0 to all)."""
        nb = self.sets[0].u.size
        self.sets[0].u[:] = xa[:nb]
        if len(self.sets) > 1:
            if self.comm.rank == 0:
                buf = np.ascontiguousarray(xa[nb:])
            else:
                buf = np.empty(sum(s.u.size for s in self.sets[1:]))
            if self.comm.size > 1:
                self.comm.Bcast(buf, root=0)
            for s in self.sets[1:]:
                s.u[:] = buf[s.sl.start - nb:s.sl.stop - nb]

    # ------------------------------------------------------------------ residual
    def _forces(self) -> None:
        """Internal and interaction forces at the current dofs (collective)."""
        m = self.model
        for s in self.sets:
            np.subtract(s.u, s.uc, out=s.v)
        m.internal_force(m.f_int)
        self.f_b.fill(0.0)
        for s in self.sets[1:]:
            s.f.fill(0.0)
        for c in self.interactions:
            c.update(self._state)
            c.add_forces(self._state)

    def _residual_into(self, out: np.ndarray) -> None:
        """r over every set into the local array ``out`` (zero at prescribed dofs)."""
        m = self.model
        b = self.sets[0]
        r = out[b.sl]
        np.subtract(m.f_int, self.f_b, out=r)
        r -= self.f_ext
        r[b.presc != 0] = 0.0
        if self.comm.rank == 0:
            for s in self.sets[1:]:
                rs = out[s.sl]
                np.negative(s.f, out=rs)
                rs -= s.f_ext
                rs[s.presc != 0] = 0.0

    def _residual_cb(self, snes, x, F) -> None:
        xa = x.getArray(readonly=True)
        self._scatter(xa)
        self._forces()
        self._x_at_forces[:] = xa
        self._residual_into(F.array)

    # ------------------------------------------------------------------ tangent
    def _jacobian_cb(self, snes, x, J, P) -> None:
        xa = x.getArray(readonly=True)
        if not np.array_equal(xa, self._x_at_forces):
            self._scatter(xa)
            self._forces()
            self._x_at_forces[:] = xa
        self.assemble_tangent()

    def assemble_tangent(self) -> PETSc.Mat:
        """K = ∂r/∂u at the state of the last force evaluation into ``self.J``."""
        T = self.tangent_collector
        T.clear()
        rows, cols, vals = self.model.tangent()
        ib = self.index[BLOCKS]
        T.add(ib[rows], ib[cols], vals)
        for c in self.interactions:
            try:
                c.add_tangent(T, self._state)
            except NotImplementedError as err:
                raise NotImplementedError(
                    f"{type(c).__name__} has no consistent tangent, so the static Newton "
                    "solver cannot take it; use DynamicRelaxation") from err
        # the diagonal of every local dof, so the pattern holds the prescribed rows' 1s
        own = np.arange(self.start, self.start + self.n_local, dtype=np.int64)
        T.add(own, own, np.zeros(own.size))
        r, c, v = T.coo()
        r = r.astype(PETSc.IntType, copy=False)
        c = c.astype(PETSc.IntType, copy=False)
        changed = (self._pattern is None or self._pattern[0].size != r.size
                   or not np.array_equal(self._pattern[0], r)
                   or not np.array_equal(self._pattern[1], c))
        if self.comm.allreduce(changed, op=MPI.LOR):  # collective: every rank or none
            # release the factorization of the old pattern before the matrix is rebuilt
            # (MUMPS in parallel otherwise writes through stale structures)
            self.snes.getKSP().getPC().reset()
            self.J.setPreallocationCOO(r, c)
            self.J.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, True)
            self._pattern = (r.copy(), c.copy())
            self.pattern_builds += 1
        self.J.setValuesCOO(v, addv=PETSc.InsertMode.INSERT_VALUES)
        self.J.assemble()
        if self.comm.allreduce(self._presc_global.size):
            self.J.zeroRowsColumns(self._presc_global, diag=1.0)
        return self.J

    # ------------------------------------------------------------------ convergence
    def _converged_cb(self, snes, it, norms):
        _, _, fnorm = norms
        if it == 0:
            self._history = []
        self._history.append(float(fnorm))
        if not math.isfinite(fnorm):
            return PETSc.SNES.ConvergedReason.DIVERGED_FUNCTION_NANORINF
        # the reference at the current iterate: moved prescribed dofs make the first
        # iterate's reactions (and so a reference taken there) spuriously large, so such
        # an increment is never accepted before one Newton step
        self._ref = self._reference()
        if fnorm <= self.rtol * self._ref and not (it == 0 and self._moved):
            return PETSc.SNES.ConvergedReason.CONVERGED_FNORM_ABS
        if it >= self.max_it:
            return PETSc.SNES.ConvergedReason.DIVERGED_MAX_IT
        return PETSc.SNES.ConvergedReason.ITERATING

    def _reference(self) -> float:
        """The force norm of the tolerance: applied forces on the free dofs and the
        reactions at the prescribed ones (collective; at the current state)."""
        m = self.model
        b = self.sets[0]
        free = b.presc == 0
        reac = m.f_int - self.f_b - self.f_ext
        loc = float(np.dot(self.f_ext[free], self.f_ext[free]))
        loc += float(np.dot(reac[~free], reac[~free]))
        tot = self.comm.allreduce(loc)
        for s in self.sets[1:]:
            fe = s.f_ext[s.presc == 0]
            tot += float(np.dot(fe, fe))
        return math.sqrt(tot) or 1.0

    # ------------------------------------------------------------------ solve
    def solve(
        self,
        load_factor: float = 1.0,
        displacement: Mapping[str, Sequence[float | None]] | None = None,
        max_it: int | None = None,
        line_search: str | None = None,
    ) -> NewtonResult:
        """Equilibrium under ``f_dead + load_factor · f_live`` (and the prescribed
        displacements), from the committed state; committed if it converges, else the
        committed state is restored.

        Args:
            load_factor: factor on the live loads.
            displacement: ``{prescription name: (ux, uy)}`` [m]: total displacements of
                the prescribed dofs of that prescription (``None``: leave as it is).
            max_it: Newton iterations for this solve only (default the solver's
                ``max_it``), e.g. from a state dynamic relaxation left near equilibrium.
            line_search: PETSc's line search for this solve only (default the
                options'), e.g. ``"bt"`` where the critical-point one cycles.
        """
        if line_search is not None:
            self.snes.getLineSearch().setType(line_search)
            try:
                return self.solve(load_factor, displacement, max_it)
            finally:
                self._make_snes()  # back to the options' line search
        if max_it is not None:
            if max_it < 1:
                raise ValueError(f"max_it must be >= 1, got {max_it}")
            keep = self.max_it
            self.max_it = int(max_it)
            self.snes.setTolerances(max_it=self.max_it)
            try:
                return self.solve(load_factor, displacement)
            finally:
                self.max_it = keep
                self.snes.setTolerances(max_it=keep)
        self._moved = bool(displacement)
        if displacement:
            self.prescribe(displacement)
        self._load_factor = float(load_factor)
        self._set_load(load_factor)
        self._gather(self.x.array)
        self._forces()
        self._ref = self._reference()
        self._history = []
        self.snes.solve(None, self.x)
        reason = self.snes.getConvergedReason()
        its = self.snes.getIterationNumber()
        converged = reason > 0
        xa = self.x.getArray(readonly=True)
        if not np.array_equal(xa, self._x_at_forces):
            self._scatter(xa)
            self._forces()
            self._x_at_forces[:] = xa
        fl = np.zeros(self.n_local)
        self._residual_into(fl)
        with np.errstate(over="ignore", invalid="ignore"):  # a diverged iterate: inf,
            rn = math.sqrt(self.comm.allreduce(float(np.dot(fl, fl))))  # rejected below
        self._ref = self._reference()
        if converged and not (rn <= self.rtol * self._ref and (its > 0 or not self._moved)):
            # SNES said converged but the state is not in equilibrium (seen at the
            # first solve after a failed linear solve): not accepted
            converged = False
            reason = int(PETSc.SNES.ConvergedReason.DIVERGED_FUNCTION_NANORINF)
        if converged:
            self.commit()
            self.load_factor = float(load_factor)
        else:
            # a failed solve may leave the preconditioner failed (a zero pivot): set it
            # up afresh next time
            self._make_snes()
            self.restore()
        res = NewtonResult(float(load_factor), converged, int(its), rn, self._ref,
                           _reason_name(reason), tuple(self._history))
        self.results.append(res)
        if self.comm.rank == 0:
            log.info("Newton: load factor %.6g %s in %d iterations (|r|/|f| = %.2e, %s)",
                     load_factor, "converged" if converged else "NOT converged", its,
                     res.relative_residual, res.reason)
        return res

    def solve_retrying(self, load_factor: float = 1.0) -> NewtonResult:
        """:meth:`solve`, and where it fails with the options' line search (if not
        ``bt`` already) once more with the backtracking one, as :meth:`settle` does."""
        res = self.solve(load_factor)
        if res.converged or self.snes.getLineSearch().getType() == "bt":
            return res
        return self.solve(load_factor, line_search="bt")

    def _make_snes(self) -> None:
        """A new SNES (and its KSP and line search) on the solver's options. Made again
        after a failed solve: the critical-point line search keeps the norms of the last
        step it took, and after a diverged solve (steps of 1e20) its test
        ``dot(F, Y) < atol·‖y‖`` with that stale ‖y‖ rejected the first step of every
        later solve (seen on the shear wall under displacement control); a failed
        factorization (a zero pivot) is dropped with it."""
        if self.snes is not None:
            self.snes.destroy()
        self.snes = snes = PETSc.SNES().create(comm=self.comm)
        snes.setOptionsPrefix(self._prefix)
        snes.setFunction(self._residual_cb, self.F)
        snes.setJacobian(self._jacobian_cb, self.J)
        snes.setConvergenceTest(self._converged_cb)
        snes.setTolerances(max_it=self.max_it)
        snes.setFromOptions()
        snes.getKSP().setFromOptions()

    def commit(self) -> None:
        """Accept the current state: displacements, the blocks' material state and every
        interaction's history."""
        for s in self.sets:
            s.uc[:] = s.u
        self.model.commit_state()
        for c in self.interactions:
            c.commit()

    def _extrapolation(self, ratio: float) -> None:
        """Tell the interactions that integrate a softening implicit–explicit (the
        joints' ``set_softening("imex")``) the next increment's size over the last
        committed one's (their extrapolation factor; 1 outside path following)."""
        for c in self.interactions:
            f = getattr(c, "set_extrapolation", None)
            if f is not None:
                f(ratio)

    def restore(self) -> None:
        """Back to the committed state (the displacements of every set; the interactions'
        trial states), forces evaluated there (collective)."""
        for s in self.sets:
            s.u[:] = s.uc
        for c in self.interactions:
            c.restore()
        self._forces()
        self._gather(self._x_at_forces)

    def prescribe(self, displacement: Mapping[str, Sequence[float | None]]) -> None:
        """Set prescribed dofs to total displacements [m] (see :meth:`solve`)."""
        prescribe_displacements(self.model, self.sets[1:], displacement)

    def reactions(self) -> dict[str, np.ndarray]:
        """Reaction (Rx, Ry) [N] of each prescription at the current state: the force
        the support applies, f_int − f_interactions − f_ext at its dofs (collective)."""
        m = self.model
        self._forces()
        r_b = m.f_int - self.f_b - self.f_ext
        out = {}
        for p in m.prescriptions:
            r = np.zeros(2)
            np.add.at(r, p.components, r_b[p.dofs])
            out[p.name] = m.comm.allreduce(r)
        for s in self.sets[1:]:
            for name, dofs in s.prescriptions.items():
                out[name] = -s.f[dofs] - s.f_ext[dofs]
        return out

    # ------------------------------------------------------------------ checkpoints
    def checkpoint_state(self) -> dict:
        """This rank's complete state (copies) at a committed state: every dof set's
        current and committed dofs, the load factors, the tangent's sparsity pattern,
        the increments' results, the model's and the interactions' states."""
        return {
            "solver": "static",
            "sets": [{"u": s.u.copy(), "uc": s.uc.copy(), "v": s.v.copy()} for s in self.sets],
            "load_factor": self.load_factor, "_load_factor": self._load_factor,
            "dead_factor": self.dead_factor, "_ref": self._ref, "_moved": self._moved,
            "_x_at_forces": self._x_at_forces.copy(), "_history": list(self._history),
            "results": list(self.results), "f_ext": self.f_ext.copy(), "f_b": self.f_b.copy(),
            "pattern": None if self._pattern is None else tuple(a.copy() for a in self._pattern),
            "pattern_builds": self.pattern_builds,
            "model": model_state(self.model),
            "interactions": interactions_state(self.interactions),
        }

    def set_checkpoint_state(self, st: Mapping) -> None:
        """Take a state of :meth:`checkpoint_state` (collective)."""
        if st.get("solver") != "static":
            raise ValueError(f"not a static solver's state ({st.get('solver')!r})")
        set_solver_sets_state(self, st)
        self.load_factor = st["load_factor"]
        self._load_factor = st["_load_factor"]
        self.dead_factor = st["dead_factor"]
        self._ref, self._moved = st["_ref"], st["_moved"]
        self._x_at_forces[...] = st["_x_at_forces"]
        self._history = list(st["_history"])
        self.results = list(st["results"])
        self.f_ext[...] = st["f_ext"]
        self.f_b[...] = st["f_b"]
        self._make_snes()
        pat = st["pattern"]
        if pat is not None:
            r, c = pat
            self.J.setPreallocationCOO(r, c)
            self.J.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, True)
            self._pattern = (r.copy(), c.copy())
        self.pattern_builds = st["pattern_builds"]

    # ------------------------------------------------------------------ load stepping
    def settle(self, steps: int = 8, *, min_fraction: float = 1.0 / 256.0, grow: float = 1.5,
               easy_iterations: int = 5, resume: bool = False) -> RunStatus:
        """Apply the dead loads (self-weight) from zero in increments, from the
        committed state, at the current live-load factor: a structure of blocks that
        only touch at the start has no contact stiffness yet, and a full first Newton
        step overshoots (the stiffer the contact, the worse). An increment that fails is
        undone and halved, one that converges in at most ``easy_iterations`` lets the
        next grow ``grow`` times; below ``min_fraction`` the run stops.

        ``resume``: go on from the fraction committed last (:attr:`dead_factor`, say
        after a failed settle and a change that may let it pass) instead of from zero.

        An increment that fails with the configured line search (PETSc's critical-point
        ``cp`` by default) is tried again, before it is halved, with the backtracking
        line search (``bt``: a step is shortened until ‖r‖ falls), and the rest of the
        settle keeps it. Dry joints start at their kink between closed and open, at any
        fraction of the dead loads; there ``cp``'s secant steps can cycle where ``bt``'s
        do not (the bridge builder's 6 m single span without walls: ``cp`` failed at every
        fraction from 1/8 to 1/256; ``bt`` settled it in seven increments, one second).

        Returns:
            *load reached* with the dead loads in full, or *not converged* at the dead-
            load fraction that failed (``at``; the structure then holds the fraction
            committed last, :attr:`dead_factor`).
        """
        if steps < 1:
            raise ValueError(f"steps must be >= 1, got {steps}")
        done, df = (self.dead_factor if resume else 0.0), 1.0 / steps
        self.dead_factor = done
        lam = self.load_factor
        # "bt" once an increment has failed with the options' line search
        ls = None if self.snes.getLineSearch().getType() != "bt" else "bt"
        while done < 1.0 - 1e-12:
            trial = min(1.0, done + df)
            self.dead_factor = trial
            res = self.solve(lam, line_search=ls)
            if not res.converged and ls is None:
                ls = "bt"
                res = self.solve(lam, line_search=ls)
                if self.comm.rank == 0:
                    log.info("settle: the increment to %.4g of the dead loads %s with the "
                             "backtracking line search", trial,
                             "converged" if res.converged else "failed also")
            if res.converged:
                done = trial
                if res.iterations <= easy_iterations:
                    df *= grow
                continue
            self.dead_factor = done
            if df <= min_fraction * (1 + 1e-12):
                return RunStatus(Status.NOT_CONVERGED, lam, lam, trial,
                                 f"dead loads: Newton did not converge ({res.reason}) at "
                                 f"{trial:.4g} of them")
            df = max(0.5 * df, min_fraction)
        self.dead_factor = 1.0
        return RunStatus(Status.LOAD_REACHED, lam, lam, None, "dead loads applied")

    def advance(
        self,
        load_factor: float | None = None,
        displacement: Mapping[str, Sequence[float | None]] | None = None,
        *,
        steps: int = 1,
        min_fraction: float = 1.0 / 256.0,
        grow: float = 1.5,
        easy_iterations: int = 5,
        callback: Callable[[NewtonResult], None] | None = None,
    ) -> tuple[RunStatus, list[NewtonResult]]:
        """Go from the committed state to a target load factor and/or prescribed
        displacements along a straight path, in ``steps`` increments at first: an
        increment that fails is undone and halved, one that converges in at most
        ``easy_iterations`` lets the next grow ``grow`` times (never past the target). A
        failure at an increment below ``min_fraction`` of the path stops the run.

        Returns:
            ``(status, results)``: *load reached* if the target was reached, else *not
            converged* at the path fraction it failed at (``at``: the load factor, or
            the fraction of the displacement path when only displacements move);
            ``load`` and ``peak`` are the committed load factor.
        """
        if steps < 1:
            raise ValueError(f"steps must be >= 1, got {steps}")
        lam0 = self.load_factor
        lam1 = lam0 if load_factor is None else float(load_factor)
        start: dict[str, tuple] = {}
        for name, val in (displacement or {}).items():
            start[name] = tuple(None if v is None else self._prescribed_value(name, c)
                                for c, v in enumerate(val))
        results: list[NewtonResult] = []
        t, dt = 0.0, 1.0 / steps
        while t < 1.0 - 1e-12:
            tn = min(1.0, t + dt)
            disp = {name: tuple(None if v is None else a + tn * (float(v) - a)
                                for v, a in zip(val, start[name], strict=True))
                    for name, val in (displacement or {}).items()}
            res = self.solve(lam0 + tn * (lam1 - lam0), displacement=disp or None)
            results.append(res)
            if callback is not None:
                callback(res)
            if res.converged:
                t = tn
                if res.iterations <= easy_iterations:
                    dt *= grow
                continue
            # (the failed solve went back to the committed state, prescribed values too)
            if dt <= min_fraction * (1 + 1e-12):
                lam = self.load_factor
                at = lam0 + tn * (lam1 - lam0) if lam1 != lam0 else tn
                return (RunStatus(Status.NOT_CONVERGED, lam, lam, at,
                                  f"Newton did not converge ({res.reason}) at {tn:.4g} of the "
                                  "path, after cut-backs"), results)
            dt = max(0.5 * dt, min_fraction)
        lam = self.load_factor
        return RunStatus(Status.LOAD_REACHED, lam, lam, None, "target reached"), results

    def _prescribed_value(self, name: str, comp: int) -> float:
        """The current value [m] of component ``comp`` of prescription ``name`` (the
        mean over its dofs; collective)."""
        for s in self.sets[1:]:
            if name in s.prescriptions:
                return float(s.u[s.prescriptions[name][comp]])
        p = next((p for p in self.model.prescriptions if p.name == name), None)
        if p is None:
            raise ValueError(f"no prescription named {name!r}")
        vals = self.model.u.x.array[p.dofs[p.components == comp]]
        tot = [sum(x) for x in zip(*self.comm.allgather((float(vals.sum()), vals.size)),
                                   strict=True)]
        return tot[0] / tot[1] if tot[1] else 0.0

    def load_to_collapse(
        self,
        increment: float,
        *,
        start: float = 0.0,
        max_load: float = math.inf,
        min_increment: float | None = None,
        grow: float = 1.5,
        easy_iterations: int = 5,
        max_increment: float | None = None,
        mechanism_ratio: float = 1e-2,
        monitor: Callable[[], float] | None = None,
        callback: Callable[[NewtonResult], None] | None = None,
    ) -> StaticRun:
        """Load control: raise the live-load factor until no equilibrium is found.

        From the equilibrium at ``start`` the factor grows by ``increment``; an increment
        that converges in at most ``easy_iterations`` makes the next one ``grow`` times
        larger (up to ``max_increment``, default 4 × ``increment``); one that fails is
        undone and halved, down to ``min_increment`` (default ``increment``/64).

        Status: *load reached* when ``max_load`` is carried. Otherwise the run stops
        without equilibrium at the smallest increment; it is a *mechanism* if the
        structure had lost its stiffness there — the current stiffness parameter
        (Bergan et al. 1978: the incremental stiffness Δλ/|Δu| of the last converged
        increment over that of the first) below ``mechanism_ratio`` — and *not
        converged* otherwise (the last load a lower bound). ``monitor()`` gives the
        displacement measure [m] of the stiffness (default: the norm of u).

        Returns:
            :class:`StaticRun`.
        """
        if not increment > 0:
            raise ValueError(f"increment must be > 0, got {increment}")
        dmin = increment / 64.0 if min_increment is None else float(min_increment)
        dmax = 4.0 * increment if max_increment is None else float(max_increment)
        if not 0 < dmin <= increment <= dmax:
            raise ValueError("need 0 < min_increment <= increment <= max_increment")

        def measure() -> float:
            if monitor is not None:
                return float(monitor())
            u = self.sets[0].u
            return math.sqrt(self.comm.allreduce(float(np.dot(u, u))))

        run = StaticRun(RunStatus(Status.NOT_CONVERGED, start, start))
        level, step = float(start), float(increment)
        d_prev = measure()
        k0 = None  # incremental stiffness of the first increment
        k_last = None
        run.load_factors.append(level)
        run.iterations.append(0)
        while level < max_load:
            trial = min(level + step, max_load)
            res = self.solve(trial)
            run.results.append(res)
            if callback is not None:
                callback(res)
            if res.converged:
                d = measure()
                dd = abs(d - d_prev)
                k = (trial - level) / dd if dd > 0 else math.inf
                if k0 is None and math.isfinite(k):
                    k0 = k
                k_last = k
                level, d_prev = trial, d
                run.load_factors.append(level)
                run.iterations.append(res.iterations)
                if res.iterations <= easy_iterations:
                    step = min(step * grow, dmax)
                continue
            if step <= dmin * (1 + 1e-12):
                sp = (k_last / k0) if (k0 and k_last is not None) else math.nan
                detail = (f"Newton did not converge at {trial:.6g} ({res.reason}); current "
                          f"stiffness parameter {sp:.3g}")
                st = Status.MECHANISM if sp < mechanism_ratio else Status.NOT_CONVERGED
                run.status = RunStatus(st, level, max(run.load_factors), trial, detail)
                return run
            step = max(0.5 * step, dmin)
        run.status = RunStatus(Status.LOAD_REACHED, level, max(run.load_factors), None,
                               f"carried {level:.6g}")
        return run

    # ------------------------------------------------------------------ path following
    def _solve_linear(self, rhs: np.ndarray, out: np.ndarray) -> bool:
        """out = K⁻¹ rhs with the assembled tangent (local arrays; collective). False if
        the linear solver failed (a zero pivot: a singular tangent)."""
        if self._work is None:
            self._work = (self.F.duplicate(), self.x.duplicate())
        b, x = self._work
        b.array[:] = rhs
        ksp = self.snes.getKSP()
        ksp.setOperators(self.J, self.J)
        try:
            ksp.solve(b, x)
        except PETSc.Error:
            return False
        ok = ksp.getConvergedReason() > 0 and np.all(np.isfinite(x.array))
        out[:] = x.array
        return bool(self.comm.allreduce(ok, op=MPI.LAND))

    def _set_load(self, lam: float) -> None:
        m = self.model
        np.multiply(m.f_live, lam, out=self.f_ext)
        if self.dead_factor == 1.0:
            self.f_ext += m.f_dead
        else:
            self.f_ext += self.dead_factor * m.f_dead
        self._load_factor = float(lam)

    def _free_norm(self, v: np.ndarray) -> float:
        return math.sqrt(self.comm.allreduce(float(np.dot(v, v))))

    def _live_vector(self) -> np.ndarray:
        """The live load on the free dofs, as a local PETSc array (zero elsewhere)."""
        q = np.zeros(self.n_local)
        b = self.sets[0]
        q[b.sl] = self.model.f_live
        q[b.sl][b.presc != 0] = 0.0
        return q

    def _arc_increment(self, ds: float, a: np.ndarray, q: np.ndarray, b: float = 0.0,
                       max_backtracks: int = 6, max_uphill: int = 6, *,
                       damping: np.ndarray | None = None, x_prev: np.ndarray | None = None,
                       lam_start: float | None = None, commit: bool = True,
                       ds_scale: float | None = None,
                       constraint: Callable[[], tuple[float, np.ndarray, float]] | None = None,
                       ctol: float = 1e-8,
                       predictor: tuple[np.ndarray, float] | None = None,
                       ) -> tuple[NewtonResult, float]:
        """One increment of a linear path constraint from the committed state: find
        (u, λ) with r(u, λ) = 0 and a·(u − u_c) + b (λ − λ_c) = ds (the bordered Newton
        method: two solves with the same tangent per iteration). Indirect displacement
        control has b = 0; dissipation control (Gutiérrez 2004) a = ½ f_ext(λ_c),
        b = −½ q·u_c. A step that no backtracking makes decrease |r| is taken at the
        smallest fraction at most ``max_uphill`` times (then the increment fails: an
        orbit between two states is not worth 25 iterations). On convergence the state
        is committed (with ``commit``; else kept as the current, uncommitted state);
        otherwise restored. Returns (result, λ).

        ``damping`` (a local array, zero at prescribed dofs) adds the viscous force
        C (x − x_prev) to the residual and C to the tangent's diagonal: one step of
        pseudo-transient continuation (:meth:`_jump`); ``lam_start`` is then the load
        factor the step starts from and ``ds_scale`` the size of the constraint's
        tolerance (ds may be 0).

        ``constraint`` replaces the linear constraint by a nonlinear one, g(u) = ds:
        called at the current state it returns (g, ∂g/∂u as a local array, ∂g/∂λ),
        and the increment converges once |g − ds| ≤ ``ctol`` · ds_scale.

        ``predictor`` (Δx as a local array, Δλ): the first iterate is the committed
        state plus this step (the secant of the previous increment, scaled to ds) instead
        of the tangent's step along the live load. Near a peak the tangent at the
        committed state may be of the wrong branch for the way the path goes on (a
        softening joint point that is on its surface at the committed state gets the
        elastic tangent there, as no step has loaded it yet), and its predictor then
        lands far from the path even for a small ds; the previous increment's secant
        keeps the points that were loading on their branch."""
        lam_c = self.load_factor if lam_start is None else float(lam_start)
        cscale = abs(ds) if ds_scale is None else float(ds_scale)
        xc = np.zeros(self.n_local)
        self._gather(xc)
        x = xc.copy()
        lam = lam_c
        r = np.zeros(self.n_local)
        dq = np.zeros(self.n_local)
        dr = np.zeros(self.n_local)

        def dot(u, v):
            return self.comm.allreduce(float(np.dot(u, v)))

        def evaluate(xa, lam_):
            self._scatter(xa)
            self._set_load(lam_)
            self._forces()
            self._x_at_forces[:] = xa
            self._residual_into(r)
            if damping is not None:
                r[:] += damping * (xa - x_prev)
            return self._free_norm(r)

        def tangent():
            self.assemble_tangent()
            if damping is not None:
                self._add_diagonal(damping)

        history: list[float] = []
        converged, its, reason = False, 0, "DIVERGED_MAX_IT"
        # predictor: the tangent at the committed state along the live load, or the
        # given one
        rn = evaluate(x, lam)
        g_now = 0.0
        if constraint is not None:
            g_now, a, b = constraint()
        ok = True
        if predictor is not None:
            x += predictor[0]
            lam += predictor[1]
        else:
            tangent()
            if not self._solve_linear(q, dq):
                reason, ok = "DIVERGED_LINEAR_SOLVE", False
            else:
                adq = dot(a, dq) + b
                if adq == 0.0 or not math.isfinite(adq):
                    reason, ok = "DIVERGED_LINEAR_SOLVE", False
                else:
                    dlam = (ds - g_now) / adq
                    x += dlam * dq
                    lam += dlam
        # the best iterate (|r|/ref, λ, x), kept only with relaxed acceptance on
        best_rn, best_lam = math.inf, lam
        x_best = np.empty_like(x) if self.relaxed_rtol > self.rtol else None
        if ok:
            rn = evaluate(x, lam)
            ref = self._reference()
            history.append(rn)
            uphill = 0
            while True:
                if constraint is not None:
                    g_now, a, b = constraint()
                    c = g_now - ds
                else:
                    c = dot(a, x - xc) + b * (lam - lam_c) - ds
                if rn <= self.rtol * ref and abs(c) <= ctol * cscale:
                    converged, reason = True, "CONVERGED_FNORM_ABS"
                    break
                if x_best is not None and abs(c) <= ctol * cscale and rn / ref < best_rn:
                    best_rn, best_lam = rn / ref, lam
                    x_best[:] = x
                if its >= self.max_it or not math.isfinite(rn):
                    reason = "DIVERGED_MAX_IT" if math.isfinite(rn) else "DIVERGED_FNORM_NAN"
                    break
                its += 1
                tangent()
                if not (self._solve_linear(-r, dr) and self._solve_linear(q, dq)):
                    reason = "DIVERGED_LINEAR_SOLVE"
                    break
                adq = dot(a, dq) + b
                if adq == 0.0 or not math.isfinite(adq):
                    reason = "DIVERGED_LINEAR_SOLVE"
                    break
                dlam = -(c + dot(a, dr)) / adq
                du = dr + dlam * dq
                # the full step if it lowers |r|; else the critical point of the
                # line (r·Δu = 0, the energy's minimum along it where the forces
                # derive from one: a law's kink crossed by the step — a joint
                # closing, a sliding point reversing — makes |r| jump while r·Δu
                # stays continuous, and backtracking on |r| alone then orbits
                # between two states); else backtracking on |r|. The constraint is
                # linear: any fraction of the step keeps a·Δu on its way to ds.
                x0, lam0, rn0 = x.copy(), lam, rn
                g0 = dot(r, du)
                x = x0 + du
                lam = lam0 + dlam
                rn = evaluate(x, lam)
                if not rn < rn0:  # (NaN too: a state no law can take)
                    found = self._critical_point(g0, dot(r, du), x0, lam0, du, dlam,
                                                 evaluate, r)
                    if found is None:
                        alpha = 0.5
                        for _ in range(max_backtracks):
                            x = x0 + alpha * du
                            lam = lam0 + alpha * dlam
                            rn = evaluate(x, lam)
                            if rn < rn0 or alpha < 0.5 ** max_backtracks:
                                break
                            alpha *= 0.5
                    else:  # the state is left at the fraction found
                        alpha, rn = found
                        x = x0 + alpha * du
                        lam = lam0 + alpha * dlam
                ref = self._reference()
                history.append(rn)
                if not rn < rn0:
                    uphill += 1
                    if uphill > max_uphill:
                        reason = "DIVERGED_LINE_SEARCH"
                        break
        if not converged and best_rn <= self.relaxed_rtol:
            # Newton orbits just above the tolerance (a point of a law at its kink
            # flipping branch from one iterate to the next): the best iterate, if within
            # the relaxed tolerance, is accepted
            rn = evaluate(x_best, best_lam)
            lam = best_lam
            ref = self._reference()
            if rn <= self.relaxed_rtol * ref:
                converged, reason = True, "CONVERGED_RELAXED"
                self.relaxed += 1
        ref = self._reference() if converged else max(self._ref, 1.0)
        if converged:
            if commit:
                self.commit()
                self.load_factor = float(lam)
        else:
            self._set_load(self.load_factor)
            self.restore()
            lam = self.load_factor
        res = NewtonResult(float(lam), converged, its, rn, ref, reason, tuple(history))
        self.results.append(res)
        if self.comm.rank == 0:
            log.info("arc length: Δs %.4g, load factor %.6g %s in %d iterations (%s)", ds,
                     lam, "converged" if converged else "NOT converged", its, reason)
        return res, lam

    def _add_diagonal(self, d: np.ndarray) -> None:
        """Add the local array ``d`` to the assembled tangent's diagonal."""
        if self._dvec is None:
            self._dvec = self.x.duplicate()
        self._dvec.array[:] = d
        self.J.setDiagonal(self._dvec, addv=PETSc.InsertMode.ADD_VALUES)
        self.J.assemble()

    def _jump(self, ds: float, a: np.ndarray, q: np.ndarray, max_steps: int = 60,
              eta0: float = 1e-2) -> tuple[NewtonResult, float, int]:
        """Equilibrium at the displacement measure's next value a·(u − u_c) = ds where
        the path turns back (a snap-back: no equilibrium near the committed state at the
        next displacement, the load must drop). Found by pseudo-transient continuation
        (Kelley & Keyes 1998, "Convergence analysis of pseudo-transient continuation",
        SIAM J. Numer. Anal. 35): a viscous force η D (u − u_prev), D the diagonal of
        the tangent at the committed state, is added and the damped equilibria are
        followed in pseudo time, η cut as the residual falls (switched evolution
        relaxation) and raised on a failed step, until the undamped residual meets the
        tolerance. The displacement measure stays at ds throughout (the λ of each step
        is free): the state jumped to is the one a jack holding the load-line
        displacement would find, the load dropping at constant displacement. Every
        pseudo step returns from the committed history, so the result is one
        backward-Euler increment from the committed state, as any other. Committed on
        success. Returns (result, λ, pseudo steps)."""
        self._forces()
        self.assemble_tangent()
        dv = self.J.getDiagonal()
        diag = np.abs(dv.array.copy())
        dv.destroy()
        diag[self._presc_global - self.start] = 0.0  # no viscosity on prescribed dofs
        lam_c = self.load_factor
        xc = np.zeros(self.n_local)
        self._gather(xc)
        x_prev = xc.copy()
        lam = lam_c
        r = np.zeros(self.n_local)
        eta, first, steps, its = eta0, True, 0, 0
        res = NewtonResult(lam_c, False, 0, math.inf, 1.0, "DIVERGED_MAX_IT", ())
        rn_prev = None
        while steps < max_steps:
            steps += 1
            res, lam_new = self._arc_increment(ds if first else 0.0, a, q,
                                               damping=eta * diag, x_prev=x_prev,
                                               lam_start=lam, commit=False,
                                               ds_scale=abs(ds))
            its += res.iterations
            if not res.converged:
                # restored to the committed state: start over, more viscous
                eta *= 16.0
                first, lam, rn_prev = True, lam_c, None
                x_prev = xc.copy()
                if eta > 1e4:
                    break
                continue
            first = False
            lam = lam_new
            x = np.zeros(self.n_local)
            self._gather(x)
            # the undamped residual at the damped equilibrium
            self._residual_into(r)
            rn = self._free_norm(r)
            ref = self._reference()
            if rn <= self.rtol * ref or (res.reason == "CONVERGED_RELAXED"
                                         and rn <= self.relaxed_rtol * ref):
                self.commit()
                self.load_factor = float(lam)
                out = NewtonResult(float(lam), True, its, rn, ref, "CONVERGED_PSEUDO_TRANSIENT",
                                   res.history)
                self.results.append(out)
                if self.comm.rank == 0:
                    log.info("snap-back jumped at fixed displacement measure: load factor "
                             "%.6g -> %.6g in %d pseudo steps, %d iterations", lam_c, lam,
                             steps, its)
                return out, float(lam), steps
            # switched evolution relaxation: less viscosity as the residual falls
            eta = eta * min(4.0, max(0.05, rn / rn_prev)) if rn_prev else eta * 0.25
            rn_prev = rn
            x_prev = x
        self._set_load(lam_c)
        self.restore()
        out = NewtonResult(lam_c, False, its, res.residual, res.reference,
                           "DIVERGED_PSEUDO_TRANSIENT", res.history)
        self.results.append(out)
        return out, lam_c, steps

    def _critical_point(self, g0: float, g1: float, x0: np.ndarray, lam0: float,
                        du: np.ndarray, dlam: float, evaluate, r: np.ndarray,
                        max_evals: int = 6, tol: float = 0.5
                        ) -> tuple[float, float] | None:
        """The step fraction α ∈ (0, 1) where g(α) = r(x0 + α Δu, λ0 + α Δλ)·Δu changes
        sign (Illinois regula falsi, at most ``max_evals`` residuals; stops once
        |g| ≤ ``tol`` |g(0)|, Crisfield's slack line search), with |r| there (the state
        is left evaluated at it); None when the step does not bracket one
        (g(0) < 0 < g(1) is needed: a descent direction that overshoots)."""
        if not (g0 < 0.0 < g1) or not math.isfinite(g1):
            return None
        lo, glo, hi, ghi = 0.0, g0, 1.0, g1
        side = 0
        for _ in range(max_evals):
            alpha = (lo * ghi - hi * glo) / (ghi - glo)
            alpha = min(max(alpha, lo + 0.01 * (hi - lo)), hi - 0.01 * (hi - lo))
            rn = evaluate(x0 + alpha * du, lam0 + alpha * dlam)
            ga = self.comm.allreduce(float(np.dot(r, du)))
            if not math.isfinite(ga):
                return None
            if abs(ga) <= tol * abs(g0):
                break
            if ga > 0.0:
                hi, ghi = alpha, ga
                if side == 1:
                    glo *= 0.5
                side = 1
            else:
                lo, glo = alpha, ga
                if side == -1:
                    ghi *= 0.5
                side = -1
        return alpha, rn

    def _dissipation(self) -> tuple[float, np.ndarray, float]:
        """The energy the interactions' laws dissipate from the committed state to the
        current one [J], its gradient over the local dofs and its λ derivative (0)."""
        b = self.sets[0]
        a = np.zeros(self.n_local)
        d = 0.0
        for c in self.interactions:
            fn = getattr(c, "dissipation", None)
            if fn is not None:
                dc, g = fn(self._state)
                d += dc
                a[b.sl] += g
        a[b.sl][b.presc != 0] = 0.0
        return d, a, 0.0

    def _dissipation_step(self, q: np.ndarray, work: float,
                          fractions: Sequence[float] = (0.05, 0.0125, 0.003, 0.0008, 0.0002)
                          ) -> tuple[list[NewtonResult], float, bool]:
        """Increments under dissipation control from the committed state, prescribing
        ``fractions`` of ``work`` [J] in turn (5 % down to 0.02 %) as the energy the
        joints' laws dissipate (their own account: plastic work of the
        return mapping, exact; its gradient by finite differences); stops at the first
        that converges. Returns every result (the last the one that counts), the
        fraction of the last, and whether it was the joints' own dissipation (True) or
        the fallback: failing every fraction, the first three are tried with the
        Gutiérrez estimate below.

        The energy is the laws' own, not the Gutiérrez (2004) estimate
        ½ [f_ext(λ_c)·Δu − Δλ q·u_c]: that estimate assumes secant unloading (damage),
        while the joints and contacts here unload elastically from a permanent
        deformation (plasticity); for them it counts an elastic unloading as
        dissipation, and the path then runs down and up the unloading line without
        moving on."""
        out = []
        a0 = np.zeros(self.n_local)
        for frac in fractions:
            res, _ = self._arc_increment(frac * work, a0, q, constraint=self._dissipation,
                                         ctol=1e-4)
            out.append(res)
            if res.converged:
                return out, frac, True
        # last, Gutiérrez's secant estimate (linear in the increment): where the joints'
        # own account finds no step it may still find an equilibrium to go on from —
        # every state it reaches is one, though it may lie on an unloading line
        b = self.sets[0]
        a = np.zeros(self.n_local)
        f = self.dead_factor * self.model.f_dead + self.load_factor * self.model.f_live
        a[b.sl] = np.where(b.presc != 0, 0.0, 0.5 * f)
        xc = np.zeros(self.n_local)
        self._gather(xc)
        bb = -0.5 * self.comm.allreduce(float(np.dot(q, xc)))
        for frac in fractions[:3]:
            res, _ = self._arc_increment(frac * work, a, q, b=bb)
            out.append(res)
            if res.converged:
                break
        return out, frac, False

    def follow(
        self,
        increment: float,
        *,
        control: str = "arc-length",
        weights: np.ndarray | None = None,
        prescription: str | None = None,
        component: int = 1,
        direction: float = 1.0,
        max_displacement: float = math.inf,
        max_load: float = math.inf,
        max_steps: int = 400,
        min_increment: float | None = None,
        max_increment: float | None = None,
        grow: float = 1.5,
        easy_iterations: int = 6,
        peak_drop: float = 0.05,
        stop_drop: float = 0.5,
        mechanism_ratio: float = 1e-2,
        dissipation: bool = True,
        max_stall_steps: int = 100,
        callback: Callable[[PathPoint], None] | None = None,
        safe_point: Callable[[int, dict], None] | None = None,
        resume: Mapping | None = None,
    ) -> StaticRun:
        """Trace the load–displacement path from the committed state up to and past the
        peak load.

        Two controls:

        * ``"arc-length"`` (indirect displacement control, de Borst 1987; the form
          Lourenço & Rots used for masonry): the live-load factor λ is an unknown and
          each increment moves a generalized displacement ``w·u`` by ``increment`` [m],
          solved by the bordered Newton method (two solves with one factorization per
          iteration). ``weights`` (a local array over the block dofs) default to the
          live load scaled to unit sum, ``w·u`` being then the displacement of the load
          along its own direction (downward for a downward load). A displacement
          measure passes limit points where load control stops, and λ goes down the
          descending branch by itself (snap-backs in the measure are not followed;
          pick weights that grow monotonically, such as the loaded point's
          displacement or a crack opening);
        * ``"displacement"``: prescription ``prescription``'s ``component`` is driven by
          ``increment`` [m] per step in the sense ``direction`` (+1 or −1) at a fixed
          live-load factor (a platen); the load is the force the platen applies along
          the drive [N], the displacement measure the drive from the start.

        Snap-backs (arc length, ``dissipation``): where an increment of the
        displacement measure finds no equilibrium even at the smallest size — a mortar
        joint that cracks may make the loaded point move back — the increment is retried
        under dissipation control (the switching of Verhoosel et al. 2009): the energy
        the joints' laws dissipate (their own plastic work) is prescribed instead (5 %,
        1.25 %, 0.3 %, 0.08 %, 0.02 % of the work ½ λ_c d done so far), which only
        grows; failing that, Gutiérrez's (2004) secant estimate ½ [f_ext(λ_c)·Δu −
        Δλ q·u_c] (it may also step along an elastic unloading line); failing that, the
        state a jack holding the displacement would jump to (:meth:`_jump`). Each
        increment that follows tries the displacement measure's smallest increment first
        — an equilibrium at the next
        displacement ends the snap-back — and else stays under dissipation control, at
        the fraction that converged last (grown by ``grow`` after one of at most twice
        ``easy_iterations``, at most 5 %), until the displacement measure moves
        forward. Such increments may move the measure backwards; after
        ``max_stall_steps`` increments that neither pass the farthest displacement
        reached nor dissipate energy in the joints' own account (the fallback's steps,
        which may run down and up an unloading line), with the load within ``peak_drop``
        of its peak, the run ends *not converged*.

        Increments: one converging in at most ``easy_iterations`` lets the next grow
        ``grow`` times (up to ``max_increment``, default 8 × ``increment``); one that
        fails is undone and halved, down to ``min_increment`` (default
        ``increment``/64; ``assess`` uses 1/1024).

        Status (the loads: λ for arc length, the reaction [N] for displacement
        control): *peak passed* once the load has fallen ``stop_drop`` below its
        maximum (the run then stops), or at the end of the run if it fell at least
        ``peak_drop`` below it — a fall counted only in states that prove the peak
        passed: at the farthest displacement reached, or dissipating more in the joints'
        own account (not on the way down an unloading line) — and the last load is
        still that far down (a path that came back up near its peak may go higher);
        else at ``max_displacement`` [m] (of the measure) a
        *mechanism* if the current stiffness parameter (Bergan et al. 1978) of the last
        step is below ``mechanism_ratio`` (the load no longer rising), *displacement
        limit reached* otherwise; *load reached* once the load reaches ``max_load``
        (the run stops there: the structure carries it); *not converged* if an
        increment fails at the smallest size (or ``max_steps`` is reached) before the
        peak was passed.

        Checkpoints: ``safe_point(steps, path_state)`` is called after every converged
        increment that does not end the run, the solver committed there, with the
        path's own state (a picklable dict: the run so far, the peak, the increment
        size, the secant predictor, the snap-back and stall counters); a run resumed
        with ``resume=path_state`` from the solver's state of that moment
        (:meth:`set_checkpoint_state`), with the same arguments otherwise, goes on
        exactly as the run would have.

        Returns:
            :class:`StaticRun` with ``loads`` and ``displacements`` (the measure) of
            every converged step, the start first.
        """
        if not increment > 0:
            raise ValueError(f"increment must be > 0, got {increment}")
        if control not in ("arc-length", "displacement"):
            raise ValueError(f"control must be 'arc-length' or 'displacement', got {control!r}")
        dmin = increment / 64.0 if min_increment is None else float(min_increment)
        dmax = 8.0 * increment if max_increment is None else float(max_increment)
        if not 0 < dmin <= increment <= dmax:
            raise ValueError("need 0 < min_increment <= increment <= max_increment")
        if not 0 < peak_drop <= stop_drop < 1:
            raise ValueError("need 0 < peak_drop <= stop_drop < 1")
        if max_stall_steps < 1:
            raise ValueError(f"max_stall_steps must be >= 1, got {max_stall_steps}")

        def dot(u, v):
            return self.comm.allreduce(float(np.dot(u, v)))

        relaxed0 = self.relaxed
        if control == "arc-length":
            q = self._live_vector()
            a = np.zeros(self.n_local)
            b = self.sets[0]
            if weights is None:
                w = np.where(b.presc != 0, 0.0, self.model.f_live)
                tot = self.comm.allreduce(float(np.abs(w).sum()))
                if tot == 0.0:
                    raise ValueError("arc length needs a live load (none on the free dofs)")
                a[b.sl] = w / tot
            else:
                w = np.asarray(weights, dtype=float)
                if w.shape != b.u.shape:
                    raise ValueError(f"weights must have the block dofs' shape {b.u.shape}")
                a[b.sl] = w
            if dot(a, a) == 0.0:
                raise ValueError("the weights of the displacement measure are all zero")

            def measure() -> float:
                xa = np.zeros(self.n_local)
                self._gather(xa)
                return dot(a, xa)

            def load() -> float:
                return self.load_factor
        else:
            if prescription is None:
                raise ValueError("displacement control needs a prescription name")
            if component not in (0, 1):
                raise ValueError(f"component must be 0 or 1, got {component}")
            if direction not in (1.0, -1.0):
                raise ValueError(f"direction must be 1 or -1, got {direction}")
            sign = float(direction)  # the drive's sense; the load: the reaction along it
            names = {p.name for p in self.model.prescriptions}
            for s in self.sets[1:]:
                names |= set(s.prescriptions)
            if prescription not in names:
                raise ValueError(f"no prescription named {prescription!r}")
            d0 = self._prescribed_value(prescription, component)

            def measure() -> float:
                return sign * (self._prescribed_value(prescription, component) - d0)

            def load() -> float:
                return sign * float(self.reactions()[prescription][component])

        if resume is None:
            run = StaticRun(RunStatus(Status.NOT_CONVERGED, load(), load()))
            lam0 = load()
            d_start = measure()
            run.loads.append(lam0)
            run.displacements.append(0.0)
            run.load_factors.append(self.load_factor)
            run.iterations.append(0)
        peak, k0, k_last = lam0 if resume is None else 0.0, None, None
        switched = 0  # increments taken under dissipation control
        jumped = 0  # snap-backs passed at a fixed displacement measure (:meth:`_jump`)
        d_far, stall = 0.0, 0  # the farthest displacement; steps since it last grew
        fallen = 0.0  # the largest fall below the peak in states that prove it passed
        astray = False  # a fallback step taken since the farthest displacement
        diss: float | None = None  # on a snap-back: the fraction of ½ λ d dissipated per step
        step = float(increment)
        status = None
        steps = 0
        # the secant predictor: the previous increment of the displacement measure
        # (Δx, Δλ, its a·Δx), scaled to the next one (see _arc_increment)
        x_start = np.zeros(self.n_local)
        secant: tuple[np.ndarray, float, float] | None = None
        ds_last = float(increment)  # the last committed increment of the measure
        if resume is not None:
            if resume.get("control") != control:
                raise ValueError(f"the path state is of {resume.get('control')!r} control, "
                                 f"not {control!r}")
            (run, lam0, d_start, peak, k0, k_last, switched, jumped, d_far, stall, fallen,
             astray, diss, step, steps, secant) = (
                resume[k] for k in ("run", "lam0", "d_start", "peak", "k0", "k_last",
                                    "switched", "jumped", "d_far", "stall", "fallen",
                                    "astray", "diss", "step", "steps", "secant"))
            if control == "displacement":
                d0 = resume["d0"]
            ds_last = float(resume.get("ds_last", increment))
        while steps < max_steps:
            d_now = run.displacements[-1]
            self._gather(x_start)
            lam_start = self.load_factor
            plain = False  # this increment moved the displacement measure directly
            ds = min(step, max_displacement - d_now) if math.isfinite(max_displacement) else step
            if ds <= 1e-12 * max(abs(max_displacement), 1.0):
                break
            ds_used = ds  # its size, if it moved the measure
            in_snap = diss is not None
            dissipating = False  # this increment dissipated in the joints' own account
            if control == "arc-length" and in_snap:
                # on a snap-back: first the displacement measure's smallest increment (an
                # equilibrium ahead at the next displacement ends the snap-back, as a
                # jack under displacement control would jump to it; tried even while the
                # path goes back: skipping it let the anchored repair arch's path run
                # back to 0.05 mm under a pulling load); else go on under dissipation
                # control, at the fraction that worked last (grown after an easy
                # increment: up to twice ``easy_iterations``, the constraint being
                # nonlinear)
                ds_used = min(dmin, ds)
                self._extrapolation(ds_used / ds_last)
                res, _ = self._arc_increment(ds_used, a, q)
                plain = res.converged
                if res.converged:
                    in_snap = False
                    diss, step = None, dmin
                else:
                    run.results.append(res)
                    self._extrapolation(1.0)
                    tried, frac, dissipating = self._dissipation_step(
                        q, 0.5 * abs(run.loads[-1]) * d_now, (diss, diss / 4.0, diss / 16.0))
                    run.results.extend(tried[:-1])
                    res = tried[-1]
                    if res.converged:
                        switched += 1
                        diss = min(frac * (grow if res.iterations <= 2 * easy_iterations
                                           else 1.0), 0.05)
            elif control == "arc-length":
                pred = None
                if secant is not None and secant[2] > 0.0:
                    f = ds / secant[2]
                    pred = (f * secant[0], f * secant[1])
                self._extrapolation(ds / ds_last)
                res, _ = self._arc_increment(ds, a, q, predictor=pred)
                if not res.converged and pred is not None:
                    # then the tangent's predictor
                    run.results.append(res)
                    res, _ = self._arc_increment(ds, a, q)
                plain = res.converged
                if (not res.converged and dissipation and peak > 0 and d_now > 0
                        and step <= dmin * (1 + 1e-12)):
                    # no equilibrium at the next displacement near this state: the path
                    # turns back (a snap-back). Follow the turn under dissipation
                    # control; else find the state a jack holding the displacement
                    # would jump to (the load drops at the next displacement)
                    run.results.append(res)
                    self._extrapolation(1.0)
                    tried, frac, dissipating = self._dissipation_step(
                        q, 0.5 * abs(run.loads[-1]) * d_now)
                    run.results.extend(tried[:-1])
                    res = tried[-1]
                    if res.converged:
                        switched += 1
                        in_snap, diss = True, frac
                    else:
                        run.results.append(res)
                        res, _, _ = self._jump(ds, a, q)
                        if res.converged:
                            jumped += 1
            else:
                target = d0 + sign * (d_now + ds)
                disp = {prescription: (target, None) if component == 0 else (None, target)}
                self._extrapolation(ds / ds_last)
                res = None
                if secant is not None and secant[2] > 0.0:
                    # start from the previous increment's step, scaled: a drive that
                    # jumps alone shears the joints beside it far past their strength at
                    # the first iterate (the wall's top bed joint), and Newton from there
                    # diverges where the secant's start converges
                    self._scatter(x_start + (ds / secant[2]) * secant[0])
                    res = self.solve(self.load_factor, displacement=disp)
                    if not res.converged:
                        run.results.append(res)
                if res is None or not res.converged:
                    res = self.solve(self.load_factor, displacement=disp)
                plain = res.converged
            run.results.append(res)
            if not res.converged:
                if step <= dmin * (1 + 1e-12) or in_snap:
                    lam = run.loads[-1]
                    detail = (f"Newton did not converge ({res.reason}) at displacement "
                              f"{d_now + ds:.4g} m after cut-backs to {dmin:.3g} m")
                    # (and the load still down: a path that came back up near its
                    # peak may go higher, so its peak is no collapse load)
                    fell = peak > 0 and fallen >= peak_drop and lam <= (1 - peak_drop) * peak
                    status = RunStatus(Status.PEAK_PASSED if fell else Status.NOT_CONVERGED,
                                       lam, peak, None if fell else d_now + ds,
                                       ("the load had fallen " f"{100 * fallen:.0f} % "
                                        "below its peak; then " if fell else "") + detail,
                                       at_kind="displacement")
                    break
                step = max(0.5 * step, dmin)
                continue
            steps += 1
            if plain:
                ds_last = ds_used
                x_now = np.zeros(self.n_local)
                self._gather(x_now)
                dx = x_now - x_start
                secant = (dx, self.load_factor - lam_start,
                          dot(a, dx) if control == "arc-length" else ds)
            else:
                secant = None
            d = measure() - d_start
            lam = load()
            dd, dl = d - run.displacements[-1], lam - run.loads[-1]
            k = dl / dd if dd != 0 else math.inf
            if k0 is None and math.isfinite(k) and k > 0:
                k0 = k
            k_last = k
            run.loads.append(lam)
            run.displacements.append(d)
            run.load_factors.append(self.load_factor)
            run.iterations.append(res.iterations)
            new_peak = lam > peak
            peak = max(peak, lam)
            if d > d_far:
                d_far, stall = d, 0
            elif not dissipating:
                # (an increment that dissipated in the joints' own account is progress
                # along a snap-back, however far back it goes: not counted)
                stall += 1
            # how far the load has fallen below its peak, read only where that proves
            # a peak passed: at the farthest displacement yet, or in a state that
            # dissipated more in the joints' own account on a path that has taken no
            # fallback step since it last was at the farthest displacement. Not on the
            # way down an unloading line (the Gutiérrez fallback's steps may run down
            # one, and dissipation control may go on from there): a load that falls
            # there says nothing of what the structure carries further on
            if d >= d_far:
                astray = False
            elif not (plain or dissipating):
                astray = True  # a fallback's step, behind the farthest displacement
            if new_peak:
                fallen = 0.0
            elif peak > 0 and (d >= d_far or (dissipating and not astray)):
                fallen = max(fallen, 1.0 - lam / peak)
            if stall >= max_stall_steps:
                msg = (f"{stall} increments (under dissipation control) without getting "
                       f"past displacement {d_far:.4g} m: the path runs back and forth there")
                if fallen >= peak_drop and lam <= (1 - peak_drop) * peak:
                    status = RunStatus(Status.PEAK_PASSED, lam, peak, None,
                                       f"the load had fallen {100 * fallen:.0f} % below its "
                                       f"peak; then {msg}")
                else:
                    status = RunStatus(Status.NOT_CONVERGED, lam, peak, d_far, msg,
                                       at_kind="displacement")
                break
            if in_snap and dd > 0:
                # the snap-back is over: back to the displacement measure, from its
                # smallest increment
                diss, step = None, dmin
            if callback is not None:
                callback(PathPoint(lam, d, self.load_factor, res.iterations))
            if lam >= max_load:
                status = RunStatus(Status.LOAD_REACHED, lam, peak, None,
                                   f"carried {lam:.6g} >= max_load = {max_load:.6g}")
                break
            if peak > 0 and fallen >= stop_drop:
                status = RunStatus(Status.PEAK_PASSED, lam, peak, None,
                                   f"the load fell to {100 * lam / peak:.0f} % of its peak "
                                   f"at displacement {d:.4g} m")
                break
            if res.iterations <= easy_iterations:
                step = min(step * grow, dmax)
            if safe_point is not None:
                safe_point(steps, {
                    "control": control, "run": run, "lam0": lam0, "d_start": d_start,
                    "peak": peak, "k0": k0, "k_last": k_last, "switched": switched,
                    "jumped": jumped, "d_far": d_far, "stall": stall, "fallen": fallen,
                    "astray": astray, "diss": diss, "step": step, "steps": steps,
                    "secant": secant, "ds_last": ds_last,
                    "d0": d0 if control == "displacement" else None})
        if status is None:
            lam = run.loads[-1]
            d = run.displacements[-1]
            sp = k_last / k0 if (k0 and k_last is not None) else math.nan
            if peak > 0 and fallen >= peak_drop and lam <= (1 - peak_drop) * peak:
                status = RunStatus(Status.PEAK_PASSED, lam, peak, None,
                                   f"the load fell {100 * fallen:.0f} % below its peak by "
                                   f"displacement {d:.4g} m")
            elif steps >= max_steps:
                status = RunStatus(Status.NOT_CONVERGED, lam, peak, d,
                                   f"max_steps = {max_steps} reached before the peak",
                                   at_kind="displacement")
            elif abs(sp) < mechanism_ratio:
                status = RunStatus(Status.MECHANISM, lam, peak, None,
                                   f"the load no longer rises at displacement {d:.4g} m "
                                   f"(current stiffness parameter {sp:.2g})")
            else:
                status = RunStatus(Status.DISPLACEMENT_LIMIT, lam, peak, None,
                                   f"max_displacement = {max_displacement:.4g} m reached "
                                   f"(current stiffness parameter {sp:.2g})")
        self._extrapolation(1.0)
        relaxed = self.relaxed - relaxed0
        if relaxed:
            status = dataclasses.replace(
                status, detail=f"{status.detail}; {relaxed} increment(s) accepted at a "
                               f"residual up to {self.relaxed_rtol:.3g} of the force norm "
                               "(Newton's iterations stalled above rtol = "
                               f"{self.rtol:.3g})")
        if jumped:
            status = dataclasses.replace(
                status, detail=f"{status.detail}; {jumped} snap-back(s) passed at constant "
                               "displacement (the load dropping, as under a displacement-"
                               "controlled jack)")
        if switched:
            status = dataclasses.replace(
                status, detail=f"{status.detail}; {switched} increment(s) under dissipation "
                               "control (snap-backs)")
        run.status = status
        if self.comm.rank == 0:
            log.info("path following: %s", status.describe())
        return run

    # ------------------------------------------------------------------ checks
    def check_tangent(self, h: float | None = None, columns: Sequence[int] | None = None
                      ) -> float:
        """Largest relative difference between the assembled tangent and central finite
        differences of the residual, over the given global columns (default: all; for
        small models — each column costs two residual evaluations; collective).

        The step ``h`` defaults to 1e-9 of the largest reference coordinate span."""
        self._gather(self.x.array)
        xa0 = self.x.array.copy()
        self._scatter(xa0)
        self._forces()
        self.assemble_tangent()
        if h is None:
            span = float(np.ptp(self.model.blocks.x, axis=0).max())
            h = 1e-9 * span
        cols = range(self.n_global) if columns is None else columns
        rp = np.zeros(self.n_local)
        rm = np.zeros(self.n_local)
        num = 0.0
        den = 0.0
        presc = set(self._presc_global.tolist())
        col_vec = self.J.createVecLeft()
        for j in cols:
            for sign, out in ((1.0, rp), (-1.0, rm)):
                xa = xa0.copy()
                if self.start <= j < self.start + self.n_local:
                    xa[j - self.start] += sign * h
                self._scatter(xa)
                self._forces()
                self._residual_into(out)
            fd = (rp - rm) / (2 * h)
            self.J.getColumnVector(j, col_vec)
            kj = col_vec.getArray(readonly=True).copy()
            is_presc = self.comm.allreduce(int(j in presc), op=MPI.MAX)
            if is_presc:
                continue
            own_presc = np.array([g in presc for g in range(self.start,
                                                          self.start + self.n_local)])
            kj[own_presc] = 0.0
            fd[own_presc] = 0.0
            num = max(num, self.comm.allreduce(float(np.max(np.abs(kj - fd), initial=0.0)),
                                               op=MPI.MAX))
            den = max(den, self.comm.allreduce(float(np.max(np.abs(kj), initial=0.0)),
                                               op=MPI.MAX))
        self._scatter(xa0)
        self._forces()
        self._x_at_forces[:] = xa0
        return num / den if den > 0 else num


def _reason_name(reason: int) -> str:
    for name in dir(PETSc.SNES.ConvergedReason):
        if not name.startswith("_") and getattr(PETSc.SNES.ConvergedReason, name) == reason:
            return name
    return str(reason)
