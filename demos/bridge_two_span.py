"""A two-span masonry arch bridge with its fill, the soil under its central pier, and an
abnormal vehicle's bogie traversing it (issue #22; the reference paper's first
application, its Figure 6).

The case ``cases/bridge_two_span.toml`` (every value argued there; built by
``masonry_fdem.geometry.bridge.Bridge``): two 6 m segmental stone spans
(rise 1.5 m, 0.4 m rings, dry joints μ 0.6) on a 1.5 m pier and two abutments, 2 m from
the foundation to the springings; 0.4 m of granular fill (Mohr–Coulomb) and 0.1 m of
surfacing over the crowns; the pier stands on a 3 m deep Mohr–Coulomb soil, the abutments
on rigid ground. The vehicle: a two-axle bogie (1.8 m between equal axles, 0.3 m tyre
patches). At each of its positions (four, from the first span's quarter to the pier)
the bogie is loaded to collapse, quasi-statically
(Newton, arc length); the positions are shared among the ranks (one rank per run). The
bridge is symmetric, so the bogie is moved over the first span and up to the pier.

Writes to ``--out``: ``sweep.md`` and ``sweep.png`` (collapse load against the bogie's
position, each run's status), ``vertical_stress_<x>.png`` (σ_yy in the fill, the soil and
the arches at the peak load: the paper's Figure 6) and ``mechanism_<x>.png`` (the
deformed bridge at the end of the run) for two positions — the critical one and the one
over the pier.

    mpirun -n 2 python demos/bridge_two_span.py --out out_bridge_two_span   (make demo-bridge)
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from mpi4py import MPI

import numpy as np

from masonry_fdem.assessment.bridge_case import load_bridge_case
from masonry_fdem.io.plot import plot_blocks

TONNE = 9806.65  # [N]

ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
ap.add_argument("--out", default="out_bridge_two_span")
ap.add_argument("--case", default=str(Path(__file__).resolve().parents[1] / "cases" /
                                      "bridge_two_span.toml"))
ap.add_argument("--positions", type=float, nargs="*", default=None,
                help="x [m] of the vehicle's centre (default: the case's vehicle.positions)")
args = ap.parse_args()
comm = MPI.COMM_WORLD

case = load_bridge_case(args.case)
BRIDGE = case.bridge
SPAN = BRIDGE.spans[0]
positions = list(args.positions or case.positions)
if not positions:
    raise SystemExit(f"{args.case}: no vehicle.positions, and none given (--positions)")
out = Path(args.out)
if comm.rank == 0:
    out.mkdir(parents=True, exist_ok=True)
comm.barrier()
sp = BRIDGE.springings()
x_pier = 0.5 * (sp[0][1] + sp[1][0]) if len(sp) > 1 else sp[0][1]  # the first pier

t0 = time.perf_counter()
rows, drawn = [], {}
for k in range(comm.rank, len(positions), comm.size):
    x = positions[k]
    model, run = case.run(x, comm=MPI.COMM_SELF)
    rows.append(dict(x=x, load=run.peak, collapsed=run.collapsed,
                     status=run.status.status.value, line=run.line(), seconds=run.seconds,
                     cells=model.blocks.n_cells))
    print(f"[rank {comm.rank}] bogie at x = {x:g} m: {run.line()} ({run.seconds:.0f} s)",
          flush=True)
    drawn[x] = (model, run)
rows = sorted((r for part in comm.allgather(rows) for r in part), key=lambda r: r["x"])
proved = [r for r in rows if r["collapsed"]]
crit = min(proved, key=lambda r: r["load"]) if proved else None
picks = {min(positions, key=lambda p: abs(p - x_pier))}
if crit is not None:
    picks.add(crit["x"])

for x, (model, run) in drawn.items():
    if x not in picks or run.sigma_yy is None:
        continue
    now = model.u.x.array.copy()
    model.u.x.array[:] = run.u_peak
    lo, hi = np.percentile(run.sigma_yy / 1e3, [1.0, 99.0])
    plot_blocks(model, out / f"vertical_stress_{x:g}.png", field=run.sigma_yy / 1e3,
                cmap="viridis_r", clim=(lo, min(hi, 0.0) if lo < 0 else hi),
                title=f"bogie at x = {x:g} m: σ_yy [kPa] at the peak, {run.peak / 1e3:.0f} kN\n"
                      "(compression < 0; colours clipped at 1 %, 99 %)")
    model.u.x.array[:] = now
    plot_blocks(model, out / f"mechanism_{x:g}.png", scale=5.0,
                title=f"bogie at x = {x:g} m: deformed ×5 at the end of the run\n"
                      f"{run.line().split(' (')[0]}")

if comm.rank == 0:
    b = BRIDGE
    lines = [
        "# Two-span arch bridge: collapse load against the bogie's position", "",
        f"{len(rows)} positions, {time.perf_counter() - t0:.0f} s on {comm.size} rank(s); "
        f"{rows[0]['cells']} triangles. Spans 2 × {SPAN.span:g} m (rise {SPAN.rise:g} m, "
        f"ring {SPAN.ring_thickness:g} m), pier {b.piers[0]:g} m at x = {x_pier:g} m on "
        f"{b.soil_depth:g} m of soil; road {b.road_level():.2f} m, cover {b.cover:g} m "
        f"(surfacing {b.surfacing:g} m). Vehicle: axles at {list(case.vehicle.offsets)} m "
        f"from its centre, relative loads {list(case.vehicle.loads)}, "
        f"{case.vehicle.patch:g} m patches; the load is the vehicle's total, per "
        f"{b.width:g} m of barrel width.", "",
        "| vehicle centre x [m] | / first span | collapse load [kN] | [t] | status | time [s] |",
        "|---|---|---|---|---|---|"]
    for r in rows:
        mark = "" if r["collapsed"] else "≥ "
        lines.append(f"| {r['x']:g} | {r['x'] / SPAN.span:.3f} | {mark}{r['load'] / 1e3:.1f} | "
                     f"{mark}{r['load'] / TONNE:.2f} | {r['status']} | {r['seconds']:.0f} |")
    lines.append("")
    if crit is None:
        lines.append("No run proved a collapse load: no critical position.")
    else:
        lines.append(f"Critical position among those run: bogie centre at x = {crit['x']:g} m "
                     f"({crit['x'] / SPAN.span:.3f} of the first span), {crit['load'] / 1e3:.1f}"
                     f" kN ({crit['load'] / TONNE:.2f} t).")
    text = "\n".join(lines) + "\n"
    (out / "sweep.md").write_text(text, encoding="utf-8")
    print(text)

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    xs = np.array([r["x"] for r in rows])
    ys = np.array([r["load"] for r in rows]) / 1e3
    ok = np.array([r["collapsed"] for r in rows])
    fig, ax = plt.subplots(figsize=(6.5, 4))
    ax.plot(xs, ys, "-", color="C0", lw=1)
    ax.plot(xs[ok], ys[ok], "o", color="C0", label="collapse (peak passed)")
    if (~ok).any():
        ax.plot(xs[~ok], ys[~ok], "^", mfc="none", color="C0", label="lower bound (no peak)")
    for (a, c) in b.springings():
        ax.axvspan(a, c, color="0.9", zorder=0)
    ax.axvline(x_pier, color="0.5", ls=":", lw=1, label="pier")
    ax.set_xlabel("bogie centre x [m] (spans shaded)")
    ax.set_ylabel("collapse load, both axles [kN per 1 m]")
    ax.set_xlim(-0.5, x_pier + 0.5)
    ax.set_title("Two-span bridge: collapse load against the bogie's position", fontsize=9)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out / "sweep.png", dpi=120)
    plt.close(fig)
    print(f"wrote {out / 'sweep.md'}, sweep.png, vertical_stress_*.png, mechanism_*.png")
