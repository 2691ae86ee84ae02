"""Parsing and checking an arch case file (TOML or a dict of the same shape) into an
:class:`~masonry_fdem.assessment.specs.ArchCase`; see :mod:`masonry_fdem.assessment.case`
for the schema.

Each table is checked by its pydantic model (:mod:`.schema`: types, bounds, required and
unknown keys, units) and by the magnitude checks (:data:`masonry_fdem.checks.PLAUSIBLE`,
switched off per key by ``[checks] allow``); what is left here are the rules between
keys and tables (a rise that fits the kind of arch, damage naming existing rings, a load
on the span, the mesh size against the ring thickness, the load against the arch's
self-weight). Every problem is collected and raised together in one
:class:`~masonry_fdem.assessment.specs.CaseError`, one line each, naming its key.
"""

from __future__ import annotations

import math
import re
import tomllib
from collections.abc import Mapping
from dataclasses import fields
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np

from masonry_fdem import checks
from masonry_fdem.assessment import schema as S
from masonry_fdem.assessment.schema import show, validate
from masonry_fdem.assessment.specs import (
    PASSIVE_MOBILISATION,
    S_TOL,
    TONNE_FORCE,
    AnalysisSpec,
    AnchorLayout,
    AnchorSpec,
    ArchCase,
    ArchSpec,
    CaseError,
    Damage,
    DamageKind,
    DiskFillSpec,
    FillSpec,
    LoadControl,
    LoadingSpec,
    Objective,
    SearchSpec,
)
from masonry_fdem.constants import G
from masonry_fdem.geometry.arches import ArchKind, arch_layout
from masonry_fdem.interactions.anchors import Anchor, BondLaw, JointDowel, SteelLaw
from masonry_fdem.interactions.joints import JointMaterial
from masonry_fdem.materials.elastic import Material
from masonry_fdem.materials.plasticity import MohrCoulomb

__all__ = ["load_case", "parse_joint", "parse_materials"]

_JOINT_KEYS = tuple(f.name for f in fields(JointMaterial))
_SAND_FORBIDDEN = ("ft", "GfI", "c", "GfII")
#: plausible ratios (low, high): mesh size / ring thickness, load increment and maximum
#: load / the arch's self-weight, displacement increment / span
MESH_RATIO = (0.01, 2.0)
INCREMENT_RATIO = (1e-3, 2.0)
MAX_LOAD_RATIO = (1e-2, 100.0)
DISPLACEMENT_RATIO = (1e-8, 0.05)


def _allow_hint(key: str) -> str:
    return f'[checks] allow = ["{key}"]'


class _Ctx:
    """The problems found so far and the ``[checks] allow`` list."""

    def __init__(self, allow: tuple[str, ...] = ()):
        self.problems: list[str] = []
        self.allow = allow
        self.implausible: set[str] = set()  # tables with implausible magnitudes

    def table(self, model, data, path):
        """``data`` validated by ``model`` and its magnitudes checked (None if invalid)."""
        obj = validate(model, data, path, self.problems)
        implausible = S.magnitude_problems(obj, path, self.allow)
        self.problems += implausible
        self.implausible |= {path} if implausible else set()
        return obj

    def ratio(self, key, value, ref, bounds, unit, ref_text):
        msg = checks.ratio_problem(key, value, ref, *bounds, unit, ref_text,
                                   allow=self.allow, allow_hint=_allow_hint(key))
        if msg:
            self.problems.append(msg)


