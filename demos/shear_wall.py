# # A masonry shear wall: mortar joints and brick cracks under precompression and a push
#
# This demo illustrates how to:
#
# - build an 18-course running-bond wall of 210 x 52 mm bricks (about 1 m square) between a
#   fixed base and a steel top beam,
# - bond the bricks with mortar joints (the Lourenço–Rots composite interface: tension
#   cut-off, Coulomb friction with softening cohesion, compression cap) and make the
#   bricks fracturable (each brick is cut into its triangles and rejoined by a cohesive
#   crack law, so cracks can run diagonally through the units),
# - bring the wall to equilibrium under self-weight and a vertical precompression by
#   dynamic relaxation, then push the top beam sideways (explicit dynamics, slow ramp),
# - record the horizontal load–displacement curve and draw the crack pattern.
#
# The material values are those Lourenço & Rots (1997) used for the TU Eindhoven shear
# walls (joint stiffness 82/36 N/mm³, f_t = 0.16 MPa, G_fI = 12 N/m, c = 0.224 MPa,
# tan φ = 0.75, G_fII = 50 N/m, cap f_c = 10.5 MPa). Unlike those tests, the top beam here
# may rotate: the wall works as a cantilever, not between two clamped beams.
#
# Run with `python demos/shear_wall.py` or `mpirun -n 2 python demos/shear_wall.py`;
# `--courses 6 --bricks 3` gives a small wall.

# +
import argparse
import logging
import time
from pathlib import Path

from mpi4py import MPI

import numpy as np

from masonry_fdem import Material, Model
from masonry_fdem.interactions import BlockContact, ContactSettings, JointMaterial, Joints
from masonry_fdem.geometry import mesh_blocks, wall_layout
from masonry_fdem.io import History, ProgressBar, VTXOutput, plot_blocks
from masonry_fdem.solvers import DynamicRelaxation, ExplicitSolver

# -

BRICK_L, BRICK_H, THICK = 0.21, 0.052, 0.1  # [m]
MORTAR = JointMaterial(kn=82e9, ks=36e9, ft=0.16e6, GfI=12.0, c=0.224e6, tan_phi=0.75,
                       GfII=50.0, fc=10.5e6, Cs=9.0, kappa_p=0.09e-3, Gfc=5000.0)
BRICK_CRACK = JointMaterial(ft=2.0e6, GfI=80.0, c=2.8e6, tan_phi=1.0, GfII=800.0,
                            penalty=10.0)
GLUE = JointMaterial(kn=82e9, ks=36e9, ft=5e6, GfI=1000.0, c=5e6, GfII=1000.0, tan_phi=1.0)


def shear_wall(courses=18, bricks=5, *, fracture=True, mesh_size=None, comm=MPI.COMM_WORLD):
    """The wall model, its joints and contact (not yet loaded)."""
    wall = wall_layout(courses=courses, bricks_per_course=bricks, brick_length=BRICK_L,
                       brick_height=BRICK_H)
    width, height = bricks * BRICK_L, courses * BRICK_H
    base = np.array([[-0.1, -0.1], [width + 0.1, -0.1], [width + 0.1, 0.0], [-0.1, 0.0]])
    beam = np.array([[0.0, height], [width, height], [width, height + 0.1],
                     [0.0, height + 0.1]])
    blocks = mesh_blocks([base, beam, *wall.polygons],
                         materials=["concrete", "steel", *wall.materials],
                         names=["base", "beam", *wall.names],
                         mesh_size=mesh_size or 0.5 * BRICK_L, comm=comm)
    if fracture:
        blocks = blocks.fractured("brick:*")
    model = Model(blocks, {"concrete": Material(2400.0, 30e9, 0.2),
                           "steel": Material(7850.0, 200e9, 0.3),
                           "brick": Material(1800.0, 16.7e9, 0.15)}, width=THICK, comm=comm)
    contact = BlockContact(model, ContactSettings(friction=0.75, penalty=82e9))
    joints = Joints(model, {("brick", "brick"): MORTAR, ("brick", "concrete"): GLUE,
                            ("brick", "steel"): GLUE},
                    cracks={"brick": BRICK_CRACK}, contact=contact)
    return model, joints, contact, (width, height)


