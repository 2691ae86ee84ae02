"""The explicit step at scale, phase by phase, on one rank and on all: speed-up and
parallel efficiency of the contact phase (the reference paper's Figure 5) and of the
full step.

Model: a running-bond brick wall (215 x 65 mm bricks, 102.5 mm thick) on a fixed base,
its lower half laid in mortar (cohesive joints), its upper half dry (frictional contact
between every brick), stitched by vertical steel anchors through the mortared half; its
top courses thrown sideways at 1 m/s, under gravity. Two presets: ``facets`` (the
default), 160 x 160 bricks of two triangles each (4 facets a brick), about 100 000
boundary facets and 51 000 elements: the contact phase at the size of the paper's
Figure 5; ``elements``, 30 x 30 bricks meshed at 20 mm (about 113 triangles a brick,
as bricks that may crack are meshed; the base block too), about 100 000 elements and
28 000 facets: the full step at 100 000 elements. ``--courses``, ``--bricks`` and
``--mesh-size`` override a preset.

In one ``mpirun -n P`` run the model is built and stepped twice, from the same start:
first on rank 0 alone (COMM_SELF; the other ranks wait), then on all P ranks. For each
phase it prints the median time per step over chunks of steps (the slowest rank's), the
speed-up T1/TP and the parallel efficiency T1/(P TP):

* contact search: neighbour-list rebuilds (facet boxes, ghost-facet exchange, ADT build
  and self search, pair history), per step on average (every ``--rebuild-every`` steps
  or sooner on travel);
* contact halo: the ghost nodes' positions and velocities (``Alltoallv``);
* contact kernels: the dampers, the pair forces and their sums into the nodes;
* joints, anchors: their forces (halo included) and commits;
* elements: the internal-force assembly (dolfinx) with the material update;
* the rest: the central-difference update, energies' work sums, the loop.

and the full step in nanoseconds per element-step. At the end the positions of every
node after the run on one rank and on P ranks are compared (they should be equal to the
bit: forces are summed in one global order).

``--preset disks``: the same phases for disks — the jammed, vibrating packing of
``benchmarks/disks.py`` (``--disks``, default 1e5; its outer ring fixed, no gravity), in
the package's explicit solver, on one rank and on all: disk search (the travel check and
any rebuild of the pair list), disk forces, the rest (the central-difference update of
the disks and the solver's loop). Every rank holds every disk (a replicated dof set);
each computes the forces of the pairs touching the disks it owns, a contiguous share of
the storage order, and the shares are gathered (``Disks.add_forces``), so the force
phase divides among the ranks while the search and the update are done by each rank
for all; the final centres on one and on P ranks are compared as above (equal to the
bit: each disk's force is summed over its pairs in the list's order on any rank count).

Run: ``mpirun -n 2 python benchmarks/scaling.py [--preset facets|elements] [--steps 600]``.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from collections import defaultdict

from mpi4py import MPI

import numpy as np

from masonry_fdem import Material, Model
from masonry_fdem.geometry import mesh_blocks, wall_layout
from masonry_fdem.interactions import (Anchor, Anchors, BlockContact, ContactSettings,
                                       JointMaterial, Joints)
from masonry_fdem.solvers import ExplicitSolver

L, H, T = 0.215, 0.065, 0.1025  # brick length, height, wall thickness [m]


def build(args, comm):
    """The wall on ``comm``: model, solver and its interactions."""
    wall = wall_layout(courses=args.courses, bricks_per_course=args.bricks, brick_length=L,
                       brick_height=H, joint=0.0)
    width = args.bricks * L
    half = 0.5 * args.courses * H
    mats = ["mortared" if np.mean(p[:, 1]) < half else "dry" for p in wall.polygons]
    base = np.array([[-0.5, -0.3], [width + 0.5, -0.3], [width + 0.5, 0.0], [-0.5, 0.0]])
    blocks = mesh_blocks([base, *wall.polygons], materials=["base", *mats],
                         names=["base", *wall.names], mesh_size=args.mesh_size, comm=comm)
    brick = Material(1800.0, 5e9, 0.2)
    model = Model(blocks, {"base": Material(2400.0, 30e9, 0.2), "mortared": brick,
                           "dry": brick}, width=T, comm=comm)
    model.fix_blocks("base")
    model.add_gravity()
    top = blocks.block_centroid[:, 1] > 0.8 * args.courses * H
    model.v[0::2] = np.where(top[model.node_block], 1.0, 0.0)
    contact = BlockContact(model, ContactSettings(friction=0.6, restitution=0.5,
                                                  rebuild_every=args.rebuild_every))
    mortar = JointMaterial(ft=2e5, GfI=10.0, c=3e5, GfII=50.0)
    joints = Joints(model, {("mortared", "mortared"): mortar, ("base", "mortared"): mortar,
                            ("dry", "dry"): None, ("dry", "mortared"): None,
                            ("base", "dry"): None}, contact=contact)
    xs = np.arange(0.5 * L, width, args.anchor_spacing)
    anchors = Anchors(model, [Anchor([[x, 0.02], [x, half - 0.02]], diameter=0.012,
                                     name=f"a{k}") for k, x in enumerate(xs)])
    solver = ExplicitSolver(model, interactions=[contact, joints, anchors], damping=1.0)
    return model, solver, contact, joints, anchors


def measure_disks(args, comm):
    """:func:`measure` for the ``disks`` preset: median time per step of the disk phases
    (slowest rank), the final centres in the user's numbering, and facts of the run."""
    import importlib.util  # noqa: PLC0415
    from pathlib import Path  # noqa: PLC0415

    from masonry_fdem.geometry import rectangle  # noqa: PLC0415
    from masonry_fdem.interactions.disks import Disks  # noqa: PLC0415

    spec = importlib.util.spec_from_file_location(
        "disk_benchmark", Path(__file__).with_name("disks.py"))
    DB = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = DB  # (its dataclasses look their module up)
    spec.loader.exec_module(DB)
    p = DB.packing(int(args.disks))
    d = Disks(p.x, p.r, {"gravel": DB.MAT}, "gravel", width=DB.WIDTH,
              margin=DB.MARGIN * p.r.min(), max_overlap=p.max_overlap, comm=comm)
    d.v[:] = p.v
    d.omega[:] = p.omega
    d.fix(p.fixed)
    lo = p.x.min(axis=0) - 10.0 * DB.R0  # the solver advances a model: a fixed block aside
    blocks = mesh_blocks([rectangle(lo[0] - DB.R0, lo[1] - DB.R0, lo[0], lo[1])],
                         materials="b", mesh_size=DB.R0, comm=comm)
    model = Model(blocks, {"b": Material(2600.0, 1e9, 0.25)}, width=DB.WIDTH, comm=comm)
    model.fix_blocks(0)
    solver = ExplicitSolver(model, dt=p.dt, interactions=d)
    tm = Timers()
    tm.wrap(d, "update", "disk search")
    tm.wrap(d, "add_forces", "disk forces")
    tm.wrap(model, "internal_force", "elements")
    solver.run(steps=20)  # warm-up: JIT caches, first search and sort
    def phases(d, step):
        row = {k: d.get(k, 0.0) for k in DISK_PHASES[:3]}
        row["rest"] = step - sum(row.values())
        row["full step"] = step
        return row

    med = sample(solver, tm, args, comm, phases)
    info = dict(disks=d.n, pairs=int(d.pairs.shape[0]), dt=solver.dt, rebuilds=d.rebuilds)
    return med, d.by_id(d.x.reshape(-1, 2)).copy(), info