# ---------------------------------------------------------------------- tables
def _parse_arch(m: S.ArchModel, ctx: _Ctx) -> ArchSpec | None:
    bad = ctx.problems.append
    ok = True
    v = m.voussoirs
    if isinstance(v, list) and len(v) != m.rings:
        bad(f"arch.voussoirs: {len(v)} values but the arch has {m.rings} rings")
        ok = False
    counts = tuple(v) if isinstance(v, list) else (v,) * m.rings
    rise = None
    if m.kind == "semicircular":
        if m.rise is not None and abs(m.rise - 0.5 * m.span) > 1e-9 * m.span:
            bad(f"arch.rise: a semicircular arch has rise span/2 = {0.5 * m.span:g} m, got "
                f"{m.rise:g}; use kind = 'segmental' or 'pointed'")
            ok = False
    elif m.rise is None:
        bad(f"arch.rise: missing (required by kind = {m.kind!r})")
        ok = False
    elif m.kind == "segmental" and not m.rise < 0.5 * m.span:
        bad(f"arch.rise: must be < {0.5 * m.span:g} (span/2) for a segmental arch, got "
            f"{m.rise:g} [m]")
        ok = False
    elif m.kind == "pointed" and not m.rise > 0.5 * m.span:
        bad(f"arch.rise: must be > {0.5 * m.span:g} (span/2) for a pointed arch, got "
            f"{m.rise:g} [m]")
        ok = False
    else:
        rise = m.rise
    mesh = m.mesh_size if m.mesh_size is not None else 0.25 * m.ring_thickness
    if m.mesh_size is not None:
        ctx.ratio("arch.mesh_size", m.mesh_size, m.ring_thickness, MESH_RATIO, "m",
                  "the ring thickness")
    if not ok or "arch" in ctx.implausible:  # an arch in mm: its geometry says nothing more
        return None
    spec = ArchSpec(ArchKind(m.kind), m.span, rise, m.rings, m.ring_thickness, counts,
                    m.stagger, m.segments, m.abutment_height, m.abutment_width, m.width,
                    mesh, m.voussoir_material, m.abutment_material)
    try:
        with checks.expert():  # the magnitudes were checked above, with [checks] allow
            arch_layout(**spec.layout_kwargs())
    except ValueError as e:
        bad(f"arch: {e}")
        return None
    return spec


def parse_materials(data: Any, ctx: _Ctx) -> dict[str, Material]:
    """``[materials.<name>]`` tables -> Material (Mohr–Coulomb with ``phi``)."""
    out: dict[str, Material] = {}
    if not isinstance(data, Mapping):
        ctx.problems.append("materials: must be a table of [materials.<name>] tables")
        return out
    for name, table in data.items():
        path = f"materials.{name}"
        m = ctx.table(S.MaterialModel, table, path)
        if m is None:
            continue
        coulomb = {"c", "phi", "psi"} & m.given()
        if coulomb and m.phi is None:
            ctx.problems.append(f"{path}.phi: missing (required by a Mohr–Coulomb material "
                                f"with {', '.join(sorted(coulomb))})")
            continue
        psi, c = m.psi or 0.0, m.c or 0.0
        if coulomb and psi > m.phi:
            ctx.problems.append(f"{path}.psi: the dilatancy angle {psi:g} exceeds the "
                                f"friction angle {m.phi:g}")
            continue
        try:
            with checks.expert():  # magnitudes: checked by ctx.table, with [checks] allow
                out[name] = (MohrCoulomb(density=m.density, E=m.E, nu=m.nu, c=c, phi=m.phi,
                                         psi=psi) if coulomb else Material(m.density, m.E, m.nu))
        except ValueError as e:
            ctx.problems.append(f"{path}: {e}")
    return out


def _joint(path: str, vals: dict[str, float], ctx: _Ctx) -> JointMaterial | None:
    ft, fc = vals.get("ft", 0.0), vals.get("fc")
    if fc is not None and not ft < fc and not {f"{path}.ft", "*"} & set(ctx.allow):
        ctx.problems.append(f"{path}.ft = {ft:g} Pa is not below fc = {fc:g} Pa: a "
                            "tensile strength is a small fraction of the compressive one "
                            f"(if you mean it: {_allow_hint(path + '.ft')})")
        return None
    try:
        with checks.expert():  # magnitudes: checked by the schema, with [checks] allow
            jm = JointMaterial(**vals)
        if jm.kn is not None:
            jm.row(1.0, 0.0, 1.0)  # the snap-back checks, which need the stiffness
    except ValueError as e:
        ctx.problems.append(f"{path}: {e}")
        return None
    return jm


def parse_joint(data: Any, path: str, ctx: _Ctx) -> JointMaterial | None:
    """A ``[joints.mortar]``-like table -> JointMaterial (None, with problems, if bad)."""
    m = ctx.table(S.JointModel, data, path)
    return _joint(path, m.values(), ctx) if m is not None else None


