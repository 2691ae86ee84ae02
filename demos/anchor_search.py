"""A small anchor layout search: where should one or two stitching anchors go?

The arch: span 2 m, one ring of 0.2 m in 12 voussoirs, dry joints (the arch of
``tests/test_assess.py``, rigid-block limit load 5.1 kN), loaded at quarter span and
traced by the Newton solver (the default ``analysis.solver``: arc length on the
load-line displacement) to its peak and past it, up to 3 mm of load-line displacement
(about eight times where the unstrengthened arch peaks); a run whose load has fallen 5 %
below its peak by then (``post_peak_drop = 0.05``) ends *peak passed* and gives a
collapse load. The candidates: one or two straight anchors (16 mm bars) drilled from the
intrados at six positions, leaning 20 deg to the intrados tangent towards either
springing (42 layouts), and two bad ones, rejected with the reason before anything runs:
an anchor too long for the ring, and two anchors 34 mm apart.
Objective: the largest gain of collapse load per metre of anchor. Each layout is run
short first (coarse: the same path cut short at four times the displacement where the
unstrengthened arch peaked), the best six in full. Every ranked layout carries its run's
status; one whose run ends without passing its peak is shown as a lower bound (">=") and
ranks after every measured collapse load. The two ranks run two layouts at a time; the
journal lets an interrupted search resume (``--resume``).

Then the throughput on the reference three-ring arch of ``masonry-fdem example``
(:data:`masonry_fdem.assessment.case.EXAMPLE_CASE`: span 3 m, three 0.11 m brick rings,
sand between them): the unstrengthened arch and three single inclined anchors (30 deg,
through the rings) traced to past their peaks by the same search, two side by side;
prints each run's status and time, the median time per layout and the layouts assessed
per hour on these ranks.

    mpirun -n 2 python demos/anchor_search.py --out out_anchor_search   (under a minute)
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
import tomllib
from pathlib import Path

from mpi4py import MPI

from masonry_fdem.assessment.case import EXAMPLE_CASE, AnchorLayout, SearchSpec, load_case
from masonry_fdem.assessment.repair import BASELINE
from masonry_fdem.assessment.search import search

ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
ap.add_argument("--out", default="out_anchor_search")
ap.add_argument("--resume", action="store_true")
args = ap.parse_args()
comm = MPI.COMM_WORLD
out = Path(args.out)

case = load_case({
    "arch": {"span": 2.0, "ring_thickness": 0.2, "voussoirs": 12, "abutment_height": 0.3,
             "abutment_width": 0.4, "mesh_size": 0.2},
    "materials": {"brick": {"density": 2000.0, "E": 10e9, "nu": 0.2},
                  "abutment": {"density": 2000.0, "E": 30e9, "nu": 0.2}},
    "joints": {"mortar": {"tan_phi": 10.0}},
    "loading": {"position": 0.25, "displacement_increment": 1e-4, "max_displacement": 3e-3},
    "analysis": {"penalty_factor": 10.0, "post_peak_drop": 0.05, "limit_analysis": False},
}, name="dry_arch")
space = SearchSpec(positions=(0.1, 0.25, 0.36, 0.5, 0.7, 0.85), counts=(1, 2),
                   inclinations=(20.0, 160.0), diameter=0.016, keep=6, keep_ratio=0.3,
                   layouts=(AnchorLayout((0.4,), 30.0, 1.0),
                            AnchorLayout((0.15, 0.17), 30.0)))
t0 = time.perf_counter()
res = search(case, space, out=out, resume=args.resume, overwrite=not args.resume,
             comm=comm)
if comm.rank == 0:
    print(f"dry one-ring arch ({case.analysis.solver} solver): unstrengthened "
          f"{res.baseline_text}; {len(space.candidates())} layouts: {len(res.rejected)} "
          f"rejected, {len(res.pruned)} dropped after the coarse runs, {len(res.ranking)} "
          "run in full")
    for r in res.ranking:
        print(f"  {r.rank}. {r.key}: {r.load_text} ({r.gain / 1e3:+.2f} kN, gain "
              f"{r.gain_kind}), {r.length:.2f} m, {r.gain_per_metre / 1e3:.2f} kN/m "
              f"[{r.status}]")
    bounds = [r for r in res.ranking if not r.collapsed]
    print(f"  {len(res.ranking) - len(bounds)} collapse loads measured, {len(bounds)} "
          "lower bounds (ranked after them)")
    for key, why in res.rejected[:3]:
        print(f"  rejected {key}: {why}")
    print(f"  {res.evaluations} runs in {time.perf_counter() - t0:.0f} s "
          f"({res.reused} from the journal); report: {res.report.resolve()}")

# ---- throughput: the reference three-ring arch, each layout traced to past its peak
ref = load_case(tomllib.loads(EXAMPLE_CASE), name="reference_arch")
ref_space = SearchSpec(positions=(0.15, 0.25, 0.35), counts=(1,), inclinations=(30.0,),
                       diameter=0.016, coarse=False)
t1 = time.perf_counter()
rres = search(ref, ref_space, out=out / "reference_arch", resume=args.resume,
              overwrite=not args.resume, comm=comm)
wall = time.perf_counter() - t1
if comm.rank == 0:
    rows = [json.loads(line) for line in
            (out / "reference_arch" / "journal.jsonl").read_text().splitlines()]
    print(f"reference three-ring arch ({ref.analysis.solver} solver; {comm.size} layouts "
          f"at a time, one rank each):")
    for row in rows:
        what = "unstrengthened" if row["key"] == BASELINE else row["key"]
        print(f"  {what}: {row['status']}, {row['peak_load'] / 1e3:.2f} kN at "
              f"{row['peak_displacement'] * 1e3:.2f} mm, {row['steps']} steps, "
              f"{row['elapsed']:.1f} s")
    times = [row["elapsed"] for row in rows if row["key"] != BASELINE]
    peaks = sum(row["status"] == "peak passed" for row in rows)
    rate = (f"{len(rows)} runs ({peaks} to peak passed) in {wall:.0f} s: "
            f"{3600.0 * len(rows) / wall:.0f} layouts assessed per hour to the peak on "
            f"{comm.size} ranks" if not rres.reused else
            f"{rres.reused} runs from the journal (no wall time measured)")
    print(f"  {statistics.median(times):.1f} s median, {statistics.mean(times):.1f} s mean "
          f"per anchored layout on one rank; {rate}")
