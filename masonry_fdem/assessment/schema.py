"""The typed schema of the case files: one pydantic model per TOML table.

Why pydantic (2): the case files were checked by hand, key by key (``Table.number(key,
gt=0.0)`` and its kin: ``tables.py``, ``parse.py`` and the bridge's loader, some 850
lines). Every table of a case is a flat record of typed, bounded fields; a declarative
model says that in one line per key, and pydantic (widely used, actively maintained, with
a compiled core and wheels on PyPI for every platform the project runs on) checks types,
bounds, required and unknown keys of a whole table at once and reports *every* error
with its location (``loc``), which is what a case file needs: all problems together,
each naming its key. Strict mode keeps TOML's types honest (``span = "3 m"`` and
``rings = 2.5`` are refused, ``true`` is no number, NaN and inf are refused).
Alternatives weighed: ``attrs``/``cattrs`` (structuring, but neither bounds nor the
collection of every error with its path), ``marshmallow`` (schemas apart from the
types, untyped results), JSON Schema with ``jsonschema`` (errors name JSON pointers, no
Python objects out, units would need a custom keyword anyway), keeping the hand-written
checker (every new key costs a line of checking code, and nothing carries a unit). The
cost: one dependency (``pydantic>=2``, with ``pydantic-core``), imported only by the case
file readers.

What the schema adds to pydantic (this module):

* :class:`Meta` on each number: its SI unit and, for the magnitude checks, the kind of
  quantity in :data:`masonry_fdem.checks.PLAUSIBLE` (the one place that says what is
  plausible: the API checks ``Material``, ``JointMaterial`` and ``arch_layout`` with the
  same table);
* :func:`validate`: one table against its model, every pydantic error turned into one line
  ``table.key: must be > 0, got -0.1 [m]`` (unknown keys with the closest known key);
* :func:`magnitude_problems`: after validation, each number with a kind outside its
  plausible range gives ``arch.span = 4000 m is implausible for ...: expected 0.2 to 100
  m; did you give millimetres? (if you mean it: [checks] allow = ["arch.span"])``.

The models cover the arch case files (:mod:`.parse`) and the bridge case files
(:mod:`.bridge_case`). The rules between keys and tables (a rise that fits the kind of
arch, damage naming existing rings, a load on the span, the mesh size against the ring
thickness, loads against the self-weight, ...) stay in those modules, on the validated
models. Units: SI (m, Pa, kg/m³, N, N/m, Pa/m, degrees for angles).
"""

import difflib
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Annotated, Any, Literal, Union, get_args

from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator

from masonry_fdem.checks import magnitude_problem

__all__ = ["AnalysisModel", "AnchorModel", "ArchModel", "BondModel", "ChecksModel",
           "DAMAGE_MODELS", "FillModel", "JointModel", "LoadingModel", "MaterialModel",
           "Meta", "RingJointModel", "RootModel", "SearchModel", "SteelModel",
           "magnitude_problems", "show", "validate"]


@dataclass(frozen=True)
class Meta:
    """Unit [SI] of a field and the kind of quantity of its magnitude check (None: none)."""

    unit: str = ""
    kind: str | None = None


def num(unit: str = "", kind: str | None = None, *, optional: bool = False, **bounds: float):
    """A strict, finite float field with bounds (gt, ge, lt, le), a unit and a kind."""
    inner = Annotated[float, Field(**bounds)] if bounds else float
    return Annotated[Union[inner, None] if optional else inner, Meta(unit, kind)]  # noqa: UP007


def integer(*, optional: bool = False, **bounds: int):
    inner = Annotated[int, Field(**bounds)] if bounds else int
    return Union[inner, None] if optional else inner  # noqa: UP007


def numbers(unit: str = "", *, optional: bool = False, **bounds: float):
    """A non-empty list of finite floats, each within the bounds."""
    item = Annotated[float, Field(**bounds)] if bounds else float
    inner = Annotated[list[item], Field(min_length=1)]
    return Annotated[Union[inner, None] if optional else inner, Meta(unit)]  # noqa: UP007


