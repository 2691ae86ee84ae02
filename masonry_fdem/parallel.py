"""Distribution of whole blocks over MPI ranks.

Masonry blocks interact only through contact and joints, never through shared nodes, so the
natural parallel unit is the block: every block lives wholly on one rank and the finite
element assembly needs no ghost exchange at all. The blocks are distributed by recursive
coordinate bisection (RCB) of their centroids, weighted by their cell counts, and a custom
dolfinx cell partitioner sends each cell to its block's rank.
"""

from __future__ import annotations

import logging
from typing import TYPE_CHECKING

from mpi4py import MPI

import numpy as np

import dolfinx
import dolfinx.graph
import dolfinx.mesh

if TYPE_CHECKING:
    from masonry_fdem.geometry import BlockMesh

__all__ = [
    "rcb_block_ranks",
    "create_block_mesh",
    "DistributedBlockMesh",
    "NodeExchange",
    "exchange_ids",
]

log = logging.getLogger(__name__)


def rcb_block_ranks(
    centroids: np.ndarray, weights: np.ndarray, nparts: int
) -> np.ndarray:
    """Assign blocks to ``nparts`` ranks by weighted recursive coordinate bisection.

    Args:
        centroids: (n_blocks, dim) block centroids [m].
        weights: (n_blocks,) work per block (e.g. its number of cells).
        nparts: number of parts (ranks).

    Returns:
        (n_blocks,) int32 part of each block. Parts are contiguous in space; their weights
        differ by at most one block's weight from the ideal split.
    """
    centroids = np.asarray(centroids, dtype=np.float64)
    weights = np.asarray(weights, dtype=np.float64)
    n = centroids.shape[0]
    if nparts < 1:
        raise ValueError(f"nparts must be >= 1, got {nparts}")
    part = np.zeros(n, dtype=np.int32)

    def split(ids: np.ndarray, first: int, count: int) -> None:
        if count == 1 or ids.size == 0:
            part[ids] = first
            return
        left_parts = count // 2
        pts = centroids[ids]
        extent = pts.max(axis=0) - pts.min(axis=0)
        axis = int(np.argmax(extent))
        # stable sort so equal coordinates are split deterministically
        order = ids[np.lexsort((ids, pts[:, axis]))]
        cum = np.cumsum(weights[order])
        target = cum[-1] * left_parts / count
        cut = int(np.searchsorted(cum, target, side="left")) + 1
        cut = min(max(cut, 1), order.size - 1) if order.size > 1 else order.size
        split(order[:cut], first, left_parts)
        split(order[cut:], first + left_parts, count - left_parts)

    split(np.arange(n), 0, nparts)
    return part


class DistributedBlockMesh:
    """A dolfinx mesh holding all blocks, with block and material ids of its local cells.

    Attributes:
        mesh: the dolfinx mesh (reference configuration).
        blocks: the serial :class:`BlockMesh` it was built from (same on every rank).
        block_rank: (n_blocks,) rank owning each block.
        cell_block: (n_local_cells,) block id of each local cell.
        cell_material: (n_local_cells,) material id of each local cell.
        node_input: (n_local_geometry_nodes,) index of each local geometry node in
            ``blocks.x``.
    """

    def __init__(self, mesh: dolfinx.mesh.Mesh, blocks: BlockMesh, block_rank: np.ndarray):
        self.mesh = mesh
        self.blocks = blocks
        self.block_rank = block_rank
        tdim = mesh.topology.dim
        n_local = mesh.topology.index_map(tdim).size_local
        original = np.asarray(mesh.topology.original_cell_index, dtype=np.int64)[:n_local]
        self.cell_input = original
        self.cell_block = blocks.cell_block[original].astype(np.int32)
        self.cell_material = blocks.cell_material[original].astype(np.int32)
        self.node_input = np.asarray(mesh.geometry.input_global_indices, dtype=np.int64)
        self.local_blocks = np.flatnonzero(block_rank == mesh.comm.rank).astype(np.int32)
        self.cell_tags_block = _tags(mesh, self.cell_block)
        self.cell_tags_material = _tags(mesh, self.cell_material)


def _tags(mesh: dolfinx.mesh.Mesh, values: np.ndarray) -> dolfinx.mesh.MeshTags:
    cells = np.arange(values.size, dtype=np.int32)
    return dolfinx.mesh.meshtags(mesh, mesh.topology.dim, cells, values.astype(np.int32))


