"""The two-span bridge of ``cases/bridge_two_span.toml`` with its fill as disks, an abnormal
vehicle's bogie traversing it at a fixed load (issue #22; the reference paper's first
application, its Figure 6: masonry as deformable blocks, the fill as circular discrete
elements, the soil under the central pier as a Mohr–Coulomb continuum).

The case's bridge (two 6 m segmental stone spans on a 1.5 m pier founded on 3 m of soil,
0.4 m of fill and 0.1 m of surfacing over the crowns) with ``[bridge] fill_model =
"disks"`` (:class:`~masonry_fdem.assessment.disk_bridge.DiskBridge`): the fill region
over-packed by disks, settled on the held arches and trimmed to its top; the surfacing
lowered onto it, every block released and the whole settled under self-weight (explicit
dynamics, Cundall's local damping, until the unbalanced-force ratios of the disks and the
blocks fall below 1e-3). Then the bogie (two equal axles 1.8 m apart, 0.3 m tyre patches
pressing on the surfacing) is put on the road at its first position, its load raised in
four steps, and driven along the road to the pier (seven positions a metre apart), held
to equilibrium at each position.

The load: ``--load`` [N] for both axles over the 1 m strip of barrel the plane model
stands for, 100 kN by default (two 50 kN axles). It is an assumption, not a code value: a
heavy abnormal axle of 16.5 t (162 kN) shared over some 3 m of barrel width; about a
fifth of the collapse load the continuum model of the same bridge finds with the bogie at
mid-span (``demos/bridge_two_span.py``, 483–505 kN). Twice that (200 kN) sank the road
0.25 m into the disks under the first position and took 400 s to settle there: a
cohesionless disk fill under a plane-strain tyre strip is far softer than the continuum
fill with its 5 kPa of cohesion.

Writes to ``--out``: ``traverse.md`` (per position: the explicit steps to equilibrium,
the road's settlement under each axle, the ratios), ``traverse.png`` (settlement under
each axle against the bogie's position), and for two positions (``--pictures``)
``vertical_stress_<x>.png``, σ_yy in the fill averaged from the disks' contact forces over
0.25 m cells (Love–Weber): the load paths through the fill (the paper's Figure 6), and
``blocks_stress_<x>.png``, σ_yy in the arches, the pier, the soil and the surfacing;
``paraview/``: the blocks (``model.pvd``, or ``displacement.bp``/``stress.bp``/``joints.bp``
with the ADIOS2 reader) and the disks (``disks.pvd``), one frame per position (time: the
bogie centre's x [m]; -1 under self-weight).

    mpirun -n 2 python demos/bridge_two_span_disks.py --out out_bridge_two_span_disks
    (make demo-bridge)

The disks are held by every rank (their forces divided among the ranks), the blocks
distributed; two ranks give the result of one.
"""

from __future__ import annotations

import argparse
import os
import time
import tomllib
from pathlib import Path

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # one BLAS thread per rank

from mpi4py import MPI  # noqa: E402

import numpy as np  # noqa: E402

