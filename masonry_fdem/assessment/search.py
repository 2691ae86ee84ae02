"""The anchor layout search of ``masonry-fdem repair``.

:func:`search` looks for a near-optimal anchor layout over the candidate space of the
case's ``[search]`` table (:class:`~masonry_fdem.assessment.case.SearchSpec`): straight anchors
drilled from the intrados (:func:`~masonry_fdem.assessment.layouts.inclined_anchors`) at
``count`` of the ``positions``, each ``inclination``, ``length`` and ``prestress``.

* **Checks first.** A layout whose anchor leaves the structure (through the extrados,
  into the air past a springing, through a missing voussoir) or whose anchors overlap
  (closer than ``min_spacing``) is rejected with the reason and never run; the search
  goes on with the others.
* **Objectives.** ``gain_per_metre``: the largest collapse-load gain over the
  unstrengthened arch per metre of anchor installed (Σ bars × length).
  ``cheapest``: the shortest total anchor length whose collapse load reaches ``target``.
* **Coarse to fine.** The coarse level is a shorter run of each layout, a fast proxy
  of the collapse load. Under the Newton solver (``analysis.solver = "newton"``, the
  default) it is the same path cut short: traced to :data:`COARSE_TRAVEL` times the
  load-line displacement at which the unstrengthened arch peaked in its fine run (run
  first), at most half the fine run's travel (``max_displacement``, or Newton's default
  of half the arch's thickness) — the fine run goes on past the peak until the load has
  fallen to half of it or that travel is used up, which is most of its cost. A layout
  that peaks later than that shows a lower bound at the coarse level. Under dynamic
  relaxation (``"dr"``): under load control without following the peak (``follow_peak =
  false``: the load where equilibrium is first lost), under displacement control to
  half of ``max_displacement``. Layouts whose coarse gain
  per metre is below ``keep_ratio`` of the best, or that are not among the best
  ``keep``, are dropped as hopeless; the rest are run at the fine level (the case's own
  analysis, peak followed).
  Under ``cheapest`` the coarse level drops layouts whose coarse collapse load is below
  ``keep_ratio`` × target; the fine runs stop as soon as the target is carried
  (``max_load = target``), in order of increasing anchor length, and the search stops
  at the first round in which a layout reaches the target: every layout not yet run is
  longer.
* **Collapse loads and lower bounds.** Every run ends with a status
  (:class:`~masonry_fdem.solvers.status.RunStatus`); only *peak passed* gives a collapse
  load. A layout whose fine run ends otherwise (no equilibrium found, displacement limit,
  ``max_load`` carried) has a lower bound of its collapse load: it is shown as one and
  ranked after every layout with a measured collapse load (under ``cheapest``, carrying
  the target is proof enough). A gain is measured only when the layout's and the
  unstrengthened arch's runs both give collapse loads (see
  :func:`~masonry_fdem.assessment.repair.gain_kind`). The coarse level's loads are
  proxies (mostly lower bounds).
* **Parallel.** The ranks are split into groups of ``group_size`` (MPI
  sub-communicators); each group runs one layout at a time (``assess`` on its
  sub-communicator); one round runs as many layouts as there are groups.
* **Resumable.** Every finished evaluation is appended to ``journal.jsonl`` in the search
  folder (after each round). ``resume=True`` (``--resume``) reads it back and runs only
  what is missing; the ranking is the same as that of a run straight through.

Units: SI (N, m); angles in degrees.
"""

from __future__ import annotations

import csv
import hashlib
import json
import os
import time
from collections.abc import Callable, Mapping
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any

from mpi4py import MPI

import numpy as np

from masonry_fdem.assessment.assess import assess
from masonry_fdem.assessment.case import AnchorLayout, ArchCase, CaseError, Objective, SearchSpec
from masonry_fdem.assessment.repair import BASELINE, as_case, free_folder, gain_kind
from masonry_fdem.solvers.status import Status

