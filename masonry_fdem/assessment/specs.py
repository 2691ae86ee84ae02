"""The parts of an arch case (:class:`ArchCase`): arch, loading, damage, analysis,
anchors and layout search specs, each frozen and checked by :mod:`.parse`. Units SI."""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace
from enum import StrEnum
from pathlib import Path
from typing import Any

import numpy as np

from masonry_fdem import checks
from masonry_fdem.assessment.layouts import inclined_anchors, intrados_stitch, radial_anchors
from masonry_fdem.constants import G
from masonry_fdem.geometry.arches import ArchKind, arch_layout, arch_parameter, ring_pieces
from masonry_fdem.geometry.layout import BlockLayout
from masonry_fdem.geometry.planar import inside_any, on_segments, polyline_distance
from masonry_fdem.interactions.anchors import Anchor, BondLaw, JointDowel, SteelLaw
from masonry_fdem.interactions.joints import JointMaterial
from masonry_fdem.materials.elastic import Material

__all__ = ["TONNE_FORCE", "AnalysisSpec", "AnchorLayout", "AnchorSpec", "ArchCase", "ArchSpec",
           "CaseError", "Damage", "DamageKind", "LoadControl", "LoadingSpec", "Objective",
           "SearchSpec", "S_TOL", "DiskFillSpec", "FillSpec", "SPREADER", "classify_interface",
           "top_of", "joint_or_contact"]

#: One tonne-force [N].
TONNE_FORCE = 1000.0 * G

REQUIRED = object()
S_TOL = 1e-9

#: The loading beam on the road of a case with fill: a steel plate [m thick], its material.
SPREADER = ("spreader", 0.05, Material(density=7850.0, E=210e9, nu=0.3))


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


#: default share of Rankine's passive pressure of the fill that the limit analysis may
#: mobilise against an arch swaying into it: full passive pressure needs a wall movement of
#: a few percent of its height, far more than an arch sways before it collapses, so
#: analysts of arches with RING's fill model take a fraction of it; here a third (set it
#: per case; 0 leaves the passive resistance out).
PASSIVE_MOBILISATION = 0.33


@dataclass(frozen=True)
class DiskFillSpec:
    """``[fill.disks]``: the fill as disks (``[fill] model = "disks"``), loaded to collapse
    by explicit dynamics (:class:`~masonry_fdem.assessment.disk_fill.DiskFillBridge`).
    ``count`` disks asked of the packer; ``porosity`` of the packing (the disks' solid
    density is the fill material's density / (1 − porosity)); the disks' ``E`` [Pa],
    ``nu``, ``friction``, ``rolling_friction``, ``restitution``; Cundall's
    ``local_damping``; the packing's ``seed``; ``tol`` of the unbalanced-force ratios that
    define an equilibrium; ``max_steps`` explicit steps per load (and per stage of the
    settling under self-weight, of which there are three); ``runaway`` [m], the travel of
    a voussoir under one constant load that proves it has no equilibrium (default: a
    quarter of the ring thickness); ``surfacing`` [m], a road
    layer of ``surfacing_material`` over the disks, within the cover (0: none);
    ``cell`` [m], the width of the cells over which the report averages the disks'
    stress."""

    count: int = 5600
    porosity: float = 0.2
    E: float = 1e8
    nu: float = 0.25
    friction: float = 0.5
    rolling_friction: float = 0.3
    restitution: float = 0.5
    local_damping: float = 0.7
    seed: int = 1
    tol: float = 1e-3
    max_steps: int = 600_000
    runaway: float | None = None
    surfacing: float = 0.0
    surfacing_material: str | None = None
    cell: float = 0.2


