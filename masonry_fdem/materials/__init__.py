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
