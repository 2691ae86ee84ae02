"""The block material interface: a law writes its stress in UFL.

A block material is a :class:`~masonry_fdem.materials.Material` (density ρ [kg/m³],
Young's modulus E [Pa], Poisson's ratio ν: they set the lumped mass, the stable time step
and the default contact and joint stiffnesses). Its constitutive law is one of its methods:

* :meth:`Material.second_piola` — the second Piola–Kirchhoff stress S [Pa] as a UFL
  expression of the Green–Lagrange strain ``k.E`` (the default, St. Venant–Kirchhoff), or
* :meth:`Material.first_piola` — the first Piola–Kirchhoff stress P = F S [Pa] directly
  (override it for laws written on F, such as neo-Hookean);
* :meth:`Material.history` and :meth:`Material.trial_history` — scalar history variables
  at the quadrature points (a damage threshold, ...). ``k.state[name]`` is the COMMITTED
  value, a function in a quadrature space; ``trial_history`` gives the value it would take
  at the current displacement, as UFL. The stress may use both. The solvers commit the
  trial values: the explicit solver every step, dynamic relaxation only when a load
  increment has converged;
* :meth:`Material.energy_density` — the stored energy per reference volume [J/m³] (for
  the energy account; default: the St. Venant–Kirchhoff energy).

Laws whose update is a return mapping (plasticity) are
:class:`~masonry_fdem.materials.ReturnMapping` materials: a numba kernel updates their
state at the quadrature points from the strain, and their stress enters the form as a
quadrature function (``k.stress``).

The :class:`~masonry_fdem.model.Model` compiles ONE internal-force form for all blocks,
``Σ_m ∫ P_m : ∇w w dX(m)``, each material acting on its own tagged cells. A user law is
a subclass, written in a few lines of UFL without touching the package::

    @dataclass(frozen=True)
    class NeoHooke(Material):
        def first_piola(self, k):
            Finv = ufl.inv(k.F)
            return k.mu * (k.F - Finv.T) + k.lam * ufl.ln(ufl.det(k.F)) * Finv.T

Units are SI throughout.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import ufl

__all__ = ["LawContext"]


@dataclass
class LawContext:
    """What a law sees when it writes its stress in UFL (one per material of a model).

    Attributes:
        mesh: the dolfinx mesh of all blocks.
        u: the displacement function [m].
        H: displacement gradient ∇u (reference configuration).
        F: deformation gradient I + ∇u.
        E: Green–Lagrange strain (H + Hᵀ + HᵀH)/2.
        lam: in-plane Lamé constant λ [Pa] (the plane-stress λ* = 2λμ/(λ+2μ) under plane
            stress), a dolfinx Constant.
        mu: shear modulus μ [Pa], a dolfinx Constant.
        hypothesis: the model's :class:`~masonry_fdem.materials.Hypothesis`.
        h: the element size sqrt(2 × cell area) [m] (the crack-band width of a triangle
            that is half of an h × h square), UFL.
        state: committed history variables of this material by name (quadrature functions).
        stress: for a return-mapping law, the second Piola–Kirchhoff stress its kernel
            computed [Pa] (2×2 UFL); None otherwise.
        energy: for a return-mapping law, its elastic energy density [J/m³]; else None.
        E_committed: the Green–Lagrange strain at the last commit (UFL; for
            :meth:`Material.dissipation_increment`, whose trapezoidal rule over the
            increment takes the strains at both of its ends).
    """

    mesh: Any
    u: Any
    H: Any
    F: Any
    E: Any
    lam: Any
    mu: Any
    hypothesis: Any
    h: Any
    state: dict = field(default_factory=dict)
    stress: Any = None
    energy: Any = None
    E_committed: Any = None

    @property
    def I(self):  # noqa: E743
        """The 2×2 identity."""
        return ufl.Identity(2)
