# # A masonry arch barrel settling under its self-weight
#
# This demo illustrates how to:
#
# - build a block geometry with Gmsh (one block per polygon, no shared nodes),
# - make a model with a material, gravity and supports,
# - bring it to equilibrium by dynamic relaxation, with load increments,
# - write a history CSV, a ParaView (VTX) time series and a PNG picture.
#
# Until contact and mortar joints arrive, the arch ring is one monolithic elastic block,
# built in at its springings: its crown settles by a fraction of a millimetre. Later
# versions of this demo load a multi-ring voussoir arch to collapse.
#
# Run with `python demos/settle_arch.py` or `mpirun -n 2 python demos/settle_arch.py`.

# +
import argparse
import logging
import time
from pathlib import Path

from mpi4py import MPI

import numpy as np

from masonry_fdem import Material, Model
from masonry_fdem.constants import G
from masonry_fdem.geometry import mesh_blocks
from masonry_fdem.io import History, ProgressBar, VTXOutput, plot_blocks
from masonry_fdem.solvers import DynamicRelaxation

# -

parser = argparse.ArgumentParser(description=__doc__)
parser.add_argument("--span", type=float, default=5.0, help="clear span [m]")
parser.add_argument("--thickness", type=float, default=0.45, help="ring thickness [m]")
parser.add_argument("--width", type=float, default=1.0, help="barrel width [m]")
parser.add_argument("--mesh-size", type=float, default=0.08, help="element size [m]")
parser.add_argument("--steps", type=int, default=5, help="load increments")
parser.add_argument("--out", type=Path, default=Path("out_settle_arch"))
args = parser.parse_args()

comm = MPI.COMM_WORLD
logging.basicConfig(level=logging.INFO if comm.rank == 0 else logging.WARNING,
                    format="%(message)s")

# ## Geometry: a semicircular ring as one polygon (intrados and extrados as polylines)

R = 0.5 * args.span
t = args.thickness
theta = np.linspace(0.0, np.pi, 61)
extrados = np.c_[(R + t) * np.cos(theta), (R + t) * np.sin(theta)]
intrados = np.c_[R * np.cos(theta[::-1]), R * np.sin(theta[::-1])]
ring = np.vstack([extrados, intrados])
blocks = mesh_blocks([ring], materials="brick", names=["ring"], mesh_size=args.mesh_size,
                     comm=comm)

# ## Model: clay brick masonry, plane stress over the barrel width

brick = Material(density=2000.0, E=5.0e9, nu=0.2)
model = Model(blocks, {"brick": brick}, width=args.width, comm=comm)
model.fix(lambda X: X[1] < 1e-9, name="springings")
model.add_gravity(live=True)  # gravity scaled by the load factor: applied in increments
model.monitor("crown", (0.0, R))

# ## Dynamic relaxation in load increments

out = args.out
history = History(out / "history.csv", comm)
vtx = VTXOutput(model, out)
dr = DynamicRelaxation(model, rtol=1e-7)
bar = ProgressBar("settling", comm=comm)
factors = np.linspace(1.0 / args.steps, 1.0, args.steps)
t0 = time.perf_counter()
for k, lf in enumerate(factors):
    res = dr.solve(lf)
    reaction = dr.reactions()["springings"]
    crown = model.monitor_values()["crown"]
    history.append({"load_factor": lf, "iterations": res.iterations,
                    "residual": res.relative_residual, "crown": crown,
                    "reaction": reaction, "strain_energy": model.strain_energy()})
    vtx.write(float(lf))
    bar.update((k + 1) / len(factors), f"crown {1e3 * crown[1]:.4f} mm")
    if not res.converged:
        break
bar.close()
vtx.close()
history.close()
png = plot_blocks(model, out / "settled.png", field="von_mises", scale=500.0,
                  title="arch ring under self-weight (displacements x500)")

weight = model.total_mass() * G  # of the meshed ring
if comm.rank == 0:
    print(f"blocks: {blocks.n_blocks}, cells: {blocks.n_cells}, ranks: {comm.size}")
    print(f"dynamic relaxation: {sum(r.iterations for r in dr.results)} iterations in "
          f"{len(dr.results)} increments, {time.perf_counter() - t0:.1f} s")
    print(f"crown settlement under self-weight: {-1e3 * crown[1]:.4f} mm")
    print(f"support reaction {reaction[1] / 1e3:.4f} kN vs weight {weight / 1e3:.4f} kN")
    print(f"outputs in {out.resolve()}: history.csv, displacement.bp, stress.bp, settled.png")