class _Table(BaseModel):
    model_config = ConfigDict(extra="forbid", strict=True, allow_inf_nan=False, frozen=True,
                              populate_by_name=True)

    def given(self) -> set[str]:
        """The keys the file gave (by their TOML names)."""
        out = set()
        for name in self.model_fields_set:
            f = type(self).model_fields[name]
            out.add(f.alias or name)
        return out


# ---------------------------------------------------------------------- the tables
class RootModel(_Table):
    """The case file's top level: which tables there are (each checked by its own model)."""

    arch: dict[str, Any]
    materials: dict[str, Any]
    joints: dict[str, Any]
    loading: dict[str, Any] = {}
    damage: list[dict[str, Any]] = []
    analysis: dict[str, Any] = {}
    anchors: list[dict[str, Any]] = []
    search: dict[str, Any] | None = None
    fill: dict[str, Any] | None = None
    checks: dict[str, Any] = {}


class ChecksModel(_Table):
    """``[checks]``: ``allow``, the keys (``"arch.span"``, ``"materials.brick.E"``; ``"*"``
    for all) whose magnitude checks an expert switches off."""

    allow: list[str] = []


class ArchModel(_Table):
    """``[arch]`` (see :mod:`masonry_fdem.assessment.case`)."""

    kind: Literal["semicircular", "segmental", "pointed"] = "semicircular"
    span: num("m", "span", gt=0.0)
    rise: num("m", "rise", optional=True, gt=0.0) = None
    rings: integer(ge=1) = 1
    ring_thickness: num("m", "ring_thickness", gt=0.0)
    voussoirs: Any
    stagger: num("", ge=0.0, lt=1.0) = 0.5
    segments: integer(ge=1) = 1
    abutment_height: num("m", "length", gt=0.0)
    abutment_width: num("m", "length", optional=True, gt=0.0) = None
    width: num("m", "width", gt=0.0) = 1.0
    mesh_size: num("m", optional=True, gt=0.0) = None
    voussoir_material: str = "brick"
    abutment_material: str = "abutment"

    @field_validator("voussoirs", mode="before")
    @classmethod
    def _voussoirs(cls, v: Any) -> Any:
        vals = v if isinstance(v, list) else [v]
        if not vals or any(isinstance(a, bool) or not isinstance(a, int) or a < 1
                           for a in vals):
            raise ValueError(f"must be an integer >= 1 or a list of them, got {show(v)}")
        return v


class MaterialModel(_Table):
    """``[materials.<name>]``: elastic, or Mohr–Coulomb with ``phi`` (and ``c``, ``psi``)."""

    density: num("kg/m³", "density", gt=0.0)
    E: num("Pa", "E", gt=0.0)
    nu: num("", gt=-1.0, lt=0.5)
    c: num("Pa", "soil_c", optional=True, ge=0.0) = None
    phi: num("deg", "angle", optional=True, ge=0.0, lt=90.0) = None
    psi: num("deg", "angle", optional=True, ge=0.0, lt=90.0) = None


class JointModel(_Table):
    """``[joints.mortar]``: the fields of
    :class:`~masonry_fdem.interactions.joints.JointMaterial` (None: its default)."""

    kn: num("Pa/m", "stiffness", optional=True, gt=0.0) = None
    ks: num("Pa/m", "stiffness", optional=True, gt=0.0) = None
    ft: num("Pa", "ft", optional=True, ge=0.0) = None
    GfI: num("N/m", "Gf", optional=True, ge=0.0) = None
    c: num("Pa", "c", optional=True, ge=0.0) = None
    tan_phi: num("", "tan_phi", optional=True, ge=0.0) = None
    GfII: num("N/m", "Gf", optional=True, ge=0.0) = None
    tan_psi: num("", optional=True, ge=0.0) = None
    psi_confinement: num("Pa", optional=True, lt=0.0) = None
    psi_decay: num("1/m", optional=True, ge=0.0) = None
    fc: num("Pa", "fc", optional=True, gt=0.0) = None
    Cs: num("", optional=True, ge=0.0) = None
    kappa_p: num("m", optional=True, gt=0.0) = None
    Gfc: num("N/m", "Gfc", optional=True, gt=0.0) = None
    penalty: num("", optional=True, gt=0.0) = None

    def values(self) -> dict[str, float]:
        """The fields the file gave, for ``JointMaterial(**values)``."""
        return {k: getattr(self, k) for k in self.model_fields_set if k != "type"}


