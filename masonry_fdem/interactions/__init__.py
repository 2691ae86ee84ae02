"""Everything that acts between blocks, disks and anchors, behind one protocol.

Layers inside this package (lower ones never import higher ones): ``protocol`` and
``search`` (ADT broad phase) → ``contact`` (facet–facet) → ``joints`` → ``disks`` →
``anchors``. Every provider is an :class:`~masonry_fdem.interactions.protocol.Interaction`;
the solvers call nothing else.
"""

from masonry_fdem.interactions.anchors import Anchor, Anchors, BondLaw, DowelLaw, SteelLaw
from masonry_fdem.interactions.anchors import straight_anchor, wall_ties
from masonry_fdem.interactions.contact import BlockContact, ContactSettings
from masonry_fdem.interactions.contact import restitution_damping_ratio
from masonry_fdem.interactions.disks import DiskBlockContact, DiskMaterial, Disks
from masonry_fdem.interactions.disks import pack_disks, spatial_order
from masonry_fdem.interactions.joints import JOINT_STATES, JointMaterial, Joints
from masonry_fdem.interactions.protocol import BLOCKS, DofSet, Interaction, State
from masonry_fdem.interactions.search import ADTree, brute_force_pairs, build_adt
from masonry_fdem.interactions.search import inflate, query_adt, self_pairs

__all__ = [
    "BLOCKS", "DofSet", "Interaction", "State",
    "ADTree", "Anchor", "Anchors", "BlockContact", "BondLaw", "ContactSettings",
    "DiskBlockContact", "DiskMaterial", "Disks", "DowelLaw", "JOINT_STATES", "JointMaterial",
    "Joints", "SteelLaw", "brute_force_pairs", "build_adt", "inflate", "pack_disks",
    "query_adt", "restitution_damping_ratio", "self_pairs", "spatial_order",
    "straight_anchor", "wall_ties",
]


def precompile() -> None:
    """Compile and cache the kernels of every interaction."""
    from masonry_fdem.interactions import _sums, anchors, contact, disks, joints, search

    for package in (_sums, search, contact, joints, disks, anchors):
        package.precompile()
