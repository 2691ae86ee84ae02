"""An arch case's fill as disks, loaded quasi-statically to collapse (issue #22, item 4:
the reference paper's way of modelling a bridge's fill).

The arch of an :class:`~masonry_fdem.assessment.case.ArchCase` with ``[fill]`` (its
voussoirs, mortar joints and block contact as :func:`~masonry_fdem.assessment.assess.build_model`
has them), with the fill region packed by rigid disks instead of the Mohr–Coulomb
continuum (:func:`~masonry_fdem.interactions.disks.fill.fill_disks`; the disks' solid
density is the fill's bulk density over 1 − porosity), two fixed end walls, and a guided
loading beam on the road at the case's load position (``loading.spreader_width`` wide),
bearing on the disks or, optionally, on a road layer (``surfacing``) over them. Disks
touch the blocks through :class:`~masonry_fdem.interactions.DiskBlockContact`
with the fill's interface friction tan δ.

Why explicit dynamics and not Newton: a disk packing has no tangent worth the name (its
contacts open, close and slip by the thousand, and rattlers have none), so equilibrium
is found as the reference paper finds it: central differences with Cundall's local
non-viscous damping (``local_damping``, 0.7) until the unbalanced-force ratio falls below
``tol`` — the disks' (mean |m g + f| over mean |m g| of the disks with two contacts or
more: rattlers left out, :meth:`Disks.unbalanced_ratio`) and the free block dofs'
(Σ|f_ext + f_con − f_int| over Σ|f_int|: the unbalanced force against the forces the
blocks carry, the fill's thrust among them — over their weight alone, the disks' contact
noise on the extrados would never let it fall).

Stages (:meth:`DiskFillBridge.settle`, :meth:`DiskFillBridge.load`):

1. the fill settles under gravity on the held arch and beneath the held beam (every
   block fixed: the disks' own time step; the arch, far stiffer, hardly moves);
2. the voussoirs are released on their joints and the beam is guided (vertical motion
   only); the whole settles again under self-weight;
3. the beam's load rises in equal steps of ``increment`` [N], each held until the
   ratios fall below ``tol``: that load is carried, an equilibrium. A load at which
   instead the ring runs on — a voussoir moves ``runaway`` [m] under the constant load
   (default: a quarter of the ring thickness) — has no equilibrium: the structure is a
   mechanism, status
   *mechanism*, and its collapse load is the last load carried, within one increment
   (below). A load at which neither happens within ``max_steps`` is *not converged*:
   the last load carried is a lower bound only. The beam sinking into the fill (a
   bearing failure of a cohesionless packing under a narrow beam, which finds its
   bearing again some tenths of a metre down) is not a mechanism of the bridge.

Units: SI (N, m, s, kg). The loads are over the case's barrel ``width``.
"""

from __future__ import annotations

import math
import shutil
import time
from dataclasses import dataclass, field, replace
from pathlib import Path

from mpi4py import MPI

import numpy as np

from masonry_fdem.interactions.protocol import BLOCKS
from masonry_fdem.solvers.status import RunStatus, Status

__all__ = ["DiskFillBridge", "DiskFillRun", "assess_disk_fill", "draw_stress", "stress_grid"]


@dataclass
class DiskFillRun:
    """Result of :meth:`DiskFillBridge.load`: ``status``; ``loads`` [N] carried (each an
    equilibrium; the first is 0, self-weight only) against ``displacements`` [m] (the
    beam's settlement under the live load, positive down); ``steps`` and ``ratios``
    (disks', blocks') per load; ``moved``, ``ring_moved`` [m]: how far the beam and the
    ring (its largest voussoir displacement) ran at the last load tried; ``seconds`` of
    wall time."""

    status: RunStatus
    increment: float
    loads: list[float] = field(default_factory=list)
    displacements: list[float] = field(default_factory=list)
    steps: list[int] = field(default_factory=list)
    ratios: list[tuple[float, float]] = field(default_factory=list)
    moved: float = 0.0
    ring_moved: float = 0.0
    seconds: float = 0.0

    @property
    def collapse_load(self) -> float | None:
        """The collapse load [N] if the run proved one (the last load carried; the
        structure had no equilibrium one increment above it), else None."""
        return self.status.collapse_load

    def line(self) -> str:
        """The outcome in words, in kN."""
        return self.status.describe("kN", 1e3, ".1f")


