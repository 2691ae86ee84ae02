"""Contact between blocks: ADT broad phase, facet-to-facet penalty narrow phase, and the
bonded (cohesive) joints that turn into contact when they break."""

from masonry_fdem.contact.adt import ADTree, build_adt, inflate, query_adt, self_pairs
from masonry_fdem.contact.disk_block import DiskBlockContact
from masonry_fdem.contact.joints import JOINT_STATES, JointMaterial, Joints
from masonry_fdem.contact.penalty import BlockContact, ContactSettings, restitution_damping_ratio

__all__ = [
    "ADTree",
    "JOINT_STATES",
    "JointMaterial",
    "Joints",
    "BlockContact",
    "DiskBlockContact",
    "ContactSettings",
    "build_adt",
    "inflate",
    "query_adt",
    "restitution_damping_ratio",
    "self_pairs",
]
