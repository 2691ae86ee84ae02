"""Parsing and checking an arch case file (TOML or a dict of the same shape) into an
:class:`~masonry_fdem.assessment.specs.ArchCase`; see :mod:`masonry_fdem.assessment.case`
for the schema."""

from __future__ import annotations

import math
import re
import tomllib
from collections.abc import Mapping, Sequence
from dataclasses import fields
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np

from masonry_fdem.assessment.specs import S_TOL, TONNE_FORCE, AnalysisSpec, AnchorLayout, AnchorSpec
from masonry_fdem.assessment.specs import ArchCase, ArchSpec, CaseError, Damage, DamageKind
from masonry_fdem.assessment.specs import PASSIVE_MOBILISATION, FillSpec, LoadControl, LoadingSpec
from masonry_fdem.assessment.specs import Objective, SearchSpec
from masonry_fdem.assessment.tables import REQUIRED, Table, show
from masonry_fdem.geometry.arches import ArchKind, arch_layout
from masonry_fdem.interactions.anchors import Anchor, BondLaw, SteelLaw
from masonry_fdem.interactions.joints import JointMaterial
from masonry_fdem.materials.elastic import Material
from masonry_fdem.materials.plasticity import MohrCoulomb

__all__ = ["load_case"]

_ARCH_KEYS = ("kind", "span", "rise", "rings", "ring_thickness", "voussoirs", "stagger",
              "segments", "abutment_height", "abutment_width", "width", "mesh_size",
              "voussoir_material", "abutment_material")
_JOINT_KEYS = tuple(f.name for f in fields(JointMaterial))
_COULOMB_KEYS = ("c", "phi", "psi")
_FILL_KEYS = ("cover", "material", "interface_friction", "interface_stiffness", "mesh_size",
              "wall_thickness", "passive_mobilisation")
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
                  "post_peak_drop", "follow_peak", "solver", "newton_rtol",
                  "newton_iterations", "newton_steps")
_ANCHOR_KEYS = ("layout", "angles", "cover", "start_angle", "end_angle", "depth", "pieces",
                "positions", "inclination", "length",
                "diameter", "count", "prestress", "plates", "bond_diameter", "segment", "name",
                "steel", "bond")
_STEEL_KEYS = tuple(f.name for f in fields(SteelLaw))


def _parse_arch(t: Table) -> ArchSpec | None:
    kind = t.string("kind", "semicircular", [k.value for k in ArchKind])
    span = t.number("span", gt=0.0)
    rings = t.integer("rings", 1, ge=1)
    thick = t.number("ring_thickness", gt=0.0)
    counts: tuple[int, ...] | None = None
    v = t.raw("voussoirs", REQUIRED)
    if v is not None:
        vals = v if isinstance(v, list) else [v]
        if not vals or any(isinstance(a, bool) or not isinstance(a, int) or a < 1 for a in vals):
            t.bad("voussoirs", f"must be an integer >= 1 or a list of them, got {show(v)}")
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


def _parse_materials(root: Table) -> dict[str, Material]:
    out = {}
    data = root.raw("materials", REQUIRED)
    if data is None:
        return out
    if not isinstance(data, Mapping):
        root.bad("materials", "must be a table of [materials.<name>] tables")
        return out
    for name in data:
        t = Table(root.problems, f"materials.{name}", data[name],
                  ("density", "E", "nu", *_COULOMB_KEYS))
        rho, E = t.number("density", gt=0.0), t.number("E", gt=0.0)
        nu = t.number("nu", gt=-1.0, lt=0.5)
        coulomb = any(k in t.data for k in _COULOMB_KEYS)
        if coulomb:
            # a Mohr–Coulomb soil (the fill): c [Pa], phi, psi [degrees]
            c = t.number("c", 0.0, ge=0.0)
            phi = t.number("phi", ge=0.0, lt=90.0)
            psi = t.number("psi", 0.0, ge=0.0, lt=90.0)
            if None in (c, phi, psi):
                continue
            if psi > phi:
                t.bad("psi", f"the dilatancy angle {psi:g} exceeds the friction angle {phi:g}")
                continue
        if None not in (rho, E, nu):
            try:
                out[name] = (MohrCoulomb(density=rho, E=E, nu=nu, c=c, phi=phi, psi=psi)
                             if coulomb else Material(rho, E, nu))
            except ValueError as e:
                root.problems.append(f"materials.{name}: {e}")
    return out


