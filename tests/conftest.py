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
