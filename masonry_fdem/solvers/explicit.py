"""Explicit central-difference time integration with lumped mass.

One step: internal forces from the dolfinx form at ``u(n)``, the forces of every
interaction (through the protocol of :mod:`masonry_fdem.interactions.protocol`), external
loads, then one numba kernel — the same for every dof set: block nodes, disk centres and
rotations, anchor bar nodes — updates velocities and displacements, overwrites
prescribed dofs, computes support reactions and accumulates the energy account. Nothing
is allocated in the step.

The energy account (:meth:`ExplicitSolver.energies`, :class:`EnergyAccount`) closes: the
kinetic energy, the energies stored in the elements and in every interaction, every
dissipation (the elements' plasticity and damage, each interaction's, the solver's
damping) minus the work of the loads and of the supports equal the total at the start,
up to a ``residual`` that is round-off for a conservative run. Every work is counted as
central difference does (force at u(n) times the midpoint increment (u(n+1) − u(n−1))/2,
kinetic energy at the half step), and the stored energies, evaluated where the forces
were (at u(n)), are carried to the same level — the half step — by their forces' work
over the half step: ``stored − ½ f(n)·(u(n+1) − u(n))``, exact for linear springs (where
it is ½ u(n)·K u(n+1), the energy central difference conserves).

The time step is ``safety`` times the critical one, the smallest over the dof sets of
``(2/ω)(√(1 + ζ²) − ζ)`` = ``4/(√(4ω² + γ²) + γ)``: ω² bounded for the blocks by the
largest element eigenvalue of the linear stiffness with lumped mass plus the bounds the
interactions add (contact penalties, joints, anchors, disks), for every other dof set by
the bounds of the interactions acting on it, and γ = 2ζω the sum of the interactions'
bounds of their dampers' rates (the restitution of the block contact), which act on the
velocity of the half step before. It is reported (``ExplicitSolver.stability``, logged),
and a user time step above the critical one is refused.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from mpi4py import MPI

import numpy as np

from masonry_fdem.constants import DT_SAFETY
from masonry_fdem.interactions.protocol import BLOCKS, Interaction, State
from masonry_fdem.solvers import _kernels as K
from masonry_fdem.solvers._setup import (
    Ordering,
    as_interactions,
    damped_step,
    owned_dofsets,
    stability_terms,
)
from masonry_fdem.solvers.restart import (
    interactions_state,
    model_state,
    set_solver_sets_state,
)

if TYPE_CHECKING:
    from masonry_fdem.io.checkpoint import Checkpointer

__all__ = ["ExplicitSolver", "EnergyAccount", "StableStep", "UnstableTimeStepError"]

log = logging.getLogger(__name__)


class UnstableTimeStepError(ValueError):
    """A requested time step exceeds the critical one."""


@dataclass(frozen=True)
class EnergyAccount:
    """Energies [J] since the start of the run, over every dof set (block nodes, disks,
    anchor bars) and global over ranks.

    The account::

        kinetic + Σ stored + Σ dissipated + damping − external − support
            = initial + residual

    ``stored`` holds the energy stored now, by store: ``"strain"`` (the blocks' elements:
    their exact strain energy) and each interaction by name (its ``energies()["stored"]``:
    contact penalty, joints, anchors, disks, ...), all at the half step of the kinetic
    energy (see the module doc). ``dissipated`` holds the energy dissipated since the
    start, by mechanism: ``"elements"`` (plastic work and damage of the blocks'
    materials, :meth:`Model.element_dissipation`) and each interaction's (by its details
    where it gives them — ``"contact friction"``, ``"contact damper"`` — else by name).
    ``damping`` is the solver's (mass-proportional and local) damping, ``external`` the
    work of the applied loads (gravity, live loads), ``support`` that of the reactions at
    prescribed dofs, ``initial`` the total at the start (kinetic + stored), and
    ``residual`` what is left over: round-off for a conservative run, else the time
    discretisation of the laws (contacts opening and closing within a step, friction,
    nonlinear springs), plus any energy an interaction does not report (the anchors' bond
    and plasticity). ``exchanged`` is Σ over the steps of |work of the loads| + |work of
    the supports| (of each rank's part: a little more on several ranks), and
    :attr:`scale` = |initial| + exchanged the energy put through the system, the
    measure of the residual (:attr:`relative_residual`).

    The solver's own terms: ``balance`` = kinetic + internal + damping − external −
    support − contact − initial kinetic, the central-difference identity (round-off);
    ``internal`` is the work done against the blocks' internal forces, ``contact`` the
    work done BY the forces of all interactions. ``interactions`` holds, per interaction
    name, its own :meth:`energies` as it reports them (``stored``, ``dissipated`` since
    it was made, details), ``work`` (the work its forces did in this run) and
    ``unaccounted`` (its share of the residual: work + stored at the half step +
    dissipated in the run − stored at the start); ``unaccounted`` is their sum.
    """

    kinetic: float
    internal: float
    external: float
    damping: float
    support: float
    contact: float
    balance: float
    interactions: dict[str, dict[str, float]] = field(default_factory=dict)
    unaccounted: float = 0.0
    stored: dict[str, float] = field(default_factory=dict)
    dissipated: dict[str, float] = field(default_factory=dict)
    initial: float = 0.0
    residual: float = 0.0
    exchanged: float = 0.0

    @property
    def total_stored(self) -> float:
        """Σ of the stored energies [J]."""
        return float(sum(self.stored.values()))

    @property
    def total_dissipated(self) -> float:
        """Σ of the dissipations in the run, the solver's damping included [J]."""
        return float(sum(self.dissipated.values())) + self.damping

    @property
    def scale(self) -> float:
        """The energy put through the system [J]: |initial| + exchanged."""
        return abs(self.initial) + self.exchanged

    @property
    def relative_residual(self) -> float:
        """residual / scale (0 when nothing happened)."""
        return self.residual / self.scale if self.scale > 0 else 0.0

    def summary(self) -> str:
        """The account in a few lines [J], for a demo's or a user's printout."""
        def terms(d):
            return ", ".join(f"{k} {v:.4g}" for k, v in d.items())

        return (
            f"energy account [J]: kinetic {self.kinetic:.4g}; stored: "
            f"{terms(self.stored)}\n"
            f"  dissipated: {terms(self.dissipated)}, solver damping {self.damping:.4g}\n"
            f"  work of the loads {self.external:.4g}, of the supports {self.support:.4g};"
            f" initial {self.initial:.4g}\n"
            f"  residual {self.residual:.3e} ({self.relative_residual:.2e} of "
            f"{self.scale:.4g} put through)")


@dataclass(frozen=True)
class StableStep:
    """The critical time step of one dof set and what sets it.

    Attributes:
        omega2: the ω² bounds [1/s²] that add up, by source ("elements" for the blocks'
            elements, else the interaction's name).
        gamma: the damper rate bounds γ [1/s] that add up, by interaction name.
        local_damping: Cundall's local damping α of the set's solver (the step is divided
            by √(1 + α) of the largest α).
        dt: the critical step [s], ``4/(√(4ω² + γ²) + γ) / √(1 + α)`` (∞: nothing bounds it).
    """

    omega2: dict[str, float]
    gamma: dict[str, float]
    local_damping: float
    dt: float

    def __str__(self) -> str:
        w2 = sum(self.omega2.values())
        g = sum(self.gamma.values())
        terms = ", ".join(f"{k} {v:.3g}" for k, v in self.omega2.items())
        text = f"dt {self.dt:.4g} s from omega^2 {w2:.3g} 1/s^2 ({terms})"
        if g > 0:
            dampers = ", ".join(f"{k} {v:.3g}" for k, v in self.gamma.items())
            text += (f", damper rate {g:.3g} 1/s ({dampers}; zeta {g / (2 * np.sqrt(w2)):.3g})"
                     if w2 > 0 else f", damper rate {g:.3g} 1/s ({dampers})")
        if self.local_damping > 0:
            text += f", local damping {self.local_damping:.3g}"
        return text


class _Set:
    """The explicit solver's arrays of one dof set (views of the owner's state), and
    those of its own, which follow the set's storage order when its owner permutes it
    (``ordering``, see :meth:`~masonry_fdem.interactions.protocol.DofSet.permute`)."""

    def __init__(self, name, u, v, f_int, f_ext, f_con, mass, presc, vp, reaction,
                 replicated, prescriptions, ds=None):
        self.name = name
        self.u, self.v, self.f_int, self.f_ext, self.f_con = u, v, f_int, f_ext, f_con
        self.mass = mass
        self.minv = 1.0 / mass
        self.presc, self.vp, self.reaction = presc, vp, reaction
        self.replicated = replicated
        self.prescriptions = prescriptions
        self.energy = np.zeros(K.N_ENERGY)
        self.du = np.zeros_like(u)
        self.local = 0.0  # Cundall's local damping coefficient α
        self.good_u = u.copy()  # the last finite state (ExplicitSolver.run)
        self.good_v = v.copy()
        self.ordering = Ordering(ds)
        self.own = [self.minv, self.f_int, self.du, self.good_u, self.good_v]


class ExplicitSolver:
    """Central-difference integrator of a :class:`~masonry_fdem.model.Model` and the dof
    sets its interactions bring (disks, anchor bars).

    Args:
        model: the model to advance (its ``u`` and ``v`` are the state).
        dt: time step [s]; by default ``safety`` times the critical step.
        safety: fraction of the critical step used when ``dt`` is None.
        damping: mass-proportional damping coefficient α [1/s] (f_damp = α M v), on every
            dof set.
        local_damping: Cundall's local non-viscous damping, for quasi-static runs of
            granular fill: each free dof's unbalanced force g is reduced by
            α |g| sign(v), α ∈ [0, 1) (0.7 is usual); one α for every dof set, or α per
            dof-set name (e.g. ``{"disks": 0.7, "disk_rotations": 0.7}``, others 0).
            Its work counts as damping energy. It makes the stiffest mode up to 1 + α
            stiffer (where the velocity opposes the force), so the critical time step is
            divided by √(1 + α) of the largest α.
        load_factor: factor on the live loads (constant, or a function of time).
        interactions: what acts between blocks, disks and anchors: one
            :class:`~masonry_fdem.interactions.protocol.Interaction` or a sequence of them
            (contact, joints, disks, disk–block contact, anchors, a user's), or None.
            Their bounds enter the stable time step.

    Raises:
        UnstableTimeStepError: ``dt`` exceeds the critical time step.
    """

    def __init__(
        self,
        model,
        dt: float | None = None,
        *,
        safety: float = DT_SAFETY,
        damping: float = 0.0,
        local_damping: float | Mapping[str, float] = 0.0,
        load_factor: float | Callable[[float], float] = 1.0,
        interactions: Interaction | Sequence[Interaction] | None = None,
    ):
        self.model = model
        self.interactions = as_interactions(interactions)
        owned = owned_dofsets(self.interactions)
        names = {BLOCKS, *owned}
        alpha = (dict(local_damping) if isinstance(local_damping, Mapping)
                 else dict.fromkeys(names, local_damping))
        if set(alpha) - names:
            raise ValueError(f"local_damping: no dof set {sorted(set(alpha) - names)}; "
                             f"have {sorted(names)}")
        for name, a in alpha.items():
            if not 0.0 <= a < 1.0:
                raise ValueError(f"local damping must lie in [0, 1), got {a} for {name!r}")
        alpha = {k: float(a) for k, a in alpha.items()}
        self.names = _unique_names(self.interactions)
        w2, gamma = stability_terms(self.interactions, owned, self.names)
        w2[BLOCKS] = {"elements": model.stable_omega2(), **w2[BLOCKS]}
        # local damping stiffens a mode whose velocity opposes its force (the highest
        # one, alternating each step) by up to 1 + α: the critical step shrinks by √(1 + α)
        a_max = max(alpha.values(), default=0.0)
        #: the critical step of each dof set and its terms (:class:`StableStep`)
        self.stability = {
            name: StableStep(w2[name], gamma[name], a_max,
                             damped_step(sum(w2[name].values()), sum(gamma[name].values()))
                             / np.sqrt(1.0 + a_max))
            for name in (BLOCKS, *owned)}
        self.dt_critical = min(st.dt for st in self.stability.values())
        if dt is None:
            if not 0 < safety <= 1:
                raise ValueError(f"time-step safety factor must be in (0, 1], got {safety}")
            dt = safety * self.dt_critical
        elif not (np.isfinite(dt) and dt > 0):
            raise ValueError(f"time step must be > 0 s, got {dt}")
        elif dt > self.dt_critical:
            raise UnstableTimeStepError(
                f"time step {dt:.6g} s exceeds the stable time step "
                f"{self.dt_critical:.6g} s (of the blocks, interactions and dampers: "
                + "; ".join(f"{k}: {v}" for k, v in self.stability.items()) + ")"
            )
        if damping < 0:
            raise ValueError(f"damping must be >= 0 1/s, got {damping}")
        self.dt = float(dt)
        self.damping = float(damping)
        self.load_factor = load_factor
        self.t = 0.0
        self.n = 0
        self.presc, self.vp = model.prescribed_arrays(0.0)
        self._timed = [p for p in model.prescriptions if p.time_dependent]
        self.f_ext = model.external_force(self._factor(0.0))
        self.reaction = np.zeros_like(self.f_ext)
        self.f_con = np.zeros_like(self.f_ext)
        self.sets = [_Set(BLOCKS, model.u.x.array, model.v, model.f_int, self.f_ext,
                          self.f_con, model.mass, self.presc, self.vp, self.reaction, False,
                          {})]
        for ds in owned.values():
            self.sets.append(_Set(ds.name, ds.u, ds.v, np.zeros_like(ds.u), ds.f_ext, ds.f,
                                  ds.mass, ds.presc, ds.vp, ds.reaction, ds.replicated,
                                  ds.prescriptions, ds))
        for s in self.sets:
            s.local = alpha.get(s.name, 0.0)
        self.kinetic0 = sum(self._kinetic(s) for s in self.sets)
        # the account's values at the start, taken in the first step (_StartValues)
        self._start: _StartValues | None = None
        u = {s.name: s.u for s in self.sets}
        v = {s.name: s.v for s in self.sets}
        # each interaction adds into arrays of its own, so the work of its forces is known
        # (a single one adds into the totals directly)
        self._own = len(self.interactions) > 1
        self._states = [State(u, v, {s.name: np.zeros_like(s.u) if self._own else s.f_con
                                     for s in self.sets}, self.dt, True)
                        for _ in self.interactions]
        # work of each interaction's forces on the distributed and on the replicated sets
        self.work = np.zeros((2, len(self.interactions)))
        # owned sets whose owner may permute them, with the per-dof arrays to move along
        self._ordered = [(s, s.own + [st.f[s.name] for st in self._states
                                      if st.f[s.name] is not s.f_con])
                         for s in self.sets[1:]]
        if model.comm.rank == 0:
            log.info(
                "explicit: dt = %.4g s (critical %.4g s, safety %.3g)",
                self.dt, self.dt_critical, self.dt / self.dt_critical,
            )
            for name, st in self.stability.items():
                log.info("explicit: stable step of %s: %s", name, st)

    def _kinetic(self, s: _Set) -> float:
        ke = 0.5 * float(np.dot(s.mass * s.v, s.v))
        return ke if s.replicated else self.model.comm.allreduce(ke)

    def _factor(self, t: float) -> float:
        lf = self.load_factor
        return float(lf(t)) if callable(lf) else float(lf)

    def _follow_orders(self) -> None:
        """Move the solver's own per-dof arrays after an owner permuted its dof set (the
        disks sorting themselves at a rebuild; checked after every ``update``)."""
        for s, arrays in self._ordered:
            s.ordering.follow(arrays)

    def step(self) -> None:
        """Advance one time step (collective)."""
        m = self.model
        self._follow_orders()
        t_half = self.t + 0.5 * self.dt
        for p in self._timed:
            self.vp[p.dofs] = p.value(t_half)
        if callable(self.load_factor):
            m.external_force(self._factor(self.t), out=self.f_ext)
        m.qstate.t_rate = self.dt  # rate-dependent laws see the physical step
        m.internal_force(self.model.f_int)
        for s in self.sets:
            s.f_con.fill(0.0)
        for c, st in zip(self.interactions, self._states, strict=True):
            if self._own:
                for s in self.sets:
                    st.f[s.name].fill(0.0)
            c.update(st)
            self._follow_orders()
            c.add_forces(st)
            if self._own:
                for s in self.sets:
                    s.f_con += st.f[s.name]
            c.commit()
        m.commit_state()
        if self._start is None:
            self._start = self._start_values()
        one = len(self.interactions) == 1  # its forces are f_con: the step sums its work
        for s in self.sets:
            w = K.central_difference_step(s.u, s.v, s.f_int, s.f_ext, s.f_con, s.mass,
                                          s.minv, s.presc, s.vp, self.damping, self.dt,
                                          s.reaction, s.energy, s.du, s.local)
            if one:
                self.work[int(s.replicated), 0] += w
        if self._own:
            for k, st in enumerate(self._states):
                for s in self.sets:
                    self.work[int(s.replicated), k] += K.dot(st.f[s.name], s.du)
        self.t += self.dt
        self.n += 1

    def run(
        self,
        *,
        t_end: float | None = None,
        steps: int | None = None,
        every: int = 100,
        callback: Callable[[ExplicitSolver], None] | None = None,
        until: Callable[[ExplicitSolver], bool] | None = None,
        checkpoint: Checkpointer | None = None,
    ) -> int:
        """Advance to time ``t_end`` [s] or by ``steps`` steps.

        ``callback(solver)`` is called every ``every`` steps and at the end (history,
        output, progress). ``until(solver)``, called after it, stops the run early when it
        returns True (e.g. ``lambda s: disks.unbalanced_ratio() < 1e-3``; it must return
        the same on every rank). A NaN or infinite state stops the run with
        FloatingPointError; the last good state (checked every ``every`` steps) is restored
        in the model.

        ``checkpoint`` (a :class:`~masonry_fdem.io.checkpoint.Checkpointer`): every
        ``every`` steps is a safe point where it writes the complete state when its own
        count is due (``solver.n`` a multiple of ``checkpoint.every``) or a signal asked
        to stop — then the run raises :class:`~masonry_fdem.io.checkpoint.Interrupted`.
        A run resumed with :meth:`resume` from such a checkpoint (``every`` the same, the
        checkpoint's step a multiple of it) and run to the same end gives the same state
        bit for bit.

        Returns:
            The number of steps taken.
        """
        if (t_end is None) == (steps is None):
            raise ValueError("give exactly one of t_end or steps")
        if steps is None:
            steps = max(0, int(np.ceil((t_end - self.t) / self.dt - 1e-9)))
        for s in self.sets:
            s.good_u[:] = s.u
            s.good_v[:] = s.v
        good_t = self.t
        t0 = time.perf_counter()
        for k in range(1, steps + 1):
            self.step()
            if k % every == 0 or k == steps:
                if not self._finite():
                    for s in self.sets:
                        s.u[:] = s.good_u
                        s.v[:] = s.good_v
                    bad_t, self.t = self.t, good_t
                    raise FloatingPointError(
                        f"non-finite displacement or velocity at t = {bad_t:.6g} s "
                        f"(step {self.n}); the state at t = {good_t:.6g} s is kept"
                    )
                for s in self.sets:
                    s.good_u[:] = s.u
                    s.good_v[:] = s.v
                good_t = self.t
                if callback is not None:
                    callback(self)
                if until is not None and until(self):
                    steps = k
                    break
                if checkpoint is not None:
                    checkpoint.safe_point(self.n, self.checkpoint_state)
        log.debug("explicit: %d steps in %.3f s", steps, time.perf_counter() - t0)
        return steps

    # ------------------------------------------------------------------ checkpoints
    def checkpoint_state(self) -> dict:
        """This rank's complete state (copies): time [s], step count, every dof set's
        arrays and energy account, the interactions' and the model's states."""
        return {
            "solver": "explicit", "t": self.t, "n": self.n, "dt": self.dt,
            "kinetic0": self.kinetic0, "start": self._start, "work": self.work.copy(),
            "sets": [{k: getattr(s, k).copy() for k in
                      ("u", "v", "energy", "du", "reaction", "vp", "f_ext")}
                     for s in self.sets],
            "model": model_state(self.model),
            "interactions": interactions_state(self.interactions),
        }

    def set_checkpoint_state(self, st: Mapping) -> None:
        """Take a state of :meth:`checkpoint_state` (collective)."""
        if st.get("solver") != "explicit":
            raise ValueError(f"not an explicit solver's state ({st.get('solver')!r})")
        if st["dt"] != self.dt:
            raise ValueError(f"the state's time step {st['dt']:.6g} s is not this solver's "
                             f"{self.dt:.6g} s")
        set_solver_sets_state(self, st)
        self.t, self.n = float(st["t"]), int(st["n"])
        self.kinetic0 = st["kinetic0"]
        self._start = st["start"]
        self.work[...] = st["work"]

    def resume(self, checkpoint: Checkpointer) -> int:
        """Take the current checkpoint of ``checkpoint`` (collective; the solver built as
        for the run that wrote it, on as many ranks).

        Returns:
            The step count reached (:attr:`n`).

        Raises:
            CheckpointError: none, corrupt, or written by another number of ranks.
        """
        _, st = checkpoint.read()
        self.set_checkpoint_state(st)
        return self.n

    def _finite(self) -> bool:
        ok = all(bool(np.isfinite(s.energy[K.E_KINETIC]) and np.isfinite(s.v).all())
                 for s in self.sets)
        return bool(self.model.comm.allreduce(ok, op=MPI.LAND))

    def _half_step_work(self) -> np.ndarray:
        """½ dt f·v of the internal force (entry 0) and of each interaction's forces,
        over every dof set and rank (collective): the forces' work over the half step
        u(n) → u(n+1) after a step (v is v(n+½)), or u(−1) → u(0) in the first one
        before the update (v is v(−½))."""
        n = len(self.interactions)
        parts = np.zeros((2, n + 1))
        b = self.sets[0]
        parts[0, 0] = K.dot(b.f_int, b.v)
        for k, st in enumerate(self._states):
            for s in self.sets:
                parts[int(s.replicated), k + 1] += K.dot(st.f[s.name], s.v)
        total = self.model.comm.allreduce(parts[0]) + parts[1]
        return 0.5 * self.dt * total

    def _start_values(self) -> _StartValues:
        """The account at the start, in the first step after the forces at u(0) and the
        commit (collective): the stored energies at u(0) carried back to the half step
        before by their forces' work over u(−1) → u(0), and the dissipations so far (the
        first step's included, as its work is excluded)."""
        lag = self._half_step_work()
        own = [dict(c.energies()) for c in self.interactions]
        return _StartValues(
            strain=self.model.strain_energy() - lag[0],
            elements=self.model.element_dissipation(),
            stored=[float(e.get("stored", 0.0)) + lag[k + 1] for k, e in enumerate(own)],
            dissipated=own)

    def _strain_before_step(self) -> float:
        """The blocks' strain energy at u(n), where the last internal forces were
        evaluated (u(n+1) − dt v(n+½); collective)."""
        u = self.model.u.x.array
        saved = u.copy()
        u -= self.dt * self.model.v
        try:
            return self.model.strain_energy()
        finally:
            u[:] = saved

    def energies(self) -> EnergyAccount:
        """The energy account over every dof set, summed over ranks, with each
        interaction's own energies (collective; see :class:`EnergyAccount`)."""
        comm = self.model.comm
        e = np.zeros(K.N_ENERGY)
        for s in self.sets:
            if not s.replicated:
                e += s.energy
        e = comm.allreduce(e)
        for s in self.sets:
            if s.replicated:
                e = e + s.energy
        if self._start is None:  # no step yet: the kinetic energy is the initial one
            e[K.E_KINETIC] = self.kinetic0
        bal = (
            e[K.E_KINETIC] + e[K.E_INTERNAL] + e[K.E_DAMPING]
            - e[K.E_EXTERNAL] - e[K.E_SUPPORT] - e[K.E_CONTACT] - self.kinetic0
        )
        work = comm.allreduce(self.work[0].copy()) + self.work[1]  # replicated: once
        m = self.model
        own = [dict(c.energies()) for c in self.interactions]
        start = self._start
        if start is None:  # no step yet: the state as it is, no work done
            lag = np.zeros(len(self.interactions) + 1)
            strain = m.strain_energy()
            start = _StartValues(strain=strain, elements=m.element_dissipation(),
                                 stored=[float(en.get("stored", 0.0)) for en in own],
                                 dissipated=own)
        else:
            lag = self._half_step_work()
            strain = self._strain_before_step() + lag[0]
        stored = {"strain": strain}
        dissipated = {"elements": m.element_dissipation() - start.elements}
        per, unaccounted = {}, 0.0
        for k, (name, en, w) in enumerate(zip(self.names, own, work, strict=True)):
            held = float(en.get("stored", 0.0)) - lag[k + 1]
            before = start.dissipated[k]
            lost = float(en.get("dissipated", 0.0)) - float(before.get("dissipated", 0.0))
            stored[name] = held
            dissipated.update(_mechanisms(name, en, before, lost))
            en["work"] = float(w)
            en["unaccounted"] = float(w) + held + lost - start.stored[k]
            unaccounted += en["unaccounted"]
            per[name] = en
        initial = self.kinetic0 + start.strain + sum(start.stored)
        residual = (e[K.E_KINETIC] + sum(stored.values()) + sum(dissipated.values())
                    + e[K.E_DAMPING] - e[K.E_EXTERNAL] - e[K.E_SUPPORT] - initial)
        return EnergyAccount(
            kinetic=float(e[K.E_KINETIC]), internal=float(e[K.E_INTERNAL]),
            external=float(e[K.E_EXTERNAL]), damping=float(e[K.E_DAMPING]),
            support=float(e[K.E_SUPPORT]), contact=float(e[K.E_CONTACT]),
            balance=float(bal), interactions=per, unaccounted=float(unaccounted),
            stored={k: float(v) for k, v in stored.items()},
            dissipated={k: float(v) for k, v in dissipated.items()},
            initial=float(initial), residual=float(residual),
            exchanged=float(e[K.E_EXCHANGED]),
        )

    def reactions(self) -> dict[str, np.ndarray]:
        """Total reaction force (Rx, Ry) [N] of each prescription (collective)."""
        out = {}
        for p in self.model.prescriptions:
            r = np.zeros(2)
            np.add.at(r, p.components, self.reaction[p.dofs])
            out[p.name] = self.model.comm.allreduce(r)
        for s in self.sets[1:]:
            for name, dofs in s.prescriptions.items():
                out[name] = s.reaction[dofs].copy()
        return out


@dataclass(frozen=True)
class _StartValues:
    """The energy account at the start of a run (see ``ExplicitSolver._start_values``):
    strain and each interaction's stored energy at the half step before the first,
    the elements' dissipation, and each interaction's own energies, at the start."""

    strain: float
    elements: float
    stored: list[float]
    dissipated: list[dict[str, float]]


def _mechanisms(name: str, now: Mapping[str, float], before: Mapping[str, float],
                lost: float) -> dict[str, float]:
    """An interaction's dissipation in the run by mechanism: its details (keys ending
    in ``_dissipated`` or ``_loss``, e.g. the contact's friction and damper) when there
    are two or more and they add up to its total, else the total under its name."""
    keys = [k for k in now if k != "dissipated" and k.endswith(("_dissipated", "_loss"))]
    parts = {k: float(now[k]) - float(before.get(k, 0.0)) for k in keys}
    if len(parts) >= 2 and abs(sum(parts.values()) - lost) <= 1e-9 * max(1.0, abs(lost)):
        return {f"{name} {k.removesuffix('_dissipated').removesuffix('_loss')}": v
                for k, v in parts.items()}
    return {name: lost}


def _unique_names(interactions: list[Interaction]) -> list[str]:
    """The interactions' names, numbered where one repeats ("contact", "contact#2")."""
    names: list[str] = []
    for c in interactions:
        base = str(c.name)
        name, k = base, 1
        while name in names:
            k += 1
            name = f"{base}#{k}"
        names.append(name)
    return names
