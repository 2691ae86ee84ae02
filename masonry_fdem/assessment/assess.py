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
     increment without equilibrium is undone and halved ``refinements`` times. A stall
     is not a collapse (near the peak the structure is so soft that the equilibrium
     iterations run out): with ``follow_peak`` the run goes on from the last
     equilibrium under displacement control, as below; without it, it ends *not
     converged* at the load tried, the last load carried a lower bound;
   * ``control = "displacement"``: a rigid platen (the nodes under the spreader's ends)
     is driven down in steps of ``displacement_increment`` [m] from its self-weight
     position; the load is the platen's reaction. This traces the post-peak branch and
     reaches the peak where load control stops short;
4. one status (:class:`~masonry_fdem.solvers.status.RunStatus`) ends every run:
   *peak passed* (the load fell ``post_peak_drop`` below its peak, or stayed below it for
   ``post_peak_steps`` steps): the peak is the collapse load; *not converged* (a step
   found no equilibrium within ``max_iterations``), *displacement limit reached*
   (``max_displacement``) or *load reached* (``max_load`` carried): no collapse load, the
   largest load carried is a lower bound of it;
5. after every converged step the opening of every radial joint (springings included) at
   its two ends, beyond the self-weight state, and the state of its mortar: an end is
   open when it has opened by more than ``hinge_opening`` times the joint's length (the
   ring thickness; 1e-4 by default) and, for a bonded joint, its mortar there has
   cracked (the tensile or shear strength exceeded at the integration point nearest that
   end: status *softening*, *open* or *sliding*, or the joint handed over to the
   contact; an elastic opening of intact mortar is no hinge). One end open, the other
   not: a hinge (its side, intrados or extrados, named); both ends open: the joint has
   separated. Mortar crushed at a joint is an event of its own (*crushed*). The first
   load at which each joint does so is the hinge sequence. Where a hinge counts from is
   a matter of definition (a crack an observer could not see, or one he could), so the
   first hinge is also reported at wider openings, ``HINGE_OPENINGS`` × the ring
   thickness (:attr:`Assessment.first_hinges`).

