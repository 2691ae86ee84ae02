"""Mesh block outlines with Gmsh, each block on its own, into one :class:`BlockMesh`.

Every polygon becomes its own Gmsh plane surface with its own points and lines (Gmsh's
built-in kernel with ``Geometry.AutoCoherence = 0``): nothing is fragmented or made
coherent, so touching blocks get separate nodes on their common edge.

Mesh density:

* ``mesh_size=None``, or a size at least the block's diameter (largest vertex distance),
  gives the coarsest mesh: Gmsh's "initial mesh only" algorithm triangulates the outline
  with no node other than its vertices, so a block with ``k`` vertices gets ``k - 2``
  triangles (a rectangular brick exactly 2).
* a smaller ``mesh_size`` [m] is the target edge length for Gmsh's Frontal-Delaunay mesher.

Crossed blocks (``crossed``): a soil's linear triangles lock in isochoric plastic flow
(a non-dilatant Mohr–Coulomb fill at collapse) on a general triangulation, but not on
crossed triangles, where each quadrilateral is split by its diagonals into four
(Nagtegaal, Parks & Rice 1974: on a parallelogram the four triangles' volume changes are
linearly dependent, so the incompressibility constraints number three per quadrilateral,
not four). Such a block is meshed into quadrilaterals (Gmsh's Frontal-Delaunay for quads,
Blossom full-quad recombination) and each is split at its vertex average into four
triangles. Its boundary nodes are those of the quadrilateral mesh.

Gmsh runs on rank 0 only when a communicator is given; the block mesh is then broadcast.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Sequence
from typing import Any

import gmsh
import numpy as np

from masonry_fdem.geometry._gmsh import gmsh_model, on_root
from masonry_fdem.geometry.blockmesh import BlockMesh
from masonry_fdem.geometry.polygons import as_polygon, polygon_diameter

__all__ = ["cross_quads", "mesh_blocks", "material_table"]

log = logging.getLogger(__name__)

# Gmsh 2D algorithm ids
_ALGO_INITIAL_ONLY = 3
_ALGO_FRONTAL_DELAUNAY = 6
_ALGO_FRONTAL_QUADS = 8
_TRIANGLE = 2  # Gmsh element type of the 3-node triangle
_QUADRANGLE = 3  # Gmsh element type of the 4-node quadrilateral

_MESH_OPTIONS = {
    "Geometry.AutoCoherence": 0,
    "Mesh.Algorithm": _ALGO_FRONTAL_DELAUNAY,
    "Mesh.ElementOrder": 1,
    "Mesh.RecombineAll": 0,
    "Mesh.MeshSizeMin": 0.0,
    "Mesh.MeshSizeMax": 1e22,
    "Mesh.MeshSizeFactor": 1.0,
    "Mesh.MeshSizeFromPoints": 1,
    "Mesh.MeshSizeFromCurvature": 0,
    "Mesh.MeshSizeExtendFromBoundary": 1,
    "Mesh.RecombinationAlgorithm": 3,  # Blossom full-quad (only where recombined)
}


def material_table(materials: str | Sequence[str], n: int) -> tuple[tuple[str, ...], np.ndarray]:
    """Material names (first-use order) and the material id of each of ``n`` blocks.

    Args:
        materials: one material name for all blocks, or one per block.
        n: number of blocks.

    Returns:
        ``(material_names, block_material)`` with ``block_material`` int32 ``(n,)``.
    """
    per_block = [materials] * n if isinstance(materials, str) else [str(m) for m in materials]
    if len(per_block) != n:
        raise ValueError(f"got {len(per_block)} materials for {n} blocks")
    names = tuple(dict.fromkeys(per_block))
    index = {m: i for i, m in enumerate(names)}
    return names, np.array([index[m] for m in per_block], dtype=np.int32)


def _mesh_sizes(mesh_size: float | Sequence[float] | None, n: int) -> list[float | None]:
    if mesh_size is None:
        return [None] * n
    sizes = np.broadcast_to(np.asarray(mesh_size, dtype=np.float64), (n,))
    if not np.all(np.isfinite(sizes)) or np.any(sizes <= 0.0):
        raise ValueError(f"mesh_size must be positive and finite, got {mesh_size}")
    return [float(s) for s in sizes]


def cross_quads(x: np.ndarray, quads: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Split quadrilaterals into four triangles each about their vertex average.

    Args:
        x: ``(n, 2)`` node coordinates [m].
        quads: ``(m, 4)`` node ids, each quadrilateral in a consistent orientation.

    Returns:
        ``(x_new, triangles)``: the nodes with the ``m`` centres appended (centre ``k`` is
        node ``n + k``), and ``(4 m, 3)`` triangles in the quadrilaterals' orientation.
    """
    quads = np.asarray(quads, dtype=np.int64).reshape(-1, 4)
    n = x.shape[0]
    centre = np.arange(n, n + quads.shape[0], dtype=np.int64)
    tri = np.stack([np.stack([quads[:, k], quads[:, (k + 1) % 4], centre], axis=1)
                    for k in range(4)], axis=1).reshape(-1, 3)
    return np.vstack([x, x[quads].mean(axis=1)]), tri


