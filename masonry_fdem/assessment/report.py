"""The run folder of an assessment: pictures, curves, hinge sequence and report.md."""

from __future__ import annotations

import csv
import json
import shutil
from dataclasses import asdict
from pathlib import Path

from mpi4py import MPI

import numpy as np

from masonry_fdem.assessment.specs import DiskFillSpec
from masonry_fdem.io.plot import save_load_curve
from masonry_fdem.io.rundir import hand_over, partial_folder
from masonry_fdem.solvers.status import Status

__all__ = ["read_curve", "status_text", "thrust_lines", "write_run_folder"]


def write_run_folder(case, res, folder: Path, model, inter, anchors, comm,
                     snapshots: dict | None = None, stress: tuple | None = None,
                     disks=None, extra=None, load_label: str | None = None) -> None:
    """Write the run folder of an assessment (collective): the mechanism picture, the
    curve, the hinge sequence and the report, into a hidden folder handed over when
    complete; ``res.folder`` and ``res.report`` are set. ``snapshots`` (``{name: (local
    displacement array, load [N], load-line displacement [m])}``, e.g. "first hinge" and
    "peak load") are drawn deformed as ``<name>.png`` (blocks only: the joint and anchor
    states are those of the end of the run, so they are not drawn there). ``stress``
    (``(local σ_yy per cell [Pa], local displacements, load [N], load-line displacement
    [m])``, taken at the peak load of a case with fill) is drawn as
    ``vertical_stress.png``: the load's path through the fill into the arch. ``disks``
    (a disk fill's :class:`~masonry_fdem.interactions.disks.Disks`) are drawn in the
    mechanism picture, which is then drawn deformed at true scale (×1: the disks where
    they are); ``extra(tmp)`` (collective) draws more pictures into the hidden folder and
    returns their ``(name, file, load [N], displacement [m])``; ``load_label`` replaces
    the mechanism picture's "P = <last load carried>"."""
    from masonry_fdem.io import plot_blocks

    tmp = partial_folder(folder)
    error = None
    if comm.rank == 0:
        shutil.rmtree(tmp, ignore_errors=True)
        try:
            tmp.mkdir(parents=True)
        except OSError as exc:
            error = f"cannot create {tmp}: {exc.strerror or exc}"
    error = comm.bcast(error, root=0)
    if error:
        raise RuntimeError(error)
    try:
        span = case.arch.span
        u = model.gather_nodal(model.u.x.array)
        umax = float(np.abs(u).max()) if u is not None and u.size else 0.0
        umax = comm.bcast(umax, root=0)
        mag = 0.05 * span / umax if umax > 0 and disks is None else 1.0
        pts = case.load_points()
        last = float(res.loads[-1]) if len(res.loads) else 0.0
        at_peak = res.hinges_at_collapse
        plot_blocks(model, tmp / "mechanism.png", field="displacement", scale=mag,
                    title=f"{case.name}: deformed ×{mag:.0f} at the end of the run",
                    joints=inter[1], anchors=anchors, loads=pts, disks=disks,
                    load_label=load_label or f"P = {last / 1e3:.2f} kN",
                    hinges=[e.position for e in at_peak] or None,
                    hinge_labels=[_order(res, e) for e in at_peak],
                    hinge_sides=[_side(e) for e in at_peak])
        drawn = []
        if snapshots:
            now = model.u.x.array.copy()
            try:
                for name, (us, load, disp) in snapshots.items():
                    model.u.x.array[:] = us
                    um = comm.allreduce(float(np.abs(us).max()) if us.size else 0.0,
                                        op=MPI.MAX)
                    m = 0.05 * span / um if um > 0 else 1.0
                    file = name.replace(" ", "_") + ".png"
                    # the hinges open by then (along the path: by the displacement)
                    opened = [e for e in res.events if e.kind == "hinge"
                              and e.displacement <= disp * (1 + 1e-9)]
                    plot_blocks(model, tmp / file, field="displacement", scale=m,
                                title=f"{case.name}: at the {name}\n{load / 1e3:.2f} kN, "
                                      f"{disp * 1e3:.3f} mm (deformed ×{m:.0f})",
                                loads=pts, load_label=f"P = {load / 1e3:.2f} kN",
                                hinges=[e.position for e in opened] or None,
                                hinge_labels=[str(e.order) for e in opened],
                                hinge_sides=[_side(e) for e in opened])
                    drawn.append((name, file, load, disp))
            finally:
                model.u.x.array[:] = now
        if stress is not None:
            syy, us, load, disp = stress
            parts = comm.gather((model.dmesh.cell_input, syy), root=0)
            cells = np.zeros(model.blocks.n_cells)
            if comm.rank == 0:
                for idx, vals in parts:
                    cells[idx] = vals
            now = model.u.x.array.copy()
            try:
                model.u.x.array[:] = us
                # the colour scale spans the 1st to 99th percentile of the fill's and the
                # arch's cells: the peaks at the beam's edges would wash out the rest
                lo = hi = 0.0
                if comm.rank == 0:
                    lo, hi = np.percentile(cells / 1e3, [1.0, 99.0])
                lo, hi = comm.bcast((float(lo), float(hi)), root=0)
                plot_blocks(model, tmp / "vertical_stress.png", field=cells / 1e3, scale=1.0,
                            cmap="viridis_r", clim=(lo, min(hi, 0.0) if lo < 0 else hi),
                            title=f"{case.name}\nσ_yy [kPa] at the peak: {load / 1e3:.1f} kN, "
                                  f"{disp * 1e3:.1f} mm (clipped at 1 %, 99 %)")
                drawn.append(("vertical stress at the peak load", "vertical_stress.png", load,
                              disp))
            finally:
                model.u.x.array[:] = now
        if extra is not None:
            drawn += extra(tmp)
        hand_over(lambda t: _write_rank0(case, res, t, mag, drawn, folder), tmp, folder, comm)
    except BaseException:
        if comm.rank == 0:
            shutil.rmtree(tmp, ignore_errors=True)
        raise
    res.folder = folder
    res.report = folder / "report.md"
    comm.barrier()


