"""Tests of masonry_fdem.geometry: block mesh, builders, Gmsh meshing, .msh import/export.

Runs serially and under ``mpirun -n 2``; tests that pass ``comm`` check that every rank
receives identical arrays.
"""

import hashlib
import math
from pathlib import Path

from mpi4py import MPI

import gmsh
import numpy as np
import pytest

from masonry_fdem import geometry as g
from masonry_fdem.geometry import BlockMesh

COMM = MPI.COMM_WORLD
REL = 1e-12  # relative tolerance of exact (polygon) areas: round-off only


# ---------------------------------------------------------------- helpers
def assert_canonical(bm: BlockMesh) -> None:
    """Facts every block mesh must satisfy."""
    # contiguous, non-shared nodes: every cell's nodes lie in its block's node range
    nb = bm.node_block[bm.cells]
    assert np.all(nb == bm.cell_block[:, None])
    assert np.all(np.diff(bm.node_offsets) > 0) and np.all(np.diff(bm.cell_offsets) > 0)
    assert np.array_equal(np.unique(bm.cells), np.arange(bm.n_nodes))  # no unused node
    assert np.all(bm.cell_area > 0.0)  # counter-clockwise
    assert bm.cell_block.shape == (bm.n_cells,) and bm.cell_material.shape == (bm.n_cells,)


def assert_boundary_loops(bm: BlockMesh) -> None:
    """Each block's boundary facets form one closed loop enclosing exactly its area."""
    f, off = bm.boundary_facets, bm.facet_offsets
    assert off[0] == 0 and off[-1] == f.shape[0]
    for b in range(bm.n_blocks):
        loop = f[off[b]:off[b + 1]]
        assert loop.shape[0] >= 3
        assert np.all(bm.node_block[loop] == b)
        assert np.array_equal(loop[1:, 0], loop[:-1, 1]), "facets not chained"
        assert loop[-1, 1] == loop[0, 0], "loop not closed"
        assert np.unique(loop[:, 0]).size == loop.shape[0], "more than one loop"
        p, q = bm.x[loop[:, 0]], bm.x[loop[:, 1]]
        signed = 0.5 * np.sum(p[:, 0] * q[:, 1] - q[:, 0] * p[:, 1])
        assert signed == pytest.approx(bm.block_area[b], rel=REL)


def rank0_tmp(tmp_path: Path) -> Path:
    """A folder that exists on rank 0 (files read with comm are read there)."""
    return Path(COMM.bcast(str(tmp_path), root=0))


def same_on_all_ranks(*arrays) -> bool:
    digest = tuple(hashlib.sha1(np.ascontiguousarray(a).tobytes()).hexdigest() for a in arrays)
    return all(d == digest for d in COMM.allgather(digest))


# ---------------------------------------------------------------- walls
def test_wall_running_bond_counts_area_and_no_shared_nodes():
    courses, n, length, height = 5, 4, 0.215, 0.065
    bm = g.build_wall(courses=courses, bricks_per_course=n, brick_length=length,
                      brick_height=height)
    assert_canonical(bm)
    full = bm.select("brick:*")
    half = bm.select("half:*")
    # courses 0, 2, 4: n full; courses 1, 3: n-1 full + 2 halves
    assert full.size == 3 * n + 2 * (n - 1) and half.size == 2 * 2
    assert bm.n_blocks == 3 * n + 2 * (n + 1)
    assert bm.block_area.sum() == pytest.approx(n * length * courses * height, rel=REL)
    assert np.allclose(bm.block_area[half], 0.5 * length * height, rtol=REL)
    assert np.allclose(bm.bounds, [0.0, 0.0, n * length, courses * height], atol=1e-15)
    # touching bricks keep separate nodes at the same place
    _, counts = np.unique(np.round(bm.x, 12), axis=0, return_counts=True)
    assert counts.max() >= 2
    assert bm.material_names == ("brick",) and np.all(bm.block_material == 0)


