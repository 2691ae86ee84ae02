"""Case files of ``masonry-fdem assess``: one masonry arch to assess, described in TOML.

:func:`load_case` reads a TOML file (or a dict of the same shape), checks everything and
returns a frozen :class:`ArchCase`; it never creates a file or folder. Every problem found
is collected, and all of them are raised together in one :class:`CaseError`, one line
each, naming the table and key (``arch.ring_thickness: must be > 0, got -0.1``). Unknown
keys are rejected with the closest known key as a suggestion. :func:`prepare_run_folder`
creates the output folder of a valid case.

Units are SI throughout: m, N, Pa, kg/m³, N/m (fracture energies), Pa/m (joint
stiffnesses); angles of anchors in degrees. Positions along the arch are fractions ``s``
of the arch, 0 at the left springing, 0.5 at the crown, 1 at the right springing (for a
circular arch ``s`` is proportional to the angle, see :mod:`masonry_fdem.geometry.arches`).
The arch stands with the middle of its span at the origin, on the springing line.

Schema (``*``: required):

``[arch]``
    ``kind`` "semicircular" (default), "segmental" or "pointed"; ``span``\\* clear span
    between the intrados springings [m]; ``rise`` intrados rise [m], required for
    segmental (< span/2) and pointed (> span/2) arches, none for semicircular ones;
    ``rings`` number of rings (1); ``ring_thickness``\\* [m]; ``voussoirs``\\* per ring, one
    integer for all rings or a list, innermost ring first; ``stagger`` joint shift of ring
    ``k`` in voussoirs is ``stagger·k`` (0.5), in [0, 1); ``segments`` straight pieces
    per voussoir face (1); ``abutment_height``\\* height of the abutment blocks under the
    springings [m]; ``abutment_width`` [m] from the intrados springing outward (default:
    the springing joint); ``width`` barrel width, out of plane [m] (1.0); ``mesh_size``
    element size [m] (ring_thickness/4); ``voussoir_material`` ("brick") and
    ``abutment_material`` ("abutment"): names of ``[materials]`` tables.
``[materials.<name>]``
    ``density``\\* [kg/m³], ``E``\\* [Pa], ``nu``\\* — one table per block material; those
    named in ``[arch]`` must exist.
``[joints.mortar]``\\*
    The :class:`~masonry_fdem.interactions.joints.joints.JointMaterial` of the joints between voussoirs
    and at the springings: ``kn``, ``ks`` [Pa/m] (default from the blocks' E), ``ft`` [Pa],
    ``GfI`` [N/m], ``c`` [Pa], ``tan_phi``, ``GfII`` [N/m], ``tan_psi``,
    ``psi_confinement`` [Pa], ``psi_decay`` [1/m], ``fc`` [Pa], ``Cs``, ``kappa_p`` [m],
    ``Gfc`` [N/m], ``penalty``; defaults as in JointMaterial (an empty table is a dry
    joint with tan φ = 0.6).
``[joints.ring]``
    The interfaces between rings. ``type = "bonded"`` (default): the mortar, with any
    field given here replacing the mortar's; ``type = "sand"``: a dry sand layer, friction
    only: ``tan_phi``\\* and optionally the stiffnesses and the cap (no ``ft``, ``GfI``,
    ``c``, ``GfII``). Default: the mortar.
``[loading]``
    A vertical load on the extrados, raised in increments. ``position`` fraction of the
    span from the left springing (0.25) *or* ``x`` horizontal distance from the left
    intrados springing [m]; ``spreader_width`` [m] (0: point load); ``increment`` [N]
    (9806.65, one tonne-force); ``max_load`` [N] (none: until collapse; under
    displacement control the run also ends once the load reaches it); ``self_weight``
    (true); ``control`` "load" (default) or "displacement"; ``displacement_increment``
    [m] (required for displacement control); ``max_displacement`` [m] (none).
``[[damage]]``
    Any number of entries, each with ``type``\\*:

    * "ring_separation": no bond between rings ``rings`` (two ring indices ``[a, b]``:
      every interface between them; or "all", the default) for ``from`` <= s <= ``to``
      (0, 1); the separated faces are left to frictional contact.
    * "decayed_mortar": the strengths ``ft``, ``c``, ``fc`` of the joints of ``rings``
      (list or "all") in ``from`` <= s <= ``to`` are multiplied by ``factor``\\* in (0, 1];
      an interface between two listed rings decays too. Overlapping zones: smallest factor.
    * "open_joint": the joint ``index`` of ring ``ring``\\* has no bond; joint ``j`` is
      the start of voussoir ``j`` (0 and n: the springings). Instead of ``index``,
      ``position`` picks the joint nearest to that s.
    * "missing_brick": voussoir ``index``\\* of ring ``ring``\\* is removed.
``[analysis]``
    ``limit_analysis`` run the rigid-block limit analysis first (true); ``friction``
    Coulomb coefficient of that analysis (default: the mortar's tan_phi); ``dr_rtol``
    relative residual of dynamic relaxation (1e-6); ``max_iterations`` per increment
    (200000); ``output`` run folder ("runs/<case file stem>"; relative to the working
    directory); ``refinements`` halvings of a load increment that finds no equilibrium
    before collapse is declared (4); ``hinge_opening`` [m] opening (beyond the
    self-weight state) at which an end of a joint counts as open (1e-5); ``penalty_factor``
    of the block contact at dry joints, × E/h (20); displacement control stops once the
    load has fallen for ``post_peak_steps`` (3) steps after the peak, or below
    (1 − ``post_peak_drop``) (0.2) of it; ``follow_peak`` (true): under load control, when
    an increment finds no equilibrium, go on from the last equilibrium under displacement
    control (steps of ``displacement_increment``, default a quarter of the load-line
    displacement reached) to find the peak and the post-peak branch.
``[[anchors]]``
    Repairs: ``layout``\\* "radial" (``angles``\\*: list of polar angles [deg] about the
    intrados centre, 90 = crown; ``cover`` [m] from intrados and extrados, 0.02) or
    "stitch" (``start_angle``\\*, ``end_angle``\\* [deg], ``depth``\\* above the intrados [m],
    ``pieces`` chords); ``diameter``\\* bar diameter [m]; ``count`` bars across the width
    (1); ``prestress`` [N] (0); ``plates`` "none", "start", "end" or "both"; optional
    ``bond_diameter`` [m], ``segment`` [m], ``name``; ``[anchors.steel]`` ``E``,
    ``yield_stress`` [Pa], ``hardening`` [Pa], ``rupture_strain``, ``density``
    (:class:`~masonry_fdem.interactions.anchors.SteelLaw`); ``[anchors.bond]`` ``slip`` [m] and
    ``stress`` [Pa] lists (:class:`~masonry_fdem.interactions.anchors.BondLaw`). Circular arches only.
    ``layout = "inclined"``: straight anchors drilled from the intrados (``positions``\\*:
    s of the entry points; ``inclination`` [deg] to the intrados tangent, 90 = radial,
    below 90 leaning towards the right springing; ``length`` [m], default through to
    ``cover`` below the extrados). An anchor that leaves the structure is refused.
``[search]``
    The candidate space of an anchor layout search (:class:`SearchSpec`,
    :func:`masonry_fdem.assessment.repair.search`): ``positions`` (s), ``counts`` (anchors per
    layout, [1]), ``inclinations`` [deg] ([90]), ``lengths`` [m] or "through"
    (["through"]), ``prestress`` [N] ([0]); every combination, plus explicit
    ``[[search.layouts]]`` (``positions``\\*, ``inclination``, ``length``, ``prestress``).
    The bars: ``diameter`` [m] (0.016), ``bars`` across the width (1), ``cover`` [m]
    (0.02), ``[search.steel]``, ``[search.bond]``; ``min_spacing`` [m] between anchors
    (0.05). ``objective`` "gain_per_metre" (default) or "cheapest" (needs ``target``
    [N]); ``keep`` (4) and ``keep_ratio`` (0.5): what survives the coarse level;
    ``coarse`` (true); ``max_candidates`` (500).

:data:`EXAMPLE_CASE` is the reference case, a three-ring brick arch with sand between the
rings loaded at quarter span (the TRL test of Owen et al.); :data:`REPAIR_EXAMPLE` is the
same under displacement control with anchors.
"""

from __future__ import annotations

import difflib
import math
import numbers
import re
import tomllib
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, fields, replace
from enum import StrEnum
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np

