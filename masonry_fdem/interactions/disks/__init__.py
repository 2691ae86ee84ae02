"""Rigid circular discrete elements (granular fill): the disk set with its disk–disk
contact, packing, and disk–block contact."""

from masonry_fdem.interactions.disks.disk_block import DiskBlockContact
from masonry_fdem.interactions.disks.disks import DiskMaterial, Disks
from masonry_fdem.interactions.disks.packing import pack_disks, spatial_order

__all__ = ["DiskBlockContact", "DiskMaterial", "Disks", "pack_disks", "spatial_order"]


def precompile() -> None:
    """Compile and cache the disk kernels: a small set stepped through the protocol, the
    disk–facet kernel, the packer."""
    import numpy as np
    from mpi4py import MPI

    from masonry_fdem.interactions.disks import _facet_kernels, _kernels
    from masonry_fdem.interactions.protocol import State

    mat = DiskMaterial(density=1.0, E=1e6, nu=0.2, rolling_friction=0.1)
    d = Disks(np.array([[0.0, 0.0], [1.9, 0.0], [9.0, 9.0]]), np.ones(3), {"d": mat}, "d",
              comm=MPI.COMM_SELF)
    sets = d.dofsets()
    st = State({s.name: s.u for s in sets}, {s.name: s.v for s in sets},
               {s.name: s.f for s in sets}, 1e-3, True)
    d.update(st)
    d.add_forces(st)
    d.cell_stress((-1.0, -1.0), (1.0, 1.0))
    d.contact_counts()
    _kernels.love_sum_points(d.x, np.zeros(1, dtype=np.int64), np.zeros((1, 2)),
                             np.zeros((1, 2)), -1.0, -1.0, 1.0, 1.0, np.zeros((2, 2)))
    _kernels.brute_force_disk_pairs(d.x, d.r, 0.1)
    perm, _ = _kernels.cell_order(d.x, d.r, 0.1, d.ids)
    crowd = np.r_[np.linspace(0.0, 1.0, 80)[:, None] * [1.0, 0.5], [[1e3, 1e3]]]
    _kernels.cell_order(crowd, np.ones(81), 0.1, np.arange(81))  # a crowded cell
    _kernels.carry_history_renumbered(d.pairs, d.hist, perm[::-1].copy(), d.pairs,
                                      d.hist.copy())
    _kernels.hertz_force(1.0, 0.5, 0.1, 0.2)
    _kernels.max_node_move(np.zeros(8), np.zeros(8), np.arange(4, dtype=np.int64))
    _facet_kernels.precompile()
    pack_disks(np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]), 0.1, 0.15, 0.5)
    from masonry_fdem.interactions.disks import fill

    fill._inside_clear(np.zeros((1, 2)), np.ones(1), np.array([[0.0, 0.0], [1.0, 0.0],
                                                               [0.0, 1.0]]), 0.0,
                       np.zeros(1, dtype=np.int8))