def _gmsh_triangulate(
    polygons: Sequence[np.ndarray], sizes: Sequence[float | None], names: Sequence[str],
    crossed: Sequence[bool] | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mesh each polygon as a separate Gmsh surface; returns (x, cells, cell_block)."""
    crossed = [False] * len(polygons) if crossed is None else list(crossed)
    with gmsh_model(_MESH_OPTIONS):
        geo = gmsh.model.geo
        surfaces = []
        coarse = []
        for poly, h in zip(polygons, sizes, strict=True):
            diameter = polygon_diameter(poly)
            is_coarse = h is None or h >= diameter
            lc = 2.0 * diameter if is_coarse else h
            pts = [geo.addPoint(px, py, 0.0, lc) for px, py in poly]
            lines = [geo.addLine(pts[i], pts[(i + 1) % len(pts)]) for i in range(len(pts))]
            surfaces.append(geo.addPlaneSurface([geo.addCurveLoop(lines)]))
            coarse.append(is_coarse)
        geo.synchronize()
        for s, c, q in zip(surfaces, coarse, crossed, strict=True):
            if q:
                gmsh.model.mesh.setAlgorithm(2, s, _ALGO_FRONTAL_QUADS)
                gmsh.model.mesh.setRecombine(2, s)
            elif c:
                gmsh.model.mesh.setAlgorithm(2, s, _ALGO_INITIAL_ONLY)
        gmsh.model.mesh.generate(2)
        tags, xyz, _ = gmsh.model.mesh.getNodes()
        tags = np.asarray(tags, dtype=np.int64)
        x = np.asarray(xyz, dtype=np.float64).reshape(-1, 3)[:, :2]
        row = np.full(int(tags.max()) + 1, -1, dtype=np.int64)
        row[tags] = np.arange(tags.size)
        cells, cell_block = [], []
        for b, s in enumerate(surfaces):
            _, node_tags = gmsh.model.mesh.getElementsByType(_TRIANGLE, s)
            tri = row[np.asarray(node_tags, dtype=np.int64).reshape(-1, 3)]
            if crossed[b]:
                _, quad_tags = gmsh.model.mesh.getElementsByType(_QUADRANGLE, s)
                quads = row[np.asarray(quad_tags, dtype=np.int64).reshape(-1, 4)]
                x, split = cross_quads(x, quads)
                tri = np.vstack([tri, split])
            if len(tri) == 0:
                raise ValueError(f"Gmsh produced no triangles for block {names[b]!r}")
            cells.append(tri)
            cell_block.append(np.full(tri.shape[0], b, dtype=np.int64))
    return x, np.concatenate(cells), np.concatenate(cell_block)


def mesh_blocks(
    polygons: Sequence[np.ndarray],
    *,
    materials: str | Sequence[str],
    names: Sequence[str] | None = None,
    mesh_size: float | Sequence[float] | None = None,
    comm: Any | None = None,
    crossed: Sequence[str] = (),
) -> BlockMesh:
    """Mesh each polygon on its own into linear triangles; all blocks in one mesh.

    Args:
        polygons: block outlines, ``(k, 2)`` vertex arrays [m], either orientation.
        materials: material name of all blocks, or one per block.
        names: unique block names; default ``"block:<i>"``.
        mesh_size: target triangle edge length [m] (one value, or one per block); None or
            a size at least the block's diameter gives the coarsest mesh (``k - 2``
            triangles for a ``k``-vertex block, 2 for a rectangle).
        comm: mpi4py communicator; if given, Gmsh runs on rank 0 and every rank receives
            the same block mesh (collective call).
        crossed: names of blocks meshed with crossed triangles (quadrilaterals split by
            their diagonals; for soils, which must not lock in isochoric plastic flow).

    Returns:
        The block mesh, blocks in the order of ``polygons``.

    Raises:
        ValueError: invalid polygons (too few vertices, zero area, crossing edges),
            mismatched ``materials``/``names`` lengths, duplicate names, bad ``mesh_size``,
            a ``crossed`` name that is no block.
    """
    n = len(polygons)
    if n == 0:
        raise ValueError("mesh_blocks needs at least one polygon")
    names = [f"block:{i}" for i in range(n)] if names is None else [str(s) for s in names]
    if len(names) != n:
        raise ValueError(f"got {len(names)} names for {n} polygons")
    if len(set(names)) != n:
        dup = sorted({s for s in names if names.count(s) > 1})
        raise ValueError(f"duplicate block names: {dup[:5]}")
    material_names, block_material = material_table(materials, n)
    sizes = _mesh_sizes(mesh_size, n)
    unknown = sorted(set(crossed) - set(names))
    if unknown:
        raise ValueError(f"crossed: no block named {unknown[:5]}")
    cross = [name in set(crossed) for name in names]
    # validate everywhere (cheap), so bad input fails the same way on every rank
    polys = [as_polygon(p, name) for p, name in zip(polygons, names, strict=True)]

    def work() -> dict:
        t0 = time.perf_counter()
        x, cells, cell_block = _gmsh_triangulate(polys, sizes, names, cross)
        bm = BlockMesh.from_arrays(
            x, cells, cell_block, block_names=names, material_names=material_names,
            block_material=block_material,
        )
        log.debug("meshed %d blocks into %d triangles in %.3f s",
                  bm.n_blocks, bm.n_cells, time.perf_counter() - t0)
        return bm.core_arrays()

    return BlockMesh(**on_root(comm, work))
