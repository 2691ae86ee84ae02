"""Repairs of a masonry arch: unstrengthened against anchored, and a layout search.

:func:`compare` assesses one case twice, without its ``[[anchors]]`` and with them, and
writes one report: both load–displacement curves on one plot, both mechanisms, the
anchors' bar forces and bond slips at the peak load (``masonry-fdem repair CASE.toml``).
The gain is measured only when both runs give a collapse load (peak passed); a run
ending otherwise gives a lower bound, and the gain says so (:func:`gain_kind`).

The layout search is :mod:`masonry_fdem.assessment.search`.

Units: SI (N, m).
"""

from __future__ import annotations

import json
import shutil
from collections.abc import Mapping
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from mpi4py import MPI

import numpy as np

from masonry_fdem.assessment.assess import Assessment, assess
from masonry_fdem.assessment.report import anchor_peaks_table
from masonry_fdem.io.plot import save_load_curve
from masonry_fdem.io.rundir import hand_over, partial_folder, run_folder_problem
from masonry_fdem.assessment.case import (
    ArchCase,
    CaseError,
    load_case,
)

__all__ = ["BASELINE", "Comparison", "as_case", "compare", "free_folder", "gain_kind",
           "gain_text"]

BASELINE = "unstrengthened"
_SUBFOLDERS = ("unstrengthened", "anchored")


# ------------------------------------------------------------------------ comparison
def gain_kind(base_collapsed: bool, new_collapsed: bool) -> str:
    """What a gain ``new / base − 1`` of the largest loads carried is, from whether each
    run proved a collapse load: "measured" (both), "lower bound" (only the base: the new
    load is a lower bound, the gain at least this), "upper bound" (only the new one: the
    base is a lower bound, the gain at most this) or "not measured" (two lower bounds:
    the gain may be larger or smaller)."""
    if base_collapsed and new_collapsed:
        return "measured"
    if base_collapsed:
        return "lower bound"
    if new_collapsed:
        return "upper bound"
    return "not measured"


def gain_text(gain: float, kind: str) -> str:
    """A gain [fraction] and its :func:`gain_kind` in words, e.g. "at least +65 %"."""
    pct = f"{100 * gain:+.0f} %"
    return {"measured": pct, "lower bound": f"at least {pct}",
            "upper bound": f"at most {pct}"}.get(
        kind, f"not measured (two lower bounds; their ratio {pct})")


@dataclass
class Comparison:
    """Result of :func:`compare` (loads [N], lengths [m]).

    Attributes:
        unstrengthened, anchored: the two :class:`~masonry_fdem.assessment.assess.Assessment`.
        gain: anchored / unstrengthened largest load carried − 1: a measured gain only
            if ``gain_kind`` is "measured" (both runs gave a collapse load).
        anchor_length: Σ bars × length of the anchors [m].
        folder, report: the run folder and its ``report.md`` (None if not written).
    """

    case: str
    unstrengthened: Assessment
    anchored: Assessment
    anchor_length: float
    folder: Path | None = None
    report: Path | None = None

    @property
    def gain(self) -> float:
        return self.anchored.peak_load / self.unstrengthened.peak_load - 1.0

    @property
    def gain_kind(self) -> str:
        """"measured", "lower bound", "upper bound" or "not measured" (:func:`gain_kind`)."""
        return gain_kind(self.unstrengthened.collapsed, self.anchored.collapsed)

    @property
    def gain_text(self) -> str:
        """The gain in words: "+65 %", "at least +65 %", ... (:func:`gain_text`)."""
        return gain_text(self.gain, self.gain_kind)


def as_case(case) -> ArchCase:
    """An ArchCase as it is, or loaded from a TOML file or a dict."""
    return case if isinstance(case, ArchCase) else load_case(case)


def free_folder(folder: Path, overwrite: bool, comm, source, resume: bool = False) -> None:
    """Refuse a run folder that cannot take the run (CaseError naming it; collective)."""
    error = run_folder_problem(folder, overwrite=overwrite, resume=resume, comm=comm)
    if error:
        raise CaseError(error, str(source) if source else None)


