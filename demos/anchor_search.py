"""A small anchor layout search: where should one or two stitching anchors go?

The arch: span 2 m, one ring of 0.2 m in 12 voussoirs, dry joints (the arch of
``tests/test_assess.py``, rigid-block limit load 5.1 kN), a platen at quarter span driven
down in 0.1 mm steps to 0.3 mm. The candidates: one or two straight anchors (16 mm bars)
drilled from the intrados at six positions, leaning 20 deg to the intrados tangent towards
either springing (42 layouts), and two bad ones, rejected with the reason before anything
runs: an anchor too long for the ring, and two anchors 34 mm apart.
Objective: the largest gain of collapse load per metre of anchor. Each layout is run
short first (coarse: to 0.15 mm), the best six in full. The two ranks run two layouts at
a time; the journal lets an interrupted search resume (``--resume``).

    mpirun -n 2 python demos/anchor_search.py --out out_anchor_search   (about 2 min)
"""

from __future__ import annotations

import argparse
import time

from mpi4py import MPI

from masonry_fdem.assessment.case import AnchorLayout, SearchSpec, load_case
from masonry_fdem.assessment.search import search

ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
ap.add_argument("--out", default="out_anchor_search")
ap.add_argument("--resume", action="store_true")
args = ap.parse_args()
comm = MPI.COMM_WORLD

case = load_case({
    "arch": {"span": 2.0, "ring_thickness": 0.2, "voussoirs": 12, "abutment_height": 0.3,
             "abutment_width": 0.4, "mesh_size": 0.2},
    "materials": {"brick": {"density": 2000.0, "E": 10e9, "nu": 0.2},
                  "abutment": {"density": 2000.0, "E": 30e9, "nu": 0.2}},
    "joints": {"mortar": {"tan_phi": 10.0}},
    "loading": {"position": 0.25, "control": "displacement", "displacement_increment": 1e-4,
                "max_displacement": 3e-4},
    "analysis": {"solver": "dr", "dr_rtol": 1e-3, "max_iterations": 25000,
                 "penalty_factor": 10.0, "post_peak_steps": 1, "limit_analysis": False},
}, name="dry_arch")
space = SearchSpec(positions=(0.1, 0.25, 0.36, 0.5, 0.7, 0.85), counts=(1, 2),
                   inclinations=(20.0, 160.0), diameter=0.016, keep=6, keep_ratio=0.3,
                   layouts=(AnchorLayout((0.4,), 30.0, 1.0),
                            AnchorLayout((0.15, 0.17), 30.0)))
t0 = time.perf_counter()
res = search(case, space, out=args.out, resume=args.resume, overwrite=not args.resume,
             comm=comm)
if comm.rank == 0:
    print(f"dry one-ring arch: unstrengthened {res.baseline_text}; "
          f"{len(space.candidates())} layouts: {len(res.rejected)} rejected, "
          f"{len(res.pruned)} dropped after the coarse runs, {len(res.ranking)} run in full")
    for r in res.ranking[:5]:
        print(f"  {r.rank}. {r.key}: {r.load_text} ({r.gain / 1e3:+.2f} kN, gain "
              f"{r.gain_kind}), {r.length:.2f} m, {r.gain_per_metre / 1e3:.2f} kN/m")
    for key, why in res.rejected[:3]:
        print(f"  rejected {key}: {why}")
    print(f"  {res.evaluations} runs in {time.perf_counter() - t0:.0f} s "
          f"({res.reused} from the journal); report: {res.report.resolve()}")
