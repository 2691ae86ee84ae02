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
    width = 5.0                   # [m] the barrel's (default 1: a strip)
    spandrel_thickness = 0.4      # [m] each of the two spandrel walls (default 0: none;
    spandrel_block = 0.5          #   continuum fill only), their blocks' length [m]
    backing = 0.5                 # [m] the haunches' backing above the springings (default
                                  #   0: none; continuum fill only)
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
    crossed = false               # fill, surfacing, soil in crossed triangles (no locking)
    [bridge.disks]                # with [bridge] fill_model = "disks" (default
    count = 6000                  #   "continuum"): as an arch case's [fill.disks], without
                                  #   its surfacing keys (the bridge's surfacing is used);
                                  #   needs a surfacing and vehicle.load (DiskBridge)
    [materials.stone] ...         # density, E, nu (and c, phi, psi: Mohr–Coulomb)
    [joints.mortar] ...           # the masonry's joints
    [joints.spandrel] ...         # the spandrel walls' joints (default: the mortar)
    [vehicle]
    offsets = [0.9, -0.9]         # [m] axles from the vehicle's reference point
    loads = [1.0, 1.0]            # relative axle weights
    patch = 0.3                   # [m]
    positions = [1.5, 3.0]        # [m] x of the reference point at each run
    load = 1e5                    # [N] the vehicle's total for a traverse at a fixed load
    [analysis]
    increment = 1e-3              # [m] first arc-length increment of the axles' settlement
    max_displacement = 0.1        # [m]
    stop_drop = 0.1               # stop once the load has fallen this far below its peak

Every problem is reported at once, naming its key
(:class:`~masonry_fdem.assessment.specs.CaseError`): each table is checked by its model
in :mod:`masonry_fdem.assessment.schema` (types, ranges, units, magnitudes;
``[checks] allow`` as in the arch case files), then the bridge by
:class:`~masonry_fdem.geometry.bridge.Bridge`. Units: SI.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from mpi4py import MPI

from masonry_fdem import checks
from masonry_fdem.assessment import schema as S
from masonry_fdem.assessment.bridge import BridgeRun, Vehicle, bridge_model, load_bridge
from masonry_fdem.assessment.parse import (
    _Ctx,
    _load_toml,
    checks_allow,
    parse_joint,
    parse_materials,
)
from masonry_fdem.assessment.schema import validate
from masonry_fdem.assessment.specs import CaseError, DiskFillSpec
from masonry_fdem.checks import numerical_failures
from masonry_fdem.geometry.bridge import Bridge, BridgeError, Span
from masonry_fdem.interactions.joints import JointMaterial
from masonry_fdem.materials.elastic import Material
from masonry_fdem.materials.plasticity import MohrCoulomb

