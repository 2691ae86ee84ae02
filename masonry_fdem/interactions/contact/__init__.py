"""Facet-to-facet penalty contact between blocks with Coulomb friction."""

from masonry_fdem.interactions.contact.penalty import (
    BlockContact,
    ContactSettings,
    restitution_damping_ratio,
)

__all__ = ["BlockContact", "ContactSettings", "restitution_damping_ratio"]


def precompile() -> None:
    """Compile and cache the contact kernels."""
    from masonry_fdem.interactions.contact import _kernels

    _kernels.precompile()
