"""Repairs: grouted steel anchors embedded in the masonry, with bond–slip and prestress."""

from masonry_fdem.interactions.anchors.anchors import Anchor, Anchors, BondLaw, DowelLaw
from masonry_fdem.interactions.anchors.anchors import SteelLaw, straight_anchor, wall_ties

__all__ = ["Anchor", "Anchors", "BondLaw", "DowelLaw", "SteelLaw", "straight_anchor",
           "wall_ties"]


def precompile() -> None:
    """Compile and cache the anchor kernels."""
    from masonry_fdem.interactions.anchors import _kernels

    _kernels.precompile()
