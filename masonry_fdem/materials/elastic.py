"""St. Venant–Kirchhoff elasticity in total Lagrangian form (the default block law).

The law is written on the Green–Lagrange strain ``E = (FᵀF − I)/2 = (H + Hᵀ + HᵀH)/2``, so a rigid rotation of
a block, however large, produces no stress: this is what lets blocks of a collapsing arch
tumble without spurious forces. In two dimensions the in-plane law uses

* plane strain: the Lamé constants λ, μ of the material;
* plane stress: μ and the reduced constant λ* = 2λμ/(λ + 2μ), the classical plane-stress
  reduction applied to the Green–Lagrange strain (exact for small strain, the usual
  engineering choice for the moderate strains of masonry units).

Units are SI: E [Pa], density [kg/m³], the out-of-plane width [m].
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass
from enum import Enum

import ufl

from masonry_fdem.checks import check_magnitude

__all__ = [
    "Hypothesis",
    "Material",
    "lame_parameters",
    "green_lagrange",
    "svk_second_piola",
    "svk_energy_density",
    "cauchy_stress",
]


class Hypothesis(Enum):
    """Two-dimensional idealisation of the out-of-plane direction."""

    PLANE_STRESS = "plane_stress"
    PLANE_STRAIN = "plane_strain"


@dataclass(frozen=True)
class Material:
    """Block material: St. Venant–Kirchhoff elasticity, and the base of every block law.

    Args:
        density: mass density ρ [kg/m³], > 0.
        E: Young's modulus [Pa], > 0.
        nu: Poisson's ratio, -1 < ν < 0.5.

    Raises:
        ValueError: a constant out of its mathematical range;
            :class:`~masonry_fdem.checks.ImplausibleValueError` one out of the plausible
            range of :data:`~masonry_fdem.checks.PLAUSIBLE` (E in 1e5..1e12 Pa, density in
            100..12000 kg/m³), unless allowed by :func:`masonry_fdem.checks.expert`.

    A subclass changes the law by overriding :meth:`second_piola` (a stress from the
    Green–Lagrange strain) or :meth:`first_piola`, and may keep history variables at the
    quadrature points (:meth:`history`, :meth:`trial_history`); see
    :mod:`masonry_fdem.materials.base`. E and ν remain the initial elastic constants: they
    bound the stable time step and set default contact stiffnesses.
    """

    density: float
    E: float
    nu: float

    def __post_init__(self) -> None:
        for name in ("density", "E", "nu"):
            value = getattr(self, name)
            if value is None or not isinstance(value, numbers.Real) or not math.isfinite(value):
                raise ValueError(f"material constant {name} must be a finite number, got {value!r}")
            object.__setattr__(self, name, float(value))
        if self.density <= 0:
            raise ValueError(f"material density must be > 0 kg/m^3, got {self.density}")
        if self.E <= 0:
            raise ValueError(f"Young's modulus E must be > 0 Pa, got {self.E}")
        if not -1.0 < self.nu < 0.5:
            raise ValueError(f"Poisson's ratio nu must satisfy -1 < nu < 0.5, got {self.nu}")
        # magnitudes (off inside masonry_fdem.checks.expert())
        check_magnitude("density", self.density, "density", type(self).__name__)
        check_magnitude("E", self.E, "E", type(self).__name__)

    # ---------------------------------------------------------------- the law (UFL)
    def second_piola(self, k):
        """Second Piola–Kirchhoff stress S [Pa] from ``k.E`` (St. Venant–Kirchhoff)."""
        return svk_second_piola(k.E, k.lam, k.mu)

    def first_piola(self, k):
        """First Piola–Kirchhoff stress P = F S [Pa]; what the internal force integrates."""
        return k.F * self.second_piola(k)

    def energy_density(self, k):
        """Stored energy per reference volume [J/m³] (St. Venant–Kirchhoff)."""
        return svk_energy_density(k.E, k.lam, k.mu)

    def dissipation_increment(self, k):
        """The energy per reference volume [J/m³] the law dissipates when the trial
        history (:meth:`trial_history` at the current strain) is committed over the
        committed one, as UFL; None (the default) for a law that dissipates nothing, or
        whose history is not dissipative. The model sums it at every commit that
        changes a history variable (:meth:`~masonry_fdem.model.Model.damage_dissipation`),
        for the explicit solver's energy account."""
        return None

    def history(self) -> dict[str, float]:
        """Scalar history variables at the quadrature points and their initial values."""
        return {}

    def trial_history(self, k) -> dict:
        """The value each history variable takes if the current state is accepted (UFL)."""
        return {}

    def output_fields(self, history: dict, h) -> dict:
        """Fields derived from the committed history arrays (per cell of size ``h`` [m])
        for output, e.g. the damage; numpy in, numpy out."""
        return {}

    def check_mesh(self, h_max: float, hypothesis: Hypothesis) -> None:
        """Raise ValueError if the law cannot be used with elements of size up to
        ``h_max`` [m] (a softening law that would snap back)."""

    def wave_speed(self, hypothesis: Hypothesis) -> float:
        """Dilatational wave speed of the 2D continuum [m/s]."""
        lam, mu = lame_parameters(self, hypothesis)
        return math.sqrt((lam + 2.0 * mu) / self.density)


def lame_parameters(material: Material, hypothesis: Hypothesis) -> tuple[float, float]:
    """The in-plane Lamé constants (λ or λ*, μ) [Pa] for the 2D idealisation."""
    E, nu = material.E, material.nu
    mu = E / (2.0 * (1.0 + nu))
    lam = E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))
    if hypothesis is Hypothesis.PLANE_STRESS:
        lam = 2.0 * lam * mu / (lam + 2.0 * mu)
    return lam, mu


def green_lagrange(H):
    """Green–Lagrange strain E = (H + Hᵀ + HᵀH)/2 from the displacement gradient H = ∇u.

    Written on H rather than as (FᵀF − I)/2: the latter cancels catastrophically at the
    small strains of masonry (a strain of 1e-4 loses four digits), which puts a floor of
    round-off noise under the out-of-balance force of dynamic relaxation.
    """
    return 0.5 * (H + H.T + H.T * H)


def svk_second_piola(E, lam, mu):
    """Second Piola–Kirchhoff stress S = λ tr(E) I + 2μ E [Pa]."""
    I = ufl.Identity(E.ufl_shape[0])
    return lam * ufl.tr(E) * I + 2.0 * mu * E


def svk_energy_density(E, lam, mu):
    """Strain energy per reference volume W = λ/2 tr(E)² + μ E:E [J/m³]."""
    return 0.5 * lam * ufl.tr(E) ** 2 + mu * ufl.inner(E, E)


def cauchy_stress(F, S):
    """Cauchy stress σ = F S Fᵀ / det F [Pa]."""
    return F * S * F.T / ufl.det(F)