from masonry_fdem.assessment.bridge_case import load_bridge_case  # noqa: E402
from masonry_fdem.assessment.disk_bridge import draw_bridge_stress  # noqa: E402
from masonry_fdem.assessment.disk_fill import stress_grid  # noqa: E402
from masonry_fdem.io import DiskOutput  # noqa: E402
from masonry_fdem.io.plot import plot_blocks  # noqa: E402
from masonry_fdem.io.vtx import VTXOutput  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--case", default=str(ROOT / "cases" / "bridge_two_span.toml"))
    ap.add_argument("--out", default="out_bridge_two_span_disks")
    ap.add_argument("--load", type=float, default=100e3,
                    help="the bogie's total load [N] over the 1 m strip (default 100 kN)")
    ap.add_argument("--count", type=int, default=6000, help="disks asked of the packer")
    ap.add_argument("--positions", type=float, nargs="*",
                    default=[0.75, 1.75, 2.75, 3.75, 4.75, 5.75, 6.75],
                    help="x [m] of the bogie's centre, in the order driven (default: every "
                         "metre from 0.75 m to the pier's centre, 6.75 m)")
    ap.add_argument("--pictures", type=float, nargs="*", default=[2.75, 6.75],
                    help="positions [m] whose stress is pictured (default: the bogie "
                         "astride the first span's crown, 2.75 m, and over the pier)")
    ap.add_argument("--cell", type=float, default=0.25,
                    help="width [m] of the stress-averaging cells")
    ap.add_argument("--max-steps", type=int, default=300_000,
                    help="explicit steps allowed per stage and per position")
    args = ap.parse_args()
    comm = MPI.COMM_WORLD
    say = print if comm.rank == 0 else (lambda *a, **k: None)
    data = tomllib.loads(Path(args.case).read_text(encoding="utf-8"))
    data["bridge"]["fill_model"] = "disks"
    data["bridge"]["disks"] = {"count": args.count}
    data["bridge"]["mesh"].pop("crossed", None)
    data["vehicle"]["load"] = args.load
    data["vehicle"]["positions"] = list(args.positions)
    case = load_bridge_case(data, name=Path(args.case).stem + " (disk fill)")
    out = Path(args.out)
    if comm.rank == 0:
        out.mkdir(parents=True, exist_ok=True)
    comm.barrier()
    t0 = time.perf_counter()
    b = case.disk_bridge(comm)
    say(f"{b.disks.n} disks (r {b.disks.r.min() * 1e3:.0f}–{b.disks.r.max() * 1e3:.0f} mm), "
        f"{b.model.blocks.n_cells} triangles, blocks' inertia ×{b.inertia_scale:.0f}; "
        "settling under self-weight ...", flush=True)
    tol = (case.disks.tol if case.disks else 1e-3)
    ok = b.settle(tol=tol, max_steps=args.max_steps)
    rd, rb = b.ratios()
    settle_s = time.perf_counter() - t0
    say(f"self-weight: {'equilibrium' if ok else 'NOT settled'} (ratios disks {rd:.1e}, "
        f"blocks {rb:.1e}; {b.steps_held} + {b.steps_free} steps, {b.trimmed} disks trimmed "
        f"above the fill, {settle_s:.0f} s)", flush=True)
    if not ok:
        raise SystemExit("the fill did not settle under self-weight: no traverse")
    pictures = {min(case.positions, key=lambda p, x=x: abs(p - x)) for x in args.pictures}
    drawn = []
    # ParaView: the blocks (displacement, stress, joint states) and the disks, one frame
    # per position of the bogie (time = the bogie centre's x [m]), the first under
    # self-weight (time = -1)
    pv = out / "paraview"
    blocks_out = VTXOutput(b.model, pv, joints=b.blocks[1])
    disks_out = DiskOutput(b.disks, pv)
    blocks_out.write(-1.0)
    disks_out.write(-1.0)

    def at(br, x):
        blocks_out.write(x)
        disks_out.write(x)
        s = ", ".join(f"{v * 1e3:.2f}" for v in br.axle_settlements(ref))
        ring = br.ring_motion(ring0)
        say(f"  bogie at x = {x:g} m: equilibrium in {br.last_steps} steps; road settlement "
            f"under the axles {s} mm, the ring moved {ring * 1e3:.2f} mm "
            f"({time.perf_counter() - t0:.0f} s)", flush=True)
        if x in pictures:
            grid = stress_grid(br, args.cell)
            path = out / f"vertical_stress_{x:g}.png"
            if comm.rank == 0:
                draw_bridge_stress(br, grid, (br.disks.x, br.disks.r), path, title=(
                    f"{case.name}: bogie at x = {x:g} m, {args.load / 1e3:.0f} kN; σ_yy in "
                    "the disk fill"))
            drawn.append(path.name)
            # the blocks' σ_yy (arches, pier, soil, surfacing) with the disks, deformed
            top = float(br.slab[:, 1].max())
            name = f"blocks_stress_{x:g}.png"
            plot_blocks(br.model, out / name, field="sigma_yy", disks=br.disks,
                        loads=np.array([(xa, top) for xa, _ in br.axles]),
                        load_label=" + ".join(f"{p / 1e3:.0f}" for _, p in br.axles) + " kN",
                        title=f"bogie at x = {x:g} m: σ_yy in the blocks, the disks drawn")
            drawn.append(name)

    ref = b.model.u.x.array.copy()
    ring0 = b.ring_state()
    run = b.traverse(case.vehicle, case.positions, case.load, tol=tol,
                     max_steps=args.max_steps, callback=at)
    blocks_out.close()
    say(run.line(), flush=True)
    if comm.rank != 0:
        return
    br = case.bridge
    lines = [
        "# Two-span arch bridge with disk fill: the bogie traversing it", "",
        f"{b.disks.n} disks (radii {b.disks.r.min() * 1e3:.0f}–{b.disks.r.max() * 1e3:.0f} "
        f"mm, porosity {case.disks.porosity:g}), {b.model.blocks.n_cells} triangles; "
        f"{comm.size} rank(s), {time.perf_counter() - t0:.0f} s in all, of which "
        f"{settle_s:.0f} s settling under self-weight ({b.steps_held} + {b.steps_free} "
        f"explicit steps, ratios below {tol:g}). Spans 2 × {br.spans[0].span:g} m, pier "
        f"{br.piers[0]:g} m on {br.soil_depth:g} m of soil, cover {br.cover:g} m (surfacing "
        f"{br.surfacing:g} m). The bogie: axles at {list(case.vehicle.offsets)} m from its "
        f"centre, {case.load / 1e3:.0f} kN in all over the {br.width:g} m strip, "
        f"{case.vehicle.patch:g} m tyre patches.", "",
        f"**Status: {run.line()}**", "",
        "| bogie centre x [m] | explicit steps | settlement under each axle [mm] | "
        "ring's largest displacement [mm] | ratios (disks, blocks) |", "|---|---|---|---|---|"]
    for x, n, s, g, r in zip(run.positions, run.steps, run.settlements, run.ring, run.ratios,
                             strict=True):
        lines.append(f"| {x:g} | {n} | {', '.join(f'{v * 1e3:.2f}' for v in s)} | "
                     f"{g * 1e3:.2f} | {r[0]:.1e}, {r[1]:.1e} |")
    lines += ["", "Settlement: the surfacing's top under each tyre patch; the ring's: the "
              "largest displacement of a voussoir node; both from the state under "
              "self-weight. Pictures: " + ", ".join(drawn) + ". ParaView: paraview/model.pvd "
              "(blocks) and paraview/disks.pvd, one frame per position (time: x [m])."]
    text = "\n".join(lines) + "\n"
    (out / "traverse.md").write_text(text, encoding="utf-8")
    print(text)

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.5, 3.8))
    if run.positions:
        s = np.array(run.settlements) * 1e3
        for k, o in enumerate(case.vehicle.offsets):
            ax.plot(run.positions, s[:, k], "o-", label=f"axle {k} (centre {o:+g} m)")
    for a, c in br.springings():
        ax.axvspan(a, c, color="0.9", zorder=0)
    if run.positions:
        ax.set_xlim(min(run.positions) - 1.0, max(run.positions) + 1.0)
    ax.set_xlabel("bogie centre x [m] (spans shaded)")
    ax.set_ylabel("road settlement under the axle [mm]")
    ax.set_title(f"Disk-filled two-span bridge: {case.load / 1e3:.0f} kN bogie traversing",
                 fontsize=9)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out / "traverse.png", dpi=120)
    plt.close(fig)
    print(f"wrote {out / 'traverse.md'}, traverse.png, " + ", ".join(drawn))


if __name__ == "__main__":
    main()
