"""A single-span masonry arch bridge with its fill under a traversing axle (issue #22).

The case `cases/bridge_single_span.toml` (a 6 m segmental stone arch under 0.4 m of
granular fill, Mohr–Coulomb in plane strain, friction-only interfaces with the arch, the
abutments and the retaining end walls; an axle line load on a 0.3 m loading beam) is
loaded to collapse with the axle at each of several positions along the span, quasi-
statically at each (Newton, arc length), and each time also without its fill (the bare
ring, with its rigid-block limit load). The positions are shared among the ranks (one
rank per run). Prints and writes to ``--out``:

* ``sweep.md``: collapse load against position, with fill and bare, each run's status,
  beside the limit analysis of the ring with the fill as RING models it (its weight, the
  axle dispersed 2:1, a passive resistance up to the case's ``passive_mobilisation`` of
  Rankine's) and of the bare ring; the critical position (the lowest collapse load with
  fill) — LimitState:RING's question — of the FDEM among the positions run, and of the
  limit analysis on a fine grid of positions (with and without the passive resistance);
  ``sweep.png`` the same as a plot;
* a run folder per position with fill (``fill_<position>/``: report, curve, mechanism,
  ``vertical_stress.png`` — the vertical stress in the fill and the arch at the peak load,
  the load's path through the fill); the critical position's and the mid-span one's
  pictures are copied to ``vertical_stress_<position>.png``.

    mpirun -n 2 python demos/bridge.py --out out_bridge          # (make demo-bridge)
    mpirun -n 2 python demos/bridge.py --coarse --out out_bridge # (make demo)

``--coarse``: half the voussoirs and a fill mesh twice as coarse, four positions.
"""

from __future__ import annotations

import argparse
import shutil
import time
from dataclasses import replace
from pathlib import Path

from mpi4py import MPI

import numpy as np

from masonry_fdem.assessment.assess import assess
from masonry_fdem.assessment.case import load_case

TONNE = 9806.65  # [N]
ROOT = Path(__file__).resolve().parents[1]

ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
ap.add_argument("--out", default="out_bridge")
ap.add_argument("--case", default=str(ROOT / "cases" / "bridge_single_span.toml"))
ap.add_argument("--coarse", action="store_true",
                help="half the voussoirs, a coarser fill mesh, four positions (minutes)")
ap.add_argument("--positions", type=float, nargs="*", default=None,
                help="load positions as fractions of the span (default 0.1 to 0.5)")
args = ap.parse_args()
comm = MPI.COMM_WORLD
case = load_case(args.case)
positions = args.positions or ([0.15, 0.25, 0.35, 0.5] if args.coarse else
                               [0.1, 0.15, 0.2, 0.25, 0.3, 0.35, 0.4, 0.5])
