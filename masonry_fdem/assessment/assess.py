"""Remnant strength of a masonry arch: load to collapse, hinge sequence, limit analysis.

:func:`assess` runs one :class:`~masonry_fdem.assessment.case.ArchCase` (``masonry-fdem assess
CASE.toml`` on the command line):

1. the rigid-block limit analysis of the same blocks (linear programming, seconds): the
   collapse load LimitState:RING-style tools give, reported beside the FDEM result;
2. the FDEM model: deformable voussoirs and abutments (the abutments fixed), mortar and
   ring interfaces as :class:`~masonry_fdem.interactions.Joints` (a joint without tensile
   strength or cohesion in the case file is a dry joint, left to the frictional
   :class:`~masonry_fdem.interactions.BlockContact`), anchors if any; self-weight first;
3. load to collapse by dynamic relaxation (velocity-quotient damping, see
   :mod:`masonry_fdem.solvers.dynamic_relaxation`):

   * ``control = "load"``: the load on the spreader grows by ``increment`` [N]; an
     increment without equilibrium is undone and halved ``refinements`` times; the
     collapse load is the last load carried, within the last increment tried;
   * ``control = "displacement"``: a rigid platen (the nodes under the spreader's ends)
     is driven down in steps of ``displacement_increment`` [m] from its self-weight
     position; the load is the platen's reaction and the collapse load its peak. This
     traces the post-peak branch and reaches the peak where load control stops short
     (near the peak the structure is so soft that equilibrium iterations stall);
4. after every converged step the opening of every radial joint (springings included) at
   its two ends, beyond the self-weight state: an end opens past ``hinge_opening`` [m]
   while the other stays closed: a hinge (its side, intrados or extrados, named); both
   ends open: the joint has separated. The first load at which each joint does so is the
   hinge sequence.

Every output goes to one run folder, written only when the run is complete (the files
are assembled in a hidden sibling folder and moved in at the end; a run that fails
leaves nothing): ``report.md`` (the summary with pictures), ``load_displacement.png``,
``mechanism.png`` (deformed blocks, magnified), ``hinges.png`` (the hinges of FDEM and of
the limit analysis on the arch), ``curve.csv``, ``hinges.csv``, ``summary.json`` and the
case file. Units are SI: N, m.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from mpi4py import MPI

import numpy as np

from masonry_fdem.assessment.case import ArchCase, CaseError, LoadControl, load_case
from masonry_fdem.assessment.specs import classify_interface
from masonry_fdem.geometry.arches import arch_centre, arch_parameter
from masonry_fdem.assessment.report import write_run_folder
from masonry_fdem.io.rundir import run_folder_problem

__all__ = ["Assessment", "JointEvent", "anchor_state", "assess", "build_model"]


@dataclass(frozen=True)
class JointEvent:
    """A joint that opened: a hinge (one end open) or a separation (both ends).

    Attributes:
        order: 1 for the first joint to open, 2 for the next, ...
        joint: ``"ring k joint j"`` (joint j starts voussoir j; 0 and n: the springings).
        blocks: the two blocks.
        kind: "hinge" or "separation".
        side: "intrados" or "extrados" (hinge: the side that opens), "" (separation).
        position: ``(x, y)`` [m] of the hinge, the end the blocks rotate about (the
            closed one, as the hinges of limit analysis); separation: the midpoint.
        s: the position along the arch, 0 left springing, 0.5 crown, 1 right springing.
        load: the load [N] of the first converged step with the joint open.
        displacement: the load-line displacement [m] then.
    """

    order: int
    joint: str
    blocks: tuple[str, str]
    kind: str
    side: str
    position: tuple[float, float]
    s: float
    load: float
    displacement: float


@dataclass
class Assessment:
    """Result of :func:`assess` (loads [N] on the whole barrel width, lengths [m]).

    Attributes:
        case: the case name.
        control: "load" or "displacement".
        collapse_load: the largest load carried (load control: the last converged load;
            displacement control: the peak reaction).
        resolution: the load step that failed last (load control) or the largest load
            change between the peak and its neighbouring steps (displacement control).
        collapsed: False if ``max_load`` (or ``max_displacement``) was reached first.
        loads, displacements: the load–displacement curve at the load line (converged
            steps; displacement downward positive), self-weight state first.
        iterations: DR iterations of each point of the curve.
        events: the hinge sequence.
        hinges_at_collapse: the joints open at the collapse state.
        limit_load: the limit-analysis collapse load (None if not run), ``limit_status``
            its LP status and ``limit_hinges`` its hinges (``(blocks, position)``).
        folder, report: the run folder and ``report.md`` (None if not written).
        cells, elapsed: the mesh size and the wall time [s].
        anchors: per anchor at the collapse state (see :func:`anchor_state`); empty
            without anchors.
        anchor_length: Σ count × length of the anchors [m] (0 without anchors).
    """

    case: str
    control: str
    collapse_load: float
    resolution: float
    collapsed: bool
    loads: np.ndarray
    displacements: np.ndarray
    iterations: list[int]
    events: list[JointEvent]
    hinges_at_collapse: list[JointEvent]
    limit_load: float | None = None
    limit_status: str | None = None
    limit_hinges: list[tuple[tuple[str, str], tuple[float, float]]] = field(
        default_factory=list)
    folder: Path | None = None
    report: Path | None = None
    cells: int = 0
    elapsed: float = 0.0
    anchors: list[dict] = field(default_factory=list)
    anchor_length: float = 0.0

    @property
    def ratio(self) -> float | None:
        """FDEM collapse load / limit-analysis load."""
        if not self.limit_load or not math.isfinite(self.limit_load):
            return None
        return self.collapse_load / self.limit_load


# ---------------------------------------------------------------------------- the model

def _with(interactions: list, anchors) -> list:
    """The solver's interactions: contact and joints, then the anchors if any."""
    return interactions if anchors is None else [*interactions, anchors]

