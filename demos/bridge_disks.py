"""A single-span arch bridge with its fill as disks, loaded to collapse quasi-statically
(issue #22, item 4; the reference paper's way of modelling a bridge's fill).

The case (default `cases/bridge_single_span.toml`: a 6 m segmental stone arch under 0.4 m
of fill, a 0.3 m loading beam at quarter span) with its ``[fill]`` packed by disks
instead of the Mohr–Coulomb continuum
(:class:`~masonry_fdem.assessment.disk_fill.DiskFillBridge`: the region over-packed,
settled on the held arch and trimmed to the road; the arch released and settled again;
then the beam's load in steps, each held by explicit dynamics with Cundall's local
damping until the unbalanced-force ratios of the disks and of the blocks fall below 1e-3;
a load under which the ring runs on (a voussoir moves a quarter of the ring thickness) is
a mechanism and the collapse load is the last load carried). It is the case run by ``assess`` with ``[fill]
model = "disks"`` (the options below replace the case's values); the run folder ``--out``
holds what any assessment writes (``report.md``, ``curve.csv``: load, the beam's settlement
under the live load, explicit steps per load; ``load_displacement.png``, ``summary.json``)
with ``vertical_stress.png``, σ_yy in the fill averaged from the contact forces over cells
(Love–Weber, ``cell`` wide) at the last load carried, the load's path to the arch, and
``mechanism.png``, the blocks and disks at the end of the run, to scale.

    mpirun -n 2 python demos/bridge_disks.py --out out_bridge_disks
    python demos/bridge_disks.py --position 0.4 --count 3000 --increment 20e3

The disks are held by every rank (the disk–disk forces divided among them), the blocks
distributed; two ranks give the result of one.
"""

from __future__ import annotations

import argparse
import os
from dataclasses import replace
from pathlib import Path

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # one BLAS thread per rank (see benchmarks/bridge_disks.py)

from mpi4py import MPI  # noqa: E402

from masonry_fdem.assessment.assess import assess  # noqa: E402
from masonry_fdem.assessment.case import load_case  # noqa: E402
from masonry_fdem.assessment.specs import DiskFillSpec  # noqa: E402
from masonry_fdem.constants import G  # noqa: E402
from masonry_fdem.materials import MohrCoulomb  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--case", default=str(ROOT / "cases" / "bridge_single_span.toml"))
    ap.add_argument("--out", default="out_bridge_disks")
    ap.add_argument("--position", type=float, default=None,
                    help="load position as a fraction of the span (default: the case's)")
    ap.add_argument("--count", type=int, default=None,
                    help="disks asked of the packer (default: the case's [fill.disks], 5600)")
    ap.add_argument("--increment", type=float, default=10e3,
                    help="load step [N] (10 kN; the case's is one tonne-force)")
    ap.add_argument("--max-steps", type=int, default=None,
                    help="explicit steps allowed per load (default: the case's, 600000)")
    ap.add_argument("--surfacing", type=float, default=0.0,
                    help="thickness [m] of a road layer over the disks, within the cover "
                         "(a bituminous surfacing on a granular road base, Mohr–Coulomb: "
                         "E 1 GPa, c 100 kPa, φ 35°, as cases/bridge_two_span.toml)")
    ap.add_argument("--cell", type=float, default=None,
                    help="width of the stress-averaging cells [m] (default: the case's, 0.2)")
    args = ap.parse_args()
    comm = MPI.COMM_WORLD
    say = print if comm.rank == 0 else (lambda *a, **k: None)
    case = load_case(args.case)
    if case.fill is None:
        raise SystemExit(f"{args.case}: the case has no [fill] to pack with disks")
    d = case.fill.disks or DiskFillSpec()
    given = {k: v for k, v in (("count", args.count), ("max_steps", args.max_steps),
                               ("cell", args.cell)) if v is not None}
    if args.surfacing > 0:
        given.update(surfacing=args.surfacing, surfacing_material="road")
        case = replace(case, material_table={**case.material_table, "road": MohrCoulomb(
            density=2300.0, E=1e9, nu=0.3, c=100e3, phi=35.0)})
    loading = replace(case.loading, increment=args.increment)
    if args.position is not None:
        loading = replace(loading, position=args.position)
    case = replace(case, loading=loading,
                   fill=replace(case.fill, model="disks", disks=replace(d, **given)))
    say(f"{case.name}: disk fill, load at {case.loading.position:g} of the span on a "
        f"{case.loading.spreader_width:g} m beam in {args.increment / 1e3:g} kN steps"
        + (f", on {args.surfacing:g} m of surfacing" if args.surfacing > 0 else "")
        + f"; {comm.size} rank(s)", flush=True)
    res = assess(case, out=args.out, overwrite=True, progress="lines", comm=comm)
    say(f"status: {res.status_line} ({res.status.detail})")
    cl = res.collapse_load
    if cl is not None:
        say(f"collapse load {cl / 1e3:.1f} kN ({cl / (1000 * G):.2f} t) per "
            f"{case.arch.width:g} m of barrel")
    if res.limit_load is not None:
        say(f"limit analysis with fill: {res.limit_load / 1e3:.1f} kN")
    say(f"wrote {res.report} ({res.elapsed:.0f} s)")


if __name__ == "__main__":
    main()