def create_block_mesh(
    blocks: BlockMesh, comm: MPI.Comm = MPI.COMM_WORLD, degree: int = 1
) -> DistributedBlockMesh:
    """Create ONE dolfinx mesh of all blocks, each block wholly on one rank.

    Every rank must pass the same ``blocks`` (the geometry builders broadcast it). Rank 0
    feeds all cells to dolfinx; the partitioner sends each cell to its block's rank, chosen
    by :func:`rcb_block_ranks`.

    Args:
        blocks: the block mesh (linear triangles).
        comm: communicator of the model.
        degree: degree of the coordinate element (1: straight-sided triangles).

    Returns:
        The distributed mesh with its block and material cell ids.
    """
    import basix.ufl

    if degree != 1:
        raise NotImplementedError("only straight-sided (degree 1) geometry is supported")
    n_cells_block = np.diff(blocks.cell_offsets)
    block_rank = rcb_block_ranks(blocks.block_centroid, n_cells_block, comm.size)
    dest = block_rank[blocks.cell_block].astype(np.int32)

    if comm.rank == 0:
        cells = np.ascontiguousarray(blocks.cells, dtype=np.int64)
        x = np.ascontiguousarray(blocks.x, dtype=np.float64)
    else:
        cells = np.zeros((0, 3), dtype=np.int64)
        x = np.zeros((0, 2), dtype=np.float64)

    def partitioner(pcomm, nparts, cell_types, cell_lists):
        n_here = sum(len(c) for c in cell_lists) // 3
        if pcomm.rank == 0:
            if n_here != dest.size:
                raise RuntimeError("block partitioner: unexpected cell count on rank 0")
            d = dest
        else:
            d = np.zeros(n_here, dtype=np.int32)
        return dolfinx.graph.adjacencylist(np.ascontiguousarray(d))._cpp_object

    element = basix.ufl.element("Lagrange", "triangle", 1, shape=(2,))
    mesh = dolfinx.mesh.create_mesh(
        comm, cells, element, x, partitioner=partitioner if comm.size > 1 else None
    )
    dmesh = DistributedBlockMesh(mesh, blocks, block_rank)
    # a block on one rank only: every local cell's block must be owned here
    if not np.all(block_rank[dmesh.cell_block] == comm.rank):
        raise RuntimeError("a block was split between ranks")
    log.debug("rank %d holds %d blocks", comm.rank, dmesh.local_blocks.size)
    return dmesh


class NodeExchange:
    """Copies of nodal values between ranks, for contact across rank boundaries.

    Each rank sends the values of some of its nodes to other ranks (``send[r]``: local
    node indices whose values rank r receives, in an order both sides agree on), and
    receives ``n_recv[r]`` ghost values from each rank r. ``forward`` sends owned values to
    the ghost copies; ``reverse`` adds ghost contributions (forces) back to the owners. Both
    are collective ``Alltoallv`` calls, so no tags are needed.

    Args:
        comm: communicator.
        send: per rank, the local node indices to send (int64 arrays; empty for self).
        n_recv: per rank, the number of ghost nodes received.
    """

    def __init__(self, comm: MPI.Comm, send: list[np.ndarray], n_recv: list[int]):
        self.comm = comm
        self.send_nodes = np.concatenate([np.asarray(s, dtype=np.int64) for s in send]) \
            if send else np.zeros(0, dtype=np.int64)
        self.send_counts = np.array([len(s) for s in send], dtype=np.int64)
        self.recv_counts = np.asarray(n_recv, dtype=np.int64)
        self.n_ghost = int(self.recv_counts.sum())
        self._buffers: dict[tuple[str, int], np.ndarray] = {}  # reused every step
        self._displs: dict = {}

    def _buffer(self, kind: str, rows: int, w: int) -> np.ndarray:
        buf = self._buffers.get((kind, w))
        if buf is None:
            buf = self._buffers[(kind, w)] = np.zeros((rows, w))
        return buf

    def _displ(self, counts, width):
        key = (id(counts), width)
        hit = self._displs.get(key)
        if hit is None:
            c = counts * width
            hit = self._displs[key] = (c, np.concatenate([[0], np.cumsum(c)[:-1]]))
        return hit

    def forward(self, values: np.ndarray, out: np.ndarray) -> None:
        """values: (n_local, w) owned values → out: (n_ghost, w) ghost copies."""
        w = values.shape[1]
        sbuf = self._buffer("send", self.send_nodes.size, w)
        np.take(values, self.send_nodes, axis=0, out=sbuf)
        sc, sd = self._displ(self.send_counts, w)
        rc, rd = self._displ(self.recv_counts, w)
        self.comm.Alltoallv([sbuf, (sc, sd), MPI.DOUBLE], [out, (rc, rd), MPI.DOUBLE])

    def reverse(self, ghost_values: np.ndarray, out: np.ndarray) -> None:
        """ghost_values: (n_ghost, w) contributions → added to out: (n_local, w) owners."""
        w = ghost_values.shape[1]
        sbuf = np.ascontiguousarray(ghost_values)
        rbuf = self._buffer("recv", self.send_nodes.size, w)
        sc, sd = self._displ(self.recv_counts, w)
        rc, rd = self._displ(self.send_counts, w)
        self.comm.Alltoallv([sbuf, (sc, sd), MPI.DOUBLE], [rbuf, (rc, rd), MPI.DOUBLE])
        np.add.at(out, self.send_nodes, rbuf)


def exchange_ids(comm: MPI.Comm, send: list[np.ndarray]) -> list[np.ndarray]:
    """Send ``send[r]`` (int64 arrays) to each rank r; returns what each rank sent here."""
    counts = np.array([len(s) for s in send], dtype=np.int64)
    recv_counts = np.zeros_like(counts)
    comm.Alltoall(counts, recv_counts)
    sbuf = np.concatenate(send).astype(np.int64) if len(send) else np.zeros(0, np.int64)
    rbuf = np.zeros(int(recv_counts.sum()), dtype=np.int64)
    sd = np.concatenate([[0], np.cumsum(counts)[:-1]])
    rd = np.concatenate([[0], np.cumsum(recv_counts)[:-1]])
    comm.Alltoallv([sbuf, (counts, sd), MPI.INT64_T], [rbuf, (recv_counts, rd), MPI.INT64_T])
    return [rbuf[rd[r] : rd[r] + recv_counts[r]] for r in range(comm.size)]
