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

The same as ``masonry-fdem bridge`` on the case with ``[bridge] fill_model = "disks"``
(:func:`masonry_fdem.assessment.bridge_runs.traverse_bridge`). The disks are held by
every rank (their forces divided among the ranks), the blocks
distributed; two ranks give the result of one.
"""

from __future__ import annotations

import argparse
import os
import tomllib
from pathlib import Path

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # one BLAS thread per rank

from mpi4py import MPI  # noqa: E402

from masonry_fdem.assessment.bridge_case import load_bridge_case  # noqa: E402
from masonry_fdem.assessment.bridge_runs import traverse_bridge  # noqa: E402

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
    data = tomllib.loads(Path(args.case).read_text(encoding="utf-8"))
    data["bridge"]["fill_model"] = "disks"
    data["bridge"]["disks"] = {"count": args.count}
    data["bridge"]["mesh"].pop("crossed", None)
    data["vehicle"]["load"] = args.load
    data["vehicle"]["positions"] = list(args.positions)
    case = load_bridge_case(data, name=Path(args.case).stem + " (disk fill)")
    try:
        traverse_bridge(case, args.out, pictures=args.pictures, cell=args.cell,
                        max_steps=args.max_steps, comm=MPI.COMM_WORLD)
    except RuntimeError as exc:
        raise SystemExit(str(exc)) from None


if __name__ == "__main__":
    main()
