"""Block layouts (outlines + names + materials) and builders of walls, stacks, block on base.

A :class:`BlockLayout` is pure geometry: no Gmsh, the same on every rank, cheap to combine
(``wall + base``) and to move. :meth:`BlockLayout.mesh` (or :func:`mesh_blocks`) turns it
into a :class:`BlockMesh`. The ``*_layout`` functions build layouts; each has a ``build_*``
twin that meshes it in one call.

Conventions: lengths in metres; ``origin`` is the bottom-left corner of the lowest block
(walls, stacks, base); blocks are named ``"<role>:<index...>"`` so that shell patterns such
as ``"brick:*"`` select a role, and get the material given for that role.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from masonry_fdem.geometry.blockmesh import BlockMesh
from masonry_fdem.geometry.meshing import mesh_blocks
from masonry_fdem.geometry.polygons import as_polygon, polygon_area, rectangle

__all__ = [
    "BlockLayout",
    "wall_layout",
    "stack_layout",
    "block_on_base_layout",
    "build_wall",
    "build_stack",
    "build_block_on_base",
]


@dataclass(frozen=True, eq=False)
class BlockLayout:
    """Outlines of the blocks of a structure with their names and materials.

    Attributes:
        polygons: counter-clockwise ``(k, 2)`` outlines [m] (normalised on creation).
        materials: material name of each block.
        names: unique name of each block.
    """

    polygons: tuple[np.ndarray, ...]
    materials: tuple[str, ...]
    names: tuple[str, ...]

    def __post_init__(self) -> None:
        names = tuple(str(s) for s in self.names)
        mats = tuple(str(m) for m in self.materials)
        if not (len(self.polygons) == len(mats) == len(names)):
            raise ValueError("polygons, materials and names must have the same length")
        if len(set(names)) != len(names):
            dup = sorted({s for s in names if names.count(s) > 1})
            raise ValueError(f"duplicate block names: {dup[:5]}")
        polys = tuple(as_polygon(p, n) for p, n in zip(self.polygons, names, strict=True))
        object.__setattr__(self, "polygons", polys)
        object.__setattr__(self, "materials", mats)
        object.__setattr__(self, "names", names)

    def __len__(self) -> int:
        return len(self.polygons)

    def __add__(self, other: BlockLayout) -> BlockLayout:
        return BlockLayout(
            self.polygons + other.polygons,
            self.materials + other.materials,
            self.names + other.names,
        )

    @property
    def areas(self) -> np.ndarray:
        """``(n_blocks,)`` exact polygon areas [m^2]."""
        return np.array([polygon_area(p) for p in self.polygons])

    @property
    def bounds(self) -> np.ndarray:
        """``(4,)`` bounding box ``[xmin, ymin, xmax, ymax]`` [m]."""
        allp = np.vstack(self.polygons)
        return np.concatenate([allp.min(axis=0), allp.max(axis=0)])

    def mesh(self, mesh_size: float | None = None, comm: Any | None = None,
             crossed: Sequence[str] = ()) -> BlockMesh:
        """Mesh the layout with :func:`mesh_blocks` (see there for ``mesh_size``, ``comm``
        and ``crossed``)."""
        return mesh_blocks(
            self.polygons, materials=self.materials, names=self.names,
            mesh_size=mesh_size, comm=comm, crossed=crossed,
        )


def _positive(**values: float) -> None:
    for key, v in values.items():
        if not (np.isfinite(v) and v > 0.0):
            raise ValueError(f"{key} must be positive, got {v}")


def wall_layout(
    *,
    courses: int,
    bricks_per_course: int,
    brick_length: float,
    brick_height: float,
    joint: float = 0.0,
    origin: Sequence[float] = (0.0, 0.0),
    material: str = "brick",
    start_with_half: bool = False,
) -> BlockLayout:
    """A wall in running (stretcher) bond with flush ends.

    Full courses hold ``bricks_per_course`` bricks; the courses in between hold
    ``bricks_per_course - 1`` full bricks and a half brick at each end, so every vertical
    joint sits over the middle of a brick below. With joint thickness ``j`` a half brick is
    ``(brick_length - j) / 2`` long, which keeps the ends flush; the wall is
    ``n * brick_length + (n - 1) * j`` long and ``courses * brick_height + (courses - 1) * j``
    high. Joints are gaps (mortar is modelled by interfaces, not by blocks).

    Args:
        courses: number of courses (rows), >= 1.
        bricks_per_course: full bricks in a full course, >= 1.
        brick_length: brick length [m].
        brick_height: brick height [m].
        joint: joint thickness [m] (0: bricks touch).
        origin: bottom-left corner of the wall [m].
        material: material of all bricks.
        start_with_half: if True the bottom course is the one with half bricks.

    Returns:
        Blocks named ``"brick:<course>:<k>"`` (full) and ``"half:<course>:<k>"`` (half
        bricks), ``k`` counted from the left within the course, courses from the bottom.
    """
    if courses < 1 or bricks_per_course < 1:
        raise ValueError("courses and bricks_per_course must be >= 1")
    _positive(brick_length=brick_length, brick_height=brick_height)
    if not (0.0 <= joint < brick_length):
        raise ValueError(f"joint must be in [0, brick_length), got {joint}")
    ox, oy = (float(v) for v in origin)
    half = 0.5 * (brick_length - joint)
    polys, names = [], []
    for c in range(courses):
        y0 = oy + c * (brick_height + joint)
        y1 = y0 + brick_height
        halves = (c % 2 == 1) != start_with_half
        if halves:
            lengths = [half] + [brick_length] * (bricks_per_course - 1) + [half]
        else:
            lengths = [brick_length] * bricks_per_course
        xa = ox
        for k, length in enumerate(lengths):
            is_half = halves and k in (0, len(lengths) - 1)
            polys.append(rectangle(xa, y0, xa + length, y1))
            names.append(f"{'half' if is_half else 'brick'}:{c}:{k}")
            xa += length + joint
    return BlockLayout(tuple(polys), (material,) * len(polys), tuple(names))


def stack_layout(
    n: int,
    *,
    width: float,
    height: float,
    offset: float = 0.0,
    alternate: bool = False,
    origin: Sequence[float] = (0.0, 0.0),
    material: str = "block",
) -> BlockLayout:
    """A column of ``n`` equal rectangular blocks, each resting on the one below.

    Args:
        n: number of blocks, >= 1.
        width: block width [m].
        height: block height [m].
        offset: horizontal shift of each block relative to the one below [m] (a staircase
            overhang), or, with ``alternate``, of every other block (a zig-zag).
        alternate: shift blocks 1, 3, 5, ... by ``offset`` instead of accumulating.
        origin: bottom-left corner of the bottom block [m].
        material: material of all blocks.

    Returns:
        Blocks named ``"block:<i>"`` from the bottom (i = 0).
    """
    if n < 1:
        raise ValueError("a stack needs n >= 1 blocks")
    _positive(width=width, height=height)
    ox, oy = (float(v) for v in origin)
    polys, names = [], []
    for i in range(n):
        shift = offset * (i % 2) if alternate else offset * i
        x0, y0 = ox + shift, oy + i * height
        polys.append(rectangle(x0, y0, x0 + width, y0 + height))
        names.append(f"block:{i}")
    return BlockLayout(tuple(polys), (material,) * n, tuple(names))


def block_on_base_layout(
    *,
    width: float,
    height: float,
    base_width: float,
    base_height: float,
    offset: float = 0.0,
    gap: float = 0.0,
    origin: Sequence[float] = (0.0, 0.0),
    material: str = "block",
    base_material: str = "base",
) -> BlockLayout:
    """A rectangular block standing on a wider base block.

    Args:
        width: block width [m].
        height: block height [m].
        base_width: base width [m], larger than ``width``.
        base_height: base height [m].
        offset: horizontal offset of the block centre from the base centre [m].
        gap: vertical gap between base top and block bottom [m] (0: in contact).
        origin: bottom-left corner of the base [m].
        material: material of the block.
        base_material: material of the base.

    Returns:
        Two blocks, ``"base"`` then ``"block"``.
    """
    _positive(width=width, height=height, base_width=base_width, base_height=base_height)
    if base_width <= width:
        raise ValueError(f"base_width ({base_width}) must exceed the block width ({width})")
    if gap < 0.0:
        raise ValueError(f"gap must be >= 0, got {gap}")
    ox, oy = (float(v) for v in origin)
    xc = ox + 0.5 * base_width + offset
    y0 = oy + base_height + gap
    return BlockLayout(
        (
            rectangle(ox, oy, ox + base_width, oy + base_height),
            rectangle(xc - 0.5 * width, y0, xc + 0.5 * width, y0 + height),
        ),
        (base_material, material),
        ("base", "block"),
    )


def build_wall(*, mesh_size: float | None = None, comm: Any | None = None,
               **layout: Any) -> BlockMesh:
    """Mesh :func:`wall_layout` (same keyword arguments); see :func:`mesh_blocks`."""
    return wall_layout(**layout).mesh(mesh_size, comm)


def build_stack(n: int, *, mesh_size: float | None = None, comm: Any | None = None,
                **layout: Any) -> BlockMesh:
    """Mesh :func:`stack_layout` (same arguments); see :func:`mesh_blocks`."""
    return stack_layout(n, **layout).mesh(mesh_size, comm)


def build_block_on_base(*, mesh_size: float | None = None, comm: Any | None = None,
                        **layout: Any) -> BlockMesh:
    """Mesh :func:`block_on_base_layout` (same keyword arguments); see :func:`mesh_blocks`."""
    return block_on_base_layout(**layout).mesh(mesh_size, comm)
