"""Broad phase: the alternating digital tree (Bonet & Peraire 1991) over facet boxes,
and the box and speed helpers the neighbour lists are built from."""

from masonry_fdem.interactions.search._kernels import (
    boxes_on_cells,
    facet_boxes,
    mark_cells,
    max_speed,
)
from masonry_fdem.interactions.search.adt import (
    ADTree,
    brute_force_pairs,
    build_adt,
    inflate,
    query_adt,
    self_pairs,
)

__all__ = ["ADTree", "boxes_on_cells", "brute_force_pairs", "build_adt", "facet_boxes",
           "inflate", "mark_cells", "max_speed", "query_adt", "self_pairs"]


def precompile() -> None:
    """Compile and cache the search kernels."""
    import numpy as np

    from masonry_fdem.interactions.search import _kernels

    _kernels.precompile()
    boxes = np.array([[0.0, 0.0, 1.0, 1.0], [0.5, 0.5, 2.0, 2.0], [3.0, 3.0, 4.0, 4.0]])
    self_pairs(boxes, np.array([0, 1, 1]))
    brute_force_pairs(boxes)
    query_adt(build_adt(boxes), boxes)
