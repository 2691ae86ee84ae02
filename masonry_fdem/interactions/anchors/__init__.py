"""Repairs: grouted steel anchors embedded in the masonry, with bond–slip and prestress."""

from masonry_fdem.interactions.anchors.anchors import Anchors, straight_anchor, wall_ties
from masonry_fdem.interactions.anchors.laws import (Anchor, BondLaw, DowelLaw, JointDowel,
                                                     SteelLaw)

__all__ = ["Anchor", "Anchors", "BondLaw", "DowelLaw", "JointDowel", "SteelLaw",
           "straight_anchor", "wall_ties"]


def precompile() -> None:
    """Compile and cache the anchor kernels."""
    from masonry_fdem.interactions.anchors import _kernels

    _kernels.precompile()