from masonry_fdem.assessment.layouts import inclined_anchors, intrados_stitch, radial_anchors
from masonry_fdem.constants import G
from masonry_fdem.interactions.anchors import Anchor, BondLaw, SteelLaw
from masonry_fdem.interactions.joints.joints import JointMaterial
from masonry_fdem.geometry.arches import ArchKind, ring_pieces, arch_layout
from masonry_fdem.geometry.layout import BlockLayout
from masonry_fdem.materials.elastic import Material

__all__ = [
    "EXAMPLE_CASE",
    "REPAIR_EXAMPLE",
    "TONNE_FORCE",
    "AnalysisSpec",
    "AnchorLayout",
    "AnchorSpec",
    "Objective",
    "SearchSpec",
    "ArchCase",
    "ArchSpec",
    "CaseError",
    "Damage",
    "DamageKind",
    "LoadControl",
    "LoadingSpec",
    "load_case",
    "prepare_run_folder",
]

#: One tonne-force [N].
TONNE_FORCE = 1000.0 * G

EXAMPLE_CASE = """\
# Reference case: three-ring brick arch with wet sand between the rings (ring separation),
# loaded to collapse at quarter span in 1 tonne increments (after the TRL tests of
# multi-ring arches, Owen et al.). Coarse: one triangle through each ring (~5 min on
# 2 cores); refine mesh_size and dr_rtol for a study.

[arch]
kind = "semicircular"          # semicircular | segmental (needs rise) | pointed (needs rise)
span = 3.0                     # clear span between the intrados springings [m]
rings = 3
ring_thickness = 0.11          # [m]
voussoirs = [26, 28, 30]       # per ring, innermost first (~0.19 m long each)
stagger = 0.5                  # joints of ring k shifted by 0.5·k voussoir
segments = 1                   # straight pieces per voussoir face
abutment_height = 0.5          # [m]
abutment_width = 0.6           # [m], from the intrados springing outward
width = 1.0                    # barrel width, out of plane [m]
mesh_size = 0.11               # [m]
voussoir_material = "brick"
abutment_material = "abutment"

[materials.brick]
density = 2000.0               # [kg/m^3]
E = 10e9                       # [Pa]
nu = 0.2

[materials.abutment]
density = 2400.0
E = 30e9
nu = 0.2

[joints.mortar]                # lime mortar, 10 mm joints
kn = 2.5e11                    # [Pa/m]
ks = 1.0e11                    # [Pa/m]
ft = 0.1e6                     # [Pa]
GfI = 10.0                     # [N/m]
c = 0.15e6                     # [Pa]
tan_phi = 0.6
GfII = 50.0                    # [N/m]
fc = 10e6                      # [Pa]

[joints.ring]                  # weak layer of sand between the rings
type = "sand"
tan_phi = 0.5
kn = 5e9                       # [Pa/m]
ks = 2e9                       # [Pa/m]

[loading]
position = 0.25                # fraction of the span from the left springing (or x [m])
spreader_width = 0.1           # [m]
increment = 9806.65            # 1 tonne [N]
max_load = 490332.5            # 50 tonnes [N]
self_weight = true
control = "load"               # load | displacement (then displacement_increment [m])
# displacement_increment = 3e-5  # [m]; under load control: the steps after a stall

[analysis]
limit_analysis = true
friction = 0.6                 # of the rigid-block limit analysis (no bond)
dr_rtol = 1e-4                 # out-of-balance force / applied load
max_iterations = 60000         # per increment; beyond: no equilibrium found
refinements = 0                # halvings of an increment that finds no equilibrium
follow_peak = true             # then go on under displacement control to the peak
post_peak_steps = 2
# output = "runs/arch"         # default: runs/<case file stem>

# Damage, any number of entries:
# [[damage]]
# type = "ring_separation"     # rings = [0, 1] or "all"; from/to: fractions of the arch
# rings = [0, 1]
# from = 0.3
# to = 0.7
# [[damage]]
# type = "missing_brick"
# ring = 0
# index = 12

# Repairs:
# [[anchors]]
# layout = "radial"            # or "stitch" (start_angle, end_angle, depth)
# angles = [45.0, 67.5, 90.0, 112.5, 135.0]
# diameter = 0.016             # [m]
# [anchors.steel]
# yield_stress = 500e6         # [Pa]
# [anchors.bond]
# slip = [2e-4, 2e-3]          # [m]
# stress = [2e6, 1e6]          # [Pa]
"""

def _repair_example() -> str:
    text = EXAMPLE_CASE.replace(
        'control = "load"               # load | displacement (then displacement_increment [m])\n'
        '# displacement_increment = 3e-5  # [m]; under load control: the steps after a stall',
        'control = "displacement"       # the platen driven down: load control stalls early on\n'
        '                               # ring-separated arches (see the README)\n'
        'displacement_increment = 1e-4  # [m]\n'
        'max_displacement = 1.5e-3      # [m]')
    text = text.replace("post_peak_steps = 2", "post_peak_steps = 1")
    text = text.replace("limit_analysis = true", "limit_analysis = false")
    text = text.split("# Damage, any number of entries:")[0]
    head = ("# Repair example (`masonry-fdem example --repair`): the reference case below,\n"
            "# driven under displacement control, unstrengthened and with the anchors at the\n"
            "# end (`masonry-fdem repair`).\n")
    return head + text + \
        """# The repair: nine straight anchors drilled from the intrados at 30 deg to it, through
# the three rings (tying them across the sand layers and across the radial joints), and
# two curved stitches along the barrel, one in the inner ring and one in the outer ring.
[[anchors]]
layout = "inclined"
positions = [0.05, 0.15, 0.25, 0.35, 0.45, 0.55, 0.65, 0.75, 0.85]  # s of the entry points
inclination = 30.0             # [deg] to the intrados tangent (90: radial)
diameter = 0.016               # [m]
name = "inclined"
# steel and bond: the defaults ([anchors.steel], [anchors.bond] tables to change them)

[[anchors]]
layout = "stitch"
start_angle = 10.0             # [deg] about the intrados centre, 90 = crown
end_angle = 170.0
depth = 0.05                   # [m] above the intrados
diameter = 0.016
name = "intrados stitch"

[[anchors]]
layout = "stitch"
start_angle = 10.0
end_angle = 170.0
depth = 0.28
diameter = 0.016
name = "extrados stitch"

# A layout search ([search], see the README) would go here; `masonry-fdem repair` runs
# the comparison above and the search if both are given.
"""



_REQUIRED = object()
_S_TOL = 1e-9


class CaseError(ValueError):
    """Problems in a case, all of them (``problems``: one line each)."""

    def __init__(self, problems: str | Sequence[str], source: str | None = None):
        self.problems = [problems] if isinstance(problems, str) else list(problems)
        self.source = source
        head = f"{source}: " if source else ""
        if len(self.problems) == 1:
            msg = head + self.problems[0]
        else:
            msg = f"{head}{len(self.problems)} problems:\n" + "\n".join(
                "  " + p for p in self.problems)
        super().__init__(msg)


class LoadControl(StrEnum):
    """How the load is raised."""

    LOAD = "load"
    DISPLACEMENT = "displacement"


class DamageKind(StrEnum):
    """Kinds of ``[[damage]]`` entries."""

    RING_SEPARATION = "ring_separation"
    DECAYED_MORTAR = "decayed_mortar"
    OPEN_JOINT = "open_joint"
    MISSING_BRICK = "missing_brick"


@dataclass(frozen=True)
class ArchSpec:
    """The ``[arch]`` table (lengths in m); ``voussoirs`` has one count per ring."""

    kind: ArchKind
    span: float
    rise: float | None
    rings: int
    ring_thickness: float
    voussoirs: tuple[int, ...]
    stagger: float
    segments: int
    abutment_height: float
    abutment_width: float | None
    width: float
    mesh_size: float
    voussoir_material: str
    abutment_material: str

    def layout_kwargs(self) -> dict[str, Any]:
        """Keyword arguments of :func:`~masonry_fdem.geometry.arch_layout`."""
        return dict(kind=self.kind, span=self.span, rise=self.rise, rings=self.rings,
                    ring_thickness=self.ring_thickness, voussoirs=list(self.voussoirs),
                    stagger=self.stagger, segments=self.segments,
                    abutment_height=self.abutment_height, abutment_width=self.abutment_width,
                    material=self.voussoir_material,
                    abutment_material=self.abutment_material)

    def joint_positions(self, ring: int) -> np.ndarray:
        """Positions s of the joints of ``ring``, springings included (n_blocks + 1)."""
        pieces = ring_pieces(self.voussoirs[ring], self.stagger * ring)
        return np.array([pieces[0][0], *(b for _, b in pieces)])

    def blocks_in_ring(self, ring: int) -> int:
        """Number of voussoirs of ``ring`` (one more than ``voussoirs`` if staggered)."""
        return len(self.joint_positions(ring)) - 1


