"""masonry-fdem: the command line for the standard workflows.

Subcommands:

  info MESH.msh         blocks, materials and cells of a user mesh
  settle MESH.msh       bring the blocks to equilibrium under self-weight by dynamic
                        relaxation, with contact between the blocks and bonded joints
                        where the mesh has named interface lines (--joint); writes the
                        history CSV, ParaView files and a picture to --out
  assess CASE.toml      load a masonry arch to collapse; the run folder gets a report
  repair CASE.toml      the same arch unstrengthened and with the case's [[anchors]],
                        side by side in one report, and/or a search for an efficient
                        anchor layout over the case's [search] table
  bridge CASE.toml      a bridge case ([bridge]): with a continuum fill, the vehicle
                        loaded to collapse at each position (the critical one); with a
                        disk fill, the vehicle driven across at its load
  example               print the reference case file
  precompile            compile the numba kernels before an MPI run

Every subcommand takes -v (more messages, -vv for debugging) and -q (no progress
output, warnings and errors only). Units are SI (m, N, Pa, kg/m^3) unless an option
says otherwise. Run "masonry-fdem SUBCOMMAND --help" for the options of one subcommand.
"""

from __future__ import annotations

import argparse
import logging
import math
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
    try:
        return name, Material(rho, E, nu)
    except ValueError as exc:  # out of range or implausible: say which constant
        raise argparse.ArgumentTypeError(f"material {text!r}: {exc}") from None


