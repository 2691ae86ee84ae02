"""Mohr–Coulomb and Drucker–Prager elasto-plasticity (with a Perzyna visco-plastic
variant), updated by a return mapping at the quadrature points in numba.

The laws are finite-strain plasticity with Hencky elasticity: F = Fᵉ Fᵖ, Kirchhoff
stress τ = λ tr εᵉ I + 2μ εᵉ of the elastic logarithmic strain εᵉ = ½ ln(Fᵉ Fᵉᵀ), and the
return mapping on εᵉ by the exponential map (:mod:`masonry_fdem.materials._finite_plastic`).
Blocks and soil may rotate and shear by any amount: isochoric flow stays isochoric, which
a law additive in the Green–Lagrange strain would not do (its trace grows as γ²/2 in
simple shear). For small strains it is the classical additive law. Plane strain keeps
F_zz = 1; plane stress solves the out-of-plane stretch for τ_zz = 0 at each point.

* :class:`MohrCoulomb` — f = (σ₁ − σ₃) + (σ₁ + σ₃) sin φ − 2 c cos φ, non-associated flow
  with dilatancy angle ψ, cohesion hardening or softening c(α) = max(c₀ + H α, c_min);
  return in principal stresses to the main plane, an edge or the apex (de Souza Neto,
  Perić & Owen, *Computational Methods for Plasticity*, 2008, §8.2). For soil (with
  φ = 0 it is Tresca: an undrained clay) and for the crushing of units
  (:meth:`MohrCoulomb.from_strengths`).
* :class:`DruckerPrager` — f = √J₂ + η p − ξ c, matched to Mohr–Coulomb (plane strain,
  outer or inner cone), with an optional Perzyna viscosity η_v [Pa·s]:
  ε̇ᵖ = ⟨f⟩/η_v ∂g/∂σ, integrated by backward Euler over the solver's time increment.

Units: stresses and cohesion [Pa], angles in degrees, viscosity [Pa·s].
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from masonry_fdem.materials import _finite_plastic as FP
from masonry_fdem.materials import _plastic_kernels as PK
from masonry_fdem.materials.elastic import Hypothesis, Material

__all__ = ["ReturnMapping", "MohrCoulomb", "DruckerPrager", "N_STATE", "PLASTIC_WORK"]

N_STATE = PK.N_STATE
PLASTIC_WORK = PK.S_WP  # column of the plastic work density [J/m³] in the state


def _finite(obj, *names, lo=None, hi=None, strict_lo=False):
    for name in names:
        value = getattr(obj, name)
        if not (isinstance(value, int | float) and math.isfinite(value)):
            raise ValueError(f"{type(obj).__name__}: {name} must be a finite number, got {value!r}")
        value = float(value)
        if lo is not None and (value < lo or (strict_lo and value == lo)):
            raise ValueError(f"{type(obj).__name__}: {name} must be {'>' if strict_lo else '>='} "
                             f"{lo}, got {value}")
        if hi is not None and value >= hi:
            raise ValueError(f"{type(obj).__name__}: {name} must be < {hi}, got {value}")
        object.__setattr__(obj, name, value)


def _check_coulomb(m) -> None:
    _finite(m, "c", "c_min", lo=0.0)
    _finite(m, "phi", lo=0.0, hi=90.0)
    _finite(m, "psi", lo=0.0, hi=90.0)
    _finite(m, "hardening")
    name = type(m).__name__
    if m.psi > m.phi:
        raise ValueError(f"{name}: the dilatancy angle psi={m.psi} exceeds the friction "
                         f"angle phi={m.phi}")
    if m.c == 0.0 and m.phi == 0.0:
        raise ValueError(f"{name}: c = 0 and phi = 0 has no strength")
    if m.c_min > m.c:
        raise ValueError(f"{name}: c_min={m.c_min} exceeds c={m.c}")


@dataclass(frozen=True)
class ReturnMapping(Material):
    """Base of laws whose state is updated by a numba return mapping.

    The model evaluates the displacement gradient at the law's quadrature points, calls
    :meth:`return_map` (trial state from the committed one), and integrates the second
    Piola–Kirchhoff stress the kernel wrote (``k.stress``). A subclass supplies
    :meth:`kernel_params`.
    """

    def kernel_params(self, hypothesis: Hypothesis) -> np.ndarray:
        raise NotImplementedError

    @staticmethod
    def return_map(grad, s0, s1, stress, energy, qps, prm, dt) -> None:
        """Trial state ``s1`` and stress from the committed ``s0`` at the displacement
        gradient ``grad`` (nq, 4) of the points ``qps`` (see
        :func:`masonry_fdem.materials._finite_plastic.finite_plastic_update`)."""
        FP.finite_plastic_update(grad, s0, s1, stress, energy, qps, prm, dt)

    def second_piola(self, k):
        return k.stress

    def energy_density(self, k):
        return k.energy

    def _coulomb_params(self, hypothesis: Hypothesis) -> np.ndarray:
        """Kernel parameters shared by the Coulomb-type laws: 3D elastic constants, the
        out-of-plane hypothesis, c, sin φ, sin ψ and the cohesion hardening."""
        prm = np.zeros(PK.N_PRM)
        E, nu = self.E, self.nu
        prm[PK.P_LAM] = E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))
        prm[PK.P_MU] = E / (2.0 * (1.0 + nu))
        prm[PK.P_PLANE_STRESS] = 1.0 if Hypothesis(hypothesis) is Hypothesis.PLANE_STRESS else 0.0
        prm[PK.P_C] = self.c
        prm[PK.P_SINPHI] = math.sin(math.radians(self.phi))
        prm[PK.P_SINPSI] = math.sin(math.radians(self.psi))
        prm[PK.P_H] = self.hardening
        prm[PK.P_CMIN] = self.c_min
        return prm


@dataclass(frozen=True)
class MohrCoulomb(ReturnMapping):
    """Mohr–Coulomb elasto-plasticity.

    Args:
        density, E, nu: as :class:`Material`.
        c: cohesion c₀ [Pa], ≥ 0.
        phi: friction angle φ [degrees], 0 ≤ φ < 90 (φ = 0: Tresca).
        psi: dilatancy angle ψ [degrees], 0 ≤ ψ ≤ φ (ψ = φ: associated flow).
        hardening: H = dc/dα [Pa] (negative: cohesion softening).
        c_min: lower bound of the cohesion [Pa].
    """

    c: float = 0.0
    phi: float = 0.0
    psi: float = 0.0
    hardening: float = 0.0
    c_min: float = 0.0

    def __post_init__(self) -> None:
        super().__post_init__()
        _check_coulomb(self)

    @classmethod
    def from_strengths(cls, *, density: float, E: float, nu: float, fc: float, ft: float,
                       psi: float = 0.0, **kw) -> MohrCoulomb:
        """The Mohr–Coulomb law with uniaxial compressive and tensile strengths fc, ft [Pa]
        (crushing of units): sin φ = (fc − ft)/(fc + ft), c = √(fc ft)/2."""
        if not (fc > 0 and ft > 0 and ft <= fc):
            raise ValueError(f"need 0 < ft <= fc, got fc={fc}, ft={ft}")
        phi = math.degrees(math.asin((fc - ft) / (fc + ft)))
        return cls(density=density, E=E, nu=nu, c=0.5 * math.sqrt(fc * ft), phi=phi, psi=psi, **kw)

    @property
    def fc(self) -> float:
        """Uniaxial compressive strength 2c cos φ/(1 − sin φ) [Pa]."""
        p = math.radians(self.phi)
        return 2.0 * self.c * math.cos(p) / (1.0 - math.sin(p))

    @property
    def ft(self) -> float:
        """Uniaxial tensile strength 2c cos φ/(1 + sin φ) [Pa]."""
        p = math.radians(self.phi)
        return 2.0 * self.c * math.cos(p) / (1.0 + math.sin(p))

    def kernel_params(self, hypothesis: Hypothesis) -> np.ndarray:
        prm = self._coulomb_params(hypothesis)
        prm[PK.P_SURFACE] = 0.0
        return prm


@dataclass(frozen=True)
class DruckerPrager(ReturnMapping):
    """Drucker–Prager elasto-plasticity matched to Mohr–Coulomb, optionally Perzyna
    visco-plastic.

    Args:
        density, E, nu: as :class:`Material`.
        c, phi, psi, hardening, c_min: the Mohr–Coulomb constants it is matched to.
        fit: "plane_strain" (same plane-strain collapse loads as Mohr–Coulomb; φ = 0 gives
            von Mises with √J₂ ≤ c), "outer" (compression meridian) or "inner" (tension
            meridian).
        viscosity: Perzyna viscosity η_v [Pa·s] (0: rate independent). The rate is that
            of the solver's time step (explicit) or of the ``dt`` given to dynamic
            relaxation (default: infinitely slow, the rate-independent limit).
    """

    c: float = 0.0
    phi: float = 0.0
    psi: float = 0.0
    hardening: float = 0.0
    c_min: float = 0.0
    fit: str = "plane_strain"
    viscosity: float = 0.0

    def __post_init__(self) -> None:
        super().__post_init__()
        _check_coulomb(self)
        _finite(self, "viscosity", lo=0.0)
        if self.fit not in ("plane_strain", "outer", "inner"):
            raise ValueError(f"DruckerPrager: fit must be 'plane_strain', 'outer' or 'inner', "
                             f"got {self.fit!r}")

    def cone(self) -> tuple[float, float, float]:
        """(η, ξ, η̄) of f = √J₂ + η p − ξ c and of the flow potential √J₂ + η̄ p."""
        return PK.mc_matched_dp(self.c, math.sin(math.radians(self.phi)),
                                math.sin(math.radians(self.psi)), self.fit)

    def kernel_params(self, hypothesis: Hypothesis) -> np.ndarray:
        prm = self._coulomb_params(hypothesis)
        prm[PK.P_ETA] = self.viscosity
        prm[PK.P_SURFACE] = 1.0
        eta, xi, etabar = self.cone()
        prm[PK.P_DP_ETA], prm[PK.P_DP_XI], prm[PK.P_DP_ETABAR] = eta, xi, etabar
        return prm