def _parse_joints(data: Any, ctx: _Ctx):
    bad = ctx.problems.append
    if not isinstance(data, Mapping):
        bad(f"joints: must be a table, got {show(data)}")
        return None, None, "bonded"
    for key in data:
        if key not in ("mortar", "ring"):
            bad(f"unknown key {key!r} in [joints] (expected one of mortar, ring)")
    if "mortar" not in data:
        bad("[joints.mortar]: missing table (required)")
        mm = None
    else:
        mm = ctx.table(S.JointModel, data["mortar"], "joints.mortar")
    mortar = _joint("joints.mortar", mm.values(), ctx) if mm is not None else None
    if "ring" not in data:
        return mortar, mortar, "bonded"
    rm = ctx.table(S.RingJointModel, data["ring"], "joints.ring")
    if rm is None:
        return mortar, None, "bonded"
    rvals = rm.values()
    if rm.type == "sand":
        forbidden = [k for k in _SAND_FORBIDDEN if k in rvals]
        for key in forbidden:
            bad(f"joints.ring.{key}: a sand layer (type = 'sand') is friction only; remove "
                "the key or use type = 'bonded'")
        if rm.tan_phi is None:
            bad("joints.ring.tan_phi: missing (a sand layer needs its friction coefficient)")
        if forbidden or rm.tan_phi is None:
            return mortar, None, "sand"
        return mortar, _joint("joints.ring", rvals, ctx), "sand"
    if mm is None or mortar is None:
        return mortar, None, "bonded"
    ring = mortar if not rvals else _joint("joints.ring", {**mm.values(), **rvals}, ctx)
    return mortar, ring, "bonded"


def _parse_fill(m: S.FillModel, mats: Mapping[str, Material], arch: ArchSpec | None,
                data: Mapping[str, Any], ctx: _Ctx) -> FillSpec | None:
    bad = ctx.problems.append
    mat = m.material
    materials = data.get("materials") if isinstance(data.get("materials"), Mapping) else {}
    if mat not in materials:
        bad(f"fill.material: no [materials.{mat}] in the case")
        return None
    if arch is not None and mat in (arch.voussoir_material, arch.abutment_material):
        bad(f"fill.material: {mat!r} is the arch's own material; give the fill its own")
        return None
    if mat in mats and not isinstance(mats[mat], MohrCoulomb):
        bad(f"fill.material: [materials.{mat}] is elastic: a fill needs c, phi (and psi) "
            "for its Mohr–Coulomb strength")
        return None
    fm = mats.get(mat)
    if fm is None:
        return None
    # default interface friction: tan(2/3 phi) of the fill (a rough wall; Potyondy 1961)
    mu = (m.interface_friction if m.interface_friction is not None
          else math.tan(math.radians(2.0 / 3.0 * fm.phi)))
    size = m.mesh_size if m.mesh_size is not None else (
        2.0 * arch.mesh_size if arch is not None else None)
    if size is None:
        return None
    # default interface stiffness: 20 E_fill / mesh size (stiff beside the fill's own
    # compliance, like the default penalty of the contact)
    kn = m.interface_stiffness if m.interface_stiffness is not None else 20.0 * fm.E / size
    passive = (m.passive_mobilisation if m.passive_mobilisation is not None
               else PASSIVE_MOBILISATION)
    disks = None
    if m.model == "disks":
        d = m.disks if m.disks is not None else S.DiskFillModel()
        if d.surfacing >= m.cover:
            bad(f"fill.disks.surfacing: {d.surfacing:g} m must be thinner than the cover "
                f"{m.cover:g} m")
        if d.surfacing > 0 and d.surfacing_material is None:
            bad("fill.disks.surfacing: a road layer needs its surfacing_material (the name of "
                "a [materials] table)")
        if d.surfacing_material is not None:
            if d.surfacing_material not in materials:
                bad(f"fill.disks.surfacing_material: no [materials.{d.surfacing_material}] in "
                    "the case")
            elif d.surfacing == 0:
                bad("fill.disks.surfacing_material: given, but fill.disks.surfacing is 0 "
                    "(no road layer)")
        disks = DiskFillSpec(**{k: getattr(d, k) for k in S.DiskFillModel.model_fields})
    elif m.disks is not None:
        bad('fill.disks: given, but fill.model is "continuum" (set model = "disks" to pack '
            "the fill with disks)")
    if m.backing > 0.0 and m.model == "disks":
        bad("fill.backing: not with a disk fill (the disks are packed over the bare "
            "extrados); use the continuum fill, or backing = 0")
    return FillSpec(m.cover, mat, mu, kn, size, m.wall_thickness, passive, m.crossed,
                    m.incline_loads, m.model, disks, m.backing)


