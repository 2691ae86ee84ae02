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
over the pier — and a ParaView series per position (``paraview_<x>/model.pvd``). The same
as ``masonry-fdem bridge cases/bridge_two_span.toml``
(:func:`masonry_fdem.assessment.bridge_runs.sweep_bridge`).

    mpirun -n 2 python demos/bridge_two_span.py --out out_bridge_two_span
    (make demo-bridge-collapse)
"""

from __future__ import annotations

import argparse
from pathlib import Path

from mpi4py import MPI

from masonry_fdem.assessment.bridge_case import load_bridge_case
from masonry_fdem.assessment.bridge_runs import sweep_bridge

ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
ap.add_argument("--out", default="out_bridge_two_span")
ap.add_argument("--case", default=str(Path(__file__).resolve().parents[1] / "cases" /
                                      "bridge_two_span.toml"))
ap.add_argument("--positions", type=float, nargs="*", default=None,
                help="x [m] of the vehicle's centre (default: the case's vehicle.positions)")
args = ap.parse_args()
case = load_bridge_case(args.case)
res = sweep_bridge(case, args.out, args.positions or None, comm=MPI.COMM_WORLD)
if MPI.COMM_WORLD.rank == 0:
    print(f"wrote {Path(args.out) / 'sweep.md'}, sweep.png, " + ", ".join(res.pictures)
          + ", paraview_<x>/")