class DiskFillBridge:
    """An arch case with its ``[fill]`` packed by disks (collective on ``comm``).

    Args:
        case: an :class:`~masonry_fdem.assessment.case.ArchCase` with ``[fill]`` (its cover,
            bulk density from the fill material, interface friction) and ``[loading]``
            (position, spreader width).
        count: disks asked of the packer (some 5–25 % fewer are kept along the edges).
        porosity: of the packing; the disks' solid density is ρ_fill / (1 − porosity).
        E, nu, friction, rolling_friction, restitution: the disks'
            (:class:`~masonry_fdem.interactions.disks.DiskMaterial`); E [Pa].
        local_damping: Cundall's α, on every dof set.
        seed: of the packing (the same on every rank).
        mesh_size: of the blocks [m] (default the case's ``arch.mesh_size``).
        inertia_scale: density scaling of the blocks (:meth:`Model.scale_inertia`, their
            weight kept); default: the factor that gives the blocks the disks' stable
            step (none if theirs is longer already). 1: none. Quasi-static only.
        overfill: the region is packed this fraction of the fill's depth above the road,
            settled on the held arch, and the disks whose centres then lie above the road
            removed (a loose packing settles; the road stays where the case has it).
        surfacing: thickness [m] of a road layer on the disks (default none: the beam
            bears on the disks), part of the case's ``cover``: one block from end wall to
            end wall (1 cm clear of each), in plane strain, touching the disks with the
            fill's interface friction and the beam with the block contact's.
        surfacing_material: its :class:`~masonry_fdem.materials.Material` (e.g. a
            :class:`~masonry_fdem.materials.MohrCoulomb` road base), needed with a
            surfacing.

    Raises:
        ValueError: the case has no ``[fill]``, or bad packing input.
    """

    BEAM = "spreader"

    def __init__(self, case, *, count: int = 5600, porosity: float = 0.2, E: float = 1e8,
                 nu: float = 0.25, friction: float = 0.5, rolling_friction: float = 0.3,
                 restitution: float = 0.5, local_damping: float = 0.7, seed: int = 1,
                 mesh_size: float | None = None, inertia_scale: float | None = None,
                 overfill: float = 0.25, surfacing: float = 0.0, surfacing_material=None,
                 comm: MPI.Comm = MPI.COMM_WORLD):
        from masonry_fdem.assessment.specs import SPREADER, joint_or_contact
        from masonry_fdem.geometry import polygon_area
        from masonry_fdem.geometry.fill import fill_layout
        from masonry_fdem.geometry.layout import BlockLayout
        from masonry_fdem.interactions import BlockContact, Joints
        from masonry_fdem.interactions.disks import DiskMaterial
        from masonry_fdem.interactions.disks.fill import fill_disks, radii_for_count
        from masonry_fdem.model import Model

        if case.fill is None:
            raise ValueError("a disk fill needs a case with [fill] (its cover, material "
                             "and interface friction)")
        if not 0.0 <= local_damping < 1.0:
            raise ValueError(f"local_damping must lie in [0, 1), got {local_damping}")
        self.case, self.comm = case, comm
        fill = case.fill
        if not (math.isfinite(surfacing) and 0.0 <= surfacing < fill.cover):
            raise ValueError(f"surfacing must be >= 0 m and thinner than the cover "
                             f"{fill.cover:g} m, got {surfacing}")
        if surfacing > 0 and surfacing_material is None:
            raise ValueError("a surfacing needs its surfacing_material")
        self.surfacing = float(surfacing)
        structure = case.layout()
        below = fill.cover - self.surfacing  # the disks' cover over the crown
        self.fill_polygon = fill_layout(structure, cover=below,
                                        wall_thickness=fill.wall_thickness).polygons[0]
        area = polygon_area(self.fill_polygon)
        r_min, r_max = radii_for_count(area, count, porosity)
        self.road = case.road_level()
        self.fill_top = self.road - self.surfacing
        # packed higher than its top (a loose packing settles by a sixth of its depth),
        # settled, then trimmed to it: a fill whose surface is where the case has it
        depth = self.fill_top - float(self.fill_polygon[:, 1].min())
        if not overfill >= 0:
            raise ValueError(f"overfill must be >= 0, got {overfill}")
        self.overfill = overfill * depth
        x, r, walls = fill_disks(structure, cover=below + self.overfill, r_min=r_min,
                                 r_max=r_max, porosity=porosity, seed=seed,
                                 wall_thickness=fill.wall_thickness)
        xl, half = case.load_x(), 0.5 * case.loading.spreader_width
        name, t, _ = SPREADER
        top = self.road + self.overfill  # the beam (and surfacing) wait above the packing
        beam = np.array([[xl - half, top], [xl + half, top], [xl + half, top + t],
                         [xl, top + t], [xl - half, top + t]])
        layout = structure + walls + BlockLayout((beam,), (name,), (name,))
        top_layer = [name]
        if self.surfacing > 0:
            x0 = float(self.fill_polygon[:, 0].min()) + 0.01
            x1 = float(self.fill_polygon[:, 0].max()) - 0.01
            if not (x0 < xl - half and xl + half < x1):
                raise ValueError("the loading beam overhangs the surfacing's ends")
            y0 = top - self.surfacing
            slab = np.array([[x0, y0], [x1, y0], [x1, top], [xl + half, top],
                             [xl - half, top], [x0, top]])
            layout = layout + BlockLayout((slab,), ("surfacing",), ("surfacing",))
            top_layer.append("surfacing")
        self.layout = layout
        h = case.arch.mesh_size if mesh_size is None else float(mesh_size)
        sizes = [0.5 * t if n == name else fill.wall_thickness if n.startswith("wall:")
                 else 0.5 * self.surfacing if n == "surfacing" else h for n in layout.names]
        # the beam of the voussoirs' material, not the continuum case's steel: its
        # stiffness hardly matters to the load it spreads, and steel's would set the
        # block contact's penalty, and so the time step, eight times shorter
        mats = dict(case.material_table)
        mats[name] = mats[case.arch.voussoir_material]
        hyp = {}
        if self.surfacing > 0:
            mats["surfacing"] = surfacing_material
            hyp["surfacing"] = "plane_strain"
        model = Model(layout.mesh(sizes, comm), mats, hypotheses=hyp, width=case.arch.width,
                      comm=comm)
        model.fix_blocks("abutment:*", name="abutments")
        model.fix_blocks("wall:*", name="walls")
        model.add_gravity()
        # the load: a unit force at the middle of the beam's top, scaled by the solver's
        # load factor (the factor is the load [N])
        model.add_point_load((xl, top + t), (0.0, -1.0), blocks=name)
        contact = BlockContact(model, case.analysis.contact_settings())
        jm = case.joint_materials()
        v, a = case.arch.voussoir_material, case.arch.abutment_material

        table = {(v, v): joint_or_contact(jm[(v, v)]), (v, a): joint_or_contact(jm[(v, a)]),
                 (a, a): None}
        if self.surfacing > 0:
            table[(name, "surfacing")] = None  # the beam on the road: block contact
        joints = Joints(model, table, where=[(w, joint_or_contact(m)) for w, m in
                                              case.joint_rules(structure)],
                        contact=contact)
        rho = case.materials()[fill.material].density
        mat = DiskMaterial(density=rho / (1.0 - porosity), E=E, nu=nu, friction=friction,
                           restitution=restitution, rolling_friction=rolling_friction)

        self._attach(model, [contact, joints], x, r, mat, width=case.arch.width,
                     friction=fill.interface_friction, local_damping=local_damping,
                     inertia_scale=inertia_scale,
                     held=[("voussoir:*", "arch"), (top_layer, "beam held")])
        self.beam_nodes = np.flatnonzero(np.isin(model.node_block,
                                                 model.select_blocks(name))).astype(np.int64)
        self._top_nodes = np.flatnonzero(np.isin(
            model.node_block, model.select_blocks(top_layer))).astype(np.int64)
        self._top_range = ((xl - half, xl + half) if self.surfacing == 0
                           else (float(slab[0, 0]), float(slab[1, 0])))
        self._n_beam = comm.allreduce(int(self.beam_nodes.size))

    def _attach(self, model, blocks, x, r, mat, *, width: float, friction: float,
                local_damping: float, inertia_scale: float | None, held) -> None:
        """Shared by the constructors: the disks ``(x, r)`` of ``mat`` under gravity,
        touching the blocks with ``friction``; the blocks' density scaling; the blocks
        ``held`` (``(selection, name)`` pairs) while the fill settles; the voussoirs'
        dofs; the state before :meth:`settle`."""
        from masonry_fdem.interactions import DiskBlockContact
        from masonry_fdem.interactions.disks import Disks

        comm = self.comm

        def make(x, r):
            disks = Disks(x, r, {"fill": mat}, "fill", width=width, comm=comm)
            disks.add_gravity()
            return disks, DiskBlockContact(disks, model, friction=friction)

        self._make_disks = make
        self.model, self.blocks = model, blocks
        self.disks, self.coupling = make(x, r)
        self.local_damping = float(local_damping)
        # density scaling of the blocks (their weight kept): the block contact's penalty
        # sets a step tens of times shorter than the disks', and the fill then creeps to
        # rest over millions of steps; blocks as slow as the disks share their step
        st = self._solver(True).stability
        auto = (st["disks"].dt / st[BLOCKS].dt) ** 2
        self.inertia_scale = max(1.0, auto) if inertia_scale is None else float(inertia_scale)
        model.scale_inertia(self.inertia_scale)
        self._held = [model.fix_blocks(sel, name=name) for sel, name in held]
        ring_nodes = np.flatnonzero(np.isin(model.node_block,
                                            model.select_blocks("voussoir:*")))
        self._ring_dofs = np.column_stack([2 * ring_nodes, 2 * ring_nodes + 1]).ravel()
        self.solver = None
        self.last_steps = 0  # explicit steps of the last load carried
        self.settled = False
        self.trimmed = 0
        self.surface = math.nan

    @classmethod
    def from_case(cls, case, comm: MPI.Comm = MPI.COMM_WORLD) -> DiskFillBridge:
        """The bridge as the case file's ``[fill] model = "disks"`` and ``[fill.disks]``
        ask (:class:`~masonry_fdem.assessment.specs.DiskFillSpec`; its defaults without
        them)."""
        from masonry_fdem.assessment.specs import DiskFillSpec

        if case.fill is None:
            raise ValueError("a disk fill needs a case with [fill]")
        d = case.fill.disks or DiskFillSpec()
        road = case.materials()[d.surfacing_material] if d.surfacing > 0 else None
        return cls(case, count=d.count, porosity=d.porosity, E=d.E, nu=d.nu,
                   friction=d.friction, rolling_friction=d.rolling_friction,
                   restitution=d.restitution, local_damping=d.local_damping, seed=d.seed,
                   surfacing=d.surfacing, surfacing_material=road, comm=comm)

    # ------------------------------------------------------------------ state
    def beam_settlement(self) -> float:
        """The beam's mean downward displacement [m] (collective)."""
        u = self.model.u.x.array
        s = float(u[2 * self.beam_nodes + 1].sum())
        return -self.comm.allreduce(s) / self._n_beam

    def ratios(self) -> tuple[float, float]:
        """``(disks, blocks)`` unbalanced-force ratios of the last step (collective)."""
        rd = self.disks.unbalanced_ratio([self.coupling])
        b = self.solver.sets[0]
        free = b.presc == 0
        g = float(np.abs(b.f_ext + b.f_con - b.f_int)[free].sum())
        w = float(np.abs(b.f_int)[free].sum())
        g, w = self.comm.allreduce(np.array([g, w]))
        return rd, (float(g / w) if w > 0 else 0.0)

    def _solver(self, blocks: bool):
        """An explicit solver of the disks, the disk–block contact and (``blocks``) the
        voussoirs' contact and joints, from the model's present prescriptions."""
        from masonry_fdem.solvers import ExplicitSolver

        inter = [self.disks, self.coupling] + (self.blocks if blocks else [])
        return ExplicitSolver(self.model, interactions=inter, load_factor=0.0,
                              local_damping=self.local_damping)

    def ring_state(self) -> np.ndarray:
        """This rank's voussoir displacements now [m] (a ``ref`` for :meth:`ring_motion`)."""
        return self.model.u.x.array[self._ring_dofs].copy()

    def ring_motion(self, ref: np.ndarray) -> float:
        """The largest displacement [m] of a voussoir node since the state whose
        displacements are ``ref`` (this rank's voussoir dofs; collective)."""
        u = self.model.u.x.array[self._ring_dofs].reshape(-1, 2) - ref.reshape(-1, 2)
        local = float(np.sqrt((u * u).sum(axis=1)).max(initial=0.0))
        return self.comm.allreduce(local, op=MPI.MAX)

    def _equilibrate(self, *, tol: float, max_steps: int, every: int,
                     runaway: float = math.inf) -> tuple[str, int, float, float]:
        """Run until both ratios are below ``tol`` ("equilibrium"), a voussoir has moved
        ``runaway`` [m] ("runaway": the ring running on, not the beam sinking into the
        fill) or ``max_steps`` ("steps"). Returns the outcome, the steps taken, and how
        far the ring and the beam moved [m]."""
        watch = math.isfinite(runaway)
        start = self.beam_settlement()
        ref = self.model.u.x.array[self._ring_dofs].copy()
        out = {"why": "steps"}

        def check(s) -> bool:
            rd, rb = self.ratios()
            if rd < tol and rb < tol:
                out["why"] = "equilibrium"
                return True
            if watch and self.ring_motion(ref) > runaway:
                out["why"] = "runaway"
                return True
            return False

        steps = self.solver.run(steps=max_steps, every=every, until=check)
        return out["why"], steps, self.ring_motion(ref), self.beam_settlement() - start

    def _lower_beam_onto_fill(self) -> None:
        """Move the beam (and the surfacing) down onto the settled disks under it (a
        hundredth of the smallest radius above the highest of them), so that it does not
        fall."""
        x, r = self.disks.x, self.disks.r
        a, b = self._top_range
        dx = np.maximum(np.maximum(a - x[:, 0], x[:, 0] - b), 0.0)
        under = dx < r
        if not under.any():
            raise RuntimeError("no disk under the loading beam after the fill settled")
        top = float(np.max(x[under, 1] + np.sqrt(r[under] ** 2 - dx[under] ** 2)))
        self.surface = top
        shift = top + 0.01 * float(r.min()) - self.fill_top - self.overfill
        u = self.model.u.x.array
        u[2 * self._top_nodes + 1] += shift
        self.model.u.x.scatter_forward()

    def _guide(self) -> None:
        """Once the blocks are released: the loading beam guided (vertical motion only)."""
        self.model.prescribe_velocity(self.BEAM, (0.0, None), name="beam guide")

    def settle(self, *, tol: float = 1e-3, max_steps: int = 200_000,
               every: int = 500) -> bool:
        """Stages 1 and 2 of the module doc (collective). Returns whether both reached
        equilibrium (ratios below ``tol``)."""
        self.solver = self._solver(False)
        why1, self.steps_held, _, _ = self._equilibrate(tol=tol, max_steps=max_steps,
                                                       every=every)
        if self.overfill > 0 and why1 == "equilibrium":
            keep = self.disks.x[:, 1] <= self.fill_top
            self.trimmed = int(self.disks.n - keep.sum())
            self.disks, self.coupling = self._make_disks(self.disks.x[keep],
                                                         self.disks.r[keep])
            self.solver = self._solver(False)
            why1, more, _, _ = self._equilibrate(tol=tol, max_steps=max_steps, every=every)
            self.steps_held += more
        for p in self._held:
            self.model.prescriptions.remove(p)
        self._lower_beam_onto_fill()
        self._guide()
        self.solver = self._solver(True)
        why2, self.steps_free, _, _ = self._equilibrate(tol=tol, max_steps=max_steps,
                                                       every=every)
        self.settled = why1 == why2 == "equilibrium"
        self.dead_settlement = self.beam_settlement()
        return self.settled

    def load(self, increment: float, *, max_load: float = math.inf, tol: float = 1e-3,
             max_steps: int = 600_000, every: int = 500, runaway: float | None = None,
             callback=None) -> DiskFillRun:
        """Stage 3 of the module doc (collective): the beam's load [N] in steps of
        ``increment`` to collapse, ``max_load`` or no equilibrium. :meth:`settle` first.

        Args:
            increment: load step [N] (whole barrel width).
            max_load: stop after carrying this load [N] (status *load reached*).
            tol: unbalanced-force ratio of an equilibrium (disks and blocks).
            max_steps: explicit steps allowed per load.
            every: steps between ratio checks.
            runaway: the ring's travel [m] (its largest voussoir displacement) under one
                constant load that proves no equilibrium (default: a quarter of the ring
                thickness). The ring's, not the beam's: a beam on a cohesionless fill
                sinks into it by tenths of a metre before it finds its bearing, and the
                load is then carried (a footing gains capacity with its depth).
            callback: ``callback(bridge, load)`` after each equilibrium (pictures, output).

        Raises:
            RuntimeError: the bridge has not settled under self-weight (:meth:`settle`).
            ValueError: a bad increment, tol or runaway.
        """
        ring_t = self.case.arch.ring_thickness
        return self._raise_load(increment, lambda: self.beam_settlement() - self.dead_settlement,
                                max_load=max_load, tol=tol, max_steps=max_steps, every=every,
                                runaway=0.25 * ring_t if runaway is None else runaway,
                                callback=callback, mover="the beam")

    def _raise_load(self, increment: float, settlement, *, max_load: float, tol: float,
                    max_steps: int, every: int, runaway: float, callback,
                    mover: str) -> DiskFillRun:
        """The live load's factor raised in steps of ``increment`` [N], each held to
        equilibrium (:meth:`load`); ``settlement()`` [m] the displacement recorded;
        ``mover``: what :meth:`beam_settlement` follows, in words."""
        if not self.settled:
            raise RuntimeError("the disk fill has not settled under self-weight: call "
                               "settle() first (and check that it returns True)")
        if not (math.isfinite(increment) and increment > 0):
            raise ValueError(f"increment must be > 0 N, got {increment}")
        if not 0 < tol < 1:
            raise ValueError(f"tol must lie in (0, 1), got {tol}")
        runaway = float(runaway)
        if not runaway > 0:
            raise ValueError(f"runaway must be > 0 m, got {runaway}")
        t0 = time.perf_counter()
        run = DiskFillRun(RunStatus(Status.NOT_CONVERGED, 0.0, 0.0), increment)
        run.loads.append(0.0)
        run.displacements.append(0.0)
        run.steps.append(self.steps_free)
        run.ratios.append(self.ratios())
        k = 0
        while True:
            k += 1
            p = k * increment
            if p > max_load * (1 + 1e-12):
                run.status = RunStatus(Status.LOAD_REACHED, run.loads[-1], run.loads[-1],
                                       detail=f"{max_load / 1e3:.4g} kN asked")
                break
            self.solver.load_factor = p
            self.model.external_force(p, out=self.solver.f_ext)
            why, steps, ring, moved = self._equilibrate(tol=tol, max_steps=max_steps,
                                                        every=every, runaway=runaway)
            run.moved, run.ring_moved = moved, ring
            if why == "equilibrium":
                run.loads.append(p)
                run.displacements.append(settlement())
                run.steps.append(steps)
                run.ratios.append(self.ratios())
                self.last_steps = steps
                if callback is not None:
                    callback(self, p)
                continue
            last = run.loads[-1]
            rd, rb = self.ratios()
            if why == "runaway":
                run.status = RunStatus(
                    Status.MECHANISM, last, last,
                    detail=(f"no equilibrium at {p / 1e3:.4g} kN: the ring ran "
                            f"{ring * 1e3:.1f} mm ({mover} {moved * 1e3:.1f} mm) under "
                            f"that constant load in {steps} steps (ratios: disks "
                            f"{rd:.1e}, blocks {rb:.1e}); the "
                            f"collapse load lies between {last / 1e3:.4g} and "
                            f"{p / 1e3:.4g} kN"))
            else:
                run.status = RunStatus(
                    Status.NOT_CONVERGED, last, last, at=p,
                    detail=(f"explicit: ratios disks {rd:.1e}, blocks {rb:.1e} after "
                            f"{steps} steps at {p / 1e3:.4g} kN (tol {tol:g}); {mover} "
                            f"moved {moved * 1e3:.2f} mm, the ring {ring * 1e3:.2f} mm"))
            break
        run.seconds = time.perf_counter() - t0
        return run


