"""Constitutive laws of the blocks: UFL stresses, history at quadrature points, and
return mappings in numba (see :mod:`masonry_fdem.materials.base` for the interface)."""

from masonry_fdem.materials.base import LawContext
from masonry_fdem.materials.damage import RankineDamage
from masonry_fdem.materials.elastic import (
    Hypothesis,
    Material,
    cauchy_stress,
    green_lagrange,
    lame_parameters,
    svk_energy_density,
    svk_second_piola,
)
from masonry_fdem.materials.plasticity import DruckerPrager, MohrCoulomb, ReturnMapping

__all__ = [
    "DruckerPrager",
    "Hypothesis",
    "LawContext",
    "Material",
    "MohrCoulomb",
    "RankineDamage",
    "ReturnMapping",
    "cauchy_stress",
    "green_lagrange",
    "lame_parameters",
    "svk_energy_density",
    "svk_second_piola",
]


def precompile() -> None:
    """Compile and cache the material kernels (quadrature helpers, return mapping)."""
    import numpy as np

    from masonry_fdem.materials import _plastic_kernels as PK
    from masonry_fdem.materials.quadrature import p1_gradients, scatter_rows

    p1_gradients(np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]), np.zeros(6),
                 np.array([[0, 1, 2]], dtype=np.int64), np.zeros(1, dtype=np.int32),
                 np.zeros(1, dtype=np.int64), np.zeros((1, 4)))
    scatter_rows(np.zeros((2, 3)), np.zeros(2, dtype=np.int64), np.zeros((3, 3)))
    strain = np.array([[1e-3, -2e-3, 5e-4], [1e-3, -2e-3, 5e-4]])
    qps = np.arange(2, dtype=np.int64)
    for law in (MohrCoulomb(density=2000.0, E=1e6, nu=0.2, c=100.0, phi=30.0),
                DruckerPrager(density=2000.0, E=1e6, nu=0.2, c=100.0, phi=30.0, viscosity=1.0)):
        for hyp in ("plane_strain", "plane_stress"):
            s0 = np.zeros((2, PK.N_STATE))
            PK.plastic_update(strain, s0, s0.copy(), np.zeros((2, 4)), np.zeros(2), qps,
                              law.kernel_params(hyp), 1e-3)
            law.return_map(np.zeros((2, 4)) + 1e-3, s0, s0.copy(), np.zeros((2, 4)),
                           np.zeros(2), qps, law.kernel_params(hyp), 1e-3)
    PK.yield_value(np.zeros(4), 0.0, law.kernel_params("plane_strain"))
