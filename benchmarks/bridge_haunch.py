"""How the loaded fill drives the loaded haunch of the single-span bridge (issue #22).

The single span's FDEM critical position is 0.1–0.15 of the span where its limit analysis
(RING's fill model) has 0.2–0.225 (docs/bridge.md). This script measures why: it runs
`cases/bridge_single_span.toml` (`assess`, one process per position) and, at the first
equilibrium under the load and at the peak, sums the forces that the fill's interface puts
on the mechanism's first block (the voussoirs from the loaded springing to the hinge near
a quarter of the span: `--voussoirs`, default 0–5 of 24) and their moment about the
springing's intrados, the point that block turns about, split into the part of the
horizontal forces (a push towards the crown, lever: the height) and of the vertical ones
(lever: the distance from the springing). RING's model loads the ring with vertical
forces only.

    python benchmarks/bridge_haunch.py --positions 0.1 0.25
    mpirun -n 2 python benchmarks/bridge_haunch.py        # the positions shared out

Units: kN, kNm per 1 m of barrel width.
"""

from __future__ import annotations

import argparse
from dataclasses import replace
from pathlib import Path

from mpi4py import MPI

import numpy as np

from masonry_fdem.assessment.assess import assess
from masonry_fdem.assessment.case import load_case

ROOT = Path(__file__).resolve().parents[1]

ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
ap.add_argument("--case", default=str(ROOT / "cases" / "bridge_single_span.toml"))
ap.add_argument("--positions", type=float, nargs="*", default=[0.1, 0.25])
ap.add_argument("--voussoirs", type=int, nargs=2, default=[0, 5],
                help="first and last voussoir of ring 0 in the block (from the left)")
args = ap.parse_args()
comm = MPI.COMM_WORLD


def haunch(model, joints, first: int, last: int, pivot: np.ndarray) -> dict:
    """The fill's forces on voussoirs first..last of ring 0: resultant and the moment
    that turns the block down and towards the crown about ``pivot`` (collective)."""
    block = [f"voussoir:0:{j}" for j in range(first, last + 1)]
    pts, f = joints.forces_on(block, by="fill")
    r = pts - pivot
    return {"F": f.sum(axis=0), "Mh": float(np.sum(f[:, 0] * r[:, 1])),
            "Mv": float(np.sum(-f[:, 1] * r[:, 0])), "points": len(pts)}


lines = []
for k in range(comm.rank, len(args.positions), comm.size):
    pos = args.positions[k]
    case = load_case(args.case)
    case = replace(case, loading=replace(case.loading, position=pos))
    pivot = np.array([-0.5 * case.arch.span, 0.0])  # the left springing's intrados
    rec: dict = {}

    def on_step(p, rec=rec, pivot=pivot) -> None:
        joints = p["interactions"][1]
        if "first" not in rec:
            rec["first"] = (p["load"], haunch(p["model"], joints, *args.voussoirs, pivot))
        if p["load"] > rec.get("peak", (-np.inf,))[0]:
            rec["peak"] = (p["load"], haunch(p["model"], joints, *args.voussoirs, pivot))

    res = assess(case, write=False, progress=False, comm=MPI.COMM_SELF, callback=on_step)
    (l0, h0), (l1, h1) = rec["first"], rec["peak"]
    dh, dv = h1["Mh"] - h0["Mh"], h1["Mv"] - h0["Mv"]
    out = [f"load at {pos:g} of the span: {res.status_line}"]
    for name, load, h in (("first step", l0, h0), ("peak", l1, h1)):
        out.append(f"  {name} ({load / 1e3:.1f} kN): fill on voussoirs "
                   f"{args.voussoirs[0]}-{args.voussoirs[1]}: Fx {h['F'][0] / 1e3:.1f} kN, "
                   f"Fy {h['F'][1] / 1e3:.1f} kN; moment about the springing from the "
                   f"horizontal forces {h['Mh'] / 1e3:.1f} kNm, from the vertical "
                   f"{h['Mv'] / 1e3:.1f} kNm ({h['points']} points)")
    out.append(f"  from the first step to the peak: horizontal {dh / 1e3:+.1f} kNm, vertical "
               f"{dv / 1e3:+.1f} kNm; the horizontal forces' share "
               f"{dh / (dh + dv):.2f}" if dh + dv else "  no change")
    lines.append((pos, out))
lines = sorted((x for part in comm.allgather(lines) for x in part), key=lambda t: t[0])
if comm.rank == 0:
    for _, out in lines:
        print("\n".join(out))
