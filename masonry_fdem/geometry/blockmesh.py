"""The block mesh: all masonry units as linear triangles in flat arrays, one block per unit.

A :class:`BlockMesh` is what every later stage (model, contact, output) reads. Blocks never
share a node: the nodes of block ``b`` are the rows ``node_offsets[b]:node_offsets[b+1]`` of
``x`` and its triangles the rows ``cell_offsets[b]:cell_offsets[b+1]`` of ``cells``.
Triangles are counter-clockwise. Everything else (areas, centroids, boundary facets, ...)
is derived from these arrays on first use and cached.

Build one with :meth:`BlockMesh.from_arrays` (validates, renumbers and re-orients any
triangle soup) or with the meshing and import functions of this package.
"""

from __future__ import annotations

import fnmatch
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import cached_property

import numpy as np

__all__ = ["BlockMesh", "unit_name"]

# A triangle whose |2 * area| is below this times its longest edge squared is degenerate.
_DEGENERATE_TOL = 1e-12
# Show at most this many offending items in an error message.
_MAX_LISTED = 5


def _listed(items) -> str:
    items = list(items)
    more = f", ... ({len(items)} in all)" if len(items) > _MAX_LISTED else ""
    return ", ".join(str(i) for i in items[:_MAX_LISTED]) + more


def _twice_area(x: np.ndarray, cells: np.ndarray) -> np.ndarray:
    """Twice the signed area of each triangle [m^2], positive if counter-clockwise."""
    a, b, c = x[cells[:, 0]], x[cells[:, 1]], x[cells[:, 2]]
    return (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])


