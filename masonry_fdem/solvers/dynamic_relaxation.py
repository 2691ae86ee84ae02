"""Underwood's adaptive dynamic relaxation for quasi-static equilibrium.

The static problem ``f_int(u) = f_ext`` is solved as the steady state of a fictitious,
critically damped dynamic system (Underwood 1983, in Belytschko & Hughes, *Computational
Methods for Transient Analysis*, pp. 245–265):

* fictitious time step dt = 1 and fictitious masses from Gerschgorin's bound of the
  stiffness, ``m_i = α (dt²/4) Σ_j |K_ij|`` (α = 1.1 by default), so the iteration is stable;
* damping ``c = 2 √(Δxᵀ K Δx / Δxᵀ M Δx)`` from the Rayleigh quotient of the lowest mode,
  ``Δx`` the displacement since the start of the load increment. Underwood approximates
  ``K Δx`` with a diagonal local stiffness ``Δf_i / Δx_i``; we use the secant product
  ``Δxᵀ K Δx = Δxᵀ (f_int(u) − f_int(u0))``, which needs no per-dof division (that
  division amplifies round-off where a dof barely moves, so runs on different rank counts
  drifted apart) and is exact for a linear structure;
  With ``damping="velocity"`` the quotient is taken on the last velocity instead,
  ``c = 2 √(vᵀ (f(uₙ) − f(uₙ₋₁)) / vᵀ M v)`` (``uₙ − uₙ₋₁ = dt v``): a Rayleigh quotient
  is never below the lowest eigenvalue, so the lowest mode is never under-damped, and
  once the fast modes have died out the velocity *is* the slowest mode, so ``c`` tends
  to critical damping of it. Under displacement control the increment's displacement
  field is a static response to a local load, whose quotient lies far above the lowest
  eigenvalue; the velocity estimate then needs 2–9 times fewer iterations (measured on a
  dry 12-voussoir arch pushed to collapse, ``benchmarks/collapse_vs_limit_analysis.py``);
* ``v(n+½) = ((2 − c dt) v(n−½) + 2 dt r(n)/m) / (2 + c dt)``, ``u(n+1) = u(n) + dt v(n+½)``;
* convergence when the out-of-balance force norm over the free dofs falls below
  ``rtol · |f_ext|`` and the fictitious kinetic energy below ``ke_tol`` times its peak.

Every dof set moves by the same update: the block nodes, and the sets the interactions
bring (disk centres and rotations, anchor bar nodes), each with fictitious masses from
the row sums of its stiffness (the interactions' ``add_rowsum``). The replicated sets
(held whole on every rank) enter the residual and the displacement quotient; the
velocity quotient is taken over the block dofs, which carry the structure's lowest mode.

Load increments scale the live loads; an increment that does not converge within
``max_iter`` iterations is reported as not in equilibrium. That is not proof that no
equilibrium exists (near a peak the structure is soft and DR stalls): a load-to-collapse
run that stalls ends *not converged* (:class:`~masonry_fdem.solvers.status.RunStatus`), its
last converged load a lower bound of the collapse load, never the collapse load.
History (material state of the blocks, every interaction's) is committed only when an
increment converges; a failed increment is undone by :meth:`DynamicRelaxation.restore` of
the :meth:`DynamicRelaxation.snapshot` taken before it (every interaction's full state).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from masonry_fdem.interactions.protocol import BLOCKS, Interaction, State
from masonry_fdem.solvers import _kernels as K
from masonry_fdem.solvers._setup import (
    Ordering,
    as_interactions,
    owned_dofsets,
    prescribe_displacements,
)
from masonry_fdem.solvers.status import RunStatus, Status

__all__ = ["CollapseResult", "DynamicRelaxation", "DRResult"]

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class DRResult:
    """Outcome of one load increment.

    Attributes:
        load_factor: factor on the live loads.
        converged: equilibrium found within the iteration limit.
        iterations: DR iterations used.
        residual: final out-of-balance force norm over the free dofs [N].
        reference: the force norm the residual is compared to [N].
    """

    load_factor: float
    converged: bool
    iterations: int
    residual: float
    reference: float

    @property
    def relative_residual(self) -> float:
        return self.residual / self.reference if self.reference > 0 else self.residual


@dataclass(frozen=True)
class CollapseResult:
    """Outcome of :meth:`DynamicRelaxation.load_to_collapse`.

    Attributes:
        status: how the run ended (:class:`~masonry_fdem.solvers.status.RunStatus`):
            *load reached* when ``max_load`` was carried, else *not converged* at the load
            factor tried last (dynamic relaxation cannot tell a stall from a collapse:
            its ``collapse_load`` is None and the last converged factor only a lower bound).
        load_factor: the last load factor with equilibrium.
        resolution: the increment that failed last (the gap between ``load_factor`` and
            the factor where no equilibrium was found).
        history: the converged load factors, in order.
    """

    status: RunStatus
    load_factor: float
    resolution: float
    history: list[float]

    @property
    def collapsed(self) -> bool:
        """Whether the run proved a collapse load (never, for dynamic relaxation's load
        control: a stall is not a collapse)."""
        return self.status.status.gives_collapse_load

    @property
    def collapse_load_factor(self) -> float | None:
        """The collapse load factor if the run proved one, else None."""
        return self.status.collapse_load


class _Set:
    """Dynamic relaxation's arrays of one dof set: the unknowns ``u`` (the owner's), the
    fictitious velocity and masses, the force accumulator ``f`` handed to the
    interactions and the resisting force ``res`` (internal minus interaction forces).
    Those of its own follow the set's storage order when its owner permutes it
    (``ordering``)."""

    def __init__(self, name, u, f, f_ext, mfict, presc, replicated, prescriptions, res,
                 ds=None):
        self.name, self.u, self.f, self.f_ext = name, u, f, f_ext
        self.m, self.presc, self.replicated = mfict, presc, replicated
        self.prescriptions = prescriptions
        self.res = res
        self.v = np.zeros_like(u)
        self.u0 = np.zeros_like(u)
        self.res0 = np.zeros_like(u)
        self.sums = np.zeros(4)
        self.ordering = Ordering(ds)

    def follow_order(self) -> None:
        """Move the arrays of its own if the owner permuted the set since last seen."""
        self.ordering.follow((self.m, self.v, self.u0, self.res0, self.res))


class DynamicRelaxation:
    """Adaptive dynamic relaxation of a :class:`~masonry_fdem.model.Model`.

    Args:
        model: the model (its ``u`` is the unknown; ``v`` is not touched).
        rtol: out-of-balance force tolerance relative to the applied load norm.
        ke_tol: fictitious kinetic energy tolerance relative to its peak in the increment.
        max_iter: iteration limit per load increment.
        mass_safety: α in the fictitious mass bound (≥ 1).
        interactions: one :class:`~masonry_fdem.interactions.protocol.Interaction` or a
            sequence of them (contact, joints, disks, disk–block contact, anchors, a
            user's), or None. Their row sums enter the fictitious masses; their forces
            (without velocity-dependent damping) enter the residual; friction slips by the
            fictitious displacement increments; the dof sets they own (disks, anchor bar
            nodes) join the unknowns. Their states, and the material state of the blocks
            (damage, plastic strain), are committed only when an increment converges.
        damping: "displacement" (Underwood: the Rayleigh quotient of the displacement
            since the start of the increment) or "velocity" (of the last velocity; see
            the module doc). The blocks' dofs only enter the velocity quotient.
    """

    def __init__(
        self,
        model,
        *,
        rtol: float = 1e-6,
        ke_tol: float = 1e-10,
        max_iter: int = 200_000,
        mass_safety: float = 1.1,
        interactions: Interaction | Sequence[Interaction] | None = None,
        damping: str = "displacement",
    ):
        if damping not in ("displacement", "velocity"):
            raise ValueError(f"damping must be 'displacement' or 'velocity', got {damping!r}")
        self.damping = damping
        if not rtol > 0:
            raise ValueError(f"rtol must be > 0, got {rtol}")
        if mass_safety < 1:
            raise ValueError(f"mass_safety must be >= 1, got {mass_safety}")
        self.model = model
        self.rtol = float(rtol)
        self.ke_tol = float(ke_tol)
        self.max_iter = int(max_iter)
        self.dt = 1.0
        self.interactions = as_interactions(interactions)
        owned = owned_dofsets(self.interactions)
        _, rowsum = model.element_bounds()
        rows = {BLOCKS: rowsum.copy(), **{n: np.zeros(ds.u.size) for n, ds in owned.items()}}
        for c in self.interactions:
            c.add_rowsum(rows)
        scale = mass_safety * 0.25 * self.dt**2
        for name, r in rows.items():
            if np.any(scale * r <= 0):
                raise ValueError(f"a dof of {name!r} has no stiffness: is a node not attached "
                                 "to any element?")
        self.presc, _ = model.prescribed_arrays(0.0)
        self.f_ext = np.zeros_like(model.f_int)
        self.f_net = np.zeros_like(model.f_int)  # −f_int + f_interactions, then negated
        self.mfict = scale * rows[BLOCKS]
        blocks = _Set(BLOCKS, model.u.x.array, self.f_net, self.f_ext, self.mfict, self.presc,
                      False, {}, self.f_net)
        self.sets = [blocks] + [
            _Set(n, ds.u, ds.f, ds.f_ext, scale * rows[n], ds.presc, ds.replicated,
                 ds.prescriptions, np.zeros_like(ds.u), ds) for n, ds in owned.items()]
        self.v = blocks.v
        self._fprev = np.zeros_like(model.f_int)
        self._sums = np.zeros(6)  # the blocks' measures, then the velocity quotient's parts
        blocks.sums = self._sums[:4]
        self._vsums = self._sums[4:]
        self._state = State({s.name: s.u for s in self.sets}, {s.name: s.v for s in self.sets},
                            {s.name: s.f for s in self.sets}, self.dt, False)
        self.results: list[DRResult] = []

    def solve(
        self,
        load_factor: float = 1.0,
        displacement: Mapping[str, Sequence[float | None]] | None = None,
        dt: float | None = None,
    ) -> DRResult:
        """Bring the model to equilibrium under ``f_dead + load_factor · f_live``.

        Args:
            load_factor: factor on the live loads.
            displacement: displacement control: ``{prescription name: (ux, uy)}`` [m]
                sets the prescribed dofs of that prescription (a loading platen, or a
                prescribed anchor node) to these total displacements (``None``: leave that
                component as it is).
            dt: the physical duration of the increment [s] seen by rate-dependent
                (Perzyna) laws; None: infinitely slow loading (the rate-independent limit).
        """
        m = self.model
        m.rate_time_step = math.inf if dt is None else dt
        comm = m.comm
        if displacement:
            self.prescribe(displacement)
        m.external_force(load_factor, out=self.f_ext)
        blocks, others = self.sets[0], self.sets[1:]
        for s in others:
            s.follow_order()
        free = self.presc == 0
        ref2 = comm.allreduce(float(np.dot(self.f_ext[free], self.f_ext[free])))
        for s in others:  # replicated: counted once
            fe = s.f_ext[s.presc == 0]
            ref2 += float(np.dot(fe, fe))
        for s in self.sets:
            s.u0[:] = s.u
            s.v[:] = 0.0
        by_velocity = self.damping == "velocity"
        ke_peak = 0.0
        c = 0.0
        r_norm = math.inf
        ref = math.sqrt(ref2)
        it = 0
        converged = False
        for it in range(1, self.max_iter + 1):
            self._resisting_force()
            first = it == 1
            if first:
                for s in self.sets:
                    s.res0[:] = s.res
                if ref == 0.0:
                    ref2 = comm.allreduce(float(np.dot(blocks.res, blocks.res)))
                    for s in others:
                        ref2 += float(np.dot(s.res, s.res))
                    ref = math.sqrt(ref2) or 1.0
            K.dr_measure(blocks.u, blocks.u0, blocks.v, blocks.res, blocks.res0, blocks.f_ext,
                         blocks.m, blocks.presc, blocks.sums)
            if by_velocity:
                K.dr_velocity_quotient(blocks.v, blocks.res, self._fprev, blocks.m,
                                       blocks.presc, first, self._vsums)
            r2, num, den, ke, num_v, den_v = comm.allreduce(self._sums)
            if by_velocity:
                num, den = num_v, den_v
            for s in others:  # every rank holds them whole: added once
                K.dr_measure(s.u, s.u0, s.v, s.res, s.res0, s.f_ext, s.m, s.presc, s.sums)
                r2 += s.sums[0]
                if not by_velocity:
                    num += s.sums[1]
                    den += s.sums[2]
                ke += s.sums[3]
            r_norm = math.sqrt(r2)
            ke_peak = max(ke_peak, ke)
            # a residual far below the tolerance is equilibrium even where the kinetic
            # energy, relative to a tiny peak (a start at equilibrium), is round-off noise
            if r_norm <= self.rtol * ref and (ke <= self.ke_tol * max(ke_peak, 1e-300)
                                              or r_norm <= 1e-2 * self.rtol * ref):
                converged = True
                break
            if not math.isfinite(r_norm):
                raise FloatingPointError(
                    f"dynamic relaxation diverged at load factor {load_factor} (iteration {it})"
                )
            if it > 1 and den > 0 and num > 0:
                c = min(2.0 * math.sqrt(num / den), 1.9 / self.dt)
            # else keep the last estimate: a non-positive quotient (contact opening,
            # friction slip) says nothing of the lowest frequency, and c = 0 would leave
            # the iteration undamped
            for s in self.sets:
                K.dr_update(s.u, s.v, s.res, s.f_ext, s.m, s.presc, c, self.dt, first)
        if converged:
            self.commit()
        res = DRResult(float(load_factor), converged, it, r_norm, ref)
        self.results.append(res)
        if comm.rank == 0:
            log.info(
                "DR: load factor %.4g %s after %d iterations (|r|/|f| = %.2e)",
                load_factor, "converged" if converged else "NOT converged", it,
                res.relative_residual,
            )
        return res

    def commit(self) -> None:
        """Accept the current state: the blocks' material state and every interaction's."""
        self.model.commit_state()
        for c in self.interactions:
            c.commit()

    def prescribe(self, displacement: Mapping[str, Sequence[float | None]]) -> None:
        """Set prescribed dofs to total displacements [m] (see :meth:`solve`)."""
        prescribe_displacements(self.model, self.sets[1:], displacement)

    def _resisting_force(self) -> None:
        """Into ``res`` of every set: f_int(u) − f_interactions(u) [N], what the applied
        loads must balance (the interactions see the fictitious velocities)."""
        m = self.model
        m.internal_force(m.f_int)
        np.negative(m.f_int, out=self.f_net)
        for s in self.sets[1:]:
            s.f.fill(0.0)
        for c in self.interactions:
            c.update(self._state)
            for s in self.sets[1:]:
                s.follow_order()
            c.add_forces(self._state)
        np.negative(self.f_net, out=self.f_net)
        for s in self.sets[1:]:
            np.negative(s.f, out=s.res)

    def snapshot(self) -> dict:
        """The unknowns of every dof set and every interaction's state (copies), for
        :meth:`restore`."""
        return {"dofs": {s.name: s.u.copy() for s in self.sets},
                "interactions": [c.state() for c in self.interactions]}

    def restore(self, snap: Mapping) -> None:
        """Back to a :meth:`snapshot` (collective: contact neighbour lists are rebuilt)."""
        for s in self.sets:
            s.u[:] = snap["dofs"][s.name]
        for c, st in zip(self.interactions, snap["interactions"], strict=True):
            c.set_state(st)

    def load_to_collapse(
        self,
        increment: float,
        *,
        start: float = 0.0,
        max_load: float = math.inf,
        refinements: int = 4,
        callback: Callable[[DRResult], None] | None = None,
    ) -> CollapseResult:
        """Raise the live-load factor in increments until no equilibrium is found.

        From the equilibrium at ``start``, the load factor grows by ``increment``; when an
        increment finds no equilibrium (``max_iter`` reached), the state before it is
        restored and the increment halved, up to ``refinements`` times.

        Status (logged on rank 0): *load reached* if ``max_load`` is carried; otherwise
        *not converged* at the factor tried last, after all refinements. The last
        converged factor is then a lower bound of the collapse load factor (the stall
        may lie below the peak); ``resolution`` is the increment that failed.

        Returns:
            :class:`CollapseResult` with the status and the converged factors in order.
        """
        if not increment > 0:
            raise ValueError(f"increment must be > 0, got {increment}")
        if refinements < 0:
            raise ValueError(f"refinements must be >= 0, got {refinements}")
        level = float(start)
        step = float(increment)
        converged: list[float] = []
        halvings = 0
        while level < max_load:
            trial = min(level + step, max_load)
            snap = self.snapshot()
            res = self.solve(trial)
            if callback is not None:
                callback(res)
            if res.converged:
                level = trial
                converged.append(level)
                continue
            self.restore(snap)
            if halvings == refinements:
                detail = (f"dynamic relaxation: no equilibrium within {self.max_iter} "
                          f"iterations (|r|/|f| = {res.relative_residual:.2e}) after "
                          f"{refinements} halving(s) of the increment")
                return self._finish(CollapseResult(
                    RunStatus(Status.NOT_CONVERGED, level, level,
                              trial, detail), level, trial - level, converged))
            halvings += 1
            step *= 0.5
        return self._finish(CollapseResult(
            RunStatus(Status.LOAD_REACHED, level, level, None,
                      f"carried the largest load factor asked for, {level:.6g}"),
            level, step, converged))

    def _finish(self, result: CollapseResult) -> CollapseResult:
        if self.model.comm.rank == 0:
            log.info("DR load to collapse: %s", result.status.describe())
        return result

    def load_steps(
        self,
        factors: Sequence[float],
        callback: Callable[[DRResult], None] | None = None,
    ) -> list[DRResult]:
        """Solve a sequence of load increments; stop at the first one without equilibrium.

        Returns:
            The results of the increments attempted (the last one not converged if the
            structure could not carry it: its collapse load lies between the last two).
        """
        out = []
        for lf in factors:
            res = self.solve(lf)
            out.append(res)
            if callback is not None:
                callback(res)
            if not res.converged:
                break
        return out

    def reactions(self) -> dict[str, np.ndarray]:
        """Reaction (Rx, Ry) [N] of each prescription: f_int − f_ext at its dofs (for an
        anchor node's, the force its prescription applies)."""
        m = self.model
        self._resisting_force()
        out = {}
        for p in m.prescriptions:
            r = np.zeros(2)
            np.add.at(r, p.components, self.f_net[p.dofs] - self.f_ext[p.dofs])
            out[p.name] = m.comm.allreduce(r)
        for s in self.sets[1:]:
            for name, dofs in s.prescriptions.items():
                out[name] = s.res[dofs] - s.f_ext[dofs]
        return out
