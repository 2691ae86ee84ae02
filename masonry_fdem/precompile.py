"""Compile and cache every numba kernel once, before MPI ranks start.

Run ``python -m masonry_fdem.precompile`` serially (``make`` does) so that ranks of a
parallel run load the cache instead of racing to write it.
"""

from __future__ import annotations

import numpy as np

__all__ = ["precompile"]


def precompile() -> None:
    """Call each kernel once on tiny arrays of the production dtypes."""
    from masonry_fdem.solvers import _kernels as K

    n = 6
    u = np.zeros(n)
    v = np.zeros(n)
    f = np.zeros(n)
    m = np.ones(n)
    mask = np.zeros(n, dtype=np.int8)
    K.gather(u, np.zeros(n, dtype=np.int64), v)
    K.central_difference_step(u, v, f, f, f, m, m, mask, v, 0.0, 1e-3, f.copy(),
                              np.zeros(K.N_ENERGY))
    K.dr_measure(u, u, v, f, f, f, m, mask, np.zeros(4))
    K.dr_update(u, v, f, f, m, mask, 0.0, 1.0, True)
    xy = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    cells = np.array([[0, 1, 2]], dtype=np.int64)
    one = np.ones(1)
    K.p1_element_bounds(xy, cells, one, one, one, 1.0, np.zeros(1), np.zeros(n))

    from masonry_fdem.contact import _kernels as C

    X = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    uu = np.zeros(8)
    facets = np.array([[0, 1], [1, 2], [2, 3], [3, 0]], dtype=np.int64)
    fnext = np.array([1, 2, 3, 0], dtype=np.int64)
    fprev = np.array([3, 0, 1, 2], dtype=np.int64)
    pairs = np.array([[0, 2]], dtype=np.int64)
    p1 = np.ones(1)
    work = np.zeros(C.N_WORK)
    C.facet_facet_forces(X, uu, uu, facets, fprev, fnext, pairs, p1, p1, p1, p1, p1, 1.0, 1e-3,
                         np.zeros((1, 2)), np.zeros((1, 2)), np.zeros(8), np.zeros(3), work)
    C.facet_boxes(X, uu, facets, 0.1, np.zeros((4, 4)))
    C.max_speed(uu)

    from masonry_fdem.contact.adt import brute_force_pairs, query_adt, self_pairs

    boxes = np.array([[0.0, 0.0, 1.0, 1.0], [0.5, 0.5, 2.0, 2.0], [3.0, 3.0, 4.0, 4.0]])
    self_pairs(boxes, np.array([0, 1, 1]))
    brute_force_pairs(boxes)
    from masonry_fdem.contact.adt import build_adt

    query_adt(build_adt(boxes), boxes)


if __name__ == "__main__":
    precompile()
    print("masonry_fdem: numba kernels compiled and cached")