def compare(
    case: ArchCase | str | Path | Mapping[str, Any],
    *,
    out: str | Path | None = None,
    overwrite: bool = False,
    progress: bool | None = None,
    comm: MPI.Comm = MPI.COMM_WORLD,
    write: bool = True,
    side_by_side: bool = True,
) -> Comparison:
    """Assess a case without and with its ``[[anchors]]`` (collective).

    Args:
        case: an :class:`~masonry_fdem.assessment.case.ArchCase` with anchors, a TOML file or a dict.
        out: the run folder (default: the case's ``analysis.output``); it gets
            ``report.md``, ``curves.png``, ``anchors.png``, ``summary.json`` and the two
            assessment folders ``unstrengthened/`` and ``anchored/``.
        overwrite: replace a run folder that exists and is not empty.
        progress: progress bars on stderr (default: when stderr is a terminal).
        comm: MPI communicator.
        write: write the run folder (False: compute only).
        side_by_side: on two or more ranks, run the two assessments at the same time,
            each on half of the ranks (False: one after the other on all ranks).

    Raises:
        CaseError: a bad case, a case without anchors, or a folder that is not free.
    """
    case = as_case(case)
    if not case.anchor_specs:
        raise CaseError("anchors: the case has no [[anchors]] to compare with the "
                        "unstrengthened arch", str(case.source) if case.source else None)
    folder = Path(out) if out is not None else case.analysis.output
    tmp = partial_folder(folder)
    if write:
        free_folder(folder, overwrite, comm, case.source)
        if comm.rank == 0:
            shutil.rmtree(tmp, ignore_errors=True)
        comm.barrier()
    bare = replace(case.with_anchors(()), name=f"{case.name} (unstrengthened)")
    anchored = replace(case, name=f"{case.name} (anchored)")
    kw = dict(progress=progress, write=write, overwrite=True)
    try:
        if side_by_side and comm.size >= 2:
            # the two assessments at the same time, each on half of the ranks
            half = comm.size // 2
            color = 0 if comm.rank < half else 1
            sub = comm.Split(color, comm.rank)
            if color == 1:  # one progress bar on the terminal, the first pair's
                kw["progress"] = False
            try:
                mine = assess((bare, anchored)[color], out=tmp / _SUBFOLDERS[color], comm=sub,
                              **kw)
            finally:
                sub.Free()
            r0 = comm.bcast(mine if comm.rank == 0 else None, root=0)
            r1 = comm.bcast(mine if comm.rank == half else None, root=half)
        else:
            r0 = assess(bare, out=tmp / "unstrengthened", comm=comm, **kw)
            r1 = assess(anchored, out=tmp / "anchored", comm=comm, **kw)
        result = Comparison(case.name, r0, r1, r1.anchor_length)
        if write:
            hand_over(lambda t: _write_comparison(case, result, t), tmp, folder, comm)
            result.folder, result.report = folder, folder / "report.md"
            for r, sub in ((r0, "unstrengthened"), (r1, "anchored")):
                r.folder, r.report = folder / sub, folder / sub / "report.md"
    except BaseException:
        if write and comm.rank == 0:
            shutil.rmtree(tmp, ignore_errors=True)
        raise
    comm.barrier()
    return result


