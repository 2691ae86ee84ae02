"""The one protocol between the solvers and everything that acts on the degrees of freedom.

A solver moves *dof sets* (:class:`DofSet`): the block nodes (the model's displacement
field), and the sets an interaction brings along — disk translations and rotations,
anchor bar nodes. It asks every :class:`Interaction` for its forces through a
:class:`State` (the current positions, velocities and force accumulators of every set)
and knows nothing else about it: no ``hasattr``, no branch on the kind of interaction.

Calls a solver makes, and when:

* ``dofsets()`` — once, at set-up: the dof sets this interaction owns (they join the
  unknowns: one central-difference kernel advances every set in the explicit solver, one
  dynamic-relaxation update in DR);
* ``stable_omega2()`` — once, at set-up: its bound of ω² [1/s²] per dof set, added to
  the set's own bound in the stable time step ``2/ω_max``;
* ``stable_damping()`` — once, at set-up: its bound of the rate γ [1/s] of its viscous
  dampers per dof set (the largest eigenvalue of M⁻¹C; default none), added over the
  interactions; the explicit step with the velocity of the half step before is stable
  for ``dt ≤ 4/(√(4ω² + γ²) + γ)`` = ``(2/ω)(√(1 + ζ²) − ζ)`` with ζ = γ/(2ω);
* ``add_rowsum(rows)`` — once, at set-up: Σ_j |K_ij| [N/m] of its springs into the row
  sums of each dof set (dynamic relaxation's fictitious masses);
* ``update(state)`` then ``add_forces(state)`` — at every force evaluation (an explicit
  step, a DR iteration): neighbour lists for the current positions (collective), then
  its forces added into ``state.f`` (collective where it exchanges between ranks);
* ``commit()`` — when the state is accepted (every explicit step, a converged DR
  increment): a provider that keeps a trial state apart from its committed one (joints,
  anchors) accepts it; ``restore()`` — drop the trial state, back to the last commit.
  History that evolves in place (the friction springs of contact and disks) needs
  neither; a solver that may undo a whole increment (dynamic relaxation's load to
  collapse) takes ``state()`` before it and gives it back with ``set_state()``;
* ``energies()`` — its energies [J], global over ranks (collective): ``"stored"``
  (elastic energy held now) and ``"dissipated"`` (since the start), plus any details;
* ``state()`` / ``set_state(s)`` — its complete state as named arrays (checkpoints);
* ``add_tangent(K, state)`` — at a Newton iteration of the static solver, after
  ``update`` and ``add_forces`` at the same state: its consistent tangent −∂f/∂u into the
  :class:`Tangent` collector ``K`` (entries by global dof number; the solver assembles
  them into one PETSc matrix). The default raises ``NotImplementedError``: such an
  interaction can be used by the explicit solver and dynamic relaxation only.

In the static solver the ``State`` is *static*: ``state.v`` holds the displacement since
the last commit and ``dt`` is 1, and every force must be a function of the committed
history and the current displacement alone (backward Euler): a provider whose history
evolves in place (friction springs) starts each evaluation from its committed history.

A user's interaction is a subclass with ``add_forces`` and ``stable_omega2`` (and
``add_rowsum`` to be usable by dynamic relaxation); see ``docs/interactions.md``.

Units: SI (m, N, J, s).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

__all__ = ["BLOCKS", "DofSet", "Interaction", "State", "Tangent"]

BLOCKS = "blocks"  # the name of the block nodes' dof set (the model's displacement)


@dataclass(eq=False)
class DofSet:
    """A set of degrees of freedom advanced by the solvers (flat float64 arrays, views of
    the owner's state, so that the owner sees every update).

    Attributes:
        name: unique name ("disks", "disk_rotations", "anchors", ...).
        u: displacements or positions [m, rad].
        v: velocities [m/s, rad/s].
        mass: lumped mass or rotational inertia of each dof [kg, kg m²] (> 0).
        f: the interaction forces on the set [N, N m] (zeroed and filled by the solver).
        f_ext: applied forces [N] (gravity), constant unless the owner changes them.
        presc: int8 mask of the dofs whose motion is prescribed (held: velocity ``vp``).
        vp: prescribed velocities [m/s].
        reaction: force the prescription applies at each prescribed dof [N] (explicit).
        prescriptions: named groups of prescribed dofs ``{name: (dof_x, dof_y)}``
            (for ``DynamicRelaxation.solve(displacement=...)`` and ``reactions()``).
        replicated: every rank holds the whole set (its sums are not reduced over ranks).
        order: (n,) int64, the original number of the dof stored at each position (the
            identity until the owner permutes the set).
        generation: how many times the owner has permuted the set.

    Permutation. An owner may reorder the storage of its set in place (the disks sort
    themselves in space at neighbour-list rebuilds, so that throughput does not depend on
    the order the user made them in): it calls :meth:`permute`, which moves every array
    of the set (u, v, mass, f, f_ext, presc, vp, reaction, and the dofs named in
    ``prescriptions``) and records the new ``order``. A solver keeping per-dof arrays of
    its own (inverse masses, fictitious velocities, snapshots) compares ``generation``
    with the one it last saw after every ``update()`` (and at the start of a step) and
    moves its arrays the same way (:class:`masonry_fdem.solvers._setup.Ordering`). The
    event is carried by the set, not by an extra protocol call, because the permutation
    is decided inside ``update()`` (at a rebuild) and every solver already calls that;
    ``order`` rather than the last permutation alone is recorded, so a follower that
    missed several events (a restored state) still finds its way with one gather.
    """

    name: str
    u: np.ndarray
    v: np.ndarray
    mass: np.ndarray
    f: np.ndarray
    f_ext: np.ndarray | None = None
    presc: np.ndarray | None = None
    vp: np.ndarray | None = None
    reaction: np.ndarray | None = None
    prescriptions: Mapping[str, np.ndarray] = field(default_factory=dict)
    replicated: bool = True
    order: np.ndarray | None = None
    generation: int = 0

    def __post_init__(self) -> None:
        n = self.u.size
        for key in ("v", "mass", "f"):
            if getattr(self, key).size != n:
                raise ValueError(f"dof set {self.name!r}: {key} has {getattr(self, key).size} "
                                 f"entries for {n} dofs")
        if self.f_ext is None:
            self.f_ext = np.zeros(n)
        if self.presc is None:
            self.presc = np.zeros(n, dtype=np.int8)
        if self.vp is None:
            self.vp = np.zeros(n)
        if self.reaction is None:
            self.reaction = np.zeros(n)
        if self.order is None:
            self.order = np.arange(n, dtype=np.int64)

    def permute(self, perm: np.ndarray) -> None:
        """Reorder the set in place: the dof now stored at position k is the one stored
        at ``perm[k]`` before (every array of the set, the ``prescriptions`` renumbered;
        the owner's own arrays, of which these are views, move with them)."""
        perm = np.asarray(perm, dtype=np.int64)
        n = self.u.size
        if perm.shape != (n,):
            raise ValueError(f"dof set {self.name!r}: a permutation of {n} dofs expected, "
                             f"got shape {perm.shape}")
        seen = set()
        for key in ("u", "v", "mass", "f", "f_ext", "presc", "vp", "reaction", "order"):
            a = getattr(self, key)
            if id(a) not in seen:  # an array given twice moves once
                seen.add(id(a))
                a[...] = a[perm]
        if self.prescriptions:
            new_of_old = np.empty(n, dtype=np.int64)
            new_of_old[perm] = np.arange(n)
            for dofs in self.prescriptions.values():
                dofs[...] = new_of_old[dofs]
        self.generation += 1


class State:
    """What an interaction sees at a force evaluation.

    Attributes:
        u, v, f: per dof-set name (``BLOCKS`` for the block nodes), the flat
            displacements/positions, velocities and force accumulators; an interaction
            adds its forces into ``f`` and writes nothing else.
        dt: the step [s] (1 in dynamic relaxation, where ``v`` is the increment per
            iteration).
        damping: whether velocity-dependent forces act (False in dynamic relaxation).
        static: the static solver's state: ``v`` is the displacement since the last
            commit, ``dt`` is 1, and forces are functions of the committed history and
            the current displacement (see the module doc).
    """

    __slots__ = ("u", "v", "f", "dt", "damping", "static")

    def __init__(self, u: dict[str, np.ndarray], v: dict[str, np.ndarray],
                 f: dict[str, np.ndarray], dt: float, damping: bool, static: bool = False):
        self.u, self.v, self.f = u, v, f
        self.dt = float(dt)
        self.damping = bool(damping)
        self.static = bool(static)


class Tangent:
    """Collects the entries of a consistent tangent by global dof number (COO).

    The static solver numbers every dof of the problem once across ranks: the block
    nodes of each rank, then the dof sets the interactions own (held whole on every rank,
    numbered after rank 0's block dofs). A provider adds −∂f/∂u of its forces with
    :meth:`add`; repeated entries are summed, and an entry whose row another rank owns
    (a pair across ranks) is sent there by PETSc: each entry must be added by ONE rank.

    Attributes:
        index: per dof-set name (``BLOCKS`` and the interactions' sets), the global
            number of each local dof.
        node_dof: per node of the BlockMesh (input numbering, every rank), the global
            number of its x dof (its y dof is the next one): for ghost nodes.
        rank: this rank (a replicated set's entries are added by rank 0 alone).
    """

    def __init__(self, index: Mapping[str, np.ndarray], node_dof: np.ndarray, rank: int = 0):
        self.index = dict(index)
        self.node_dof = node_dof
        self.rank = int(rank)
        self.rows: list[np.ndarray] = []
        self.cols: list[np.ndarray] = []
        self.vals: list[np.ndarray] = []

    def add(self, rows: np.ndarray, cols: np.ndarray, values: np.ndarray) -> None:
        """Add ``values[k]`` to entry (``rows[k]``, ``cols[k]``) (global dof numbers)."""
        rows = np.asarray(rows, dtype=np.int64).ravel()
        cols = np.asarray(cols, dtype=np.int64).ravel()
        values = np.asarray(values, dtype=np.float64).ravel()
        if not rows.size == cols.size == values.size:
            raise ValueError(f"tangent entries: {rows.size} rows, {cols.size} columns, "
                             f"{values.size} values")
        self.rows.append(rows)
        self.cols.append(cols)
        self.vals.append(values)

    def node_dofs(self, input_nodes: np.ndarray) -> np.ndarray:
        """Global dof numbers (x, y interleaved) of BlockMesh nodes by input id."""
        base = self.node_dof[np.asarray(input_nodes, dtype=np.int64)]
        return (base[:, None] + np.arange(2)[None, :]).ravel()

    def coo(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """All entries added so far (rows, columns, values)."""
        if not self.rows:
            z = np.zeros(0, dtype=np.int64)
            return z, z.copy(), np.zeros(0)
        return np.concatenate(self.rows), np.concatenate(self.cols), np.concatenate(self.vals)

    def clear(self) -> None:
        self.rows.clear()
        self.cols.clear()
        self.vals.clear()


class Interaction(ABC):
    """Base of every interaction (see the module docstring for the protocol).

    Subclasses list the attributes that make up their history in ``state_attributes``;
    :meth:`state` and :meth:`set_state` copy them (arrays and scalars).
    """

    name: str = "interaction"
    state_attributes: tuple[str, ...] = ()

    def dofsets(self) -> tuple[DofSet, ...]:
        """The dof sets this interaction owns (none by default)."""
        return ()

    def update(self, state: State) -> None:  # noqa: B027  (optional hook)
        """Prepare for forces at the current positions (neighbour lists; collective)."""

    @abstractmethod
    def add_forces(self, state: State) -> None:
        """Add the forces [N] at the current positions into ``state.f``."""

    def add_tangent(self, K: Tangent, state: State) -> None:
        """Add the consistent tangent −∂f/∂u of its forces at ``state`` into ``K`` (a
        :class:`Tangent`; static solver), after ``add_forces`` at the same state."""
        raise NotImplementedError(f"{type(self).__name__} has no consistent tangent yet")

    @abstractmethod
    def stable_omega2(self) -> dict[str, float]:
        """Bound of ω² [1/s²] this interaction adds, per dof-set name (collective)."""

    def stable_damping(self) -> dict[str, float]:
        """Bound of the rate γ [1/s] of its viscous dampers per dof-set name (the largest
        eigenvalue of M⁻¹C; collective). None by default."""
        return {}

    def add_rowsum(self, rows: Mapping[str, np.ndarray]) -> None:  # noqa: B027
        """Add Σ_j |K_ij| [N/m] of its springs to ``rows[name]`` of each dof set."""

    def energies(self) -> dict[str, float]:
        """``stored`` and ``dissipated`` energy [J] and details, global (collective)."""
        return {"stored": 0.0, "dissipated": 0.0}

    def commit(self) -> None:  # noqa: B027
        """Accept the current (trial) state."""

    def restore(self) -> None:  # noqa: B027
        """Return to the state of the last :meth:`commit` (collective)."""

    def state(self) -> dict[str, np.ndarray]:
        """The complete state as named arrays (copies)."""
        return {k: np.array(getattr(self, k), copy=True) for k in self.state_attributes}

    def set_state(self, state: Mapping[str, np.ndarray]) -> None:
        """Take a state of :meth:`state` (arrays of fixed size are written in place, so
        views such as a dof set's stay valid)."""
        missing = [k for k in self.state_attributes if k not in state]
        if missing:
            raise KeyError(f"{type(self).__name__}: state lacks {missing}")
        for k in self.state_attributes:
            new = np.asarray(state[k])
            cur = getattr(self, k)
            if isinstance(cur, np.ndarray) and cur.shape == new.shape:
                cur[...] = new
            elif isinstance(cur, np.ndarray):
                setattr(self, k, np.array(new, dtype=cur.dtype, copy=True))
            else:
                setattr(self, k, type(cur)(new))
        self._state_changed()

    def _state_changed(self) -> None:  # noqa: B027
        """Hook after :meth:`set_state` (e.g. derived arrays, neighbour lists)."""
