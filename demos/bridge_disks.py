"""A single-span arch bridge with its fill as disks, loaded to collapse quasi-statically
(issue #22, item 4; the reference paper's way of modelling a bridge's fill).

The case (default `cases/bridge_single_span.toml`: a 6 m segmental stone arch under 0.4 m
of fill, a 0.3 m loading beam at quarter span) with its ``[fill]`` packed by disks
instead of the Mohr–Coulomb continuum
(:class:`~masonry_fdem.assessment.disk_fill.DiskFillBridge`: the region over-packed,
settled on the held arch and trimmed to the road; the arch released and settled again;
then the beam's load in steps, each held by explicit dynamics with Cundall's local
damping until the unbalanced-force ratios of the disks and of the blocks fall below 1e-3;
a load under which the beam runs a quarter of the ring thickness is a mechanism and the
collapse load is the last load carried). Writes to ``--out``:

* ``curve.csv`` (load [N], beam settlement [m], explicit steps, ratios; first line the
  status) and ``curve.png``;
* ``vertical_stress.png``: σ_yy in the fill averaged from the contact forces over cells
  (Love–Weber, ``--cell`` wide) at the last load carried, the load's path to the arch;
* ``collapse.png``: the blocks and disks at the end of the run (the mechanism, or where
  the run stopped).

    mpirun -n 2 python demos/bridge_disks.py --out out_bridge_disks
    python demos/bridge_disks.py --position 0.4 --count 3000 --increment 20e3

The disks are held by every rank (the disk–disk forces divided among them), the blocks
distributed; two ranks give the result of one.
"""

from __future__ import annotations

import argparse
import os
import time
from dataclasses import replace
from pathlib import Path

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # one BLAS thread per rank (see benchmarks/bridge_disks.py)

from mpi4py import MPI  # noqa: E402

import numpy as np  # noqa: E402

from masonry_fdem.assessment.case import load_case  # noqa: E402
from masonry_fdem.assessment.disk_fill import DiskFillBridge  # noqa: E402
from masonry_fdem.constants import G  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


def stress_grid(b: DiskFillBridge, cell: float):
    """σ_yy [Pa] over square cells of the fill's bounding box (NaN where a cell holds
    fewer than three disk centres); collective."""
    poly = b.fill_polygon
    xs = np.arange(poly[:, 0].min(), poly[:, 0].max() + 1e-9, cell)
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


