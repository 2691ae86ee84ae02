"""What the explicit solver and dynamic relaxation share: the interactions they are given
and the dof sets these bring along."""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence

from masonry_fdem.interactions.protocol import BLOCKS, DofSet, Interaction

__all__ = ["as_interactions", "owned_dofsets", "prescribe_displacements", "summed_omega2"]


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


def summed_omega2(interactions: list[Interaction], names: Iterable[str]) -> dict[str, float]:
    """Σ over the interactions of their ω² bounds [1/s²], per dof-set name."""
    known = {BLOCKS, *names}
    w2 = dict.fromkeys(known, 0.0)
    for c in interactions:
        for name, value in c.stable_omega2().items():
            if name not in known:
                raise ValueError(f"{type(c).__name__} bounds a dof set {name!r} that no "
                                 f"interaction brings (have {sorted(known)})")
            if not value >= 0:
                raise ValueError(f"{type(c).__name__}: ω² bound of {name!r} must be >= 0, "
                                 f"got {value}")
            w2[name] += float(value)
    return w2


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