@dataclass(frozen=True)
class LoadingSpec:
    """The ``[loading]`` table; ``position`` is always the fraction of the span."""

    position: float
    spreader_width: float
    increment: float
    max_load: float | None
    self_weight: bool
    control: LoadControl
    displacement_increment: float | None
    max_displacement: float | None


@dataclass(frozen=True)
class Damage:
    """One ``[[damage]]`` entry; ``start``/``end`` are its ``from``/``to``."""

    kind: DamageKind
    rings: tuple[int, ...] = ()
    start: float = 0.0
    end: float = 1.0
    factor: float = 1.0
    ring: int | None = None
    index: int | None = None


@dataclass(frozen=True)
class AnalysisSpec:
    """The ``[analysis]`` table."""

    limit_analysis: bool
    friction: float
    dr_rtol: float
    max_iterations: int
    output: Path
    refinements: int = 4
    hinge_opening: float = 1e-5
    penalty_factor: float = 20.0
    post_peak_steps: int = 3
    post_peak_drop: float = 0.2
    follow_peak: bool = True


@dataclass(frozen=True)
class AnchorSpec:
    """One ``[[anchors]]`` entry (angles in degrees, lengths in m, forces in N)."""

    layout: str
    diameter: float
    steel: SteelLaw
    bond: BondLaw
    angles: tuple[float, ...] = ()
    cover: float = 0.02
    start_angle: float | None = None
    end_angle: float | None = None
    depth: float | None = None
    pieces: int | None = None
    positions: tuple[float, ...] = ()
    inclination: float = 90.0
    length: float | None = None
    count: float = 1.0
    prestress: float = 0.0
    plates: str = "none"
    bond_diameter: float | None = None
    segment: float | None = None
    name: str = "anchor"

    def build(self, arch: ArchSpec) -> list[Anchor]:
        """The anchors in ``arch``.

        Raises:
            ValueError: an angle outside the arch, a non-circular arch, bad anchor data.
        """
        kw = dict(diameter=self.diameter, steel=self.steel, bond=self.bond, count=self.count,
                  prestress=self.prestress, plates=self.plates,
                  bond_diameter=self.bond_diameter, segment=self.segment, name=self.name)
        geo = dict(span=arch.span, kind=arch.kind.value, rise=arch.rise)
        if self.layout == "radial":
            return radial_anchors(self.angles, ring_thickness=arch.ring_thickness,
                                  rings=arch.rings, cover=self.cover, **geo, **kw)
        if self.layout == "inclined":
            return inclined_anchors(self.positions, inclination=self.inclination,
                                    length=self.length, ring_thickness=arch.ring_thickness,
                                    rings=arch.rings, cover=self.cover, **geo, **kw)
        depth = arch.rings * arch.ring_thickness
        if not 0.0 < self.depth < depth:
            raise ValueError(f"depth {self.depth} m is outside the arch (0..{depth:g} m)")
        return [intrados_stitch(self.start_angle, self.end_angle, depth=self.depth,
                                pieces=self.pieces, **geo, **kw)]


@dataclass(frozen=True)
class AnchorLayout:
    """One candidate of a layout search: straight anchors drilled from the intrados
    (see :func:`~masonry_fdem.assessment.layouts.inclined_anchors`), all alike.

    Attributes:
        positions: s of the entry points (0: left springing, 1: right springing).
        inclination: angle to the intrados tangent [deg] (90: radial).
        length: anchor length [m] (None: through to the extrados cover).
        prestress: lock-off force [N] per bar (0: passive anchors).
    """

    positions: tuple[float, ...]
    inclination: float = 90.0
    length: float | None = None
    prestress: float = 0.0

    @property
    def key(self) -> str:
        """A stable, readable identifier (the search journal's key)."""
        pos = ",".join(f"{p:.4g}" for p in self.positions)
        ell = "through" if self.length is None else f"{self.length:.4g}m"
        return f"s=[{pos}] {self.inclination:.4g}deg {ell} P={self.prestress:.4g}N"

    def spec(self, search: SearchSpec) -> AnchorSpec:
        """The ``[[anchors]]`` entry of this layout with the search's bar and bond."""
        return AnchorSpec("inclined", search.diameter, search.steel, search.bond,
                          positions=self.positions, inclination=self.inclination,
                          length=self.length, cover=search.cover, count=search.bars,
                          prestress=self.prestress,
                          plates="both" if self.prestress > 0 else "none", name="anchor")


class Objective(StrEnum):
    """What the layout search looks for."""

    GAIN_PER_METRE = "gain_per_metre"
    CHEAPEST = "cheapest"


@dataclass(frozen=True)
class SearchSpec:
    """The ``[search]`` table: the candidate space of a layout search (see
    :func:`masonry_fdem.assessment.repair.search`). Lengths [m], angles [deg], forces [N].

    The candidates are every combination of ``count`` positions out of ``positions``
    (for each of ``counts``), with each of ``inclinations``, ``lengths`` and
    ``prestress``, plus the explicit ``layouts``.
    """

    positions: tuple[float, ...] = ()
    counts: tuple[int, ...] = (1,)
    inclinations: tuple[float, ...] = (90.0,)
    lengths: tuple[float | None, ...] = (None,)
    prestress: tuple[float, ...] = (0.0,)
    layouts: tuple[AnchorLayout, ...] = ()
    diameter: float = 0.016
    bars: float = 1.0
    cover: float = 0.02
    min_spacing: float = 0.05
    steel: SteelLaw = SteelLaw()
    bond: BondLaw = BondLaw.uniform(2e6, 2e-4)
    objective: Objective = Objective.GAIN_PER_METRE
    target: float | None = None
    keep: int = 4
    keep_ratio: float = 0.5
    coarse: bool = True
    max_candidates: int = 500

    def __post_init__(self) -> None:
        object.__setattr__(self, "objective", Objective(self.objective))
        if self.objective is Objective.CHEAPEST and self.target is None:
            raise ValueError('objective "cheapest" needs a target load [N]')
        if self.keep < 1 or not 0.0 <= self.keep_ratio <= 1.0:
            raise ValueError(f"keep must be >= 1 and keep_ratio in [0, 1], got "
                             f"{self.keep}, {self.keep_ratio}")

    def candidates(self) -> list[AnchorLayout]:
        """The candidate layouts, in a fixed order (explicit ``layouts`` last)."""
        import itertools

        out = []
        for n in self.counts:
            for pos in itertools.combinations(self.positions, n):
                for inc in self.inclinations:
                    for ell in self.lengths:
                        for p in self.prestress:
                            out.append(AnchorLayout(tuple(pos), inc, ell, p))
        return out + list(self.layouts)