__all__ = ["BridgeCase", "load_bridge_case"]

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
    crossed: bool = False
    fill_model: str = "continuum"
    disks: DiskFillSpec | None = None
    load: float | None = None
    spandrel_joint: JointMaterial | None = None

    def disk_bridge(self, comm: MPI.Comm = MPI.COMM_WORLD):
        """The bridge with its fill as disks (``[bridge] fill_model = "disks"``, its
        ``[bridge.disks]``; :class:`~masonry_fdem.assessment.disk_bridge.DiskBridge`), not
        yet settled (collective)."""
        from masonry_fdem.assessment.disk_bridge import DiskBridge

        if self.fill_model != "disks":
            raise ValueError(f"{self.name}: bridge.fill_model is {self.fill_model!r}, not "
                             '"disks"')
        d = self.disks or DiskFillSpec()
        return DiskBridge(self.bridge, self.materials, self.mortar, self.interface,
                          count=d.count, porosity=d.porosity, E=d.E, nu=d.nu,
                          friction=d.friction, rolling_friction=d.rolling_friction,
                          restitution=d.restitution, local_damping=d.local_damping,
                          seed=d.seed, mesh_size=self.mesh, comm=comm)

    @numerical_failures("the bridge run")
    def run(self, x: float, comm: MPI.Comm = MPI.COMM_WORLD, *, on_model=None):
        """Build the model with the vehicle at ``x`` [m] and load it to collapse
        (collective). ``on_model(model, interactions)``, if given, is called once the
        model is built and returns the ``callback(load, displacement)`` of
        :func:`~masonry_fdem.assessment.bridge.load_bridge` (or None). Returns
        ``(model, BridgeRun)``."""
        model, inter, axles = bridge_model(self.bridge, self.materials, self.mortar,
                                           self.interface, self.vehicle, x,
                                           mesh_size=self.mesh, crossed=self.crossed,
                                           spandrel_joint=self.spandrel_joint, comm=comm)
        cb = on_model(model, inter) if on_model is not None else None
        run: BridgeRun = load_bridge(model, inter, axles, self.interface,
                                     self.bridge.road_level(), callback=cb, comm=comm,
                                     **self.analysis)
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
    ctx = _Ctx()
    ctx.allow = checks_allow(data, ctx.problems)
    problems = ctx.problems
    validate(S.BridgeRootModel, data, "", problems)
    data = data if isinstance(data, Mapping) else {}

    def table(key):
        v = data.get(key)
        return v if isinstance(v, Mapping) else None

    mats = parse_materials(table("materials"), ctx) if table("materials") is not None else {}
    bm = ctx.table(S.BridgeModel, table("bridge"), "bridge") if table("bridge") else None
    bridge, interface, parts, mesh = None, None, {}, {}
    if bm is not None:
        if not bm.spans:
            problems.append("bridge.spans: missing: at least one [[bridge.spans]] (the fill "
                            "would lie above no arch)")
        spans = [Span(s.span, s.rise, s.ring_thickness, s.voussoirs, s.kind, s.rings)
                 for s in bm.spans]
        pm = bm.materials
        parts = {"masonry": pm.masonry, "pier": pm.pier or pm.masonry,
                 "wall": pm.wall or pm.pier or pm.masonry, "fill": pm.fill,
                 "surfacing": pm.surfacing, "soil": pm.soil,
                 "spandrel": pm.spandrel or pm.pier or pm.masonry,
                 "backing": pm.backing or pm.pier or pm.masonry}
        kw: dict[str, Any] = dict(pier_height=bm.pier_height, abutment_width=bm.abutment_width,
                                  cover=bm.cover, surfacing=bm.surfacing,
                                  soil_depth=bm.soil_depth, wall_thickness=bm.wall_thickness,
                                  width=bm.width, spandrel_thickness=bm.spandrel_thickness,
                                  spandrel_block=bm.spandrel_block, backing=bm.backing)
        if bm.soil_margin is not None:
            kw["soil_margin"] = bm.soil_margin
        if bm.soil_extent is not None:
            kw["soil_extent"] = tuple(bm.soil_extent)
        used = {parts["masonry"], parts["pier"], parts["wall"], parts["fill"]}
        if bm.surfacing > 0:
            used.add(parts["surfacing"])
        if bm.soil_depth > 0:
            used.add(parts["soil"])
        if bm.spandrel_thickness > 0:
            used.add(parts["spandrel"])
        if bm.backing > 0:
            used.add(parts["backing"])
        known = table("materials") or {}
        for part, m in parts.items():
            if m in used and m not in known:
                problems.append(f"bridge.materials.{part}: no [materials.{m}] in the case")
        for part in ("fill", "soil"):
            m = parts[part]
            if m in mats and m in used and not isinstance(mats[m], MohrCoulomb):
                problems.append(f"bridge.materials.{part}: [materials.{m}] is elastic: a "
                                f"{part} needs c, phi (and psi) for its Mohr–Coulomb strength")
        defaults = {"masonry": 0.2, "pier": 0.3, "wall": 0.3, "fill": 0.2, "surfacing": 0.1,
                    "soil": 0.4}
        mesh = {part: getattr(bm.mesh, part) or defaults[part] for part in defaults}
        mesh["spandrel"] = bm.mesh.spandrel or mesh["fill"]
        fm = mats.get(parts["fill"])
        it = bm.interface
        mu = it.tan_phi if it.tan_phi is not None else (
            math.tan(math.radians(2.0 / 3.0 * fm.phi)) if isinstance(fm, MohrCoulomb) else 0.5)
        kn = it.kn if it.kn is not None else (20.0 * fm.E / mesh["fill"] if fm else 1e9)
        with checks.expert():  # magnitudes: checked by the schema, with [checks] allow
            interface = JointMaterial(kn=kn, ks=it.ks or kn / 2.6, tan_phi=mu)
        if not problems:
            try:
                bridge = Bridge(spans=tuple(spans), piers=tuple(bm.piers), materials=parts,
                                **kw)
            except BridgeError as e:
                problems.append(f"bridge: {e}")
    mortar = spandrel_joint = None
    joints = table("joints")
    if joints is not None:
        for key in joints:
            if key not in ("mortar", "spandrel"):
                problems.append(f"unknown key {key!r} in [joints] (expected mortar, "
                                "spandrel)")
        if "mortar" not in joints:
            problems.append("[joints.mortar]: missing table (required)")
        else:
            mortar = parse_joint(joints["mortar"], "joints.mortar", ctx)
        if "spandrel" in joints:
            spandrel_joint = parse_joint(joints["spandrel"], "joints.spandrel", ctx)
            if bm is not None and bm.spandrel_thickness <= 0:
                problems.append("joints.spandrel: given, but the bridge has no spandrel "
                                "walls (bridge.spandrel_thickness = 0)")
        wj = spandrel_joint or mortar
        if (bm is not None and bm.spandrel_thickness > 0 and bm.fill_model == "continuum"
                and wj is not None and wj.fc is None):
            problems.append("joints.spandrel: the spandrel walls' joints need a compressive "
                            "strength fc (a [joints.spandrel] table, or fc in "
                            "[joints.mortar]): walls of elastic blocks between the end walls "
                            "would carry any thrust")
    vehicle, positions = None, ()
    vm = ctx.table(S.VehicleModel, table("vehicle"), "vehicle") if table("vehicle") else None
    if vm is not None:
        positions = tuple(vm.positions)
        try:
            vehicle = Vehicle(tuple(vm.offsets), tuple(vm.loads or [1.0] * len(vm.offsets)),
                              vm.patch)
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
    disks = None
    if bm is not None and bm.fill_model == "disks":
        d = bm.disks if bm.disks is not None else S.DiskFillModel()
        if d.surfacing > 0 or d.surfacing_material is not None:
            problems.append("bridge.disks.surfacing: a bridge's road layer is [bridge] "
                            "surfacing (and [bridge.materials] surfacing), not the disks'")
        if bm.surfacing <= 0:
            problems.append('bridge.surfacing: a bridge with fill_model = "disks" needs a '
                            "surfacing (> 0 m): the vehicle's tyres bear on it, not on "
                            "single disks")
        if bm.spandrel_thickness > 0:
            problems.append('bridge.spandrel_thickness: spandrel walls are modelled with a '
                            'continuum fill only (fill_model = "continuum"): disks would '
                            "overlap them in the plane")
        if bm.backing > 0:
            problems.append('bridge.backing: the backing is modelled with a continuum fill '
                            'only (fill_model = "continuum"): the disks are packed over the '
                            "bare extrados")
        if bm.mesh.crossed:
            problems.append('bridge.mesh.crossed: the fill is disks (fill_model = "disks"); '
                            "crossed triangles are for a continuum fill")
        if vm is not None and vm.load is None:
            problems.append('vehicle.load: missing: with fill_model = "disks" the vehicle '
                            "traverses the bridge at a fixed total load [N]")
        disks = DiskFillSpec(**{k: getattr(d, k) for k in S.DiskFillModel.model_fields})
    elif bm is not None and bm.disks is not None:
        problems.append('bridge.disks: given, but bridge.fill_model is "continuum" (set '
                        'fill_model = "disks" to pack the fill with disks)')
    am = ctx.table(S.BridgeAnalysisModel, table("analysis") or {}, "analysis")
    analysis = {k: v for k, v in (am.model_dump() if am else {}).items() if v is not None}
    if problems:
        raise CaseError(list(dict.fromkeys(problems)), label)  # each line once
    assert bridge is not None and mortar is not None and vehicle is not None
    return BridgeCase(name, bridge, mats, mortar, interface, vehicle, positions, mesh,
                      analysis, bool(bm.mesh.crossed), bm.fill_model, disks,
                      None if vm is None or vm.load is None else float(vm.load),
                      spandrel_joint)