def _order(res, hinge) -> str:
    """The order of opening of a hinge at the peak load (its joint's first event)."""
    return next((str(e.order) for e in res.events
                 if e.joint == hinge.joint and e.kind == hinge.kind), "")


def _side(event) -> float:
    """+1 for a hinge that turns about the extrados (its intrados opens), -1 for one that
    turns about the intrados: where its label goes, outside or inside the ring."""
    return -1.0 if event.side == "extrados" else 1.0


def _write_rank0(case, res, tmp: Path, mag: float, drawn=(), folder: Path | None = None) -> None:
    import matplotlib

    from masonry_fdem.assessment.assess import status_dict

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    with open(tmp / "curve.csv", "w", newline="", encoding="utf-8") as fh:
        fh.write(f"# status: {status_text(res)}\n")
        w = csv.writer(fh)
        w.writerow(["load_N", "displacement_m", "iterations"])
        for row in zip(res.loads, res.displacements, res.iterations, strict=True):
            w.writerow([f"{row[0]:.6g}", f"{row[1]:.6e}", row[2]])
    with open(tmp / "hinges.csv", "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["order", "joint", "kind", "side", "x_m", "y_m", "s", "load_N",
                    "displacement_m"])
        for e in res.events:
            w.writerow([e.order, e.joint, e.kind, e.side, f"{e.position[0]:.4f}",
                        f"{e.position[1]:.4f}", f"{e.s:.4f}", f"{e.load:.6g}",
                        f"{e.displacement:.6e}"])
    summary = {k: v for k, v in asdict(res).items()
               if k not in ("loads", "displacements", "iterations", "folder", "report",
                            "status")}
    summary["status"] = status_dict(res.status)
    summary["status_line"] = status_text(res)
    summary["collapse_load"] = res.collapse_load
    summary["ratio_to_limit_analysis"] = res.ratio
    summary["peak_load_to_limit_analysis"] = res.bound_ratio
    with open(tmp / "summary.json", "w", encoding="utf-8") as fh:
        json.dump(summary, fh, indent=1, default=str)
    if case.source is not None and Path(case.source).is_file():
        shutil.copyfile(case.source, tmp / "case.toml")

    fig, ax = plt.subplots(figsize=(6, 4))
    ax.plot(res.displacements * 1e3, res.loads / 1e3, "o-", ms=3, label="FDEM")
    if res.limit_load:
        ax.axhline(res.limit_load / 1e3, color="C3", ls="--", label="limit analysis")
    for e in res.events:
        ax.annotate(str(e.order), (e.displacement * 1e3, e.load / 1e3), fontsize=7,
                    color="C2", xytext=(2, -9), textcoords="offset points")
    save_load_curve(fig, ax, f"{case.name}: {res.control} control", tmp / "load_displacement.png")

    _hinges_figure(case, res, tmp / "hinges.png")
    paraview = ([] if folder is None else
                [p.name for p in sorted(folder.glob("paraview*")) if (p / "model.pvd").is_file()])
    (tmp / "report.md").write_text(_report(case, res, mag, drawn, paraview), encoding="utf-8")