@dataclass(frozen=True, eq=False)
class ArchCase:
    """A validated case (see the module doc); build it with :func:`load_case`."""

    name: str
    arch: ArchSpec
    material_table: Mapping[str, Material]
    mortar: JointMaterial
    ring_joint: JointMaterial
    ring_joint_type: str
    loading: LoadingSpec
    damage: tuple[Damage, ...]
    analysis: AnalysisSpec
    anchor_specs: tuple[AnchorSpec, ...]
    source: Path | None = None
    search: SearchSpec | None = None

    def layout(self) -> BlockLayout:
        """The arch and its abutments, without the voussoirs of "missing_brick" damage."""
        full = arch_layout(**self.arch.layout_kwargs())
        gone = {f"voussoir:{d.ring}:{d.index}" for d in self.damage
                if d.kind is DamageKind.MISSING_BRICK}
        keep = [i for i, n in enumerate(full.names) if n not in gone]
        return BlockLayout(tuple(full.polygons[i] for i in keep),
                           tuple(full.materials[i] for i in keep),
                           tuple(full.names[i] for i in keep))

    def mesh_layout(self) -> BlockLayout:
        """:meth:`layout` with the :meth:`load_points` added as vertices of the
        voussoirs they bear on, so the mesh has a node exactly there (the outlines are
        unchanged: the new vertices lie on straight edges)."""
        layout = self.layout()
        polys = list(layout.polygons)
        tol = 1e-9 * self.arch.span
        for pt in self.load_points():
            for i, (poly, name) in enumerate(zip(polys, layout.names, strict=True)):
                if not name.startswith("voussoir:"):
                    continue
                a, b = poly, np.roll(poly, -1, axis=0)
                d = b - a
                t = np.einsum("ij,ij->i", pt - a, d) / np.einsum("ij,ij->i", d, d)
                near = np.linalg.norm(a + np.clip(t, 0, 1)[:, None] * d - pt, axis=1)
                k = int(np.argmin(near))
                if near[k] > tol:
                    continue
                if np.min(np.linalg.norm(poly - pt, axis=1)) > tol:
                    polys[i] = np.insert(poly, k + 1, pt, axis=0)
                break
        return BlockLayout(tuple(polys), layout.materials, layout.names)

    def materials(self) -> dict[str, Material]:
        """Block material name -> :class:`~masonry_fdem.materials.Material`."""
        return dict(self.material_table)

    def anchors(self) -> list[Anchor]:
        """The ``[[anchors]]`` as :class:`~masonry_fdem.interactions.anchors.Anchor` objects."""
        return [a for spec in self.anchor_specs for a in spec.build(self.arch)]

    def anchor_problems(self, anchors: Sequence[Anchor] | None = None,
                        min_spacing: float | None = None) -> list[str]:
        """What is wrong with an anchor layout in this arch (empty if nothing).

        Args:
            anchors: the anchors (default: the case's own :meth:`anchors`).
            min_spacing: if given, two anchors closer than this [m] (crossing, touching
                or running side by side) are a problem too.

        An anchor leaves the structure when a point of it lies outside every block of
        :meth:`layout` (through the extrados, past a springing into the air, through
        a missing voussoir); it is tested every 1/20 of a ring thickness along the bar.
        """
        anchors = self.anchors() if anchors is None else list(anchors)
        polys = list(self.layout().polygons)
        tol = 1e-9 * self.arch.span
        step = self.arch.ring_thickness / 20.0
        out = []
        for k, a in enumerate(anchors):
            label = a.name or f"anchor {k}"
            pts = []
            for p, q in zip(a.points[:-1], a.points[1:], strict=True):
                m = max(1, math.ceil(np.linalg.norm(q - p) / step))
                pts.append(p + np.linspace(0.0, 1.0, m + 1)[:, None] * (q - p))
            pts = np.vstack(pts)
            bad = ~_inside_any(polys, pts, tol)
            if bad.any():
                x, y = pts[int(np.argmax(bad))]
                out.append(f"{label} leaves the structure at ({x:.3f}, {y:.3f}) m: "
                           "that point is in no block of the arch or its abutments")
        if min_spacing is not None:
            for i in range(len(anchors)):
                for j in range(i + 1, len(anchors)):
                    d = _polyline_distance(anchors[i].points, anchors[j].points)
                    if d < min_spacing:
                        li = anchors[i].name or f"anchor {i}"
                        lj = anchors[j].name or f"anchor {j}"
                        how = "cross" if d <= tol else f"are {d * 1e3:.1f} mm apart"
                        out.append(f"{li} and {lj} overlap: they {how}, closer than the "
                                   f"minimum spacing {min_spacing * 1e3:.0f} mm")
        return out

    def with_anchors(self, specs: Sequence[AnchorSpec]) -> ArchCase:
        """The same case with these ``[[anchors]]`` instead of its own (none: unstrengthened)."""
        return replace(self, anchor_specs=tuple(specs))

    def load_x(self) -> float:
        """Horizontal coordinate [m] of the load (the origin is at mid-span)."""
        return (self.loading.position - 0.5) * self.arch.span

    def load_point(self) -> tuple[float, float]:
        """``(x, y)`` [m] of the load on the extrados (on the voussoir outlines)."""
        x = self.load_x()
        return x, _top_of(self.layout(), x)

    def load_points(self) -> np.ndarray:
        """``(k, 2)`` points [m] where the spreader bears on the extrados: its two ends
        (the load point if there is no spreader); each takes an equal share."""
        half = 0.5 * self.loading.spreader_width
        if half == 0.0:
            return np.array([self.load_point()])
        layout, x = self.layout(), self.load_x()
        return np.array([[xs, _top_of(layout, xs)] for xs in (x - half, x + half)])

    def joint_materials(self) -> dict[tuple[str, str], JointMaterial]:
        """Joint material per pair of block materials (the mortar) for
        :class:`~masonry_fdem.interactions.joints.joints.Joints`; see :meth:`joint_rules` for the rest."""
        v, a = self.arch.voussoir_material, self.arch.abutment_material
        return {(v, v): self.mortar, (v, a): self.mortar}

    def joint_rules(
        self, layout: BlockLayout | None = None
    ) -> list[tuple[Callable[[np.ndarray], bool], JointMaterial | None]]:
        """``where`` rules of :class:`~masonry_fdem.interactions.joints.joints.Joints`: the ring
        interfaces and the damaged joints (None: no bond, left to the contact).

        A joint segment matches a rule when its midpoint lies on one of the rule's
        interfaces of ``layout`` (default :meth:`layout`).
        """
        from masonry_fdem.solvers.limit_analysis import find_interfaces

        layout = self.layout() if layout is None else layout
        itf = find_interfaces(layout)
        groups: dict[Any, tuple[JointMaterial | None, list[int]]] = {}
        for i in range(itf.size):
            where = _classify(layout.names[itf.block_a[i]], layout.names[itf.block_b[i]],
                              self.arch)
            if where is None:
                continue
            mid = 0.5 * (itf.start[i] + itf.end[i])
            key = self._joint_state(where, mid)
            if key == ("joint", 1.0):
                continue  # plain mortar: the materials table
            if key not in groups:
                groups[key] = (self._joint_material(*key), [])
            groups[key][1].append(i)
        tol = 1e-6 * self.arch.span
        return [(_on_segments(itf.start[idx], itf.end[idx], tol), mat)
                for mat, idx in groups.values()]

    def _joint_state(self, where: tuple[str, int, int], mid: np.ndarray):
        kind, k, j = where
        s = (self.arch.joint_positions(k)[j] if kind == "joint"
             else _arch_parameter(self.arch, mid))
        factor = 1.0
        for d in self.damage:
            inside = d.start - _S_TOL <= s <= d.end + _S_TOL
            if d.kind is DamageKind.OPEN_JOINT and kind == "joint" and (k, j) == (d.ring, d.index):
                return ("dry", 0.0)
            if d.kind is DamageKind.RING_SEPARATION and kind == "ring" and inside:
                if min(d.rings) < k <= max(d.rings):
                    return ("dry", 0.0)
            if d.kind is DamageKind.DECAYED_MORTAR and inside:
                if (k in d.rings) and (kind == "joint" or k - 1 in d.rings):
                    factor = min(factor, d.factor)
        return (kind, factor)

    def _joint_material(self, kind: str, factor: float) -> JointMaterial | None:
        if kind == "dry":
            return None
        base = self.mortar if kind == "joint" else self.ring_joint
        if factor == 1.0:
            return base
        return replace(base, ft=base.ft * factor, c=base.c * factor,
                       fc=None if base.fc is None else base.fc * factor)

    def limit_analysis(self, **kw: Any):
        """Rigid-block collapse load of the case by
        :func:`~masonry_fdem.solvers.limit_analysis.limit_analysis`: the live load is 1 N shared by
        :meth:`load_points`, so the load factor is the collapse load [N]. Keywords
        override the arguments (e.g. ``friction``)."""
        from masonry_fdem.solvers.limit_analysis import limit_analysis

        pts = self.load_points()
        args = dict(
            density={n: m.density for n, m in self.material_table.items()},
            width=self.arch.width, supports="abutment:*",
            live_loads=[((p[0], p[1]), (0.0, -1.0 / len(pts))) for p in pts],
            friction=self.analysis.friction, g=G if self.loading.self_weight else 0.0,
            max_load_factor=self.loading.max_load or 1e9)
        args.update(kw)
        return limit_analysis(self.layout(), **args)


# ---------------------------------------------------------------------- geometry helpers
def _top_of(layout: BlockLayout, x: float) -> float:
    """Highest y [m] of the voussoir outlines on the vertical line through x."""
    best = -math.inf
    for poly, name in zip(layout.polygons, layout.names, strict=True):
        if not name.startswith("voussoir:"):
            continue
        a, b = poly, np.roll(poly, -1, axis=0)
        lo, hi = np.minimum(a[:, 0], b[:, 0]), np.maximum(a[:, 0], b[:, 0])
        m = (lo <= x) & (x <= hi) & (hi > lo)
        if m.any():
            t = (x - a[m, 0]) / (b[m, 0] - a[m, 0])
            best = max(best, float(np.max(a[m, 1] + t * (b[m, 1] - a[m, 1]))))
    if not math.isfinite(best):
        raise CaseError(f"loading: no voussoir under x = {x:g} m")
    return best


