"""Bridge case files: a ``[bridge]`` section (spans, piers, fill, surfacing, soil), the
materials, the mortar, a ``[vehicle]`` and the positions it traverses.

.. code-block:: toml

    [bridge]
    piers = [1.5]                 # [m] widths, one fewer than the spans
    pier_height = 2.0             # [m] foundation to springing
    abutment_width = 1.0          # [m]
    cover = 0.5                   # [m] over the highest crown's extrados (surfacing included)
    surfacing = 0.1               # [m]
    soil_depth = 3.0              # [m] (0: rigid ground)
    soil_extent = [3.0, 10.5]     # [m] (default: under the whole bridge)
    [[bridge.spans]]
    span = 6.0                    # [m] and rise, ring_thickness, voussoirs, kind, rings
    ...
    [bridge.materials]            # material of each part (names of [materials.*])
    masonry = "stone"
    ...
    [bridge.interface]            # the fill's interfaces (friction-only)
    tan_phi = 0.43                # default tan(2/3 φ_fill)
    kn = 5e9                      # [Pa/m] default 20 E_fill / fill mesh size
    [bridge.mesh]                 # [m] element sizes per part
    [materials.stone] ...         # density, E, nu (and c, phi, psi: Mohr–Coulomb)
    [joints.mortar] ...           # the masonry's joints
    [vehicle]
    offsets = [0.9, -0.9]         # [m] axles from the vehicle's reference point
    loads = [1.0, 1.0]            # relative axle weights
    patch = 0.3                   # [m]
    positions = [1.5, 3.0]        # [m] x of the reference point at each run
    [analysis]
    increment = 1e-3              # [m] first arc-length increment of the axles' settlement
    max_displacement = 0.1        # [m]
    stop_drop = 0.1               # stop once the load has fallen this far below its peak

Every problem is reported at once, naming its key (:class:`~masonry_fdem.assessment.specs.CaseError`).
Units: SI.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from mpi4py import MPI

from masonry_fdem.assessment.bridge import BridgeRun, Vehicle, bridge_model, load_bridge
from masonry_fdem.assessment.parse import _JOINT_KEYS, _joint, _joint_values, _load_toml
from masonry_fdem.assessment.parse import _parse_materials
from masonry_fdem.assessment.specs import CaseError
from masonry_fdem.assessment.tables import REQUIRED, Table
from masonry_fdem.geometry.bridge import Bridge, BridgeError, Span
from masonry_fdem.interactions.joints import JointMaterial
from masonry_fdem.materials.elastic import Material
from masonry_fdem.materials.plasticity import MohrCoulomb

__all__ = ["BridgeCase", "load_bridge_case"]

_BRIDGE_KEYS = ("spans", "piers", "pier_height", "abutment_width", "cover", "surfacing",
                "soil_depth", "soil_margin", "soil_extent", "wall_thickness", "width",
                "materials", "interface", "mesh")
_SPAN_KEYS = ("span", "rise", "ring_thickness", "voussoirs", "kind", "rings")
_PARTS = ("masonry", "pier", "wall", "fill", "surfacing", "soil")


@dataclass(frozen=True)
class BridgeCase:
    """A checked bridge case (:func:`load_bridge_case`)."""

    name: str
    bridge: Bridge
    materials: dict[str, Material]
    mortar: JointMaterial
    interface: JointMaterial
    vehicle: Vehicle
    positions: tuple[float, ...]
    mesh: dict[str, float]
    analysis: dict[str, float] = field(default_factory=dict)

    def run(self, x: float, comm: MPI.Comm = MPI.COMM_WORLD):
        """Build the model with the vehicle at ``x`` [m] and load it to collapse
        (collective). Returns ``(model, BridgeRun)``."""
        model, inter, axles = bridge_model(self.bridge, self.materials, self.mortar,
                                           self.interface, self.vehicle, x,
                                           mesh_size=self.mesh, comm=comm)
        run: BridgeRun = load_bridge(model, inter, axles, self.interface,
                                     self.bridge.road_level(), comm=comm, **self.analysis)
        return model, run


def load_bridge_case(source: str | Path | Mapping[str, Any], *,
                     name: str | None = None) -> BridgeCase:
    """Read and check a bridge case (a TOML file or a dict of the same shape).

    Raises:
        CaseError: every problem of the case, one per line, each naming its key.
    """
    if isinstance(source, Mapping):
        data, label, name = source, None, name or "bridge"
    else:
        path = Path(source)
        data, label, name = _load_toml(path), str(path), name or path.stem
    problems: list[str] = []
    root = Table(problems, "", data, ("bridge", "materials", "joints", "vehicle", "analysis"))
    mats = _parse_materials(root)
    bt = root.table("bridge", _BRIDGE_KEYS, required=True)
    bridge = None
    parts: dict[str, str] = {}
    interface = None
    mesh: dict[str, float] = {}
    if bt is not None:
        spans = []
        for k, sd in enumerate(bt.tables("spans")):
            st = Table(problems, f"bridge.spans[{k}]", sd, _SPAN_KEYS)
            vals = (st.number("span", gt=0.0), st.number("rise", gt=0.0),
                    st.number("ring_thickness", gt=0.0), st.integer("voussoirs", ge=1),
                    st.string("kind", "segmental", ("semicircular", "segmental", "pointed")),
                    st.integer("rings", 1, ge=1))
            if None not in vals:
                spans.append(Span(*vals))
        if not bt.tables("spans"):
            bt.bad("spans", "missing: at least one [[bridge.spans]] (the fill would lie above "
                   "no arch)")
        mt = bt.table("materials", _PARTS, required=True)
        if mt is not None:
            for part in _PARTS:
                default = None if part in ("masonry", "fill") else {
                    "pier": mt.data.get("masonry"), "wall": mt.data.get("pier",
                                                                        mt.data.get("masonry")),
                    "surfacing": "surfacing", "soil": "soil"}[part]
                v = mt.string(part, default if default is not None else REQUIRED)
                if isinstance(v, str):
                    parts[part] = v
        # the numbers of the bridge; its own checks then run in Bridge
        kw = {}
        for key, default, bound in (("pier_height", 1.0, "gt"), ("abutment_width", 1.0, "gt"),
                                    ("cover", REQUIRED, "gt"), ("surfacing", 0.0, "ge"),
                                    ("soil_depth", 0.0, "ge"), ("wall_thickness", 0.3, "gt"),
                                    ("width", 1.0, "gt")):
            v = bt.number(key, default, **{bound: 0.0})
            if v is not None:
                kw[key] = v
        piers = bt.numbers("piers", ())
        if "soil_margin" in bt.data:
            kw["soil_margin"] = bt.number("soil_margin", ge=0.0)
        if "soil_extent" in bt.data:
            ext = bt.numbers("soil_extent")
            if ext is not None and len(ext) != 2:
                bt.bad("soil_extent", f"must be [x_min, x_max], got {list(ext)}")
            elif ext is not None:
                kw["soil_extent"] = ext
        used = {parts.get("masonry"), parts.get("pier"), parts.get("wall"), parts.get("fill")}
        if kw.get("surfacing", 0.0) > 0:
            used.add(parts.get("surfacing"))
        if kw.get("soil_depth", 0.0) > 0:
            used.add(parts.get("soil"))
        for part, m in parts.items():
            if m in used and "materials" in data and m not in data["materials"]:
                problems.append(f"bridge.materials.{part}: no [materials.{m}] in the case")
        for part in ("fill", "soil"):
            m = parts.get(part)
            if m in mats and m in used and not isinstance(mats[m], MohrCoulomb):
                problems.append(f"bridge.materials.{part}: [materials.{m}] is elastic: a "
                                f"{part} needs c, phi (and psi) for its Mohr–Coulomb strength")
        mesh_t = bt.table("mesh", _PARTS)
        for part in _PARTS:
            v = mesh_t.number(part, None, gt=0.0) if mesh_t is not None else None
            mesh[part] = v if v is not None else {"fill": 0.2, "surfacing": 0.1, "soil": 0.4,
                                                  "wall": 0.3, "pier": 0.3}.get(part, 0.2)
        fm = mats.get(parts.get("fill", ""))
        it = bt.table("interface", ("tan_phi", "kn", "ks"))
        mu0 = math.tan(math.radians(2.0 / 3.0 * fm.phi)) if isinstance(fm, MohrCoulomb) else 0.5
        mu = it.number("tan_phi", mu0, ge=0.0) if it is not None else mu0
        kn0 = 20.0 * fm.E / mesh["fill"] if fm is not None else 1e9
        kn = it.number("kn", kn0, gt=0.0) if it is not None else kn0
        ks = it.number("ks", None, gt=0.0) if it is not None else None
        if None not in (mu, kn):
            interface = JointMaterial(kn=kn, ks=ks or kn / 2.6, tan_phi=mu)
        if not problems and len(spans) == len(bt.tables("spans")):
            try:
                bridge = Bridge(spans=tuple(spans), piers=piers or (), materials=dict(parts),
                                **kw)
            except BridgeError as e:
                problems.append(f"bridge: {e}")
    joints = root.table("joints", ("mortar",), required=True)
    mortar = None
    if joints is not None:
        mt = joints.table("mortar", _JOINT_KEYS, required=True)
        vals = _joint_values(mt) if mt is not None else None
        if vals is not None:
            mortar = _joint(mt, vals)
    vehicle, positions = None, ()
    vt = root.table("vehicle", ("offsets", "loads", "patch", "positions"), required=True)
    if vt is not None:
        offs = vt.numbers("offsets", (0.0,))
        loads = vt.numbers("loads", tuple(1.0 for _ in (offs or (0.0,))))
        patch = vt.number("patch", 0.3, gt=0.0)
        positions = vt.numbers("positions") or ()
        if None not in (offs, loads, patch):
            try:
                vehicle = Vehicle(offs, loads, patch)
            except BridgeError as e:
                problems.append(str(e))
        if bridge is not None and vehicle is not None:
            for x in positions:
                for k, (xa, _) in enumerate(vehicle.axles(x)):
                    try:
                        bridge.check_on_deck(xa, 0.5 * vehicle.patch,
                                             f"vehicle.positions: at {x:g} m, axle {k}")
                    except BridgeError as e:
                        problems.append(str(e))
    analysis = {}
    at = root.table("analysis", ("increment", "max_displacement", "stop_drop", "max_steps"))
    if at is not None:
        for key, kwb in (("increment", dict(gt=0.0)), ("max_displacement", dict(gt=0.0)),
                         ("stop_drop", dict(gt=0.0, lt=1.0))):
            v = at.number(key, None, **kwb)
            if v is not None:
                analysis[key] = v
        if "max_steps" in at.data:
            v = at.integer("max_steps", ge=1)
            if v is not None:
                analysis["max_steps"] = v
    if problems:
        raise CaseError(problems, label)
    assert bridge is not None and mortar is not None and vehicle is not None
    return BridgeCase(name, bridge, mats, mortar, interface, vehicle, tuple(positions), mesh,
                      analysis)

