"""Read a user's Gmsh mesh into a :class:`BlockMesh`, and write a block mesh to ``.msh``.

Two ways to find the blocks of an imported mesh:

* ``blocks="physical"``: each physical surface group is one block, named after the group
  (``"physical:<tag>"`` if unnamed). Nodes on the common edge of two groups are duplicated,
  so a conforming mesh of a whole wall becomes separate blocks. Surfaces in no group are
  left out.
* ``blocks="components"``: each connected set of triangles (connected through shared
  nodes) is a block, named ``"<group>:<k>"`` after the physical group of its cells (or
  ``"block:<k>"``), ``k`` counting the components of that group.

Materials: ``materials`` maps physical group names (or shell patterns such as
``"brick:*"``) to material names. Without it a block's material is the part of its group
name before the first ``":"`` (``"brick:17"`` -> ``"brick"``), or ``"default"`` for cells in
no group. :func:`write_msh` writes one physical group per block named after the block, so
``read_msh(path, materials=dict(zip(bm.block_names, bm.block_material_names)))``
restores a block mesh exactly.

Linear triangles are read as they are; linear quadrangles are split into two triangles.

Joints: a physical *line* group (Physical Curve, 1D) drawn along interfaces between blocks
names those joints. :func:`read_msh_lines` reads the segments of every such group and
:func:`interface_rules` turns ``{group name: joint material}`` into the ``where`` rules of
:class:`~masonry_fdem.interactions.Joints`, so the interfaces on a group get the joint
material named for it, e.g.::

    lines = read_msh_lines("wall.msh")
    joints = Joints(model, {("brick", "brick"): None},
                    where=interface_rules(lines, {"bed": mortar, "head": None}))
"""

from __future__ import annotations

import fnmatch
import logging
from pathlib import Path
from typing import Any, Literal

import gmsh
import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from masonry_fdem.geometry._gmsh import gmsh_model, on_root
from masonry_fdem.geometry.blockmesh import BlockMesh

__all__ = ["interface_rules", "read_msh", "read_msh_lines", "write_msh"]

log = logging.getLogger(__name__)

_LINE, _TRIANGLE, _QUADRANGLE = 1, 2, 3  # Gmsh types: linear lines, triangles, quads
_DEFAULT_MATERIAL = "default"


def _default_material(group: str | None) -> str:
    return _DEFAULT_MATERIAL if group is None else group.split(":", 1)[0]


class _MaterialMap:
    """Physical group name -> material, remembering which entries were used."""

    def __init__(self, materials: dict[str, str] | None, path: Path):
        self.materials = None if materials is None else dict(materials)
        self.path = path
        self.used: set[str] = set()

    def __call__(self, group: str | None) -> str:
        if self.materials is None:
            return _default_material(group)
        if group is None:
            raise ValueError(f"{self.path}: cells in no physical group, so no material "
                             "can be assigned from `materials`")
        keys = [group] if group in self.materials else [
            k for k in self.materials if fnmatch.fnmatchcase(group, k)]
        if not keys:
            raise ValueError(f"{self.path}: physical group {group!r} is not in `materials` "
                             f"(keys: {sorted(self.materials)})")
        self.used.add(keys[0])
        return self.materials[keys[0]]

    def check_all_used(self) -> None:
        if self.materials is not None:
            unused = sorted(set(self.materials) - self.used)
            if unused:
                raise ValueError(f"{self.path}: `materials` names physical groups that are "
                                 f"not in the mesh: {unused}")


def _surface_cells(path: Path) -> dict[int, np.ndarray]:
    """Triangles (Gmsh node tags, ``(m, 3)``) of each 2D entity, quadrangles split."""
    out: dict[int, np.ndarray] = {}
    for _, tag in gmsh.model.getEntities(2):
        types, _, nodes = gmsh.model.mesh.getElements(2, tag)
        tris = []
        for etype, enodes in zip(types, nodes, strict=True):
            enodes = np.asarray(enodes, dtype=np.int64)
            if etype == _TRIANGLE:
                tris.append(enodes.reshape(-1, 3))
            elif etype == _QUADRANGLE:
                q = enodes.reshape(-1, 4)
                tris += [q[:, [0, 1, 2]], q[:, [0, 2, 3]]]
            else:
                name = gmsh.model.mesh.getElementProperties(etype)[0]
                raise ValueError(f"{path}: unsupported element type {name!r}; only linear "
                                 "triangles (and quadrangles) are supported")
        if tris:
            out[tag] = np.concatenate(tris)
    return out