def push(model, joints, contact, size, *, precompression=0.30e6, d_max=3e-3,
         t_load=0.08, samples=200, callback=None):
    """Precompress (dynamic relaxation), then push the beam sideways by d_max [m] over
    t_load [s]. Returns the beam displacement [m] and horizontal load [N] arrays."""
    width, height = size
    model.fix_blocks("base", name="base")
    model.add_gravity(live=False)
    model.add_pressure(lambda x: np.isclose(x[1], height + 0.1) & (x[0] > -1e-9)
                       & (x[0] < width + 1e-9), precompression, live=False)
    dr = DynamicRelaxation(model, interactions=[contact, joints], rtol=1e-6)
    res = dr.solve(1.0)
    if not res.converged:
        raise RuntimeError("the precompressed wall found no equilibrium")
    t_r = 0.1 * t_load
    v0 = d_max / (t_load - 0.5 * t_r)
    model.prescribe_velocity("beam", lambda t: (v0 * min(t / t_r, 1.0), None), name="beam")
    solver = ExplicitSolver(model, interactions=[contact, joints], damping=50.0)
    disp, load = [0.0], [0.0]

    def record(s):
        t = s.t
        disp.append(v0 * (0.5 * t * t / t_r if t < t_r else 0.5 * t_r + t - t_r))
        load.append(s.reactions()["beam"][0])
        if callback is not None:
            callback(s, disp[-1], load[-1])

    every = max(1, int(round(t_load / solver.dt / samples)))
    solver.run(t_end=t_load, every=every, callback=record)
    return np.array(disp), np.array(load), solver


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description="masonry shear wall")
    parser.add_argument("--courses", type=int, default=18)
    parser.add_argument("--bricks", type=int, default=5, help="full bricks per course")
    parser.add_argument("--precompression", type=float, default=0.30e6, help="[Pa]")
    parser.add_argument("--push", type=float, default=3e-3, help="top displacement [m]")
    parser.add_argument("--time", type=float, default=0.08, help="push duration [s]")
    parser.add_argument("--no-fracture", action="store_true", help="bricks do not crack")
    parser.add_argument("--out", type=Path, default=Path("out_shear_wall"))
    args = parser.parse_args()
    comm = MPI.COMM_WORLD
    logging.basicConfig(level=logging.INFO if comm.rank == 0 else logging.WARNING,
                        format="%(message)s")
    t0 = time.perf_counter()
    model, joints, contact, size = shear_wall(args.courses, args.bricks,
                                              fracture=not args.no_fracture, comm=comm)
    out = args.out
    history = History(out / "history.csv", comm)
    vtx = VTXOutput(model, out, joints=joints)
    bar = ProgressBar("pushing", comm=comm)

    def record(s, d, f):
        e = joints.energies()
        history.append({"time": s.t, "displacement": d, "load": f,
                        "joint_dissipated": e["joint_dissipated"]})
        bar.update(d / args.push, f"{1e3 * d:.2f} mm, {1e-3 * f:.1f} kN")

    disp, load, solver = push(model, joints, contact, size,
                              precompression=args.precompression, d_max=args.push,
                              t_load=args.time, callback=record)
    bar.close()
    vtx.write(solver.t)
    vtx.close()
    history.close()
    counts = joints.counts()
    png = plot_blocks(model, out / "cracks.png", field="von_mises", scale=50.0,
                      joints=joints, title="shear wall: cracks (x50 displacement)")
    if comm.rank == 0:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(5, 4), dpi=120)
        ax.plot(1e3 * disp, 1e-3 * load)
        ax.set_xlabel("top displacement [mm]")
        ax.set_ylabel("horizontal load [kN]")
        ax.set_title(f"shear wall, precompression {args.precompression / 1e6:.2f} MPa")
        ax.grid(True)
        fig.savefig(out / "load_displacement.png", bbox_inches="tight")
        plt.close(fig)
        print(f"{model.blocks.n_blocks} blocks, {model.blocks.n_cells} cells, "
              f"{joints.n_segments} joint segments, {comm.size} rank(s); "
              f"{solver.n} steps of {solver.dt:.2e} s; {time.perf_counter() - t0:.1f} s")
        print(f"peak horizontal load {1e-3 * load.max():.2f} kN at "
              f"{1e3 * disp[np.argmax(load)]:.2f} mm; final {1e-3 * load[-1]:.2f} kN")
        print("joint segments: " + ", ".join(f"{k} {v}" for k, v in counts.items()))
        print(f"outputs in {out.resolve()}: history.csv, load_displacement.png, "
              f"cracks.png, displacement.bp, stress.bp, joints.bp")