def thrust_lines(case, la) -> list[list[tuple[float, float]]]:
    """The line of thrust of a limit-analysis result: per ring of the arch, the point [m]
    where the resultant of each radial joint acts (springing to springing), from
    :attr:`~masonry_fdem.solvers.limit_analysis.LimitResult.thrust_points`; joints that
    carry no compression are left out. Empty if the LP found no equilibrium."""
    from masonry_fdem.assessment.specs import classify_interface

    forces = np.asarray(la.interface_forces, dtype=float)
    if forces.size == 0 or not np.all(np.isfinite(forces)):
        return []
    pts = la.thrust_points
    itf = la.interfaces
    rings: dict[int, list[tuple[int, tuple[float, float]]]] = {}
    for i in range(itf.size):
        where = classify_interface(la.names[itf.block_a[i]], la.names[itf.block_b[i]],
                                   case.arch)
        if where is None or where[0] != "joint" or not np.all(np.isfinite(pts[i])):
            continue
        rings.setdefault(where[1], []).append((where[2], (float(pts[i][0]),
                                                          float(pts[i][1]))))
    return [[p for _, p in sorted(rows)] for _, rows in sorted(rings.items())]


def _damage_segments(case, layout):
    """Interfaces of ``layout`` changed by the case's [[damage]]: ``(dry, weakened)``
    lists of ``(2, 2)`` segments [m] (no bond: open joints, separated rings; weakened:
    decayed mortar)."""
    from masonry_fdem.assessment.specs import classify_interface
    from masonry_fdem.solvers.limit_analysis import find_interfaces

    dry, weak = [], []
    if not case.damage:
        return dry, weak
    itf = find_interfaces(layout)
    for i in range(itf.size):
        where = classify_interface(layout.names[itf.block_a[i]], layout.names[itf.block_b[i]],
                                   case.arch)
        if where is None:
            continue
        kind, factor = case._joint_state(where, 0.5 * (itf.start[i] + itf.end[i]))
        seg = np.array([itf.start[i], itf.end[i]])
        if kind == "dry":
            dry.append(seg)
        elif factor < 1.0:
            weak.append(seg)
    return dry, weak