def _load(path: Path) -> tuple[np.ndarray, np.ndarray, dict[int, np.ndarray]]:
    """Merge the file into the current Gmsh model; return (node tags, xyz, cells)."""
    try:
        gmsh.merge(str(path))
    except Exception as exc:
        raise ValueError(f"Gmsh cannot read {path}: {exc}") from exc
    for _, tag in gmsh.model.getEntities(3):
        if any(len(t) for t in gmsh.model.mesh.getElements(3, tag)[1]):
            raise ValueError(f"3D mesh: {path} has volume elements; only plane meshes of "
                             "triangles are supported")
    if path.suffix == ".geo" and not any(
            len(gmsh.model.mesh.getElements(2, t)[1]) for _, t in gmsh.model.getEntities(2)):
        gmsh.model.mesh.generate(2)
    tags, xyz, _ = gmsh.model.mesh.getNodes()
    xyz = np.asarray(xyz, dtype=np.float64).reshape(-1, 3)
    scale = max(float(np.abs(xyz).max(initial=0.0)), 1.0)
    if np.any(np.abs(xyz[:, 2]) > 1e-12 * scale):
        raise ValueError(f"3D mesh: {path} has nodes with nonzero z; blocks must lie in the "
                         "plane z = 0")
    cells = _surface_cells(path)
    if not cells:
        raise ValueError(f"{path}: no triangles (a 2D mesh of triangles is required)")
    return np.asarray(tags, dtype=np.int64), xyz[:, :2], cells


def _groups_of_entities() -> tuple[dict[str, list[int]], dict[int, list[str]]]:
    """Surfaces of each physical surface group (by name, in tag order), groups of each surface."""
    groups: dict[str, list[int]] = {}
    of_entity: dict[int, list[str]] = {}
    for _, ptag in sorted(gmsh.model.getPhysicalGroups(2)):
        name = gmsh.model.getPhysicalName(2, ptag) or f"physical:{ptag}"
        if name in groups:
            raise ValueError(f"two physical surface groups are named {name!r}")
        ents = sorted(int(e) for e in gmsh.model.getEntitiesForPhysicalGroup(2, ptag))
        groups[name] = ents
        for ent in ents:
            of_entity.setdefault(ent, []).append(name)
    return groups, of_entity


def _read(path: Path, mode: str, materials: dict[str, str] | None) -> dict:
    if not path.is_file():
        raise FileNotFoundError(f"mesh file not found: {path}")
    with gmsh_model():
        tags, x_all, cells = _load(path)
        groups, of_entity = _groups_of_entities()
    row = np.full(int(tags.max()) + 1, -1, dtype=np.int64)
    row[tags] = np.arange(tags.size)
    matmap = _MaterialMap(materials, path)
    if not groups and (mode == "physical" or materials is not None):
        why = "blocks='physical'" if mode == "physical" else "`materials` was given"
        raise ValueError(f"{path}: no physical surface groups, but {why}; tag each block "
                         "with a Physical Surface (or use blocks='components' without "
                         "materials)")
    block_names: list[str] = []
    block_mats: list[str] = []
    if mode == "physical":
        multi = {e: g for e, g in of_entity.items() if len(g) > 1 and e in cells}
        if multi:
            e, g = next(iter(multi.items()))
            raise ValueError(f"{path}: surface {e} is in several physical groups {g}; a "
                             "cell must belong to one block")
        xs, cs, cb = [], [], []
        n0 = 0
        for name, group_ents in groups.items():
            ents = [e for e in group_ents if e in cells]
            if not ents:
                log.warning("%s: physical group %r has no triangles; skipped", path, name)
                continue
            tri = row[np.concatenate([cells[e] for e in ents])]
            used, local = np.unique(tri, return_inverse=True)
            xs.append(x_all[used])  # nodes duplicated per group
            cs.append(local.reshape(-1, 3) + n0)
            cb.append(np.full(tri.shape[0], len(block_names), dtype=np.int64))
            n0 += used.size
            block_names.append(name)
            block_mats.append(matmap(name))
        dropped = [e for e in cells if e not in of_entity]
        if dropped:
            log.warning("%s: surfaces %s are in no physical group; left out", path, dropped)
        if not block_names:
            raise ValueError(f"{path}: no triangles in any physical surface group")
        x, tri, cell_block = np.vstack(xs), np.concatenate(cs), np.concatenate(cb)
    else:
        ents = sorted(cells)
        tri = row[np.concatenate([cells[e] for e in ents])]
        cell_group = [of_entity.get(e, [None])[0] for e in ents for _ in range(len(cells[e]))]
        n = x_all.shape[0]
        a = tri[:, [0, 1, 2]].ravel()
        b = tri[:, [1, 2, 0]].ravel()
        graph = coo_matrix((np.ones(a.size, dtype=np.int8), (a, b)), shape=(n, n))
        _, node_label = connected_components(graph, directed=False)
        label = node_label[tri[:, 0]]
        _, first = np.unique(label, return_index=True)
        rank = np.empty(label.max() + 1, dtype=np.int64)
        rank[label[np.sort(first)]] = np.arange(first.size)
        cell_block = rank[label]
        per_prefix: dict[str, int] = {}
        for b_id, c0 in enumerate(np.sort(first)):
            in_block = np.flatnonzero(cell_block == b_id)
            grps = sorted({cell_group[i] for i in in_block}, key=lambda g: (g is None, g))
            mats = {matmap(g) for g in grps}
            if len(mats) > 1:
                raise ValueError(f"{path}: connected cells of groups {grps} have different "
                                 f"materials {sorted(mats)}; split them into separate "
                                 "blocks (blocks='physical') or give one material")
            prefix = cell_group[c0] or "block"
            k = per_prefix.get(prefix, 0)
            per_prefix[prefix] = k + 1
            block_names.append(f"{prefix}:{k}")
            block_mats.append(mats.pop())
        x = x_all
    matmap.check_all_used()
    material_names = tuple(dict.fromkeys(block_mats))
    bmat = [material_names.index(m) for m in block_mats]
    bm = BlockMesh.from_arrays(x, tri, cell_block, block_names=block_names,
                               material_names=material_names, block_material=bmat)
    return bm.core_arrays()


