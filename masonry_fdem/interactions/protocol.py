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
* ``add_tangent(K, state)`` — its consistent tangent ∂f/∂u into a PETSc matrix, for the
  static Newton solver (the next step of the package: not implemented by any provider
  yet; the default raises ``NotImplementedError``).

A user's interaction is a subclass with ``add_forces`` and ``stable_omega2`` (and
``add_rowsum`` to be usable by dynamic relaxation); see ``docs/interactions.md``.

Units: SI (m, N, J, s).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

__all__ = ["BLOCKS", "DofSet", "Interaction", "State"]

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


class State:
    """What an interaction sees at a force evaluation.

    Attributes:
        u, v, f: per dof-set name (``BLOCKS`` for the block nodes), the flat
            displacements/positions, velocities and force accumulators; an interaction
            adds its forces into ``f`` and writes nothing else.
        dt: the step [s] (1 in dynamic relaxation, where ``v`` is the increment per
            iteration).
        damping: whether velocity-dependent forces act (False in dynamic relaxation).
    """

    __slots__ = ("u", "v", "f", "dt", "damping")

    def __init__(self, u: dict[str, np.ndarray], v: dict[str, np.ndarray],
                 f: dict[str, np.ndarray], dt: float, damping: bool):
        self.u, self.v, self.f = u, v, f
        self.dt = float(dt)
        self.damping = bool(damping)


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

    def add_tangent(self, K, state: State) -> None:
        """Add the consistent tangent −∂f/∂u into the PETSc matrix ``K`` (static solver)."""
        raise NotImplementedError(f"{type(self).__name__} has no consistent tangent yet")

    @abstractmethod
    def stable_omega2(self) -> dict[str, float]:
        """Bound of ω² [1/s²] this interaction adds, per dof-set name (collective)."""

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