def _arch_parameter(arch: ArchSpec, p: np.ndarray) -> float:
    """Position s in [0, 1] of point ``p`` [m] along the arch (inverse of arch_curve)."""
    x, y = float(p[0]), float(p[1])
    half = 0.5 * arch.span
    if arch.kind is ArchKind.POINTED:
        c = (arch.rise**2 - half * half) / arch.span
        xl = -abs(x)
        r = math.hypot(xl - c, y)
        theta = math.atan2(y, xl - c)
        crown = math.atan2(math.sqrt(max(r * r - c * c, 0.0)), -c)
        u = (math.pi - theta) / (2.0 * (math.pi - crown))
        return u if x <= 0.0 else 1.0 - u
    if arch.kind is ArchKind.SEMICIRCULAR:
        yc, alpha = 0.0, 0.5 * math.pi
    else:
        radius = (half * half + arch.rise**2) / (2.0 * arch.rise)
        yc, alpha = arch.rise - radius, math.asin(half / radius)
    theta = math.atan2(y - yc, x)
    return (0.5 * math.pi + alpha - theta) / (2.0 * alpha)


def _classify(na: str, nb: str, arch: ArchSpec) -> tuple[str, int, int] | None:
    """("joint", ring, joint index) or ("ring", upper ring, -1) of the interface of two
    blocks; None between abutments."""
    pa, pb = na.split(":"), nb.split(":")
    if pa[0] == "abutment":
        pa, pb = pb, pa
    if pa[0] != "voussoir":
        return None
    ka, ja = int(pa[1]), int(pa[2])
    if pb[0] == "abutment":
        return ("joint", ka, 0 if pb[1] == "left" else arch.blocks_in_ring(ka))
    kb, jb = int(pb[1]), int(pb[2])
    if ka == kb:
        return ("joint", ka, max(ja, jb))
    return ("ring", max(ka, kb), -1)


def _on_segments(p0: np.ndarray, p1: np.ndarray, tol: float) -> Callable[[np.ndarray], bool]:
    p0, d = np.array(p0, dtype=float), np.array(p1, dtype=float) - np.array(p0, dtype=float)
    l2 = np.einsum("ij,ij->i", d, d)

    def on(x: np.ndarray) -> bool:
        x = np.asarray(x, dtype=float)[:2]
        t = np.clip(np.einsum("ij,ij->i", x - p0, d) / l2, 0.0, 1.0)
        return bool(np.min(np.linalg.norm(p0 + t[:, None] * d - x, axis=1)) <= tol)

    return on


def _inside_any(polys: Sequence[np.ndarray], pts: np.ndarray, tol: float) -> np.ndarray:
    """Whether each point lies in (or within ``tol`` of) one of the polygons."""
    inside = np.zeros(len(pts), dtype=bool)
    x, y = pts[:, 0], pts[:, 1]
    for poly in polys:
        a, b = poly, np.roll(poly, -1, axis=0)
        # even-odd rule
        cross = ((a[None, :, 1] > y[:, None]) != (b[None, :, 1] > y[:, None]))
        with np.errstate(divide="ignore", invalid="ignore"):
            xc = a[None, :, 0] + (y[:, None] - a[None, :, 1]) * (b[None, :, 0] - a[None, :, 0]) \
                / (b[None, :, 1] - a[None, :, 1])
        inside |= (np.count_nonzero(cross & (x[:, None] < xc), axis=1) % 2) == 1
        # on an edge
        d = b - a
        t = np.clip(((pts[:, None, :] - a[None]) * d[None]).sum(-1) / (d * d).sum(-1), 0, 1)
        near = np.linalg.norm(a[None] + t[..., None] * d[None] - pts[:, None, :], axis=-1)
        inside |= near.min(axis=1) <= tol
    return inside


def _segment_distance(p: np.ndarray, q: np.ndarray, r: np.ndarray, s: np.ndarray) -> float:
    """Distance between the segments pq and rs (0 if they cross)."""
    def orient(a, b, c):
        return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])

    d1, d2, d3, d4 = orient(r, s, p), orient(r, s, q), orient(p, q, r), orient(p, q, s)
    if d1 * d2 < 0 and d3 * d4 < 0:
        return 0.0

    def to_segment(x, a, b):
        ab = b - a
        t = float(np.clip(np.dot(x - a, ab) / np.dot(ab, ab), 0.0, 1.0))
        return float(np.linalg.norm(a + t * ab - x))

    return min(to_segment(p, r, s), to_segment(q, r, s), to_segment(r, p, q),
               to_segment(s, p, q))


def _polyline_distance(a: np.ndarray, b: np.ndarray) -> float:
    """Smallest distance between two polylines [m]."""
    return min(_segment_distance(a[i], a[i + 1], b[j], b[j + 1])
               for i in range(len(a) - 1) for j in range(len(b) - 1))


# ---------------------------------------------------------------------- reading tables
def _show(v: Any) -> str:
    return repr(v) if isinstance(v, str) else str(v)


class _Table:
    """Typed access to one table; problems go to ``problems``, bad values come back None."""

    def __init__(self, problems: list[str], path: str, data: Any, allowed: Sequence[str]):
        self.problems, self.path = problems, path
        if not isinstance(data, Mapping):
            problems.append(f"{path}: must be a table, got {_show(data)}")
            data = {}
        self.data = data
        for key in data:
            if key not in allowed:
                close = difflib.get_close_matches(key, list(allowed), n=1)
                hint = (f"did you mean {close[0]!r}?" if close
                        else "expected one of " + ", ".join(allowed))
                where = f"[{path}]" if path else "the case"
                problems.append(f"unknown key {key!r} in {where} ({hint})")

    def name(self, key: str) -> str:
        return f"{self.path}.{key}" if self.path else key

    def bad(self, key: str, msg: str) -> None:
        self.problems.append(f"{self.name(key)}: {msg}")

    def raw(self, key: str, default: Any) -> Any:
        if key in self.data:
            return self.data[key]
        if default is _REQUIRED:
            self.bad(key, "missing (required)")
        return None if default is _REQUIRED else default

    def number(self, key: str, default: Any = _REQUIRED, *, gt: float | None = None,
               ge: float | None = None, lt: float | None = None,
               le: float | None = None) -> float | None:
        v = self.raw(key, default)
        if v is None or key not in self.data:
            return v
        if isinstance(v, bool) or not isinstance(v, numbers.Real) or not math.isfinite(v):
            self.bad(key, f"must be a finite number, got {_show(v)}")
            return None
        for bound, op, ok in ((gt, ">", lambda a, b: a > b), (ge, ">=", lambda a, b: a >= b),
                              (lt, "<", lambda a, b: a < b), (le, "<=", lambda a, b: a <= b)):
            if bound is not None and not ok(v, bound):
                self.bad(key, f"must be {op} {bound:g}, got {v}")
                return None
        return float(v)

    def integer(self, key: str, default: Any = _REQUIRED, *, ge: int | None = None) -> int | None:
        v = self.raw(key, default)
        if v is None or key not in self.data:
            return v
        if isinstance(v, bool) or not isinstance(v, numbers.Integral):
            self.bad(key, f"must be an integer, got {_show(v)}")
            return None
        if ge is not None and v < ge:
            self.bad(key, f"must be >= {ge}, got {v}")
            return None
        return int(v)

    def string(self, key: str, default: Any = _REQUIRED,
               choices: Sequence[str] | None = None) -> str | None:
        v = self.raw(key, default)
        if v is None or key not in self.data:
            return v
        if not isinstance(v, str):
            self.bad(key, f"must be a string, got {_show(v)}")
            return None
        if choices is not None and v not in choices:
            self.bad(key, f"must be one of {', '.join(map(repr, choices))}, got {v!r}")
            return None
        return v

    def boolean(self, key: str, default: bool) -> bool | None:
        v = self.raw(key, default)
        if not isinstance(v, bool):
            self.bad(key, f"must be true or false, got {_show(v)}")
            return None
        return v

    def numbers(self, key: str, default: Any = _REQUIRED) -> tuple[float, ...] | None:
        v = self.raw(key, default)
        if v is None or key not in self.data:
            return v
        if (not isinstance(v, list) or not v or any(
                isinstance(a, bool) or not isinstance(a, numbers.Real) or not math.isfinite(a)
                for a in v)):
            self.bad(key, f"must be a non-empty list of numbers, got {_show(v)}")
            return None
        return tuple(float(a) for a in v)

    def table(self, key: str, allowed: Sequence[str], required: bool = False) -> _Table | None:
        if key not in self.data:
            if required:
                self.problems.append(f"[{self.name(key)}]: missing table (required)")
            return None
        return _Table(self.problems, self.name(key), self.data[key], allowed)

    def tables(self, key: str) -> list[Any]:
        v = self.data.get(key, [])
        if not isinstance(v, list) or not all(isinstance(e, Mapping) for e in v):
            self.problems.append(f"{self.name(key)}: must be a list of tables ([[{key}]])")
            return []
        return v