def build_model(case: ArchCase, comm: MPI.Comm = MPI.COMM_WORLD):
    """The FDEM model of a case (collective).

    Returns:
        ``(model, interactions, anchors)``: the :class:`~masonry_fdem.model.Model` (its
        abutments fixed, self-weight as a dead load), ``[BlockContact, Joints]`` and the
        :class:`~masonry_fdem.interactions.anchors.Anchors` (None without anchors).
    """
    from masonry_fdem.interactions.anchors import Anchors
    from masonry_fdem.model import Model
    from masonry_fdem.interactions import BlockContact, ContactSettings, Joints

    layout = case.mesh_layout()
    mesh = layout.mesh(case.arch.mesh_size, comm)
    model = Model(mesh, case.materials(), width=case.arch.width, comm=comm)
    model.fix_blocks("abutment:*", name="abutments")
    if case.loading.self_weight:
        model.add_gravity()
    contact = BlockContact(model, ContactSettings(
        friction=case.analysis.friction, penalty_factor=case.analysis.penalty_factor))

    def bond(jm):
        return jm if jm is not None and (jm.bonded or jm.kn is not None) else None

    table = {k: bond(v) for k, v in case.joint_materials().items()}
    rules = [(where, bond(jm)) for where, jm in case.joint_rules(layout)]
    joints = Joints(model, table, where=rules, contact=contact)
    specs = case.anchors()
    anchors = Anchors(model, specs) if specs else None
    return model, [contact, joints], anchors


