"""Rigid circular discrete elements (disks) for granular fill.

A :class:`Disks` set holds, per disk, the centre x (n, 2) [m], rotation θ [rad], velocity
v (n, 2) [m/s] and angular velocity ω [rad/s] (both at half steps, as the blocks'), radius
r [m], mass m = ρ π r² w [kg] and rotational inertia I = m r²/2 [kg m²] for the
out-of-plane thickness w [m] of the model. Disks are advanced by the same central-difference
step as the blocks.

The set is an :class:`~masonry_fdem.interactions.protocol.Interaction` (disk–disk contact)
that owns two dof sets, ``"disks"`` (centres) and ``"disk_rotations"``, advanced by the
solvers' one integrator with the blocks: ``ExplicitSolver(model, interactions=[disks,
DiskBlockContact(disks, model)])``.

Disk–disk contact is Hertz–Mindlin–Coulomb with hysteretic restitution and optional rolling
resistance (:mod:`masonry_fdem.interactions.disks._kernels`, where the 2D law is stated and
justified). Candidate pairs come from a cell list (disks are nearly monodisperse within a
factor of a few, which a uniform grid serves best), rebuilt when a disk has moved by half
the margin since the last rebuild; the tangential and rolling histories of persisting
pairs are carried over.

Storage order. The contact kernels run over the pair list and read and write the disks
of each pair: when neighbours in space are far apart in memory every pair misses the
cache, and throughput then depended on the order the user made the disks in (0.41–0.78×
LAMMPS's disk-steps per second numbered at random against 0.77–1.10× in spatial order,
``benchmarks/disks.py``). So the set sorts itself: at the first rebuild the solvers
trigger (the first ``update()``) and every ``sort_every``-th rebuild after it, the disks
are stored in the order of the cells of the cell-list grid, row by row (y, then x), and
by x, then y within a cell (:func:`~masonry_fdem.interactions.disks._kernels.cell_order`).
Row-major cells rather than a Morton or Hilbert key: the pair search walks this very
grid, so disk i's neighbours lie in i's own row of cells and the next one — three
sequential streams a hardware prefetcher follows, whose working set (three rows of
cells) stays in L2 up to ~10⁶–10⁷ disks in a square region — and the order costs one
counting sort, no key. Within a cell by position (the id only for coincident centres),
so that the order is a function of the disks themselves, not of their numbering: two
runs of the same disks given in different orders store them alike from the first step
on, and then perform the same operations in the same order — bitwise equal (only the
solver's initial kinetic energy, summed before the first step, differs by round-off).

The sort permutes every per-disk array in place (:meth:`Disks._permute`: those of the two
dof sets through :meth:`DofSet.permute`, which records the event — a ``generation``
counter and the new ``order`` — for the solvers to move their own per-dof arrays, and
r, m, material, ids here) and renumbers the pair list with its friction and rolling
history (:func:`~masonry_fdem.interactions.disks._kernels.carry_history_renumbered`); a
:class:`DiskBlockContact` renumbers its (disk, block) pairs when it sees ``generation``
change. ``Disks(..., sort=False)`` keeps the user's order.

What the user sees. Until the first step the storage order is the user's (set ``v``,
``omega``, :meth:`fix` as before). After it, the per-disk attributes ``x``, ``theta``,
``v``, ``omega``, ``f``, ``torque``, ``r``, ``m``, ``inertia``, ``mat``, ``fixed`` and the
disk numbers in ``pairs`` are in STORAGE order: ``ids[k]`` is the original index (the
position in the arrays given to the constructor) of the disk stored at k, ``slot[i]``
where original disk i is stored, and :meth:`by_id` turns a per-disk array into the user's
numbering. :meth:`fix`, :meth:`contact_counts`, :meth:`save` / :meth:`load` and the disk
output (:class:`~masonry_fdem.io.disk_output.DiskOutput`) speak the user's numbering;
sums over disks (energies, :meth:`cell_stress`, :meth:`bulk_density`, :meth:`weight`)
do not depend on the order.

A fill is brought to rest by ``ExplicitSolver(..., local_damping=0.7)`` (Cundall's local
damping) until :meth:`Disks.unbalanced_ratio` is small; :meth:`Disks.cell_stress` and
:meth:`Disks.bulk_density` then measure the averaged stress and density in a cell.

Parallel runs: every rank holds every disk and computes the disk–disk forces of all of
them identically (the disk state stays replicated, nothing is exchanged); block couplings
are computed by the rank owning the block and summed over ranks.

Units are SI throughout.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from mpi4py import MPI

import numpy as np

from masonry_fdem.constants import G
from masonry_fdem.interactions.disks import _kernels as DK
from masonry_fdem.interactions.protocol import DofSet, Interaction, State

__all__ = ["DiskMaterial", "Disks", "add_disk_rowsum"]


def add_disk_rowsum(rows, k: float, r: np.ndarray) -> None:
    """Add a spring bound k [N/m] to every disk translation and k r² to every rotation."""
    rows["disks"] += k
    rows["disk_rotations"] += k * r * r


@dataclass(frozen=True)
class DiskMaterial:
    """Material of disks.

    Args:
        density: ρ [kg/m³] > 0.
        E: Young's modulus [Pa] > 0 (Hertz contact stiffness).
        nu: Poisson's ratio, -1 < ν < 0.5.
        friction: Coulomb coefficient μ ≥ 0.
        restitution: coefficient of restitution e in (0, 1] of a binary impact.
        rolling_friction: rolling resistance μ_r ≥ 0 (angular fill), 0 for none.
    """

    density: float
    E: float
    nu: float
    friction: float = 0.5
    restitution: float = 0.5
    rolling_friction: float = 0.0

    def __post_init__(self) -> None:
        for name in ("density", "E", "nu", "friction", "restitution", "rolling_friction"):
            value = getattr(self, name)
            if not isinstance(value, numbers.Real) or not math.isfinite(value):
                raise ValueError(f"DiskMaterial.{name} must be a finite number, got {value!r}")
            object.__setattr__(self, name, float(value))
        if self.density <= 0 or self.E <= 0:
            raise ValueError("DiskMaterial: density and E must be > 0")
        if not -1.0 < self.nu < 0.5:
            raise ValueError(f"DiskMaterial: nu must satisfy -1 < nu < 0.5, got {self.nu}")
        if self.friction < 0 or self.rolling_friction < 0:
            raise ValueError("DiskMaterial: friction coefficients must be >= 0")
        if not 0.0 < self.restitution <= 1.0:
            raise ValueError(f"DiskMaterial: restitution must lie in (0, 1], got "
                             f"{self.restitution}")

    def row(self) -> np.ndarray:
        out = np.zeros(DK.N_DPROPS)
        out[DK.P_E], out[DK.P_NU], out[DK.P_MU] = self.E, self.nu, self.friction
        out[DK.P_REST], out[DK.P_MU_ROLL] = self.restitution, self.rolling_friction
        return out


class Disks(Interaction):
    """A set of rigid disks (see the module docstring).

    Args:
        x: (n, 2) centres [m].
        r: (n,) radii [m] > 0.
        materials: material of each material name.
        material: the material name of every disk (one name, or one per disk).
        width: out-of-plane thickness w [m] (that of the model they fill).
        margin: travel allowance of the pair list [m] (default: 0.2 r_min).
        max_overlap: the largest relative overlap δ/r_min expected, which bounds the
            Hertz stiffness in the stable time step (default 0.02).
        comm: MPI communicator (all ranks hold all disks; the disk–disk forces are
            divided among them, see :meth:`add_forces`, so that on several ranks
            whatever reads the pairs' history — :meth:`state`,
            :meth:`pair_forces`, :meth:`contact_counts`, :meth:`cell_stress`,
            :meth:`unbalanced_ratio` — is collective).
        sort: store the disks in cell order from the first step on (see the module
            docstring); False keeps the order given.
        sort_every: sort at every this many pair-list rebuilds (≥ 1), after the first
            one of the run.
    """

    name = "disks"
    state_attributes = ("x", "theta", "v", "omega", "fixed", "pairs", "hist", "work",
                        "rebuilds", "ids")

    def __init__(
        self,
        x: np.ndarray,
        r: np.ndarray,
        materials: Mapping[str, DiskMaterial],
        material: str | Sequence[str],
        *,
        width: float = 1.0,
        margin: float | None = None,
        max_overlap: float = 0.02,
        comm: MPI.Comm = MPI.COMM_WORLD,
        sort: bool = True,
        sort_every: int = 10,
    ):
        x = np.array(x, dtype=float, copy=True)
        r = np.array(r, dtype=float, copy=True).ravel()
        if x.ndim != 2 or x.shape[1] != 2 or x.shape[0] != r.size:
            raise ValueError(f"disk centres must have shape (n, 2) with n = len(r) = {r.size}, "
                             f"got {x.shape}")
        if r.size == 0:
            raise ValueError("no disks given")
        if not (np.all(np.isfinite(x)) and np.all(np.isfinite(r)) and np.all(r > 0)):
            raise ValueError("disk centres must be finite and radii finite and > 0")
        if not (np.isfinite(width) and width > 0):
            raise ValueError(f"width must be > 0 m, got {width}")
        self.names = tuple(materials)
        for name, mat in materials.items():
            if not isinstance(mat, DiskMaterial):
                raise TypeError(f"materials[{name!r}] must be a DiskMaterial")
        names = [material] * r.size if isinstance(material, str) else list(material)
        if len(names) != r.size:
            raise ValueError("give one material name, or one per disk")
        unknown = sorted(set(names) - set(self.names))
        if unknown:
            raise ValueError(f"no DiskMaterial given for {unknown}; have {list(self.names)}")
        self.comm = comm
        self.width = float(width)
        self.n = r.size
        self.x = x
        self.r = r
        lookup = {n: k for k, n in enumerate(self.names)}
        self.mat = np.array([lookup[n] for n in names], dtype=np.int64)
        self.materials = dict(materials)
        rho = np.array([materials[n].density for n in self.names])[self.mat]
        self.m = rho * np.pi * r * r * self.width
        self.inertia = 0.5 * self.m * r * r
        self.theta = np.zeros(self.n)
        self.v = np.zeros((self.n, 2))
        self.omega = np.zeros(self.n)
        self.f = np.zeros((self.n, 2))  # contact forces [N] of the last evaluation
        self.torque = np.zeros(self.n)  # contact torques [N m]
        self.fixed = np.zeros(self.n, dtype=np.int8)
        self._fixed_xy = np.zeros(2 * self.n, dtype=np.int8)
        self.g = np.zeros(2)
        self._weight = np.zeros((self.n, 2))  # m g [N]
        self.props = np.array([materials[n].row() for n in self.names])
        self.table = DK.pair_table(self.props)
        self.margin = 0.2 * float(r.min()) if margin is None else float(margin)
        if not self.margin >= 0:
            raise ValueError("margin must be >= 0 m")
        self.max_overlap = float(max_overlap)
        if int(sort_every) < 1:
            raise ValueError(f"sort_every must be >= 1, got {sort_every}")
        self.sort = bool(sort)
        self.sort_every = int(sort_every)
        self.ids = np.arange(self.n, dtype=np.int64)  # original id of each stored disk
        self.slot = np.arange(self.n, dtype=np.int64)  # storage position of each id
        self.generation = 0  # permutations of the storage so far
        self._sorted_at = None  # the rebuild count at the last sort (None: not yet)
        self._fresh = True  # the first update() rebuilds (and sorts)
        self.pairs = np.empty((0, 2), dtype=np.int64)
        self.hist = np.zeros((0, DK.N_HIST))
        # the neighbour search's buffers: two pair lists and histories used in turn, and
        # its scratch (see _rebuild)
        self._pair_bufs = [np.empty((0, 2), dtype=np.int64) for _ in range(2)]
        self._hist_bufs = [np.empty((0, DK.N_HIST)) for _ in range(2)]
        self._cur = 0
        self._sweep = np.empty((0, 2), dtype=np.int64)
        self._x_ref = self.x.copy()
        self.rebuilds = 0
        self.work = np.zeros(DK.N_WORK)
        # on several ranks: the disks each rank owns in the force evaluation (contiguous
        # shares of the storage order), its scratch and the shares' counts and offsets
        size, rank = comm.size, comm.rank
        self._bounds = np.array([p * self.n // size for p in range(size + 1)], dtype=np.int64)
        self._own = (int(self._bounds[rank]), int(self._bounds[rank + 1]))
        cnt = np.diff(self._bounds)
        self._shares = (2 * cnt, 2 * self._bounds[:-1], cnt, self._bounds[:-1].copy())
        self._fp = np.zeros((self.n, 2)) if size > 1 else np.zeros((0, 2))
        self._tp = np.zeros(self.n) if size > 1 else np.zeros(0)
        self._wp = np.zeros(DK.N_WORK)
        self._hist_stale = False  # rows of pairs skipped by this rank are behind
        self._rebuild(sort=False)
        self._dofsets = (
            DofSet("disks", self.x.reshape(-1), self.v.reshape(-1), np.repeat(self.m, 2),
                   self.f.reshape(-1), f_ext=self._weight.reshape(-1), presc=self._fixed_xy),
            DofSet("disk_rotations", self.theta, self.omega, self.inertia, self.torque,
                   presc=self.fixed),
        )

    # ------------------------------------------------------------------ set-up
    def add_gravity(self, g: Sequence[float] = (0.0, -G)) -> None:
        """Gravity acceleration g [m/s²] on every disk."""
        self.g[:] = np.asarray(g, dtype=float)
        self._weight[:] = self.m[:, None] * self.g[None, :]

    def fix(self, sel: np.ndarray) -> None:
        """Hold the selected disks in place: a boolean mask over the disks or their
        indices, in the user's numbering (the order given to the constructor)."""
        chosen = np.arange(self.n)[np.asarray(sel)]
        self.fixed[self.slot[chosen]] = 1
        self._fixed_xy[:] = np.repeat(self.fixed, 2)

    def by_id(self, a: np.ndarray) -> np.ndarray:
        """A per-disk array in storage order (first axis n: ``x``, ``v``, ``f``, ...)
        as a new array in the user's numbering: row i belongs to original disk i."""
        a = np.asarray(a)
        if a.shape[:1] != (self.n,):
            raise ValueError(f"a per-disk array has {self.n} rows, got shape {a.shape}")
        out = np.empty_like(a)
        out[self.ids] = a
        return out

    @property
    def weight(self) -> float:
        """Total weight |g| Σ m [N] of the free disks."""
        return float(np.linalg.norm(self.g) * self.m[self.fixed == 0].sum())

    def kinetic_energy(self) -> float:
        """½ Σ (m v² + I ω²) [J] at the half step."""
        return float(0.5 * (self.m * (self.v**2).sum(axis=1)).sum()
                     + 0.5 * (self.inertia * self.omega**2).sum())

    # ------------------------------------------------------------------ time step
    def stable_omega2(self, contacts: int = 6) -> dict[str, float]:
        """Bound of ω² [1/s²] of the disk contacts: ``contacts`` (at most per disk) times the
        largest single-contact bound over material pairs, disk–disk and disk–wall, for the
        smallest disk at the overlap ``max_overlap · r_min`` (:func:`pair_omega2` on the
        stiffest, unloading branch)."""
        rmin = float(self.r.min())
        smallest = np.flatnonzero(self.r == rmin)  # the lightest of them: any order
        k = int(smallest[np.argmin(self.m[smallest])])
        m, inertia = float(self.m[k]), float(self.inertia[k])
        d = self.max_overlap * rmin
        w2 = 0.0
        for a in range(len(self.names)):
            for b in range(len(self.names)):
                t = self.table[a, b]
                kn = DK.hertz_stiffness_bound(t[DK.T_ESTAR], rmin, rmin, self.width, d,
                                              t[DK.T_REST])
                w2 = max(w2, DK.pair_omega2(kn, t[DK.T_KAPPA], t[DK.T_MU_ROLL], rmin, rmin,
                                            m, m, inertia, inertia))
                kw = DK.hertz_stiffness_bound(t[DK.T_ESTAR], rmin, math.inf, self.width, d,
                                              t[DK.T_REST])
                w2 = max(w2, DK.pair_omega2(kw, t[DK.T_KAPPA], t[DK.T_MU_ROLL], rmin, rmin,
                                            m, 1e300, inertia, 1e300))
        return {"disks": contacts * w2}

    def add_rowsum(self, rows) -> None:
        """The stiffest spring a disk can feel, ω² m_min [N/m], on every translation, and
        times r² on every rotation (dynamic relaxation's fictitious masses)."""
        add_disk_rowsum(rows, self.stable_omega2()["disks"] * float(self.m.min()), self.r)

    # ------------------------------------------------------------------ interaction
    def dofsets(self) -> tuple[DofSet, ...]:
        """Centres (x, y per disk) and rotations, with weights m g as applied forces."""
        return self._dofsets

    def _rebuild(self, sort: bool = True) -> None:
        """New candidate pairs at the current centres, after sorting the disks if it is
        time to (history carried, renumbered if they moved)."""
        self._sync_hist()
        perm = None
        if sort and self.sort and (self._sorted_at is None
                                   or self.rebuilds - self._sorted_at >= self.sort_every):
            self._sorted_at = self.rebuilds
            perm, same = DK.cell_order(self.x, self.r, self.margin, self.ids)
            if same:
                perm = None
            else:
                self._permute(perm)
        # the pairs and their history go into the buffers the list before last used
        # (kept: allocating them anew cost a fifth of a rebuild at 1e6 disks); the
        # current list, in the other buffers or the caller's arrays, is read meanwhile
        k = 1 - self._cur
        cnt, self._sweep, out = DK.cell_list_pairs_grow(self.x, self.r, self.margin,
                                                       self._sweep, self._pair_bufs[k])
        hbuf = self._hist_bufs[k]
        if hbuf.shape[0] < out.shape[0]:
            hbuf = np.empty((out.shape[0], DK.N_HIST))
        self._pair_bufs[k], self._hist_bufs[k] = out, hbuf
        self._cur = k
        pairs, hist = out[:cnt], hbuf[:cnt]  # every row of hist is written below
        if perm is None:
            DK.carry_history(self.pairs, self.hist, pairs, hist)
        else:
            DK.carry_history_renumbered(self.pairs, self.hist, perm, pairs, hist)
        self.pairs, self.hist = pairs, hist
        self._x_ref[:] = self.x
        self.rebuilds += 1

    def _permute(self, perm: np.ndarray) -> None:
        """Store the disk now at position perm[k] at position k, in every per-disk array
        (the dof sets' through :meth:`DofSet.permute`, which tells the solvers), and
        count the event in ``generation``. The pair list is left to the caller (it still
        holds the old numbers)."""
        dofs, rot = self._dofsets
        dofs.permute((2 * perm[:, None] + np.arange(2)[None, :]).ravel())
        rot.permute(perm)  # theta, omega, inertia, torque, fixed
        for a in (self.r, self.m, self.mat, self._x_ref, self.ids):
            a[...] = a[perm]
        self.slot[self.ids] = np.arange(self.n)
        self.generation += 1

    def rebuild(self) -> None:
        """Find the candidate pairs again now, at the current centres (history carried;
        the disks are sorted first when it is time to)."""
        self._rebuild()
        self._fresh = False

    def update(self, state: State) -> None:
        """Find the candidate pairs again at the first call, and once a disk has moved
        by half the margin (sorting the disks when it is time to)."""
        x = state.u["disks"].reshape(-1, 2)  # a view of self.x
        if self._fresh or DK.max_move(x, self._x_ref) > 0.5 * self.margin:
            self._rebuild()
            self._fresh = False

    def add_forces(self, state: State) -> None:
        """Disk–disk contact forces and torques at the current positions (collective).

        On several ranks each rank computes the pairs touching the disks it owns (a
        contiguous share of the storage order), adds into those disks only — each from
        its pairs in the list's order, so bitwise as one rank would — and the shares are
        gathered on every rank; the energies are summed over the ranks. The history rows
        of the pairs a rank skipped are brought up to date when next read
        (:meth:`_sync_hist`)."""
        x = state.u["disks"].reshape(-1, 2)
        v = state.v["disks"].reshape(-1, 2)
        if self.comm.size == 1:
            DK.disk_disk_forces(x, v, state.v["disk_rotations"], self.r, self.mat,
                                self.table, self.pairs, self.hist, self.width, state.dt,
                                state.f["disks"].reshape(-1, 2), state.f["disk_rotations"],
                                self.work)
            return
        lo, hi = self._own
        fp, tp, wp = self._fp, self._tp, self._wp
        fp[lo:hi] = 0.0
        tp[lo:hi] = 0.0
        wp[:] = 0.0
        DK.disk_disk_forces_range(x, v, state.v["disk_rotations"], self.r, self.mat,
                                  self.table, self.pairs, self.hist, self.width, state.dt,
                                  fp, tp, wp, lo, hi)
        self._hist_stale = True
        c2, d2, c1, d1 = self._shares
        self.comm.Allgatherv(MPI.IN_PLACE, [fp, (c2, d2), MPI.DOUBLE])
        self.comm.Allgatherv(MPI.IN_PLACE, [tp, (c1, d1), MPI.DOUBLE])
        self.comm.Allreduce(MPI.IN_PLACE, wp, op=MPI.SUM)
        state.f["disks"] += fp.reshape(-1)
        state.f["disk_rotations"] += tp
        w = self.work
        for k in (DK.W_EN, DK.W_ET, DK.W_ER):  # stored now
            w[k] = wp[k]
        for k in (DK.W_HYST, DK.W_FRIC, DK.W_ROLL):  # dissipated in the step
            w[k] += wp[k]

    def _sync_hist(self) -> None:
        """Give every rank the history rows of every pair (collective, after a force
        evaluation on several ranks): the rank owning a pair's first disk sends its rows
        (the list is sorted by first disk, so each rank's rows are one block)."""
        if not self._hist_stale:
            return
        starts = np.searchsorted(self.pairs[:, 0], self._bounds)
        n_h = self.hist.shape[1]
        self.comm.Allgatherv(MPI.IN_PLACE, [self.hist, (np.diff(starts) * n_h,
                                                        starts[:-1] * n_h), MPI.DOUBLE])
        self._hist_stale = False

    def state(self) -> dict:
        """The state (:attr:`state_attributes`), the pairs' history brought up to date on
        every rank first (collective on several ranks)."""
        self._sync_hist()
        return super().state()

    def energies(self) -> dict[str, float]:
        """Disk–disk contact energies [J] (every rank holds them all): stored (normal,
        tangential, rolling) and dissipated (restitution, friction, rolling friction)."""
        w = self.work
        stored = float(w[DK.W_EN] + w[DK.W_ET] + w[DK.W_ER])
        lost = float(w[DK.W_HYST] + w[DK.W_FRIC] + w[DK.W_ROLL])
        return {"stored": stored, "dissipated": lost,
                "normal": float(w[DK.W_EN]), "tangential": float(w[DK.W_ET]),
                "rolling": float(w[DK.W_ER]), "restitution_loss": float(w[DK.W_HYST]),
                "friction_loss": float(w[DK.W_FRIC]), "rolling_loss": float(w[DK.W_ROLL])}

    # ------------------------------------------------------------------ measurements
    def pair_forces(self) -> np.ndarray:
        """(k, 2) contact force [N] on disk j of each candidate pair (i, j) of ``pairs``
        (minus that on disk i), at the current centres with the friction history of the
        last force evaluation; zero for pairs apart. ``pairs`` holds storage positions:
        ``ids[pairs]`` are the disks in the user's numbering."""
        self._sync_hist()
        fc = np.zeros((self.pairs.shape[0], 2))
        DK.pair_forces(self.x, self.r, self.mat, self.table, self.pairs, self.hist,
                       self.width, fc)
        return fc

    def contact_counts(self, couplings: Sequence = ()) -> np.ndarray:
        """(n,) number of contacts carrying a force of each disk, in the user's
        numbering: disk–disk, plus those with blocks of the given
        :class:`DiskBlockContact` couplings (collective when couplings are given)."""
        return self.by_id(self._contact_counts(couplings))

    def _contact_counts(self, couplings: Sequence = ()) -> np.ndarray:
        """:meth:`contact_counts` in storage order."""
        count = np.zeros(self.n, dtype=np.int64)
        for c in couplings:
            disk, _, _ = c.disk_contacts()
            count += np.bincount(disk, minlength=self.n)
        if couplings and self.comm.size > 1:
            self.comm.Allreduce(MPI.IN_PLACE, count, op=MPI.SUM)
        DK.count_contacts(self.pairs, self.pair_forces(), count)
        return count

    def unbalanced_ratio(self, couplings: Sequence = ()) -> float:
        """Unbalanced-force ratio of the last force evaluation: mean |m g + f_contact| over
        mean |m g| [-], over the free disks with at least two contacts (rattlers, with none
        or one, are left out); ``couplings`` as :meth:`contact_counts` (collective then).
        Returns inf when no disk has two contacts.

        Raises:
            ValueError: no gravity is applied (:meth:`add_gravity`).
        """
        if not np.any(self.g):
            raise ValueError("the unbalanced-force ratio needs gravity (add_gravity)")
        held = (self._contact_counts(couplings) >= 2) & (self.fixed == 0)
        if not held.any():
            return math.inf
        unbal = np.linalg.norm(self.f[held] + self._weight[held], axis=1).mean()
        return float(unbal / np.linalg.norm(self._weight[held], axis=1).mean())

    def _cell(self, lo, hi) -> tuple[np.ndarray, np.ndarray, float]:
        lo = np.asarray(lo, dtype=float).ravel()
        hi = np.asarray(hi, dtype=float).ravel()
        if lo.size != 2 or hi.size != 2 or not (np.all(np.isfinite(lo))
                                                 and np.all(np.isfinite(hi))):
            raise ValueError(f"a cell is given by two finite corners (x, y) [m], got {lo}, {hi}")
        if not np.all(lo < hi):
            raise ValueError(f"cell corners must satisfy lo < hi, got lo = {lo}, hi = {hi}")
        return lo, hi, float(np.prod(hi - lo))

    def cell_stress(self, lo: Sequence[float], hi: Sequence[float],
                    couplings: Sequence = ()) -> np.ndarray:
        """Average (Love–Weber) stress [Pa] in the rectangular cell [lo, hi) [m]:

            σ_ab = 1/(A w) Σ_p Σ_c f_a (x_c − x_p)_b,

        over the disks p whose CENTRE lies in the cell (whole disks, not clipped), and over
        their contacts c: f the force on p [N], x_c the contact point — the middle of the
        overlap for a disk–disk contact, the kernel's contact point for a disk–block contact
        of the given :class:`DiskBlockContact` couplings (collective then; without them
        wall contacts are not counted, so keep the cell away from blocks). A = cell area
        [m²], w = disk thickness [m]. Tension positive, compression negative (as the
        blocks' stress). Forces are those of the last evaluation (friction history) at the
        current centres. σ is symmetric up to the disks' unbalanced torques; the full
        tensor is returned.

        Returns:
            (2, 2) σ [Pa], rows and columns (x, y).
        """
        lo, hi, area = self._cell(lo, hi)
        out = np.zeros((2, 2))
        for c in couplings:
            disk, f, xc = c.disk_contacts()
            DK.love_sum_points(self.x, disk, f, xc, lo[0], lo[1], hi[0], hi[1], out)
        if couplings and self.comm.size > 1:
            self.comm.Allreduce(MPI.IN_PLACE, out, op=MPI.SUM)
        DK.love_sum_pairs(self.x, self.r, self.pairs, self.pair_forces(), lo[0], lo[1],
                          hi[0], hi[1], out)
        return out / (area * self.width)

    def bulk_density(self, lo: Sequence[float], hi: Sequence[float]) -> float:
        """Bulk density [kg/m³] in the rectangular cell [lo, hi) [m]: the mass of the disks
        whose centre lies in the cell over the cell volume A w (the same disks as
        :meth:`cell_stress`; unbiased for a homogeneous packing, noisy for a cell of few
        disks)."""
        lo, hi, area = self._cell(lo, hi)
        inside = np.all((self.x >= lo) & (self.x < hi), axis=1)
        return float(self.m[inside].sum() / (area * self.width))

    def set_state(self, state) -> None:
        """Take a state of :meth:`state` (checkpoint, dynamic relaxation's restore): the
        storage is first permuted to the state's order (its ``ids``), so that every
        per-disk array, not only those of the state, matches it."""
        ids = np.asarray(state["ids"], dtype=np.int64) if "ids" in state else self.ids
        if not np.array_equal(ids, self.ids):
            if ids.shape != self.ids.shape or not np.array_equal(np.sort(ids),
                                                                 np.arange(self.n)):
                raise ValueError("Disks.set_state: ids is not a permutation of the disks")
            self._permute(self.slot[ids])
        super().set_state(state)

    def _state_changed(self) -> None:
        self._hist_stale = False  # the state's history is every pair's
        self._fixed_xy[:] = np.repeat(self.fixed, 2)
        self._x_ref[:] = self.x
        self.slot[self.ids] = np.arange(self.n)

    def checkpoint_state(self) -> dict:
        """:meth:`state` (in its storage order, ``ids``), the centres [m] at the last
        search for pairs, whether the first search is still to come and the rebuild count
        of the last sort (a resumed run searches and sorts again at the same steps as the
        run would have)."""
        return {**self.state(), "__x_ref": self._x_ref.copy(), "__fresh": bool(self._fresh),
                "__sorted_at": -1 if self._sorted_at is None else int(self._sorted_at)}

    def set_checkpoint_state(self, st) -> None:
        """Take a state of :meth:`checkpoint_state` (the storage permuted to its order)."""
        st = dict(st)
        x_ref = st.pop("__x_ref")
        fresh = st.pop("__fresh", False)
        sorted_at = int(st.pop("__sorted_at", -1))
        self.set_state(st)
        self._x_ref[:] = x_ref
        self._fresh = bool(fresh)
        self._sorted_at = None if sorted_at < 0 else sorted_at

    # ------------------------------------------------------------------ files
    def save(self, path: str | Path) -> None:
        """Write the disks (geometry, materials, state) to an ``.npz`` file (rank 0), in
        the user's numbering (the disks of :meth:`load` are numbered as these)."""
        if self.comm.rank == 0:
            mats = np.array([[*self.materials[n].row(), self.materials[n].density]
                             for n in self.names])
            b = self.by_id
            np.savez(path, x=b(self.x), r=b(self.r), mat=b(self.mat),
                     names=np.array(self.names), mats=mats, theta=b(self.theta), v=b(self.v),
                     omega=b(self.omega), fixed=b(self.fixed), width=self.width)
        self.comm.barrier()

    @classmethod
    def load(cls, path: str | Path, comm: MPI.Comm = MPI.COMM_WORLD, **kw) -> Disks:
        """Read disks written by :meth:`save` (state included)."""
        data = np.load(path, allow_pickle=False)
        names = [str(n) for n in data["names"]]
        mats = {}
        for n, row in zip(names, data["mats"], strict=True):
            mats[n] = DiskMaterial(density=row[-1], E=row[DK.P_E], nu=row[DK.P_NU],
                                   friction=row[DK.P_MU], restitution=row[DK.P_REST],
                                   rolling_friction=row[DK.P_MU_ROLL])
        disks = cls(data["x"], data["r"], mats, [names[k] for k in data["mat"]],
                    width=float(data["width"]), comm=comm, **kw)
        disks.theta[:] = data["theta"]
        disks.v[:] = data["v"]
        disks.omega[:] = data["omega"]
        disks.fix(np.asarray(data["fixed"]) > 0)
        return disks

    def __repr__(self) -> str:
        return (f"Disks({self.n} disks, r = {self.r.min():.3g}..{self.r.max():.3g} m, "
                f"{len(self.names)} material(s), {self.pairs.shape[0]} candidate pairs)")
