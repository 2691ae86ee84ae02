# # A dry-stacked brick wall pushed over
#
# This demo illustrates how to:
#
# - build a running-bond wall of separate bricks on a fixed base,
# - let the bricks interact by frictional penalty contact (ADT neighbour search),
# - run explicit dynamics with the stable time step the contact springs allow,
# - follow the energy account: kinetic + strain + contact penalty energy + friction, the
#   contact dampers' and the solver's damping dissipation − gravity work = the initial
#   kinetic energy, and print what is left over (the residual).
#
# The top courses get a sideways push; the wall rocks, its upper courses slide and fall.
# Run with `python demos/topple_wall.py` or `mpirun -n 2 python demos/topple_wall.py`.

# +
import argparse
import logging
import time
from pathlib import Path

from mpi4py import MPI

import numpy as np

from masonry_fdem import Material, Model
from masonry_fdem.interactions import BlockContact, ContactSettings
from masonry_fdem.geometry import mesh_blocks, wall_layout
from masonry_fdem.io import History, ProgressBar, VTXOutput, plot_blocks
from masonry_fdem.solvers import ExplicitSolver

# -

parser = argparse.ArgumentParser(description=__doc__)
parser.add_argument("--courses", type=int, default=8)
parser.add_argument("--bricks", type=int, default=4, help="bricks per course")
parser.add_argument("--push", type=float, default=1.5, help="initial speed of the top [m/s]")
parser.add_argument("--time", type=float, default=0.8, help="simulated time [s]")
parser.add_argument("--mesh-size", type=float, default=None, help="None: 2 triangles/brick")
parser.add_argument("--out", type=Path, default=Path("out_topple_wall"))
args = parser.parse_args()
comm = MPI.COMM_WORLD
logging.basicConfig(level=logging.INFO if comm.rank == 0 else logging.WARNING,
                    format="%(message)s")

# ## Geometry: 215 x 65 mm bricks in running bond on a concrete base

L, H = 0.215, 0.065
wall = wall_layout(courses=args.courses, bricks_per_course=args.bricks, brick_length=L,
                   brick_height=H)
width = args.bricks * L
base = np.array([[-1.0, -0.2], [width + 1.0, -0.2], [width + 1.0, 0.0], [-1.0, 0.0]])
blocks = mesh_blocks([base, *wall.polygons], materials=["concrete", *wall.materials],
                     names=["base", *wall.names], mesh_size=args.mesh_size, comm=comm)

# ## Model: clay bricks, 102.5 mm thick wall (plane stress), dry joints with friction 0.6

model = Model(blocks, {"concrete": Material(2400.0, 30e9, 0.2),
                       "brick": Material(1800.0, 5e9, 0.2)}, width=0.1025, comm=comm)
model.fix_blocks("base")
model.add_gravity()
top = blocks.block_centroid[:, 1] > 0.6 * args.courses * H
model.v[0::2] = np.where(top[model.node_block], args.push, 0.0)
model.monitor("top", (width, args.courses * H))
contact = BlockContact(model, ContactSettings(friction=0.6, restitution=0.3))
solver = ExplicitSolver(model, interactions=contact, damping=2.0)

# ## Run, recording the energy account

out = args.out
history = History(out / "history.csv", comm)
vtx = VTXOutput(model, out)
bar = ProgressBar("toppling", comm=comm)
every = max(1, int(0.005 / solver.dt))


def record(s):
    e = s.energies()
    history.append({"time": s.t, "top": model.monitor_values()["top"], "kinetic": e.kinetic,
                    "strain": e.stored["strain"], "contact": e.stored["contact"],
                    "friction": e.dissipated["contact friction"],
                    "contact_damper": e.dissipated["contact damper"],
                    "damping": e.damping, "gravity_work": e.external,
                    "residual": e.residual})
    vtx.write(s.t)
    bar.update(s.t / args.time, f"top x {1e3 * model.monitor_values()['top'][0]:.1f} mm")


t0 = time.perf_counter()
solver.run(t_end=args.time, every=every, callback=record)
bar.close()
vtx.close()
history.close()
png = plot_blocks(model, out / "toppled.png", field="block", scale=1.0,
                  title=f"dry brick wall at t = {solver.t:.2f} s")
e = solver.energies()  # collective: on every rank
if comm.rank == 0:
    print(f"{blocks.n_blocks - 1} bricks, {blocks.n_cells} cells, {comm.size} rank(s); "
          f"dt = {solver.dt:.2e} s, {solver.n} steps in {time.perf_counter() - t0:.1f} s")
    print(e.summary())
    print(f"energy residual {e.residual:.3e} J: {100 * e.relative_residual:.4f} % of the "
          f"work done ({e.scale:.4g} J: the initial kinetic energy {e.initial:.4g} J and "
          f"gravity's work, {e.exchanged:.4g} J step by step in absolute value)")
    print(f"neighbour-list rebuilds: {contact.rebuilds}")
    print(f"outputs in {out.resolve()}: history.csv, displacement.bp, stress.bp, toppled.png")
