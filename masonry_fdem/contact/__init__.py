"""Contact between blocks: ADT broad phase, facet-to-facet penalty narrow phase."""

from masonry_fdem.contact.adt import ADTree, build_adt, inflate, query_adt, self_pairs
from masonry_fdem.contact.penalty import BlockContact, ContactSettings, restitution_damping_ratio

__all__ = [
    "ADTree",
    "BlockContact",
    "ContactSettings",
    "build_adt",
    "inflate",
    "query_adt",
    "restitution_damping_ratio",
    "self_pairs",
]
