"""``masonry-fdem``: the command line for the standard workflows.

Subcommands:

* ``masonry-fdem info MESH.msh`` — blocks, materials and cells of a user mesh;
* ``masonry-fdem settle MESH.msh --material brick=2000,5e9,0.2 --fix-below 0.0`` — bring
  the blocks to equilibrium under self-weight by dynamic relaxation and write the
  history CSV, ParaView files and a picture to ``--out``;
* ``masonry-fdem assess CASE.toml`` — load a masonry arch to collapse (see
  :mod:`masonry_fdem.assessment.assess`); the run folder gets a report; ``masonry-fdem example``
  prints the reference case file;
* ``masonry-fdem repair CASE.toml`` — the same arch unstrengthened and with the case's
  ``[[anchors]]``, side by side in one report, and/or a search for an efficient anchor
  layout over the case's ``[search]`` table (see :mod:`masonry_fdem.assessment.repair`);
* ``masonry-fdem precompile`` — compile the numba kernels before an MPI run.
"""

from __future__ import annotations

import argparse
import logging
import sys
from pathlib import Path

__all__ = ["main"]


def _material(text: str):
    from masonry_fdem import Material

    try:
        name, values = text.split("=", 1)
        rho, E, nu = (float(v) for v in values.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"material {text!r}: expected NAME=density,E,nu (SI units)"
        ) from None
    return name, Material(rho, E, nu)


def _read(args, comm):
    from masonry_fdem.geometry import read_msh

    return read_msh(args.mesh, blocks=args.blocks, comm=comm)


def cmd_info(args) -> int:
    from mpi4py import MPI

    blocks = _read(args, MPI.COMM_WORLD)
    if MPI.COMM_WORLD.rank == 0:
        print(f"{args.mesh}: {blocks.n_blocks} blocks, {blocks.n_cells} triangles, "
              f"{blocks.n_nodes} nodes")
        print(f"materials: {', '.join(blocks.material_names)}")
        print(f"total area: {blocks.block_area.sum():.6g} m^2")
    return 0


def cmd_settle(args) -> int:
    from mpi4py import MPI

    import numpy as np

    from masonry_fdem import Model
    from masonry_fdem.io import History, VTXOutput, plot_blocks
    from masonry_fdem.solvers import DynamicRelaxation

    comm = MPI.COMM_WORLD
    blocks = _read(args, comm)
    materials = dict(args.material or [])
    model = Model(blocks, materials, hypothesis=args.hypothesis, width=args.width, comm=comm)
    model.fix(lambda X: X[1] <= args.fix_below + 1e-9, name="base")
    model.add_gravity(live=True)
    dr = DynamicRelaxation(model, rtol=args.rtol)
    out = Path(args.out)
    with History(out / "history.csv", comm) as hist, VTXOutput(model, out) as vtx:
        for lf in np.linspace(1.0 / args.steps, 1.0, args.steps):
            res = dr.solve(lf)
            hist.append({"load_factor": lf, "iterations": res.iterations,
                         "residual": res.relative_residual,
                         "reaction": dr.reactions()["base"]})
            vtx.write(float(lf))
            if not res.converged:
                break
    plot_blocks(model, out / "settled.png", field="von_mises", scale=args.scale)
    if comm.rank == 0:
        state = "in equilibrium" if dr.results[-1].converged else "NOT in equilibrium"
        print(f"{state} after {sum(r.iterations for r in dr.results)} iterations; "
              f"outputs in {out.resolve()}")
    return 0 if dr.results[-1].converged else 1