def read_msh(
    path: str | Path,
    *,
    blocks: Literal["physical", "components"] = "physical",
    materials: dict[str, str] | None = None,
    comm: Any | None = None,
) -> BlockMesh:
    """Import a plane Gmsh mesh (``.msh``, or a ``.geo`` that is meshed in 2D) as blocks.

    Args:
        path: the file.
        blocks: "physical" (one block per physical surface group, shared nodes duplicated)
            or "components" (one block per connected set of cells).
        materials: physical group name or shell pattern -> material name; every group
            that holds blocks must be covered and every key must match a group.
        comm: mpi4py communicator; if given, rank 0 reads and every rank receives the
            same block mesh (collective call).

    Returns:
        The block mesh.

    Raises:
        FileNotFoundError: the file does not exist.
        ValueError: unreadable file, 3D mesh (volume elements or nonzero z), no triangles,
            non-linear elements, missing physical groups or materials, a cell in two groups.
    """
    if blocks not in ("physical", "components"):
        raise ValueError(f"blocks must be 'physical' or 'components', got {blocks!r}")
    path = Path(path)
    return BlockMesh(**on_root(comm, lambda: _read(path, blocks, materials)))


def _read_lines(path: Path) -> dict[str, np.ndarray]:
    if not path.is_file():
        raise FileNotFoundError(f"mesh file not found: {path}")
    out: dict[str, np.ndarray] = {}
    with gmsh_model():
        try:
            gmsh.merge(str(path))
        except Exception as exc:
            raise ValueError(f"Gmsh cannot read {path}: {exc}") from exc
        tags, xyz, _ = gmsh.model.mesh.getNodes()
        tags = np.asarray(tags, dtype=np.int64)
        xyz = np.asarray(xyz, dtype=np.float64).reshape(-1, 3)
        row = np.full(int(tags.max(initial=0)) + 1, -1, dtype=np.int64)
        row[tags] = np.arange(tags.size)
        for _, ptag in sorted(gmsh.model.getPhysicalGroups(1)):
            name = gmsh.model.getPhysicalName(1, ptag) or f"physical:{ptag}"
            if name in out:
                raise ValueError(f"{path}: two physical line groups are named {name!r}")
            segs = []
            for ent in gmsh.model.getEntitiesForPhysicalGroup(1, ptag):
                types, _, nodes = gmsh.model.mesh.getElements(1, int(ent))
                for etype, enodes in zip(types, nodes, strict=True):
                    if etype != _LINE:
                        ename = gmsh.model.mesh.getElementProperties(etype)[0]
                        raise ValueError(f"{path}: physical line group {name!r} has "
                                         f"{ename!r} elements; only 2-node lines are read")
                    segs.append(row[np.asarray(enodes, dtype=np.int64).reshape(-1, 2)])
            if not segs:
                log.warning("%s: physical line group %r has no line elements; skipped",
                            path, name)
                continue
            seg = np.concatenate(segs)
            out[name] = xyz[seg][:, :, :2].copy()
    return out