def _parse_loading(m: S.LoadingModel, span: float | None, ctx: _Ctx) -> LoadingSpec | None:
    bad = ctx.problems.append
    pos = None
    if m.position is not None and m.x is not None:
        bad("loading: give position or x, not both")
    elif m.x is not None:
        if span is not None:
            if not 0.0 <= m.x <= span:
                bad(f"loading.x: {m.x:g} m is off the arch (0..{span:g} m from the left "
                    "springing)")
            else:
                pos = m.x / span
    else:
        pos = 0.25 if m.position is None else m.position
        if not 0.0 <= pos <= 1.0:
            # (the two conventions named in the message)
            bad(f"loading.position: {pos:g} is off the arch (0..1 of the span): "
                "loading.position is a fraction of the span, horizontally from the left "
                "springing (unlike the positions s along the arch of [[damage]] and "
                "[[anchors]])")
            pos = None
    spread = m.spreader_width
    if None not in (pos, span) and (pos - 0.5 * spread / span < -S_TOL
                                    or pos + 0.5 * spread / span > 1 + S_TOL):
        bad(f"loading.spreader_width: a {spread:g} m spreader centred at {pos * span:g} m "
            f"from the left springing runs off the span (0..{span:g} m)")
    inc = m.increment if m.increment is not None else TONNE_FORCE
    if m.max_load is not None and m.max_load < inc:
        bad(f"loading.max_load: {m.max_load:g} N is less than one increment ({inc:g} N)")
    if m.control == "displacement" and m.displacement_increment is None:
        bad("loading.displacement_increment: missing (required by control = "
            "'displacement')")
        return None
    if pos is None:
        return None
    return LoadingSpec(pos, spread, inc, m.max_load, m.self_weight, LoadControl(m.control),
                       m.displacement_increment, m.max_displacement)


def _ring_list(path: str, v: Any, rings: int | None, pair: bool, ctx: _Ctx):
    bad = ctx.problems.append
    if v == "all":
        return None if rings is None else tuple(range(rings))
    if (not isinstance(v, list) or not v or (pair and len(v) != 2)
            or any(isinstance(a, bool) or not isinstance(a, int) for a in v)):
        want = "two ring indices [a, b]" if pair else "a list of ring indices"
        bad(f"{path}.rings: must be \"all\" or {want}, got {show(v)}")
        return None
    out_of = [a for a in v if a < 0 or (rings is not None and a >= rings)]
    if out_of:
        bad(f"{path}.rings: {out_of[0]} but the arch has {rings} rings (0..{(rings or 0) - 1})")
        return None
    if pair and v[0] == v[1]:
        bad(f"{path}.rings: needs two different rings, got {v}")
        return None
    return tuple(sorted(set(v)))


def _parse_damage(i: int, data: Any, arch: ArchSpec | None, rings: int | None, ctx: _Ctx):
    path = f"damage[{i}]"
    bad = ctx.problems.append
    kind = data.get("type") if isinstance(data, Mapping) else None
    if kind not in S.DAMAGE_MODELS:
        known = ", ".join(map(repr, S.DAMAGE_MODELS))
        bad(f"{path}.type: must be one of {known}, got {show(kind)}" if kind is not None
            else f"{path}.type: missing (required: one of {known})")
        return None
    m = ctx.table(S.DAMAGE_MODELS[kind], data, path)
    if m is None:
        return None
    kind = DamageKind(kind)
    if kind in (DamageKind.RING_SEPARATION, DamageKind.DECAYED_MORTAR):
        if kind is DamageKind.RING_SEPARATION and rings is not None and rings < 2:
            bad(f"{path}: ring separation needs an arch with 2 or more rings")
            return None
        which = _ring_list(path, m.rings, rings, kind is DamageKind.RING_SEPARATION, ctx)
        if not m.end > m.start:
            bad(f"{path}.to: must be > from ({m.start:g}), got {m.end:g} (from and to are "
                "positions s along the arch: 0 left springing, 0.5 crown, 1 right "
                "springing; not fractions of the span)")
            return None
        if which is None or arch is None:
            return None
        return Damage(kind, which, m.start, m.end, getattr(m, "factor", 1.0))
    if rings is not None and m.ring >= rings:
        bad(f"{path}.ring: {m.ring} but the arch has {rings} rings (0..{rings - 1})")
        return None
    if kind is DamageKind.OPEN_JOINT and m.position is not None:
        if m.index is not None:
            bad(f"{path}: give index or position, not both")
            return None
        if arch is None:
            return None
        s = m.position
        return Damage(kind, ring=m.ring,
                      index=int(np.argmin(abs(arch.joint_positions(m.ring) - s))))
    if m.index is None:
        bad(f"{path}.index: missing (give index or position)")
        return None
    if arch is None:
        return None
    n, j = arch.blocks_in_ring(m.ring), m.index
    if kind is DamageKind.MISSING_BRICK and j >= n:
        bad(f"{path}.index: {j} but ring {m.ring} has {n} voussoirs (0..{n - 1})")
        return None
    if kind is DamageKind.OPEN_JOINT and j > n:
        bad(f"{path}.index: {j} but ring {m.ring} has joints 0..{n} (0 and {n}: the "
            "springings)")
        return None
    return Damage(kind, ring=m.ring, index=j)


