"""Shared fixtures; collective-safe teardown for runs under mpirun."""

import gc

from mpi4py import MPI

import numpy as np
import pytest

import masonry_fdem  # noqa: F401  (dolfinx_solver before dolfinx)


@pytest.fixture(autouse=True)
def _collective_teardown():
    yield
    gc.collect()
    MPI.COMM_WORLD.barrier()


def rectangle(x0: float, y0: float, x1: float, y1: float) -> np.ndarray:
    """Counter-clockwise rectangle polygon [m]."""
    return np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]], dtype=float)


def alternating_grid(length: float, depth: float, h: float):
    """Nodes (n, 2) [m], triangles and the column index of each triangle of a length × depth
    rectangle on a grid of h × h squares, each halved by a diagonal that alternates like a
    checkerboard (so every square edge is a line of element edges)."""
    nx, ny = round(length / h), round(depth / h)
    xs, ys = np.linspace(0, length, nx + 1), np.linspace(0, depth, ny + 1)
    X, Y = np.meshgrid(xs, ys, indexing="ij")
    i, j = np.meshgrid(np.arange(nx), np.arange(ny), indexing="ij")
    i, j = i.ravel(), j.ravel()
    a, b = i * (ny + 1) + j, (i + 1) * (ny + 1) + j
    c, d = b + 1, a + 1
    even = (i + j) % 2 == 0
    t1 = np.where(even[:, None], np.c_[a, b, c], np.c_[a, b, d])
    t2 = np.where(even[:, None], np.c_[a, c, d], np.c_[b, c, d])
    return np.c_[X.ravel(), Y.ravel()], np.concatenate([t1, t2]), np.tile(i, 2)