def _parse_fill(t: Table, mats: Mapping[str, Material], arch: ArchSpec | None,
                data: Mapping[str, Any]) -> FillSpec | None:
    cover = t.number("cover", gt=0.0)
    mat = t.string("material", "fill")
    if mat is not None and mat not in data.get("materials", {}):
        t.bad("material", f"no [materials.{mat}] in the case")
        mat = None
    elif mat is not None and arch is not None and mat in (arch.voussoir_material,
                                                          arch.abutment_material):
        t.bad("material", f"{mat!r} is the arch's own material; give the fill its own")
        mat = None
    elif mat is not None and mat in mats and not isinstance(mats[mat], MohrCoulomb):
        t.bad("material", f"[materials.{mat}] is elastic: a fill needs c, phi (and psi) "
              "for its Mohr–Coulomb strength")
        mat = None
    fm = mats.get(mat) if mat is not None else None
    # default interface friction: tan(2/3 phi) of the fill (a rough wall; Potyondy 1961)
    mu0 = math.tan(math.radians(2.0 / 3.0 * fm.phi)) if isinstance(fm, MohrCoulomb) else 0.5
    mu = t.number("interface_friction", mu0, ge=0.0)
    # default interface stiffness: 20 E_fill / mesh size (stiff beside the fill's own
    # compliance, like the default penalty of the contact)
    size = t.number("mesh_size", None, gt=0.0)
    if size is None and arch is not None:
        size = 2.0 * arch.mesh_size
    kn0 = 20.0 * fm.E / size if fm is not None and size else None
    kn = t.number("interface_stiffness", kn0, gt=0.0)
    wall = t.number("wall_thickness", 0.3, gt=0.0)
    # the part of the passive pressure the limit analysis may mobilise (RING's fill model)
    passive = t.number("passive_mobilisation", PASSIVE_MOBILISATION, ge=0.0, le=1.0)
    if None in (cover, mat, mu, kn, size, wall, passive):
        return None
    spec = FillSpec(cover, mat, mu, kn, size, wall, passive)
    return spec


def _joint_values(t: Table, skip: Sequence[str] = ()) -> dict[str, float] | None:
    vals, ok = {}, True
    for key in _JOINT_KEYS:
        if key in t.data and key not in skip:
            vals[key] = t.number(key)
            ok &= vals[key] is not None
    return vals if ok else None


def _joint(t: Table, vals: dict[str, float]) -> JointMaterial | None:
    try:
        jm = JointMaterial(**vals)
        if jm.kn is not None:
            jm.row(1.0, 0.0, 1.0)  # the snap-back checks, which need the stiffness
        return jm
    except ValueError as e:
        t.problems.append(f"{t.path}: {e}")
        return None


def _parse_joints(root: Table):
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


def _parse_loading(t: Table, span: float | None) -> LoadingSpec | None:
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
            # (issue #24: the two conventions named in the message)
            t.bad("position", f"{pos:g} is off the arch (0..1 of the span): loading.position "
                  "is a fraction of the span, horizontally from the left springing (unlike "
                  "the positions s along the arch of [[damage]] and [[anchors]])")
            pos = None
    spread = t.number("spreader_width", 0.0, ge=0.0)
    if None not in (pos, spread, span) and (
            pos - 0.5 * spread / span < -S_TOL or pos + 0.5 * spread / span > 1 + S_TOL):
        t.bad("spreader_width", f"a {spread:g} m spreader centred at {pos * span:g} m from "
              f"the left springing runs off the span (0..{span:g} m)")
    inc = t.number("increment", TONNE_FORCE, gt=0.0)
    max_load = t.number("max_load", None, gt=0.0)
    if None not in (inc, max_load) and max_load < inc:
        t.bad("max_load", f"{max_load:g} N is less than one increment ({inc:g} N)")
    weight = t.boolean("self_weight", True)
    control = t.string("control", "load", [c.value for c in LoadControl])
    dinc = t.number("displacement_increment",
                    REQUIRED if control == "displacement" else None, gt=0.0)
    dmax = t.number("max_displacement", None, gt=0.0)
    if None in (pos, spread, inc, weight, control) or (control == "displacement" and not dinc):
        return None
    return LoadingSpec(pos, spread, inc, max_load, weight, LoadControl(control), dinc, dmax)


def _ring_index(t: Table, key: str, rings: int | None) -> int | None:
    k = t.integer(key, ge=0)
    if k is not None and rings is not None and k >= rings:
        t.bad(key, f"{k} but the arch has {rings} rings (0..{rings - 1})")
        return None
    return k


def _ring_list(t: Table, rings: int | None, pair: bool) -> tuple[int, ...] | None:
    v = t.raw("rings", "all")
    if v == "all":
        return None if rings is None else tuple(range(rings))
    if (not isinstance(v, list) or not v or (pair and len(v) != 2)
            or any(isinstance(a, bool) or not isinstance(a, int) for a in v)):
        want = "two ring indices [a, b]" if pair else "a list of ring indices"
        t.bad("rings", f"must be \"all\" or {want}, got {show(v)}")
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
    t = Table(problems, path, data, allowed)
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
            t.bad("to", f"must be > from ({a:g}), got {b:g} (from and to are positions s "
                  "along the arch: 0 left springing, 0.5 crown, 1 right springing; not "
                  "fractions of the span)")
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
    t = Table(problems, path, data, _ANCHOR_KEYS)
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


