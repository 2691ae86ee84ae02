"""Version and packaging differences of dolfinx, kept in one place.

The pip wheel ``dolfinx-solver-real`` ships PETSc and MPICH and must be imported before
dolfinx/petsc4py. On a conda-forge or Docker dolfinx the module does not exist and nothing
needs doing.
"""

from __future__ import annotations

import importlib.util

HAS_SOLVER_WHEEL = importlib.util.find_spec("dolfinx_solver") is not None
if HAS_SOLVER_WHEEL:  # pragma: no branch
    import dolfinx_solver  # noqa: F401

import dolfinx  # noqa: E402

DOLFINX_VERSION = tuple(int(p) for p in dolfinx.__version__.split(".")[:2])

__all__ = ["DOLFINX_VERSION", "HAS_SOLVER_WHEEL"]