Every output goes to one run folder, written only when the run is complete (the files
are assembled in a hidden sibling folder and moved in at the end; a run that fails
leaves nothing): ``report.md`` (the summary with pictures), ``load_displacement.png``,
``mechanism.png`` (deformed blocks, magnified), ``first_hinge.png`` and ``peak_load.png``
(the arch deformed at the first hinge and at the peak load), ``hinges.png`` (the hinges of
FDEM and of the limit analysis on the arch), ``curve.csv`` (its first line ``# status: ...``),
``hinges.csv``, ``summary.json`` and the case file. Units are SI: N, m.
"""

from __future__ import annotations

import logging
import math
import shutil
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from mpi4py import MPI

import numpy as np

from masonry_fdem.assessment.case import ArchCase, CaseError, LoadControl, load_case
from masonry_fdem.assessment.specs import SPREADER, classify_interface, joint_or_contact
from masonry_fdem.geometry.arches import arch_centre, arch_parameter
from masonry_fdem.assessment.report import thrust_lines, write_run_folder
from masonry_fdem.assessment.thrust import JointThrust
from masonry_fdem.checks import numerical_failures
from masonry_fdem.io.rundir import run_folder_problem
from masonry_fdem.solvers.status import RunStatus, Status

__all__ = ["HINGE_OPENINGS", "Assessment", "JointEvent", "anchor_state", "assess", "build_model",
           "status_dict", "status_from_dict"]

log = logging.getLogger(__name__)


#: wider openings (× the joint's length, the ring thickness) at which the first hinge is
#: also reported, beside ``hinge_opening``'s: 0.1 mm and 1 mm on a 0.1 m ring, the
#: second a crack an observer sees (a relative rotation of the blocks of about 0.01 rad)
HINGE_OPENINGS = (1e-3, 1e-2)


@dataclass(frozen=True)
class JointEvent:
    """A joint that opened: a hinge (one end open) or a separation (both ends).

    Attributes:
        order: 1 for the first joint to open, 2 for the next, ...
        joint: ``"ring k joint j"`` (joint j starts voussoir j; 0 and n: the springings).
        blocks: the two blocks.
        kind: "hinge", "separation" or "crushed" (the mortar crushed at an end).
        side: "intrados" or "extrados" (hinge: the side that opens; crushed: the crushed
            side), "" (separation).
        position: ``(x, y)`` [m] of the hinge, the end the blocks rotate about (the
            closed one, as the hinges of limit analysis); crushed: the crushed end;
            separation: the midpoint.
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
        control: "arc-length" (the Newton solver), or "load" or "displacement" (dynamic
            relaxation, as the case asks).
        status: how the run ended (:class:`~masonry_fdem.solvers.status.RunStatus`, loads
            [N]; ``at``: the load [N] tried, or the load-line displacement [m] tried when
            ``stopped_under`` is "displacement"); :attr:`status_line` says it in words.
        peak_load: the largest load carried: the collapse load if the status gives one,
            else a lower bound of it.
        resolution: the load step that failed last (load control) or the largest load
            change between the peak and its neighbouring steps (displacement control).
        loads, displacements: the load–displacement curve at the load line (converged
            steps; displacement downward positive), self-weight state first.
        iterations: DR or Newton iterations of each point of the curve (with a disk fill:
            explicit steps).
        events: the hinge sequence.
        hinges_at_collapse: the joints open at the peak load (with a disk fill: at the end
            of the run, the mechanism's after a mechanism).
        limit_load: the limit-analysis collapse load (None if not run), ``limit_status``
            its LP status, ``limit_explanation`` its outcome in plain words and
            ``limit_hinges`` its hinges (``(blocks, position)``; relative rotations
            only: its sliding and separating interfaces are counted in
            ``limit_explanation``).
        folder, report: the run folder and ``report.md`` (None if not written).
        cells, elapsed: the mesh size and the wall time [s].
        anchors: per anchor at the peak load (see :func:`anchor_state`); empty
            without anchors.
        anchor_length: Σ count × length of the anchors [m] (0 without anchors).
        stopped_under: "load" or "displacement": the control of the last step (under
            load control with ``follow_peak`` the run may end under displacement control).
        anchor_peaks: per anchor, its largest bar force over the whole run [N]
            (``force_max``), the load-line displacement [m] and the load [N] where it
            occurred, and ``yield_force`` [N] (empty without anchors).
        ring_separation: per layer between rings (``layer``: the ring above it), the
            state where it opened widest over the run: ``max_opening`` [m], the
            ``span_fraction`` over which it was separated then (both ends of an
            interface opened by more than ``threshold`` [m], 1e-3 × the ring thickness,
            beyond the self-weight state), and the ``load`` [N] and load-line
            ``displacement`` [m] there (empty for a single ring).
        ring_separation_at_peak: the same keys per layer, in the state at the peak
            load (while the arch is loaded up to its collapse load, before it falls).
    """

    case: str
    control: str
    status: RunStatus
    peak_load: float
    resolution: float
    loads: np.ndarray
    displacements: np.ndarray
    iterations: list[int]
    events: list[JointEvent]
    hinges_at_collapse: list[JointEvent]
    limit_load: float | None = None
    limit_status: str | None = None
    limit_explanation: str = ""
    limit_hinges: list[tuple[tuple[str, str], tuple[float, float]]] = field(
        default_factory=list)
    folder: Path | None = None
    report: Path | None = None
    cells: int = 0
    elapsed: float = 0.0
    anchors: list[dict] = field(default_factory=list)
    anchor_length: float = 0.0
    stopped_under: str = "load"
    anchor_peaks: list[dict] = field(default_factory=list)
    ring_separation: list[dict] = field(default_factory=list)
    ring_separation_at_peak: list[dict] = field(default_factory=list)
    #: the first hinge counted at each opening, ``hinge_opening`` and ``HINGE_OPENINGS``
    #: (× the joint's length): per opening ``ratio``, ``opening`` [m] (of the first
    #: hinge's joint), ``step`` (the curve's index), ``joint``, ``side``, ``s``, ``load``
    #: [N] and ``displacement`` [m]; ``step`` and the rest None where no joint reached it
    first_hinges: list[dict] = field(default_factory=list)
    #: the limit analysis's line of thrust: per ring, the points [m] where the resultant
    #: crosses each radial joint, springing to springing (empty without limit analysis)
    limit_thrust: list[list[tuple[float, float]]] = field(default_factory=list)
    #: the FDEM's line of thrust at the peak load: per ring, the points [m] where the
    #: resultant of the contact and joint forces across each radial joint crosses it,
    #: springing to springing (:class:`~masonry_fdem.assessment.thrust.JointThrust`)
    fdem_thrust: list[list[tuple[float, float]]] = field(default_factory=list)

    @property
    def collapse_load(self) -> float | None:
        """The collapse load [N] if the run proved one (peak passed, mechanism), else None
        (then :attr:`peak_load` is a lower bound of it)."""
        return self.status.collapse_load

    @property
    def collapsed(self) -> bool:
        """Whether the run proved a collapse load."""
        return self.status.status.gives_collapse_load

    @property
    def ratio(self) -> float | None:
        """FDEM collapse load / limit-analysis load (None without either; for a run
        without a collapse load see :attr:`bound_ratio`)."""
        if self.collapse_load is None:
            return None
        return self.bound_ratio

    @property
    def bound_ratio(self) -> float | None:
        """FDEM largest load carried / limit-analysis load (a lower bound of the ratio
        when the run gives no collapse load)."""
        if not self.limit_load or not math.isfinite(self.limit_load):
            return None
        return self.peak_load / self.limit_load

    @property
    def status_line(self) -> str:
        """The status in words, e.g. "peak passed — collapse load 12.20 kN" or "not
        converged at 12.50 kN — the arch carried 12.20 kN, a lower bound of its collapse
        load" (without the detail)."""
        st = self.status
        carried = f"{st.peak / 1e3:.2f} kN"
        if st.status.gives_collapse_load:
            return f"{st.status.value} — collapse load {carried}"
        if st.status is Status.NOT_CONVERGED:
            if st.at is None:
                where = ""
            elif self.stopped_under == "displacement" or st.at_kind == "displacement":
                where = f" at {st.at * 1e3:.3g} mm load-line displacement"
            else:
                where = f" at {st.at / 1e3:.2f} kN"
            head = f"not converged{where}"
        else:
            head = st.status.value
        return f"{head} — the arch carried {carried}, a lower bound of its collapse load"


def status_dict(status: RunStatus) -> dict:
    """A :class:`RunStatus` as a JSON-able dict (:func:`status_from_dict` reads it back)."""
    return {"status": status.status.value, "load": float(status.load),
            "peak": float(status.peak), "at": None if status.at is None else float(status.at),
            "detail": status.detail, "collapse_load": status.collapse_load,
            "at_kind": status.at_kind}


def status_from_dict(d: Mapping[str, Any]) -> RunStatus:
    """The :class:`RunStatus` of a :func:`status_dict`."""
    return RunStatus(Status(d["status"]), float(d["load"]), float(d["peak"]),
                     None if d.get("at") is None else float(d["at"]), d.get("detail", ""),
                     d.get("at_kind", "load"))


# ---------------------------------------------------------------------------- the model

def _settle(solver, joints, case: ArchCase) -> RunStatus:
    """Self-weight by Newton (:meth:`StaticSolver.settle`). With fill, its friction-only
    interfaces are held stuck (tan δ = 10) while the fill takes its weight, then released
    to their own friction in steps of half, each an equilibrium: from zero stress the
    stick/slip split of a friction-only interface does not shrink with the load step, and
    Newton can cycle at the first one (seen on the TRL arch with fill)."""
    if case.fill is None or joints is None:
        return solver.settle()
    jf = case.fill.interface()
    mu = jf.tan_phi

    def release(f: float) -> tuple[float, object]:
        """Halve tan δ from ``f`` down to μ, each an equilibrium; (the last tan δ set,
        the failed solve's reason or None)."""
        while f > mu:
            f = max(mu, 0.5 * f)
            joints.set_friction(jf, f)
            r = solver.solve_retrying(solver.load_factor)
            if not r.converged:
                return f, r.reason
        return f, None

    f = max(10.0, 4.0 * mu)
    joints.set_friction(jf, f)
    st = solver.settle()
    if st.status is not Status.LOAD_REACHED:
        # held stuck, the fill found no equilibrium at some fraction of its weight (the
        # TRL case with its triangles halved: at 0.53): release the interfaces to their
        # own friction where it stands, then go on with the rest of the weight
        f, why = release(f)
        if why is None:
            st = solver.settle(resume=True)
    if st.status is Status.LOAD_REACHED:
        f, why = release(f)
        if why is not None:
            st = RunStatus(Status.NOT_CONVERGED, st.load, st.peak, f,
                           f"the fill's interfaces released to tan δ = {f:.3g}: Newton did "
                           f"not converge ({why})")
    joints.set_friction(jf, mu)  # (a failure falls back on dynamic relaxation)
    return st


def case_limit_analysis(case: ArchCase, comm: MPI.Comm = MPI.COMM_WORLD):
    """The limit analysis of an assessment (collective; run on rank 0, broadcast), or None
    when the case's ``analysis.limit_analysis`` is off. No bond in the LP: the joints slide
    at ``analysis.friction``, a friction-only layer that the FDEM model has as a joint (the
    sand between rings) at its own tan φ."""
    if not case.analysis.limit_analysis:
        return None
    la = None
    if comm.rank == 0:
        dry = [(on, jm.tan_phi) for on, jm in case.joint_rules()
               if jm is not None and not jm.bonded and jm.kn is not None]
        try:
            la = case.limit_analysis(friction=lambda _a, _b, mid: next(
                (mu for on, mu in dry if on(mid)), case.analysis.friction))
            if la.status == "infeasible":
                log.warning("%s: limit analysis: %s", case.name, la.explanation)
        except (RuntimeError, ArithmeticError, ValueError) as exc:
            la = exc  # raised on every rank below, none left waiting
    la = comm.bcast(la if comm.rank == 0 else None, root=0)
    if isinstance(la, Exception):
        raise la
    return la


def limit_rotation_hinges(la) -> list[tuple[tuple[str, str], tuple[float, float]]]:
    """``(blocks, position)`` of the limit analysis's hinges (relative rotation about one
    end); its sliding and separating interfaces left out (empty without an LP)."""
    from masonry_fdem.solvers.limit_analysis import HingeKind

    if la is None:
        return []
    return [(h.blocks, h.position) for h in la.hinges if h.kind == HingeKind.HINGE]


def limit_load_of(la) -> float | None:
    """The collapse load [N] of a limit analysis (None without one, or when it found none:
    infinite or infeasible)."""
    load = float(la.load_factor) if la is not None else None
    return load if load is not None and math.isfinite(load) else None


def progress_bar(name: str, progress, comm: MPI.Comm):
    """The progress display :func:`assess` asks for with ``progress`` (see there), or None
    (collective)."""
    from masonry_fdem.io import ProgressBar

    if progress is False:
        return None
    if progress not in (None, True, "bar", "lines"):
        raise ValueError(f"progress={progress!r}: expected None, True, False, 'bar' or "
                         "'lines'")
    return ProgressBar(name, comm=comm, mode="lines" if progress == "lines" else "bar",
                       force=progress is True)


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
    from masonry_fdem.interactions import BlockContact, Joints

    layout = case.mesh_layout()
    sizes = [case.arch.mesh_size] * len(layout)
    hyp = {}
    friction_table = {}
    fill = case.fill
    if fill is not None:
        # the fill, its end walls (coarse: fixed), the loading beam (two elements thick)
        size = {"fill": fill.mesh_size, "spreader": 0.5 * SPREADER[1]}
        sizes = [size.get(n, fill.wall_thickness if n.startswith("wall:") else
                          case.arch.mesh_size) for n in layout.names]
        hyp = {fill.material: "plane_strain"}
        friction_table = {pair: fill.interface_friction for pair, jm in
                          case.joint_materials().items() if fill.material in pair}
    mesh = layout.mesh(sizes, comm, crossed=("fill",) if fill is not None and fill.crossed
                       else ())
    model = Model(mesh, case.materials(), hypotheses=hyp, width=case.arch.width, comm=comm)
    model.fix_blocks("abutment:*", name="abutments")
    if fill is not None:
        model.fix_blocks("wall:*", name="walls")
        if any(n.startswith("backing:") for n in layout.names):
            model.fix_blocks("backing:*", name="backing")
        # the loading beam is guided: it moves down without sliding or tilting
        model.prescribe_velocity(SPREADER[0], (0.0, None), name="beam guide")
    if case.loading.self_weight:
        model.add_gravity()
    contact = BlockContact(model, case.analysis.contact_settings(friction_table=friction_table))

    table = {k: joint_or_contact(v) for k, v in case.joint_materials().items()}
    rules = [(where, joint_or_contact(jm)) for where, jm in case.joint_rules(layout)]
    joints = Joints(model, table, where=rules, contact=contact)
    joints.set_softening(case.analysis.softening)
    specs = case.anchors()
    anchors = Anchors(model, specs) if specs else None
    return model, [contact, joints], anchors


class _InterfaceOpenings:
    """Normal openings at the two ends of the arch's interfaces of one kind ("joint":
    radial joints, "ring": the layers between rings), minus the self-weight state's
    (collective). ``rows``: per interface ``(interface, (ring, index), (name a, name b),
    block a, block b)``; ``ends`` ``(n, 2, 2)`` [m]; ``normal`` from block a to b; ``node``
    the node of each block nearest each end (-1: on another rank)."""

    def __init__(self, case: ArchCase, model, kind: str):
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
            if where is not None and where[0] == kind:
                self.rows.append((i, where[1:], (na, nb), names.index(na), names.index(nb)))
        n = len(self.rows)
        self.ends = np.zeros((n, 2, 2))
        self.normal = np.zeros((n, 2))
        self.node = -np.ones((n, 2, 2), dtype=np.int64)  # [interface, end, block a/b]
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


class _JointMonitor(_InterfaceOpenings):
    """Openings and mortar states of the radial joints at their two ends (collective)."""

    def __init__(self, case: ArchCase, model, joints=None):
        super().__init__(case, model, "joint")
        self.labels = [f"ring {w[0]} joint {w[1]}" for _, w, _, _, _ in self.rows]
        n = len(self.rows)
        self.side = [self._intrados_end(k) for k in range(n)]
        self.length = np.linalg.norm(self.ends[:, 1] - self.ends[:, 0], axis=1)
        # the mortar's integration point of each joint nearest each end, and its
        # segment (-1: a dry joint)
        self.joints = joints
        self.point = -np.ones((n, 2), dtype=np.int64)
        if joints is not None and joints.n_segments:
            sb = joints.seg_blocks[joints.q_seg]
            xp = joints.point_positions()
            for k, (_, _, _, ba, bb) in enumerate(self.rows):
                mine = np.flatnonzero(((sb[:, 0] == ba) & (sb[:, 1] == bb))
                                      | ((sb[:, 0] == bb) & (sb[:, 1] == ba)))
                if mine.size == 0:
                    continue
                for e in range(2):
                    d = np.linalg.norm(xp[mine] - self.ends[k, e], axis=1)
                    self.point[k, e] = mine[int(np.argmin(d))]

    def _intrados_end(self, k: int) -> int:
        """0 or 1: the end of joint k nearer the arch's centre of curvature."""
        arch = self.case.arch
        c = arch_centre(arch.kind, arch.span, arch.rise, self.ends[k].mean(axis=0)[0])
        d = np.linalg.norm(self.ends[k] - c, axis=1)
        return int(np.argmin(d))

    def classify(self, ratio: float) -> tuple[list[tuple[int, str, str]], np.ndarray]:
        """``(row, kind, side)`` of the joints that are hinges, separated or crushed (see
        the module doc: an end opened by more than ``ratio`` × the joint's length, its
        mortar cracked through), and the openings [m]."""
        outs, op = self.classify_at((ratio,))
        return outs[0], op

    def classify_at(self, ratios: Sequence[float]
                    ) -> tuple[list[list[tuple[int, str, str]]], np.ndarray]:
        """:meth:`classify` at each of ``ratios`` from one evaluation of the openings and
        the mortar's states (collective): the lists, and the openings [m]."""
        from masonry_fdem.interactions.joints.joints import JOINT_STATES

        op = self.openings()
        intact = np.zeros(op.shape, dtype=bool)  # ends whose mortar has not cracked
        crushed = np.zeros(op.shape, dtype=bool)
        if self.joints is not None and self.joints.n_segments:
            st = self.joints.point_status()  # collective
            has = self.point >= 0
            pt = np.where(has, self.point, 0)
            # cracked: the tensile (or shear) strength exceeded there — softening, open or
            # sliding — or the joint handed over to the contact
            cracked = (st >= JOINT_STATES.index("softening")) & (
                st != JOINT_STATES.index("crushed"))
            cracked |= np.repeat(self.joints.released, 2)
            intact = has & ~cracked[pt]
            crushed = has & (st[pt] == JOINT_STATES.index("crushed"))
        outs = []
        for ratio in ratios:
            opened = (op > ratio * self.length[:, None]) & ~intact
            out = []
            for k in range(len(self.rows)):
                if opened[k].all():
                    out.append((k, "separation", ""))
                elif opened[k].any():
                    end = int(np.argmax(np.where(opened[k], op[k], -np.inf)))
                    out.append((k, "hinge", "intrados" if end == self.side[k]
                                else "extrados"))
                elif crushed[k].any():
                    end = int(np.argmax(crushed[k]))
                    out.append((k, "crushed", "intrados" if end == self.side[k]
                                else "extrados"))
            outs.append(out)
        return outs, op

    def event(self, k: int, kind: str, side: str, order: int, load: float,
              disp: float, opening: np.ndarray) -> JointEvent:
        """The event of joint k, its ``opening`` at both ends [m] given."""
        label, blocks = self.labels[k], self.rows[k][2]
        if kind == "hinge":
            pos = self.ends[k, int(np.argmin(opening))]
        elif kind == "crushed":
            pos = self.ends[k, self.side[k] if side == "intrados" else 1 - self.side[k]]
        else:
            pos = self.ends[k].mean(axis=0)
        a = self.case.arch
        s = arch_parameter(a.kind, a.span, a.rise, self.ends[k].mean(axis=0))
        return JointEvent(order, label, blocks, kind, side, (float(pos[0]), float(pos[1])),
                          float(s), float(load), float(disp))


class _RingMonitor(_InterfaceOpenings):
    """Radial openings of the interfaces between rings (the sand or collar layers), at
    both ends of each interface, minus the self-weight state's (collective).

    A layer counts as separated where it has opened by more than ``SEPARATION`` × the
    ring thickness beyond the self-weight state: 1e-3 × 0.109 m = 0.11 mm on the TRL arch,
    fifty times the elastic decompression of its sand layers under self-weight (about
    10 kPa / 5e9 Pa/m = 2 µm); a cohesionless layer has no tensile strength, so any
    clear opening is a separation."""

    SEPARATION = 1e-3

    def __init__(self, case: ArchCase, model):
        super().__init__(case, model, "ring")
        self.span = case.arch.span
        self.threshold = self.SEPARATION * case.arch.ring_thickness
        self.layer = np.array([w[0] for _, w, _, _, _ in self.rows], dtype=np.int64)
        self.extent = np.abs(self.ends[:, 1, 0] - self.ends[:, 0, 0])  # [m] along x

    def layers(self) -> list[dict]:
        """Per layer (``layer``: the ring above it): the largest opening [m] and the
        fraction of the span [-] over which the layer is separated (both ends of an
        interface open beyond the threshold) now."""
        op = self.openings()
        out = []
        for r in np.unique(self.layer):
            mine = self.layer == r
            sep = mine & (op.min(axis=1) > self.threshold)
            out.append({"layer": int(r), "max_opening": float(op[mine].max()),
                        "span_fraction": float(self.extent[sep].sum() / self.span),
                        "threshold": float(self.threshold)})
        return out


# ---------------------------------------------------------------------------- the run
@numerical_failures("the assessment")
def assess(
    case: ArchCase | str | Path | Mapping[str, Any],
    *,
    out: str | Path | None = None,
    overwrite: bool = False,
    progress: bool | str | None = None,
    comm: MPI.Comm = MPI.COMM_WORLD,
    write: bool = True,
    callback: Callable[[dict], None] | None = None,
    resume: bool = False,
    checkpoint_every: int = 10,
) -> Assessment:
    """Load an arch case to collapse and report it (collective; see the module doc).

    Args:
        case: an :class:`~masonry_fdem.assessment.case.ArchCase`, a TOML file or a dict of one.
        out: the run folder (default: the case's ``analysis.output``).
        overwrite: allow a run folder that exists and is not empty.
        progress: progress of rank 0: ``"bar"`` or True, a tqdm bar on stderr that counts
            the increments (True: even when stderr is not a terminal); ``"lines"``,
            one line per increment on stdout (load factor = load / limit-analysis
            load, load [kN], load-line displacement [mm], iterations, status);
            False, none; None (default), the bar when stderr is a terminal.
        comm: MPI communicator.
        write: write the run folder (False: compute only).
        callback: called on every rank after each converged step with
            ``{"load": N, "displacement": m, "iterations": int, "model": the Model,
            "interactions": [BlockContact, Joints], "anchors": Anchors or None}`` (the
            model at that equilibrium: read
            it, e.g. ``Joints.forces_on``; collective calls on every rank).
        resume: go on from the checkpoint in the run folder (same case, same number of
            ranks) instead of starting afresh; the result is the one the run would have
            given (bit for bit).
        checkpoint_every: under the Newton solver (with ``write``), write a checkpoint
            into ``<run folder>/checkpoint`` every this many converged increments of the
            path (0: only on a stop); removed when the run finishes. A stop requested
            by a signal (:func:`~masonry_fdem.io.checkpoint.stop_on_signals`) ends the
            run at the next converged increment with a checkpoint and
            :class:`~masonry_fdem.io.checkpoint.Interrupted`.

    Raises:
        CaseError: a bad case, or a run folder that is not free; nothing is written.
        NumericalError: a solve broke down (NaN, overflow, a PETSc or HiGHS failure), with
            the likely cause.
        CheckpointError: ``resume`` without a usable checkpoint (none, corrupt, another
            number of ranks, or the case changed since the run began).
        Interrupted: stopped on request after writing a checkpoint.
    """
    from masonry_fdem.io.checkpoint import (
        Checkpointer,
        CheckpointError,
        Interrupted,
        rearm,
        stop_requested,
    )

    t_start = time.perf_counter()
    if not isinstance(case, ArchCase):
        case = load_case(case)
    folder = Path(out) if out is not None else case.analysis.output
    if resume and not write:
        raise ValueError("resume needs the run folder (write=True)")
    if write and not resume:
        error = run_folder_problem(folder, overwrite=overwrite, comm=comm)
        if error and (folder / "checkpoint" / "CURRENT").is_file():
            error += f" (it holds the checkpoint of a stopped run: --resume {folder})"
        if error:
            raise CaseError(error, str(case.source) if case.source else None)
    if case.fill is not None and case.fill.model == "disks":
        if resume:
            raise CheckpointError(f"{case.name}: runs with a disk fill are not "
                                  "checkpointed; this one cannot be resumed")
        from masonry_fdem.assessment.disk_fill import assess_disk_fill

        return assess_disk_fill(case, folder=folder, write=write, progress=progress,
                                comm=comm, callback=callback, t_start=t_start)
    ck = None
    if write and case.analysis.solver == "newton":
        ck = Checkpointer(folder, comm, kind="assess", every=checkpoint_every,
                          meta={"case": case.name, "case_sha256": case_digest(case),
                                "case_file": (str(Path(case.source).resolve())
                                              if case.source else None)})
    resumed = None
    if resume:
        if ck is None:
            raise CheckpointError(f"{case.name}: only runs of analysis.solver = \"newton\" "
                                  "are checkpointed; this one cannot be resumed")
        manifest, resumed = ck.read()
        elapsed0 = float(resumed["assess"]["elapsed"])
        if comm.rank == 0:
            log.info("%s: resuming from %s (increment %d)", case.name,
                     manifest["generation"], manifest["step"])
    from masonry_fdem.solvers import DynamicRelaxation

    ld = case.loading
    an = case.analysis
    la = resumed["assess"]["la"] if resumed is not None else case_limit_analysis(case, comm)
    limit_load = limit_load_of(la)

    model, inter, anchors = build_model(case, comm)
    rearm()  # (the mesh generator resets the signal handlers)
    monitor = _JointMonitor(case, model, next((i for i in inter if i.name == "joints"), None))
    rings = _RingMonitor(case, model)
    points = case.load_points()
    bar = progress_bar(case.name, progress, comm)

    prestressed = anchors is not None and any(a.prestress > 0 for a in anchors.anchors)
    newton = an.solver == "newton"
    if newton:
        from masonry_fdem.solvers.static import StaticSolver

        solver = StaticSolver(model, interactions=_with(inter, anchors), rtol=an.newton_rtol,
                              max_it=an.newton_iterations)
    it0 = 0  # (a resumed run takes it from the checkpoint)
    if newton and resumed is None:
        st0 = _settle(solver, next((i for i in inter if i.name == "joints"), None), case)
        ok, why = st0.status is Status.LOAD_REACHED, st0.detail
        if not ok:
            # Newton from the unloaded state, where the blocks only touch, can overshoot
            # (stiff contact, many dry joints): dynamic relaxation settles the arch, then
            # Newton takes over from its equilibrium
            if comm.rank == 0:
                log.info("%s: Newton did not settle the arch under self-weight (%s); "
                         "dynamic relaxation settles it, Newton goes on from there",
                         case.name, why)
            res = DynamicRelaxation(model, interactions=_with(inter, anchors),
                                    rtol=an.dr_rtol, ke_tol=math.inf,
                                    max_iter=an.max_iterations, damping="velocity").solve(0.0)
            solver.dead_factor = 1.0
            solver.commit()
            r0 = solver.solve(0.0, max_it=max(an.newton_iterations, 100))
            # Newton's convergence from there proves the equilibrium, whether or not the
            # relaxation reached its own tolerance first
            ok = r0.converged
            why = (f"dynamic relaxation: {res.iterations} iterations"
                   f"{'' if res.converged else ' (not converged)'}, then Newton: {r0.reason}")
        if ok and prestressed:
            # prestressed anchors: equilibrium under self-weight and the jacking forces,
            # then lock-off (the bond acts from here on) and equilibrium again
            anchors.lock_off()
            r0 = solver.solve(0.0)
            ok, why = r0.converged, f"after the anchors' lock-off ({r0.reason})"
        if not ok:
            raise RuntimeError(f"{case.name}: Newton found no equilibrium under self-weight "
                               f"({why}): the arch cannot stand (or try analysis.solver = "
                               "\"dr\")")
        it0 = sum(r.iterations for r in solver.results)
    elif resumed is None:
        dr = DynamicRelaxation(model, interactions=_with(inter, anchors), rtol=an.dr_rtol,
                               ke_tol=math.inf, max_iter=an.max_iterations, damping="velocity")
        res = dr.solve(0.0)
        if res.converged and prestressed:
            anchors.lock_off()
            it_sw = res.iterations
            res = dr.solve(0.0)
            res = replace(res, iterations=res.iterations + it_sw)
        if not res.converged:
            raise RuntimeError(f"{case.name}: no equilibrium under self-weight within "
                               f"{res.iterations} iterations (analysis.max_iterations): the "
                               "arch cannot stand, or needs more iterations")
        it0 = res.iterations
    monitor.base = monitor.openings() + monitor.base
    rings.base = rings.openings() + rings.base
    separation: dict[int, dict] = {}  # per layer: its widest opening over the run
    # deformed states for the report's pictures: at the first hinge and at the peak load
    snapshots: dict[str, tuple[np.ndarray, float, float]] = {}
    loads, disps, iters = [0.0], [0.0], [it0]
    events: list[JointEvent] = []
    seen: set[tuple[int, str]] = set()  # (joint, kind) already in the sequence
    state: dict[str, Any] = {"open": [], "anchors": [], "fdem_thrust": []}
    # the first hinge at each opening (``hinge_opening``'s is the sequence's first hinge)
    first_hinges = [{"ratio": float(r), "opening": None, "step": None, "joint": None,
                     "side": None, "s": None, "load": None, "displacement": None}
                    for r in sorted({an.hinge_opening, *HINGE_OPENINGS})]
    thrust = JointThrust(case, model)
    anchor_peaks: dict[str, dict] = {}  # per anchor: its largest bar force over the run

    # load-line displacement: mean vertical displacement of the nodes nearest the points
    load_nodes = [model.nearest_node(p, case.load_blocks()) for p in points]
    u_sw = _mean_uy(model, load_nodes) if resumed is None else 0.0
    best = {"load": -math.inf}
    open_at_collapse: list = []
    anchors_at_collapse: list = state["anchors"]

    def run_state() -> dict:
        """This rank's record of the run so far (for a checkpoint)."""
        return {"loads": loads, "disps": disps, "iters": iters, "events": events,
                "seen": seen, "state": state, "anchor_peaks": anchor_peaks,
                "snapshots": snapshots, "separation": separation, "best": best,
                "first_hinges": first_hinges, "monitor_base": monitor.base,
                "rings_base": rings.base, "u_sw": u_sw,
                "open_at_collapse": open_at_collapse,
                "anchors_at_collapse": anchors_at_collapse, "it0": it0, "la": la,
                "elapsed": elapsed0 + time.perf_counter() - t_start}

    elapsed0 = 0.0 if resumed is None else elapsed0
    if resumed is not None:
        r = resumed["assess"]
        it0, u_sw = r["it0"], r["u_sw"]
        monitor.base, rings.base = r["monitor_base"], r["rings_base"]
        for mine, theirs in ((loads, r["loads"]), (disps, r["disps"]), (iters, r["iters"]),
                             (events, r["events"]), (first_hinges, r["first_hinges"])):
            mine[:] = theirs
        for mine, theirs in ((state, r["state"]), (anchor_peaks, r["anchor_peaks"]),
                             (snapshots, r["snapshots"]), (separation, r["separation"]),
                             (best, r["best"])):
            mine.clear()
            mine.update(theirs)
        seen.update(r["seen"])
        open_at_collapse = r["open_at_collapse"]
        anchors_at_collapse = r["anchors_at_collapse"]

    # the ParaView series (collective): the state at the start (self-weight, or where a
    # resumed run goes on: its own series, the earlier one kept), every `every`
    # converged increments, and the last
    every = an.paraview_every
    vtx = None
    if write and every > 0:
        from masonry_fdem.io import VTXOutput

        sub = "paraview" if resumed is None else f"paraview_from_{len(loads) - 1}"
        if comm.rank == 0:  # (an overwritten run's frames would outnumber this one's)
            shutil.rmtree(folder / sub, ignore_errors=True)
        comm.barrier()
        vtx = VTXOutput(model, folder / sub, joints=monitor.joints)
        vtx.write(float(len(loads) - 1), velocity=0.0)
    written = {"last": len(loads) - 1}

    def frame() -> None:
        if vtx is not None and written["last"] != len(loads) - 1:
            vtx.write(float(len(loads) - 1), velocity=0.0)
            written["last"] = len(loads) - 1

    def record(load: float, iterations: int) -> None:
        disp = u_sw - _mean_uy(model, load_nodes)
        loads.append(float(load))
        disps.append(float(disp))
        iters.append(int(iterations))
        # the case's opening, and the wider ones whose first hinge is still to come
        wider = [fh for fh in first_hinges
                 if fh["step"] is None and fh["ratio"] != an.hinge_opening]
        outs, op = monitor.classify_at([an.hinge_opening] + [fh["ratio"] for fh in wider])
        opened = outs[0]
        state["open"] = [(k, kind, side, load, disp, op[k]) for k, kind, side in opened]
        layers = rings.layers()
        for lay in layers:
            best = separation.get(lay["layer"])
            if best is None or lay["max_opening"] > best["max_opening"]:
                separation[lay["layer"]] = {**lay, "load": float(load),
                                            "displacement": float(disp)}
        if anchors is not None:
            state["anchors"] = anchor_state(anchors)
            for a in state["anchors"]:
                pk = anchor_peaks.setdefault(a["name"], {
                    "name": a["name"], "force_max": -math.inf, "displacement": 0.0,
                    "load": 0.0, "yield_force": a["yield_force"]})
                if a["force_max"] > pk["force_max"]:
                    pk.update(force_max=a["force_max"], displacement=float(disp),
                              load=float(load))
                if "dowel_max" in a and a["dowel_max"] > pk.get("dowel_max", -1.0):
                    pk.update(dowel_max=a["dowel_max"], dowel_strength=a["dowel_strength"],
                              dowel_load=float(load))
        for k, kind, side in opened:
            if (k, kind) not in seen:
                seen.add((k, kind))
                events.append(monitor.event(k, kind, side, len(events) + 1, load, disp,
                                            op[k]))
        own = next(fh for fh in first_hinges if fh["ratio"] == an.hinge_opening)
        for fh, here in zip([own, *wider], outs, strict=True):
            if fh["step"] is not None:
                continue
            hinge = [(k, side) for k, kind, side in here if kind == "hinge"]
            if hinge:
                k, side = max(hinge, key=lambda x: op[x[0]].max())
                e = monitor.event(k, "hinge", side, 0, load, disp, op[k])
                fh.update(opening=float(op[k].max()), step=len(loads) - 1, joint=e.joint,
                          side=side, s=e.s, load=float(load), displacement=float(disp))
        if "first hinge" not in snapshots and any(e.kind == "hinge" for e in events):
            snapshots["first hinge"] = (model.u.x.array.copy(), float(load), float(disp))
        if "peak load" not in snapshots or load > snapshots["peak load"][1]:
            snapshots["peak load"] = (model.u.x.array.copy(), float(load), float(disp))
            state["separation_at_peak"] = [{**lay, "load": float(load),
                                            "displacement": float(disp)} for lay in layers]
            state["fdem_thrust"] = thrust.lines(inter)
            if case.fill is not None and write:
                # the load's path through the fill: σ_yy per cell at the peak
                model.update_stress()
                n = model.dmesh.cell_input.size
                state["stress"] = (model.stress.x.array.reshape(-1, 4)[:n, 3].copy(),
                                   model.u.x.array.copy(), float(load), float(disp))
        if bar is not None:
            past = load < max(loads[:-1])
            factor = f"{load / limit_load:.3f}" if limit_load else "-"
            bar.increment(f"{case.name}: increment {len(loads) - 1}: load factor {factor}, "
                          f"load {load / 1e3:.3f} kN, displacement {disp * 1e3:.4f} mm, "
                          f"iterations {iterations}, "
                          f"{'converged, past the peak' if past else 'converged'}",
                          load=f"{load / 1e3:.2f} kN", u=f"{disp * 1e3:.3f} mm",
                          open=len({k for k, _ in seen}))
        if (len(loads) - 1) % max(every, 1) == 0:
            frame()
        if callback is not None:
            callback({"load": load, "displacement": disp, "iterations": iterations,
                      "model": model, "interactions": inter, "anchors": anchors})
        if ck is None and comm.allreduce(stop_requested(), op=MPI.LOR):
            raise Interrupted(folder, len(loads) - 1, (
                f"interrupted: {case.name} stopped at step {len(loads) - 1}; dynamic "
                "relaxation runs write no checkpoint: run the case again to finish it"))

    collapse, resolution = 0.0, 0.0
    status: RunStatus | None = None
    if newton:
        # path following: past the peak until the load falls to half its maximum, or to
        # the displacement limit
        span_t = case.arch.rings * case.arch.ring_thickness
        d_inc = ld.displacement_increment or 1e-5 * case.arch.span
        d_max = ld.max_displacement or 0.5 * span_t

        def on_point(p) -> None:
            nonlocal open_at_collapse, anchors_at_collapse
            record(p.load, p.iterations)
            if p.load > best["load"]:
                best["load"] = p.load
                open_at_collapse = state["open"]
                anchors_at_collapse = state["anchors"]

        common = dict(max_displacement=d_max, max_load=ld.max_load or math.inf,
                      peak_drop=an.post_peak_drop, stop_drop=max(0.5, an.post_peak_drop),
                      max_steps=an.newton_steps, callback=on_point,
                      # down to 1/1024 of the increment: sliding sand layers and
                      # stitches switch between stick and slip in steps of ~0.1 µm
                      min_increment=d_inc / 1024.0)
        # under either control: indirect displacement control of the load-line
        # displacement (equal forces on the spreader's ends, as a spreader beam jacked
        # at its middle gives; dynamic relaxation's "displacement" is a rigid platen)
        for p in points:
            model.add_point_load(p, (0.0, -1.0 / len(points)), blocks=case.load_blocks())
        path = None
        if resumed is not None:
            solver.set_checkpoint_state(resumed["solver"])
            path = resumed["path"]

        def safe_point(steps: int, path_state: dict) -> None:
            ck.safe_point(steps, lambda: {"solver": solver.checkpoint_state(),
                                          "path": path_state, "assess": run_state()})

        run = solver.follow(d_inc, **common, safe_point=safe_point if ck else None,
                            resume=path)
        st = run.status
        status = replace(st, detail=f"Newton, arc length on the load-line displacement: "
                                    f"{st.detail}")
        stopped_under = "displacement"
        collapse = float(st.peak)
        if len(loads) > 1:
            k_peak = int(np.argmax(loads))
            nb = [loads[j] for j in (k_peak - 1, k_peak + 1) if 0 < j < len(loads)]
            resolution = max((abs(collapse - x) for x in nb), default=collapse)
    else:
        stalled = ""  # under load control with follow_peak: where load control stalled
        drive_from = None  # load-line displacement [m] where displacement control starts
        if ld.control is LoadControl.LOAD:
            for p in points:
                model.add_point_load(p, (0.0, -1.0 / len(points)), blocks=case.load_blocks())

            def on_step(r) -> None:
                if r.converged:
                    record(r.load_factor, r.iterations)

            cres = dr.load_to_collapse(ld.increment, max_load=ld.max_load or math.inf,
                                       refinements=an.refinements, callback=on_step)
            collapse, resolution = cres.load_factor, cres.resolution
            open_at_collapse = state["open"]
            anchors_at_collapse = state["anchors"]
            st = cres.status
            if st.status is Status.LOAD_REACHED:
                status = replace(st, detail=f"max_load = {ld.max_load / 1e3:.2f} kN carried")
            else:
                stalled = (f"load control: no equilibrium at {st.at / 1e3:.2f} kN within "
                           f"max_iterations = {an.max_iterations}, refinements = "
                           f"{an.refinements}")
                status = replace(st, detail=stalled)
            if st.status is Status.NOT_CONVERGED and an.follow_peak:
                # no equilibrium within the iteration limit is not yet proof that none
                # exists (near the peak the structure is so soft that DR stalls): go on from
                # the last equilibrium by driving the platen down
                drive_from = disps[-1]
                # (a quarter of the displacement reached, but not below span/1e5 when the
                # first increment already failed)
                dstep = ld.displacement_increment or max(disps[-1] / 4.0, 1e-5 * case.arch.span)
        else:
            drive_from, dstep = 0.0, ld.displacement_increment
        stopped_under = ld.control.value
        if drive_from is not None:
            stopped_under = "displacement"
            sel = [int(n) for n in load_nodes]
            ids = comm.allgather([int(model.node_input[n]) for n in sel if n >= 0])
            _prescribe_node_ids(model, {g for part in ids for g in part}, "platen")
            lf = collapse if ld.control is LoadControl.LOAD else 0.0
            # the live load stays as it was; the platen's reaction adds to it
            dr = DynamicRelaxation(model, interactions=_with(inter, anchors), rtol=an.dr_rtol,
                                   ke_tol=math.inf, max_iter=an.max_iterations,
                                   damping="velocity")
            peak, k_peak, falling = collapse, len(loads) - 1, 0
            then = f"{stalled}; then " if stalled else ""
            step = 0
            while True:
                step += 1
                d = drive_from + step * dstep
                if ld.max_displacement is not None and d > ld.max_displacement * (1 + 1e-12):
                    status = RunStatus(Status.DISPLACEMENT_LIMIT, loads[-1], peak, None,
                                       f"{then}max_displacement = "
                                       f"{ld.max_displacement * 1e3:.3g} mm reached before the "
                                       "load passed a peak")
                    break
                r = dr.solve(lf, displacement={"platen": (None, u_sw - d)})
                if not r.converged:
                    status = RunStatus(Status.NOT_CONVERGED, loads[-1], peak, d,
                                       f"{then}displacement control: no equilibrium at "
                                       f"{d * 1e3:.3g} mm within max_iterations = "
                                       f"{an.max_iterations}", at_kind="displacement")
                    break
                load = lf - float(dr.reactions()["platen"][1])
                record(load, r.iterations)
                if load > peak:
                    peak, k_peak, falling = load, len(loads) - 1, 0
                    open_at_collapse = state["open"]
                    anchors_at_collapse = state["anchors"]
                else:
                    falling += 1
                fell = 100.0 * (1.0 - load / peak) if peak > 0 else math.nan
                if load < (1 - an.post_peak_drop) * peak:
                    status = RunStatus(Status.PEAK_PASSED, load, peak, None,
                                       f"the load fell {fell:.1f} % below its peak "
                                       f"(post_peak_drop = {an.post_peak_drop:g})")
                    break
                if falling >= an.post_peak_steps:
                    status = RunStatus(Status.PEAK_PASSED, load, peak, None,
                                       f"the load stayed below its peak for {falling} "
                                       f"step(s) (post_peak_steps), {fell:.1f} % below it at "
                                       "the last")
                    break
                if ld.max_load is not None and load >= ld.max_load:
                    # carries the load asked for; no collapse sought
                    status = RunStatus(Status.LOAD_REACHED, load, peak, None,
                                       f"max_load = {ld.max_load / 1e3:.2f} kN carried")
                    break
            if peak > collapse or ld.control is LoadControl.DISPLACEMENT:
                nb = [loads[j] for j in (k_peak - 1, k_peak + 1) if 0 < j < len(loads)]
                resolution = max((abs(peak - x) for x in nb), default=peak)
            collapse = peak
    assert status is not None
    if bar is not None:
        bar.close()

    hinges_now = [monitor.event(k, kind, side, 0, load, disp, op)
                  for k, kind, side, load, disp, op in open_at_collapse]
    result = Assessment(
        case=case.name, control="arc-length" if newton else ld.control.value, status=status,
        peak_load=float(collapse),
        resolution=float(resolution), stopped_under=stopped_under,
        loads=np.array(loads), displacements=np.array(disps), iterations=iters,
        events=events, hinges_at_collapse=hinges_now, limit_load=limit_load,
        limit_status=None if la is None else str(la.status),
        limit_explanation="" if la is None else la.explanation,
        limit_hinges=limit_rotation_hinges(la),
        limit_thrust=[] if la is None else thrust_lines(case, la),
        fdem_thrust=state["fdem_thrust"],
        cells=int(model.blocks.n_cells), anchors=anchors_at_collapse,
        anchor_length=0.0 if anchors is None else anchors.total_length,
        anchor_peaks=list(anchor_peaks.values()),
        ring_separation=[separation[r] for r in sorted(separation)],
        ring_separation_at_peak=list(state.get("separation_at_peak", [])),
        first_hinges=first_hinges)
    if vtx is not None:
        frame()
        vtx.close()
    result.elapsed = elapsed0 + time.perf_counter() - t_start
    if comm.rank == 0:
        log.info("%s: %s (%s)", case.name, result.status_line, status.detail)
    if write:
        write_run_folder(case, result, folder, model, inter, anchors, comm,
                         snapshots=snapshots, stress=state.get("stress"))
        if ck is not None:
            ck.remove()  # finished: nothing to resume
    return result


def case_digest(case: ArchCase) -> str:
    """SHA-256 of a case: of its file when it came from one, else of its parsed form
    (a resume checks that the case did not change since the run began)."""
    import hashlib

    src = Path(case.source) if case.source else None
    if src is not None and src.is_file():
        return hashlib.sha256(src.read_bytes()).hexdigest()
    return hashlib.sha256(repr(case).encode()).hexdigest()


def anchor_state(anchors) -> list[dict]:
    """The state of each anchor (collective): ``name``, ``length`` [m], ``count``,
    ``distance`` [m] of the bar nodes from the anchor's start, ``force`` [N per bar] of
    each bar element (tension positive), ``slip`` [m] at each node, ``force_max`` [N],
    ``slip_max`` [m], ``yield_force`` [N], ``yielded`` and ``ruptured`` element counts;
    with a joint dowel (``Anchor.shear``), ``dowel_max`` [N per bar], the largest |force|
    of its dowels across the joints, and ``dowel_strength`` [N per bar] (None: elastic)."""
    nodes = anchors.node_results()
    force = anchors.axial_force()
    dowels = anchors.dowel_results()
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
        if a.shear is not None:
            mine = dowels["anchor"] == k
            out[-1]["dowel_max"] = float(np.abs(dowels["force"][mine]).max(initial=0.0))
            st = float(a.shear.strength)  # None: an elastic dowel
            out[-1]["dowel_strength"] = st if math.isfinite(st) else None
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