def _parse_steel_bond(t: Table, problems: list[str], path: str):
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


def _parse_search(t: Table, problems: list[str]) -> SearchSpec | None:
    n0 = len(problems)

    def s_list(key):
        v = t.numbers(key, None)
        if v is not None and not all(-S_TOL <= x <= 1 + S_TOL for x in v):
            t.bad(key, f"every position must be in [0, 1] (s along the arch), got {list(v)}")
        return v

    positions = s_list("positions") or ()
    counts = t.raw("counts", [1])
    if not (isinstance(counts, list) and counts and all(
            isinstance(c, int) and not isinstance(c, bool) and c >= 1 for c in counts)):
        t.bad("counts", f"must be a non-empty list of integers >= 1, got {show(counts)}")
        counts = [1]
    incl = t.numbers("inclinations", (90.0,)) or (90.0,)
    if not all(0.0 < a < 180.0 for a in incl):
        t.bad("inclinations", f"every angle must be in (0, 180) degrees, got {list(incl)}")
    lengths_raw = t.raw("lengths", ["through"])
    lengths: list[float | None] = []
    if not isinstance(lengths_raw, list) or not lengths_raw:
        t.bad("lengths", f"must be a non-empty list of lengths [m] or \"through\", got "
                         f"{show(lengths_raw)}")
    else:
        for v in lengths_raw:
            if v == "through":
                lengths.append(None)
            elif isinstance(v, int | float) and not isinstance(v, bool) and v > 0 and \
                    math.isfinite(v):
                lengths.append(float(v))
            else:
                t.bad("lengths", f"every entry must be a length > 0 [m] or \"through\", "
                                 f"got {show(v)}")
    prestress = t.numbers("prestress", (0.0,)) or (0.0,)
    if any(p < 0 for p in prestress):
        t.bad("prestress", f"forces must be >= 0 [N], got {list(prestress)}")
    layouts = []
    for i, d in enumerate(t.tables("layouts")):
        lt = Table(problems, f"search.layouts[{i}]", d, _LAYOUT_KEYS)
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
    root = Table(problems, "", data, ("arch", "materials", "joints", "loading", "damage",
                                       "analysis", "anchors", "search", "fill"))
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
    lt = root.table("loading", _LOADING_KEYS) or Table(problems, "loading", {}, ())
    loading = _parse_loading(lt, span)
    rings = arch.rings if arch else None
    if rings is None and at is not None:  # a bad arch elsewhere still lets us check indices
        rv = at.data.get("rings", 1)
        rings = rv if isinstance(rv, int) and not isinstance(rv, bool) and rv >= 1 else None
    damage = [_parse_damage(i, d, problems, arch, rings)
              for i, d in enumerate(root.tables("damage"))]
    anchors = [_parse_anchor(i, a, problems, arch) for i, a in enumerate(root.tables("anchors"))]
    st = root.table("search", _SEARCH_KEYS)
    search = _parse_search(st, problems) if st is not None else None
    ft = root.table("fill", _FILL_KEYS)
    fill = _parse_fill(ft, mats, arch, data) if ft is not None else None
    if ft is not None and fill is not None and loading is not None and not (
            loading.spreader_width > 0):
        ft.problems.append("loading: a load on the fill needs a loading beam "
                           "(spreader_width > 0): a point load would punch into the soil")
    an = root.table("analysis", _ANALYSIS_KEYS) or Table(problems, "analysis", {}, ())
    analysis = AnalysisSpec(
        an.boolean("limit_analysis", True),
        an.number("friction", mortar.tan_phi if mortar else 0.6, ge=0.0),
        an.number("dr_rtol", 1e-6, gt=0.0),
        an.integer("max_iterations", 200_000, ge=1),
        Path(an.string("output", f"runs/{name}") or "."),
        an.integer("refinements", 4, ge=0),
        an.number("hinge_opening", 1e-4, gt=0.0),
        an.number("penalty_factor", 20.0, gt=0.0),
        an.integer("post_peak_steps", 3, ge=1),
        an.number("post_peak_drop", 0.2, gt=0.0),
        an.boolean("follow_peak", True),
        an.string("solver", "newton", ["newton", "dr"]),
        an.number("newton_rtol", 1e-6, gt=0.0),
        an.integer("newton_iterations", 25, ge=1),
        an.integer("newton_steps", 400, ge=1))
    if analysis.post_peak_drop is not None and not analysis.post_peak_drop < 1.0:
        an.bad("post_peak_drop", f"must be < 1, got {analysis.post_peak_drop:g}")
    if not problems and None in (arch, mortar, ring, loading):
        problems.append("the case is incomplete")  # a check above forgot to say why
    if problems:
        raise CaseError(problems, label)
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