def test_wall_joints_flush_ends_and_bond():
    n, length, height, joint = 3, 0.2, 0.1, 0.01
    lay = g.wall_layout(courses=2, bricks_per_course=n, brick_length=length,
                        brick_height=height, joint=joint, origin=(1.0, 2.0))
    wall_length = n * length + (n - 1) * joint
    for c in range(2):
        xs = np.vstack([p for p, s in zip(lay.polygons, lay.names, strict=True)
                        if s.split(":")[1] == str(c)])
        assert xs[:, 0].min() == pytest.approx(1.0) and xs[:, 0].max() == pytest.approx(
            1.0 + wall_length)
    # vertical joints of course 1 sit over the middle of course-0 bricks
    mids = [p[:, 0].mean() for p, s in zip(lay.polygons, lay.names, strict=True)
            if s.startswith("brick:0:")]
    gaps = sorted({round(p[:, 0].max() + 0.5 * joint, 12)
                   for p, s in zip(lay.polygons, lay.names, strict=True)
                   if s.split(":")[1] == "1"})[:-1]
    assert np.allclose(gaps, mids[:len(gaps)], atol=1e-12)
    assert lay.bounds[3] == pytest.approx(2.0 + 2 * height + joint)


def test_coarsest_mesh_is_two_triangles_and_finer_keeps_area():
    kw = dict(courses=3, bricks_per_course=3, brick_length=0.3, brick_height=0.1)
    coarse = g.build_wall(**kw)
    big = g.build_wall(mesh_size=10.0, **kw)  # larger than any block
    fine = g.build_wall(mesh_size=0.03, **kw)
    for bm in (coarse, big):
        assert np.all(np.diff(bm.cell_offsets) == 2)
        assert np.all(np.diff(bm.node_offsets) == 4)
    assert np.all(np.diff(fine.cell_offsets) > 2)
    assert fine.n_cells > 10 * coarse.n_cells
    assert fine.block_area == pytest.approx(coarse.block_area, rel=REL)
    for bm in (coarse, fine):
        assert_canonical(bm)
        assert_boundary_loops(bm)
    # the longest facet of the fine mesh is about mesh_size, not the brick length
    e = fine.x[fine.boundary_facets[:, 1]] - fine.x[fine.boundary_facets[:, 0]]
    assert np.linalg.norm(e, axis=1).max() < 0.06


def test_mesh_blocks_many_blocks_and_polygon_validation():
    rng = np.random.default_rng(0)
    polys = [np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float) * 0.1 + [0.2 * i, 0.0]
             for i in range(300)]
    bm = g.mesh_blocks([p[::-1] for p in polys],  # clockwise input
                       materials=[["a", "b"][i % 2] for i in range(300)])
    assert bm.n_blocks == 300 and bm.n_cells == 600
    assert bm.material_names == ("a", "b")
    assert np.array_equal(bm.block_material, np.arange(300) % 2)
    assert bm.block_names[7] == "block:7"
    assert np.allclose(bm.block_centroid[:, 0], 0.2 * np.arange(300) + 0.05)
    # a polygon with many vertices (a circle) meshes to k - 2 triangles
    t = np.linspace(0, 2 * np.pi, 40, endpoint=False) + rng.uniform(0, 1e-3)
    circ = np.column_stack([np.cos(t), np.sin(t)])
    assert g.mesh_blocks([circ], materials="c").n_cells == 38
    with pytest.raises(ValueError, match="cross"):
        g.mesh_blocks([np.array([[0, 0], [2, 2], [2, 0], [0, 1]], float)], materials="a")
    with pytest.raises(ValueError, match="zero area"):
        g.mesh_blocks([np.array([[0, 0], [1, 0], [2, 0]], float)], materials="a")
    with pytest.raises(ValueError, match="3D"):
        g.mesh_blocks([np.array([[0, 0, 1], [1, 0, 1], [0, 1, 1]], float)], materials="a")
    with pytest.raises(ValueError, match="materials"):
        g.mesh_blocks(polys[:2], materials=["a"])
    with pytest.raises(ValueError, match="duplicate"):
        g.mesh_blocks(polys[:2], materials="a", names=["x", "x"])
    with pytest.raises(ValueError, match="mesh_size"):
        g.mesh_blocks(polys[:2], materials="a", mesh_size=-1.0)