def draw_stress(b: DiskFillBridge, grid, load: float, y0: float, disks, path: Path) -> None:
    """The stress grid, the disks ``(x, r)`` and the beam's bottom ``y0`` [m] as they
    were at ``load``, over the blocks' outlines (undeformed)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import PatchCollection
    from matplotlib.patches import Circle, Polygon

    xs, ys, sig = grid
    fig, ax = plt.subplots(figsize=(11, 4.2))
    m = ax.pcolormesh(xs, ys, np.ma.masked_invalid(-sig / 1e3), cmap="magma_r",
                      shading="flat", vmin=0.0)
    fig.colorbar(m, ax=ax, label="vertical stress in the fill, compression [kPa]")
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
                 f"(the last load carried; cells {grid[0][1] - grid[0][0]:.2f} m)",
                 fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--case", default=str(ROOT / "cases" / "bridge_single_span.toml"))
    ap.add_argument("--out", default="out_bridge_disks")
    ap.add_argument("--position", type=float, default=None,
                    help="load position as a fraction of the span (default: the case's)")
    ap.add_argument("--count", type=int, default=5600, help="disks asked of the packer")
    ap.add_argument("--increment", type=float, default=10e3, help="load step [N]")
    ap.add_argument("--max-steps", type=int, default=600_000,
                    help="explicit steps allowed per load")
    ap.add_argument("--surfacing", type=float, default=0.0,
                    help="thickness [m] of a road layer over the disks, within the cover "
                         "(a bituminous surfacing on a granular road base, Mohr–Coulomb: "
                         "E 1 GPa, c 100 kPa, φ 35°, as cases/bridge_two_span.toml)")
    ap.add_argument("--cell", type=float, default=0.2,
                    help="width of the stress-averaging cells [m]")
    args = ap.parse_args()
    comm = MPI.COMM_WORLD
    say = print if comm.rank == 0 else (lambda *a, **k: None)
    case = load_case(args.case)
    if args.position is not None:
        case = replace(case, loading=replace(case.loading, position=args.position))
    out = Path(args.out)
    if comm.rank == 0:
        out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    from masonry_fdem.materials import MohrCoulomb

    road = MohrCoulomb(density=2300.0, E=1e9, nu=0.3, c=100e3, phi=35.0)
    b = DiskFillBridge(case, count=args.count, surfacing=args.surfacing,
                       surfacing_material=road if args.surfacing > 0 else None, comm=comm)
    say(f"{case.name}: load at {case.loading.position:g} of the span on a "
        f"{case.loading.spreader_width:g} m beam"
        + (f" on {args.surfacing:g} m of surfacing" if args.surfacing > 0 else "")
        + f"; {b.disks.n} disks packed (r "
        f"{b.disks.r.min() * 1e3:.1f}..{b.disks.r.max() * 1e3:.1f} mm), {comm.size} "
        f"rank(s); blocks' inertia ×{b.inertia_scale:.0f} (density scaling)", flush=True)
    if not b.settle():
        say("the fill did not settle under self-weight (ratios "
            f"{b.ratios()}): nothing loaded")
        return
    say(f"settled: {b.trimmed} disks trimmed above the road, {b.disks.n} left; "
        f"{b.steps_held} + {b.steps_free} steps ({time.perf_counter() - t0:.0f} s); "
        f"the disks' top under the {'surfacing' if args.surfacing > 0 else 'beam'} "
        f"{b.surface:.3f} m (asked {b.fill_top:.3f} m)",
        flush=True)
    last = {}

    def at(br, p):
        last["grid"] = stress_grid(br, args.cell)
        last["load"] = p
        last["disks"] = (br.disks.x.copy(), br.disks.r.copy())
        last["beam"] = br.road + br.overfill - br.beam_settlement()  # its bottom [m]
        say(f"  {p / 1e3:7.1f} kN carried: beam settlement "
            f"{(br.beam_settlement() - br.dead_settlement) * 1e3:7.2f} mm, "
            f"{time.perf_counter() - t0:.0f} s", flush=True)

    run = b.load(args.increment, max_steps=args.max_steps, callback=at)
    say(f"{run.line()}")
    cl = run.collapse_load
    if cl is not None:
        say(f"collapse load {cl / 1e3:.1f} kN ({cl / (1000 * G):.2f} t) per "
            f"{case.arch.width:g} m of barrel; wall time {time.perf_counter() - t0:.0f} s")
    if comm.rank == 0:
        with open(out / "curve.csv", "w") as fh:
            fh.write(f"# status: {run.status.describe('kN', 1e3, '.1f')}\n")
            fh.write("load_N,settlement_m,steps,ratio_disks,ratio_blocks\n")
            for p, d, n, (rd, rb) in zip(run.loads, run.displacements, run.steps,
                                         run.ratios, strict=True):
                fh.write(f"{p:.6g},{d:.6e},{n},{rd:.3e},{rb:.3e}\n")
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(6, 4))
        ax.plot(np.array(run.displacements) * 1e3, np.array(run.loads) / 1e3, "o-")
        ax.set_xlabel("beam settlement under the load [mm]")
        ax.set_ylabel("load [kN]")
        ax.set_title(f"disk fill, load at {case.loading.position:g} of the span\n"
                     f"{run.status.status.value}", fontsize=10)
        ax.grid(alpha=0.3)
        fig.tight_layout()
        fig.savefig(out / "curve.png", dpi=130)
        plt.close(fig)
        if "grid" in last:
            draw_stress(b, last["grid"], last["load"], last["beam"], last["disks"],
                        out / "vertical_stress.png")
    from masonry_fdem.io.plot import plot_blocks

    plot_blocks(b.model, out / "collapse.png", disks=b.disks, joints=b.blocks[1],
                title=f"disk fill at the end of the run: {run.status.status.value}"
                + (f", collapse load {cl / 1e3:.0f} kN" if cl is not None else ""))
    say(f"wrote {out}/: curve.csv, curve.png, vertical_stress.png, collapse.png "
        f"({time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    main()