def _steel_bond(m, path: str, ctx: _Ctx):
    steel = bond = None
    try:
        steel = SteelLaw(**m.steel.values())
    except ValueError as e:
        ctx.problems.append(f"{path}.steel: {e}")
    if m.bond is None:
        bond = Anchor.__dataclass_fields__["bond"].default_factory()
    else:
        try:
            bond = BondLaw(tuple(m.bond.slip), tuple(m.bond.stress))
        except ValueError as e:
            ctx.problems.append(f"{path}.bond: {e}")
    return steel, bond


_USED = {"radial": ("angles", "cover"), "stitch": ("start_angle", "end_angle", "depth",
                                                   "pieces"),
         "inclined": ("positions", "inclination", "length", "cover")}


def _parse_anchor(i: int, data: Any, arch: ArchSpec | None, ctx: _Ctx):
    path = f"anchors[{i}]"
    m = ctx.table(S.AnchorModel, data, path)
    if m is None:
        return None
    n0 = len(ctx.problems)
    given = m.given()
    for key in sorted({k for v in _USED.values() for k in v}):
        if key in given and key not in _USED[m.layout]:
            ctx.problems.append(f"{path}.{key}: not used by layout = {m.layout!r}")
    need = {"radial": ("angles",), "stitch": ("start_angle", "end_angle", "depth"),
            "inclined": ("positions",)}[m.layout]
    for key in need:
        if getattr(m, key) is None:
            ctx.problems.append(f"{path}.{key}: missing (required by layout = {m.layout!r})")
    steel, bond = _steel_bond(m, path, ctx)
    shear = None
    if m.shear is not None and steel is not None:
        sm, sgiven = m.shear, m.shear.given()
        if (sm.fc is None) == (sm.stiffness is None):
            ctx.problems.append(f"{path}.shear: give fc (the bedding's compressive strength: "
                                "the dowel from the bar) or stiffness and strength, not both")
        elif sm.fc is not None:
            if "strength" in sgiven:
                ctx.problems.append(f"{path}.shear.strength: computed from the bar with fc; "
                                    "give stiffness and strength without fc instead")
            else:
                shear = JointDowel.from_bar(m.diameter, steel.E, steel.yield_stress, sm.fc,
                                            c1=sm.c1, c0=sm.c0)
        else:
            for key in ("c1", "c0"):
                if key in sgiven:
                    ctx.problems.append(f"{path}.shear.{key}: used only with fc")
            shear = JointDowel(sm.stiffness, math.inf if sm.strength is None else sm.strength)
    if len(ctx.problems) > n0:
        return None
    kw: dict[str, Any] = dict(diameter=m.diameter, count=m.count, prestress=m.prestress,
                              plates=m.plates, bond_diameter=m.bond_diameter,
                              segment=m.segment, name=m.name or f"anchor{i}", shear=shear)
    if m.layout == "radial":
        kw.update(angles=tuple(m.angles), cover=m.cover)
    elif m.layout == "stitch":
        kw.update(start_angle=m.start_angle, end_angle=m.end_angle, depth=m.depth,
                  pieces=m.pieces)
    else:
        kw.update(positions=tuple(m.positions), inclination=m.inclination, length=m.length,
                  cover=m.cover)
    spec = AnchorSpec(m.layout, steel=steel, bond=bond, **kw)
    if arch is not None:
        try:
            spec.build(arch)
        except (ValueError, TypeError) as e:
            ctx.problems.append(f"{path}: {e}")
            return None
    return spec