class RingJointModel(JointModel):
    """``[joints.ring]``: ``type`` "bonded" (the mortar, fields replaced) or "sand"."""

    type: Literal["bonded", "sand"] = "bonded"


class DiskFillModel(_Table):
    """``[fill.disks]`` (see :class:`~masonry_fdem.assessment.specs.DiskFillSpec`)."""

    count: integer(ge=50) = 5600
    porosity: num("", gt=0.0, lt=0.5) = 0.2
    E: num("Pa", "E", gt=0.0) = 1e8
    nu: num("", gt=-1.0, lt=0.5) = 0.25
    friction: num("", "tan_phi", ge=0.0) = 0.5
    rolling_friction: num("", ge=0.0) = 0.3
    restitution: num("", gt=0.0, le=1.0) = 0.5
    local_damping: num("", ge=0.0, lt=1.0) = 0.7
    seed: integer(ge=0) = 1
    tol: num("", gt=0.0, lt=1.0) = 1e-3
    max_steps: integer(ge=1000) = 600_000
    runaway: num("m", optional=True, gt=0.0) = None
    surfacing: num("m", ge=0.0) = 0.0
    surfacing_material: str | None = None
    cell: num("m", gt=0.0) = 0.2


class FillModel(_Table):
    """``[fill]``."""

    model: Literal["continuum", "disks"] = "continuum"
    disks: DiskFillModel | None = None

    cover: num("m", "length", gt=0.0)
    material: str = "fill"
    interface_friction: num("", "tan_phi", optional=True, ge=0.0) = None
    interface_stiffness: num("Pa/m", "stiffness", optional=True, gt=0.0) = None
    mesh_size: num("m", optional=True, gt=0.0) = None
    wall_thickness: num("m", "length", gt=0.0) = 0.3
    passive_mobilisation: num("", optional=True, ge=0.0, le=1.0) = None
    crossed: bool = False
    incline_loads: bool = False
    backing: num("m", ge=0.0) = 0.0


class LoadingModel(_Table):
    """``[loading]`` (``position``/``x`` on the span are checked in :mod:`.parse`)."""

    position: num("", optional=True) = None
    x: num("m", optional=True) = None
    spreader_width: num("m", ge=0.0) = 0.0
    increment: num("N", optional=True, gt=0.0) = None
    max_load: num("N", optional=True, gt=0.0) = None
    self_weight: bool = True
    control: Literal["load", "displacement"] = "load"
    displacement_increment: num("m", optional=True, gt=0.0) = None
    max_displacement: num("m", optional=True, gt=0.0) = None


class _Damage(_Table):
    type: str


class RingSeparationModel(_Damage):
    rings: Any = "all"
    start: num("", ge=0.0, le=1.0) = Field(0.0, alias="from")
    end: num("", ge=0.0, le=1.0) = Field(1.0, alias="to")


class DecayedMortarModel(RingSeparationModel):
    factor: num("", gt=0.0, le=1.0)


class OpenJointModel(_Damage):
    ring: integer(ge=0)
    index: integer(optional=True, ge=0) = None
    position: num("", optional=True, ge=0.0, le=1.0) = None


class MissingBrickModel(_Damage):
    ring: integer(ge=0)
    index: integer(ge=0)


