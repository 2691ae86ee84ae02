"""Time integration: explicit central difference, dynamic relaxation, the static Newton
solver on PETSc SNES; the status of a quasi-static run."""

from masonry_fdem.solvers.dynamic_relaxation import CollapseResult, DRResult, DynamicRelaxation
from masonry_fdem.solvers.explicit import EnergyAccount, ExplicitSolver, UnstableTimeStepError
from masonry_fdem.solvers.static import NewtonResult, StaticRun, StaticSolver
from masonry_fdem.solvers.status import RunStatus, Status

__all__ = [
    "CollapseResult",
    "DRResult",
    "DynamicRelaxation",
    "EnergyAccount",
    "ExplicitSolver",
    "NewtonResult",
    "RunStatus",
    "StaticRun",
    "StaticSolver",
    "Status",
    "UnstableTimeStepError",
]


def precompile() -> None:
    """Compile and cache the integrators' kernels."""
    from masonry_fdem.solvers import _kernels

    _kernels.precompile()
