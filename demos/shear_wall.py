# # The TU Eindhoven shear wall as tested: precompression held, top beam pushed level
#
# This demo illustrates how to:
#
# - build the wall of the Eindhoven shear-wall tests (Raijmakers & Vermeltfoort 1992) as
#   Lourenço & Rots (1997) modelled it: 990 x 1000 mm, 16 active courses of expanded units
#   (210 x 52 mm bricks + 10 mm joint = 220 x 62 mm) in running bond between the two
#   clamped courses, which are part of the steel beams; zero-thickness mortar joints (the
#   Lourenço–Rots composite interface: tension cut-off, Coulomb friction with softening
#   cohesion, compression cap) and a potential crack down the middle of every brick,
#   as in their model;
# - hold the top beam level but free to move vertically (an `EqualDisplacement` tie on
#   its vertical displacements) and drive its horizontal displacement (a prescription),
# - apply the vertical precompression (held: a dead load), then trace the horizontal
#   load–displacement curve past its peak with the static Newton solver under
#   displacement control, ending with an explicit status,
# - draw the curve and the crack pattern.
#
# Material values: Lourenço & Rots (1997), J. Eng. Mech. 123(7), their set for the walls
# at 0.30 MPa (J4D, J5D): bricks E = 16.7 GPa, ν = 0.15; joints k_n = 82, k_s = 36 N/mm³,
# f_t = 0.25 MPa, G_fI = 0.018 N/mm, c = 0.35 MPa, tan φ = 0.75, G_fII = 0.125 N/mm, cap
# f_c = 10.5 MPa, C_s = 9, G_fc = 5 N/mm, κ_p = 0.09 mm; brick cracks f_t = 2.0 MPa,
# G_fI = 0.08 N/mm. For the walls at 1.21 and 2.12 MPa they lowered the joint values to
# f_t = 0.16 MPa, G_fI = 0.012 N/mm, c = 0.224 MPa, G_fII = 0.05 N/mm (`--set high`).
# The tests at 0.30 MPa peaked at about 50 kN (J4D/J5D as Lourenço & Rots compare them;
# recalled, not re-read here: no copy of the paper was at hand).
#
# Run with `python demos/shear_wall.py` or `mpirun -n 2 python demos/shear_wall.py`;
# `--courses 6 --bricks 2` gives a small wall.

# +
import argparse
import logging
import time
from pathlib import Path

from mpi4py import MPI

import numpy as np

from masonry_fdem import Material, Model
from masonry_fdem.geometry import mesh_blocks
from masonry_fdem.interactions import BlockContact, ContactSettings, JointMaterial, Joints
from masonry_fdem.interactions.ties import EqualDisplacement
from masonry_fdem.io import History, VTXOutput, plot_blocks
from masonry_fdem.solvers import StaticSolver

# -

UNIT_L, UNIT_H, THICK = 0.22, 0.062, 0.1  # [m] expanded unit (brick + 10 mm joint), depth
BEAM_H = 0.1  # [m] depth of the steel beams drawn above and below the wall


def _joint_set(which: str) -> JointMaterial:
    """Lourenço & Rots (1997) joint values: "low" for the walls at 0.30 MPa, "high" for
    those at 1.21 and 2.12 MPa (SI units)."""
    cap = dict(kn=82e9, ks=36e9, tan_phi=0.75, fc=10.5e6, Cs=9.0, kappa_p=0.09e-3,
               Gfc=5000.0)
    if which == "low":
        return JointMaterial(ft=0.25e6, GfI=18.0, c=0.35e6, GfII=125.0, **cap)
    if which == "high":
        return JointMaterial(ft=0.16e6, GfI=12.0, c=0.224e6, GfII=50.0, **cap)
    raise ValueError(f"joint set must be 'low' or 'high', got {which!r}")


# brick cracks: f_t = 2.0 MPa, G_fI = 0.08 N/mm (Lourenço & Rots 1997); the shear values
# (c = 1.4 f_t, G_fII = 10 G_fI) follow their joint ratios (assumed)
BRICK_CRACK = JointMaterial(ft=2.0e6, GfI=80.0, c=2.8e6, tan_phi=1.0, GfII=800.0,
                            penalty=10.0)