__all__ = ["COARSE_TRAVEL", "RankedLayout", "SearchInterrupted", "SearchResult", "search"]

COARSE_TRAVEL = 4.0
"""Under the Newton solver, the coarse level traces each layout to this many times the
load-line displacement at which the unstrengthened arch peaked (its fine run)."""


class SearchInterrupted(RuntimeError):
    """The search stopped before its end (``stop_after``); resume it with
    ``resume=True``: the journal keeps every finished evaluation."""


@dataclass
class RankedLayout:
    """One layout of the final ranking (loads [N], lengths [m]).

    Attributes:
        rank: 1 for the best.
        layout: the :class:`~masonry_fdem.assessment.case.AnchorLayout`.
        peak_load: the largest load it carried at the fine level (under ``cheapest``:
            capped at the target): its collapse load if ``status`` gives one, else a
            lower bound of it.
        gain: peak load − the unstrengthened peak load (see ``gain_kind``).
        length: Σ bars × length of its anchors (the cost).
        gain_per_metre: gain / length [N/m].
        reaches_target: whether it carries the target (None without a target).
        status: how its fine run ended (a :class:`~masonry_fdem.solvers.status.Status`
            value, e.g. "peak passed").
        gain_kind: "measured", "lower bound", "upper bound" or "not measured"
            (:func:`~masonry_fdem.assessment.repair.gain_kind`).
    """

    rank: int
    layout: AnchorLayout
    peak_load: float
    gain: float
    length: float
    gain_per_metre: float
    reaches_target: bool | None
    status: str
    gain_kind: str

    @property
    def key(self) -> str:
        return self.layout.key

    @property
    def collapsed(self) -> bool:
        """Whether its fine run proved a collapse load."""
        return Status(self.status).gives_collapse_load

    @property
    def collapse_load(self) -> float | None:
        """Its collapse load [N] if its fine run proved one, else None."""
        return self.peak_load if self.collapsed else None

    @property
    def load_text(self) -> str:
        """"5.20 kN (collapse load)" or ">= 5.20 kN (lower bound: load reached)"."""
        if self.collapsed:
            return f"{self.peak_load / 1e3:.2f} kN (collapse load)"
        return f">= {self.peak_load / 1e3:.2f} kN (lower bound: {self.status})"


@dataclass
class SearchResult:
    """Result of :func:`search`.

    Attributes:
        objective: "gain_per_metre" or "cheapest".
        baseline: the unstrengthened arch's largest load carried at the fine level [N]
            (its collapse load if ``baseline_status`` gives one, else a lower bound).
        baseline_status: how that run ended (a Status value).
        ranking: the layouts run at the fine level, best first.
        best: the best layout (None if no layout was run).
        cheapest: the shortest layout of the ranking that reaches the target (None
            without a target or if none does).
        rejected: ``(key, reason)`` of layouts that were not run: invalid geometry
            (leaves the structure, overlapping anchors) or a failed run.
        pruned: ``(key, reason)`` of layouts dropped as hopeless.
        coarse: ``key -> largest load carried`` at the coarse level (a proxy).
        evaluations: runs made by this call; ``reused``: taken from the journal.
        folder, report: the search folder and ``report.md`` (None if not written).
    """

    case: str
    objective: str
    target: float | None
    baseline: float
    ranking: list[RankedLayout]
    rejected: list[tuple[str, str]]
    pruned: list[tuple[str, str]]
    coarse: dict[str, float] = field(default_factory=dict)
    baseline_status: str = Status.PEAK_PASSED.value
    evaluations: int = 0
    reused: int = 0
    elapsed: float = 0.0
    folder: Path | None = None
    report: Path | None = None

    @property
    def best(self) -> RankedLayout | None:
        return self.ranking[0] if self.ranking else None

    @property
    def baseline_collapsed(self) -> bool:
        """Whether the unstrengthened fine run proved a collapse load."""
        return Status(self.baseline_status).gives_collapse_load

    @property
    def baseline_text(self) -> str:
        """The unstrengthened load in words: a collapse load or a lower bound."""
        if self.baseline_collapsed:
            return f"{self.baseline / 1e3:.2f} kN (collapse load)"
        return f">= {self.baseline / 1e3:.2f} kN (lower bound: {self.baseline_status})"

    @property
    def cheapest(self) -> RankedLayout | None:
        ok = [r for r in self.ranking if r.reaches_target]
        return min(ok, key=lambda r: (r.length, r.key)) if ok else None