#: ``[[damage]]`` ``type`` -> its model
DAMAGE_MODELS: dict[str, type[_Damage]] = {
    "ring_separation": RingSeparationModel, "decayed_mortar": DecayedMortarModel,
    "open_joint": OpenJointModel, "missing_brick": MissingBrickModel}


class AnalysisModel(_Table):
    """``[analysis]``."""

    limit_analysis: bool = True
    friction: num("", "tan_phi", optional=True, ge=0.0) = None
    dr_rtol: num("", gt=0.0) = 1e-6
    max_iterations: integer(ge=1) = 200_000
    output: str | None = None
    refinements: integer(ge=0) = 4
    hinge_opening: num("", gt=0.0) = 1e-4
    penalty_factor: num("", gt=0.0) = 20.0
    post_peak_steps: integer(ge=1) = 3
    post_peak_drop: num("", gt=0.0, lt=1.0) = 0.2
    follow_peak: bool = True
    solver: Literal["newton", "dr"] = "newton"
    newton_rtol: num("", gt=0.0) = 1e-6
    newton_iterations: integer(ge=1) = 25
    newton_steps: integer(ge=1) = 400
    paraview_every: integer(ge=0) = 10
    softening: Literal["implicit", "imex"] = "implicit"
    through_layers: bool = False


class SteelModel(_Table):
    """``[anchors.steel]``, ``[search.steel]``:
    :class:`~masonry_fdem.interactions.anchors.SteelLaw`."""

    E: num("Pa", "steel_E", optional=True, gt=0.0) = None
    yield_stress: num("Pa", "stress", optional=True, gt=0.0) = None
    hardening: num("Pa", optional=True, ge=0.0) = None
    rupture_strain: num("", optional=True, gt=0.0) = None
    density: num("kg/m³", "density", optional=True, gt=0.0) = None

    def values(self) -> dict[str, float]:
        return {k: getattr(self, k) for k in self.model_fields_set}


class BondModel(_Table):
    """``[anchors.bond]``: :class:`~masonry_fdem.interactions.anchors.BondLaw`."""

    slip: numbers("m")
    stress: numbers("Pa")


class ShearModel(_Table):
    """``[anchors.shear]``: the bar's dowel action across the joints it crosses
    (:class:`~masonry_fdem.interactions.anchors.JointDowel`): ``fc`` (the bedding's
    compressive strength; stiffness and strength from the bar by ``JointDowel.from_bar``,
    with ``c1``, ``c0``), or ``stiffness`` [N/m] and ``strength`` [N] per bar."""

    fc: num("Pa", "fc", optional=True, gt=0.0) = None
    c1: num("", gt=0.0) = 0.8
    c0: num("", gt=0.0) = 1.3
    stiffness: num("N/m", optional=True, gt=0.0) = None
    strength: num("N", "force", optional=True, gt=0.0) = None


class AnchorModel(_Table):
    """``[[anchors]]``; which keys a ``layout`` uses is checked in :mod:`.parse`."""

    layout: Literal["radial", "stitch", "inclined"]
    angles: numbers("deg", optional=True) = None
    cover: num("m", ge=0.0) = 0.02
    start_angle: num("deg", optional=True) = None
    end_angle: num("deg", optional=True) = None
    depth: num("m", optional=True, gt=0.0) = None
    pieces: integer(optional=True, ge=1) = None
    positions: numbers("", optional=True) = None
    inclination: num("deg", gt=0.0, lt=180.0) = 90.0
    length: num("m", optional=True, gt=0.0) = None
    diameter: num("m", "diameter", gt=0.0)
    count: num("", gt=0.0) = 1.0
    prestress: num("N", "force", ge=0.0) = 0.0
    plates: Literal["none", "start", "end", "both"] = "none"
    bond_diameter: num("m", "diameter", optional=True, gt=0.0) = None
    segment: num("m", optional=True, gt=0.0) = None
    name: str | None = None
    steel: SteelModel = SteelModel()
    bond: BondModel | None = None
    shear: ShearModel | None = None