if args.coarse:
    arch = case.arch
    case = replace(case, arch=replace(arch, voussoirs=tuple((n + 1) // 2 for n in arch.voussoirs)),
                   fill=replace(case.fill, mesh_size=2.0 * case.fill.mesh_size))
out = Path(args.out)
if comm.rank == 0:
    out.mkdir(parents=True, exist_ok=True)
comm.barrier()



def _lp(load, status) -> str:
    """An LP load [N] for the table: "no mechanism" when the LP found none."""
    if load is None or status != "collapse":
        return str(status).replace("_", " ")
    return f"{load / 1e3:.1f}"


t0 = time.perf_counter()
rows = []
for k in range(comm.rank, len(positions), comm.size):
    pos = positions[k]
    c = replace(case, name=f"{case.name} at {pos:g} span",
                loading=replace(case.loading, position=pos))
    t = time.perf_counter()
    filled = assess(c, out=out / f"fill_{pos:g}", overwrite=True, progress=False,
                    comm=MPI.COMM_SELF)
    bare = assess(replace(c, fill=None), write=False, progress=False, comm=MPI.COMM_SELF)
    rows.append(dict(position=pos, load=filled.peak_load, collapsed=filled.collapsed,
                     status=filled.status.status.value, line=filled.status_line,
                     bare=bare.peak_load, bare_collapsed=bare.collapsed,
                     limit=bare.limit_load, limit_fill=filled.limit_load,
                     limit_fill_status=filled.limit_status, seconds=time.perf_counter() - t))
    print(f"[rank {comm.rank}] {pos:g} span: with fill {filled.status_line}; bare "
          f"{bare.status_line} ({time.perf_counter() - t:.0f} s)", flush=True)
rows = sorted((r for part in comm.allgather(rows) for r in part), key=lambda r: r["position"])

def _lp_sweep(xs: np.ndarray, passive: bool, incline: bool = False) -> np.ndarray:
    """Limit load [N] with fill at each position (NaN where the LP finds no mechanism);
    ``incline``: the fill's loads on chords steeper than its interface friction lean
    uphill by the excess."""
    out = []
    for pos in xs:
        res = replace(case, loading=replace(case.loading, position=float(pos))).limit_analysis(
            passive=passive, incline=incline)
        out.append(res.load_factor if res.status == "collapse" else np.nan)
    return np.array(out)


def _critical(xs: np.ndarray, loads: np.ndarray) -> str:
    if not np.isfinite(loads).any():
        return "none (no mechanism at any position)"
    k = int(np.nanargmin(loads))
    return f"{xs[k]:g} of the span ({loads[k] / 1e3:.1f} kN)"


if comm.rank == 0:
    fine = np.round(np.arange(0.05, 0.5001, 0.025), 3)
    lp_fine, lp_none = _lp_sweep(fine, True), _lp_sweep(fine, False)
    lp_lean = _lp_sweep(fine, True, incline=True)
    lean_at = _lp_sweep(np.array([r["position"] for r in rows]), True, incline=True)
    proved = [r for r in rows if r["collapsed"]]
    crit = min(proved, key=lambda r: r["load"]) if proved else None
    lines = [f"# {case.name}: collapse load against the axle's position", "",
             f"{len(rows)} positions, {time.perf_counter() - t0:.0f} s on {comm.size} "
             f"rank(s). Loads per {case.arch.width:g} m of barrel width. LP: the rigid-block "
             "limit analysis of the same ring — bare, and with the fill as RING models it "
             "(its weight over the extrados, the axle dispersed 2:1, a passive resistance "
             f"up to {case.fill.passive_mobilisation:g} of Rankine's); \"loads leaning\": "
             "the same with the fill's loads on the extrados leaning uphill where it is "
             "steeper than the fill's interface friction angle, by the excess.",
             "", "| position / span | with fill [kN] | [t] | status | LP with fill [kN] | "
             "LP, loads leaning [kN] | bare ring [kN] | LP bare [kN] | fill / bare |",
             "|---|---|---|---|---|---|---|---|---|"]
    for r, lean in zip(rows, lean_at, strict=True):
        mark = "" if r["collapsed"] else "≥ "
        bmark = "" if r["bare_collapsed"] else "≥ "
        lines.append(f"| {r['position']:g} | {mark}{r['load'] / 1e3:.1f} | "
                     f"{mark}{r['load'] / TONNE:.2f} | {r['status']} | "
                     f"{_lp(r['limit_fill'], r['limit_fill_status'])} | "
                     f"{f'{lean / 1e3:.1f}' if np.isfinite(lean) else 'no mechanism'} | "
                     f"{bmark}{r['bare'] / 1e3:.2f} | "
                     f"{(r['limit'] or float('nan')) / 1e3:.2f} | "
                     f"{r['load'] / r['bare']:.2f} |")
    lines.append("")
    if crit is None:
        lines.append("No run proved a collapse load (every status above is a lower bound): "
                     "no critical position.")
    else:
        lines.append(f"Critical position: {crit['position']:g} of the span, collapse load "
                     f"{crit['load'] / 1e3:.1f} kN ({crit['load'] / TONNE:.2f} t) — among the "
                     "positions run, whose runs proved a collapse (*peak passed*).")
    lines += ["", f"Limit analysis with fill on a grid of {fine.size} positions (rigid ring, "
              "seconds): critical position " + _critical(fine, lp_fine) + f" with passive "
              f"resistance (m = {case.fill.passive_mobilisation:g}); "
              + _critical(fine, lp_none) + " without; " + _critical(fine, lp_lean)
              + " with the loads leaning."]
    text = "\n".join(lines) + "\n"
    (out / "sweep.md").write_text(text, encoding="utf-8")
    print(text)

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    x = np.array([r["position"] for r in rows])
    fig, ax = plt.subplots(figsize=(6.5, 4))
    ok = np.array([r["collapsed"] for r in rows])
    y = np.array([r["load"] for r in rows]) / 1e3
    ax.plot(x, y, "-", color="C0", lw=1)
    ax.plot(x[ok], y[ok], "o", color="C0", label="with fill: collapse (peak passed)")
    if (~ok).any():
        ax.plot(x[~ok], y[~ok], "^", mfc="none", color="C0", label="with fill: lower bound")
    ax.plot(x, [r["bare"] / 1e3 for r in rows], "s-", color="C1", ms=4, label="bare ring")
    ax.plot(x, [(r["limit"] or np.nan) / 1e3 for r in rows], "x--", color="C3",
            label="bare ring, limit analysis")
    ax.plot(fine, lp_fine / 1e3, "--", color="C2", lw=1.2,
            label=f"limit analysis with fill (passive × {case.fill.passive_mobilisation:g})")
    ax.plot(fine, lp_none / 1e3, ":", color="C2", lw=1.2,
            label="limit analysis with fill, no passive")
    ax.plot(fine, lp_lean / 1e3, "-.", color="C4", lw=1.2,
            label="limit analysis with fill, loads leaning")
    if crit is not None:
        ax.axvline(crit["position"], color="0.5", ls=":", lw=1)
    ax.set_xlabel("axle position / span")
    ax.set_ylabel(f"collapse load [kN per {case.arch.width:g} m]")
    ax.set_yscale("log")
    ax.set_title(f"{case.name}: collapse load against the axle's position", fontsize=9)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out / "sweep.png", dpi=120)
    plt.close(fig)
    picks = {r["position"] for r in ([crit] if crit else []) + [rows[-1]]}
    for pos in sorted(picks):
        src = out / f"fill_{pos:g}" / "vertical_stress.png"
        if src.is_file():
            shutil.copyfile(src, out / f"vertical_stress_{pos:g}.png")
    print(f"wrote {out / 'sweep.md'}, sweep.png, vertical_stress_*.png and the run folders")