def _fingerprint(case: ArchCase, spec: SearchSpec) -> str:
    parts = [repr(case.arch), repr(sorted(case.material_table.items())), repr(case.mortar),
             repr(case.ring_joint), repr(case.loading), repr(case.damage),
             repr(replace(case.analysis, output=Path("."))), repr(spec),
             "journal rows with the run status; Newton's coarse level cut short after the "
             "unstrengthened peak (v3)"]
    return hashlib.sha256("\n".join(parts).encode()).hexdigest()[:16]


def _newton(case: ArchCase) -> bool:
    return case.analysis.solver == "newton"


def _level_case(case: ArchCase, level: str, spec: SearchSpec,
                peak_displacement: float | None = None) -> ArchCase:
    """The case run at ``level`` (without anchors); ``peak_displacement`` [m]: where the
    unstrengthened arch peaked in its fine run (Newton's coarse level is cut short a few
    times that far)."""
    an = replace(case.analysis, limit_analysis=False)
    ld = case.loading
    if level == "coarse" and _newton(case):
        # Newton follows the peak by itself (follow_peak is dynamic relaxation's); its
        # fine run goes on to half the peak load or to the travel limit (assess's default:
        # half the arch's thickness); the coarse run stops a few times past the
        # unstrengthened peak's displacement, at most at half that travel
        full = ld.max_displacement or 0.5 * case.arch.rings * case.arch.ring_thickness
        travel = 0.5 * full
        if peak_displacement is not None and peak_displacement > 0:
            travel = min(travel, COARSE_TRAVEL * peak_displacement)
        ld = replace(ld, max_displacement=travel)
    elif level == "coarse":
        an = replace(an, follow_peak=False)
        if ld.max_displacement is not None:
            ld = replace(ld, max_displacement=0.5 * ld.max_displacement)
    if spec.objective is Objective.CHEAPEST and spec.target is not None:
        ld = replace(ld, max_load=spec.target)
    return replace(case, analysis=an, loading=ld, anchor_specs=())


class _Journal:
    """The append-only record of finished evaluations (rank 0 writes, all ranks read)."""

    def __init__(self, folder: Path | None, fingerprint: str, comm, resume: bool, source):
        self.folder, self.comm = folder, comm
        self.done: dict[tuple[str, str], dict] = {}
        if folder is None:
            return
        error, lines = None, []
        if comm.rank == 0:
            folder.mkdir(parents=True, exist_ok=True)
            head = folder / "search.json"
            if head.exists():
                try:
                    fp = json.loads(head.read_text()).get("fingerprint")
                except (OSError, ValueError):
                    fp = None
                if fp != fingerprint:
                    error = (f"output: {folder} holds the journal of a different search "
                             "(another case or candidate space); choose another output or "
                             "overwrite it")
            else:
                head.write_text(json.dumps({"fingerprint": fingerprint}))
            jf = folder / "journal.jsonl"
            if error is None and resume and jf.exists():
                for line in jf.read_text().splitlines():
                    try:
                        lines.append(json.loads(line))
                    except ValueError:  # a line cut short by the interruption
                        break
        error = comm.bcast(error, root=0)
        if error:
            raise CaseError(error, str(source) if source else None)
        for row in comm.bcast(lines, root=0):
            self.done[(row["level"], row["key"])] = row

    def add(self, rows: list[dict]) -> None:
        for row in rows:
            self.done[(row["level"], row["key"])] = row
        if self.folder is not None and self.comm.rank == 0 and rows:
            with open(self.folder / "journal.jsonl", "a") as fh:
                for row in rows:
                    fh.write(json.dumps(row) + "\n")
                fh.flush()
                os.fsync(fh.fileno())