class LayoutModel(_Table):
    """``[[search.layouts]]``."""

    positions: numbers("")
    inclination: num("deg", gt=0.0, lt=180.0) = 90.0
    length: num("m", optional=True, gt=0.0) = None
    prestress: num("N", "force", ge=0.0) = 0.0


class SearchModel(_Table):
    """``[search]``."""

    positions: numbers("", optional=True) = None
    counts: Annotated[list[Annotated[int, Field(ge=1)]], Field(min_length=1)] = [1]
    inclinations: numbers("deg", gt=0.0, lt=180.0) = [90.0]
    lengths: Any = ["through"]
    prestress: numbers("N", ge=0.0) = [0.0]
    layouts: list[LayoutModel] = []
    diameter: num("m", "diameter", gt=0.0) = 0.016
    bars: num("", gt=0.0) = 1.0
    cover: num("m", ge=0.0) = 0.02
    min_spacing: num("m", ge=0.0) = 0.05
    steel: SteelModel = SteelModel()
    bond: BondModel | None = None
    objective: Literal["gain_per_metre", "cheapest"] = "gain_per_metre"
    target: num("N", optional=True, gt=0.0) = None
    keep: integer(ge=1) = 4
    keep_ratio: num("", ge=0.0, le=1.0) = 0.5
    coarse: bool = True
    max_candidates: integer(ge=1) = 500

    @field_validator("positions")
    @classmethod
    def _positions(cls, v: Any) -> Any:
        if v is not None and not all(-1e-9 <= x <= 1 + 1e-9 for x in v):
            raise ValueError(f"every position must be in [0, 1] (s along the arch), got {v}")
        return v

    @field_validator("lengths", mode="before")
    @classmethod
    def _lengths(cls, v: Any) -> Any:
        if not isinstance(v, list) or not v:
            raise ValueError(f'must be a non-empty list of lengths [m] or "through", got '
                             f"{show(v)}")
        for a in v:
            if a != "through" and not (isinstance(a, int | float) and not isinstance(a, bool)
                                       and math.isfinite(a) and a > 0):
                raise ValueError(f'every entry must be a length > 0 [m] or "through", got '
                                 f"{show(a)}")
        return v


# ---------------------------------------------------------------------- errors as lines
def show(v: Any) -> str:
    """A value as the message shows it (strings quoted)."""
    return repr(v) if isinstance(v, str) else str(v)


def _join(path: str, loc: tuple) -> str:
    out = path
    for part in loc:
        if isinstance(part, int):
            out += f"[{part}]"
        else:
            out = f"{out}.{part}" if out else str(part)
    return out


def _unwrap(tp: Any) -> Any:
    """The model class inside Optional/list/Annotated, else None."""
    if isinstance(tp, type) and issubclass(tp, BaseModel):
        return tp
    for arg in get_args(tp):
        m = _unwrap(arg)
        if m is not None:
            return m
    return None


def _walk(model: type[BaseModel], loc: tuple):
    """(field info, model of its table) of the key at ``loc`` (None if not a field)."""
    info, parent = None, model
    for part in loc:
        if isinstance(part, int) or model is None:
            continue
        fields = {f.alias or n: f for n, f in model.model_fields.items()}
        info, parent = fields.get(part), model
        if info is None:
            return None, parent
        model = _unwrap(info.annotation)
    return info, parent


def _unit(info) -> str:
    for m in getattr(info, "metadata", []) if info is not None else []:
        if isinstance(m, Meta) and m.unit:
            return f" [{m.unit}]"
    return ""


