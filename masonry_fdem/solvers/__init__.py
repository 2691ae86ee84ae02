"""Time integration: explicit central difference and dynamic relaxation."""

from masonry_fdem.solvers.dynamic_relaxation import DRResult, DynamicRelaxation
from masonry_fdem.solvers.explicit import EnergyAccount, ExplicitSolver, UnstableTimeStepError

__all__ = [
    "DRResult",
    "DynamicRelaxation",
    "EnergyAccount",
    "ExplicitSolver",
    "UnstableTimeStepError",
]
