"""Geometry: masonry blocks as polygons, meshed block by block with Gmsh, and mesh import.

Blocks (bricks, voussoirs, stones) are plane polygons. Each is meshed on its own into linear
triangles, so blocks never share a node, and all of them go into one array-based
:class:`BlockMesh` (nodes and cells contiguous per block, counter-clockwise triangles,
block and material ids, boundary facets). This package never imports dolfinx; turning a
block mesh into a dolfinx mesh is done by :mod:`masonry_fdem.parallel`.

Typical use::

    from masonry_fdem import geometry

    wall = geometry.build_wall(courses=6, bricks_per_course=4, brick_length=0.215,
                               brick_height=0.065, joint=0.0)
    arch = geometry.arch_layout(span=2.0, ring_thickness=0.1, voussoirs=21, rings=2,
                                abutment_height=0.3).mesh(mesh_size=0.05, comm=MPI.COMM_WORLD)
    user = geometry.read_msh("bridge.msh", materials={"brick:*": "brick", "fill": "soil"})

Lengths are in metres, areas in square metres.
"""

from masonry_fdem.geometry.arches import (
    ArchKind,
    arch_circle,
    arch_curve,
    arch_layout,
    arch_parameter,
    build_arch,
    ring_pieces,
)
from masonry_fdem.geometry.blockmesh import BlockMesh, unit_name
from masonry_fdem.geometry.grids import crossed_grid, graded
from masonry_fdem.geometry.layout import (
    BlockLayout,
    block_on_base_layout,
    build_block_on_base,
    build_stack,
    build_wall,
    stack_layout,
    wall_layout,
)
from masonry_fdem.geometry.meshing import cross_quads, mesh_blocks
from masonry_fdem.geometry.msh import interface_rules, read_msh, read_msh_lines, write_msh
from masonry_fdem.geometry.polygons import as_polygon, polygon_area, polygon_centroid, rectangle

__all__ = [
    "crossed_grid",
    "graded",
    "ArchKind",
    "BlockLayout",
    "BlockMesh",
    "arch_circle",
    "arch_curve",
    "arch_parameter",
    "ring_pieces",
    "arch_layout",
    "as_polygon",
    "block_on_base_layout",
    "build_arch",
    "build_block_on_base",
    "build_stack",
    "build_wall",
    "cross_quads",
    "mesh_blocks",
    "polygon_area",
    "polygon_centroid",
    "interface_rules",
    "read_msh",
    "read_msh_lines",
    "rectangle",
    "stack_layout",
    "wall_layout",
    "unit_name",
    "write_msh",
]