_ARCH_KEYS = ("kind", "span", "rise", "rings", "ring_thickness", "voussoirs", "stagger",
              "segments", "abutment_height", "abutment_width", "width", "mesh_size",
              "voussoir_material", "abutment_material")
_JOINT_KEYS = tuple(f.name for f in fields(JointMaterial))
_SAND_FORBIDDEN = ("ft", "GfI", "c", "GfII")
_LOADING_KEYS = ("position", "x", "spreader_width", "increment", "max_load", "self_weight",
                 "control", "displacement_increment", "max_displacement")
_DAMAGE_KEYS = {
    DamageKind.RING_SEPARATION: ("type", "rings", "from", "to"),
    DamageKind.DECAYED_MORTAR: ("type", "rings", "from", "to", "factor"),
    DamageKind.OPEN_JOINT: ("type", "ring", "index", "position"),
    DamageKind.MISSING_BRICK: ("type", "ring", "index"),
}
_ANALYSIS_KEYS = ("limit_analysis", "friction", "dr_rtol", "max_iterations", "output",
                  "refinements", "hinge_opening", "penalty_factor", "post_peak_steps",
                  "post_peak_drop", "follow_peak")
_ANCHOR_KEYS = ("layout", "angles", "cover", "start_angle", "end_angle", "depth", "pieces",
                "positions", "inclination", "length",
                "diameter", "count", "prestress", "plates", "bond_diameter", "segment", "name",
                "steel", "bond")
_STEEL_KEYS = tuple(f.name for f in fields(SteelLaw))


def _parse_arch(t: _Table) -> ArchSpec | None:
    kind = t.string("kind", "semicircular", [k.value for k in ArchKind])
    span = t.number("span", gt=0.0)
    rings = t.integer("rings", 1, ge=1)
    thick = t.number("ring_thickness", gt=0.0)
    counts: tuple[int, ...] | None = None
    v = t.raw("voussoirs", _REQUIRED)
    if v is not None:
        vals = v if isinstance(v, list) else [v]
        if not vals or any(isinstance(a, bool) or not isinstance(a, int) or a < 1 for a in vals):
            t.bad("voussoirs", f"must be an integer >= 1 or a list of them, got {_show(v)}")
        elif rings is not None and isinstance(v, list) and len(vals) != rings:
            t.bad("voussoirs", f"{len(vals)} values but the arch has {rings} rings")
        elif rings is not None:
            counts = tuple(vals) * (rings if len(vals) == 1 and not isinstance(v, list) else 1)
    rise = None
    if kind is not None and span is not None:
        if kind == "semicircular":
            r = t.number("rise", None, gt=0.0)
            if r is not None and abs(r - 0.5 * span) > 1e-9 * span:
                t.bad("rise", f"a semicircular arch has rise span/2 = {0.5 * span:g} m, got "
                      f"{r:g}; use kind = 'segmental' or 'pointed'")
        elif kind == "segmental":
            rise = t.number("rise", gt=0.0, lt=0.5 * span)
        else:
            rise = t.number("rise", gt=0.5 * span)
    stagger = t.number("stagger", 0.5, ge=0.0, lt=1.0)
    segments = t.integer("segments", 1, ge=1)
    ab_h = t.number("abutment_height", gt=0.0)
    ab_w = t.number("abutment_width", None, gt=0.0)
    width = t.number("width", 1.0, gt=0.0)
    mesh = t.number("mesh_size", None, gt=0.0)
    vmat = t.string("voussoir_material", "brick")
    amat = t.string("abutment_material", "abutment")
    values = (kind, span, rings, thick, counts, stagger, segments, ab_h, width, vmat, amat)
    if any(a is None for a in values) or (kind != "semicircular" and rise is None):
        return None
    spec = ArchSpec(ArchKind(kind), span, rise, rings, thick, counts, stagger, segments, ab_h,
                    ab_w, width, mesh if mesh is not None else 0.25 * thick, vmat, amat)
    try:
        arch_layout(**spec.layout_kwargs())
    except ValueError as e:
        t.problems.append(f"arch: {e}")
        return None
    return spec


def _parse_materials(root: _Table) -> dict[str, Material]:
    out = {}
    data = root.raw("materials", _REQUIRED)
    if data is None:
        return out
    if not isinstance(data, Mapping):
        root.bad("materials", "must be a table of [materials.<name>] tables")
        return out
    for name in data:
        t = _Table(root.problems, f"materials.{name}", data[name], ("density", "E", "nu"))
        rho, E = t.number("density", gt=0.0), t.number("E", gt=0.0)
        nu = t.number("nu", gt=-1.0, lt=0.5)
        if None not in (rho, E, nu):
            try:
                out[name] = Material(rho, E, nu)
            except ValueError as e:
                root.problems.append(f"materials.{name}: {e}")
    return out


def _joint_values(t: _Table, skip: Sequence[str] = ()) -> dict[str, float] | None:
    vals, ok = {}, True
    for key in _JOINT_KEYS:
        if key in t.data and key not in skip:
            vals[key] = t.number(key)
            ok &= vals[key] is not None
    return vals if ok else None


def _joint(t: _Table, vals: dict[str, float]) -> JointMaterial | None:
    try:
        jm = JointMaterial(**vals)
        if jm.kn is not None:
            jm.row(1.0, 0.0, 1.0)  # the snap-back checks, which need the stiffness
        return jm
    except ValueError as e:
        t.problems.append(f"{t.path}: {e}")
        return None


def _parse_joints(root: _Table):
    joints = root.table("joints", ("mortar", "ring"), required=True)
    if joints is None:
        return None, None, "bonded"
    mortar = ring = None
    mt = joints.table("mortar", _JOINT_KEYS, required=True)
    mvals = _joint_values(mt) if mt is not None else None
    if mvals is not None:
        mortar = _joint(mt, mvals)
    rt = joints.table("ring", ("type", *_JOINT_KEYS))
    if rt is None:
        return mortar, mortar, "bonded"
    kind = rt.string("type", "bonded", ("bonded", "sand"))
    if kind == "sand":
        for key in _SAND_FORBIDDEN:
            if key in rt.data:
                rt.bad(key, "a sand layer (type = 'sand') is friction only; remove the key "
                       "or use type = 'bonded'")
        if "tan_phi" not in rt.data:
            rt.bad("tan_phi", "missing (a sand layer needs its friction coefficient)")
        rvals = _joint_values(rt, skip=_SAND_FORBIDDEN)
        if rvals is not None:
            ring = _joint(rt, rvals)
    elif kind == "bonded":
        rvals = _joint_values(rt)
        if rvals is not None and mvals is not None and mortar is not None:
            ring = mortar if not rvals else _joint(rt, {**mvals, **rvals})
    return mortar, ring, kind


def _parse_loading(t: _Table, span: float | None) -> LoadingSpec | None:
    pos = None
    if "position" in t.data and "x" in t.data:
        t.problems.append(f"{t.path}: give position or x, not both")
    elif "x" in t.data:
        x = t.number("x")
        if x is not None and span is not None:
            if not 0.0 <= x <= span:
                t.bad("x", f"{x:g} m is off the arch (0..{span:g} m from the left springing)")
            else:
                pos = x / span
    else:
        pos = t.number("position", 0.25)
        if pos is not None and not 0.0 <= pos <= 1.0:
            t.bad("position", f"{pos:g} is off the arch (0..1 of the span)")
            pos = None
    spread = t.number("spreader_width", 0.0, ge=0.0)
    if None not in (pos, spread, span) and (
            pos - 0.5 * spread / span < -_S_TOL or pos + 0.5 * spread / span > 1 + _S_TOL):
        t.bad("spreader_width", f"a {spread:g} m spreader centred at {pos * span:g} m from "
              f"the left springing runs off the span (0..{span:g} m)")
    inc = t.number("increment", TONNE_FORCE, gt=0.0)
    max_load = t.number("max_load", None, gt=0.0)
    if None not in (inc, max_load) and max_load < inc:
        t.bad("max_load", f"{max_load:g} N is less than one increment ({inc:g} N)")
    weight = t.boolean("self_weight", True)
    control = t.string("control", "load", [c.value for c in LoadControl])
    dinc = t.number("displacement_increment",
                    _REQUIRED if control == "displacement" else None, gt=0.0)
    dmax = t.number("max_displacement", None, gt=0.0)
    if None in (pos, spread, inc, weight, control) or (control == "displacement" and not dinc):
        return None
    return LoadingSpec(pos, spread, inc, max_load, weight, LoadControl(control), dinc, dmax)