# ---------------------------------------------------------------------- output
def stress_grid(b: DiskFillBridge, cell: float):
    """``(xs, ys, σ_yy)``: the disks' vertical stress [Pa] averaged from their contact
    forces (:meth:`Disks.cell_stress`, Love–Weber) over square cells ``cell`` [m] wide
    covering the fill's bounding box up to the road (NaN where a cell holds fewer than
    three disk centres); collective."""
    width = float(np.ptp(b.fill_polygon[:, 0]))
    if not 0 < cell <= 0.5 * width:
        raise ValueError(f"cell must lie in (0, {0.5 * width:g}] m (half the fill's width), "
                         f"got {cell}")
    poly = b.fill_polygon
    x0 = poly[:, 0].min()
    xs = x0 + cell * np.arange(int(np.ceil((poly[:, 0].max() - x0) / cell - 1e-9)) + 1)
    y0 = poly[:, 1].min()
    ys = y0 + cell * np.arange(int(np.ceil((b.road - y0) / cell - 1e-9)) + 1)
    sig = np.full((ys.size - 1, xs.size - 1), np.nan)
    x = b.disks.x
    for i in range(ys.size - 1):
        for j in range(xs.size - 1):
            lo, hi = (xs[j], ys[i]), (xs[j + 1], ys[i + 1])
            s = b.disks.cell_stress(lo, hi, [b.coupling])
            n = np.count_nonzero(np.all((x >= lo) & (x < hi), axis=1))
            if n >= 3:
                sig[i, j] = s[1, 1]
    return xs, ys, sig