class _JointMonitor:
    """Openings of the radial joints at their two ends (collective)."""

    def __init__(self, case: ArchCase, model):
        from masonry_fdem.solvers.limit_analysis import find_interfaces

        layout = case.layout()
        itf = find_interfaces(layout)
        names = list(model.blocks.block_names)
        self.case = case
        self.model = model
        self.rows = []
        for i in range(itf.size):
            na, nb = layout.names[itf.block_a[i]], layout.names[itf.block_b[i]]
            where = classify_interface(na, nb, case.arch)
            if where is None or where[0] != "joint":
                continue
            self.rows.append((i, f"ring {where[1]} joint {where[2]}", (na, nb),
                              names.index(na), names.index(nb)))
        n = len(self.rows)
        self.ends = np.zeros((n, 2, 2))
        self.normal = np.zeros((n, 2))
        self.node = -np.ones((n, 2, 2), dtype=np.int64)  # [joint, end, block a/b]
        cent = np.array([np.mean(p, axis=0) for p in layout.polygons])
        for k, (i, _, _, ba, bb) in enumerate(self.rows):
            p0, p1 = itf.start[i], itf.end[i]
            self.ends[k] = (p0, p1)
            t = (p1 - p0) / np.linalg.norm(p1 - p0)
            nrm = np.array([-t[1], t[0]])
            if np.dot(nrm, cent[itf.block_b[i]] - cent[itf.block_a[i]]) < 0:
                nrm = -nrm
            self.normal[k] = nrm
            for side, b in enumerate((ba, bb)):
                own = np.flatnonzero(model.node_block == b)
                if own.size == 0:
                    continue
                for e in range(2):
                    d = np.linalg.norm(model.X[own] - self.ends[k, e], axis=1)
                    self.node[k, e, side] = own[int(np.argmin(d))]
        self.base = np.zeros((n, 2))
        self.side = [self._intrados_end(k) for k in range(n)]

    def _intrados_end(self, k: int) -> int:
        """0 or 1: the end of joint k nearer the arch's centre of curvature."""
        arch = self.case.arch
        c = arch_centre(arch.kind, arch.span, arch.rise, self.ends[k].mean(axis=0)[0])
        d = np.linalg.norm(self.ends[k] - c, axis=1)
        return int(np.argmin(d))

    def openings(self) -> np.ndarray:
        """``(n, 2)`` normal opening [m] at both ends (positive: open), minus the
        self-weight state's."""
        u = self.model.u.x.array.reshape(-1, 2)
        du = np.zeros((len(self.rows), 2, 2, 2))
        ok = self.node >= 0
        du[ok] = u[self.node[ok]]
        du = self.model.comm.allreduce(du)
        rel = du[:, :, 1, :] - du[:, :, 0, :]
        return np.einsum("kej,kj->ke", rel, self.normal) - self.base

    def classify(self, tol: float) -> tuple[list[tuple[int, str, str]], np.ndarray]:
        """``(row, kind, side)`` of the joints open beyond ``tol`` [m], and the openings."""
        out = []
        op = self.openings()
        for k in range(len(self.rows)):
            o = op[k]
            if o.min() > tol:
                out.append((k, "separation", ""))
            elif o.max() > tol:
                end = int(np.argmax(o))
                out.append((k, "hinge", "intrados" if end == self.side[k] else "extrados"))
        return out, op

    def event(self, k: int, kind: str, side: str, order: int, load: float,
              disp: float, opening: np.ndarray) -> JointEvent:
        """The event of joint k, its ``opening`` at both ends [m] given."""
        _, label, blocks, _, _ = self.rows[k]
        if kind == "hinge":
            pos = self.ends[k, int(np.argmin(opening))]
        else:
            pos = self.ends[k].mean(axis=0)
        a = self.case.arch
        s = arch_parameter(a.kind, a.span, a.rise, self.ends[k].mean(axis=0))
        return JointEvent(order, label, blocks, kind, side, (float(pos[0]), float(pos[1])),
                          float(s), float(load), float(disp))