def wall_polygons(courses: int = 16, bricks: int = 4, split: bool = True):
    """Running bond of ``bricks`` full units and one half unit per course (the half at the
    right in even courses, at the left in odd ones), ``(bricks + ½) × 220`` mm wide.
    With ``split`` each full unit is two half-units named ``<unit>#0`` and ``<unit>#1``:
    the interface between them is the unit's potential crack (a crack law, not mortar).
    Returns polygons, names, width [m], height [m]."""
    polys, names = [], []
    for c in range(courses):
        y0, y1 = c * UNIT_H, (c + 1) * UNIT_H
        x = 0.0
        order = ["full"] * bricks + ["half"] if c % 2 == 0 else ["half"] + ["full"] * bricks
        for k, kind in enumerate(order):
            length = UNIT_L if kind == "full" else 0.5 * UNIT_L
            pieces = 2 if kind == "full" and split else 1
            for p in range(pieces):
                xa = x + p * length / pieces
                xb = xa + length / pieces
                polys.append(np.array([[xa, y0], [xb, y0], [xb, y1], [xa, y1]]))
                names.append(f"brick:{c}:{k}" + (f"#{p}" if pieces == 2 else ""))
            x += length
    return polys, names, (bricks + 0.5) * UNIT_L, courses * UNIT_H


def shear_wall(courses=16, bricks=4, *, fracture=True, joint_set="low", mesh_size=None,
               comm=MPI.COMM_WORLD):
    """The wall between its two steel beams, with its joints and contact (not loaded).
    Returns model, joints, contact, (width, height) [m]."""
    polys, names, width, height = wall_polygons(courses, bricks, split=fracture)
    base = np.array([[0.0, -BEAM_H], [width, -BEAM_H], [width, 0.0], [0.0, 0.0]])
    beam = np.array([[0.0, height], [width, height], [width, height + BEAM_H],
                     [0.0, height + BEAM_H]])
    blocks = mesh_blocks([base, beam, *polys], materials=["steel"] * 2 + ["brick"] * len(polys),
                         names=["base", "beam", *names], mesh_size=mesh_size or UNIT_H,
                         comm=comm)
    model = Model(blocks, {"steel": Material(7850.0, 200e9, 0.3),
                           "brick": Material(1800.0, 16.7e9, 0.15)}, width=THICK, comm=comm)
    mortar = _joint_set(joint_set)
    contact = BlockContact(model, ContactSettings(friction=0.75, penalty=82e9))
    # the bed joints to the clamped courses are mortar joints like the others
    joints = Joints(model, {("brick", "brick"): mortar, ("brick", "steel"): mortar},
                    cracks={"brick": BRICK_CRACK}, contact=contact)
    return model, joints, contact, (width, height)


def push(model, joints, contact, size, *, precompression=0.30e6, d_max=4e-3,
         increment=2.5e-5, vertical="held", callback=None):
    """Hold the base, tie the top beam level, apply self-weight and the precompression
    [Pa] (dead loads) with the beam free to move vertically, then drive the beam sideways
    to ``d_max`` [m] under displacement control (Newton), the beam's vertical position
    ``"held"`` where the precompression left it (the test's confined loading: the wall
    cannot lift the beam, so its vertical force grows as it rocks and dilates) or
    ``"free"`` (the precompression force held constant instead).

    Returns the solver and its :class:`StaticRun` (loads: the horizontal reaction of the
    beam [N]; displacements: its drive [m])."""
    if vertical not in ("held", "free"):
        raise ValueError(f"vertical must be 'held' or 'free', got {vertical!r}")
    width, height = size
    model.fix_blocks("base", name="base")
    model.prescribe_velocity("beam", (0.0, None), name="beam")  # x driven, y free
    level = EqualDisplacement(model, "beam", component=1, name="level beam")
    model.add_gravity(live=False)
    top = height + BEAM_H
    model.add_pressure(lambda x: np.isclose(x[1], top) & (x[0] > -1e-9)
                       & (x[0] < width + 1e-9), precompression, live=False)
    solver = StaticSolver(model, interactions=[contact, joints, level])
    st = solver.settle()
    if st.status.name != "LOAD_REACHED":
        raise RuntimeError(f"the precompressed wall found no equilibrium: {st.detail}")
    if vertical == "held":
        # from here the beam's vertical displacement is prescribed where it settled (the
        # tie made it the same at every node): a solver of its own takes the new support
        model.prescribe_velocity("beam", (None, 0.0), name="beam height")
        solver = StaticSolver(model, interactions=[contact, joints, level])
    run = solver.follow(increment, control="displacement", prescription="beam", component=0,
                        direction=1.0, max_displacement=d_max,
                        callback=None if callback is None else lambda p: callback(p, solver))
    return solver, run