def _joint(text: str):
    from dataclasses import fields

    from masonry_fdem.interactions import JointMaterial

    name, _, values = text.partition(":")
    known = {f.name for f in fields(JointMaterial)}
    kw = {}
    try:
        if not name or not values:
            raise ValueError
        if values.strip() != "dry":
            for item in values.split(","):
                key, value = item.split("=", 1)
                key = key.strip()
                if key not in known:
                    raise argparse.ArgumentTypeError(
                        f"joint {text!r}: unknown property {key!r} (known: "
                        f"{', '.join(sorted(known))})")
                kw[key] = float(value)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"joint {text!r}: expected GROUP:key=value,... (JointMaterial properties in SI "
            "units, e.g. bed:ft=1e5,GfI=10,c=1.5e5,GfII=50,tan_phi=0.75) or GROUP:dry"
        ) from None
    try:
        return name, (JointMaterial(**kw) if kw else None)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(f"joint {text!r}: {exc}") from None


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
    import math

    from mpi4py import MPI

    import numpy as np

    from masonry_fdem import Model
    from masonry_fdem.geometry import interface_rules, read_msh_lines
    from masonry_fdem.interactions import BlockContact, ContactSettings, Joints
    from masonry_fdem.io import History, ProgressBar, VTXOutput, plot_blocks
    from masonry_fdem.solvers import DynamicRelaxation

    comm = MPI.COMM_WORLD
    blocks = _read(args, comm)
    materials = dict(args.material or [])
    missing = sorted(set(blocks.material_names) - set(materials))
    if missing:
        raise ValueError(f"{args.mesh}: no --material for {missing} (materials of the mesh: "
                         f"{', '.join(blocks.material_names)})")
    model = Model(blocks, materials, hypothesis=args.hypothesis, width=args.width, comm=comm)
    model.fix(lambda X: X[1] <= args.fix_below + 1e-9, name="base")
    model.add_gravity(live=True)
    # blocks rest on each other and on the fixed base through contact (Coulomb friction);
    # interfaces on the mesh's physical line groups named by --joint get those joints
    contact = BlockContact(model, ContactSettings(friction=args.friction))
    inter = [contact]
    joints = None
    if args.joint:
        lines = read_msh_lines(args.mesh, comm=comm)
        names = blocks.material_names
        dry = {(a, b): None for a in names for b in names}
        joints = Joints(model, dry, where=interface_rules(lines, dict(args.joint)),
                        contact=contact)
        inter.append(joints)
    dr = DynamicRelaxation(model, interactions=inter, rtol=args.rtol, ke_tol=math.inf,
                           max_iter=args.max_iterations, damping="velocity")
    out = Path(args.out)
    bar = ProgressBar("settle", comm=comm) if args.verbosity >= 0 else None
    with History(out / "history.csv", comm) as hist, VTXOutput(model, out, joints=joints) as vtx:
        for lf in np.linspace(1.0 / args.steps, 1.0, args.steps):
            res = dr.solve(lf)
            hist.append({"load_factor": lf, "iterations": res.iterations,
                         "residual": res.relative_residual,
                         "reaction": dr.reactions()["base"]})
            vtx.write(float(lf))
            if bar is not None:
                bar.increment(load=f"{lf:.2f} x self-weight", iterations=res.iterations)
            if not res.converged:
                break
    if bar is not None:
        bar.close()
    plot_blocks(model, out / "settled.png", field="von_mises", scale=args.scale,
                joints=joints, title=f"{Path(args.mesh).name} under self-weight "
                                     f"(displacements ×{args.scale:g})")
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
    from masonry_fdem.io.checkpoint import (
        EXIT_INTERRUPTED,
        CheckpointError,
        Interrupted,
        read_manifest,
        stop_on_signals,
    )

    comm = MPI.COMM_WORLD
    out = args.out
    if args.resume is not None:
        if args.case is not None or out is not None:
            raise ValueError("--resume RUN_DIR takes the case and the folder from the run")
        out = args.resume
        manifest, error = None, None
        if comm.rank == 0:
            try:
                manifest = read_manifest(out)
            except CheckpointError as exc:
                error = str(exc)
        manifest, error = comm.bcast((manifest, error), root=0)
        if error:
            if comm.rank == 0:
                print(f"masonry-fdem: {error}", file=sys.stderr)
            return 1
        if not manifest.get("case_file"):
            raise ValueError(f"the run in {out} did not come from a case file")
        args.case = Path(manifest["case_file"])
    elif args.case is None:
        raise ValueError("give a case file, or --resume RUN_DIR")
    case = load_case(args.case)  # every problem of the file, before anything is written
    try:
        with stop_on_signals():
            res = assess(case, out=out, overwrite=args.overwrite,
                         progress=_progress(args), comm=comm,
                         resume=args.resume is not None)
    except Interrupted as exc:
        if comm.rank == 0:
            print(f"\nmasonry-fdem: {exc}", file=sys.stderr)
        return EXIT_INTERRUPTED
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
        disks = case.fill is not None and case.fill.model == "disks"
        print(f"hinges {'at the end of the run' if disks else 'at the peak load'}: "
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
    progress = False if args.verbosity < 0 else None
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
                if comm.rank == 0 and args.verbosity >= 0:
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


def cmd_bridge(args) -> int:
    from mpi4py import MPI

    from masonry_fdem.assessment.bridge_case import load_bridge_case
    from masonry_fdem.assessment.bridge_runs import (
        collapse_bridge,
        sweep_bridge,
        traverse_bridge,
    )

    comm = MPI.COMM_WORLD
    case = load_bridge_case(args.case)  # every problem of the file, before any run
    out = args.out if args.out is not None else Path(f"out_{case.name}")
    quiet = args.verbosity < 0
    if args.collapse and case.fill_model != "disks":
        raise ValueError("--collapse: the continuum fill is always loaded to collapse (the "
                         "option is for a disk fill)")
    if (args.increment is not None or args.max_load is not None) and not args.collapse:
        raise ValueError("--increment and --max-load go with --collapse (a disk fill)")
    if args.collapse:
        if args.increment is None:
            raise ValueError("--collapse: give the load step, --increment N (the vehicle's "
                             "total, over the bridge's width)")
        if args.pictures is not None:
            raise ValueError("--pictures: with --collapse the fill of every position is "
                             "pictured at its last load carried")
        try:
            runs = collapse_bridge(case, out, args.increment, args.positions or None,
                                   max_load=args.max_load or math.inf, cell=args.cell,
                                   max_steps=args.max_steps, comm=comm, quiet=quiet)
        except RuntimeError as exc:  # a fill that did not settle
            if comm.rank == 0:
                print(f"masonry-fdem: {exc}", file=sys.stderr)
            return 1
        if comm.rank == 0:
            for x, r in zip(args.positions or case.positions, runs, strict=True):
                print(f"{case.name}: vehicle at x = {x:g} m: {r.line()}")
            print(f"report: {(Path(out) / 'collapse.md').resolve()}")
        return 0
    if case.fill_model == "disks":
        if args.positions:
            raise ValueError("--positions: a disk fill is traversed through the case's "
                             "vehicle.positions (edit the case), or loaded to collapse at "
                             "them with --collapse")
        try:
            run = traverse_bridge(case, out, pictures=args.pictures, cell=args.cell,
                                  max_steps=args.max_steps, comm=comm, quiet=quiet)
        except RuntimeError as exc:  # the fill did not settle: nothing to traverse
            if comm.rank == 0:
                print(f"masonry-fdem: {exc}", file=sys.stderr)
            return 1
        if comm.rank == 0:
            print(f"{case.name}: status: {run.line()}")
            print(f"report: {(Path(out) / 'traverse.md').resolve()}")
        return 0
    if args.pictures is not None:
        raise ValueError("--pictures: a continuum fill's sweep pictures the critical "
                         "position and the one nearest the pier")
    res = sweep_bridge(case, out, args.positions or None,
                       paraview_every=args.paraview_every, comm=comm, quiet=quiet)
    if comm.rank == 0:
        c = res.critical
        if c is None:
            print(f"{case.name}: no run proved a collapse load (lower bounds only)")
        else:
            print(f"{case.name}: critical position x = {c['x']:g} m, collapse load "
                  f"{c['load'] / 1e3:.1f} kN")
        print(f"report: {(Path(out) / 'sweep.md').resolve()}")
    return 0


def _progress(args):
    """Progress of `assess`: none with -q; a bar when stdout is a terminal; otherwise one
    line per increment on stdout (a log, a pipe, a batch job)."""
    if args.verbosity < 0:
        return False
    return "bar" if sys.stdout.isatty() else "lines"


def cmd_example(args) -> int:
    from masonry_fdem.assessment.case import EXAMPLE_CASE, REPAIR_EXAMPLE

    sys.stdout.write(REPAIR_EXAMPLE if args.repair else EXAMPLE_CASE)
    return 0


def cmd_precompile(args) -> int:
    from masonry_fdem.precompile import precompile

    precompile()
    print("numba kernels compiled")
    return 0


def _version() -> str:
    try:
        from importlib.metadata import PackageNotFoundError, version

        return version("masonry_fdem")
    except (ImportError, PackageNotFoundError):
        from masonry_fdem import __version__

        return __version__


_VERBOSITY_EPILOG = ("-v: more messages (-vv: debugging); -q: no progress output, "
                     "warnings and errors only.")


def _verbosity_args(q: argparse.ArgumentParser, main: bool) -> None:
    """-v/-q; on a subcommand they default to "not given" so the main parser's stay."""
    default = 0 if main else argparse.SUPPRESS
    g = q.add_argument_group("output")
    g.add_argument("-v", "--verbose", action="count", default=default,
                   help="more messages: -v informs of each stage, -vv debugs")
    g.add_argument("-q", "--quiet", action="store_true", default=False if main else
                   argparse.SUPPRESS,
                   help="no progress bar or progress lines; only warnings and errors")


def _sub(sub, name: str, help: str, description: str) -> argparse.ArgumentParser:
    q = sub.add_parser(name, help=help, description=description, epilog=_VERBOSITY_EPILOG,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    _verbosity_args(q, main=False)
    return q


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="masonry-fdem", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--version", action="version", version=f"%(prog)s {_version()}",
                   help="print the version of masonry_fdem and exit")
    _verbosity_args(p, main=True)
    sub = p.add_subparsers(dest="command", required=True, metavar="SUBCOMMAND")

    def mesh_args(q):
        q.add_argument("mesh", type=Path, help="Gmsh .msh file (2D)")
        q.add_argument("--blocks", choices=["physical", "components"], default="physical",
                       help="one block per physical surface or per connected component")

    q = _sub(sub, "info", "describe a mesh",
             "Print the blocks, materials, cells and area of a Gmsh mesh (.msh) as\n"
             "masonry_fdem reads it.")
    mesh_args(q)
    q.set_defaults(func=cmd_info)
    q = _sub(sub, "settle", "equilibrium under self-weight (dynamic relaxation)",
             "Bring the blocks of a Gmsh mesh to equilibrium under their self-weight by\n"
             "dynamic relaxation in load increments. The nodes at or below --fix-below are\n"
             "fixed (the base); the blocks rest on each other and on the base through\n"
             "frictional contact. Interfaces on a physical line group (1D) of the mesh get\n"
             "the joint material given for that group with --joint; the other interfaces\n"
             "are dry contact. Writes history.csv, ParaView files (.bp, and .vtu with a\n"
             ".pvd collection) and settled.png to --out.")
    mesh_args(q)
    q.add_argument("--material", type=_material, action="append", metavar="NAME=RHO,E,NU",
                   help="a block material: density [kg/m^3], Young's modulus [Pa], "
                        "Poisson's ratio (repeat for each material of the mesh)")
    q.add_argument("--joint", type=_joint, action="append", metavar="GROUP:KEY=VALUE,...",
                   help="the joint material of the interfaces on the physical line group "
                        "GROUP: JointMaterial properties in SI units, e.g. "
                        "bed:ft=1e5,GfI=10,c=1.5e5,GfII=50,tan_phi=0.75; GROUP:dry for "
                        "contact only (repeat for each group)")
    q.add_argument("--friction", type=float, default=0.6,
                   help="Coulomb friction coefficient of the contact between blocks "
                        "(default 0.6)")
    q.add_argument("--hypothesis", choices=["plane_stress", "plane_strain"],
                   default="plane_stress")
    q.add_argument("--width", type=float, default=1.0, help="out-of-plane width [m]")
    q.add_argument("--fix-below", type=float, default=0.0,
                   help="nodes with y <= this are fixed [m] (default 0)")
    q.add_argument("--steps", type=int, default=5, help="load increments (default 5)")
    q.add_argument("--rtol", type=float, default=1e-6,
                   help="out-of-balance force tolerance, relative (default 1e-6)")
    q.add_argument("--max-iterations", type=int, default=200_000,
                   help="dynamic relaxation iterations per increment (default 200000)")
    q.add_argument("--scale", type=float, default=100.0,
                   help="displacement magnification of the picture (default 100)")
    q.add_argument("--out", default="out_settle", help="output folder (default out_settle)")
    q.set_defaults(func=cmd_settle)
    q = _sub(sub, "assess", "load an arch case to collapse; report in a run folder",
             "Load the masonry arch of a case file (TOML) to collapse and write a run\n"
             "folder with the report, the load-displacement curve, pictures and ParaView\n"
             "files. The case file format: masonry-fdem example.\n\n"
             "Progress: on a terminal, a bar that counts the load increments with the load\n"
             "[kN] and the load-line displacement [mm]; when stdout is not a terminal (a\n"
             "log file, a pipe), one line per increment: load factor (the load over the\n"
             "limit-analysis load, - without limit analysis), load [kN], displacement\n"
             "[mm], dynamic relaxation or Newton iterations, status.\n\n"
             "Ctrl-C or SIGTERM stops the run at the next converged increment with a\n"
             "checkpoint in the run folder (exit status 130); --resume RUN_DIR goes on\n"
             "from it and ends as the run would have (docs/checkpoint.md).")
    q.add_argument("case", type=Path, nargs="?",
                   help="case file (TOML; masonry-fdem example); not with --resume")
    q.add_argument("--out", type=Path, default=None,
                   help="run folder (default: analysis.output of the case)")
    q.add_argument("--overwrite", action="store_true", help="reuse a non-empty run folder")
    q.add_argument("--resume", type=Path, default=None, metavar="RUN_DIR",
                   help="go on with a run stopped by Ctrl-C or SIGTERM, from its checkpoint")
    q.set_defaults(func=cmd_assess)
    q = _sub(sub, "repair", "unstrengthened against anchored, and/or an anchor "
             "layout search ([search]); reports in a run folder",
             "Assess the arch of a case file unstrengthened and with its [[anchors]], side\n"
             "by side in one report (comparison/), and/or search for an efficient anchor\n"
             "layout over the case's [search] table (search/). The case file format:\n"
             "masonry-fdem example --repair.")
    q.add_argument("case", type=Path, help="case file (TOML) with [[anchors]] and/or [search]")
    q.add_argument("--out", type=Path, default=None,
                   help="run folder (default: analysis.output of the case); it gets "
                        "comparison/ and search/")
    q.add_argument("--overwrite", action="store_true", help="start afresh in a used folder")
    q.add_argument("--resume", action="store_true",
                   help="go on with an interrupted search (its journal) in the folder")
    q.add_argument("--group-size", type=int, default=1,
                   help="MPI ranks per layout run of the search (default 1)")
    q.set_defaults(func=cmd_repair)
    q = _sub(sub, "bridge", "a bridge case: collapse load against the vehicle's "
             "position, or a traverse over disk fill",
             "Run a bridge case file (TOML with [bridge], [[bridge.spans]], [vehicle];\n"
             "cases/bridge_two_span.toml). With [bridge] fill_model = \"continuum\" (the\n"
             "default) the vehicle is loaded to collapse at each of its positions, one\n"
             "rank per position under mpirun: sweep.md (the collapse load per position and\n"
             "the critical one), sweep.png, the vertical stress and the mechanism at the\n"
             "critical position and over the pier, a ParaView series per position. With\n"
             "fill_model = \"disks\" the disk fill is settled under self-weight and the\n"
             "vehicle driven across at [vehicle] load, equilibrium at each position:\n"
             "traverse.md, traverse.png, stress pictures for two positions, ParaView;\n"
             "with --collapse its load is raised at each position to collapse instead:\n"
             "collapse.md, collapse.png, the fill's stress at each.")
    q.add_argument("case", type=Path, help="bridge case file (TOML)")
    q.add_argument("--out", type=Path, default=None,
                   help="output folder (default out_<case name>)")
    q.add_argument("--positions", type=float, nargs="+", default=None, metavar="X",
                   help="continuum fill, or disk fill with --collapse: the vehicle's "
                        "positions x [m] (default: the case's vehicle.positions)")
    q.add_argument("--pictures", type=float, nargs="+", default=None, metavar="X",
                   help="disk fill: positions [m] whose stress is pictured (default: the "
                        "first and the one nearest the pier)")
    q.add_argument("--cell", type=float, default=0.25,
                   help="disk fill: width [m] of the stress-averaging cells (default 0.25)")
    q.add_argument("--collapse", action="store_true",
                   help="disk fill: load the vehicle to collapse at each position (a "
                        "fresh bridge settled for each) instead of driving it across")
    q.add_argument("--increment", type=float, default=None, metavar="N",
                   help="with --collapse: the load step [N] of the vehicle's total")
    q.add_argument("--max-load", type=float, default=None, metavar="N",
                   help="with --collapse: stop once this load [N] is carried")
    q.add_argument("--max-steps", type=int, default=300_000,
                   help="disk fill: explicit steps allowed to settle and per position or "
                        "load (default 300000)")
    q.add_argument("--paraview-every", type=int, default=5,
                   help="continuum fill: a ParaView frame every this many increments "
                        "(default 5; 0: none)")
    q.set_defaults(func=cmd_bridge)
    q = _sub(sub, "example", "print the reference case file",
             "Print the reference case file (TOML) of an arch assessment, with every key\n"
             "explained, to start a case from: masonry-fdem example > case.toml")
    q.add_argument("--repair", action="store_true",
                   help="the reference case with anchors, for masonry-fdem repair")
    q.set_defaults(func=cmd_example)
    q = _sub(sub, "precompile", "compile the numba kernels",
             "Compile (and cache) the numba kernels once, so that the ranks of an MPI run\n"
             "do not all compile them at the same time.")
    q.set_defaults(func=cmd_precompile)
    return p


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    args.verbosity = -1 if args.quiet else int(args.verbose)
    level = {-1: logging.WARNING, 0: logging.WARNING, 1: logging.INFO}.get(
        args.verbosity, logging.DEBUG)
    logging.basicConfig(level=level, format="%(name)s: %(message)s")
    try:
        return args.func(args)
    except (FileNotFoundError, ValueError) as exc:
        print(f"masonry-fdem: error: {exc}", file=sys.stderr)
        return 2
    except ArithmeticError as exc:  # a raw NaN/overflow a solver did not explain
        print(f"masonry-fdem: error: numerical failure ({exc}); check the magnitudes of the "
              "input (E, density, lengths in m, loads in N)", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
