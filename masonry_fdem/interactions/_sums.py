"""Nodal sums that do not depend on how the blocks are spread over ranks.

An interaction whose terms (contact pairs, joint integration points) each act on four
nodes writes their forces term by term, ``fq`` (n_terms, 8): x, y on the term's four
nodes. A node's force is then the sum over its terms in one global order (the terms'
keys or global numbers, which every rank sorts alike), so a node owned by a rank gets
the same sum, to the bit, from one rank or several — provided the rank holds every term
that acts on its nodes (a term across ranks is held, and evaluated, by both).
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["gather_rows", "node_lists"]


@njit(cache=True)
def gather_rows(fq, nodes, ptr, idx, f):
    """f[2 n], f[2 n + 1] += Σ over ``idx[ptr[i]:ptr[i + 1]]`` of the rows of ``fq`` seen
    as (4 n_terms, 2) (row 4 k + slot: term k's force on its node ``slot``) [N], in
    that order, for each node n = ``nodes[i]`` that has terms."""
    f2 = fq.reshape(-1, 2)
    for i in range(nodes.size):
        sx = 0.0
        sy = 0.0
        for e in range(ptr[i], ptr[i + 1]):
            r = idx[e]
            sx += f2[r, 0]
            sy += f2[r, 1]
        n = nodes[i]
        f[2 * n] += sx
        f[2 * n + 1] += sy


@njit(cache=True)
def _count_sort(nodes, n_nodes, touched, ptr, idx):
    """Counting sort of the rows r (ascending) by ``nodes[r]`` < n_nodes (stable: a
    node's rows stay in term order); returns the number of touched nodes."""
    counts = np.zeros(n_nodes + 1, dtype=np.int64)
    for r in range(nodes.size):
        n = nodes[r]
        if n < n_nodes:
            counts[n + 1] += 1
    nt = 0
    for n in range(n_nodes):
        if counts[n + 1] > 0:
            touched[nt] = n
            ptr[nt + 1] = ptr[nt] + counts[n + 1]
            nt += 1
        counts[n + 1] += counts[n]  # counts[n] becomes the start of node n
    for r in range(nodes.size):
        n = nodes[r]
        if n < n_nodes:
            idx[counts[n]] = r
            counts[n] += 1
    return nt


def node_lists(nodes: np.ndarray, n_nodes: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """CSR lists of the rows 4 k + slot of the terms acting on each of the first
    ``n_nodes`` (owned) nodes that has any, in term order: (the nodes, ptr, idx), ptr
    one longer than the nodes; ``nodes`` (n_terms, 4) are the local node numbers of
    each term (ghosts ≥ n_nodes are left out). Nodes without terms are not listed, so
    a sum costs the nodes the interaction touches, not the model's."""
    nodes = np.ascontiguousarray(nodes, dtype=np.int64).reshape(-1)
    n_nodes = int(n_nodes)
    touched = np.empty(n_nodes, dtype=np.int64)
    ptr = np.zeros(n_nodes + 1, dtype=np.int64)
    idx = np.empty(int(np.count_nonzero(nodes < n_nodes)), dtype=np.int64)
    nt = _count_sort(nodes, n_nodes, touched, ptr, idx)
    return touched[:nt].copy(), ptr[: nt + 1].copy(), idx


def precompile() -> None:
    """Compile :func:`gather_rows`."""
    nodes, ptr, idx = node_lists(np.arange(4).reshape(1, 4), 4)
    gather_rows(np.ones((1, 8)), nodes, ptr, idx, np.zeros(8))