def _ring_index(t: _Table, key: str, rings: int | None) -> int | None:
    k = t.integer(key, ge=0)
    if k is not None and rings is not None and k >= rings:
        t.bad(key, f"{k} but the arch has {rings} rings (0..{rings - 1})")
        return None
    return k


def _ring_list(t: _Table, rings: int | None, pair: bool) -> tuple[int, ...] | None:
    v = t.raw("rings", "all")
    if v == "all":
        return None if rings is None else tuple(range(rings))
    if (not isinstance(v, list) or not v or (pair and len(v) != 2)
            or any(isinstance(a, bool) or not isinstance(a, int) for a in v)):
        want = "two ring indices [a, b]" if pair else "a list of ring indices"
        t.bad("rings", f"must be \"all\" or {want}, got {_show(v)}")
        return None
    bad = [a for a in v if a < 0 or (rings is not None and a >= rings)]
    if bad:
        t.bad("rings", f"{bad[0]} but the arch has {rings} rings (0..{(rings or 0) - 1})")
        return None
    if pair and v[0] == v[1]:
        t.bad("rings", f"needs two different rings, got {v}")
        return None
    return tuple(sorted(set(v)))


def _parse_damage(i: int, data: Any, problems: list[str], arch: ArchSpec | None,
                  rings: int | None):
    path = f"damage[{i}]"
    kind = data.get("type") if isinstance(data, Mapping) else None
    known = isinstance(kind, str) and kind in {k.value for k in DamageKind}
    allowed = _DAMAGE_KEYS[DamageKind(kind)] if known else tuple(
        {k: 0 for keys in _DAMAGE_KEYS.values() for k in keys})
    t = _Table(problems, path, data, allowed)
    if not t.string("type", choices=[k.value for k in DamageKind]):
        return None
    kind = DamageKind(kind)
    if kind in (DamageKind.RING_SEPARATION, DamageKind.DECAYED_MORTAR):
        if kind is DamageKind.RING_SEPARATION and rings is not None and rings < 2:
            problems.append(f"{path}: ring separation needs an arch with 2 or more rings")
            return None
        which = _ring_list(t, rings, pair=kind is DamageKind.RING_SEPARATION)
        a, b = t.number("from", 0.0, ge=0.0, le=1.0), t.number("to", 1.0, ge=0.0, le=1.0)
        if None not in (a, b) and not b > a:
            t.bad("to", f"must be > from ({a:g}), got {b:g}")
            return None
        factor = 1.0
        if kind is DamageKind.DECAYED_MORTAR:
            factor = t.number("factor", gt=0.0, le=1.0)
        if None in (which, a, b, factor, arch):
            return None
        return Damage(kind, which, a, b, factor)
    ring = _ring_index(t, "ring", rings)
    if kind is DamageKind.OPEN_JOINT and "position" in t.data:
        if "index" in t.data:
            problems.append(f"{path}: give index or position, not both")
            return None
        s = t.number("position", ge=0.0, le=1.0)
        if None in (ring, s, arch):
            return None
        return Damage(kind, ring=ring, index=int(np.argmin(abs(arch.joint_positions(ring) - s))))
    if "index" not in t.data and kind is DamageKind.OPEN_JOINT:
        t.bad("index", "missing (give index or position)")
        return None
    j = t.integer("index", ge=0)
    if None in (ring, j, arch):
        return None
    n = arch.blocks_in_ring(ring)
    if kind is DamageKind.MISSING_BRICK and j >= n:
        t.bad("index", f"{j} but ring {ring} has {n} voussoirs (0..{n - 1})")
        return None
    if kind is DamageKind.OPEN_JOINT and j > n:
        t.bad("index", f"{j} but ring {ring} has joints 0..{n} (0 and {n}: the springings)")
        return None
    return Damage(kind, ring=ring, index=j)


def _parse_anchor(i: int, data: Any, problems: list[str], arch: ArchSpec | None):
    path = f"anchors[{i}]"
    t = _Table(problems, path, data, _ANCHOR_KEYS)
    layout = t.string("layout", choices=("radial", "stitch", "inclined"))
    kw: dict[str, Any] = dict(
        diameter=t.number("diameter", gt=0.0), count=t.number("count", 1.0, gt=0.0),
        prestress=t.number("prestress", 0.0, ge=0.0),
        plates=t.string("plates", "none", ("none", "start", "end", "both")),
        bond_diameter=t.number("bond_diameter", None, gt=0.0),
        segment=t.number("segment", None, gt=0.0), name=t.string("name", f"anchor{i}"))
    if layout == "radial":
        kw.update(angles=t.numbers("angles"), cover=t.number("cover", 0.02, ge=0.0))
    elif layout == "stitch":
        kw.update(start_angle=t.number("start_angle"), end_angle=t.number("end_angle"),
                  depth=t.number("depth", gt=0.0), pieces=t.integer("pieces", None, ge=1))
    elif layout == "inclined":
        kw.update(positions=t.numbers("positions"),
                  inclination=t.number("inclination", 90.0, gt=0.0, lt=180.0),
                  length=t.number("length", None, gt=0.0), cover=t.number("cover", 0.02, ge=0.0))
    used = {"radial": ("angles", "cover"), "stitch": ("start_angle", "end_angle", "depth",
                                                      "pieces"),
            "inclined": ("positions", "inclination", "length", "cover")}
    for key in sorted({k for v in used.values() for k in v}):
        if layout in used and key in t.data and key not in used[layout]:
            t.bad(key, f"not used by layout = {layout!r}")
    steel, bond = _parse_steel_bond(t, problems, path)
    optional = ("bond_diameter", "segment", "pieces", "length")
    if layout is None or steel is None or bond is None or any(
            v is None for k, v in kw.items() if k not in optional):
        return None
    spec = AnchorSpec(layout, steel=steel, bond=bond, **kw)
    if arch is not None:
        try:
            spec.build(arch)
        except (ValueError, TypeError) as e:
            problems.append(f"{path}: {e}")
            return None
    return spec

_SEARCH_KEYS = ("positions", "counts", "inclinations", "lengths", "prestress", "layouts",
                "diameter", "bars", "cover", "min_spacing", "steel", "bond", "objective",
                "target", "keep", "keep_ratio", "coarse", "max_candidates")
_LAYOUT_KEYS = ("positions", "inclination", "length", "prestress")


def _parse_steel_bond(t: _Table, problems: list[str], path: str):
    steel = bond = None
    st = t.table("steel", _STEEL_KEYS)
    svals = {k: st.number(k) for k in _STEEL_KEYS if k in st.data} if st else {}
    if None not in svals.values():
        try:
            steel = SteelLaw(**svals)
        except ValueError as e:
            problems.append(f"{path}.steel: {e}")
    bt = t.table("bond", ("slip", "stress"))
    if bt is None:
        bond = Anchor.__dataclass_fields__["bond"].default_factory()
    else:
        slip, stress = bt.numbers("slip"), bt.numbers("stress")
        if None not in (slip, stress):
            try:
                bond = BondLaw(slip, stress)
            except ValueError as e:
                problems.append(f"{path}.bond: {e}")
    return steel, bond


