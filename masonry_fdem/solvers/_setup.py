"""What the explicit solver and dynamic relaxation share: the interactions they are given
and the dof sets these bring along."""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence

import numpy as np

from masonry_fdem.interactions.protocol import BLOCKS, DofSet, Interaction

__all__ = ["Ordering", "as_interactions", "damped_step", "owned_dofsets",
           "prescribe_displacements", "stability_terms"]


def as_interactions(interactions: Interaction | Iterable[Interaction] | None
                    ) -> list[Interaction]:
    """None, one interaction, or a sequence of them → a list (each checked)."""
    if interactions is None:
        return []
    items = [interactions] if isinstance(interactions, Interaction) else list(interactions)
    for c in items:
        if not isinstance(c, Interaction):
            raise TypeError(f"{type(c).__name__} is not an Interaction (see "
                            "masonry_fdem.interactions.protocol)")
    if len({id(c) for c in items}) != len(items):
        raise ValueError("an interaction is given twice")
    return items


def owned_dofsets(interactions: list[Interaction]) -> dict[str, DofSet]:
    """The dof sets the interactions own, by name, in their order."""
    sets: dict[str, DofSet] = {}
    for c in interactions:
        for ds in c.dofsets():
            if ds.name == BLOCKS or ds.name in sets:
                raise ValueError(f"two dof sets named {ds.name!r}")
            sets[ds.name] = ds
    return sets


def stability_terms(interactions: list[Interaction], names: Iterable[str],
                    labels: list[str]) -> tuple[dict[str, dict[str, float]],
                                                dict[str, dict[str, float]]]:
    """Per dof-set name, each interaction's ω² bound [1/s²] and damper rate bound γ [1/s]
    by its label (only the non-zero ones; collective)."""
    known = {BLOCKS, *names}
    w2: dict[str, dict[str, float]] = {n: {} for n in known}
    gamma: dict[str, dict[str, float]] = {n: {} for n in known}
    for c, label in zip(interactions, labels, strict=True):
        for kind, terms, bounds in (("ω²", w2, c.stable_omega2()),
                                    ("damper rate", gamma, c.stable_damping())):
            for name, value in bounds.items():
                if name not in known:
                    raise ValueError(f"{type(c).__name__} bounds a dof set {name!r} that no "
                                     f"interaction brings (have {sorted(known)})")
                if not value >= 0:
                    raise ValueError(f"{type(c).__name__}: {kind} bound of {name!r} must "
                                     f"be >= 0, got {value}")
                if value > 0:
                    terms[name][label] = float(value)
    return w2, gamma


def damped_step(omega2: float, gamma: float) -> float:
    """Critical step [s] of central differences with a damper on the velocity of the half
    step before: 4/(√(4ω² + γ²) + γ) = (2/ω)(√(1 + ζ²) − ζ), ζ = γ/(2ω) (ω² [1/s²], γ
    [1/s]); 2/ω without dampers, 2/γ without springs, ∞ with neither."""
    if omega2 <= 0.0 and gamma <= 0.0:
        return float("inf")
    return 4.0 / (np.sqrt(4.0 * omega2 + gamma * gamma) + gamma)


def prescribe_displacements(model, sets, displacement: Mapping[str, Sequence[float | None]]
                            ) -> None:
    """Set prescribed dofs to total displacements [m]: ``{prescription name: (ux, uy)}``
    (``None``: leave that component as it is). A name is the model's prescription or one
    of a dof set's (``sets``: objects with ``u`` and ``prescriptions``, e.g. a pulled
    anchor end)."""
    by_name = {p.name: p for p in model.prescriptions}
    u = model.u.x.array
    for name, val in displacement.items():
        if len(val) != 2:
            raise ValueError(f"displacement of {name!r} needs two components (ux, uy)")
        owner = next((s for s in sets if name in s.prescriptions), None)
        if owner is not None:
            dofs = owner.prescriptions[name]
            for comp in (0, 1):
                if val[comp] is not None:
                    owner.u[dofs[comp]] = float(val[comp])
            continue
        if name not in by_name:
            names = sorted([*by_name, *(n for s in sets for n in s.prescriptions)])
            raise ValueError(f"no prescription named {name!r}; have {names}")
        p = by_name[name]
        for comp in (0, 1):
            if val[comp] is not None:
                u[p.dofs[p.components == comp]] = float(val[comp])


class Ordering:
    """Follows the storage order of a dof set whose owner may permute it
    (:meth:`~masonry_fdem.interactions.protocol.DofSet.permute`): a solver's per-dof
    arrays of its own (not views of the set) are moved the same way by :meth:`follow`.

    Args:
        ds: the dof set (None: a set nobody permutes, e.g. the block nodes).
    """

    __slots__ = ("ds", "generation", "order")

    def __init__(self, ds: DofSet | None):
        self.ds = ds
        self.generation = ds.generation if ds is not None else 0
        self.order = ds.order.copy() if ds is not None else None

    def follow(self, arrays: Iterable[np.ndarray]) -> bool:
        """If the set was permuted since the last call, reorder ``arrays`` (per-dof, in
        the order last seen) in place to the set's order now; True if it was."""
        ds = self.ds
        if ds is None or ds.generation == self.generation:
            return False
        n = self.order.size
        old_pos = np.empty(n, dtype=np.int64)
        old_pos[self.order] = np.arange(n)
        perm = old_pos[ds.order]  # new position k holds what was at perm[k]
        done = set()
        for a in arrays:
            if a is not None and id(a) not in done:
                done.add(id(a))
                a[...] = a[perm]
        self.order[:] = ds.order
        self.generation = ds.generation
        return True