def extra_vertical_force(solver) -> float:
    """The vertical force [N] the held beam adds to the precompression (> 0: the wall
    pushes the beam up, the beam holds it down); 0 when the beam is free."""
    r = solver.reactions()
    return -float(r["beam height"][1]) if "beam height" in r else 0.0


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description="TU Eindhoven shear wall, as tested")
    parser.add_argument("--courses", type=int, default=16, help="active courses")
    parser.add_argument("--bricks", type=int, default=4, help="full units per course")
    parser.add_argument("--precompression", type=float, default=0.30e6, help="[Pa]")
    parser.add_argument("--set", choices=["low", "high"], default=None,
                        help="Lourenço–Rots joint values (default: 'low' at 0.30 MPa or "
                             "less, 'high' above)")
    parser.add_argument("--push", type=float, default=4e-3, help="top displacement [m]")
    parser.add_argument("--increment", type=float, default=2.5e-5, help="first step [m]")
    parser.add_argument("--vertical", choices=["held", "free"], default="held",
                        help="top beam height after the precompression: held (the test) "
                             "or free (constant vertical force)")
    parser.add_argument("--no-fracture", action="store_true", help="bricks do not crack")
    parser.add_argument("--out", type=Path, default=Path("out_shear_wall"))
    args = parser.parse_args()
    comm = MPI.COMM_WORLD
    logging.basicConfig(level=logging.INFO if comm.rank == 0 else logging.WARNING,
                        format="%(message)s")
    joint_set = args.set or ("low" if args.precompression <= 0.3e6 + 1 else "high")
    t0 = time.perf_counter()
    model, joints, contact, size = shear_wall(args.courses, args.bricks,
                                              fracture=not args.no_fracture,
                                              joint_set=joint_set, comm=comm)
    out = args.out
    history = History(out / "history.csv", comm)

    extra = []

    def record(p, solver):
        e = joints.energies()
        extra.append(extra_vertical_force(solver))
        history.append({"displacement": p.displacement, "load": p.load,
                        "extra_vertical_force": extra[-1], "iterations": p.iterations,
                        "joint_dissipated": e["joint_dissipated"]})
        if comm.rank == 0:
            logging.info(f"  {1e3 * p.displacement:6.3f} mm  {1e-3 * p.load:8.2f} kN  "
                         f"(+{1e-3 * extra[-1]:.1f} kN vertical, {p.iterations} its)")

    solver, run = push(model, joints, contact, size, precompression=args.precompression,
                       d_max=args.push, increment=args.increment,
                       vertical=args.vertical, callback=record)
    history.close()
    vtx = VTXOutput(model, out, joints=joints)
    vtx.write(0.0)
    vtx.close()
    counts = joints.counts()
    disp, load = np.array(run.displacements), np.array(run.loads)
    plot_blocks(model, out / "cracks.png", field="von_mises", scale=50.0, joints=joints,
                title=f"shear wall at {1e3 * disp[-1]:.2f} mm: cracks (x50 displacement)")
    if comm.rank == 0:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(5, 4), dpi=120)
        ax.plot(1e3 * disp, 1e-3 * load, ".-", ms=2)
        ax.set_xlabel("horizontal displacement of the top beam [mm]")
        ax.set_ylabel("horizontal load [kN]")
        ax.set_title(f"shear wall, {args.precompression / 1e6:.2f} MPa: "
                     f"{run.status.status.value}")
        ax.grid(True)
        fig.savefig(out / "load_displacement.png", bbox_inches="tight")
        plt.close(fig)
        k = int(np.argmax(load))
        print(f"{model.blocks.n_blocks} blocks, {model.blocks.n_cells} cells, "
              f"{joints.n_segments} joint segments, {comm.size} rank(s); "
              f"{len(disp) - 1} increments; {time.perf_counter() - t0:.1f} s")
        print(f"status: {run.status.describe('kN', 1e3)}")
        n0 = args.precompression * size[0] * THICK
        print(f"peak horizontal load {1e-3 * load[k]:.3f} kN at {1e3 * disp[k]:.3f} mm; "
              f"last {1e-3 * load[-1]:.3f} kN at {1e3 * disp[-1]:.3f} mm")
        if k > 0:
            print(f"vertical force on the wall at the peak: {1e-3 * n0:.1f} kN precompression "
                  f"+ {1e-3 * extra[k - 1]:.1f} kN from the held beam ({args.vertical})")
        print("joint segments: " + ", ".join(f"{k} {v}" for k, v in counts.items()))
        print(f"outputs in {out.resolve()}: history.csv, load_displacement.png, "
              f"cracks.png, displacement.bp, stress.bp, joints.bp")