def draw_stress(b: DiskFillBridge, grid, load: float, y0: float, disks, path) -> None:
    """Draw :func:`stress_grid` ``grid`` (compression positive, kPa), the disks ``(x, r)``
    and the beam's bottom ``y0`` [m] as they were at ``load`` [N], over the blocks'
    outlines (undeformed), into the PNG ``path`` (call on one rank)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import PatchCollection
    from matplotlib.patches import Circle, Polygon

    xs, ys, sig = grid
    fig, ax = plt.subplots(figsize=(11, 4.2))
    kpa = -sig / 1e3
    # the colour scale stops at the 98th percentile of the cells: the one or two under
    # the beam would wash out the load's path through the rest
    top = float(np.nanpercentile(kpa, 98)) if np.isfinite(kpa).any() else 1.0
    m = ax.pcolormesh(xs, ys, np.ma.masked_invalid(kpa), cmap="magma_r", shading="flat",
                      vmin=0.0, vmax=max(top, 1e-9))
    fig.colorbar(m, ax=ax, extend="max", label="σ_yy in the fill, compression [kPa]")
    ax.add_collection(PatchCollection(
        [Circle(c, r) for c, r in zip(*disks, strict=True)],
        facecolor="none", edgecolor="0.55", linewidths=0.2))
    for name, poly in zip(b.layout.names, b.layout.polygons, strict=True):
        if name == b.BEAM:  # drawn where it is now, below
            continue
        ax.add_patch(Polygon(poly, closed=True, facecolor="0.85", edgecolor="k", lw=0.5,
                             zorder=0.5))
    xl, half = b.case.load_x(), 0.5 * b.case.loading.spreader_width
    ax.add_patch(Polygon([[xl - half, y0], [xl + half, y0], [xl + half, y0 + 0.05],
                          [xl - half, y0 + 0.05]], closed=True, facecolor="C0"))
    ax.annotate(f"{load / 1e3:.0f} kN", xy=(xl, y0 + 0.06), xytext=(xl, b.road + 0.6),
                ha="center", arrowprops=dict(arrowstyle="-|>", color="C3", lw=2))
    ax.set_aspect("equal")
    ax.set_xlim(xs[0] - 0.4, xs[-1] + 0.4)
    ax.set_ylim(min(p[:, 1].min() for p in b.layout.polygons), b.road + 0.8)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(f"{b.case.name}: disk fill, vertical stress at {load / 1e3:.0f} kN "
                 f"(the last load carried; cells {xs[1] - xs[0]:.2f} m; colours clipped at "
                 "the 98th percentile)", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=130, bbox_inches="tight")
    plt.close(fig)


def assess_disk_fill(case, *, folder, write: bool = True, progress=None,
                     comm: MPI.Comm = MPI.COMM_WORLD, callback=None,
                     t_start: float | None = None):
    """:func:`~masonry_fdem.assessment.assess.assess` of a case whose ``[fill]`` has
    ``model = "disks"`` (collective; called by it): the bridge of
    :meth:`DiskFillBridge.from_case` settled, then loaded in steps of
    ``loading.increment`` up to ``loading.max_load`` or collapse. Returns an
    :class:`~masonry_fdem.assessment.assess.Assessment` (``control`` "load", ``iterations``
    the explicit steps per load, the load-line displacement the beam's settlement under
    the live load, the hinge sequence from the radial joints as for any case,
    ``hinges_at_collapse`` the joints open at the end of the run — after a mechanism,
    those of the mechanism) and writes the run folder as for any case, with
    ``vertical_stress.png`` the disks' σ_yy at the last load carried and the mechanism
    drawn with the disks, to scale. ``callback`` gets ``"iterations"`` the explicit steps
    of that load and ``"bridge"`` the :class:`DiskFillBridge`. A stop requested by a
    signal (:func:`~masonry_fdem.io.checkpoint.stop_on_signals`) ends the run at the next
    load carried with :class:`~masonry_fdem.io.checkpoint.Interrupted` (no checkpoint).

    Raises:
        RuntimeError: the fill found no equilibrium under self-weight.
        ValueError: the case has anchors (not modelled with a disk fill).
    """
    from masonry_fdem.assessment.assess import (Assessment, _JointMonitor, case_limit_analysis,
                                                limit_load_of, limit_rotation_hinges,
                                                progress_bar)
    from masonry_fdem.assessment.report import thrust_lines, write_run_folder
    from masonry_fdem.assessment.specs import DiskFillSpec
    from masonry_fdem.io.checkpoint import Interrupted, rearm, stop_requested

    t_start = time.perf_counter() if t_start is None else t_start
    ld = case.loading
    spec = case.fill.disks or DiskFillSpec()
    if case.anchor_specs:
        raise ValueError(f"{case.name}: anchors are not modelled with a disk fill (the "
                         "continuum fill has them)")
    la = case_limit_analysis(case, comm)
    limit_load = limit_load_of(la)
    b = DiskFillBridge.from_case(case, comm=comm)
    rearm()  # (the mesh generator resets the signal handlers)
    half = 0.5 * float(np.ptp(b.fill_polygon[:, 0]))
    if write and not spec.cell <= half:
        raise ValueError(f"{case.name}: fill.disks.cell {spec.cell:g} m is wider than half "
                         f"the fill ({half:g} m): the stress picture would have one column")
    bar = progress_bar(case.name, progress, comm)
    if not b.settle(tol=spec.tol, max_steps=spec.max_steps):
        rd, rb = b.ratios()
        raise RuntimeError(f"{case.name}: the disk fill found no equilibrium under "
                           f"self-weight within {spec.max_steps} steps (ratios: disks "
                           f"{rd:.1e}, blocks {rb:.1e}; tol {spec.tol:g})")
    # the radial joints' hinges, from their openings beyond the self-weight state and
    # their mortar's state (as for any case)
    monitor = _JointMonitor(case, b.model, b.blocks[1])
    monitor.base = monitor.openings() + monitor.base
    events, seen = [], set()

    def joint_events(load: float, disp: float) -> list:
        opened, op = monitor.classify(case.analysis.hinge_opening)
        for k, kind, side in opened:
            if (k, kind) not in seen:
                seen.add((k, kind))
                events.append(monitor.event(k, kind, side, len(events) + 1, load, disp,
                                            op[k]))
        return [monitor.event(k, kind, side, 0, load, disp, op[k]) for k, kind, side in opened]

    last: dict = {}

    def at(br: DiskFillBridge, load: float) -> None:
        disp = br.beam_settlement() - br.dead_settlement
        steps = int(br.last_steps)
        joint_events(load, disp)
        if write:
            last.update(grid=stress_grid(br, spec.cell), load=load, disp=disp,
                        disks=(br.disks.x.copy(), br.disks.r.copy()),
                        beam=br.road + br.overfill - br.beam_settlement())
        if bar is not None:
            factor = f"{load / limit_load:.3f}" if limit_load else "-"
            bar.increment(f"{case.name}: load factor {factor}, load {load / 1e3:.3f} kN, "
                          f"beam settlement {disp * 1e3:.4f} mm, converged",
                          load=f"{load / 1e3:.2f} kN", u=f"{disp * 1e3:.3f} mm")
        if callback is not None:
            callback({"load": load, "displacement": disp, "iterations": steps,
                      "model": br.model, "interactions": br.blocks, "anchors": None,
                      "bridge": br})
        if comm.allreduce(stop_requested(), op=MPI.LOR):
            raise Interrupted(folder, int(round(load / ld.increment)), (
                f"interrupted: {case.name} stopped at {load / 1e3:.4g} kN carried; runs "
                "with a disk fill write no checkpoint: run the case again to finish it"))

    run = b.load(ld.increment, max_load=ld.max_load or math.inf, tol=spec.tol,
                 max_steps=spec.max_steps, runaway=spec.runaway, callback=at)
    if bar is not None:
        bar.close()
    st = run.status
    # the joints open at the end of the run: after a mechanism (or a load not converged),
    # those opened under the load that found no equilibrium
    tried = run.loads[-1] + (0.0 if st.status is Status.LOAD_REACHED else run.increment)
    at_end = joint_events(tried, b.beam_settlement() - b.dead_settlement)
    status = replace(st, detail=f"explicit dynamics, disk fill ({b.disks.n} disks): "
                                f"{st.detail}")
    res = Assessment(
        case=case.name, control="load", status=status, peak_load=float(run.loads[-1]),
        resolution=float(run.increment), loads=np.array(run.loads),
        displacements=np.array(run.displacements), iterations=list(run.steps),
        events=events, hinges_at_collapse=at_end, limit_load=limit_load,
        limit_status=None if la is None else str(la.status),
        limit_explanation="" if la is None else la.explanation,
        limit_hinges=limit_rotation_hinges(la),
        limit_thrust=[] if la is None else thrust_lines(case, la),
        cells=int(b.model.blocks.n_cells))
    res.elapsed = time.perf_counter() - t_start
    if write:
        def extra(tmp):
            if "grid" not in last:
                return []
            error = None
            if comm.rank == 0:
                try:
                    draw_stress(b, last["grid"], last["load"], last["beam"], last["disks"],
                                tmp / "vertical_stress.png")
                except Exception as exc:  # reaches every rank: none left waiting
                    error = f"drawing the disks' stress: {exc!r}"
            error = comm.bcast(error, root=0)
            if error:
                raise RuntimeError(error)
            return [("last load carried: the disks' vertical stress", "vertical_stress.png",
                     last["load"], last["disp"])]

        if comm.rank == 0:
            # a continuum run's outputs that this one does not write, from an earlier run
            # into the same folder
            for old in [*Path(folder).glob("paraview*"), Path(folder) / "first_hinge.png",
                        Path(folder) / "peak_load.png"]:
                if old.is_dir():
                    shutil.rmtree(old, ignore_errors=True)
                elif old.exists():
                    old.unlink()
        comm.barrier()
        label = (f"P = {tried / 1e3:.2f} kN, not carried" if tried > run.loads[-1]
                 else None)
        write_run_folder(case, res, folder, b.model, b.blocks, None, comm, disks=b.disks,
                         extra=extra, load_label=label)
    return res
