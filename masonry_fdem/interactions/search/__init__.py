"""Broad phase: the alternating digital tree (Bonet & Peraire 1991) over facet boxes,
and the box and speed helpers the neighbour lists are built from."""

from masonry_fdem.interactions.search._kernels import facet_boxes, max_speed
from masonry_fdem.interactions.search.adt import (
    ADTree,
    brute_force_pairs,
    build_adt,
    inflate,
    query_adt,
    self_pairs,
)

__all__ = ["ADTree", "brute_force_pairs", "build_adt", "facet_boxes", "inflate", "max_speed",
           "query_adt", "self_pairs"]
