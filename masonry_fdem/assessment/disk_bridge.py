"""A bridge of :class:`~masonry_fdem.geometry.bridge.Bridge` (spans, piers, soil) with its
fill as disks, and a vehicle traversing it at a fixed load (issue #22: the reference
paper's first application, its Figure 6, with the fill "as circular discrete elements").

The blocks are those of :func:`~masonry_fdem.assessment.bridge.bridge_model` (voussoirs,
piers and abutments, end walls, the soil under the piers as a Mohr–Coulomb continuum),
without the fill's continuum: the fill region is packed by rigid disks
(:func:`~masonry_fdem.interactions.disks.fill.pack_polygon`; their solid density is the
fill's bulk density over 1 − porosity), touching the blocks through
:class:`~masonry_fdem.interactions.DiskBlockContact` with the fill's interface friction
tan δ. The surfacing is one block from end wall to end wall (1 cm clear of each), in
plane strain, lying on the disks; the vehicle's axles load it as uniform pressures over
their tyre patches. A surfacing is required: a tyre patch of a few disk diameters on
bare disks would load two or three of them.

Equilibrium is found as for the single span (:mod:`~masonry_fdem.assessment.disk_fill`,
whose module doc says why explicit dynamics and not Newton): central differences with
Cundall's local damping until the unbalanced-force ratios of the disks (rattlers left out)
and of the blocks fall below ``tol``, the blocks density-scaled to the disks' stable step
(their weight kept). Stages:

1. the fill settles under gravity, packed a quarter of its depth above its top, with every
   block held; the disks above the fill's top are then removed and the rest settles again;
2. the surfacing is lowered onto the disks, every block released (the voussoirs on their
   joints, the piers on the soil), and the whole settles under self-weight;
3. :meth:`DiskBridge.traverse`: the vehicle, at a fixed total load, is put on the road at
   its first position (its load raised in ``ramp`` equal steps, each to equilibrium), then
   moved to each next position and held there to equilibrium — a traversing load,
   quasi-static at each position. A position at which the ring runs on (a voussoir moves
   ``runaway`` under the constant load) is a mechanism: the bridge does not carry the
   vehicle there; one at which neither equilibrium nor runaway comes within
   ``max_steps`` is *not converged*. Either ends the traverse. Or
   :meth:`DiskBridge.collapse`: the vehicle at one position, its load raised in equal
   steps, each held to equilibrium, until the ring runs on (*mechanism*: the collapse
   load lies between the last load carried and the next), as the single span's
   :meth:`~masonry_fdem.assessment.disk_fill.DiskFillBridge.load`.

Units: SI (N, m, s, kg); loads over the bridge's ``width``.
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

from mpi4py import MPI

import numpy as np

from masonry_fdem.assessment.disk_fill import DiskFillBridge
from masonry_fdem.geometry.bridge import Bridge, BridgeError
from masonry_fdem.solvers.status import RunStatus, Status

__all__ = ["DiskBridge", "DiskTraverse", "draw_bridge_stress"]


@dataclass
class DiskTraverse:
    """Result of :meth:`DiskBridge.traverse`: the vehicle's total ``load`` [N]; per
    position carried (``positions`` [m], the vehicle's reference point): the explicit
    ``steps`` to equilibrium, the road's settlement under each axle [m] (``settlements``,
    mean of the surfacing's top nodes in the tyre patch, from the state under self-weight),
    the largest displacement of a voussoir node from that state (``ring`` [m]) and the
    ``ratios`` (disks, blocks); ``status``: *load reached* when every position
    carried the vehicle, else *mechanism* or *not converged* at ``status.at``."""

    status: RunStatus
    load: float
    positions: list[float] = field(default_factory=list)
    steps: list[int] = field(default_factory=list)
    settlements: list[list[float]] = field(default_factory=list)
    ring: list[float] = field(default_factory=list)
    ratios: list[tuple[float, float]] = field(default_factory=list)
    seconds: float = 0.0

    def line(self) -> str:
        n = len(self.positions)
        if self.status.status is Status.LOAD_REACHED:
            return (f"the vehicle ({self.load / 1e3:.4g} kN) carried at all {n} positions "
                    "(equilibrium at each)")
        return (f"{self.status.status.value} with the vehicle ({self.load / 1e3:.4g} kN) at "
                f"x = {self.status.at:g} m, after {n} position(s) carried: "
                f"{self.status.detail}")


class DiskBridge(DiskFillBridge):
    """``bridge`` with its fill packed by disks (collective on ``comm``).

    Args:
        bridge: the geometry; it needs a ``surfacing`` (see the module doc).
        materials: :class:`~masonry_fdem.materials.Material` per name of
            ``bridge.materials`` (the fill's gives the disks' bulk density; the soil and
            surfacing usually :class:`~masonry_fdem.materials.MohrCoulomb`).
        mortar: the joints between voussoirs and on the skewbacks.
        interface: the fill's friction-only interface (its ``tan_phi`` is the disks'
            friction on the blocks; its ``kn``, ``ks`` those of the soil's and the
            surfacing's interfaces).
        count, porosity, E, nu, friction, rolling_friction, restitution, local_damping,
        seed, inertia_scale, overfill: as :class:`DiskFillBridge`.
        mesh_size: element size [m] per part name ("masonry", "pier", "wall", "surfacing",
            "soil"), or one value.
    """

    BEAM = "surfacing"

    def __init__(self, bridge: Bridge, materials: Mapping, mortar, interface, *,
                 count: int = 6000, porosity: float = 0.2, E: float = 1e8, nu: float = 0.25,
                 friction: float = 0.5, rolling_friction: float = 0.3,
                 restitution: float = 0.5, local_damping: float = 0.7, seed: int = 1,
                 mesh_size: float | Mapping[str, float] = 0.2,
                 inertia_scale: float | None = None, overfill: float = 0.25,
                 comm: MPI.Comm = MPI.COMM_WORLD):
        from masonry_fdem.assessment.bridge import adhesive_interface, fix_soil, part_materials
        from masonry_fdem.assessment.specs import joint_or_contact
        from masonry_fdem.geometry import polygon_area
        from masonry_fdem.geometry.layout import BlockLayout
        from masonry_fdem.interactions import BlockContact, ContactSettings, Joints
        from masonry_fdem.interactions.disks import DiskMaterial
        from masonry_fdem.interactions.disks.fill import pack_polygon, radii_for_count
        from masonry_fdem.model import Model

        if not isinstance(bridge, Bridge):
            raise BridgeError(f"a Bridge is needed, got {type(bridge).__name__}")
        if bridge.spandrel_thickness > 0:
            raise BridgeError("spandrel walls are modelled with a continuum fill only "
                              "(bridge_model): the disks would overlap them in the plane")
        if bridge.backing > 0:
            raise BridgeError("the backing is modelled with a continuum fill only "
                              "(bridge_model): the disks are packed over the bare extrados")
        if bridge.surfacing <= 0:
            raise BridgeError("a bridge with disk fill needs a surfacing (bridge.surfacing "
                              "> 0): the vehicle's tyres bear on it, not on single disks")
        if not 0.0 <= local_damping < 1.0:
            raise ValueError(f"local_damping must lie in [0, 1), got {local_damping}")
        if not overfill >= 0:
            raise ValueError(f"overfill must be >= 0, got {overfill}")
        if interface.kn is None or interface.ks is None:
            raise BridgeError("the fill's interface needs explicit kn and ks")
        m = bridge.materials
        mats = dict(materials)
        needed = {m["masonry"], m["pier"], m["wall"], m["fill"], m["surfacing"]}
        if bridge.soil_depth > 0:
            needed.add(m["soil"])
        missing = sorted(needed - set(mats))
        if missing:
            raise BridgeError(f"no material given for {missing}")
        self.case, self.comm, self.bridge = None, comm, bridge
        self.surfacing = s = float(bridge.surfacing)
        full = bridge.layout()
        self.road = road = bridge.road_level()
        self.fill_top = road - s
        self.fill_polygon = full.polygons[full.names.index("fill")]
        area = polygon_area(self.fill_polygon)
        r_min, r_max = radii_for_count(area, count, porosity)
        depth = self.fill_top - float(self.fill_polygon[:, 1].min())
        self.overfill = overfill * depth
        packed = self.fill_polygon.copy()
        packed[packed[:, 1] >= self.fill_top - 1e-9, 1] += self.overfill
        x, r = pack_polygon(packed, r_min, r_max, porosity, seed=seed)
        # the blocks: the bridge without its fill; the end walls up to the packing's top,
        # the surfacing between them (held above the packing until it settles)
        top = road + self.overfill
        x0, x1 = bridge.deck()
        t, yb = bridge.wall_thickness, bridge.foundation_level
        polys, names, kinds = [], [], []
        for poly, name, mat in zip(full.polygons, full.names, full.materials, strict=True):
            if name in ("fill", "surfacing"):
                continue
            if name == "wall:left":
                poly = np.array([(x0 - t, yb), (x0, yb), (x0, top), (x0 - t, top)])
            elif name == "wall:right":
                poly = np.array([(x1, yb), (x1 + t, yb), (x1 + t, top), (x1, top)])
            polys.append(poly)
            names.append(name)
            kinds.append(mat)
        a, b = x0 + 0.01, x1 - 0.01
        self.slab = np.array([(a, top - s), (b, top - s), (b, top), (a, top)])
        polys.append(self.slab)
        names.append(self.BEAM)
        kinds.append(m["surfacing"])
        # the piers and the end walls by material names of their own (their joints)
        layout, mats, m = part_materials(bridge, BlockLayout(tuple(polys), tuple(kinds),
                                                             tuple(names)), mats)
        self.layout = layout
        part = {v: k for k, v in m.items()}
        if isinstance(mesh_size, Mapping):
            # each block's part by its name (parts may share a material); the road slab
            # by its material
            sizes = [float(mesh_size.get(bridge.part_of(n) or part.get(mat, "masonry"), 0.2))
                     for n, mat in zip(layout.names, layout.materials, strict=True)]
        else:
            sizes = [float(mesh_size)] * len(layout)
        hyp = {name: "plane_strain" for name in (m["surfacing"], m["soil"]) if name in
               layout.materials}
        model = Model(layout.mesh(sizes, comm), mats, hypotheses=hyp, width=bridge.width,
                      comm=comm)
        model.fix_blocks("wall:*", name="walls")
        fix_soil(model, bridge)
        for n in bridge.foundations():  # one prescription each: each one's reaction
            if not bridge.on_soil(n):
                model.fix_blocks(n, name=n)
        model.add_gravity()
        # the interactions of the blocks, as bridge_model has them (the fill aside): the
        # masonry's mortar, dry contact of the piers and end walls, the soil's
        # friction-only interface, the piers and abutments bonded on the soil
        table: dict = {(m["masonry"], m["masonry"]): mortar, (m["masonry"], m["pier"]): mortar,
                       (m["pier"], m["pier"]): None, (m["pier"], m["wall"]): None}
        present = set(layout.materials)
        for soft in (m["surfacing"], m["soil"]):
            if soft in present:
                for o in present - {soft}:
                    table[tuple(sorted((soft, o)))] = interface
        if m["soil"] in present:
            table[tuple(sorted((m["soil"], m["pier"])))] = adhesive_interface(
                interface, mats[m["soil"]])
        fric = {pair: jm.tan_phi for pair, jm in table.items() if jm is not None
                and pair not in {(m["masonry"], m["masonry"]), (m["masonry"], m["pier"])}}
        contact = BlockContact(model, ContactSettings(friction=mortar.tan_phi,
                                                      friction_table=fric))
        joints = Joints(model, {k: joint_or_contact(v) for k, v in table.items()},
                        contact=contact)
        rho = mats[m["fill"]].density
        mat = DiskMaterial(density=rho / (1.0 - porosity), E=E, nu=nu, friction=friction,
                           restitution=restitution, rolling_friction=rolling_friction)

        # held while the fill settles: every block that is not fixed already
        held = {"voussoir:*", self.BEAM} | {n for n in bridge.foundations()
                                             if bridge.on_soil(n)}
        held |= {"pier:*"} if bridge.piers else set()
        held |= {"soil"} if bridge.soil_depth > 0 else set()
        self._attach(model, [contact, joints], x, r, mat, width=bridge.width,
                     friction=interface.tan_phi, local_damping=local_damping,
                     inertia_scale=inertia_scale,
                     held=[(sorted(held), "held while the fill settles")])
        # the surfacing plays the single span's loading beam (lowered onto the disks; its
        # mean settlement is the beam's)
        slab = np.flatnonzero(np.isin(model.node_block,
                                      model.select_blocks(self.BEAM))).astype(np.int64)
        self.beam_nodes = self._top_nodes = slab
        self._top_range = (a, b)
        self._n_beam = comm.allreduce(int(slab.size))
        # the surfacing's top nodes (reference coordinates), for the axles' settlement
        X = model.X
        on_top = np.isclose(X[self.beam_nodes, 1], top, atol=1e-9 * max(1.0, abs(top)))
        self._road_nodes = self.beam_nodes[on_top]
        self.ring_thickness = min(sp.ring_thickness * sp.rings for sp in bridge.spans)
        self.axles: list[tuple[float, float]] = []  # (x, load [N]) now on the road
        self._patch = 0.0

    def _guide(self) -> None:
        """The surfacing lies free on the disks (no guide)."""

    # ------------------------------------------------------------------ the vehicle
    def put_vehicle(self, vehicle, x: float, load: float) -> None:
        """The vehicle's axles at reference point ``x`` [m], ``load`` [N] in all, as
        uniform pressures over their tyre patches on the surfacing's top (replacing any
        vehicle on the road; collective). Sets the model's live load to the vehicle
        with a total of 1 N, and the solver's external force to dead + ``load`` times
        it."""
        half = 0.5 * vehicle.patch
        axles = vehicle.axles(x)
        for k, (xa, _) in enumerate(axles):
            self.bridge.check_on_deck(xa, half, f"axle {k} of the vehicle")
            if not (self._top_range[0] <= xa - half and xa + half <= self._top_range[1]):
                raise BridgeError(f"axle {k} of the vehicle at x = {xa:g} m overhangs the "
                                  "surfacing's ends")
        if not (math.isfinite(load) and load > 0):
            raise ValueError(f"the vehicle's load must be > 0 N, got {load}")
        model = self.model
        # the consistent nodal forces of a uniform pressure over each patch on the
        # surfacing's top edge (linear elements): its nodes' x gathered from every rank
        mine = model.X[self._road_nodes, 0]
        xs = np.unique(np.concatenate(self.comm.allgather(mine)))
        f = np.zeros(xs.size)
        for xa, share in axles:
            a, b = xa - half, xa + half
            q = share / (b - a)  # [N/m] for a unit vehicle
            for k in range(xs.size - 1):
                x0, x1 = xs[k], xs[k + 1]
                lo, hi = max(a, x0), min(b, x1)
                if hi <= lo:
                    continue
                h = x1 - x0
                # ∫ N_k and ∫ N_k+1 over [lo, hi], N_k = (x1 − x)/h
                ik = ((x1 - lo) ** 2 - (x1 - hi) ** 2) / (2.0 * h)
                f[k] += q * ik
                f[k + 1] += q * ((hi - lo) - ik)
        model.f_live[:] = 0.0
        idx = np.searchsorted(xs, mine)
        model.f_live[2 * self._road_nodes + 1] = -f[idx]
        self.axles = [(xa, share * load) for xa, share in axles]
        self._patch = vehicle.patch
        if self.solver is not None:
            self.solver.load_factor = load
            model.external_force(load, out=self.solver.f_ext)

    def axle_settlements(self, ref: np.ndarray) -> list[float]:
        """The road's mean downward displacement [m] under each axle's patch since the
        displacements ``ref`` (the model's u at an earlier state; collective)."""
        u = self.model.u.x.array
        X = self.model.X
        out = []
        half = 0.5 * self._patch
        for xa, _ in self.axles:
            nodes = self._road_nodes[np.abs(X[self._road_nodes, 0] - xa) <= half + 1e-9]
            s = float((u[2 * nodes + 1] - ref[2 * nodes + 1]).sum())
            tot, cnt = self.comm.allreduce(np.array([s, float(nodes.size)]))
            out.append(-tot / cnt if cnt else math.nan)
        return out

    def road_profile(self) -> np.ndarray:
        """``(n, 2)`` [m]: the road (the surfacing's top nodes) as deformed now, sorted by
        x, the same on every rank (collective)."""
        X = self.model.X[self._road_nodes]
        u = self.model.u.x.array
        mine = X + np.column_stack([u[2 * self._road_nodes], u[2 * self._road_nodes + 1]])
        pts = np.concatenate([np.reshape(a, (-1, 2)) for a in self.comm.allgather(mine)])
        pts = pts[np.argsort(pts[:, 0], kind="stable")]
        # a node shared by two ranks appears twice: keep one
        keep = np.ones(pts.shape[0], dtype=bool)
        keep[1:] = np.any(np.abs(np.diff(pts, axis=0)) > 1e-12, axis=1)
        return pts[keep]

    def traverse(self, vehicle, positions: Sequence[float], load: float, *,
                 tol: float = 1e-3, max_steps: int = 300_000, every: int = 500,
                 runaway: float | None = None, ramp: int = 4,
                 callback=None) -> DiskTraverse:
        """Stage 3 of the module doc (collective): the vehicle at ``load`` [N] moved through
        ``positions`` [m], equilibrium at each. :meth:`settle` first.

        Args:
            vehicle: a :class:`~masonry_fdem.assessment.bridge.Vehicle`.
            positions: x [m] of its reference point, in the order driven.
            load: the vehicle's total load [N] (over the bridge's width).
            tol, max_steps, every: as :meth:`DiskFillBridge.load`.
            runaway: a voussoir's travel [m] under one constant load that proves no
                equilibrium (default: a quarter of the thinnest ring).
            ramp: at the first position the load is raised in this many equal steps.
            callback: ``callback(bridge, x)`` after each position's equilibrium.

        Raises:
            RuntimeError: the bridge has not settled under self-weight.
            BridgeError: an axle off the deck (checked for every position first).
        """
        if not self.settled:
            raise RuntimeError("the disk fill has not settled under self-weight: call "
                               "settle() first (and check that it returns True)")
        positions = [float(x) for x in positions]
        if not positions:
            raise ValueError("no positions to traverse")
        half = 0.5 * vehicle.patch
        for x in positions:
            for k, (xa, _) in enumerate(vehicle.axles(x)):
                self.bridge.check_on_deck(xa, half, f"at x = {x:g} m, axle {k} of the "
                                                    "vehicle")
        if not (isinstance(ramp, int) and ramp >= 1):
            raise ValueError(f"ramp must be an integer >= 1, got {ramp!r}")
        if not 0 < tol < 1:
            raise ValueError(f"tol must lie in (0, 1), got {tol}")
        runaway = 0.25 * self.ring_thickness if runaway is None else float(runaway)
        if not runaway > 0:
            raise ValueError(f"runaway must be > 0 m, got {runaway}")
        t0 = time.perf_counter()
        ref = self.model.u.x.array.copy()  # the state under self-weight
        ring_ref = self.ring_state()
        run = DiskTraverse(RunStatus(Status.LOAD_REACHED, load, load), float(load))
        for i, x in enumerate(positions):
            stages = [load * (j + 1) / ramp for j in range(ramp)] if i == 0 else [load]
            steps = 0
            for p in stages:
                self.put_vehicle(vehicle, x, p)
                why, n, ring, _ = self._equilibrate(tol=tol, max_steps=max_steps,
                                                    every=every, runaway=runaway)
                steps += n
                if why != "equilibrium":
                    break
            if why != "equilibrium":
                rd, rb = self.ratios()
                carried = load if run.positions else 0.0
                if why == "runaway":
                    run.status = RunStatus(
                        Status.MECHANISM, carried, carried, at=x,
                        detail=(f"no equilibrium with {p / 1e3:.4g} kN at x = {x:g} m: the "
                                f"ring ran {ring * 1e3:.1f} mm in {n} steps (ratios: disks "
                                f"{rd:.1e}, blocks {rb:.1e})"))
                else:
                    run.status = RunStatus(
                        Status.NOT_CONVERGED, carried, carried, at=x,
                        detail=(f"explicit: ratios disks {rd:.1e}, blocks {rb:.1e} after "
                                f"{n} steps with {p / 1e3:.4g} kN at x = {x:g} m (tol "
                                f"{tol:g}); the ring moved {ring * 1e3:.2f} mm"))
                break
            run.positions.append(x)
            run.steps.append(steps)
            run.settlements.append(self.axle_settlements(ref))
            run.ring.append(self.ring_motion(ring_ref))
            run.ratios.append(self.ratios())
            self.last_steps = steps
            if callback is not None:
                callback(self, x)
        run.seconds = time.perf_counter() - t0
        return run

    def collapse(self, vehicle, x: float, increment: float, *, max_load: float = math.inf,
                 tol: float = 1e-3, max_steps: int = 300_000, every: int = 500,
                 runaway: float | None = None, callback=None):
        """The vehicle at ``x`` [m], its total load raised in steps of ``increment`` [N],
        each held to equilibrium, until the ring runs on (*mechanism*), ``max_load`` is
        carried (*load reached*) or an equilibrium does not come within ``max_steps``
        (*not converged*); collective. :meth:`settle` first.

        Returns a :class:`~masonry_fdem.assessment.disk_fill.DiskFillRun`: the loads
        carried against the road's settlement under the vehicle (its axles' settlements
        weighted by their shares, from the state under self-weight) [m]; its
        ``collapse_load`` is the last load carried when the run ends in a mechanism.
        ``runaway`` [m]: as :meth:`traverse`; ``callback(bridge, load)`` after each
        equilibrium.
        """
        if not self.settled:
            raise RuntimeError("the disk fill has not settled under self-weight: call "
                               "settle() first (and check that it returns True)")
        if not (math.isfinite(increment) and increment > 0):
            raise ValueError(f"increment must be > 0 N, got {increment}")
        ref = self.model.u.x.array.copy()
        self.put_vehicle(vehicle, x, increment)  # (checks the axles on the deck)
        shares = [w for _, w in vehicle.axles(x)]

        def settlement() -> float:
            return sum(s * w for s, w in zip(self.axle_settlements(ref), shares, strict=True))

        def at(br, load: float) -> None:
            br.axles = [(xa, w * load) for (xa, _), w in zip(br.axles, shares, strict=True)]
            if callback is not None:
                callback(br, load)

        return self._raise_load(increment, settlement, max_load=max_load, tol=tol,
                                max_steps=max_steps, every=every,
                                runaway=0.25 * self.ring_thickness if runaway is None
                                else runaway, callback=at, mover="the road")


def draw_bridge_stress(b: DiskBridge, grid, disks, path, *, title: str = "",
                       road: np.ndarray | None = None) -> None:
    """Draw :func:`~masonry_fdem.assessment.disk_fill.stress_grid` ``grid`` (compression
    positive, kPa), the disks ``(x, r)``, the blocks' outlines (undeformed) and the
    vehicle's axles now on the road, into the PNG ``path`` (call on one rank). ``road``:
    :meth:`DiskBridge.road_profile` of the same state, drawn as the deformed road (true
    scale), the axles standing on it."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import PatchCollection
    from matplotlib.patches import Circle, Polygon

    xs, ys, sig = grid
    span = float(xs[-1] - xs[0])
    fig, ax = plt.subplots(figsize=(max(8.0, 0.85 * span), 4.6))
    kpa = -sig / 1e3
    top = float(np.nanpercentile(kpa, 98)) if np.isfinite(kpa).any() else 1.0
    mesh = ax.pcolormesh(xs, ys, np.ma.masked_invalid(kpa), cmap="magma_r", shading="flat",
                         vmin=0.0, vmax=max(top, 1e-9))
    # the cells drawn within the fill's outline only (not over the blocks they overlap)
    mesh.set_clip_path(Polygon(b.fill_polygon, closed=True, transform=ax.transData))
    fig.colorbar(mesh, ax=ax, extend="max", label="σ_yy in the fill, compression [kPa]",
                 fraction=0.025, pad=0.01)
    ax.add_collection(PatchCollection([Circle(c, r) for c, r in zip(*disks, strict=True)],
                                      facecolor="none", edgecolor="0.55", linewidths=0.15))
    y_road = b.surface + b.surfacing
    for name, poly in zip(b.layout.names, b.layout.polygons, strict=True):
        if name == b.BEAM:  # drawn where it was lowered to, over the cells it shares
            poly = poly - [0.0, float(poly[:, 1].min()) - b.surface]
        ax.add_patch(Polygon(poly, closed=True, facecolor="0.85", edgecolor="k", lw=0.4,
                             zorder=2))
    if road is not None:
        ax.plot(road[:, 0], road[:, 1], "-", color="C0", lw=1.4, zorder=4,
                label="the road, deformed (true scale)")
        ax.legend(loc="upper right", fontsize=8)
    half = 0.5 * b._patch
    for xa, p in b.axles:
        y = y_road if road is None else float(np.interp(xa, road[:, 0], road[:, 1]))
        ax.add_patch(Polygon([[xa - half, y], [xa + half, y], [xa + half, y + 0.06],
                              [xa - half, y + 0.06]], closed=True, facecolor="C0", zorder=4))
        ax.annotate(f"{p / 1e3:.0f} kN", xy=(xa, y + 0.07), xytext=(xa, y_road + 1.0),
                    ha="center", arrowprops=dict(arrowstyle="-|>", color="C3", lw=2),
                    zorder=4)
    # the soil (if any) cropped a metre below the foundations: the fill is the subject
    lo = max(min(float(p[:, 1].min()) for p in b.layout.polygons),
             b.bridge.foundation_level - 1.0)
    ax.set_aspect("equal")
    ax.set_xlim(min(float(p[:, 0].min()) for p in b.layout.polygons) - 0.2,
                max(float(p[:, 0].max()) for p in b.layout.polygons) + 0.2)
    ax.set_ylim(lo, y_road + 1.3)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(title + f" (cells {xs[1] - xs[0]:.2f} m; colours clipped at the 98th "
                 "percentile)", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=130, bbox_inches="tight")
    plt.close(fig)