def _hinges_figure(case, res, path: Path) -> None:
    """The arch with the FDEM hinges at the peak load (numbered in order of opening), the
    limit analysis's hinges and line of thrust, the load and the damaged joints."""
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection
    from matplotlib.lines import Line2D

    from masonry_fdem.io.plot import label_points, legend_below

    layout = case.layout()
    span = case.arch.span
    fig, ax = plt.subplots(figsize=(7.5, 5.0))
    handles = []
    # the voussoirs of "missing_brick" damage, dashed where they were
    full = {n: p for n, p in zip(case.layout().names, case.layout().polygons, strict=True)}
    from masonry_fdem.geometry import arch_layout

    whole = arch_layout(**case.arch.layout_kwargs())
    for poly, name in zip(whole.polygons, whole.names, strict=True):
        p = np.vstack([poly, poly[:1]])
        if name in full:
            ax.fill(p[:, 0], p[:, 1], color="0.92", lw=0)
            ax.plot(p[:, 0], p[:, 1], color="0.55", lw=0.6)
        else:
            ax.plot(p[:, 0], p[:, 1], color="C1", lw=1.0, ls="--")
            if not any(h.get_label() == "missing brick" for h in handles):
                handles.append(Line2D([], [], color="C1", ls="--", label="missing brick"))
    dry, weak = _damage_segments(case, layout)
    if dry:
        ax.add_collection(LineCollection(dry, colors="C1", linewidths=2.5))
        handles.append(Line2D([], [], color="C1", lw=2.5, label="damage: no bond"))
    if weak:
        ax.add_collection(LineCollection(weak, colors="C8", linewidths=2.5))
        handles.append(Line2D([], [], color="C8", lw=2.5, label="damage: decayed mortar"))
    for line in res.limit_thrust:
        if len(line) > 1:
            q = np.asarray(line)
            ax.plot(q[:, 0], q[:, 1], "-", color="C0", lw=1.2, alpha=0.8)
    if any(len(line) > 1 for line in res.limit_thrust):
        handles.append(Line2D([], [], color="C0", lw=1.2,
                              label="line of thrust at the limit-analysis load"))
    for line in res.fdem_thrust:
        if len(line) > 1:
            q = np.asarray(line)
            ax.plot(q[:, 0], q[:, 1], "--", color="C2", lw=1.4, zorder=3)
    if any(len(line) > 1 for line in res.fdem_thrust):
        handles.append(Line2D([], [], color="C2", lw=1.4, ls="--",
                              label="line of thrust of the FDEM at its peak load"))
    for _, pos in res.limit_hinges:
        ax.plot(*pos, "x", ms=8, color="C0", mew=2, zorder=4)
    if res.limit_hinges:
        handles.append(Line2D([], [], ls="", marker="x", ms=8, color="C0", mew=2,
                              label="limit-analysis hinge"))
    for e in res.hinges_at_collapse:
        ax.plot(*e.position, "o", ms=10, mfc="none", mec="C3", mew=2, zorder=5)
    if res.hinges_at_collapse:
        handles.append(Line2D([], [], ls="", marker="o", ms=10, mfc="none", mec="C3", mew=2,
                              label="FDEM hinge at the end of the run"
                              if case.fill is not None and case.fill.model == "disks"
                              else "FDEM hinge at the peak load"))
    # the order of opening beside each joint, outside the extrados or inside the intrados
    # (radially from the middle of the springing line); neighbours share one label
    if res.events:
        pos = np.array([e.position for e in res.events], dtype=float)
        out = pos - np.array([0.0, 0.0])
        # (a hinge's position is the end it turns about: on the extrados when the
        # intrados opens)
        sign = np.array([_side(e) for e in res.events])
        ax.plot(pos[:, 0], pos[:, 1], "o", ms=3.5, color="C3", zorder=5)
        label_points(ax, pos, [str(e.order) for e in res.events], out * sign[:, None],
                     0.06 * span, fontsize=8, color="C3")
    if res.events:
        handles.append(Line2D([], [], ls="", marker="o", ms=3.5, color="C3",
                              label="joint that opened; number: order of opening"))
    pts = case.load_points()
    for x, y in pts:
        ax.annotate("", (x, y), xytext=(x, y + 0.15 * span),
                    arrowprops=dict(arrowstyle="-|>", color="k", lw=1.5, mutation_scale=12))
    peak = res.collapse_load or res.peak_load
    x0, y0 = pts.mean(axis=0)
    # beside the arrow, not over it: above it the text reached the title on a wide arch
    ax.annotate(f"P = {peak / 1e3:.2f} kN" + ("" if res.collapse_load else " (carried)"),
                (x0, y0 + 0.11 * span), xytext=(5, 0), textcoords="offset points",
                ha="left", va="center", fontsize=9,
                bbox=dict(boxstyle="round,pad=0.15", fc="white", ec="none", alpha=0.8))
    ax.set_aspect("equal")
    ax.autoscale_view()
    lo, hi = ax.get_ylim()
    ax.set_ylim(lo, max(hi, y0 + 0.22 * span))
    ax.set_xlabel("x [m] (origin at mid-span)")
    ax.set_ylabel("y [m]")
    ax.set_title(f"{case.name}: hinges and line of thrust", fontsize=11)
    ax.grid(alpha=0.2)
    if handles:
        legend_below(ax, handles=handles, ncol=2, fontsize=8, frameon=False)
    fig.tight_layout()
    fig.savefig(path, dpi=150, bbox_inches="tight")
    plt.close(fig)


def status_text(res) -> str:
    """The status line of an :class:`~masonry_fdem.assessment.assess.Assessment` with its
    detail: "peak passed — collapse load 12.20 kN (the load fell ...)"."""
    d = res.status.detail
    return f"{res.status_line} ({d})" if d else res.status_line


def _layers_table(layers) -> list[str]:
    """The markdown table of the ring layers' openings (``Assessment.ring_separation``
    or ``ring_separation_at_peak``)."""
    out = ["| layer (below ring) | widest opening [mm] | separated over | at load [kN] | "
           "at load-line displacement [mm] |", "|---|---|---|---|---|"]
    for x in layers:
        out.append(f"| {x['layer']} | {x['max_opening'] * 1e3:.3f} | "
                   f"{100 * x['span_fraction']:.0f} % of the span | "
                   f"{x['load'] / 1e3:.2f} | {x['displacement'] * 1e3:.3f} |")
    return out