# ---------------------------------------------------------------------------- the run
def assess(
    case: ArchCase | str | Path | Mapping[str, Any],
    *,
    out: str | Path | None = None,
    overwrite: bool = False,
    progress: bool | None = None,
    comm: MPI.Comm = MPI.COMM_WORLD,
    write: bool = True,
    callback: Callable[[dict], None] | None = None,
) -> Assessment:
    """Load an arch case to collapse and report it (collective; see the module doc).

    Args:
        case: an :class:`~masonry_fdem.assessment.case.ArchCase`, a TOML file or a dict of one.
        out: the run folder (default: the case's ``analysis.output``).
        overwrite: allow a run folder that exists and is not empty.
        progress: draw a progress bar on stderr (default: when stderr is a terminal).
        comm: MPI communicator.
        write: write the run folder (False: compute only).
        callback: called on every rank after each converged step with
            ``{"load": N, "displacement": m, "iterations": int}``.

    Raises:
        CaseError: a bad case, or a run folder that is not free; nothing is written.
    """
    t_start = time.perf_counter()
    if not isinstance(case, ArchCase):
        case = load_case(case)
    folder = Path(out) if out is not None else case.analysis.output
    if write:
        error = run_folder_problem(folder, overwrite=overwrite, comm=comm)
        if error:
            raise CaseError(error, str(case.source) if case.source else None)
    from masonry_fdem.io import ProgressBar
    from masonry_fdem.solvers import DynamicRelaxation

    ld = case.loading
    an = case.analysis
    la = None
    if an.limit_analysis:
        la = case.limit_analysis() if comm.rank == 0 else None
        la = comm.bcast(la, root=0)
    limit_load = float(la.load_factor) if la is not None else None
    if limit_load is not None and not math.isfinite(limit_load):
        limit_load = None

    model, inter, anchors = build_model(case, comm)
    monitor = _JointMonitor(case, model)
    points = case.load_points()
    bar = ProgressBar(f"{case.name}", comm=comm,
                      force=bool(progress)) if progress is not False else None
    scale = limit_load or ld.max_load or 20 * ld.increment

    dr = DynamicRelaxation(model, interactions=_with(inter, anchors), rtol=an.dr_rtol,
                           ke_tol=math.inf, max_iter=an.max_iterations, damping="velocity")
    res = dr.solve(0.0)
    if res.converged and anchors is not None and any(a.prestress > 0 for a in anchors.anchors):
        # prestressed anchors: equilibrium under self-weight and the jacking forces, then
        # lock-off (the bond acts from here on) and equilibrium again
        anchors.lock_off()
        it0 = res.iterations
        res = dr.solve(0.0)
        res = replace(res, iterations=res.iterations + it0)
    if not res.converged:
        raise RuntimeError(f"{case.name}: no equilibrium under self-weight "
                           f"({res.iterations} iterations); the arch cannot stand")
    monitor.base = monitor.openings() + monitor.base
    loads, disps, iters = [0.0], [0.0], [res.iterations]
    events: list[JointEvent] = []
    seen: set[int] = set()
    state: dict[str, Any] = {"open": [], "anchors": []}

    # load-line displacement: mean vertical displacement of the nodes nearest the points
    load_nodes = [model.nearest_node(p, "voussoir:*") for p in points]
    u_sw = _mean_uy(model, load_nodes)

    def record(load: float, iterations: int) -> None:
        disp = u_sw - _mean_uy(model, load_nodes)
        loads.append(float(load))
        disps.append(float(disp))
        iters.append(int(iterations))
        opened, op = monitor.classify(an.hinge_opening)
        state["open"] = [(k, kind, side, load, disp, op[k]) for k, kind, side in opened]
        if anchors is not None:
            state["anchors"] = anchor_state(anchors)
        for k, kind, side in opened:
            if k not in seen:
                seen.add(k)
                events.append(monitor.event(k, kind, side, len(events) + 1, load, disp,
                                            op[k]))
        if bar is not None:
            bar.update(load / scale, f"{load / 1e3:8.2f} kN  {disp * 1e3:7.3f} mm  "
                       f"{len(seen)} joints open")
        if callback is not None:
            callback({"load": load, "displacement": disp, "iterations": iterations})

    open_at_collapse: list = []
    anchors_at_collapse: list = state["anchors"]
    collapse, resolution, collapsed = 0.0, 0.0, False
    drive_from = None  # load-line displacement [m] where displacement control starts
    if ld.control is LoadControl.LOAD:
        for p in points:
            model.add_point_load(p, (0.0, -1.0 / len(points)), blocks="voussoir:*")

        def on_step(r) -> None:
            if r.converged:
                record(r.load_factor, r.iterations)

        cres = dr.load_to_collapse(ld.increment, max_load=ld.max_load or math.inf,
                                   refinements=an.refinements, callback=on_step)
        collapse, resolution, collapsed = cres.load_factor, cres.resolution, cres.collapsed
        open_at_collapse = state["open"]
        anchors_at_collapse = state["anchors"]
        if collapsed and an.follow_peak:
            # no equilibrium within the iteration limit is not yet proof that none
            # exists (near the peak the structure is so soft that DR stalls): go on from
            # the last equilibrium by driving the platen down
            drive_from = disps[-1]
            # (a quarter of the displacement reached, but not below span/1e5 when the
            # first increment already failed)
            dstep = ld.displacement_increment or max(disps[-1] / 4.0, 1e-5 * case.arch.span)
    else:
        drive_from, dstep = 0.0, ld.displacement_increment
    if drive_from is not None:
        sel = [int(n) for n in load_nodes]
        ids = comm.allgather([int(model.node_input[n]) for n in sel if n >= 0])
        _prescribe_node_ids(model, {g for part in ids for g in part}, "platen")
        lf = collapse if ld.control is LoadControl.LOAD else 0.0
        # the live load stays as it was; the platen's reaction adds to it
        dr = DynamicRelaxation(model, interactions=_with(inter, anchors), rtol=an.dr_rtol,
                               ke_tol=math.inf, max_iter=an.max_iterations,
                               damping="velocity")
        peak, k_peak, falling = collapse, len(loads) - 1, 0
        step = 0
        while True:
            step += 1
            d = drive_from + step * dstep
            if ld.max_displacement is not None and d > ld.max_displacement * (1 + 1e-12):
                break
            r = dr.solve(lf, displacement={"platen": (None, u_sw - d)})
            if not r.converged:
                collapsed = True
                break
            load = lf - float(dr.reactions()["platen"][1])
            record(load, r.iterations)
            if load > peak:
                peak, k_peak, falling = load, len(loads) - 1, 0
                open_at_collapse = state["open"]
                anchors_at_collapse = state["anchors"]
            else:
                falling += 1
            if falling >= an.post_peak_steps or load < (1 - an.post_peak_drop) * peak:
                collapsed = True
                break
            if ld.max_load is not None and load >= ld.max_load:
                collapsed = False  # carries the load asked for; no collapse sought
                break
        if peak > collapse or ld.control is LoadControl.DISPLACEMENT:
            nb = [loads[j] for j in (k_peak - 1, k_peak + 1) if 0 < j < len(loads)]
            resolution = max((abs(peak - x) for x in nb), default=peak)
        collapse = peak
    if bar is not None:
        bar.close()

    hinges_now = [monitor.event(k, kind, side, 0, load, disp, op)
                  for k, kind, side, load, disp, op in open_at_collapse]
    result = Assessment(
        case=case.name, control=ld.control.value, collapse_load=float(collapse),
        resolution=float(resolution), collapsed=bool(collapsed),
        loads=np.array(loads), displacements=np.array(disps), iterations=iters,
        events=events, hinges_at_collapse=hinges_now, limit_load=limit_load,
        limit_status=None if la is None else str(la.status),
        limit_hinges=[] if la is None else [(h.blocks, h.position) for h in la.hinges],
        cells=int(model.blocks.n_cells), anchors=anchors_at_collapse,
        anchor_length=0.0 if anchors is None else anchors.total_length)
    result.elapsed = time.perf_counter() - t_start
    if write:
        write_run_folder(case, result, folder, model, inter, anchors, comm)
    return result