def test_crossed_blocks_are_quadrilaterals_split_by_their_diagonals():
    """A crossed block: every interior node added is the centre of four triangles, the
    area is kept, the other blocks are meshed as before; a bad name is refused."""
    soil = np.array([[0, 0], [2.0, 0], [2.0, 0.7], [1.1, 1.2], [0, 1.0]])
    brick = np.array([[3, 0], [3.4, 0], [3.4, 0.2], [3, 0.2]], float)
    plain = g.mesh_blocks([soil, brick], materials="a", names=["soil", "brick"],
                          mesh_size=0.2)
    bm = g.mesh_blocks([soil, brick], materials="a", names=["soil", "brick"],
                       mesh_size=0.2, crossed=["soil"])
    assert_canonical(bm)
    assert_boundary_loops(bm)
    assert bm.block_area == pytest.approx(plain.block_area, rel=REL)
    cells = bm.cells[bm.cell_offsets[0]:bm.cell_offsets[1]]
    assert len(cells) % 4 == 0
    # each node of the crossed block is a vertex of its quadrilaterals (boundary or
    # interior, any count of triangles) or a centre: in exactly four triangles, whose
    # other vertices form a quadrilateral with the centre at their vertex average
    nodes, count = np.unique(cells, return_counts=True)
    boundary = np.unique(bm.boundary_facets[bm.facet_block == 0])
    centres = [v for v in nodes[count == 4] if v not in boundary and np.allclose(
        bm.x[np.unique(cells[np.any(cells == v, axis=1)])].sum(axis=0) - bm.x[v],
        4.0 * bm.x[v])]
    assert len(centres) == len(cells) // 4
    # the brick is meshed as without crossed blocks
    assert (bm.cell_offsets[2] - bm.cell_offsets[1]) == (plain.cell_offsets[2]
                                                         - plain.cell_offsets[1])
    x, tri = g.cross_quads(np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float),
                           np.array([[0, 1, 2, 3]]))
    assert np.allclose(x[4], [0.5, 0.5]) and tri.shape == (4, 3)
    with pytest.raises(ValueError, match="crossed: no block"):
        g.mesh_blocks([soil], materials="a", names=["soil"], crossed=["fill"])