def _report(case, res, mag: float, drawn=(), paraview=()) -> str:
    a, ld = case.arch, case.loading
    kn = res.peak_load / 1e3
    lines = [f"# Assessment of `{case.name}`", "", f"**Status: {res.status_line}.**", ""]
    if res.status.detail:
        lines += [f"How the run ended: {res.status.detail}.", ""]
    disk_fill = case.fill is not None and case.fill.model == "disks"
    if not res.collapsed:
        if disk_fill:
            lines += ["The run gives no collapse load: to find one, load it further (more "
                      "`fill.disks.max_steps` per load, a larger `loading.max_load`).", ""]
        elif case.analysis.solver == "newton":
            lines += ["The run gives no collapse load: to find one, trace it further (more "
                      "`newton_steps` or `newton_iterations`, a smaller "
                      "`displacement_increment`, a larger `max_displacement` or "
                      "`max_load`).", ""]
        else:
            lines += ["The run gives no collapse load: to find one, drive it past the peak "
                      "(displacement control, `follow_peak`, more `max_iterations`, a larger "
                      "`max_displacement` or `max_load`).", ""]
    lines += [
        f"- Arch: {a.kind.value}, span {a.span:g} m, {a.rings} ring(s) of {a.ring_thickness:g} m, "
        f"voussoirs {list(a.voussoirs)}, barrel width {a.width:g} m; {res.cells} triangles.",
        f"- Load: {res.control} control at {ld.position:g} of the span through a "
        f"{ld.spreader_width:g} m spreader; self-weight {'on' if ld.self_weight else 'off'}.",
        f"- Ring interfaces: {case.ring_joint_type}"
        f"{'' if a.rings > 1 else ' (one ring)'}; radial joints: "
        f"{'bonded mortar' if case.mortar.bonded else 'dry'}, tan φ {case.mortar.tan_phi:g}.",
        f"- Damage: {', '.join(d.kind.value for d in case.damage) or 'none'}; "
        f"anchors: {len(case.anchor_specs)}.",
        *([_fill_text(case)] if case.fill is not None else []),
        "",
        "| quantity | value |",
        "|---|---|",
    ]
    if res.collapsed:
        lines += [f"| FDEM collapse load | **{kn:.2f} kN** ({kn / 9.80665:.2f} t) |",
                  f"| resolution | {res.resolution / 1e3:.2f} kN |"]
    else:
        lines.append(f"| FDEM largest load carried (a lower bound, not a collapse load) | "
                     f"**{kn:.2f} kN** ({kn / 9.80665:.2f} t) |")
    if res.limit_load is not None:
        lines.append(f"| limit analysis (rigid blocks, LP{_lp_fill(case)}) | "
                     f"{res.limit_load / 1e3:.2f} kN |")
        if res.collapsed:
            lines.append(f"| FDEM / limit analysis | {res.ratio:.3f} |")
        else:
            lines.append(f"| FDEM lower bound / limit analysis | ≥ {res.bound_ratio:.3f} |")
    elif res.limit_status == "infeasible":
        lines.append(f"| limit analysis | infeasible — {res.limit_explanation or 'no '
                     'equilibrium even without the live load'} (friction "
                     f"{case.analysis.friction:g} at the radial joints, the ring "
                     "interfaces' own; the FDEM model has the mortar's bond) |")
    elif res.limit_status:
        lines.append(f"| limit analysis | {res.limit_status} |")
    lines.append(f"| solver | {_solver_text(case)} |")
    lines.append(f"| wall time | {res.elapsed:.0f} s |")
    if res.anchor_peaks:
        lines += ["", "## Anchors", ""] + anchor_peaks_table(res.anchor_peaks)
    if res.ring_separation:
        thr = res.ring_separation[0]["threshold"]
        lines += ["", "## Ring separation", "",
                  f"Widest opening of each layer between rings over the run, and the part "
                  f"of the span separated then (opened by more than {thr * 1e3:.2f} mm, "
                  "1e-3 of the ring thickness, beyond the self-weight state):", ""]
        lines += _layers_table(res.ring_separation)
        if res.ring_separation_at_peak:
            lines += ["", "At the peak load (the arch loaded up to its collapse load):", ""]
            lines += _layers_table(res.ring_separation_at_peak)
    lines += ["", "## Load–displacement at the load line", "",
              "![load-displacement](load_displacement.png)", "",
              "## Hinge sequence", ""]
    if res.events:
        lines += ["| # | joint | kind | opens at | s | hinge x, y [m] | load [kN] |",
                  "|---|---|---|---|---|---|---|"]
        for e in res.events:
            lines.append(f"| {e.order} | {e.joint} | {e.kind} | {e.side} | {e.s:.3f} | "
                         f"{e.position[0]:.3f}, {e.position[1]:.3f} | {e.load / 1e3:.2f} |")
    else:
        lines.append("No joint opened beyond the threshold.")
    if res.first_hinges:
        lines += ["", "The first hinge depends on the opening counted as one: the sequence "
                  f"above counts an end opened by {case.analysis.hinge_opening:g} × the ring "
                  "thickness, its mortar cracked; the table gives the first hinge at wider "
                  "openings too (1e-2: about a millimetre on a brick ring, a crack one "
                  "sees):", "",
                  "| opening / ring thickness | first hinge | opens at | s | load [kN] | "
                  + ("of the collapse load |" if res.collapsed
                     else "of the largest load carried |"), "|---|---|---|---|---|---|"]
        for fh in res.first_hinges:
            if fh["step"] is None:
                lines.append(f"| {fh['ratio']:g} | none over the run | | | | |")
                continue
            lines.append(f"| {fh['ratio']:g} | {fh['joint']} | {fh['side']} | {fh['s']:.3f} | "
                         f"{fh['load'] / 1e3:.2f} | {fh['load'] / res.peak_load:.2f} |")
    if disk_fill and any(e.load > res.peak_load for e in res.events):
        lines += ["", "(A load above the collapse load is the one under which the ring ran "
                  "on, with no equilibrium: those joints opened in the mechanism.)"
                  if res.status.status is Status.MECHANISM else
                  "(A load above the largest load carried is the one that found no "
                  "equilibrium within the step budget: those joints opened under it.)"]
    when = ("at the peak load" if not disk_fill else "at the end of the run (the mechanism)"
            if res.status.status is Status.MECHANISM else "at the end of the run")
    lines += ["", f"Open {when}: {len(res.hinges_at_collapse)} joint(s). "
              f"Limit analysis: {_limit_motion(res)}.", "",
              "![hinges](hinges.png)", "",
              f"## Mechanism (displacements ×{mag:.0f})", "", "![mechanism](mechanism.png)",
              *[x for name, file, load, disp in drawn for x in (
                  "", f"At the {name}: {load / 1e3:.2f} kN, {disp * 1e3:.3f} mm "
                  "load-line displacement.", "", f"![{name}]({file})")],
              "", "Files: `curve.csv`, `hinges.csv`, `summary.json`"
              + (f"; ParaView: {', '.join(f'`{p}/model.pvd`' for p in paraview)} (and the "
                 "ADIOS2 `.bp` series beside it; time = increment number, every "
                 f"{case.analysis.paraview_every} increments and the last)"
                 if paraview else "") + ".", ""]
    return "\n".join(lines)


