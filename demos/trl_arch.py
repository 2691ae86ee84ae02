"""The TRL three-ring arch (issue #21): unstrengthened against anchored, beside the test.

The case `cases/trl_arch.toml` (5 m segmental span, rise span/4, three half-brick rings
with wet sand between them, every radial joint modelled, load at quarter span through a
spreader, eleven rows of radial grouted anchors; every value with its source in the case
file, `docs/trl.md` for what it assumes and lacks) run twice, one rank each under
`mpirun -n 2`: as it is (anchored) and without its anchors. Prints each run's status
with its load in tonnes beside the test's 20 t and 41 t, the ratio when both runs proved
a collapse load (else says there is none), the anchored arch's first hinge against its
largest load, and the anchors' largest forces against yield; the report with curves,
mechanisms and anchor plots goes to the run folder.

    mpirun -n 2 python demos/trl_arch.py --out out_trl            # full case (make demo-trl)
    mpirun -n 2 python demos/trl_arch.py --coarse --out out_trl   # (make demo)

``--coarse``: a radial joint every other brick (half the courses of each ring) and the
coarsest mesh, a few minutes on two cores; the same case otherwise.
"""

from __future__ import annotations

import argparse
import time
from dataclasses import replace
from pathlib import Path

from mpi4py import MPI

from masonry_fdem.assessment.case import load_case
from masonry_fdem.assessment.repair import compare

TONNE = 9806.65  # [N]
TEST = {"unstrengthened": 20.0, "anchored": 41.0}  # [t] (Owen et al., TRL tests)
ROOT = Path(__file__).resolve().parents[1]

ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
ap.add_argument("--out", default="out_trl")
ap.add_argument("--coarse", action="store_true",
                help="a radial joint every other brick, coarsest mesh (minutes)")
args = ap.parse_args()
comm = MPI.COMM_WORLD
case = load_case(ROOT / "cases" / "trl_arch.toml")
if args.coarse:
    arch = case.arch
    case = replace(case, arch=replace(arch, voussoirs=tuple((n + 1) // 2 for n in arch.voussoirs),
                                      mesh_size=2 * arch.ring_thickness))
t0 = time.perf_counter()
res = compare(case, out=Path(args.out), overwrite=True, progress=True, comm=comm)
if comm.rank == 0:
    u, a = res.unstrengthened, res.anchored
    print(f"TRL three-ring arch{' (coarse)' if args.coarse else ''}: voussoirs "
          f"{list(case.arch.voussoirs)}, {u.cells} triangles")
    for name, r in (("unstrengthened", u), ("anchored", a)):
        print(f"  {name:15s} {r.status_line}: {r.peak_load / TONNE:.2f} t "
              f"(test: {TEST[name]:.0f} t)")
    cu, ca = u.collapse_load, a.collapse_load
    if cu is not None and ca is not None:
        print(f"  ratio anchored/unstrengthened {ca / cu:.2f} (test: 2.05)")
    else:
        which = [n for n, c in (("unstrengthened", cu), ("anchored", ca)) if c is None]
        print(f"  no ratio: the {' and '.join(which)} run proved no collapse load "
              f"(its load is a lower bound); the test's ratio is 2.05")
    if a.events:
        e = a.events[0]
        print(f"  anchored: first hinge {e.joint} ({e.kind}) at {e.load / 1e3:.1f} kN = "
              f"{e.load / a.peak_load:.2f} of its largest load (test: 28 t/41 t = 0.68)")
    if a.anchor_peaks:
        top = max(a.anchor_peaks, key=lambda x: x["force_max"])
        print(f"  largest bar force over the anchored run: {top['name']} "
              f"{top['force_max'] / 1e3:.2f} kN, {100 * top['force_max'] / top['yield_force']:.0f} %"
              f" of yield")
    print(f"  {time.perf_counter() - t0:.0f} s; report: {res.report.resolve()}")