def _parse_search(m: S.SearchModel, ctx: _Ctx) -> SearchSpec | None:
    n0 = len(ctx.problems)
    bad = ctx.problems.append
    if m.objective == "cheapest" and m.target is None:
        bad('search.target: required by objective = "cheapest" (the load to reach [N])')
    if not m.positions and not m.layouts:
        bad("search: give positions (and counts, ...) or [[search.layouts]]")
    steel, bond = _steel_bond(m, "search", ctx)
    if len(ctx.problems) > n0:
        return None
    layouts = tuple(AnchorLayout(tuple(lt.positions), lt.inclination, lt.length, lt.prestress)
                    for lt in m.layouts)
    spec = SearchSpec(positions=tuple(m.positions or ()), counts=tuple(m.counts),
                      inclinations=tuple(m.inclinations),
                      lengths=tuple(None if v == "through" else float(v) for v in m.lengths),
                      prestress=tuple(m.prestress), layouts=layouts, steel=steel, bond=bond,
                      objective=Objective(m.objective), target=m.target, diameter=m.diameter,
                      bars=m.bars, cover=m.cover, min_spacing=m.min_spacing, keep=m.keep,
                      keep_ratio=m.keep_ratio, coarse=m.coarse,
                      max_candidates=m.max_candidates)
    n = len(spec.candidates())
    if n > spec.max_candidates:
        bad(f"search: {n} candidate layouts, more than max_candidates = "
            f"{spec.max_candidates}; narrow the space or raise the limit")
        return None
    return spec


def _self_weight(arch: ArchSpec, mats: Mapping[str, Material]) -> float | None:
    """Weight [N] of the arch's voussoirs (abutments aside), None if unknown."""
    mat = mats.get(arch.voussoir_material)
    if mat is None:
        return None
    with checks.expert():
        layout = arch_layout(**arch.layout_kwargs())
    area = sum(abs(_area(p)) for p, n in zip(layout.polygons, layout.names, strict=True)
               if n.startswith("voussoir:"))
    return abs(area) * mat.density * G * arch.width