def _limit_motion(res) -> str:
    """The limit analysis's mechanism in words, e.g. "a mechanism with 4 hinges" (its
    hinges drawn in ``hinges.png``; sliding interfaces counted, not drawn)."""
    if res.limit_status != "collapse":
        return res.limit_status or "not run"
    words = res.limit_explanation.split(" by ", 1)
    return words[1] if len(words) == 2 else f"{len(res.limit_hinges)} hinges"


def anchor_peaks_table(peaks: list[dict]) -> list[str]:
    """Markdown lines: each anchor's largest bar force over the traced path, against
    its yield force, and the load-line displacement and load where it occurred."""
    lines = ["The largest bar force of each anchor over the traced path (the anchors may "
             "work hardest after the peak), and where it occurred:", "",
             "| anchor | largest bar force [kN] | of yield | at load-line displacement "
             "[mm] | at load [kN] |", "|---|---|---|---|---|"]
    for pk in peaks:
        lines.append(f"| {pk['name']} | {pk['force_max'] / 1e3:.2f} | "
                     f"{100 * pk['force_max'] / pk['yield_force']:.0f} % | "
                     f"{pk['displacement'] * 1e3:.3f} | {pk['load'] / 1e3:.2f} |")
    dow = [pk for pk in peaks if "dowel_max" in pk]
    if dow:
        lines += ["", "The largest shear force of each anchor's dowels across the joints it "
                  "crosses (per bar), against the dowel's strength:", "",
                  "| anchor | largest dowel force [kN] | of strength | at load [kN] |",
                  "|---|---|---|---|"]
        for pk in dow:
            st = pk["dowel_strength"]
            of = f"{100 * pk['dowel_max'] / st:.0f} %" if st is not None else "elastic"
            lines.append(f"| {pk['name']} | {pk['dowel_max'] / 1e3:.2f} | {of} | "
                         f"{pk['dowel_load'] / 1e3:.2f} |")
    return lines


