"""The solvers' view of what acts between blocks (contact, bonded joints)."""

from __future__ import annotations

__all__ = ["as_interactions"]


def as_interactions(contact) -> list:
    """None, one interaction object, or a sequence of them → a list.

    An interaction has ``stable_omega2()``, ``stiffness_rowsum()``,
    ``update_neighbours(v, dt)`` and ``add_forces(f, v, dt, damping)``; one with a state
    to accept also has ``commit()``.
    """
    if contact is None:
        return []
    items = list(contact) if isinstance(contact, list | tuple) else [contact]
    for c in items:
        for name in ("stable_omega2", "stiffness_rowsum", "update_neighbours", "add_forces"):
            if not hasattr(c, name):
                raise TypeError(f"{type(c).__name__} is not a contact or joint object "
                                f"(it has no {name}())")
    return items