def cmd_assess(args) -> int:
    from mpi4py import MPI

    from masonry_fdem.assessment.assess import assess
    from masonry_fdem.assessment.case import load_case
    from masonry_fdem.assessment.report import status_text

    comm = MPI.COMM_WORLD
    case = load_case(args.case)  # every problem of the file, before anything is written
    try:
        res = assess(case, out=args.out, overwrite=args.overwrite,
                     progress=False if args.quiet else None, comm=comm)
    except RuntimeError as exc:  # no equilibrium under self-weight, a folder not written
        if comm.rank == 0:
            print(f"masonry-fdem: {exc}", file=sys.stderr)
        return 1
    if comm.rank == 0:
        print(f"{case.name}: status: {status_text(res)}")
        if res.collapsed:
            line = (f"collapse load {res.collapse_load / 1e3:.2f} kN "
                    f"(resolution {res.resolution / 1e3:.2f} kN)")
        else:
            line = (f"no collapse load; lower bound {res.peak_load / 1e3:.2f} kN "
                    "(the largest load carried)")
        if res.limit_load is not None:
            line += f"; limit analysis {res.limit_load / 1e3:.2f} kN " + (
                f"(ratio {res.ratio:.3f})" if res.collapsed
                else f"(ratio >= {res.bound_ratio:.3f})")
        print(line)
        print(f"hinges at the peak load: "
              f"{', '.join(e.joint for e in res.hinges_at_collapse) or 'none'}")
        print(f"report: {res.report.resolve()}")
    return 0


def cmd_repair(args) -> int:
    from mpi4py import MPI

    from masonry_fdem.assessment.case import CaseError, load_case
    from masonry_fdem.assessment.repair import compare
    from masonry_fdem.assessment.search import SearchInterrupted, search

    comm = MPI.COMM_WORLD
    case = load_case(args.case)  # every problem of the file, before anything is written
    if not case.anchor_specs and case.search is None:
        raise CaseError("the case has neither [[anchors]] (a repair to compare with the "
                        "unstrengthened arch) nor [search] (a layout search)",
                        str(args.case))
    out = Path(args.out) if args.out is not None else case.analysis.output
    progress = False if args.quiet else None
    try:
        if case.anchor_specs:
            done = (out / "comparison" / "report.md").is_file()
            if args.resume and done:
                if comm.rank == 0:
                    print(f"comparison already done: {(out / 'comparison').resolve()}")
            else:
                res = compare(case, out=out / "comparison", overwrite=args.overwrite,
                              progress=progress, comm=comm)
                if comm.rank == 0:
                    u, a = res.unstrengthened, res.anchored
                    print(f"{case.name}: unstrengthened: {u.status_line}")
                    print(f"{case.name}: anchored: {a.status_line}")
                    print(f"gain: {res.gain_text} ({res.anchor_length:.2f} m of anchor)")
                    print(f"report: {res.report.resolve()}")
        if case.search is not None:
            def tick(info):
                if comm.rank == 0 and not args.quiet:
                    print(f"  {info['level']}: {info['done']}/{info['total']} layouts run",
                          file=sys.stderr)

            sr = search(case, out=out / "search", resume=args.resume,
                        overwrite=args.overwrite, group_size=args.group_size, comm=comm,
                        callback=tick)
            if comm.rank == 0:
                for key, why in sr.rejected:
                    print(f"rejected {key}: {why}", file=sys.stderr)
                print(f"search: unstrengthened {sr.baseline_text}; "
                      f"{len(sr.ranking)} layouts ranked, {len(sr.rejected)} rejected, "
                      f"{len(sr.pruned)} dropped as hopeless; {sr.evaluations} runs, "
                      f"{sr.reused} from the journal")
                if sr.best:
                    print(f"best: {sr.best.key}: {sr.best.load_text}, "
                          f"{sr.best.length:.2f} m of anchor, "
                          f"{sr.best.gain_per_metre / 1e3:.2f} kN per metre "
                          f"({sr.best.gain_kind})")
                if sr.target is not None:
                    ch = sr.cheapest
                    print(f"cheapest reaching {sr.target / 1e3:.2f} kN: "
                          + (f"{ch.key} ({ch.length:.2f} m)" if ch else "none"))
                print(f"report: {sr.report.resolve()}")
    except SearchInterrupted as exc:
        if comm.rank == 0:
            print(f"masonry-fdem: {exc}", file=sys.stderr)
        return 3
    except RuntimeError as exc:
        if comm.rank == 0:
            print(f"masonry-fdem: {exc}", file=sys.stderr)
        return 1
    return 0


