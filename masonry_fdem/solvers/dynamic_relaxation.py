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

Load increments scale the live loads; an increment that does not converge within
``max_iter`` iterations is reported as not in equilibrium (collapse in a load-to-collapse run).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from masonry_fdem.solvers import _kernels as K
from masonry_fdem.solvers._interactions import as_interactions

__all__ = ["DynamicRelaxation", "DRResult"]

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
        load_factor: the last load factor with equilibrium (the collapse load factor,
            within ``resolution`` above it, if ``collapsed``).
        resolution: the increment that failed last.
        collapsed: False if ``max_load`` was carried.
        history: the converged load factors, in order.
    """

    load_factor: float
    resolution: float
    collapsed: bool
    history: list[float]


class DynamicRelaxation:
    """Adaptive dynamic relaxation of a :class:`~masonry_fdem.model.Model`.

    Args:
        model: the model (its ``u`` is the unknown; ``v`` is not touched).
        rtol: out-of-balance force tolerance relative to the applied load norm.
        ke_tol: fictitious kinetic energy tolerance relative to its peak in the increment.
        max_iter: iteration limit per load increment.
        mass_safety: α in the fictitious mass bound (≥ 1).
        contact: a :class:`~masonry_fdem.interactions.BlockContact`, the bonded
            :class:`~masonry_fdem.interactions.Joints`, a sequence of them, or None. Their
            springs enter the fictitious masses; their forces (without restitution damping)
            enter the residual; friction slips by the fictitious displacement increments.
            Joint states are trial states computed from the last converged increment and
            committed only when an increment converges. So is the material state of the
            blocks (damage, plastic strain): committed only at a converged increment.
        disks: a :class:`~masonry_fdem.interactions.disks.Disks` set with its block couplings: the disk
            positions and rotations join the unknowns, with fictitious masses from the
            bound of their contact stiffness (the disks' friction histories follow the
            iteration; they are not rolled back).
        anchors: the :class:`~masonry_fdem.interactions.anchors.Anchors` of the model: their bar nodes
            join the unknowns, with fictitious masses from their stiffness row sums; their
            bond and steel states are committed at converged increments only.
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
        contact=None,
        disks=None,
        anchors=None,
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
        _, rowsum = model.element_bounds()
        self.contact = contact
        self.interactions = as_interactions(contact)
        self.anchors = anchors
        if anchors is not None:
            self.interactions.append(anchors)
            a = anchors
            self.am = mass_safety * 0.25 * self.dt**2 * a.rowsum
            self.au0 = np.zeros_like(a.u)
            self.av = np.zeros_like(a.u)
            self.af = np.zeros_like(a.u)
            self.af0 = np.zeros_like(a.u)
            self.afext = np.zeros_like(a.u)
            self._asums = np.zeros(4)
        for c in self.interactions:
            rowsum = rowsum + c.stiffness_rowsum()
        self.mfict = mass_safety * 0.25 * self.dt**2 * rowsum
        if np.any(self.mfict <= 0):
            raise ValueError("a dof has no stiffness: is a node not attached to any element?")
        self.presc, _ = model.prescribed_arrays(0.0)
        self.v = np.zeros_like(model.f_int)
        self.f_int0 = np.zeros_like(model.f_int)
        self._fprev = np.zeros_like(model.f_int)
        self.f_ext = np.zeros_like(model.f_int)
        self.f_net = np.zeros_like(model.f_int)  # f_int − f_contact
        self._sums = np.zeros(6)
        self._vsums = self._sums[4:]  # the velocity quotient's parts
        self.results: list[DRResult] = []
        self.disks = disks
        if disks is not None:
            n = disks.n
            w2 = disks.stable_omega2() + sum(c.stable_omega2() for c in disks.couplings)
            k_bound = w2 * float(disks.m.min())  # the stiffest spring a disk can feel
            self.dm = np.empty(3 * n)
            self.dm.reshape(-1, 3)[:, :2] = (mass_safety * 0.25 * self.dt**2 * k_bound)
            self.dm.reshape(-1, 3)[:, 2] = self.dm[0] * disks.r**2
            self.dq = np.zeros(3 * n)
            self.dq0 = np.zeros(3 * n)
            self.dv = np.zeros(3 * n)
            self.df = np.zeros(3 * n)
            self.df0 = np.zeros(3 * n)
            self.dfext = np.zeros(3 * n)
            self.dpresc = np.repeat(disks.fixed, 3).astype(np.int8)
            self._dsums = np.zeros(4)

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
                sets the prescribed dofs of that prescription (a loading platen) to these
                total displacements (``None``: leave that component as it is).
            dt: the physical duration of the increment [s] seen by rate-dependent
                (Perzyna) laws; None: infinitely slow loading (the rate-independent limit).
        """
        m = self.model
        m.rate_time_step = math.inf if dt is None else dt
        comm = m.comm
        if displacement:
            self.prescribe(displacement)
        m.external_force(load_factor, out=self.f_ext)
        free = self.presc == 0
        ref2 = comm.allreduce(float(np.dot(self.f_ext[free], self.f_ext[free])))
        if self.disks is not None:  # the disks' weights are applied loads too
            dw = self.disks.m[self.disks.fixed == 0]
            ref2 += float(np.dot(dw, dw)) * float(np.dot(self.disks.g, self.disks.g))
        u = m.u.x.array
        u0 = u.copy()
        by_velocity = self.damping == "velocity"
        self.v[:] = 0.0
        d = self.disks
        if d is not None:
            self._pack_disks(self.dq0)
            self.dv[:] = 0.0
        an = self.anchors
        if an is not None:
            self.au0[:] = an.u
            self.av[:] = 0.0
        ke_peak = 0.0
        c = 0.0
        r_norm = math.inf
        ref = math.sqrt(ref2)
        it = 0
        converged = False
        for it in range(1, self.max_iter + 1):
            f_net = self._resisting_force()
            if it == 1:
                self.f_int0[:] = f_net
                if ref == 0.0:
                    ref2 = comm.allreduce(float(np.dot(f_net, f_net)))
                    if an is not None:  # replicated: counted once
                        ref2 += float(np.dot(an.f, an.f))
                    ref = math.sqrt(ref2) or 1.0
            K.dr_measure(u, u0, self.v, f_net, self.f_int0, self.f_ext, self.mfict,
                         self.presc, self._sums)
            if by_velocity:
                K.dr_velocity_quotient(self.v, f_net, self._fprev, self.mfict, self.presc,
                                       it == 1, self._vsums)
            r2, num, den, ke, num_v, den_v = comm.allreduce(self._sums)
            if by_velocity:
                num, den = num_v, den_v
            if d is not None:  # every rank holds every disk: add their share once
                if it == 1:
                    self.df0[:] = self.df
                K.dr_measure(self.dq, self.dq0, self.dv, self.df, self.df0, self.dfext,
                             self.dm, self.dpresc, self._dsums)
                r2 += self._dsums[0]
                if not by_velocity:
                    num += self._dsums[1]
                    den += self._dsums[2]
                ke += self._dsums[3]
            if an is not None:
                np.negative(an.f, out=self.af)
                if it == 1:
                    self.af0[:] = self.af
                K.dr_measure(an.u, self.au0, self.av, self.af, self.af0, self.afext,
                             self.am, an.presc, self._asums)
                r2 += self._asums[0]
                if not by_velocity:
                    num += self._asums[1]
                    den += self._asums[2]
                ke += self._asums[3]
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
            K.dr_update(u, self.v, f_net, self.f_ext, self.mfict, self.presc, c, self.dt,
                        it == 1)
            if d is not None:
                K.dr_update(self.dq, self.dv, self.df, self.dfext, self.dm, self.dpresc, c,
                            self.dt, it == 1)
                self._unpack_disks()
            if an is not None:
                K.dr_update(an.u, self.av, self.af, self.afext, self.am, an.presc, c,
                            self.dt, it == 1)
        if converged:
            m.commit_state()
            for c in self.interactions:
                if hasattr(c, "commit"):
                    c.commit()
        res = DRResult(float(load_factor), converged, it, r_norm, ref)
        self.results.append(res)
        if comm.rank == 0:
            log.info(
                "DR: load factor %.4g %s after %d iterations (|r|/|f| = %.2e)",
                load_factor, "converged" if converged else "NOT converged", it,
                res.relative_residual,
            )
        return res

    def prescribe(self, displacement: Mapping[str, Sequence[float | None]]) -> None:
        """Set prescribed dofs to total displacements [m] (see :meth:`solve`)."""
        by_name = {p.name: p for p in self.model.prescriptions}
        u = self.model.u.x.array
        an = self.anchors
        for name, val in displacement.items():
            if an is not None and name in an.prescriptions:
                an.set_displacement(name, val)
                continue
            if name not in by_name:
                raise ValueError(f"no prescription named {name!r}; have {sorted(by_name)}")
            if len(val) != 2:
                raise ValueError(f"displacement of {name!r} needs two components (ux, uy)")
            p = by_name[name]
            for comp in (0, 1):
                if val[comp] is not None:
                    sel = p.components == comp
                    u[p.dofs[sel]] = float(val[comp])

    def _pack_disks(self, q) -> None:
        d = self.disks
        q3 = q.reshape(-1, 3)
        q3[:, :2] = d.x
        q3[:, 2] = d.theta

    def _unpack_disks(self) -> None:
        d = self.disks
        q3 = self.dq.reshape(-1, 3)
        d.x[:] = q3[:, :2]
        d.theta[:] = q3[:, 2]
        v3 = self.dv.reshape(-1, 3)
        d.v[:] = v3[:, :2]  # displacement increments per iteration (dt = 1)
        d.omega[:] = v3[:, 2]

    def _resisting_force(self) -> np.ndarray:
        """f_int(u) − f_contact(u) [N]: what the applied loads must balance. With disks,
        also their resisting forces −(f, torque) into ``self.df`` (gravity included)."""
        m = self.model
        m.internal_force(m.f_int)
        d = self.disks
        if not self.interactions and (d is None or not d.couplings):
            out = m.f_int
        else:
            np.negative(m.f_int, out=self.f_net)
            for c in self.interactions:
                c.update_neighbours(self.v, self.dt)
                c.add_forces(self.f_net, self.v, self.dt, damping=False)
            out = self.f_net
        if d is not None:
            d.compute_forces(self.dt)
            for c in d.couplings:
                if out is m.f_int:
                    raise RuntimeError("unreachable")
                c.add_forces(self.f_net, self.v, self.dt)
            df3 = self.df.reshape(-1, 3)
            np.negative(d.f, out=df3[:, :2])
            np.negative(d.torque, out=df3[:, 2])
            self._pack_disks(self.dq)
        if out is self.f_net:
            np.negative(self.f_net, out=self.f_net)
        return out

    def snapshot(self) -> dict:
        """The state a non-converged increment may have spoiled: displacements, the
        contact friction history, the anchors' bar nodes (committed material, joint and
        bond states are untouched by an increment that does not converge)."""
        snap = {"u": self.model.u.x.array.copy()}
        for k, c in enumerate(self.interactions):
            if all(hasattr(c, a) for a in ("keys", "tau", "pmax", "rebuild")):
                snap[("contact", k)] = (c.keys.copy(), c.tau.copy(), c.pmax.copy())
        if self.anchors is not None:
            snap["anchors"] = self.anchors.u.copy()
        if self.disks is not None:
            d = self.disks
            snap["disks"] = (d.x.copy(), d.theta.copy())
        return snap

    def restore(self, snap: dict) -> None:
        """Go back to a :meth:`snapshot` (collective: contact neighbour lists are rebuilt)."""
        self.model.u.x.array[:] = snap["u"]
        for k, c in enumerate(self.interactions):
            key = ("contact", k)
            if key in snap:
                c.keys, c.tau, c.pmax = (a.copy() for a in snap[key])
                c.rebuild(np.zeros_like(self.model.v))
        if self.anchors is not None:
            self.anchors.u[:] = snap["anchors"]
        if self.disks is not None:
            self.disks.x[:], self.disks.theta[:] = (a.copy() for a in snap["disks"])

    def load_to_collapse(
        self,
        increment: float,
        *,
        start: float = 0.0,
        max_load: float = math.inf,
        refinements: int = 4,
        callback: Callable[[DRResult], None] | None = None,
    ) -> CollapseResult:
        """Raise the live-load factor in increments until equilibrium is lost.

        From the equilibrium at ``start``, the load factor grows by ``increment``; when an
        increment finds no equilibrium (``max_iter`` reached), the state before it is
        restored and the increment halved, up to ``refinements`` times. The collapse load
        factor lies between the last converged factor and that plus the last increment
        tried (its resolution).

        Returns:
            :class:`CollapseResult` with the converged factors in order.
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
                return CollapseResult(level, trial - level, True, converged)
            halvings += 1
            step *= 0.5
        return CollapseResult(level, step, False, converged)

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
        """Reaction (Rx, Ry) [N] of each prescription: f_int − f_ext at its dofs."""
        m = self.model
        f_net = self._resisting_force()
        out = {}
        for p in m.prescriptions:
            r = np.zeros(2)
            np.add.at(r, p.components, f_net[p.dofs] - self.f_ext[p.dofs])
            out[p.name] = m.comm.allreduce(r)
        if self.anchors is not None:
            out.update(self.anchors.reactions())
        return out