def sample(solver, tm, args, comm, phases):
    """Median time per step [s] of each phase over chunks of ``args.chunk`` steps (the
    slowest rank's): ``phases(d, step)`` makes a chunk's row from the timers' seconds per
    step ``d`` and the whole step's ``step``."""
    samples = defaultdict(list)
    for _ in range(max(1, args.steps // args.chunk)):
        before = dict(tm.t)
        comm.barrier()
        t0 = time.perf_counter()
        solver.run(steps=args.chunk)
        step = (time.perf_counter() - t0) / args.chunk
        d = {k: (tm.t[k] - before.get(k, 0.0)) / args.chunk for k in tm.t}
        for k, v in phases(d, step).items():
            samples[k].append(comm.allreduce(v, op=MPI.MAX))
    return {k: statistics.median(v) for k, v in samples.items()}


def on_one_and_all(measure_fn, args):
    """``measure_fn(args, comm)`` on rank 0 alone, then on every rank: {1: result,
    P: result} on rank 0, None elsewhere."""
    world = MPI.COMM_WORLD
    res = {}
    if world.rank == 0:
        res[1] = measure_fn(args, MPI.COMM_SELF)
    world.barrier()
    if world.size > 1:
        res[world.size] = measure_fn(args, world)
    return res if world.rank == 0 else None


def print_phases(args, names, med1, medp, size):
    """The table of the phases' median times on 1 and on ``size`` ranks (``medp`` None
    on one rank) with the speed-up and the parallel efficiency."""
    print(f"median time per step over {args.steps} steps in chunks of {args.chunk} "
          f"(slowest rank)")
    head = f"{'phase':<17}{'1 rank [us]':>13}"
    if medp is not None:
        head += f"{f'{size} ranks [us]':>15}{'speed-up':>10}{'efficiency':>12}"
    print(head)
    for k in names:
        line = f"{k:<17}{1e6 * med1[k]:13.1f}"
        if medp is not None:
            line += (f"{1e6 * medp[k]:15.1f}{med1[k] / medp[k]:10.2f}"
                     f"{med1[k] / (size * medp[k]):12.2f}")
        print(line)


class Timers:
    """Wall-clock time [s] spent in named calls, wrapped around bound methods."""

    def __init__(self):
        self.t = defaultdict(float)

    def wrap(self, obj, method: str, name: str) -> None:
        fn = getattr(obj, method)
        t = self.t

        def timed(*a, **k):
            t0 = time.perf_counter()
            out = fn(*a, **k)
            t[name] += time.perf_counter() - t0
            return out

        setattr(obj, method, timed)


#: the two models: ~100 000 boundary facets (every brick two triangles: the contact
#: phase at the paper's Figure 5 size) and ~100 000 elements (bricks meshed at 20 mm,
#: ~113 triangles each, as a model whose bricks may crack is meshed: the full step)
PRESETS = {"facets": dict(courses=160, bricks=160, mesh_size=None),
           "elements": dict(courses=30, bricks=30, mesh_size=0.02)}

DISK_PHASES = ("disk search", "disk forces", "elements", "rest", "full step")

PHASES = ("contact search", "contact halo", "contact kernels", "joints", "anchors",
          "elements", "rest", "full step")


def measure(args, comm):
    """Median time per step [s] of every phase (slowest rank) and the final positions."""
    model, solver, contact, joints, anchors = build(args, comm)
    tm = Timers()
    tm.wrap(contact, "rebuild", "contact search")
    tm.wrap(contact, "_sync", "contact halo")
    tm.wrap(contact, "add_forces", "contact forces")
    tm.wrap(joints, "add_forces", "joints")
    tm.wrap(joints, "commit", "joints")
    tm.wrap(anchors, "update", "anchors")
    tm.wrap(anchors, "add_forces", "anchors")
    tm.wrap(anchors, "commit", "anchors")
    tm.wrap(model, "internal_force", "elements")
    solver.run(steps=20)  # warm-up: JIT caches, first rebuild
    def phases(d, step):
        row = {
            "contact search": d.get("contact search", 0.0),
            "contact halo": d.get("contact halo", 0.0),
            # add_forces holds the halo; the search is in update, outside it
            "contact kernels": d.get("contact forces", 0.0) - d.get("contact halo", 0.0),
            "joints": d.get("joints", 0.0),
            "anchors": d.get("anchors", 0.0),
            "elements": d.get("elements", 0.0),
            "full step": step,
        }
        row["rest"] = step - sum(row[k] for k in PHASES[:6])
        return row

    med = sample(solver, tm, args, comm, phases)
    n = model.n_nodes
    u = model.u.x.array[: 2 * n].reshape(-1, 2)
    rows = np.c_[model.node_block, model.X, u]
    rows = comm.gather(rows, root=0)
    if comm.rank == 0:
        rows = np.concatenate(rows)
        rows = rows[np.lexsort((rows[:, 2], rows[:, 1], rows[:, 0]))]
    info = dict(cells=model.blocks.n_cells, facets=int(contact.g_facets.shape[0]),
                bricks=model.blocks.n_blocks - 1, segments=joints.n_segments,
                anchors=len(anchors.anchors), pairs=comm.allreduce(
                    int((contact.counted > 0).sum()), op=MPI.SUM),
                dt=solver.dt, rebuilds=contact.rebuilds)
    return med, rows, info


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--preset", choices=[*sorted(PRESETS), "disks"], default="facets",
                    help="facets: 160 x 160 bricks of two triangles (~100 000 boundary "
                         "facets, the contact scaling); elements: 30 x 30 bricks meshed "
                         "at 20 mm (~100 000 elements, the full step); disks: the disk "
                         "phases on a jammed packing of --disks disks")
    ap.add_argument("--disks", type=float, default=1e5, help="disks of the disks preset")
    ap.add_argument("--courses", type=int, default=None, help="(default: the preset's)")
    ap.add_argument("--bricks", type=int, default=None,
                    help="bricks per course (default: the preset's)")
    ap.add_argument("--mesh-size", type=float, default=None,
                    help="element size [m] (default: the preset's; none: two triangles "
                         "per brick)")
    ap.add_argument("--steps", type=int, default=600, help="timed steps per run")
    ap.add_argument("--chunk", type=int, default=50, help="steps per timing sample")
    ap.add_argument("--rebuild-every", type=int, default=20)
    ap.add_argument("--anchor-spacing", type=float, default=2.0, help="[m]")
    args = ap.parse_args()
    if args.preset == "disks":
        return main_disks(args)
    for k, v in PRESETS[args.preset].items():
        if getattr(args, k) is None:
            setattr(args, k, v)
    size = MPI.COMM_WORLD.size
    res = on_one_and_all(measure, args)
    if res is None:
        return
    med1, rows1, info = res[1]
    print(f"wall: {info['bricks']} bricks + base, {info['cells']} cells, {info['facets']} "
          f"boundary facets, {info['segments']} joint segments, {info['anchors']} anchors; "
          f"dt = {info['dt']:.3e} s, {info['pairs']} candidate pairs at the end")
    medp = res[size][0] if size > 1 else None
    print_phases(args, PHASES, med1, medp, size)
    contact1 = sum(med1[k] for k in PHASES[:3])
    line = (f"contact phase (search + halo + kernels): {1e6 * contact1:.1f} us on 1 rank, "
            f"{1e9 * contact1 / info['facets']:.1f} ns per facet")
    if medp is not None:
        contactp = sum(medp[k] for k in PHASES[:3])
        line += (f"; {1e6 * contactp:.1f} us on {size}: speed-up {contact1 / contactp:.2f}, "
                 f"efficiency {contact1 / (size * contactp):.2f} (goal >= 0.85)")
    print(line)
    line = (f"full step: {1e9 * med1['full step'] / info['cells']:.1f} ns per element-step "
            f"on 1 rank (goal <= 200)")
    if medp is not None:
        line += f", {1e9 * medp['full step'] / info['cells']:.1f} on {size}"
    print(line)
    if size > 1:
        rowsp = res[size][1]
        same = rowsp.shape == rows1.shape and np.array_equal(rowsp[:, :3], rows1[:, :3])
        diff = np.abs(rowsp[:, 3:] - rows1[:, 3:]).max() if same else np.inf
        scale = np.abs(rows1[:, 3:]).max()
        print(f"final positions, {size} ranks against 1: largest difference {diff:.1e} m "
              f"(largest displacement {scale:.2e} m){'; equal to the bit' if diff == 0 else ''}")


def main_disks(args):
    """The ``disks`` preset: measure on rank 0 alone, then on all ranks; print."""
    size = MPI.COMM_WORLD.size
    res = on_one_and_all(measure_disks, args)
    if res is None:
        return
    med1, x1, info = res[1]
    print(f"disks: {info['disks']} disks (jammed packing of benchmarks/disks.py), "
          f"{info['pairs']} candidate pairs, dt = {info['dt']:.3e} s, "
          f"{info['rebuilds']} pair-list builds; every rank holds every disk, the forces "
          "are computed by the ranks owning the disks and gathered")
    medp = res[size][0] if size > 1 else None
    print_phases(args, DISK_PHASES, med1, medp, size)
    print(f"full step: {1e9 * med1['full step'] / info['disks']:.1f} ns per disk-step on 1 "
          "rank" + (f", {1e9 * medp['full step'] / info['disks']:.1f} on {size}"
                    if medp is not None else ""))
    if size > 1:
        xp = res[size][1]
        diff = float(np.abs(xp - x1).max())
        print(f"final centres, {size} ranks against 1: largest difference {diff:.1e} m"
              f"{'; equal to the bit' if diff == 0 else ''}")


if __name__ == "__main__":
    main()