def _parse_search(t: _Table, problems: list[str], arch: ArchSpec | None) -> SearchSpec | None:
    n0 = len(problems)

    def s_list(key):
        v = t.numbers(key, None)
        if v is not None and not all(-_S_TOL <= x <= 1 + _S_TOL for x in v):
            t.bad(key, f"every position must be in [0, 1] (s along the arch), got {list(v)}")
        return v

    positions = s_list("positions") or ()
    counts = t.raw("counts", [1])
    if not (isinstance(counts, list) and counts and all(
            isinstance(c, int) and not isinstance(c, bool) and c >= 1 for c in counts)):
        t.bad("counts", f"must be a non-empty list of integers >= 1, got {_show(counts)}")
        counts = [1]
    incl = t.numbers("inclinations", (90.0,)) or (90.0,)
    if not all(0.0 < a < 180.0 for a in incl):
        t.bad("inclinations", f"every angle must be in (0, 180) degrees, got {list(incl)}")
    lengths_raw = t.raw("lengths", ["through"])
    lengths: list[float | None] = []
    if not isinstance(lengths_raw, list) or not lengths_raw:
        t.bad("lengths", f"must be a non-empty list of lengths [m] or \"through\", got "
                         f"{_show(lengths_raw)}")
    else:
        for v in lengths_raw:
            if v == "through":
                lengths.append(None)
            elif isinstance(v, int | float) and not isinstance(v, bool) and v > 0 and \
                    math.isfinite(v):
                lengths.append(float(v))
            else:
                t.bad("lengths", f"every entry must be a length > 0 [m] or \"through\", "
                                 f"got {_show(v)}")
    prestress = t.numbers("prestress", (0.0,)) or (0.0,)
    if any(p < 0 for p in prestress):
        t.bad("prestress", f"forces must be >= 0 [N], got {list(prestress)}")
    layouts = []
    for i, d in enumerate(t.tables("layouts")):
        lt = _Table(problems, f"search.layouts[{i}]", d, _LAYOUT_KEYS)
        pos = lt.numbers("positions")
        inc = lt.number("inclination", 90.0, gt=0.0, lt=180.0)
        ell = lt.number("length", None, gt=0.0)
        pre = lt.number("prestress", 0.0, ge=0.0)
        if pos is not None and inc is not None and pre is not None:
            layouts.append(AnchorLayout(tuple(pos), inc, ell, pre))
    objective = t.string("objective", "gain_per_metre", [o.value for o in Objective])
    target = t.number("target", None, gt=0.0)
    if objective == "cheapest" and target is None and "target" not in t.data:
        t.bad("target", "required by objective = \"cheapest\" (the load to reach [N])")
    if not positions and not layouts:
        problems.append("search: give positions (and counts, ...) or [[search.layouts]]")
    steel, bond = _parse_steel_bond(t, problems, "search")
    kw = dict(diameter=t.number("diameter", 0.016, gt=0.0), bars=t.number("bars", 1.0, gt=0.0),
              cover=t.number("cover", 0.02, ge=0.0),
              min_spacing=t.number("min_spacing", 0.05, ge=0.0),
              keep=t.integer("keep", 4, ge=1), keep_ratio=t.number("keep_ratio", 0.5, ge=0.0,
                                                                   le=1.0),
              coarse=t.boolean("coarse", True),
              max_candidates=t.integer("max_candidates", 500, ge=1))
    if len(problems) > n0 or None in kw.values() or None in (steel, bond, objective):
        return None
    spec = SearchSpec(positions=tuple(positions), counts=tuple(counts),
                      inclinations=tuple(incl), lengths=tuple(lengths),
                      prestress=tuple(prestress), layouts=tuple(layouts), steel=steel,
                      bond=bond, objective=Objective(objective), target=target, **kw)
    n = len(spec.candidates())
    if n > spec.max_candidates:
        problems.append(f"search: {n} candidate layouts, more than max_candidates = "
                        f"{spec.max_candidates}; narrow the space or raise the limit")
        return None
    return spec



def _load_toml(path: Path) -> dict[str, Any]:
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as e:
        raise CaseError(f"cannot read the case file: {e.strerror or e}", str(path)) from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        msg = str(e)
        m = re.search(r"\(at line (\d+), column (\d+)\)", msg)
        where = f"line {m.group(1)}, column {m.group(2)}: " if m else ""
        msg = msg[:m.start()].strip() if m else msg
        raise CaseError(f"{where}TOML syntax error: {msg}", str(path)) from None


def load_case(source: str | Path | Mapping[str, Any], *, name: str | None = None) -> ArchCase:
    """Read and check a case; never writes anything.

    Args:
        source: path of a TOML case file, or a dict of the same shape.
        name: name of the case (default: the file stem, "case" for a dict); the default
            output folder is ``runs/<name>``.

    Returns:
        The validated case.

    Raises:
        CaseError: unreadable file, TOML syntax error (with its line), or every problem of
            the case, one per line.
    """
    if isinstance(source, Mapping):
        data, path, label = source, None, None
        name = name or "case"
    else:
        path = Path(source)
        data, label = _load_toml(path), str(path)
        name = name or path.stem
    problems: list[str] = []
    root = _Table(problems, "", data, ("arch", "materials", "joints", "loading", "damage",
                                       "analysis", "anchors", "search"))
    at = root.table("arch", _ARCH_KEYS, required=True)
    arch = _parse_arch(at) if at is not None else None
    mats = _parse_materials(root)
    if at is not None:
        for key, default in (("voussoir_material", "brick"), ("abutment_material", "abutment")):
            m = at.data.get(key, default)
            if isinstance(m, str) and isinstance(data.get("materials"), Mapping) and (
                    m not in data["materials"]):
                have = ", ".join(map(repr, data["materials"])) or "none"
                problems.append(f"materials: no material {m!r} (used by arch.{key}); "
                                f"the case defines {have}")
    mortar, ring, ring_type = _parse_joints(root)
    span = arch.span if arch else None
    if span is None and at is not None:  # a bad arch elsewhere still lets us check the load
        sv = at.data.get("span")
        span = float(sv) if isinstance(sv, int | float) and sv > 0 else None
    lt = root.table("loading", _LOADING_KEYS) or _Table(problems, "loading", {}, ())
    loading = _parse_loading(lt, span)
    rings = arch.rings if arch else None
    if rings is None and at is not None:  # a bad arch elsewhere still lets us check indices
        rv = at.data.get("rings", 1)
        rings = rv if isinstance(rv, int) and not isinstance(rv, bool) and rv >= 1 else None
    damage = [_parse_damage(i, d, problems, arch, rings)
              for i, d in enumerate(root.tables("damage"))]
    anchors = [_parse_anchor(i, a, problems, arch) for i, a in enumerate(root.tables("anchors"))]
    st = root.table("search", _SEARCH_KEYS)
    search = _parse_search(st, problems, arch) if st is not None else None
    an = root.table("analysis", _ANALYSIS_KEYS) or _Table(problems, "analysis", {}, ())
    analysis = AnalysisSpec(
        an.boolean("limit_analysis", True),
        an.number("friction", mortar.tan_phi if mortar else 0.6, ge=0.0),
        an.number("dr_rtol", 1e-6, gt=0.0),
        an.integer("max_iterations", 200_000, ge=1),
        Path(an.string("output", f"runs/{name}") or "."),
        an.integer("refinements", 4, ge=0),
        an.number("hinge_opening", 1e-5, gt=0.0),
        an.number("penalty_factor", 20.0, gt=0.0),
        an.integer("post_peak_steps", 3, ge=1),
        an.number("post_peak_drop", 0.2, gt=0.0),
        an.boolean("follow_peak", True))
    if analysis.post_peak_drop is not None and not analysis.post_peak_drop < 1.0:
        an.bad("post_peak_drop", f"must be < 1, got {analysis.post_peak_drop:g}")
    if not problems and None in (arch, mortar, ring, loading):
        problems.append("the case is incomplete")  # a check above forgot to say why
    if problems:
        raise CaseError(problems, label)
    case = ArchCase(name, arch, MappingProxyType(dict(mats)), mortar, ring, ring_type, loading,
                    tuple(damage), analysis, tuple(anchors), path, search)
    problems = [f"anchors: {p}" for p in case.anchor_problems()]
    if problems:
        raise CaseError(problems, label)
    return case


def prepare_run_folder(case: ArchCase, overwrite: bool = False, comm: Any | None = None) -> Path:
    """Create the output folder of a (validated) case.

    Args:
        case: the case; its folder is ``case.analysis.output``.
        overwrite: allow a folder that exists and is not empty (its files are kept and
            overwritten by the run as it writes them).
        comm: MPI communicator (collective): rank 0 creates the folder and every rank
            gets the same answer; None: this process alone.

    Returns:
        The folder.

    Raises:
        CaseError: the folder is not empty (and not ``overwrite``), or is a file, or
            cannot be created.
    """
    out = case.analysis.output
    error = None
    if comm is None or comm.rank == 0:
        if out.exists() and not out.is_dir():
            error = f"analysis.output: {out} exists and is not a folder"
        elif out.is_dir() and any(out.iterdir()) and not overwrite:
            error = (f"analysis.output: the folder {out} exists and is not empty; choose "
                     "another output or overwrite it")
        else:
            try:
                out.mkdir(parents=True, exist_ok=True)
            except OSError as e:
                error = f"analysis.output: cannot create {out}: {e.strerror or e}"
    if comm is not None:
        error = comm.bcast(error, root=0)
    if error:
        raise CaseError(error, str(case.source) if case.source else None)
    return out


REPAIR_EXAMPLE = _repair_example()
