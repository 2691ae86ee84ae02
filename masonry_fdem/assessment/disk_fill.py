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
   instead the beam runs ``runaway`` [m] under the constant load (default: a quarter of
   the ring thickness) has no equilibrium: the structure is a mechanism, status
   *mechanism*, and its collapse load is the last load carried, within one increment
   (below). A load at which neither happens within ``max_steps`` is *not converged*:
   the last load carried is a lower bound only.

Units: SI (N, m, s, kg). The loads are over the case's barrel ``width``.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

from mpi4py import MPI

import numpy as np

from masonry_fdem.interactions.protocol import BLOCKS
from masonry_fdem.solvers.status import RunStatus, Status

__all__ = ["DiskFillBridge", "DiskFillRun"]


@dataclass
class DiskFillRun:
    """Result of :meth:`DiskFillBridge.load`: ``status``; ``loads`` [N] carried (each an
    equilibrium; the first is 0, self-weight only) against ``displacements`` [m] (the
    beam's settlement under the live load, positive down); ``steps`` and ``ratios``
    (disks', blocks') per load; ``moved`` [m]: how far the beam ran at the last load
    tried; ``seconds`` of wall time."""

    status: RunStatus
    increment: float
    loads: list[float] = field(default_factory=list)
    displacements: list[float] = field(default_factory=list)
    steps: list[int] = field(default_factory=list)
    ratios: list[tuple[float, float]] = field(default_factory=list)
    moved: float = 0.0
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
        from masonry_fdem.interactions import (BlockContact, ContactSettings,
                                               DiskBlockContact, Joints)
        from masonry_fdem.interactions.disks import DiskMaterial, Disks
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
        contact = BlockContact(model, ContactSettings(
            friction=case.analysis.friction, penalty_factor=case.analysis.penalty_factor))
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

        def make(x, r):
            disks = Disks(x, r, {"fill": mat}, "fill", width=case.arch.width, comm=comm)
            disks.add_gravity()
            return disks, DiskBlockContact(disks, model, friction=fill.interface_friction)

        self._make_disks = make
        self.model, self.blocks = model, [contact, joints]
        self.disks, self.coupling = make(x, r)
        self.local_damping = float(local_damping)
        # density scaling of the blocks (their weight kept): the block contact's penalty
        # sets a step tens of times shorter than the disks', and the fill then creeps to
        # rest over millions of steps; blocks as slow as the disks share their step
        st = self._solver(True).stability
        auto = (st["disks"].dt / st[BLOCKS].dt) ** 2
        self.inertia_scale = max(1.0, auto) if inertia_scale is None else float(inertia_scale)
        model.scale_inertia(self.inertia_scale)
        self._held = [model.fix_blocks("voussoir:*", name="arch"),
                      model.fix_blocks(top_layer, name="beam held")]
        self.beam_nodes = np.flatnonzero(np.isin(model.node_block,
                                                 model.select_blocks(name))).astype(np.int64)
        self._top_nodes = np.flatnonzero(np.isin(
            model.node_block, model.select_blocks(top_layer))).astype(np.int64)
        self._top_range = ((xl - half, xl + half) if self.surfacing == 0
                           else (float(slab[0, 0]), float(slab[1, 0])))
        self._n_beam = comm.allreduce(int(self.beam_nodes.size))
        self.solver = None
        self.settled = False
        self.trimmed = 0
        self.surface = math.nan

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

    def _equilibrate(self, *, tol: float, max_steps: int, every: int,
                     runaway: float = math.inf) -> tuple[str, int, float]:
        """Run until both ratios are below ``tol`` ("equilibrium"), the beam has moved
        ``runaway`` [m] ("runaway") or ``max_steps`` ("steps"). Returns the outcome, the
        steps taken and how far the beam moved [m]."""
        watch = math.isfinite(runaway)
        start = self.beam_settlement() if watch else 0.0
        out = {"why": "steps"}

        def check(s) -> bool:
            rd, rb = self.ratios()
            if rd < tol and rb < tol:
                out["why"] = "equilibrium"
                return True
            if watch and self.beam_settlement() - start > runaway:
                out["why"] = "runaway"
                return True
            return False

        steps = self.solver.run(steps=max_steps, every=every, until=check)
        moved = self.beam_settlement() - start if watch else 0.0
        return out["why"], steps, moved

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

    def settle(self, *, tol: float = 1e-3, max_steps: int = 200_000,
               every: int = 500) -> bool:
        """Stages 1 and 2 of the module doc (collective). Returns whether both reached
        equilibrium (ratios below ``tol``)."""
        self.solver = self._solver(False)
        why1, self.steps_held, _ = self._equilibrate(tol=tol, max_steps=max_steps,
                                                    every=every)
        if self.overfill > 0 and why1 == "equilibrium":
            keep = self.disks.x[:, 1] <= self.fill_top
            self.trimmed = int(self.disks.n - keep.sum())
            self.disks, self.coupling = self._make_disks(self.disks.x[keep],
                                                         self.disks.r[keep])
            self.solver = self._solver(False)
            why1, more, _ = self._equilibrate(tol=tol, max_steps=max_steps, every=every)
            self.steps_held += more
        for p in self._held:
            self.model.prescriptions.remove(p)
        self._lower_beam_onto_fill()
        self.model.prescribe_velocity(self.BEAM, (0.0, None), name="beam guide")
        self.solver = self._solver(True)
        why2, self.steps_free, _ = self._equilibrate(tol=tol, max_steps=max_steps,
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
            runaway: beam travel [m] under one constant load that proves no equilibrium
                (default: a quarter of the ring thickness).
            callback: ``callback(bridge, load)`` after each equilibrium (pictures, output).

        Raises:
            RuntimeError: the bridge has not settled under self-weight (:meth:`settle`).
            ValueError: a bad increment, tol or runaway.
        """
        if not self.settled:
            raise RuntimeError("the disk fill has not settled under self-weight: call "
                               "settle() first (and check that it returns True)")
        if not (math.isfinite(increment) and increment > 0):
            raise ValueError(f"increment must be > 0 N, got {increment}")
        if not 0 < tol < 1:
            raise ValueError(f"tol must lie in (0, 1), got {tol}")
        runaway = 0.25 * self.case.arch.ring_thickness if runaway is None else float(runaway)
        if not runaway > 0:
            raise ValueError(f"runaway must be > 0 m, got {runaway}")
        t0 = time.perf_counter()
        base = self.dead_settlement
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
            why, steps, moved = self._equilibrate(tol=tol, max_steps=max_steps,
                                                  every=every, runaway=runaway)
            run.moved = moved
            if why == "equilibrium":
                run.loads.append(p)
                run.displacements.append(self.beam_settlement() - base)
                run.steps.append(steps)
                run.ratios.append(self.ratios())
                if callback is not None:
                    callback(self, p)
                continue
            last = run.loads[-1]
            rd, rb = self.ratios()
            if why == "runaway":
                run.status = RunStatus(
                    Status.MECHANISM, last, last,
                    detail=(f"no equilibrium at {p / 1e3:.4g} kN: the beam ran "
                            f"{moved * 1e3:.1f} mm under that constant load in {steps} "
                            f"steps (ratios: disks {rd:.1e}, blocks {rb:.1e}); the "
                            f"collapse load lies between {last / 1e3:.4g} and "
                            f"{p / 1e3:.4g} kN"))
            else:
                run.status = RunStatus(
                    Status.NOT_CONVERGED, last, last, at=p,
                    detail=(f"explicit: ratios disks {rd:.1e}, blocks {rb:.1e} after "
                            f"{steps} steps at {p / 1e3:.4g} kN (tol {tol:g}); the beam "
                            f"moved {moved * 1e3:.2f} mm"))
            break
        run.seconds = time.perf_counter() - t0
        return run