def read_msh_lines(path: str | Path, *, comm: Any | None = None) -> dict[str, np.ndarray]:
    """The physical line groups (1D) of a Gmsh mesh: the interfaces they mark.

    Args:
        path: the ``.msh`` file.
        comm: mpi4py communicator; if given, rank 0 reads and every rank receives the
            result (collective call).

    Returns:
        ``{group name: (m, 2, 2) segment end points [m]}`` (``"physical:<tag>"`` for an
        unnamed group); empty when the mesh has no physical lines.

    Raises:
        FileNotFoundError: the file does not exist.
        ValueError: unreadable file, two groups of one name, curved (higher-order) lines.
    """
    path = Path(path)
    return on_root(comm, lambda: _read_lines(path))


def interface_rules(lines: dict[str, np.ndarray], materials: dict[str, Any],
                    tolerance: float | None = None) -> list[tuple[Any, Any]]:
    """``where`` rules of :class:`~masonry_fdem.interactions.Joints` from line groups.

    Args:
        lines: ``{group name: (m, 2, 2) segments [m]}`` (:func:`read_msh_lines`).
        materials: ``{group name: JointMaterial or None (dry)}``; every key must be a
            group of ``lines``.
        tolerance: distance [m] from a group's segments within which a joint's midpoint
            is on the group (default: 1e-6 of the largest extent of the lines, at least
            1e-12 m).

    Returns:
        ``[(predicate(midpoint) -> bool, material), ...]`` in the order of ``materials``.

    Raises:
        ValueError: a key of ``materials`` that is not a line group.
    """
    unknown = sorted(set(materials) - set(lines))
    if unknown:
        raise ValueError(f"joint materials name physical line groups that are not in the "
                         f"mesh: {unknown} (line groups: {sorted(lines) or 'none'})")
    if tolerance is None:
        pts = np.concatenate([s.reshape(-1, 2) for s in lines.values()]) if lines else \
            np.zeros((1, 2))
        tolerance = max(1e-6 * float(np.ptp(pts, axis=0).max()), 1e-12)
    tol = float(tolerance)

    def on(seg: np.ndarray):
        a, d = seg[:, 0], seg[:, 1] - seg[:, 0]
        dd = np.maximum(np.einsum("ij,ij->i", d, d), 1e-300)

        def predicate(p) -> bool:
            t = np.clip(np.einsum("ij,ij->i", np.asarray(p)[None, :2] - a, d) / dd, 0, 1)
            dist = np.hypot(*(a + t[:, None] * d - np.asarray(p)[None, :2]).T)
            return bool(dist.min() <= tol)

        return predicate

    return [(on(lines[name]), jm) for name, jm in materials.items()]


def write_msh(block_mesh: BlockMesh, path: str | Path, *, comm: Any | None = None) -> Path:
    """Write a block mesh to a Gmsh ``.msh`` file (format 4.1, ASCII).

    Each block is a discrete surface with its own nodes and a physical group named after
    the block (physical tag = block id + 1). Materials are not stored; see the module
    docstring for a lossless round trip.

    Args:
        block_mesh: the block mesh.
        path: output file; must end in ``.msh``; parent folders are created.
        comm: mpi4py communicator; if given, rank 0 writes (collective call).

    Returns:
        The path written.
    """
    path = Path(path)
    if path.suffix != ".msh":
        raise ValueError(f"write_msh writes .msh files, got {path}")
    bm = block_mesh

    def work() -> None:
        path.parent.mkdir(parents=True, exist_ok=True)
        opts = {"Mesh.MshFileVersion": 4.1, "Mesh.Binary": 0, "Mesh.SaveAll": 0}
        with gmsh_model(opts):
            xyz = np.column_stack([bm.x, np.zeros(bm.n_nodes)])
            for b in range(bm.n_blocks):
                tag = b + 1
                n0, n1 = bm.node_offsets[b], bm.node_offsets[b + 1]
                c0, c1 = bm.cell_offsets[b], bm.cell_offsets[b + 1]
                gmsh.model.addDiscreteEntity(2, tag)
                gmsh.model.mesh.addNodes(2, tag, np.arange(n0, n1) + 1, xyz[n0:n1].ravel())
                gmsh.model.mesh.addElementsByType(tag, _TRIANGLE, [],
                                                  (bm.cells[c0:c1] + 1).ravel())
                gmsh.model.addPhysicalGroup(2, [tag], tag, name=bm.block_names[b])
            gmsh.write(str(path))

    on_root(comm, work)
    return path
