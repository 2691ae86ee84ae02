"""What an anchor is made of: the steel bar (:class:`SteelLaw`), the grout bond
(:class:`BondLaw`), the transverse dowel action (:class:`DowelLaw`) and the anchor itself
(:class:`Anchor`: its polyline, bar, bond, plates, prestress). Units SI (m, N, Pa, kg/m³).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from masonry_fdem.checks import check_positive

__all__ = ["Anchor", "BondLaw", "DowelLaw", "JointDowel", "SteelLaw"]

_PLATES = ("none", "start", "end", "both")


@dataclass(frozen=True)
class SteelLaw:
    """Uniaxial elasto-plastic steel of the bar.

    Args:
        E: Young's modulus [Pa].
        yield_stress: f_y [Pa].
        hardening: linear isotropic hardening modulus H [Pa] (stress rises by H per unit
            plastic strain); 0 for perfect plasticity.
        rupture_strain: total (engineering) strain at which the bar breaks in tension [-];
            it carries nothing afterwards.
        density: [kg/m³] (mass of the bar nodes).
    """

    E: float = 200e9
    yield_stress: float = 500e6
    hardening: float = 0.0
    rupture_strain: float = 0.10
    density: float = 7850.0

    def __post_init__(self) -> None:
        check_positive("steel E", self.E)
        check_positive("steel yield_stress", self.yield_stress)
        check_positive("steel hardening", self.hardening, allow_zero=True)
        check_positive("steel density", self.density)
        check_positive("steel rupture_strain", self.rupture_strain, allow_inf=True)
        if self.rupture_strain <= self.yield_stress / self.E:
            raise ValueError(
                f"rupture_strain {self.rupture_strain} must exceed the yield strain "
                f"{self.yield_stress / self.E:.4g}")

    def stress(self, strain: np.ndarray) -> np.ndarray:
        """Stress [Pa] on a monotonic path to ``strain`` (tension positive; for checks)."""
        eps = np.asarray(strain, dtype=float)
        ey = self.yield_stress / self.E
        a = np.abs(eps)
        hard = self.E * self.hardening / (self.E + self.hardening)
        sig = np.where(a <= ey, self.E * a, self.yield_stress + hard * (a - ey))
        sig = np.where(eps >= self.rupture_strain, 0.0, sig)
        return np.sign(eps) * sig


@dataclass(frozen=True)
class BondLaw:
    """Bond stress–slip law τ(s) of the grouted anchor, from a pull-out test.

    The envelope is piecewise linear through (0, 0) and the table points
    ``(slip[k], stress[k])``, constant beyond the last point (give a last point with
    stress 0 for a bond that is lost completely). It is odd in the slip. Unloading and
    reloading follow the initial stiffness ``k0 = stress[0]/slip[0]`` (the slip then has
    a plastic part); no later segment may be steeper than ``k0``.

    Args:
        slip: table slips [m], increasing, > 0.
        stress: table bond stresses [Pa], >= 0, the first one > 0.
    """

    slip: tuple[float, ...]
    stress: tuple[float, ...]

    def __post_init__(self) -> None:
        s = np.asarray(self.slip, dtype=float).ravel()
        t = np.asarray(self.stress, dtype=float).ravel()
        if s.size == 0 or s.size != t.size:
            raise ValueError("bond law needs as many slips as stresses (at least one point)")
        if not (np.all(np.isfinite(s)) and np.all(np.isfinite(t))):
            raise ValueError("bond law table must be finite")
        if s[0] <= 0 or np.any(np.diff(s) <= 0):
            raise ValueError(f"bond law slips must be > 0 and increasing, got {s.tolist()}")
        if np.any(t < 0) or t[0] <= 0:
            raise ValueError(f"bond stresses must be >= 0 with the first > 0, got {t.tolist()}")
        k0 = t[0] / s[0]
        slopes = np.diff(t) / np.diff(s)
        if np.any(slopes > k0 * (1 + 1e-12)):
            raise ValueError(
                "no segment of the bond law may be steeper than the first one "
                f"(k0 = {k0:.4g} Pa/m, slopes {slopes.tolist()})")
        object.__setattr__(self, "slip", tuple(float(x) for x in s))
        object.__setattr__(self, "stress", tuple(float(x) for x in t))

    @classmethod
    def uniform(cls, strength: float, elastic_slip: float) -> BondLaw:
        """Elastic up to ``strength`` [Pa] at ``elastic_slip`` [m], then constant (plastic)."""
        return cls((elastic_slip, 1e3 * elastic_slip + 1.0), (strength, strength))

    @classmethod
    def linear(cls, stiffness: float, up_to: float = 1.0) -> BondLaw:
        """Linear elastic bond τ = k s [Pa] with k = ``stiffness`` [Pa/m] (up to the slip
        ``up_to`` [m], constant beyond)."""
        return cls((up_to,), (stiffness * up_to,))

    @property
    def k0(self) -> float:
        """Initial (and unloading) stiffness [Pa/m]."""
        return self.stress[0] / self.slip[0]

    @property
    def strength(self) -> float:
        """Peak bond stress [Pa]."""
        return max(self.stress)

    def envelope(self, s: np.ndarray) -> np.ndarray:
        """τ on the monotonic envelope at slip ``s`` [m] (odd) [Pa]."""
        s = np.asarray(s, dtype=float)
        xs = np.r_[0.0, self.slip]
        ts = np.r_[0.0, self.stress]
        return np.sign(s) * np.interp(np.abs(s), xs, ts, right=ts[-1])


@dataclass(frozen=True)
class DowelLaw:
    """Transverse tie between bar and masonry: elastic–perfectly plastic.

    Args:
        stiffness: force per metre of bar per metre of transverse displacement [N/m²].
        strength: largest transverse force per metre of bar [N/m] (inf: elastic).
    """

    stiffness: float
    strength: float = math.inf

    def __post_init__(self) -> None:
        check_positive("dowel stiffness", self.stiffness)
        check_positive("dowel strength", self.strength, allow_inf=True)


@dataclass(frozen=True)
class JointDowel:
    """Dowel action of a bar where it crosses a joint: a shear spring between the two
    blocks at the crossing, across the bar, elastic–perfectly plastic (the local
    reinforcement of Lorig 1985, "A simple numerical representation of fully bonded
    passive rock reinforcement for hard rocks", Computers and Geotechnics 1, as in UDEC
    and 3DEC).

    The bar elements are trusses (axial force only) and their nodes follow the blocks
    across the bar, so a bar that crosses a joint resists its opening along the bar but,
    without this, nothing of its sliding: the shear a grouted bar carries across a sliding
    joint is its bending in the masonry on either side, a beam on an elastic foundation.

    Args:
        stiffness: force per bar per metre of relative slip of the two blocks across the
            bar [N/m].
        strength: largest force per bar [N] (inf: elastic).

    :meth:`from_bar` gives both from the bar and the masonry.
    """

    stiffness: float
    strength: float = math.inf

    def __post_init__(self) -> None:
        check_positive("joint dowel stiffness", self.stiffness)
        check_positive("joint dowel strength", self.strength, allow_inf=True)

    @classmethod
    def from_bar(cls, diameter: float, E: float, yield_stress: float, fc: float,
                 c1: float = 0.8, c0: float = 1.3) -> JointDowel:
        """The dowel of a bar of ``diameter`` d [m], Young's modulus ``E`` [Pa] and
        ``yield_stress`` f_y [Pa] bedded in a material of compressive strength ``fc`` [Pa]
        (the weaker of grout and masonry).

        * Stiffness: each half of the bar is a semi-infinite beam on a Winkler foundation
          of modulus k = k_c d [N/m²], loaded at the joint by the dowel force V with no
          moment there (the bending is antisymmetric about a zero-thickness joint). Its end
          moves y0 = 2 V λ / k (Hetényi 1946, "Beams on elastic foundation"), with
          λ = (k / (4 E I))^¼, I = π d⁴/64; the slip across the joint is 2 y0, so
          K = k / (4 λ). The subgrade coefficient k_c = 127 c1 √f_c / d^⅔ [N/mm³, f_c in
          MPa, d in mm] with c1 = 0.6–1.0 (Soroushian, Obaseki & Rojas 1987, "Bearing
          strength and stiffness of concrete under reinforcing bars", ACI Materials
          Journal 84(3); 0.8 their mean).
        * Strength: V_u = c0 d² √(f_c f_y), c0 = 1.3 (Rasmussen 1963; Vintzeleou & Tassios
          1986, "Mathematical models for dowel action under monotonic and cyclic
          conditions", Mag. Concr. Res. 38(134): yield of the bar with crushing of the
          bedding), at most the bar's shear yield f_y A/√3.
        """
        for name, v in (("diameter", diameter), ("E", E), ("yield_stress", yield_stress),
                        ("fc", fc), ("c1", c1), ("c0", c0)):
            check_positive(f"joint dowel {name}", v)
        d_mm, fc_mpa = 1e3 * diameter, 1e-6 * fc
        kc = 127.0 * c1 * math.sqrt(fc_mpa) / d_mm ** (2.0 / 3.0) * 1e9  # [N/m³]
        k = kc * diameter  # [N/m²]
        inertia = math.pi * diameter**4 / 64.0
        lam = (k / (4.0 * E * inertia)) ** 0.25
        area = math.pi * diameter**2 / 4.0
        vu = min(c0 * diameter**2 * math.sqrt(fc * yield_stress),
                 yield_stress * area / math.sqrt(3.0))
        return cls(stiffness=k / (4.0 * lam), strength=vu)


@dataclass(frozen=True)
class Anchor:
    """One anchor (or a row of ``count`` identical anchors across the model's width).

    Args:
        points: ``(k, 2)`` polyline [m] from its start to its end, k >= 2.
        diameter: bar diameter d [m] (steel area π d²/4).
        steel: the bar's :class:`SteelLaw`.
        bond: the grout bond's :class:`BondLaw`.
        bond_diameter: diameter of the bonded surface [m] (the grout sock of a Cintec
            anchor); default the bar diameter.
        prestress: lock-off force P [N] per bar (needs ``plates="both"``).
        plates: end plates at "none", "start", "end" or "both" ends.
        plate_stiffness: bearing stiffness of a plate on the masonry [N/m] per bar;
            default E_host · 0.1 m (a 100 mm plate on an elastic half-space).
        dowel: transverse :class:`DowelLaw`; default elastic with stiffness E_host.
        shear: :class:`JointDowel`, the bar's dowel action across each joint it crosses
            (None: none, the bar carries only its axial force across a joint).
        count: number of identical bars this anchor stands for across the width.
        segment: largest bar element length [m]; default the median element size of the
            block mesh.
        name: label used in messages and output.
    """

    points: np.ndarray
    diameter: float
    steel: SteelLaw = field(default_factory=SteelLaw)
    bond: BondLaw = field(default_factory=lambda: BondLaw.uniform(2e6, 2e-4))
    bond_diameter: float | None = None
    prestress: float = 0.0
    plates: str = "none"
    plate_stiffness: float | None = None
    dowel: DowelLaw | None = None
    shear: JointDowel | None = None
    count: float = 1.0
    segment: float | None = None
    name: str = ""

    def __post_init__(self) -> None:
        p = np.array(self.points, dtype=float)
        label = self.name or "anchor"
        if p.ndim != 2 or p.shape[1] != 2 or p.shape[0] < 2:
            raise ValueError(f"{label}: points must have shape (k, 2) with k >= 2, "
                             f"got {np.shape(self.points)}")
        if not np.all(np.isfinite(p)):
            raise ValueError(f"{label}: points must be finite")
        if np.any(np.linalg.norm(np.diff(p, axis=0), axis=1) <= 0):
            raise ValueError(f"{label}: two consecutive points coincide")
        object.__setattr__(self, "points", p)
        check_positive(f"{label}: diameter", self.diameter)
        if self.bond_diameter is not None:
            check_positive(f"{label}: bond_diameter", self.bond_diameter)
        check_positive(f"{label}: prestress", self.prestress, allow_zero=True)
        check_positive(f"{label}: count", self.count)
        if self.segment is not None:
            check_positive(f"{label}: segment", self.segment)
        if self.plate_stiffness is not None:
            check_positive(f"{label}: plate_stiffness", self.plate_stiffness)
        if self.plates not in _PLATES:
            raise ValueError(f"{label}: plates must be one of {list(_PLATES)}, "
                             f"got {self.plates!r}")
        if not isinstance(self.steel, SteelLaw) or not isinstance(self.bond, BondLaw):
            raise TypeError(f"{label}: steel must be a SteelLaw and bond a BondLaw")
        if self.dowel is not None and not isinstance(self.dowel, DowelLaw):
            raise TypeError(f"{label}: dowel must be a DowelLaw or None")
        if self.shear is not None and not isinstance(self.shear, JointDowel):
            raise TypeError(f"{label}: shear must be a JointDowel or None")
        if self.prestress > 0:
            if self.plates != "both":
                raise ValueError(f"{label}: a prestressed anchor needs end plates at both "
                                 f"ends (plates='both'), got plates={self.plates!r}")
            if self.prestress >= self.steel.yield_stress * self.area:
                raise ValueError(
                    f"{label}: prestress {self.prestress:.4g} N reaches the yield force "
                    f"{self.steel.yield_stress * self.area:.4g} N of the bar")

    @property
    def area(self) -> float:
        """Steel area π d²/4 of one bar [m²]."""
        return 0.25 * math.pi * self.diameter**2

    @property
    def perimeter(self) -> float:
        """Bonded perimeter π d_b of one bar [m]."""
        return math.pi * (self.bond_diameter or self.diameter)

    @property
    def length(self) -> float:
        """Length of the polyline [m]."""
        return float(np.linalg.norm(np.diff(self.points, axis=0), axis=1).sum())

    @property
    def yield_force(self) -> float:
        """f_y A of one bar [N]."""
        return self.steel.yield_stress * self.area