def _line(model: type[BaseModel], path: str, e: dict) -> str:
    loc, typ, v, ctx = e["loc"], e["type"], e.get("input"), e.get("ctx") or {}
    # drop the union/annotation tags pydantic adds to ``loc`` (e.g. "list[...]")
    loc = tuple(p for p in loc if isinstance(p, int) or not any(c in p for c in "[]|"))
    key = _join(path, loc)
    info, parent = _walk(model, tuple(p for p in loc if not isinstance(p, int)))
    unit = _unit(info)
    if typ == "extra_forbidden":
        where = f"[{_join(path, loc[:-1])}]" if _join(path, loc[:-1]) else "the case"
        known = [f.alias or n for n, f in parent.model_fields.items()]
        close = difflib.get_close_matches(str(loc[-1]), known, n=1)
        hint = (f"did you mean {close[0]!r}?" if close
                else "expected one of " + ", ".join(known))
        return f"unknown key {loc[-1]!r} in {where} ({hint})"
    if typ == "missing":
        sub = _unwrap(info.annotation) if info is not None else None
        return f"[{key}]: missing table (required)" if sub or key in (
            "arch", "materials", "joints") else f"{key}: missing (required)"
    ops = {"greater_than": ">", "greater_than_equal": ">=", "less_than": "<",
           "less_than_equal": "<="}
    if typ in ops:
        bound = next(iter(ctx.values()))
        return f"{key}: must be {ops[typ]} {bound:g}, got {show(v)}{unit}"
    if typ in ("float_type", "float_parsing", "finite_number"):
        return f"{key}: must be a finite number, got {show(v)}{unit}"
    if typ in ("int_type", "int_parsing", "int_from_float"):
        return f"{key}: must be an integer, got {show(v)}"
    if typ == "bool_type":
        return f"{key}: must be true or false, got {show(v)}"
    if typ == "string_type":
        return f"{key}: must be a string, got {show(v)}"
    if typ == "literal_error":
        return f"{key}: must be one of {ctx.get('expected', '')}, got {show(v)}"
    if typ in ("dict_type", "model_type", "model_attributes_type"):
        return f"{key}: must be a table, got {show(v)}"
    if typ == "list_type":
        return f"{key}: must be a list, got {show(v)}"
    if typ == "too_short":
        n = ctx.get("min_length", 1)
        return (f"{key}: must not be empty, got {show(v)}" if n == 1
                else f"{key}: needs {n} entries, got {show(v)}")
    if typ == "too_long":
        return f"{key}: at most {ctx.get('max_length')} entries, got {show(v)}"
    if typ == "value_error":
        return f"{key}: {str(ctx.get('error', e['msg']))}"
    return f"{key}: {e['msg']}, got {show(v)}"


def validate(model: type[BaseModel], data: Any, path: str, problems: list[str]):
    """``data`` checked against ``model``: the instance, or None with one line per error
    appended to ``problems``, each naming its key (``path`` is the table's)."""
    if isinstance(data, Mapping) and not isinstance(data, dict):
        data = dict(data)
    try:
        return model.model_validate(data)
    except ValidationError as err:
        if not isinstance(data, dict):
            problems.append(f"{path}: must be a table, got {show(data)}")
            return None
        seen = []
        for e in err.errors(include_url=False):
            line = _line(model, path, e)
            if line not in seen:
                seen.append(line)
        problems.extend(seen)
        return None


def magnitude_problems(obj: BaseModel | None, path: str, allow: tuple[str, ...]) -> list[str]:
    """The magnitude checks of a validated table (and its sub-tables): one line per number
    with a kind (:class:`Meta`) outside :data:`masonry_fdem.checks.PLAUSIBLE`, unless its
    key is in ``allow`` (``[checks] allow``)."""
    if obj is None:
        return []
    out = []
    for name, info in type(obj).model_fields.items():
        key = _join(path, (info.alias or name,))
        value = getattr(obj, name)
        if isinstance(value, BaseModel):
            out += magnitude_problems(value, key, allow)
            continue
        meta = next((m for m in info.metadata if isinstance(m, Meta)), None)
        if meta is None or meta.kind is None or name not in obj.model_fields_set:
            continue
        msg = magnitude_problem(key, value, meta.kind, allow=allow,
                                allow_hint=f'[checks] allow = ["{key}"]')
        if msg:
            out.append(msg)
    return out



