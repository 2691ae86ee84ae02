"""Time integration: explicit central difference and dynamic relaxation."""

from masonry_fdem.solvers.dynamic_relaxation import CollapseResult, DRResult, DynamicRelaxation
from masonry_fdem.solvers.explicit import EnergyAccount, ExplicitSolver, UnstableTimeStepError

__all__ = [
    "CollapseResult",
    "DRResult",
    "DynamicRelaxation",
    "EnergyAccount",
    "ExplicitSolver",
    "UnstableTimeStepError",
]


def precompile() -> None:
    """Compile and cache the integrators' kernels."""
    from masonry_fdem.solvers import _kernels

    _kernels.precompile()