def _write_comparison(case: ArchCase, res: Comparison, tmp: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    r0, r1 = res.unstrengthened, res.anchored
    fig, ax = plt.subplots(figsize=(6, 4))
    for r, label, c in ((r0, "unstrengthened", "C0"), (r1, "anchored", "C3")):
        bound = "" if r.collapsed else " (lower bound)"
        ax.plot(r.displacements * 1e3, r.loads / 1e3, "o-", ms=3, color=c,
                label=f"{label}: {r.peak_load / 1e3:.1f} kN{bound}")
        ax.axhline(r.peak_load / 1e3, color=c, lw=0.6, ls=":")
    save_load_curve(fig, ax, f"{case.name}: unstrengthened and anchored", tmp / "curves.png")

    fig, (a1, a2) = plt.subplots(2, 1, figsize=(6, 5.5), sharex=True)
    # one colour per anchor (the default cycle has ten: the eleventh repeated the first)
    cmap = plt.get_cmap("tab10" if len(r1.anchors) <= 10 else "tab20")
    for k, a in enumerate(r1.anchors):
        d = np.asarray(a["distance"])
        mid = 0.5 * (d[1:] + d[:-1])
        col = cmap(k % cmap.N)
        a1.plot(mid, np.asarray(a["force"]) / 1e3, "-", color=col, label=a["name"])
        a2.plot(d, np.asarray(a["slip"]) * 1e3, "-", color=col)
    if r1.anchors:
        a1.axhline(r1.anchors[0]["yield_force"] / 1e3, color="k", ls="--", lw=0.8,
                   label="yield force")
    a1.set_ylabel("bar force [kN per bar]")
    a2.set_ylabel("bond slip [mm]")
    a2.set_xlabel("distance from the anchor's start [m]")
    a1.set_title("anchors at the anchored arch's peak load")
    a1.legend(fontsize=7, ncol=2)
    for a in (a1, a2):
        a.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(tmp / "anchors.png", dpi=120)
    plt.close(fig)

    from masonry_fdem.assessment.assess import status_dict

    summary = {
        "case": case.name,
        "unstrengthened_status": status_dict(r0.status),
        "anchored_status": status_dict(r1.status),
        "unstrengthened_collapse_load_N": r0.collapse_load,
        "anchored_collapse_load_N": r1.collapse_load,
        "unstrengthened_peak_load_N": r0.peak_load,
        "anchored_peak_load_N": r1.peak_load,
        "gain": res.gain,
        "gain_kind": res.gain_kind,
        "anchor_length_m": res.anchor_length,
        "unstrengthened_resolution_N": r0.resolution,
        "anchored_resolution_N": r1.resolution,
        "anchors": [{k: v for k, v in a.items() if k not in ("distance", "force", "slip")}
                    for a in r1.anchors],
        "anchor_peaks": r1.anchor_peaks,
        "unstrengthened_ring_separation": r0.ring_separation,
        "anchored_ring_separation": r1.ring_separation,
        "unstrengthened_ring_separation_at_peak": r0.ring_separation_at_peak,
        "anchored_ring_separation_at_peak": r1.ring_separation_at_peak,
    }
    (tmp / "summary.json").write_text(json.dumps(summary, indent=1))

    def load(r) -> str:
        kn = r.peak_load / 1e3
        what = "collapse load" if r.collapsed else "a lower bound"
        return f"**{kn:.2f} kN** ({kn / 9.80665:.2f} t), {what}"

    def resolution(r) -> str:
        return f"{r.resolution / 1e3:.2f} kN" if r.collapsed else "–"

    kind = res.gain_kind
    per_m = (r1.peak_load - r0.peak_load) / 1e3 / max(res.anchor_length, 1e-12)
    why = {"measured": "both runs passed their peak",
           "lower bound": "the anchored run gave no collapse load: its load is a lower bound",
           "upper bound": "the unstrengthened run gave no collapse load: its load is a "
                          "lower bound",
           "not measured": "neither run passed its peak"}[kind]
    gain = (f"Gain: **{res.gain_text}** with {res.anchor_length:.2f} m of anchor "
            f"({len(r1.anchors)} bars in the model"
            + (f"; {per_m:.2f} kN per metre" if kind != "not measured" else "")
            + f"): {why}.")
    lines = [f"# Repair of `{case.name}`: unstrengthened and anchored", "",
             "| | unstrengthened | anchored |", "|---|---|---|",
             f"| status | {_head(r0)} | {_head(r1)} |",
             f"| largest load carried | {load(r0)} | {load(r1)} |",
             f"| resolution | {resolution(r0)} | {resolution(r1)} |",
             f"| joints open at the peak load | {len(r0.hinges_at_collapse)} | "
             f"{len(r1.hinges_at_collapse)} |",
             "", gain, "",
             "![curves](curves.png)", "", "## Anchors at the peak load", "",
             "| anchor | length [m] | largest bar force [kN] | yield force [kN] | "
             "largest slip [mm] | yielded / ruptured elements |", "|---|---|---|---|---|---|"]
    for a in r1.anchors:
        lines.append(f"| {a['name']} | {a['length']:.3f} | {a['force_max'] / 1e3:.2f} | "
                     f"{a['yield_force'] / 1e3:.2f} | {a['slip_max'] * 1e3:.3f} | "
                     f"{a['yielded']} / {a['ruptured']} |")
    if r1.anchor_peaks:
        lines += ["", "## Anchors over the whole run", ""] + anchor_peaks_table(
            r1.anchor_peaks)
    lines += ["", "![anchors](anchors.png)", "", "## Mechanisms", "",
              "Unstrengthened:", "", "![unstrengthened](unstrengthened/mechanism.png)", "",
              "Anchored:", "", "![anchored](anchored/mechanism.png)", "",
              "The full assessments (hinge sequences, curves as CSV): "
              "[unstrengthened](unstrengthened/report.md), [anchored](anchored/report.md).",
              ""]
    (tmp / "report.md").write_text("\n".join(lines), encoding="utf-8")


def _head(r: Assessment) -> str:
    """The status of an assessment without the load: "not converged at 12.50 kN"."""
    return r.status_line.split(" — ")[0]
