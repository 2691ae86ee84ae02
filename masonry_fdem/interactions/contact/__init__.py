"""Facet-to-facet penalty contact between blocks with Coulomb friction."""

from masonry_fdem.interactions.contact.penalty import (
    BlockContact,
    ContactSettings,
    restitution_damping_ratio,
)

__all__ = ["BlockContact", "ContactSettings", "restitution_damping_ratio"]