def test_gmsh_state_is_left_as_found():
    square = [g.rectangle(0, 0, 1, 1)]
    assert not gmsh.isInitialized()
    g.mesh_blocks(square, materials="a")
    assert not gmsh.isInitialized()
    gmsh.initialize(interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("users_model")
        gmsh.option.setNumber("Mesh.Algorithm", 5)
        g.mesh_blocks(square, materials="a", mesh_size=0.2)
        assert gmsh.isInitialized()
        assert gmsh.model.getCurrent() == "users_model"
        assert gmsh.option.getNumber("Mesh.Algorithm") == 5
    finally:
        gmsh.finalize()


def test_mesh_blocks_broadcast_identical_on_all_ranks():
    lay = g.wall_layout(courses=4, bricks_per_course=5, brick_length=0.2, brick_height=0.1)
    bm = lay.mesh(mesh_size=0.04, comm=COMM)
    assert_canonical(bm)
    assert same_on_all_ranks(bm.x, bm.cells, bm.node_offsets, bm.cell_offsets,
                             bm.block_material, bm.boundary_facets)
    assert COMM.allgather(bm.block_names) == [bm.block_names] * COMM.size
    # an error on rank 0 is raised on every rank
    with pytest.raises(ValueError, match="duplicate"):
        g.BlockLayout(lay.polygons[:2], ("a", "a"), ("x", "x")).mesh(comm=COMM)


# ---------------------------------------------------------------- BlockMesh
def test_from_arrays_renumbers_orients_and_drops_unused():
    x = np.array([[0, 0], [1, 0], [1, 1], [0, 1],  # block 1 (square)
                  [9, 9],                          # unused
                  [2, 0], [3, 0], [2, 1]], float)  # block 0 (triangle)
    cells = np.array([[0, 2, 1], [5, 6, 7], [0, 2, 3]])  # first one clockwise
    bm = BlockMesh.from_arrays(x, cells, [1, 0, 1], block_names=["tri", "sq"],
                               material_names=["m0", "m1"], cell_material=[1, 0, 1])
    assert_canonical(bm)
    assert bm.n_nodes == 7 and bm.n_blocks == 2
    assert np.array_equal(bm.node_offsets, [0, 3, 7])
    assert np.array_equal(bm.cell_offsets, [0, 1, 3])
    assert np.allclose(bm.x[:3], [[2, 0], [3, 0], [2, 1]])
    assert np.array_equal(bm.block_material, [0, 1])
    assert bm.block_area == pytest.approx([0.5, 1.0], rel=REL)
    assert bm.block_centroid == pytest.approx(np.array([[7 / 3, 1 / 3], [0.5, 0.5]]), rel=REL)
    assert bm.block_bounds[1] == pytest.approx([0, 0, 1, 1])
    assert_boundary_loops(bm)
    assert bm.facet_offsets.tolist() == [0, 3, 7]


@pytest.mark.parametrize(
    "x, cells, cell_block, kw, match",
    [
        (np.zeros((3, 3)) + [0, 0, 1], [[0, 1, 2]], [0], {}, "3D"),
        (np.zeros((3,)), [[0, 1, 2]], [0], {}, "shape"),
        ([[0, 0], [1, 0], [2, 0]], [[0, 1, 2]], [0], {}, "degenerate"),
        ([[0, 0], [1, 0], [0, 1], [1, 1]], [[0, 1, 2], [1, 3, 2]], [0, 1],
         {"block_names": ["a", "b"]}, "shared by two blocks"),
        ([[0, 0], [1, 0], [0, 1]], [[0, 1, 2]], [0], {"block_names": ["a", "b"]},
         "without cells"),
        ([[0, 0], [1, 0], [0, 1]], [[0, 1, 3]], [0], {}, "outside"),
        ([[0, 0], [1, 0], [0, 1], [1, 1]], [[0, 1, 2], [1, 3, 2]], [0, 0],
         {"material_names": ["p", "q"], "cell_material": [0, 1]}, "more than one material"),
        ([[0, 0], [1, 0], [0, 1]], [[0, 1, 2]], [0], {"block_names": ["a", "a"]}, "duplicate"),
    ],
)
def test_from_arrays_errors(x, cells, cell_block, kw, match):
    args = {"block_names": ["a"], "material_names": ["m"], **kw}
    with pytest.raises(ValueError, match=match):
        BlockMesh.from_arrays(np.asarray(x, float), np.asarray(cells), cell_block, **args)


def test_select_and_block_of_point():
    bm = g.build_wall(courses=2, bricks_per_course=2, brick_length=0.2, brick_height=0.1)
    assert bm.select("half:*").tolist() == [2, 4]
    assert bm.select(["brick:0:*", "half:1:2"]).tolist() == [0, 1, 4]
    assert bm.select(lambda c: c[1] > 0.1).tolist() == [2, 3, 4]
    assert bm.select(material="brick").size == bm.n_blocks
    with pytest.raises(ValueError, match="no block named"):
        bm.select("voussoir:*")
    assert bm.block_of_point([0.05, 0.05]) == 0
    assert bm.block_of_point([0.25, 0.15]) == 3
    assert bm.block_of_point((0.2, 0.05)) == 0  # on the shared edge: lower id
    assert bm.block_of_point([[0.35, 0.15], [1.0, 1.0]]).tolist() == [4, -1]
    sub = bm.subset([4, 0])
    assert sub.block_names == ("half:1:2", "brick:0:0")
    assert sub.block_area == pytest.approx(bm.block_area[[4, 0]], rel=REL)


# ---------------------------------------------------------------- stacks, base
def test_stack_and_block_on_base_centroids():
    w, h, off = 0.4, 0.2, 0.05
    bm = g.build_stack(5, width=w, height=h, offset=off, origin=(1.0, 0.5))
    expect = np.column_stack([1.0 + off * np.arange(5) + w / 2, 0.5 + h * (np.arange(5) + 0.5)])
    assert bm.block_centroid == pytest.approx(expect, rel=REL)
    zig = g.stack_layout(4, width=w, height=h, offset=off, alternate=True)
    assert [p[:, 0].min() for p in zig.polygons] == pytest.approx([0, off, 0, off])
    base = g.build_block_on_base(width=1.0, height=2.0, base_width=3.0, base_height=0.5,
                                 offset=0.25, material="stone")
    assert base.block_names == ("base", "block")
    assert base.block_material_names == ("base", "stone")
    assert base.block_centroid == pytest.approx(np.array([[1.5, 0.25], [1.75, 1.5]]), rel=REL)
    with pytest.raises(ValueError, match="base_width"):
        g.block_on_base_layout(width=2.0, height=1.0, base_width=1.0, base_height=1.0)


# ---------------------------------------------------------------- arches
def _ring_joint_angles(lay: g.BlockLayout, ring: int, centre=(0.0, 0.0)) -> np.ndarray:
    """Angles [rad] of the interior joints of a ring (from the block vertex angles)."""
    ends = []
    for p, name in zip(lay.polygons, lay.names, strict=True):
        if name.startswith(f"voussoir:{ring}:"):
            a = np.arctan2(p[:, 1] - centre[1], p[:, 0] - centre[0])
            ends += [a.min(), a.max()]
    ends = np.unique(np.round(ends, 12))
    return ends[(ends > 1e-9) & (ends < np.pi - 1e-9)]


def test_semicircular_arch_counts_area_and_stagger():
    span, t, n, segments = 2.0, 0.15, 9, 3
    R = span / 2
    lay = g.arch_layout(span=span, ring_thickness=t, voussoirs=n, rings=3, segments=segments)
    counts = [sum(s.startswith(f"voussoir:{k}:") for s in lay.names) for k in range(3)]
    assert counts == [n, n + 1, n]  # ring 1 shifted by half a voussoir: two half voussoirs
    # ring areas against the annulus; chords of angle <= d lose less than d^2/6 (relative)
    d = np.pi / (n * segments)
    areas = lay.areas
    for k in range(3):
        ring = [i for i, s in enumerate(lay.names) if s.startswith(f"voussoir:{k}:")]
        a, b = R + k * t, R + (k + 1) * t
        exact = 0.5 * np.pi * (b * b - a * a)
        assert areas[ring].sum() == pytest.approx(exact, rel=d * d / 6 * (b / (b - a)))
    total = 0.5 * np.pi * ((R + 3 * t) ** 2 - R**2)
    bound = np.pi / 12 * ((R + 3 * t) ** 2 + R**2) * d * d
    assert abs(areas.sum() - total) <= bound
    assert areas.sum() < total  # inscribed polygons
    # staggered joints: ring 0 radial joints at pi j / n, no joint shared by neighbours
    j0, j1, j2 = (_ring_joint_angles(lay, k) for k in range(3))
    assert j0 == pytest.approx(np.pi * np.arange(1, n) / n, abs=1e-12)
    assert j0.size == n - 1 and j1.size == n
    assert np.abs(j0[:, None] - j1[None, :]).min() > 0.4 * np.pi / n
    assert np.abs(j1[:, None] - j2[None, :]).min() > 0.4 * np.pi / n
    # radial joints: each voussoir spans the same angles on its intrados and extrados
    for p, name in zip(lay.polygons, lay.names, strict=True):
        k = int(name.split(":")[1])
        r, ang = np.hypot(p[:, 0], p[:, 1]), np.arctan2(p[:, 1], p[:, 0])
        inner, outer = ang[np.isclose(r, R + k * t)], ang[np.isclose(r, R + (k + 1) * t)]
        assert inner.size + outer.size == p.shape[0]
        assert [inner.min(), inner.max()] == pytest.approx([outer.min(), outer.max()], abs=1e-12)
    aligned = g.arch_layout(span=span, ring_thickness=t, voussoirs=n, rings=2, stagger=0.0)
    assert _ring_joint_angles(aligned, 1) == pytest.approx(_ring_joint_angles(aligned, 0))
    # meshed: every vertex on the extrados of ring 0 is a vertex of ring 1 (no overlap)
    bm = g.build_arch(span=span, ring_thickness=t, voussoirs=n, rings=3, segments=segments)
    assert_canonical(bm)
    assert_boundary_loops(bm)
    assert bm.block_area.sum() == pytest.approx(areas.sum(), rel=REL)
    r = np.linalg.norm(bm.x, axis=1)
    on_face = np.isclose(r, R + t, rtol=1e-12)
    v0 = np.round(bm.x[on_face & np.isin(bm.node_block, bm.select("voussoir:0:*"))], 12)
    v1 = np.round(bm.x[on_face & np.isin(bm.node_block, bm.select("voussoir:1:*"))], 12)
    assert {tuple(v) for v in v0} == {tuple(v) for v in v1}


def test_segmental_arch_rise_and_abutments():
    span, rise, t = 3.0, 0.6, 0.2
    R = (span**2 / 4 + rise**2) / (2 * rise)
    yc = rise - R
    lay = g.arch_layout(kind="segmental", span=span, rise=rise, ring_thickness=t,
                        voussoirs=10, rings=2, segments=3, abutment_height=0.5,
                        origin=(5.0, 1.0))
    pts = np.vstack([p for p, s in zip(lay.polygons, lay.names, strict=True)
                     if s.startswith("voussoir:0:")]) - [5.0, 1.0]
    r = np.hypot(pts[:, 0], pts[:, 1] - yc)
    intrados = pts[np.isclose(r, R, rtol=1e-12)]
    assert intrados[:, 1].max() == pytest.approx(rise, rel=1e-12)  # crown joint at s = 0.5
    assert intrados[:, 0].min() == pytest.approx(-span / 2, rel=1e-12)
    assert intrados[:, 1].min() == pytest.approx(0.0, abs=1e-12)
    assert np.sum(np.isclose(r, R + t, rtol=1e-12)) > 0
    # abutments: inclined skewback through the springing, radial from the centre
    left = lay.polygons[lay.names.index("abutment:left")] - [5.0, 1.0]
    assert left[:, 1].min() == pytest.approx(-0.5)
    top = left[left[:, 1] > -0.5 + 1e-9]
    assert len(top) == 3  # one vertex per ring face (3 faces)
    rad = (top - [0.0, yc]) / np.linalg.norm(top - [0.0, yc], axis=1)[:, None]
    assert np.allclose(rad, rad[0], atol=1e-12)
    bm = lay.mesh(mesh_size=0.1)
    assert bm.material_names == ("voussoir", "abutment")
    assert bm.block_area.sum() == pytest.approx(lay.areas.sum(), rel=1e-12)
    assert_boundary_loops(bm)
    with pytest.raises(ValueError, match="rise < span/2"):
        g.arch_layout(kind="segmental", span=2.0, rise=1.0, ring_thickness=0.1, voussoirs=5)
    with pytest.raises(ValueError, match="narrower"):
        g.arch_layout(kind="segmental", span=span, rise=rise, ring_thickness=t, voussoirs=5,
                      abutment_height=0.5, abutment_width=0.01)


def test_pointed_arch_is_symmetric_with_apex():
    span, rise, t, n = 2.0, 1.6, 0.12, 7
    lay = g.arch_layout(kind="pointed", span=span, rise=rise, ring_thickness=t, voussoirs=n,
                        rings=2, segments=2, abutment_height=0.4, abutment_width=0.5)
    pts = np.unique(np.round(np.vstack(lay.polygons), 11), axis=0)
    mirrored = np.unique(np.round(pts * [-1, 1], 11), axis=0)
    assert np.allclose(pts, mirrored, atol=1e-10)
    a = dict(zip(lay.names, lay.areas, strict=True))
    for j in range(n):
        assert a[f"voussoir:0:{j}"] == pytest.approx(a[f"voussoir:0:{n - 1 - j}"], rel=1e-10)
    assert a["abutment:left"] == pytest.approx(a["abutment:right"], rel=REL)
    # apex (0, rise) is a vertex; intrados of the left half on the circle centred (c, 0)
    assert np.any(np.all(np.isclose(pts, [0.0, rise], atol=1e-12), axis=1))
    c = (rise**2 - span**2 / 4) / span
    left = np.vstack([p for p, s in zip(lay.polygons, lay.names, strict=True)
                      if s.startswith("voussoir:0:")])
    left = left[left[:, 0] < -1e-9]
    r = np.hypot(left[:, 0] - c, left[:, 1])
    assert np.sum(np.isclose(r, span / 2 + c, rtol=1e-12)) >= n
    assert np.all(r > span / 2 + c - 1e-12)
    bm = lay.mesh()
    assert_canonical(bm)
    assert_boundary_loops(bm)
    with pytest.raises(ValueError, match="pointed arch needs rise"):
        g.arch_layout(kind="pointed", span=2.0, rise=0.9, ring_thickness=0.1, voussoirs=5)


# ---------------------------------------------------------------- .msh import/export
def _write_two_rectangles(path: Path, names=("left", "right"), z: float = 0.0) -> int:
    """Two conforming rectangles sharing an edge, one physical surface each."""
    gmsh.initialize(interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        geo = gmsh.model.geo
        p = [geo.addPoint(x, y, z, 0.25) for x, y in [(0, 0), (1, 0), (2, 0), (2, 1), (1, 1),
                                                         (0, 1)]]
        lines = [geo.addLine(p[i], p[(i + 1) % 6]) for i in range(6)]
        mid = geo.addLine(p[1], p[4])
        s1 = geo.addPlaneSurface([geo.addCurveLoop([lines[0], mid, lines[4], lines[5]])])
        s2 = geo.addPlaneSurface([geo.addCurveLoop([lines[1], lines[2], lines[3], -mid])])
        geo.synchronize()
        if names:
            gmsh.model.addPhysicalGroup(2, [s1], name=names[0])
            gmsh.model.addPhysicalGroup(2, [s2], name=names[1])
        else:
            gmsh.option.setNumber("Mesh.SaveAll", 1)
        gmsh.model.mesh.generate(2)
        n_mid = len(gmsh.model.mesh.getNodes(1, mid, includeBoundary=True)[0])
        gmsh.write(str(path))
    finally:
        gmsh.finalize()
    return n_mid


def test_read_msh_physical_duplicates_shared_nodes(tmp_path):
    path = tmp_path / "two.msh"
    n_mid = _write_two_rectangles(path)
    bm = g.read_msh(path, materials={"left": "brick", "right": "stone"})
    assert bm.block_names == ("left", "right")
    assert bm.block_material_names == ("brick", "stone")
    assert_canonical(bm)
    assert_boundary_loops(bm)
    assert bm.block_area == pytest.approx([1.0, 1.0], rel=REL)
    # nodes of the common edge exist once per block
    on_edge = np.isclose(bm.x[:, 0], 1.0)
    assert on_edge.sum() == 2 * n_mid
    assert np.unique(bm.node_block[on_edge]).tolist() == [0, 1]
    # default material: group name before ':'; pattern keys
    assert g.read_msh(path).material_names == ("left", "right")
    pat = g.read_msh(path, materials={"*": "m"})
    assert pat.material_names == ("m",)
    with pytest.raises(ValueError, match="not in `materials`"):
        g.read_msh(path, materials={"left": "brick"})
    with pytest.raises(ValueError, match="not in the mesh"):
        g.read_msh(path, materials={"left": "a", "right": "b", "lintel": "c"})
    # the shared nodes make one component, which has two materials
    with pytest.raises(ValueError, match="different materials"):
        g.read_msh(path, blocks="components")
    one = g.read_msh(path, blocks="components", materials={"*": "brick"})
    assert one.n_blocks == 1 and one.block_area[0] == pytest.approx(2.0, rel=REL)


def test_read_msh_components_and_write_round_trip(tmp_path):
    lay = g.stack_layout(3, width=1.0, height=0.5) + g.BlockLayout(
        (g.rectangle(3, 0, 5, 1),), ("base",), ("base",))
    bm = lay.mesh(mesh_size=0.2)
    path = g.write_msh(bm, tmp_path / "sub" / "stack.msh")
    # physical groups per block: an exact round trip with the materials of the blocks
    back = g.read_msh(path, materials=dict(zip(bm.block_names, bm.block_material_names,
                                               strict=True)))
    assert back.block_names == bm.block_names
    assert np.array_equal(back.node_offsets, bm.node_offsets)
    assert np.array_equal(back.cells, bm.cells)
    assert np.allclose(back.x, bm.x, rtol=0, atol=1e-15)
    assert back.block_material_names == bm.block_material_names
    # components: the touching stack blocks do not share nodes, so they stay separate
    comp = g.read_msh(path, blocks="components")
    assert comp.n_blocks == 4
    assert comp.block_names == ("block:0:0", "block:1:0", "block:2:0", "base:0")
    assert comp.block_material_names == ("block",) * 3 + ("base",)
    assert comp.block_area == pytest.approx(bm.block_area, rel=REL)


def test_read_msh_components_without_groups_and_quads(tmp_path):
    path = tmp_path / "plain.msh"
    gmsh.initialize(interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        for x0 in (0.0, 2.0):
            gmsh.model.occ.addRectangle(x0, 0, 0, 1, 1)
        gmsh.model.occ.synchronize()
        gmsh.option.setNumber("Mesh.RecombineAll", 1)
        gmsh.option.setNumber("Mesh.MeshSizeMax", 0.5)
        gmsh.option.setNumber("Mesh.SaveAll", 1)
        gmsh.model.mesh.generate(2)
        n_quads = len(gmsh.model.mesh.getElementsByType(3)[0])
        gmsh.write(str(path))
    finally:
        gmsh.finalize()
    assert n_quads > 0
    bm = g.read_msh(path, blocks="components")
    assert bm.n_blocks == 2 and bm.block_names == ("block:0", "block:1")
    assert bm.material_names == ("default",)
    assert bm.block_area == pytest.approx([1.0, 1.0], rel=REL)
    assert bm.n_cells >= 2 * n_quads  # quadrangles split in two
    with pytest.raises(ValueError, match="no physical surface groups"):
        g.read_msh(path)
    with pytest.raises(ValueError, match="no physical surface groups.*materials"):
        g.read_msh(path, blocks="components", materials={"a": "b"})


def test_read_msh_errors(tmp_path):
    missing = tmp_path / "nope.msh"
    with pytest.raises(FileNotFoundError, match="nope.msh"):
        g.read_msh(missing)
    with pytest.raises(ValueError, match="blocks must be"):
        g.read_msh(missing, blocks="cells")
    # a volume mesh
    box = tmp_path / "box.msh"
    gmsh.initialize(interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.occ.addBox(0, 0, 0, 1, 1, 1)
        gmsh.model.occ.synchronize()
        gmsh.option.setNumber("Mesh.MeshSizeMax", 0.5)
        gmsh.model.addPhysicalGroup(3, [1], name="cube")
        gmsh.model.mesh.generate(3)
        gmsh.write(str(box))
        # only a line mesh
        gmsh.model.add("line")
        gmsh.model.occ.addLine(gmsh.model.occ.addPoint(0, 0, 0), gmsh.model.occ.addPoint(1, 0, 0))
        gmsh.model.occ.synchronize()
        gmsh.model.addPhysicalGroup(1, [1], name="wire")
        gmsh.model.mesh.generate(1)
        gmsh.write(str(tmp_path / "line.msh"))
    finally:
        gmsh.finalize()
    with pytest.raises(ValueError, match="^3D mesh"):
        g.read_msh(box)
    lifted = tmp_path / "lifted.msh"
    _write_two_rectangles(lifted, z=0.5)
    with pytest.raises(ValueError, match="^3D mesh.*nonzero z"):
        g.read_msh(lifted)
    with pytest.raises(ValueError, match="no triangles"):
        g.read_msh(tmp_path / "line.msh", blocks="components")
    garbage = tmp_path / "garbage.msh"
    garbage.write_text("$MeshFormat\nthis is not a mesh\n")
    with pytest.raises(ValueError):
        g.read_msh(garbage)


def test_read_msh_with_comm_identical_on_all_ranks(tmp_path):
    folder = rank0_tmp(tmp_path)
    path = folder / "two.msh"
    if COMM.rank == 0:
        _write_two_rectangles(path, names=("brick:0", "brick:1"))
    COMM.barrier()
    bm = g.read_msh(path, comm=COMM)
    assert bm.block_names == ("brick:0", "brick:1") and bm.material_names == ("brick",)
    assert same_on_all_ranks(bm.x, bm.cells, bm.node_offsets, bm.block_material)
    out = g.write_msh(bm, folder / "copy.msh", comm=COMM)
    back = g.read_msh(out, comm=COMM)
    assert np.array_equal(back.cells, bm.cells)
    with pytest.raises(FileNotFoundError):
        g.read_msh(folder / "absent.msh", comm=COMM)


def test_many_blocks_is_fast():
    import time

    t0 = time.perf_counter()
    bm = g.build_wall(courses=40, bricks_per_course=50, brick_length=0.2, brick_height=0.1)
    _ = bm.boundary_facets
    assert bm.n_blocks == 20 * 50 + 20 * 51
    assert time.perf_counter() - t0 < 10.0
    assert math.isclose(bm.block_area.sum(), 40 * 0.1 * 50 * 0.2, rel_tol=REL)


def test_read_geo_sample_duplicates_conforming_nodes():
    geo = Path(__file__).resolve().parents[1] / "meshes" / "post_and_lintel.geo"
    bm = g.read_msh(geo, materials={"pier:*": "stone", "lintel": "stone"}, comm=COMM)
    assert bm.block_names == ("pier:left", "pier:right", "lintel")
    assert bm.material_names == ("stone",)
    assert bm.block_area == pytest.approx([0.36, 0.36, 1.4 * 0.25], rel=REL)
    assert_canonical(bm)
    assert_boundary_loops(bm)
    # the lintel rests on both piers: its nodes on y = 1.2 have twins in a pier
    on_top = np.isclose(bm.x[:, 1], 1.2)
    assert set(np.unique(bm.node_block[on_top]).tolist()) == {0, 1, 2}
