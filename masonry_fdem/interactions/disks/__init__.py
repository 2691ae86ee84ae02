"""Rigid circular discrete elements (granular fill): the disk set with its disk–disk
contact, packing, and disk–block contact."""

from masonry_fdem.interactions.disks.disk_block import DiskBlockContact
from masonry_fdem.interactions.disks.disks import DiskMaterial, Disks
from masonry_fdem.interactions.disks.packing import pack_disks, spatial_order

__all__ = ["DiskBlockContact", "DiskMaterial", "Disks", "pack_disks", "spatial_order"]