# ---------------------------------------------------------------------- bridge case files
class BridgeRootModel(_Table):
    """A bridge case file's top level (:mod:`masonry_fdem.assessment.bridge_case`)."""

    bridge: dict[str, Any]
    materials: dict[str, Any]
    joints: dict[str, Any]
    vehicle: dict[str, Any]
    analysis: dict[str, Any] = {}
    checks: dict[str, Any] = {}


class BridgeSpanModel(_Table):
    """``[[bridge.spans]]``: one arch of the bridge."""

    span: num("m", "span", gt=0.0)
    rise: num("m", "rise", gt=0.0)
    ring_thickness: num("m", "ring_thickness", gt=0.0)
    voussoirs: integer(ge=1)
    kind: Literal["semicircular", "segmental", "pointed"] = "segmental"
    rings: integer(ge=1) = 1


class BridgePartsModel(_Table):
    """``[bridge.materials]``: the ``[materials.*]`` name of each part."""

    masonry: str
    pier: str | None = None
    wall: str | None = None
    fill: str
    surfacing: str = "surfacing"
    soil: str = "soil"
    spandrel: str | None = None
    backing: str | None = None


class BridgeInterfaceModel(_Table):
    """``[bridge.interface]``: the fill's friction-only interfaces."""

    tan_phi: num("", "tan_phi", optional=True, ge=0.0) = None
    kn: num("Pa/m", "stiffness", optional=True, gt=0.0) = None
    ks: num("Pa/m", "stiffness", optional=True, gt=0.0) = None


class BridgeMeshModel(_Table):
    """``[bridge.mesh]``: element size [m] per part."""

    masonry: num("m", optional=True, gt=0.0) = None
    pier: num("m", optional=True, gt=0.0) = None
    wall: num("m", optional=True, gt=0.0) = None
    fill: num("m", optional=True, gt=0.0) = None
    surfacing: num("m", optional=True, gt=0.0) = None
    soil: num("m", optional=True, gt=0.0) = None
    spandrel: num("m", optional=True, gt=0.0) = None
    crossed: bool = False


class BridgeModel(_Table):
    """``[bridge]``."""

    spans: list[BridgeSpanModel] = []
    piers: list[float] = []
    pier_height: num("m", "length", gt=0.0) = 1.0
    abutment_width: num("m", "length", gt=0.0) = 1.0
    cover: num("m", "length", gt=0.0)
    surfacing: num("m", ge=0.0) = 0.0
    soil_depth: num("m", ge=0.0) = 0.0
    soil_margin: num("m", optional=True, ge=0.0) = None
    soil_extent: Annotated[list[float], Field(min_length=2, max_length=2)] | None = None
    wall_thickness: num("m", "length", gt=0.0) = 0.3
    width: num("m", "width", gt=0.0) = 1.0
    spandrel_thickness: num("m", ge=0.0) = 0.0
    spandrel_block: num("m", "length", gt=0.0) = 0.5
    backing: num("m", ge=0.0) = 0.0
    materials: BridgePartsModel
    interface: BridgeInterfaceModel = BridgeInterfaceModel()
    mesh: BridgeMeshModel = BridgeMeshModel()
    fill_model: Literal["continuum", "disks"] = "continuum"
    disks: DiskFillModel | None = None


class VehicleModel(_Table):
    """``[vehicle]``: axle offsets [m], relative loads, tyre patch [m], positions [m]."""

    offsets: numbers("m") = [0.0]
    loads: numbers("", optional=True) = None
    patch: num("m", gt=0.0) = 0.3
    positions: numbers("m")
    load: num("N", "force", optional=True, gt=0.0) = None


class BridgeAnalysisModel(_Table):
    """A bridge case's ``[analysis]``."""

    increment: num("m", optional=True, gt=0.0) = None
    max_displacement: num("m", optional=True, gt=0.0) = None
    stop_drop: num("", optional=True, gt=0.0, lt=1.0) = None
    max_steps: integer(optional=True, ge=1) = None