@dataclass(frozen=True, eq=False, repr=False)
class BlockMesh:
    """All blocks of a structure as one triangle mesh whose connected parts are the blocks.

    Attributes:
        x: ``(n_nodes, 2)`` float64 node coordinates [m].
        cells: ``(n_cells, 3)`` int64 node indices of counter-clockwise triangles.
        node_offsets: ``(n_blocks + 1,)`` int64; block ``b`` owns nodes
            ``node_offsets[b]:node_offsets[b+1]``.
        cell_offsets: ``(n_blocks + 1,)`` int64; block ``b`` owns cells
            ``cell_offsets[b]:cell_offsets[b+1]``.
        block_material: ``(n_blocks,)`` int32 index into ``material_names``.
        material_names: material of each material id.
        block_names: unique name of each block, e.g. ``"brick:0:3"``, ``"base"``.
        zone_material: ``(n_cells,)`` int32 material id of each cell for a mesh whose
            blocks may hold several materials (a footing cast on its soil, a weaker band
            of a specimen), else None. A mixed block's ``block_material`` is its most
            common material (used for contact and joint defaults).

    The constructor checks that the arrays are already in this canonical form; use
    :meth:`from_arrays` for anything else.
    """

    x: np.ndarray
    cells: np.ndarray
    node_offsets: np.ndarray
    cell_offsets: np.ndarray
    block_material: np.ndarray
    material_names: tuple[str, ...]
    block_names: tuple[str, ...]
    zone_material: np.ndarray | None = None

    def __post_init__(self) -> None:
        coerce = {
            "x": (np.float64, 2),
            "cells": (np.int64, 2),
            "node_offsets": (np.int64, 1),
            "cell_offsets": (np.int64, 1),
            "block_material": (np.int32, 1),
        }
        for name, (dtype, ndim) in coerce.items():
            arr = np.ascontiguousarray(getattr(self, name), dtype=dtype)
            if arr.ndim != ndim:
                raise ValueError(f"BlockMesh.{name} must have {ndim} dimensions")
            object.__setattr__(self, name, arr)
        if self.zone_material is not None:
            zm = np.ascontiguousarray(self.zone_material, dtype=np.int32).ravel()
            object.__setattr__(self, "zone_material", zm)
        object.__setattr__(self, "material_names", tuple(str(m) for m in self.material_names))
        object.__setattr__(self, "block_names", tuple(str(b) for b in self.block_names))
        self._check()

    def _check(self) -> None:
        x, cells, no, co = self.x, self.cells, self.node_offsets, self.cell_offsets
        nb = len(self.block_names)
        if x.shape[1] != 2 or cells.shape[1] != 3:
            raise ValueError("BlockMesh needs x of shape (n, 2) and cells of shape (m, 3)")
        if no.shape != (nb + 1,) or co.shape != (nb + 1,) or self.block_material.shape != (nb,):
            raise ValueError("BlockMesh offsets/materials do not match the number of blocks")
        if len(set(self.block_names)) != nb:
            raise ValueError("BlockMesh block names must be unique")
        if no[0] != 0 or no[-1] != x.shape[0] or co[0] != 0 or co[-1] != cells.shape[0]:
            raise ValueError("BlockMesh offsets must start at 0 and end at the array lengths")
        if np.any(np.diff(no) <= 0) or np.any(np.diff(co) <= 0):
            raise ValueError("BlockMesh: every block needs at least one node and one cell")
        nm = len(self.material_names)
        if np.any(self.block_material < 0) or np.any(self.block_material >= nm):
            raise ValueError("BlockMesh.block_material out of range of material_names")
        zm = self.zone_material
        if zm is not None and (zm.shape != (cells.shape[0],) or np.any(zm < 0)
                               or np.any(zm >= nm)):
            raise ValueError("BlockMesh.zone_material needs one material id in range per cell")
        cb = np.repeat(np.arange(nb), np.diff(co))
        lo, hi = no[cb], no[cb + 1]
        if np.any(cells < lo[:, None]) or np.any(cells >= hi[:, None]):
            raise ValueError("BlockMesh: a cell uses a node outside its block's node range")
        if np.any(np.bincount(cells.ravel(), minlength=x.shape[0]) == 0):
            raise ValueError("BlockMesh: every node must belong to a cell")
        if np.any(_twice_area(x, cells) <= 0.0):
            raise ValueError("BlockMesh: triangles must be counter-clockwise with positive area")

    # ------------------------------------------------------------------ construction
    @classmethod
    def from_arrays(
        cls,
        x: np.ndarray,
        cells: np.ndarray,
        cell_block: np.ndarray,
        *,
        block_names: Sequence[str],
        material_names: Sequence[str],
        block_material: np.ndarray | Sequence[int] | None = None,
        cell_material: np.ndarray | Sequence[int] | None = None,
        mixed_materials: bool = False,
    ) -> BlockMesh:
        """Build a block mesh from a triangle soup with a block id per cell.

        Nodes and cells are renumbered so that each block's are contiguous (blocks in id
        order, nodes and cells of a block in their input order), unused nodes are dropped
        and clockwise triangles are re-oriented.

        Args:
            x: ``(n, 2)`` node coordinates [m], or ``(n, 3)`` with all z equal to 0.
            cells: ``(m, 3)`` integer node indices of linear triangles.
            cell_block: ``(m,)`` block id of each cell, in ``[0, len(block_names))``.
            block_names: unique name of each block.
            material_names: name of each material id.
            block_material: ``(n_blocks,)`` material id of each block. Give this or
                ``cell_material``; if neither, there must be exactly one material.
            cell_material: ``(m,)`` material id of each cell, constant within a block
                unless ``mixed_materials``.
            mixed_materials: allow blocks of several materials (zones of one continuum).

        Returns:
            The validated, canonical block mesh.

        Raises:
            ValueError: wrong shapes, nonzero z ("3D ..."), non-finite coordinates, node
                indices out of range, degenerate triangles, a node used by two blocks, a
                block without cells, mixed materials in a block, duplicate block names.
        """
        x = np.asarray(x, dtype=np.float64)
        if x.ndim != 2 or x.shape[1] not in (2, 3):
            raise ValueError(f"x must have shape (n_nodes, 2), got {x.shape}")
        if x.shape[1] == 3:
            scale = max(float(np.abs(x[:, :2]).max(initial=0.0)), 1.0)
            if np.any(np.abs(x[:, 2]) > 1e-12 * scale):
                raise ValueError("3D coordinates: nodes with nonzero z; blocks must be planar")
            x = x[:, :2]
        if not np.all(np.isfinite(x)):
            raise ValueError("x contains non-finite coordinates")
        cells = np.asarray(cells)
        if cells.ndim != 2 or cells.shape[1] != 3 or cells.shape[0] == 0:
            raise ValueError(
                f"cells must have shape (n_cells, 3) with n_cells > 0, got {cells.shape}"
            )
        if not np.issubdtype(cells.dtype, np.integer):
            raise ValueError(f"cells must hold integer node indices, got dtype {cells.dtype}")
        cells = cells.astype(np.int64)
        if cells.min() < 0 or cells.max() >= x.shape[0]:
            raise ValueError(f"cells refer to nodes outside [0, {x.shape[0]})")
        names = tuple(str(n) for n in block_names)
        nb = len(names)
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            raise ValueError(f"duplicate block names: {_listed(dup)}")
        cell_block = np.asarray(cell_block).astype(np.int64).ravel()
        if cell_block.shape != (cells.shape[0],):
            raise ValueError("cell_block must have one entry per cell")
        if nb == 0 or cell_block.min() < 0 or cell_block.max() >= nb:
            raise ValueError(f"cell_block values must lie in [0, {nb}) (one per block name)")
        counts = np.bincount(cell_block, minlength=nb)
        if np.any(counts == 0):
            empty = [names[b] for b in np.flatnonzero(counts == 0)]
            raise ValueError(f"blocks without cells: {_listed(empty)}")
        mats = tuple(str(m) for m in material_names)
        bmat, zones = cls._block_materials(cell_block, nb, mats, block_material, cell_material,
                                           names, mixed_materials)

        # orientation and degeneracy
        a2 = _twice_area(x, cells)
        e = x[cells[:, [1, 2, 0]]] - x[cells]
        longest2 = (e * e).sum(axis=2).max(axis=1)
        bad = np.abs(a2) <= _DEGENERATE_TOL * longest2
        if np.any(bad):
            idx = np.flatnonzero(bad)
            where = [f"cell {i} of {names[cell_block[i]]}" for i in idx]
            raise ValueError(f"degenerate (zero-area) triangles: {_listed(where)}")
        cells = cells.copy()
        flip = a2 < 0.0
        cells[flip, 1], cells[flip, 2] = cells[flip, 2], cells[flip, 1].copy()

        # one block per node
        n = x.shape[0]
        inc_block = np.repeat(cell_block, 3)
        bmin = np.full(n, nb, dtype=np.int64)
        bmax = np.full(n, -1, dtype=np.int64)
        np.minimum.at(bmin, cells.ravel(), inc_block)
        np.maximum.at(bmax, cells.ravel(), inc_block)
        used = bmax >= 0
        shared = np.flatnonzero(used & (bmin != bmax))
        if shared.size:
            where = [f"node {i} at {tuple(x[i])} in {names[bmin[i]]} and {names[bmax[i]]}"
                     for i in shared]
            raise ValueError(f"nodes shared by two blocks: {_listed(where)}")

        # renumber: nodes and cells grouped by block, input order kept inside a block
        old = np.flatnonzero(used)
        node_order = old[np.argsort(bmin[old], kind="stable")]
        new_index = np.full(n, -1, dtype=np.int64)
        new_index[node_order] = np.arange(node_order.size)
        cell_order = np.argsort(cell_block, kind="stable")
        node_counts = np.bincount(bmin[old], minlength=nb)
        return cls(
            x=x[node_order],
            cells=new_index[cells[cell_order]],
            node_offsets=np.concatenate([[0], np.cumsum(node_counts)]),
            cell_offsets=np.concatenate([[0], np.cumsum(counts)]),
            block_material=bmat,
            material_names=mats,
            block_names=names,
            zone_material=None if zones is None else zones[cell_order],
        )

    @staticmethod
    def _block_materials(cell_block, nb, mats, block_material, cell_material, names,
                         mixed=False):
        if not mats:
            raise ValueError("material_names must not be empty")
        if block_material is not None and cell_material is not None:
            raise ValueError("give block_material or cell_material, not both")
        if block_material is not None:
            bmat = np.asarray(block_material).astype(np.int64).ravel()
            if bmat.shape != (nb,):
                raise ValueError("block_material must have one entry per block")
        elif cell_material is not None:
            cm = np.asarray(cell_material).astype(np.int64).ravel()
            if cm.shape != cell_block.shape:
                raise ValueError("cell_material must have one entry per cell")
            lo = np.full(nb, np.iinfo(np.int64).max)
            hi = np.full(nb, np.iinfo(np.int64).min)
            np.minimum.at(lo, cell_block, cm)
            np.maximum.at(hi, cell_block, cm)
            several = np.flatnonzero(lo != hi)
            if several.size and not mixed:
                raise ValueError(f"blocks with more than one material: "
                                 f"{_listed(names[b] for b in several)} "
                                 "(pass mixed_materials=True for zones of one continuum)")
            if several.size:
                if cm.min() < 0 or cm.max() >= len(mats):
                    raise ValueError(f"material ids must lie in [0, {len(mats)})")
                counts = np.zeros((nb, len(mats)), dtype=np.int64)
                np.add.at(counts, (cell_block, cm), 1)
                return counts.argmax(axis=1).astype(np.int32), cm.astype(np.int32)
            bmat = lo
        elif len(mats) == 1:
            bmat = np.zeros(nb, dtype=np.int64)
        else:
            raise ValueError("several material names: give block_material or cell_material")
        if bmat.min() < 0 or bmat.max() >= len(mats):
            raise ValueError(f"material ids must lie in [0, {len(mats)})")
        return bmat.astype(np.int32), None

    # ------------------------------------------------------------------ sizes
    @property
    def n_blocks(self) -> int:
        """Number of blocks."""
        return len(self.block_names)

    @property
    def n_nodes(self) -> int:
        """Number of nodes."""
        return int(self.x.shape[0])

    @property
    def n_cells(self) -> int:
        """Number of triangles."""
        return int(self.cells.shape[0])

    def __repr__(self) -> str:
        return (f"BlockMesh({self.n_blocks} blocks, {self.n_cells} cells, {self.n_nodes} nodes, "
                f"materials={list(self.material_names)})")

    # ------------------------------------------------------------------ per-entity ids
    @cached_property
    def cell_block(self) -> np.ndarray:
        """``(n_cells,)`` int32 block id of each cell."""
        return np.repeat(np.arange(self.n_blocks, dtype=np.int32), np.diff(self.cell_offsets))

    @cached_property
    def node_block(self) -> np.ndarray:
        """``(n_nodes,)`` int32 block id of each node."""
        return np.repeat(np.arange(self.n_blocks, dtype=np.int32), np.diff(self.node_offsets))

    @cached_property
    def cell_material(self) -> np.ndarray:
        """``(n_cells,)`` int32 material id of each cell."""
        if self.zone_material is not None:
            return self.zone_material
        return self.block_material[self.cell_block]

    @property
    def block_material_names(self) -> tuple[str, ...]:
        """Material name of each block."""
        return tuple(self.material_names[m] for m in self.block_material)

    # ------------------------------------------------------------------ measures
    @cached_property
    def cell_area(self) -> np.ndarray:
        """``(n_cells,)`` triangle areas [m^2]."""
        return 0.5 * _twice_area(self.x, self.cells)

    @cached_property
    def block_area(self) -> np.ndarray:
        """``(n_blocks,)`` block areas [m^2]."""
        return np.add.reduceat(self.cell_area, self.cell_offsets[:-1])

    @cached_property
    def block_centroid(self) -> np.ndarray:
        """``(n_blocks, 2)`` area centroids of the blocks [m]."""
        mid = self.x[self.cells].mean(axis=1) * self.cell_area[:, None]
        return np.add.reduceat(mid, self.cell_offsets[:-1], axis=0) / self.block_area[:, None]

    @cached_property
    def block_bounds(self) -> np.ndarray:
        """``(n_blocks, 4)`` bounding boxes ``[xmin, ymin, xmax, ymax]`` [m]."""
        start = self.node_offsets[:-1]
        lo = np.minimum.reduceat(self.x, start, axis=0)
        hi = np.maximum.reduceat(self.x, start, axis=0)
        return np.hstack([lo, hi])

    @property
    def bounds(self) -> np.ndarray:
        """``(4,)`` bounding box of the whole mesh ``[xmin, ymin, xmax, ymax]`` [m]."""
        return np.concatenate([self.x.min(axis=0), self.x.max(axis=0)])

    # ------------------------------------------------------------------ boundary
    @cached_property
    def _boundary(self) -> tuple[np.ndarray, np.ndarray]:
        cells = self.cells
        edges = np.concatenate([cells[:, [0, 1]], cells[:, [1, 2]], cells[:, [2, 0]]])
        key = np.sort(edges, axis=1)
        key = key[:, 0] * self.n_nodes + key[:, 1]
        _, inverse, count = np.unique(key, return_inverse=True, return_counts=True)
        facets = edges[count[inverse] == 1]
        # chain the facets of each block into loops: facet f is followed by the one
        # starting where f ends (blocks in order, loops in order of their first facet)
        fb = self.node_block[facets[:, 0]]
        order = np.lexsort((np.arange(facets.shape[0]), fb))
        facets = facets[order]
        nxt = np.full(self.n_nodes, -1, dtype=np.int64)
        nxt[facets[::-1, 0]] = np.arange(facets.shape[0])[::-1]
        seen = np.zeros(facets.shape[0], dtype=bool)
        chain = []
        for f in range(facets.shape[0]):
            while f >= 0 and not seen[f]:
                seen[f] = True
                chain.append(f)
                f = nxt[facets[f, 1]]
        facets = np.ascontiguousarray(facets[np.asarray(chain, dtype=np.int64)])
        counts = np.bincount(self.node_block[facets[:, 0]], minlength=self.n_blocks)
        return facets, np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)

    @property
    def boundary_facets(self) -> np.ndarray:
        """``(n_bf, 2)`` int64 node pairs of the block outlines, block interior on the left.

        Sorted by block (rows ``facet_offsets[b]:facet_offsets[b+1]``); inside a block the
        facets follow each other around each closed loop, counter-clockwise around the
        block (clockwise around holes).
        """
        return self._boundary[0]

    @property
    def facet_offsets(self) -> np.ndarray:
        """``(n_blocks + 1,)`` int64 offsets of each block's rows in ``boundary_facets``."""
        return self._boundary[1]

    @cached_property
    def facet_block(self) -> np.ndarray:
        """``(n_bf,)`` int32 block id of each boundary facet."""
        return np.repeat(np.arange(self.n_blocks, dtype=np.int32), np.diff(self.facet_offsets))

    # ------------------------------------------------------------------ queries
    def select(
        self,
        sel: str | Sequence[str] | Callable[[np.ndarray], bool] | None = None,
        *,
        material: str | Sequence[str] | None = None,
    ) -> np.ndarray:
        """Ids of the blocks chosen by name pattern, centroid predicate and/or material.

        Args:
            sel: a block name or shell pattern (``"brick:*"``, ``"voussoir:1:*"``), a
                sequence of them (union), or a predicate called with each block centroid
                ``(2,)`` [m]; None selects all blocks.
            material: keep only blocks of this material (or these materials).

        Returns:
            Sorted int64 block ids.

        Raises:
            ValueError: a name pattern or material matching no block.
        """
        keep = np.ones(self.n_blocks, dtype=bool)
        if callable(sel):
            keep &= np.array([bool(sel(c)) for c in self.block_centroid], dtype=bool)
        elif sel is not None:
            patterns = [sel] if isinstance(sel, str) else list(sel)
            hit = np.zeros(self.n_blocks, dtype=bool)
            for pat in patterns:
                m = np.array([fnmatch.fnmatchcase(n, pat) for n in self.block_names])
                if not m.any():
                    raise ValueError(f"no block named {pat!r}")
                hit |= m
            keep &= hit
        if material is not None:
            wanted = [material] if isinstance(material, str) else list(material)
            unknown = [m for m in wanted if m not in self.material_names]
            if unknown:
                raise ValueError(f"unknown material(s) {unknown}; have {list(self.material_names)}")
            ids = [self.material_names.index(m) for m in wanted]
            keep &= np.isin(self.block_material, ids)
        return np.flatnonzero(keep).astype(np.int64)

    def block_of_point(self, p: np.ndarray | Sequence[float], tol: float = 1e-12):
        """Block containing a point, or -1 if the point is in no block.

        A point on the common edge of two touching blocks is given to the lower block id.

        Args:
            p: ``(2,)`` point or ``(k, 2)`` points [m].
            tol: relative tolerance on the barycentric coordinates (points this close
                outside a triangle count as inside).

        Returns:
            An int for one point, an ``(k,)`` int64 array for several.
        """
        pts = np.asarray(p, dtype=np.float64)
        single = pts.ndim == 1
        pts = np.atleast_2d(pts)
        if pts.shape[1] != 2:
            raise ValueError(f"points must have shape (2,) or (k, 2), got {np.shape(p)}")
        bb = self.block_bounds
        size = float(np.ptp(self.x, axis=0).max())
        pad = tol * max(size, 1.0)
        out = np.full(pts.shape[0], -1, dtype=np.int64)
        for i, q in enumerate(pts):
            cand = np.flatnonzero(
                (bb[:, 0] - pad <= q[0]) & (q[0] <= bb[:, 2] + pad)
                & (bb[:, 1] - pad <= q[1]) & (q[1] <= bb[:, 3] + pad)
            )
            for b in cand:
                tri = self.x[self.cells[self.cell_offsets[b]:self.cell_offsets[b + 1]]]
                a, e1, e2 = tri[:, 0], tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]
                det = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
                d = q - a
                s = (d[:, 0] * e2[:, 1] - d[:, 1] * e2[:, 0]) / det
                t = (e1[:, 0] * d[:, 1] - e1[:, 1] * d[:, 0]) / det
                if np.any((s >= -tol) & (t >= -tol) & (s + t <= 1.0 + tol)):
                    out[i] = b
                    break
        return int(out[0]) if single else out

    def subset(self, blocks: Sequence[int] | np.ndarray) -> BlockMesh:
        """A new block mesh with only the given blocks (renumbered in the given order)."""
        ids = np.asarray(blocks, dtype=np.int64).ravel()
        cell_idx = np.concatenate(
            [np.arange(self.cell_offsets[b], self.cell_offsets[b + 1]) for b in ids]
        )
        return BlockMesh.from_arrays(
            self.x,
            self.cells[cell_idx],
            np.repeat(np.arange(ids.size), np.diff(self.cell_offsets)[ids]),
            block_names=[self.block_names[b] for b in ids],
            material_names=self.material_names,
            cell_material=self.cell_material[cell_idx],
            mixed_materials=self.zone_material is not None,
        )

    def fractured(self, sel=None, *, material=None) -> BlockMesh:
        """A copy in which the selected blocks (units) are cut into their triangles.

        Each triangle of a selected block becomes a block of its own, named
        ``"<unit>#<k>"`` (see :func:`unit_name`), with its own three nodes; the bonded
        joints (:class:`~masonry_fdem.interactions.Joints`) then tie the pieces back together
        with the unit's cohesive crack law, so cracks can open along any element edge.

        Args:
            sel, material: which blocks, as in :meth:`select` (all blocks by default).
        """
        chosen = np.zeros(self.n_blocks, dtype=bool)
        chosen[self.select(sel, material=material)] = True
        xs, cells, cb, names, cmat = [], [], [], [], []
        n = 0
        for b in range(self.n_blocks):
            c = self.cells[self.cell_offsets[b]:self.cell_offsets[b + 1]]
            if chosen[b]:
                for k, tri in enumerate(c):
                    xs.append(self.x[tri])
                    cells.append(np.arange(n, n + 3)[None, :])
                    n += 3
                    cb.append([len(names)])
                    names.append(f"{self.block_names[b]}#{k}")
                    cmat.append([self.cell_material[self.cell_offsets[b] + k]])
            else:
                nodes = np.arange(self.node_offsets[b], self.node_offsets[b + 1])
                xs.append(self.x[nodes])
                cells.append(c - self.node_offsets[b] + n)
                n += nodes.size
                cb.append(np.full(c.shape[0], len(names)))
                names.append(self.block_names[b])
                cmat.append(self.cell_material[self.cell_offsets[b]:self.cell_offsets[b + 1]])
        return BlockMesh.from_arrays(
            np.concatenate(xs), np.concatenate(cells), np.concatenate(cb),
            block_names=names, material_names=self.material_names,
            cell_material=np.concatenate(cmat), mixed_materials=self.zone_material is not None,
        )

    @cached_property
    def block_unit(self) -> np.ndarray:
        """``(n_blocks,)`` int64 unit id: pieces of one fractured unit share it."""
        units = [unit_name(n) for n in self.block_names]
        _, first, inv = np.unique(units, return_index=True, return_inverse=True)
        return np.argsort(np.argsort(first))[inv].astype(np.int64)

    def core_arrays(self) -> dict:
        """The constructor fields, e.g. to send to other ranks and rebuild there."""
        return {
            "x": self.x,
            "cells": self.cells,
            "node_offsets": self.node_offsets,
            "cell_offsets": self.cell_offsets,
            "block_material": self.block_material,
            "material_names": self.material_names,
            "block_names": self.block_names,
            "zone_material": self.zone_material,
        }


def unit_name(block_name: str) -> str:
    """The unit a block belongs to: its name up to ``#`` (pieces of a fractured unit)."""
    return block_name.split("#", 1)[0]