def anchor_state(anchors) -> list[dict]:
    """The state of each anchor (collective): ``name``, ``length`` [m], ``count``,
    ``distance`` [m] of the bar nodes from the anchor's start, ``force`` [N per bar] of
    each bar element (tension positive), ``slip`` [m] at each node, ``force_max`` [N],
    ``slip_max`` [m], ``yield_force`` [N], ``yielded`` and ``ruptured`` element counts."""
    nodes = anchors.node_results()
    force = anchors.axial_force()
    out = []
    for k, a in enumerate(anchors.anchors):
        nn, ee = anchors.anchor_nodes[k], anchors.anchor_elements[k]
        x = anchors.x[nn]
        dist = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(x, axis=0), axis=1))]
        f, slip = force[ee], nodes["slip"][nn]
        out.append({
            "name": a.name, "length": float(a.length), "count": float(a.count),
            "distance": dist.tolist(), "force": f.tolist(), "slip": slip.tolist(),
            "force_max": float(f.max()), "slip_max": float(np.abs(slip).max()),
            "yield_force": float(a.yield_force),
            "yielded": int(np.count_nonzero(anchors.yielded()[ee])),
            "ruptured": int(np.count_nonzero(anchors.ruptured()[ee])),
        })
    return out


def _mean_uy(model, nodes) -> float:
    u = model.u.x.array
    s = sum(float(u[2 * n + 1]) for n in nodes if n >= 0)
    return model.comm.allreduce(s) / len(nodes)


def _prescribe_node_ids(model, gids: set[int], name: str) -> None:
    """Prescribe the vertical dof of the nodes with these input ids (x left free)."""
    ids = np.array(sorted(gids), dtype=np.int64)
    local = np.isin(model.node_input, ids)
    model.prescribe_nodes(_NodeMask(model, local), (None, 0.0), name)


class _NodeMask:
    """A ``where`` for :meth:`Model.prescribe_nodes` that picks given local nodes."""

    def __init__(self, model, mask):
        self.x = model.X[mask]

    def __call__(self, X):
        if self.x.shape[0] == 0:
            return np.zeros(X.shape[1], dtype=bool)
        d = np.min(np.hypot(X[0][:, None] - self.x[None, :, 0],
                            X[1][:, None] - self.x[None, :, 1]), axis=1)
        return d < 1e-12
