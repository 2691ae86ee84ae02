"""Constitutive laws of the blocks (UFL expressions) and their parameters."""

from masonry_fdem.materials.elastic import (
    Hypothesis,
    Material,
    cauchy_stress,
    green_lagrange,
    lame_parameters,
    svk_energy_density,
    svk_second_piola,
)

__all__ = [
    "Hypothesis",
    "Material",
    "cauchy_stress",
    "green_lagrange",
    "lame_parameters",
    "svk_energy_density",
    "svk_second_piola",
]