@dataclass(frozen=True)
class FillSpec:
    """``[fill]``: a backfill over the arch — a Mohr–Coulomb continuum, or disks with
    ``model = "disks"`` (``disks``: :class:`DiskFillSpec`) — up to a road
    ``cover`` [m] above the crown's extrados, retained at its ends by two fixed walls on
    the abutments' outer faces (:func:`~masonry_fdem.geometry.fill.fill_layout`); always
    in plane strain. It touches the extrados, the abutments, the walls and the loading
    beam through a friction-only interface (``interface_friction`` = tan δ, normal
    stiffness ``interface_stiffness`` [Pa/m], shear stiffness kn/2.6) that opens freely.
    ``mesh_size`` [m] of its triangles; ``crossed``: mesh it with crossed triangles
    (quadrilaterals split by their diagonals, which do not lock in isochoric plastic flow;
    :func:`~masonry_fdem.geometry.meshing.mesh_blocks`) instead of a general
    triangulation; ``wall_thickness`` [m]. In the limit analysis
    (:meth:`ArchCase.limit_analysis`) the fill is RING's: its weight, the load's 2:1
    dispersion, and a horizontal passive resistance of up to ``passive_mobilisation``
    times Rankine's passive pressure on the extrados; ``incline_loads``: the loads on
    chords steeper than the interface's friction angle lean uphill by the excess
    (:func:`~masonry_fdem.geometry.fill.fill_loads`). ``backing`` [m]: the haunches'
    backing, masonry of the abutments' material up to that height above the springing
    under the fill (``backing:<i>``, fixed with the abutments; its interface with the ring
    a mortar joint, with the fill the fill's interface); 0: none."""

    cover: float
    material: str
    interface_friction: float
    interface_stiffness: float
    mesh_size: float
    wall_thickness: float = 0.3
    passive_mobilisation: float = PASSIVE_MOBILISATION
    crossed: bool = False
    incline_loads: bool = False
    #: "continuum" (Mohr–Coulomb, solved with the case's solver) or "disks" (``disks``)
    model: str = "continuum"
    disks: DiskFillSpec | None = None
    backing: float = 0.0

    def interface(self) -> JointMaterial:
        """The fill's interface as a friction-only joint material."""
        k = self.interface_stiffness
        with checks.expert():  # checked in the case file (with its [checks] allow)
            return JointMaterial(kn=k, ks=k / 2.6, tan_phi=self.interface_friction)


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
    hinge_opening: float = 1e-4
    penalty_factor: float = 20.0
    post_peak_steps: int = 3
    post_peak_drop: float = 0.2
    follow_peak: bool = True
    solver: str = "newton"
    newton_rtol: float = 1e-6
    newton_iterations: int = 25
    newton_steps: int = 400
    paraview_every: int = 10
    softening: str = "implicit"
    through_layers: bool = False

    def contact_settings(self, **kw):
        """The block contact's settings from this table (friction, penalty factor,
        contact through joint layers); ``kw`` adds others (``friction_table``)."""
        from masonry_fdem.interactions import ContactSettings

        return ContactSettings(friction=self.friction, penalty_factor=self.penalty_factor,
                               through_layers=self.through_layers, **kw)


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
    shear: JointDowel | None = None

    def build(self, arch: ArchSpec) -> list[Anchor]:
        """The anchors in ``arch``.

        Raises:
            ValueError: an angle outside the arch, a non-circular arch, bad anchor data.
        """
        kw = dict(diameter=self.diameter, steel=self.steel, bond=self.bond, count=self.count,
                  prestress=self.prestress, plates=self.plates,
                  bond_diameter=self.bond_diameter, segment=self.segment, name=self.name,
                  shear=self.shear)
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
    :func:`masonry_fdem.assessment.search.search`). Lengths [m], angles [deg], forces [N].

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
    fill: FillSpec | None = None

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
        out = BlockLayout(tuple(polys), layout.materials, layout.names)
        if self.fill is None:
            return out
        return out + self.fill_layout(out)

    def fill_layout(self, structure: BlockLayout | None = None) -> BlockLayout:
        """The fill, its two end walls and the loading beam on the road (``spreader``,
        a steel plate as wide as ``loading.spreader_width``) of a case with ``[fill]``."""
        from masonry_fdem.geometry.fill import fill_layout

        if self.fill is None:
            raise ValueError("the case has no [fill]")
        structure = self.layout() if structure is None else structure
        x, half = self.load_x(), 0.5 * self.loading.spreader_width
        f = self.fill
        fl = fill_layout(structure, cover=f.cover, wall_thickness=f.wall_thickness,
                         road_points=(x - half, x + half), material=f.material,
                         wall_material=self.arch.abutment_material, backing=f.backing)
        road = self.road_level()
        name, t, _ = SPREADER
        beam = np.array([[x - half, road], [x + half, road], [x + half, road + t],
                         [x, road + t], [x - half, road + t]])
        return fl + BlockLayout((beam,), (name,), (name,))

    def road_level(self) -> float:
        """y [m] of the road over the fill (``[fill]`` cases)."""
        from masonry_fdem.geometry.fill import crown_height

        crown = crown_height(self.layout())
        return crown + self.fill.cover

    def materials(self) -> dict[str, Material]:
        """Block material name -> :class:`~masonry_fdem.materials.Material` (with fill:
        the loading beam's steel as ``spreader``)."""
        out = dict(self.material_table)
        if self.fill is not None:
            out[SPREADER[0]] = SPREADER[2]
        return out

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
            bad = ~inside_any(polys, pts, tol)
            if bad.any():
                x, y = pts[int(np.argmax(bad))]
                out.append(f"{label} leaves the structure at ({x:.3f}, {y:.3f}) m: "
                           "that point is in no block of the arch or its abutments")
        if min_spacing is not None:
            for i in range(len(anchors)):
                for j in range(i + 1, len(anchors)):
                    d = polyline_distance(anchors[i].points, anchors[j].points)
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
        return x, top_of(self.layout(), x)

    def load_points(self) -> np.ndarray:
        """``(k, 2)`` points [m] where the load is applied, each taking an equal share:
        without fill, where the spreader bears on the extrados (its two ends; the load
        point if there is no spreader); with fill, the middle of the loading beam's top
        (the beam bears on the road)."""
        if self.fill is not None:
            return np.array([[self.load_x(), self.road_level() + SPREADER[1]]])
        return self.extrados_load_points()

    def load_blocks(self) -> str:
        """The blocks the load points bear on (``voussoir:*``, or the loading beam)."""
        return "voussoir:*" if self.fill is None else SPREADER[0]

    def extrados_load_points(self) -> np.ndarray:
        """``(k, 2)`` points [m] where the spreader would bear on the bare extrados: its
        two ends (the load point if there is no spreader)."""
        half = 0.5 * self.loading.spreader_width
        if half == 0.0:
            return np.array([self.load_point()])
        layout, x = self.layout(), self.load_x()
        return np.array([[xs, top_of(layout, xs)] for xs in (x - half, x + half)])

    def joint_materials(self) -> dict[tuple[str, str], JointMaterial]:
        """Joint material per pair of block materials (the mortar) for
        :class:`~masonry_fdem.interactions.joints.joints.Joints`; see :meth:`joint_rules` for the rest."""
        v, a = self.arch.voussoir_material, self.arch.abutment_material
        out = {(v, v): self.mortar, (v, a): self.mortar}
        if self.fill is not None:
            f, jf = self.fill.material, self.fill.interface()
            out.update({(v, f): jf, (a, f): jf, (f, SPREADER[0]): jf, (a, a): None})
        return out

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
            where = classify_interface(layout.names[itf.block_a[i]], layout.names[itf.block_b[i]],
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
        return [(on_segments(itf.start[idx], itf.end[idx], tol), mat)
                for mat, idx in groups.values()]

    def _joint_state(self, where: tuple[str, int, int], mid: np.ndarray):
        kind, k, j = where
        s = (self.arch.joint_positions(k)[j] if kind == "joint"
             else arch_parameter(self.arch.kind, self.arch.span, self.arch.rise, mid))
        factor = 1.0
        for d in self.damage:
            inside = d.start - S_TOL <= s <= d.end + S_TOL
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
        with checks.expert():  # a decayed mortar may be weaker than any fresh one
            return replace(base, ft=base.ft * factor, c=base.c * factor,
                           fc=None if base.fc is None else base.fc * factor)

    def limit_analysis(self, passive: bool = True, incline: bool | None = None, **kw: Any):
        """Rigid-block collapse load of the case by
        :func:`~masonry_fdem.solvers.limit_analysis.limit_analysis`: the live load is 1 N shared by
        :meth:`extrados_load_points`, so the load factor is the collapse load [N]. With
        ``[fill]``, the fill enters as loads (:func:`~masonry_fdem.geometry.fill.fill_loads`):
        its weight over the extrados, the live load dispersed 2:1 down to the extrados, and
        its passive resistance to a ring that sways into it, up to ``passive_mobilisation``
        times Rankine's (:func:`~masonry_fdem.geometry.fill.fill_passive`; the fill's
        cohesion included). ``passive=False`` leaves the passive resistance out.
        ``incline`` (default ``[fill] incline_loads``, false): the fill's loads on chords of
        the extrados steeper than its interface friction angle δ lean uphill by the excess
        (the fill's traction can lean at most δ from the extrados' normal; RING takes them
        vertical). With ``[fill] backing`` the backing is a support like the abutments,
        and the fill's loads and passive resistance act on the extrados above it and on
        its top. Keywords override the arguments (e.g. ``friction``)."""
        from masonry_fdem.solvers.limit_analysis import limit_analysis

        pts = self.extrados_load_points()
        live = [((p[0], p[1]), (0.0, -1.0 / len(pts))) for p in pts]
        dead, bounded = [], []
        layout, supports = self.layout(), "abutment:*"
        if self.fill is not None and self.fill.backing > 0.0:
            fl = self.fill_layout(layout)
            keep = [i for i, n in enumerate(fl.names) if n.startswith("backing:")]
            if keep:  # (none where the level lies below the abutments' tops)
                layout = layout + BlockLayout(tuple(fl.polygons[i] for i in keep),
                                              tuple(fl.materials[i] for i in keep),
                                              tuple(fl.names[i] for i in keep))
                supports = ["abutment:*", "backing:*"]
        if self.fill is not None:
            # the fill as RING models it on a rigid ring: its weight over each chord of the
            # extrados, the load dispersed 2:1, a passive resistance up to m K_p σ_v
            from masonry_fdem.geometry.fill import fill_loads

            rho = self.material_table[self.fill.material].density
            lean = self.fill.incline_loads if incline is None else incline
            dead, live = fill_loads(
                layout, road=self.road_level(), unit_weight=rho * G * self.arch.width,
                patch=(self.load_x(), self.loading.spreader_width),
                interface_friction=self.fill.interface_friction if lean else None)
            if not self.loading.self_weight:
                dead = []
            fm = self.material_table[self.fill.material]
            if passive and self.fill.passive_mobilisation > 0.0 and self.loading.self_weight:
                from masonry_fdem.geometry.fill import fill_passive

                bounded = fill_passive(
                    layout, road=self.road_level(), unit_weight=rho * G * self.arch.width,
                    phi=fm.phi, cohesion=fm.c, width=self.arch.width,
                    mobilisation=self.fill.passive_mobilisation)
        args = dict(
            density={n: m.density for n, m in self.material_table.items()},
            width=self.arch.width, supports=supports,
            live_loads=live, dead_loads=dead, bounded_loads=bounded,
            friction=self.analysis.friction, g=G if self.loading.self_weight else 0.0,
            max_load_factor=self.loading.max_load or 1e9)
        args.update(kw)
        return limit_analysis(layout, **args)


# ---------------------------------------------------------------------- geometry helpers
def top_of(layout: BlockLayout, x: float) -> float:
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


def joint_or_contact(jm: JointMaterial | None) -> JointMaterial | None:
    """A joint material for :class:`~masonry_fdem.interactions.joints.joints.Joints`: kept
    if it is bonded or has its own stiffness, else None (a dry joint, left to the block
    contact)."""
    return jm if jm is not None and (jm.bonded or jm.kn is not None) else None


def classify_interface(na: str, nb: str, arch: ArchSpec) -> tuple[str, int, int] | None:
    """("joint", ring, joint index) or ("ring", upper ring, -1) of the interface of two
    blocks; None between abutments."""
    pa, pb = na.split(":"), nb.split(":")
    if pa[0] == "abutment":
        pa, pb = pb, pa
    if pa[0] != "voussoir" or pb[0] not in ("voussoir", "abutment"):
        return None
    ka, ja = int(pa[1]), int(pa[2])
    if pb[0] == "abutment":
        return ("joint", ka, 0 if pb[1] == "left" else arch.blocks_in_ring(ka))
    kb, jb = int(pb[1]), int(pb[2])
    if ka == kb:
        return ("joint", ka, max(ja, jb))
    return ("ring", max(ka, kb), -1)
