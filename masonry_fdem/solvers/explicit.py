"""Explicit central-difference time integration with lumped mass.

One step (DESIGN.md): internal forces from the dolfinx form at ``u(n)``, external loads,
then one numba kernel updates velocities and displacements, overwrites prescribed dofs,
computes support reactions and accumulates the energy account. Nothing is allocated in
the step.

The time step is ``safety · 2/ω_max`` with ω_max bounded by the largest element eigenvalue
of the linear stiffness with lumped mass; it is reported, and a user time step above the
critical one is refused.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from dataclasses import dataclass

from mpi4py import MPI

import numpy as np

from masonry_fdem.constants import DT_SAFETY
from masonry_fdem.solvers import _kernels as K
from masonry_fdem.solvers._interactions import as_interactions

__all__ = ["ExplicitSolver", "EnergyAccount", "UnstableTimeStepError"]

log = logging.getLogger(__name__)


class UnstableTimeStepError(ValueError):
    """A requested time step exceeds the critical one."""


@dataclass(frozen=True)
class EnergyAccount:
    """Energies [J] since the start of the run (global over ranks).

    ``balance`` = kinetic + internal + damping − external − support − contact − initial
    kinetic, zero up to round-off for the central-difference identity; ``internal`` is the
    work done against the internal forces, i.e. the strain energy for an elastic body;
    ``contact`` is the work done BY the contact forces (minus the stored penalty energy and
    the frictional and contact-damping dissipation).
    """

    kinetic: float
    internal: float
    external: float
    damping: float
    support: float
    contact: float
    balance: float


class ExplicitSolver:
    """Central-difference integrator of a :class:`~masonry_fdem.model.Model`.

    Args:
        model: the model to advance (its ``u`` and ``v`` are the state).
        dt: time step [s]; by default ``safety`` times the critical step.
        safety: fraction of the critical step used when ``dt`` is None.
        damping: mass-proportional damping coefficient α [1/s] (f_damp = α M v).
        load_factor: factor on the live loads (constant, or a function of time).
        contact: a :class:`~masonry_fdem.interactions.BlockContact`, the bonded
            :class:`~masonry_fdem.interactions.Joints`, a sequence of them, or None (blocks do not
            interact). Their springs are included in the stable time step.
        disks: a :class:`~masonry_fdem.interactions.disks.Disks` set (granular fill) advanced by the same
            step, with its couplings to the blocks; its contact springs bound the step too.
        anchors: the :class:`~masonry_fdem.interactions.anchors.Anchors` of the model (repairs): their
            bar nodes are advanced by the same step; their springs bound the step.

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
        load_factor: float | Callable[[float], float] = 1.0,
        contact=None,
        disks=None,
        anchors=None,
    ):
        self.model = model
        self.contact = contact
        self.interactions = as_interactions(contact)
        self.anchors = anchors
        if anchors is not None:
            self.interactions.append(anchors)
        self.disks = disks
        self.dt_critical = model.stable_time_step(
            extra_omega2=sum(c.stable_omega2() for c in self.interactions)
        )
        if disks is not None:
            w2 = disks.stable_omega2() + sum(c.stable_omega2() for c in disks.couplings)
            self.dt_critical = min(self.dt_critical, 2.0 / np.sqrt(w2))
        if dt is None:
            if not 0 < safety <= 1:
                raise ValueError(f"time-step safety factor must be in (0, 1], got {safety}")
            dt = safety * self.dt_critical
        elif not (np.isfinite(dt) and dt > 0):
            raise ValueError(f"time step must be > 0 s, got {dt}")
        elif dt > self.dt_critical:
            raise UnstableTimeStepError(
                f"time step {dt:.6g} s exceeds the stable time step "
                f"{self.dt_critical:.6g} s (2/omega_max of the blocks)"
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
        self.energy = np.zeros(K.N_ENERGY)
        self.kinetic0 = model.kinetic_energy()
        if model.comm.rank == 0:
            log.info(
                "explicit: dt = %.4g s (critical %.4g s, safety %.3g)",
                self.dt, self.dt_critical, self.dt / self.dt_critical,
            )

    def _factor(self, t: float) -> float:
        lf = self.load_factor
        return float(lf(t)) if callable(lf) else float(lf)

    def step(self) -> None:
        """Advance one time step (collective only through the model's assembly)."""
        m = self.model
        t_half = self.t + 0.5 * self.dt
        for p in self._timed:
            self.vp[p.dofs] = p.value(t_half)
        if callable(self.load_factor):
            m.external_force(self._factor(self.t), out=self.f_ext)
        m.qstate.t_rate = self.dt  # rate-dependent laws see the physical step
        m.internal_force(self.model.f_int)
        if self.interactions:
            self.f_con.fill(0.0)
            for c in self.interactions:
                c.update_neighbours(m.v, self.dt)
                c.add_forces(self.f_con, m.v, self.dt)
                if hasattr(c, "commit"):
                    c.commit()
        d = self.disks
        if d is not None:
            d.compute_forces(self.dt)
            if d.couplings:
                if not self.interactions:
                    self.f_con.fill(0.0)
                for c in d.couplings:
                    c.add_forces(self.f_con, m.v, self.dt)
        m.commit_state()
        K.central_difference_step(
            m.u.x.array, m.v, m.f_int, self.f_ext, self.f_con, m.mass, m.minv, self.presc,
            self.vp, self.damping, self.dt, self.reaction, self.energy,
        )
        if d is not None:
            d.advance(self.dt, self.damping)
        if self.anchors is not None:
            a = self.anchors
            a.advance(self.dt, self.damping)
        self.t += self.dt
        self.n += 1

    def run(
        self,
        *,
        t_end: float | None = None,
        steps: int | None = None,
        every: int = 100,
        callback: Callable[[ExplicitSolver], None] | None = None,
    ) -> None:
        """Advance to time ``t_end`` [s] or by ``steps`` steps.

        ``callback(solver)`` is called every ``every`` steps and at the end (history,
        output, progress). A NaN or infinite state stops the run with FloatingPointError;
        the last good state (checked every ``every`` steps) is restored in the model.
        """
        if (t_end is None) == (steps is None):
            raise ValueError("give exactly one of t_end or steps")
        if steps is None:
            steps = max(0, int(np.ceil((t_end - self.t) / self.dt - 1e-9)))
        good_u = self.model.u.x.array.copy()
        good_v = self.model.v.copy()
        good_t = self.t
        t0 = time.perf_counter()
        for k in range(1, steps + 1):
            self.step()
            if k % every == 0 or k == steps:
                if not self._finite():
                    self.model.u.x.array[:] = good_u
                    self.model.v[:] = good_v
                    bad_t, self.t = self.t, good_t
                    raise FloatingPointError(
                        f"non-finite displacement or velocity at t = {bad_t:.6g} s "
                        f"(step {self.n}); the state at t = {good_t:.6g} s is kept"
                    )
                good_u[:] = self.model.u.x.array
                good_v[:] = self.model.v
                good_t = self.t
                if callback is not None:
                    callback(self)
        log.debug("explicit: %d steps in %.3f s", steps, time.perf_counter() - t0)

    def _finite(self) -> bool:
        ok = bool(np.isfinite(self.energy[K.E_KINETIC]) and np.isfinite(self.model.v).all())
        if self.anchors is not None:
            ok = ok and bool(np.isfinite(self.anchors.v).all())
        return bool(self.model.comm.allreduce(ok, op=MPI.LAND))

    def energies(self) -> EnergyAccount:
        """The energy account, summed over ranks (collective)."""
        e = self.model.comm.allreduce(self.energy.copy())
        bal = (
            e[K.E_KINETIC] + e[K.E_INTERNAL] + e[K.E_DAMPING]
            - e[K.E_EXTERNAL] - e[K.E_SUPPORT] - e[K.E_CONTACT] - self.kinetic0
        )
        return EnergyAccount(
            kinetic=float(e[K.E_KINETIC]), internal=float(e[K.E_INTERNAL]),
            external=float(e[K.E_EXTERNAL]), damping=float(e[K.E_DAMPING]),
            support=float(e[K.E_SUPPORT]), contact=float(e[K.E_CONTACT]),
            balance=float(bal),
        )

    def reactions(self) -> dict[str, np.ndarray]:
        """Total reaction force (Rx, Ry) [N] of each prescription (collective)."""
        out = {}
        for p in self.model.prescriptions:
            r = np.zeros(2)
            np.add.at(r, p.components, self.reaction[p.dofs])
            out[p.name] = self.model.comm.allreduce(r)
        if self.anchors is not None:
            a = self.anchors
            for name, dofs in a.prescriptions.items():
                out[name] = a.reaction[dofs].copy()
        return out
