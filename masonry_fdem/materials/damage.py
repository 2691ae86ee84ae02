"""Isotropic damage with a Rankine criterion, exponential softening and crack-band
regularisation (Bažant & Oh 1983; Oliver 1989), written entirely in UFL.

Effective stress S̄ = St. Venant–Kirchhoff stress of the Green–Lagrange strain. The
equivalent strain is ε̃ = ⟨σ̄₁⟩ / E, σ̄₁ the largest principal effective stress (Rankine),
and the history variable κ = max over the loading history of ε̃, starting at the damage
threshold ε₀ = f_t / E. The stress is S = (1 − d(κ)) S̄ with

    d(κ) = 1 − (ε₀/κ) exp(−(κ − ε₀)/ε_s),     ε_s = G_f / (f_t h) − ε₀/2,

so that in uniaxial tension the stress softens as σ = f_t exp(−(ε − ε₀)/ε_s) and the
energy dissipated per unit volume of the band, f_t ε₀/2 + f_t ε_s, equals G_f / h: the
energy per unit crack area is G_f whatever the element size h (crack band). h is the
element size ``k.h`` = sqrt(2 × cell area) [m], the width of a band of right triangles
that halve h × h squares. Elements larger than 2 E G_f / f_t² would snap back and are
refused. Damage is isotropic: a crack also loses compressive stiffness (no closure).

Units: f_t [Pa], G_f [J/m²].
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import ufl

from masonry_fdem.materials.elastic import (
    Hypothesis,
    Material,
    svk_energy_density,
    svk_second_piola,
)

__all__ = ["RankineDamage"]


@dataclass(frozen=True)
class RankineDamage(Material):
    """Isotropic Rankine damage with exponential softening, crack-band regularised.

    Args:
        density, E, nu: as :class:`Material`.
        ft: tensile strength f_t [Pa], > 0.
        Gf: mode-I fracture energy G_f [J/m²], > 0.
        d_max: cap on the damage (keeps a fully cracked element from losing all its
            stiffness, which would leave its nodes unrestrained), 0 < d_max ≤ 1.
    """

    ft: float = 0.0
    Gf: float = 0.0
    d_max: float = 0.999999

    def __post_init__(self) -> None:
        super().__post_init__()
        for name in ("ft", "Gf"):
            value = getattr(self, name)
            if not (isinstance(value, int | float) and math.isfinite(value) and value > 0):
                raise ValueError(
                    f"RankineDamage: {name} must be a finite number > 0, got {value!r}")
            object.__setattr__(self, name, float(value))
        if not 0.0 < self.d_max <= 1.0:
            raise ValueError(f"RankineDamage: d_max must lie in (0, 1], got {self.d_max}")

    @property
    def eps0(self) -> float:
        """Damage threshold strain ε₀ = f_t / E."""
        return self.ft / self.E

    def h_max(self) -> float:
        """Largest element size [m] without snap-back: 2 E G_f / f_t²."""
        return 2.0 * self.E * self.Gf / self.ft**2

    def check_mesh(self, h_max: float, hypothesis: Hypothesis) -> None:
        if h_max >= self.h_max():
            raise ValueError(
                f"RankineDamage(ft={self.ft:g}, Gf={self.Gf:g}): elements up to h = {h_max:.4g} m "
                f"but the softening snaps back above 2 E Gf / ft^2 = {self.h_max():.4g} m; "
                "refine the mesh of this material")

    def history(self) -> dict[str, float]:
        return {"kappa": self.eps0}

    def effective_stress(self, k):
        """The undamaged (St. Venant–Kirchhoff) second Piola–Kirchhoff stress [Pa]."""
        return svk_second_piola(k.E, k.lam, k.mu)

    def equivalent_strain(self, k):
        """Rankine equivalent strain ⟨σ̄₁⟩ / E."""
        S = self.effective_stress(k)
        half_diff = 0.5 * (S[0, 0] - S[1, 1])
        s1 = 0.5 * (S[0, 0] + S[1, 1]) + ufl.sqrt(half_diff**2 + S[0, 1] ** 2)
        return ufl.max_value(s1, 0.0) / self.E

    def trial_history(self, k) -> dict:
        return {"kappa": ufl.max_value(k.state["kappa"], self.equivalent_strain(k))}

    def damage(self, k, kappa=None):
        """Damage d(κ) ∈ [0, d_max] (UFL); κ defaults to the trial value."""
        kappa = self.trial_history(k)["kappa"] if kappa is None else kappa
        e0 = self.eps0
        es = self.Gf / (self.ft * k.h) - 0.5 * e0
        d = 1.0 - e0 / kappa * ufl.exp(-(kappa - e0) / es)
        return ufl.min_value(ufl.max_value(d, 0.0), self.d_max)

    def output_fields(self, history: dict, h) -> dict:
        import numpy as np

        kappa = np.maximum(history["kappa"], self.eps0)
        es = self.Gf / (self.ft * h) - 0.5 * self.eps0
        d = 1.0 - self.eps0 / kappa * np.exp(-(kappa - self.eps0) / es)
        return {"damage": np.clip(d, 0.0, self.d_max)}

    def second_piola(self, k):
        return (1.0 - self.damage(k)) * self.effective_stress(k)

    def energy_density(self, k):
        return (1.0 - self.damage(k)) * svk_energy_density(k.E, k.lam, k.mu)

    def dissipation_increment(self, k):
        """W̄ Δd [J/m³] over one committed increment: the dissipation rate of isotropic
        damage is W̄ ḋ (W̄ the undamaged energy density), and W̄ is taken as the bilinear
        form of the strains at the two ends of the increment, λ/2 tr E₀ tr E₁ + μ E₀:E₁ —
        what the work of the stress by the trapezoidal rule over the increment leaves
        after the change of the stored energy (1 − d) W̄ (exact for small strains), so
        that the explicit solver's energy account closes."""
        grown = self.damage(k) - self.damage(k, k.state["kappa"])
        E0, E1 = k.E_committed, k.E
        mixed = 0.5 * k.lam * ufl.tr(E0) * ufl.tr(E1) + k.mu * ufl.inner(E0, E1)
        return mixed * grown