def search(
    case: ArchCase | str | Path | Mapping[str, Any],
    space: SearchSpec | None = None,
    *,
    out: str | Path | None = None,
    resume: bool = False,
    overwrite: bool = False,
    group_size: int = 1,
    comm: MPI.Comm = MPI.COMM_WORLD,
    write: bool = True,
    stop_after: int | None = None,
    callback: Callable[[dict], None] | None = None,
) -> SearchResult:
    """Search the candidate space for a near-optimal anchor layout (collective; see the
    module doc).

    Args:
        case: the damaged arch (its own ``[[anchors]]`` are ignored).
        space: the candidate space (default: the case's ``[search]`` table).
        out: the search folder (default: ``<analysis.output>/search``): journal, ranking,
            pictures, report.
        resume: go on from the journal of an interrupted search in ``out``.
        overwrite: start afresh in a non-empty ``out``.
        group_size: ranks per layout run; the ranks form ``comm.size / group_size``
            groups that run layouts side by side.
        comm: MPI communicator.
        write: keep a journal and write the folder (False: compute only).
        stop_after: stop after this many new runs (raises :class:`SearchInterrupted`
            once they are in the journal); for time-boxed runs and tests.
        callback: called on every rank after each round with ``{"level", "done",
            "total"}``.

    Raises:
        CaseError: a bad case, no candidate space, a folder that is not free, or a
            journal of another search.
    """
    t0 = time.perf_counter()
    case = as_case(case)
    spec = space if space is not None else case.search
    src = str(case.source) if case.source else None
    if spec is None:
        raise CaseError("search: the case has no [search] table (the candidate space)", src)
    if spec.objective is Objective.CHEAPEST and spec.target is None:
        raise CaseError("search.target: required by objective = \"cheapest\"", src)
    if group_size < 1 or comm.size % group_size:
        raise ValueError(f"group_size {group_size} must divide the {comm.size} ranks")
    folder = None
    if write:
        folder = Path(out) if out is not None else case.analysis.output / "search"
        free_folder(folder, overwrite, comm, case.source, resume)
    journal = _Journal(folder, _fingerprint(case, spec), comm, resume, case.source)
    ngroups = comm.size // group_size
    sub = comm.Split(comm.rank // group_size, comm.rank)
    stats = {"new": 0, "reused": 0}
    ran: set[tuple[str, str]] = set()  # (level, key) run by this call ...
    reused: set[tuple[str, str]] = set()  # ... and taken from the journal

    # ---- checks: build every layout's anchors, reject the bad ones with the reason
    rejected: list[tuple[str, str]] = []
    valid: list[tuple[AnchorLayout, float]] = []
    seen: set[str] = set()
    for lay in spec.candidates():
        if lay.key in seen:
            continue
        seen.add(lay.key)
        try:
            anchors = lay.spec(spec).build(case.arch)
        except ValueError as exc:
            rejected.append((lay.key, str(exc)))
            continue
        problems = case.anchor_problems(anchors, min_spacing=spec.min_spacing)
        if problems:
            rejected.append((lay.key, "; ".join(problems)))
            continue
        valid.append((lay, float(sum(a.count * a.length for a in anchors))))

    def run(level: str, todo: list[tuple[AnchorLayout | None, float]],
            stop: Callable[[list[dict]], bool] | None = None) -> None:
        """Evaluate ``todo`` (None: the unstrengthened arch) at ``level``, in rounds."""
        peak_d = None
        if level == "coarse" and _newton(case):
            peak_d = journal.done[("fine", BASELINE)].get("peak_displacement")
        base = _level_case(case, level, spec, peak_d)
        pending = [(lay, ell) for lay, ell in todo
                   if (level, lay.key if lay else BASELINE) not in journal.done]
        reused.update((level, lay.key if lay else BASELINE) for lay, _ in todo
                      if (level, lay.key if lay else BASELINE) in journal.done)
        reused.difference_update(ran)
        stats["reused"] = len(reused)
        if stop is not None and stop([journal.done[(level, lay.key if lay else BASELINE)]
                                      for lay, _ in todo
                                      if (level, lay.key if lay else BASELINE)
                                      in journal.done]):
            return
        for r0 in range(0, len(pending), ngroups):
            if stop_after is not None and stats["new"] >= stop_after:
                raise SearchInterrupted(
                    f"search stopped after {stats['new']} runs; {len(pending) - r0} left at "
                    f"the {level} level; resume it to go on")
            batch = pending[r0:r0 + ngroups]
            mine = comm.rank // group_size
            row = None
            if mine < len(batch):
                lay, ell = batch[mine]
                row = _evaluate(base, lay, ell, spec, level, sub)
            # in rank order, that is in the order of the batch
            rows = [r for r in comm.allgather(row if sub.rank == 0 else None) if r is not None]
            journal.add(rows)
            ran.update((r["level"], r["key"]) for r in rows)
            stats["new"] += len(rows)
            if callback is not None:
                callback({"level": level, "done": r0 + len(batch), "total": len(pending)})
            if stop is not None and stop(rows):
                return

    def load(level, lay):
        return journal.done[(level, lay.key if lay else BASELINE)]

    pruned: list[tuple[str, str]] = []
    alive = list(valid)
    levels = ["coarse", "fine"] if spec.coarse and len(valid) > 1 else ["fine"]
    coarse: dict[str, float] = {}
    target = spec.target
    if "coarse" in levels and _newton(case):
        # the coarse level is cut short after the unstrengthened arch's peak: trace it first
        run("fine", [(None, 0.0)])
        _peak(load("fine", None))
    for level in levels:
        last = level == levels[-1]
        if spec.objective is Objective.CHEAPEST:
            alive.sort(key=lambda c: (c[1], c[0].key))
            run(level, [(None, 0.0)])
            if not last:
                run(level, alive)
                keep = []
                for lay, ell in alive:
                    row = load(level, lay)
                    if "error" in row:
                        continue
                    coarse[lay.key] = row["peak_load"]
                    if row["peak_load"] >= spec.keep_ratio * target:
                        keep.append((lay, ell))
                    else:
                        pruned.append((lay.key, f"hopeless: coarse load "
                                       f"{row['peak_load'] / 1e3:.2f} kN < "
                                       f"{spec.keep_ratio:g} x target"))
                alive = keep
            else:
                def reached(rows):
                    return any(_reaches(r, target) for r in rows if r["key"] != BASELINE)

                run(level, alive, stop=reached)
                done = [c for c in alive if (level, c[0].key) in journal.done]
                if any(_reaches(load(level, c[0]), target) for c in done):
                    best = min((c for c in done if _reaches(load(level, c[0]), target)),
                               key=lambda c: (c[1], c[0].key))
                    for lay, ell in alive:
                        if (level, lay.key) not in journal.done:
                            pruned.append((lay.key, f"not run: {ell:.2f} m of anchor, no "
                                           f"shorter than {best[0].key} ({best[1]:.2f} m), "
                                           "which reaches the target"))
                alive = done
        else:
            run(level, [(None, 0.0)] + alive)
            b = _peak(load(level, None))
            scores = []
            for lay, ell in alive:
                row = load(level, lay)
                if "error" not in row:
                    if level == "coarse":
                        coarse[lay.key] = row["peak_load"]
                    scores.append(((row["peak_load"] - b) / ell, lay, ell))
            scores.sort(key=lambda t: (-t[0], t[2], t[1].key))
            if not last and scores:
                top = scores[0][0]
                keep = []
                for i, (sc, lay, ell) in enumerate(scores):
                    if i < spec.keep and (sc >= spec.keep_ratio * top or top <= 0):
                        keep.append((lay, ell))
                    else:
                        why = (f"not among the best {spec.keep}" if i >= spec.keep else
                               f"below {spec.keep_ratio:g} x the best")
                        pruned.append((lay.key, f"hopeless: coarse gain "
                                       f"{sc / 1e3:.2f} kN/m, {why} ({top / 1e3:.2f} kN/m)"))
                alive = keep
    # failed runs are reported with the rejected ones
    for lay, _ in valid:
        for level in levels:
            row = journal.done.get((level, lay.key))
            if row is not None and "error" in row:
                rejected.append((lay.key, f"{level} run failed: {row['error']}"))
                break
    base_row = load("fine", None)
    baseline = _peak(base_row)
    base_status = base_row.get("status", Status.NOT_CONVERGED.value)
    base_collapsed = Status(base_status).gives_collapse_load
    ranking = []
    for lay, ell in alive:
        row = load("fine", lay)
        if "error" in row:
            continue
        p = row["peak_load"]
        collapsed = Status(row["status"]).gives_collapse_load
        ranking.append(RankedLayout(0, lay, p, p - baseline, ell, (p - baseline) / ell,
                                    None if target is None else _reaches(row, target),
                                    row["status"], gain_kind(base_collapsed, collapsed)))

    def order(r: RankedLayout) -> tuple:
        # a lower bound never outranks a measured collapse load (carrying the target
        # under "cheapest" is proof enough)
        if spec.objective is Objective.CHEAPEST:
            if r.reaches_target:
                return (0, r.length, False, 0.0, r.key)
            return (1, 0.0, not r.collapsed, -r.peak_load, r.key)
        return (not r.collapsed, -r.gain_per_metre, r.length, r.key)

    ranking.sort(key=order)
    for i, r in enumerate(ranking):
        r.rank = i + 1
    result = SearchResult(case.name, spec.objective.value, target, baseline, ranking,
                          rejected, pruned, coarse, base_status, stats["new"],
                          stats["reused"])
    result.elapsed = time.perf_counter() - t0
    sub.Free()
    if write:
        if comm.rank == 0:
            _write_search(case, spec, result, folder)
        result.folder, result.report = folder, folder / "report.md"
        comm.barrier()
    return result


def _reaches(row: dict, target: float | None) -> bool:
    return target is not None and "error" not in row and \
        row["peak_load"] >= target * (1.0 - 1e-9)


def _peak(row: dict) -> float:
    """The largest load carried of a journal row (the unstrengthened run must not fail)."""
    if "error" in row:
        raise RuntimeError(f"the unstrengthened arch's {row['level']} run failed: "
                           f"{row['error']}")
    return row["peak_load"]


def _evaluate(base: ArchCase, lay: AnchorLayout | None, ell: float, spec: SearchSpec,
              level: str, sub) -> dict:
    """One run (collective on ``sub``); the journal row."""
    key = lay.key if lay is not None else BASELINE
    case = base if lay is None else base.with_anchors((lay.spec(spec),))
    t = time.perf_counter()
    try:
        r = assess(case, comm=sub, write=False, progress=False)
    except (RuntimeError, ValueError) as exc:
        return {"level": level, "key": key, "error": str(exc), "length": ell}
    row = {"level": level, "key": key, "status": r.status.status.value,
           "peak_load": float(r.peak_load), "collapse_load": r.collapse_load,
           "detail": r.status.detail, "resolution": float(r.resolution),
           "length": ell, "steps": len(r.loads), "elapsed": time.perf_counter() - t,
           "peak_displacement": float(r.displacements[int(np.argmax(r.loads))])}
    if r.anchors:
        row["force_max"] = max(a["force_max"] for a in r.anchors)
        row["slip_max"] = max(a["slip_max"] for a in r.anchors)
    return row


def _atomic_write(path: Path, text: str) -> None:
    tmp = path.with_name(f".{path.name}.tmp")
    tmp.write_text(text, encoding="utf-8")
    tmp.replace(path)


def _write_search(case: ArchCase, spec: SearchSpec, res: SearchResult, folder: Path) -> None:
    import io

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    buf = io.StringIO()
    w = csv.writer(buf)
    w.writerow(["rank", "layout", "anchors", "positions", "inclination_deg", "length_m",
                "prestress_N", "anchor_metres", "status", "collapse_load_N", "peak_load_N",
                "gain_N", "gain_kind", "gain_per_metre_N_per_m", "reaches_target",
                "coarse_load_N"])
    for r in res.ranking:
        lay = r.layout
        w.writerow([r.rank, r.key, len(lay.positions), " ".join(f"{p:g}" for p in lay.positions),
                    f"{lay.inclination:g}", "through" if lay.length is None else f"{lay.length:g}",
                    f"{lay.prestress:g}", f"{r.length:.4f}", r.status,
                    "" if r.collapse_load is None else f"{r.collapse_load:.6g}",
                    f"{r.peak_load:.6g}", f"{r.gain:.6g}", r.gain_kind,
                    f"{r.gain_per_metre:.6g}",
                    "" if r.reaches_target is None else r.reaches_target,
                    f"{res.coarse[r.key]:.6g}" if r.key in res.coarse else ""])
    _atomic_write(folder / "ranking.csv", buf.getvalue())
    summary = {k: v for k, v in asdict(res).items()
               if k not in ("ranking", "folder", "report")}
    summary["ranking"] = [{"rank": r.rank, "key": r.key, "status": r.status,
                           "collapse_load": r.collapse_load, "peak_load": r.peak_load,
                           "gain": r.gain, "gain_kind": r.gain_kind, "length": r.length,
                           "gain_per_metre": r.gain_per_metre,
                           "reaches_target": r.reaches_target} for r in res.ranking]
    summary["best"] = res.best.key if res.best else None
    summary["cheapest"] = res.cheapest.key if res.cheapest else None
    _atomic_write(folder / "summary.json", json.dumps(summary, indent=1, default=str))

    # the best layouts on the arch
    show = res.ranking[:4]
    layout = case.layout()
    n = max(1, len(show))
    fig, axes = plt.subplots(1, n, figsize=(3.6 * n, 2.9), squeeze=False)
    for ax, r in zip(axes[0], show or [None], strict=False):
        for poly in layout.polygons:
            p = np.vstack([poly, poly[:1]])
            ax.plot(p[:, 0], p[:, 1], color="0.65", lw=0.5)
        if r is not None:
            for a in r.layout.spec(spec).build(case.arch):
                ax.plot(a.points[:, 0], a.points[:, 1], "-", color="C3", lw=2.2)
            ax.set_title(f"#{r.rank}: {'' if r.collapsed else '>= '}"
                         f"{r.peak_load / 1e3:.1f} kN, {r.length:.2f} m,\n"
                         f"{r.gain_per_metre / 1e3:.1f} kN/m", fontsize=8)
        for x, y in case.load_points():
            ax.annotate("", (x, y), xytext=(x, y + 0.15 * case.arch.span),
                        arrowprops=dict(arrowstyle="->", color="k"))
        ax.set_aspect("equal")
        ax.axis("off")
    fig.tight_layout()
    fig.savefig(folder / "best_layouts.png", dpi=120)
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(5.5, 4))
    for measured, mark, label in ((True, "o", "collapse load"),
                                  (False, "^", "lower bound (no collapse load)")):
        rr = [r for r in res.ranking if r.collapsed is measured]
        if rr:
            ax.plot([r.length for r in rr], [r.peak_load / 1e3 for r in rr], mark,
                    color="C3", mfc="C3" if measured else "none", label=label)
    for r in res.ranking[:4]:
        ax.annotate(f"#{r.rank}", (r.length, r.peak_load / 1e3), fontsize=8,
                    xytext=(3, 3), textcoords="offset points")
    ax.axhline(res.baseline / 1e3, color="C0", ls="--", label="unstrengthened" + (
        "" if res.baseline_collapsed else " (lower bound)"))
    if res.target:
        ax.axhline(res.target / 1e3, color="k", ls=":", label="target")
    ax.set_xlabel("anchor installed [m]")
    ax.set_ylabel("largest load carried [kN]")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(folder / "load_vs_length.png", dpi=120)
    plt.close(fig)

    goal = ("largest collapse-load gain per metre of anchor" if res.objective ==
            "gain_per_metre" else f"cheapest layout carrying {res.target / 1e3:.2f} kN")
    lines = [f"# Anchor layout search for `{case.name}`", "",
             f"Objective: {goal}. Unstrengthened: **{res.baseline_text}**. "
             f"Candidates: {len(spec.candidates())}; "
             f"rejected {len(res.rejected)}; dropped as hopeless {len(res.pruned)}; "
             f"ranked {len(res.ranking)}. Runs: {res.evaluations} in this session, "
             f"{res.reused} from the journal.", ""]
    if res.best:
        lines.append(f"Best: **{res.best.key}**: {res.best.load_text}, "
                     f"{res.best.length:.2f} m of anchor; gain {res.best.gain_kind}.")
    bounds = sum(not r.collapsed for r in res.ranking)
    notes = []
    if bounds == len(res.ranking) > 0:
        notes.append("No layout's run reached a collapse load (\"≥\": lower bounds).")
    elif bounds:
        after = ("those that carry the target reach it all the same" if res.objective ==
                 "cheapest" else "they rank after every measured one")
        notes.append(f"{bounds} of the {len(res.ranking)} layouts ran without reaching a "
                     f"collapse load (\"≥\": a lower bound); {after}.")
    if not res.baseline_collapsed:
        notes.append("The unstrengthened run gave a lower bound only: no gain below is a "
                     "measured gain.")
    if notes:
        lines.append(" ".join(notes))
    if res.target:
        ch = res.cheapest
        lines.append(f"Cheapest reaching {res.target / 1e3:.2f} kN: " +
                     (f"**{ch.key}** ({ch.length:.2f} m)." if ch else "none of those run."))
    lines += ["", "| rank | layout | anchor [m] | status | load [kN] | gain [kN] | "
              "gain per metre [kN/m] |", "|---|---|---|---|---|---|---|"]
    for r in res.ranking:
        ge = "" if r.collapsed else "≥ "
        g = "" if r.gain_kind == "measured" else f" ({r.gain_kind})"
        lines.append(f"| {r.rank} | {r.key} | {r.length:.2f} | {r.status} | "
                     f"{ge}{r.peak_load / 1e3:.2f} | {r.gain / 1e3:+.2f}{g} | "
                     f"{r.gain_per_metre / 1e3:.2f} |")
    lines += ["", "![best layouts](best_layouts.png)", "", "![load vs length]"
              "(load_vs_length.png)", ""]
    if res.rejected:
        lines += ["## Rejected", ""] + [f"- `{k}`: {why}" for k, why in res.rejected] + [""]
    if res.pruned:
        lines += ["## Dropped as hopeless", ""] + [f"- `{k}`: {why}" for k, why in res.pruned]
        lines.append("")
    lines += ["Files: `ranking.csv`, `summary.json`, `journal.jsonl` (every run; "
              "`masonry-fdem repair --resume` goes on from it).", ""]
    _atomic_write(folder / "report.md", "\n".join(lines))