def _lp_fill(case) -> str:
    f = case.fill
    if f is None:
        return ""
    m = case.materials()[f.material]
    text = (f"; the fill as RING's, of `{f.material}` (c {m.c / 1e3:g} kPa, φ {m.phi:g}°)"
            + (": its weight," if case.loading.self_weight else ":")
            + f" the load's 2:1 dispersion, passive resistance × {f.passive_mobilisation:g}"
            + (", loads leaning on steep chords" if f.incline_loads else "")
            + (f"; the backing ({f.backing:g} m) a support" if f.backing > 0 else ""))
    if f.model == "disks":
        text += "; not the disks, nor a road layer"
    return text


def _fill_text(case) -> str:
    f = case.fill
    head = (f"- Fill: {f.cover:g} m over the crown's extrados, interface tan δ "
            f"{f.interface_friction:.3g}; ")
    if f.model != "disks":
        return head + (f"a Mohr–Coulomb continuum (`{f.material}`, plane strain)"
                       + (f", on the haunches' backing {f.backing:g} m above the springing "
                          f"(`{case.arch.abutment_material}`, fixed with the abutments)"
                          if f.backing > 0 else "") + ".")
    d = f.disks or DiskFillSpec()
    return head + (f"disks ({d.count} asked of the packer; porosity {d.porosity:g}, E "
                   f"{d.E:.3g} Pa, friction {d.friction:g}, rolling friction "
                   f"{d.rolling_friction:g}; bulk density that of `{f.material}`)"
                   + (f" under {d.surfacing:g} m of `{d.surfacing_material}`"
                      if d.surfacing > 0 else "") + ".")


def _solver_text(case) -> str:
    an = case.analysis
    if case.fill is not None and case.fill.model == "disks":
        d = case.fill.disks or DiskFillSpec()
        return (f"explicit dynamics with Cundall's local damping ({d.local_damping:g}), the "
                f"fill as disks; an equilibrium when the unbalanced-force ratios of the disks "
                f"(rattlers left out) and of the blocks fall below {d.tol:g} within "
                f"{d.max_steps} steps per load; a mechanism when the ring runs on under a "
                "constant load, a voussoir moving a quarter of the ring thickness (the "
                "ring's motion, not the beam's: the beam may sink into the fill and find "
                "its bearing)")
    if an.solver == "newton":
        return (f"Newton (PETSc SNES, MUMPS), arc length on the load-line displacement; "
                f"equilibrium to {an.newton_rtol:g} of the forces"
                + ("; the joints' softening implicit–explicit (IMEX: strengths held at "
                   "values extrapolated from the last two increments)"
                   if an.softening == "imex" else "")
                + ("; the contact through a joint layer at the layer's stiffness"
                   if an.through_layers else ""))
    return (f"dynamic relaxation, {case.loading.control.value} control; equilibrium to "
            f"{an.dr_rtol:g} of the forces within {an.max_iterations} iterations")


def read_curve(path: str | Path) -> tuple[str, np.ndarray]:
    """``(status line, rows)`` of a ``curve.csv``: the text after ``# status:`` and the
    ``(n, 3)`` array of load [N], displacement [m] and iterations."""
    status, rows = "", []
    with open(path, newline="", encoding="utf-8") as fh:
        for line in fh:
            if line.startswith("#"):
                if line.startswith("# status:"):
                    status = line[len("# status:"):].strip()
                continue
            rows.append(line)
    data = list(csv.reader(rows))[1:]
    return status, np.array([[float(x) for x in r] for r in data]).reshape(-1, 3)