def _area(p: np.ndarray) -> float:
    x, y = p[:, 0], p[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


def _magnitudes_against_structure(arch: ArchSpec | None, mats: Mapping[str, Material],
                                  lm: S.LoadingModel | None, ctx: _Ctx) -> None:
    """Loads against the self-weight, displacements against the span."""
    if arch is None or lm is None:
        return
    weight = _self_weight(arch, mats)
    if weight:
        what = "the arch's self-weight"
        if lm.increment is not None:
            ctx.ratio("loading.increment", lm.increment, weight, INCREMENT_RATIO, "N", what)
        if lm.max_load is not None:
            ctx.ratio("loading.max_load", lm.max_load, weight, MAX_LOAD_RATIO, "N", what)
    if lm.displacement_increment is not None:
        ctx.ratio("loading.displacement_increment", lm.displacement_increment, arch.span,
                  DISPLACEMENT_RATIO, "m", "the span")
    if lm.max_displacement is not None:
        ctx.ratio("loading.max_displacement", lm.max_displacement, arch.span, (1e-6, 1.0),
                  "m", "the span")


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


def checks_allow(data: Any, problems: list[str]) -> tuple[str, ...]:
    """The ``[checks] allow`` list of a case (keys whose magnitude checks are off)."""
    if not isinstance(data, Mapping) or "checks" not in data:
        return ()
    m = validate(S.ChecksModel, data["checks"], "checks", problems)
    return tuple(m.allow) if m is not None else ()


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
            the case, one per line: a bad type or range, an unknown or missing key, an
            implausible magnitude (``[checks] allow`` lets an expert keep it), a rule
            between keys.
    """
    if isinstance(source, Mapping):
        data, path, label = source, None, None
        name = name or "case"
    else:
        path = Path(source)
        data, label = _load_toml(path), str(path)
        name = name or path.stem
    ctx = _Ctx()
    ctx.allow = checks_allow(data, ctx.problems)
    validate(S.RootModel, data, "", ctx.problems)  # the tables there are, their types
    data = data if isinstance(data, Mapping) else {}

    def table(key):  # a table given as one (else None: the root's check said why)
        v = data.get(key)
        return v if isinstance(v, Mapping) else None

    def tables(key):  # an array of tables
        v = data.get(key, [])
        return [e for e in v if isinstance(e, Mapping)] if isinstance(v, list) else []

    am = ctx.table(S.ArchModel, table("arch"), "arch") if table("arch") is not None else None
    arch = _parse_arch(am, ctx) if am is not None else None
    mats = parse_materials(table("materials"), ctx) if table("materials") is not None else {}
    materials = data.get("materials")
    if am is not None and isinstance(materials, Mapping):
        for key in ("voussoir_material", "abutment_material"):
            m = getattr(am, key)
            if m not in materials:
                have = ", ".join(map(repr, materials)) or "none"
                ctx.problems.append(f"materials: no material {m!r} (used by arch.{key}); "
                                    f"the case defines {have}")
    mortar, ring, ring_type = (_parse_joints(table("joints"), ctx) if table("joints")
                               is not None else (None, None, "bonded"))
    span = arch.span if arch else (am.span if am is not None else None)
    if span is None and isinstance(data.get("arch"), Mapping):  # a bad arch elsewhere
        sv = data["arch"].get("span")
        span = float(sv) if isinstance(sv, int | float) and sv > 0 else None
    lm = ctx.table(S.LoadingModel, table("loading") or {}, "loading")
    loading = _parse_loading(lm, span, ctx) if lm is not None else None
    rings = arch.rings if arch else (am.rings if am is not None else None)
    if rings is None and isinstance(data.get("arch"), Mapping):
        rv = data["arch"].get("rings", 1)
        rings = rv if isinstance(rv, int) and not isinstance(rv, bool) and rv >= 1 else None
    damage = [_parse_damage(i, d, arch, rings, ctx) for i, d in enumerate(tables("damage"))]
    anchors = [_parse_anchor(i, a, arch, ctx) for i, a in enumerate(tables("anchors"))]
    search = None
    if table("search") is not None:
        sm = ctx.table(S.SearchModel, table("search"), "search")
        search = _parse_search(sm, ctx) if sm is not None else None
    fill = None
    if table("fill") is not None:
        fmod = ctx.table(S.FillModel, table("fill"), "fill")
        fill = _parse_fill(fmod, mats, arch, data, ctx) if fmod is not None else None
        if fill is not None and loading is not None and not loading.spreader_width > 0:
            ctx.problems.append("loading: a load on the fill needs a loading beam "
                                "(spreader_width > 0): a point load would punch into the soil")
        if fill is not None and fill.model == "disks":
            bad = ctx.problems.append
            if loading is not None and loading.control is not LoadControl.LOAD:
                bad('loading.control: a disk fill is loaded in load steps, each held to '
                    'equilibrium (control = "load"), not under displacement control')
            if loading is not None and not loading.self_weight:
                bad("loading.self_weight: a disk fill settles under its weight: it cannot "
                    "be switched off")
            if anchors:
                bad("anchors: not modelled with a disk fill (the continuum fill has them)")
            if search is not None:
                bad("search: a layout search runs anchors, which a disk fill does not model")
            for key in ("mesh_size", "interface_stiffness", "crossed"):
                if key in fmod.given():
                    bad(f"fill.{key}: an option of the continuum fill; a disk fill has none "
                        "(remove it, or see [fill.disks])")
    an = ctx.table(S.AnalysisModel, table("analysis") or {}, "analysis")
    analysis = None
    if an is not None:
        analysis = AnalysisSpec(
            an.limit_analysis,
            an.friction if an.friction is not None else (mortar.tan_phi if mortar else 0.6),
            an.dr_rtol, an.max_iterations, Path(an.output or f"runs/{name}"), an.refinements,
            an.hinge_opening, an.penalty_factor, an.post_peak_steps, an.post_peak_drop,
            an.follow_peak, an.solver, an.newton_rtol, an.newton_iterations, an.newton_steps,
            an.paraview_every, an.softening, an.through_layers)
    _magnitudes_against_structure(arch, mats, lm, ctx)
    problems = ctx.problems
    if not problems and None in (arch, mortar, ring, loading, analysis):
        problems.append("the case is incomplete")  # a check above forgot to say why
    if problems:
        raise CaseError(list(dict.fromkeys(problems)), label)  # each line once
    case = ArchCase(name, arch, MappingProxyType(dict(mats)), mortar, ring, ring_type, loading,
                    tuple(damage), analysis, tuple(anchors), path, search, fill)
    if fill is not None:
        try:
            case.fill_layout()
        except ValueError as e:
            raise CaseError([f"fill: {e}"], label) from None
    problems = [f"anchors: {p}" for p in case.anchor_problems()]
    if problems:
        raise CaseError(problems, label)
    return case