def cmd_example(args) -> int:
    from masonry_fdem.assessment.case import EXAMPLE_CASE, REPAIR_EXAMPLE

    sys.stdout.write(REPAIR_EXAMPLE if args.repair else EXAMPLE_CASE)
    return 0


def cmd_precompile(args) -> int:
    from masonry_fdem.precompile import precompile

    precompile()
    print("numba kernels compiled")
    return 0


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="masonry-fdem", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("-v", "--verbose", action="store_true")
    sub = p.add_subparsers(dest="command", required=True)

    def mesh_args(q):
        q.add_argument("mesh", type=Path, help="Gmsh .msh file (2D)")
        q.add_argument("--blocks", choices=["physical", "components"], default="physical",
                       help="one block per physical surface or per connected component")

    q = sub.add_parser("info", help="describe a mesh")
    mesh_args(q)
    q.set_defaults(func=cmd_info)
    q = sub.add_parser("settle", help="equilibrium under self-weight (dynamic relaxation)")
    mesh_args(q)
    q.add_argument("--material", type=_material, action="append", metavar="NAME=RHO,E,NU")
    q.add_argument("--hypothesis", choices=["plane_stress", "plane_strain"],
                   default="plane_stress")
    q.add_argument("--width", type=float, default=1.0, help="out-of-plane width [m]")
    q.add_argument("--fix-below", type=float, default=0.0,
                   help="nodes with y <= this are fixed [m]")
    q.add_argument("--steps", type=int, default=5, help="load increments")
    q.add_argument("--rtol", type=float, default=1e-6)
    q.add_argument("--scale", type=float, default=100.0, help="picture magnification")
    q.add_argument("--out", default="out_settle")
    q.set_defaults(func=cmd_settle)
    q = sub.add_parser("assess", help="load an arch case to collapse; report in a run folder")
    q.add_argument("case", type=Path, help="case file (TOML; `masonry-fdem example`)")
    q.add_argument("--out", type=Path, default=None,
                   help="run folder (default: analysis.output of the case)")
    q.add_argument("--overwrite", action="store_true", help="reuse a non-empty run folder")
    q.add_argument("--quiet", action="store_true", help="no progress bar")
    q.set_defaults(func=cmd_assess)
    q = sub.add_parser("repair", help="unstrengthened against anchored, and/or an anchor "
                       "layout search ([search]); reports in a run folder")
    q.add_argument("case", type=Path, help="case file (TOML) with [[anchors]] and/or [search]")
    q.add_argument("--out", type=Path, default=None,
                   help="run folder (default: analysis.output of the case); it gets "
                        "comparison/ and search/")
    q.add_argument("--overwrite", action="store_true", help="start afresh in a used folder")
    q.add_argument("--resume", action="store_true",
                   help="go on with an interrupted search (its journal) in the folder")
    q.add_argument("--group-size", type=int, default=1,
                   help="MPI ranks per layout run of the search (default 1)")
    q.add_argument("--quiet", action="store_true", help="no progress output")
    q.set_defaults(func=cmd_repair)
    q = sub.add_parser("example", help="print the reference case file")
    q.add_argument("--repair", action="store_true",
                   help="the reference case with anchors, for `masonry-fdem repair`")
    q.set_defaults(func=cmd_example)
    q = sub.add_parser("precompile", help="compile the numba kernels")
    q.set_defaults(func=cmd_precompile)
    return p


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    logging.basicConfig(level=logging.INFO if args.verbose else logging.WARNING,
                        format="%(name)s: %(message)s")
    try:
        return args.func(args)
    except (FileNotFoundError, ValueError) as exc:
        print(f"masonry-fdem: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
