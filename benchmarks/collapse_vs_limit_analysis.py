"""FDEM collapse loads against rigid-block limit analysis (a study for issue #8).

Prints the collapse load of a dry-jointed structure found by dynamic relaxation, as a
ratio of the limit-analysis (LP) load of the same geometry, run in the same process:

* ``--control load``: :meth:`DynamicRelaxation.load_to_collapse` (increments of 10 % of
  the LP load, a failed increment restored and halved ``--refinements`` times); it ends
  *not converged*, its last load a lower bound of the collapse load (printed so);
* ``--control displacement``: the loaded point is driven down (arch) or sideways (block) in
  steps of ``--step`` metres; the peak reaction is the collapse load once the reaction
  has fallen 5 % below it (*peak passed*; a step without equilibrium first: a lower bound).

Cases: ``rock`` (a 0.5 × 1 m block on a fixed base pushed at its top corner) and ``arch``
(a 12-voussoir semicircular ring, span 2 m, thickness ``--t``, point load at 135°). Under
displacement control the driven node is prescribed after the self-weight equilibrium.
``--damping``: the DR damping estimate (``velocity`` by default here).

Measured (penalty factor 20; E = 10 GPa voussoirs, 1 GPa for the block):

* rock: 0.9625 (load control, where it stalls: a lower bound) / 0.9902 (displacement
  control);
* arch, t = 0.2 m, load control: 0.8625; displacement control, ``--step 2e-5``:
  peak 0.9611 with either damping estimate, 42 000–67 000 DR iterations per step with
  Underwood's estimate and 5 000–36 000 with the velocity quotient (rtol 1e-5);
* the arch's ratio falls with the stiffness: E = 1 GPa 0.914, E = 0.1 GPa 0.80 (the
  hinges bear on a zone that grows as the blocks and contact soften).

    python benchmarks/collapse_vs_limit_analysis.py --case arch --control displacement
"""

from __future__ import annotations

import argparse
import math
import time

from mpi4py import MPI

import numpy as np

from masonry_fdem import Material, Model
from masonry_fdem.interactions import BlockContact, ContactSettings
from masonry_fdem.geometry import BlockLayout, arch_layout, rectangle
from masonry_fdem.solvers.limit_analysis import limit_analysis
from masonry_fdem.solvers import DynamicRelaxation

def build(case: str, t: float, h: float, E_arch: float = 10e9):
    """Layout, LP load [N], loaded point, load direction, materials, supports."""
    if case == "rock":
        lay = BlockLayout((rectangle(-0.5, -0.2, 1.0, 0.0), rectangle(0.0, 0.0, 0.5, 1.0)),
                          ("base", "brick"), ("base", "block"))
        point, direction, rho, E, supports = (0.0, 1.0), (1.0, 0.0), 600.0, 1e9, "base"
        mats = {"brick": Material(rho, E, 0.2), "base": Material(rho, E, 0.2)}
    else:
        lay = arch_layout(span=2.0, ring_thickness=t, voussoirs=12, abutment_height=0.3,
                          abutment_width=0.4)
        r = 1.0 + t
        point = (r * math.cos(math.radians(135.0)), r * math.sin(math.radians(135.0)))
        direction, rho, E, supports = (0.0, -1.0), 2000.0, E_arch, "abutment:*"
        mats = {"voussoir": Material(rho, E, 0.2), "abutment": Material(rho, 3 * E, 0.2)}
    la = limit_analysis(lay, density=rho, width=1.0, supports=supports,
                        live_loads=[(point, direction)], friction=10.0)
    return lay, la.load_factor, np.array(point), np.array(direction), mats, supports, h


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--case", choices=["rock", "arch"], default="arch")
    ap.add_argument("--control", choices=["load", "displacement"], default="load")
    ap.add_argument("--t", type=float, default=0.2, help="arch ring thickness [m]")
    ap.add_argument("--h", type=float, default=0.2, help="mesh size [m]")
    ap.add_argument("--penalty-factor", type=float, default=20.0)
    ap.add_argument("--E", type=float, default=10e9, help="voussoir Young's modulus [Pa]")
    ap.add_argument("--step", type=float, default=2e-5, help="displacement step [m]")
    ap.add_argument("--refinements", type=int, default=4)
    ap.add_argument("--max-iter", type=int, default=100_000)
    ap.add_argument("--rtol", type=float, default=1e-6)
    ap.add_argument("--damping", choices=["displacement", "velocity"], default="velocity")
    args = ap.parse_args()
    comm = MPI.COMM_WORLD
    lay, p_la, point, direction, mats, supports, h = build(args.case, args.t, args.h, args.E)
    model = Model(lay.mesh(h, comm), mats, width=1.0, comm=comm)
    model.fix_blocks(supports)
    model.add_gravity()
    contact = BlockContact(model, ContactSettings(friction=10.0,
                                                  penalty_factor=args.penalty_factor))
    t0 = time.perf_counter()
    if args.control == "load":
        model.add_point_load(point, direction)
    dr = DynamicRelaxation(model, interactions=contact, rtol=args.rtol, ke_tol=math.inf,
                           max_iter=args.max_iter, damping=args.damping)
    assert dr.solve(0.0).converged
    if args.control == "displacement":  # the platen touches the arch after self-weight
        near = np.hypot(*(model.X - point).T)
        x0 = model.X[int(np.argmin(near))] if near.size else point
        x0 = comm.bcast(x0 if comm.rank == 0 else None, root=0)
        comps = (None, 0.0) if direction[0] == 0 else (0.0, None)
        model.prescribe_nodes(lambda X: np.hypot(X[0] - x0[0], X[1] - x0[1]) < 1e-9, comps,
                              "drive")
        load_nodes = 1 if direction[0] == 0 else 0
        dr = DynamicRelaxation(model, interactions=contact, rtol=args.rtol, ke_tol=math.inf,
                               max_iter=args.max_iter, damping=args.damping)
    status = ""
    if args.control == "load":
        res = dr.load_to_collapse(0.1 * p_la, refinements=args.refinements)
        peak = res.load_factor  # a lower bound: load control ends "not converged"
        status = res.status.describe("N")
    else:
        peak = 0.0
        sign = float(direction[load_nodes])
        # steps from the self-weight position of the driven node
        drive = next(p for p in model.prescriptions if p.name == "drive")
        sel = drive.components == load_nodes
        u_sw = comm.allreduce(float(model.u.x.array[drive.dofs[sel]].sum()))
        u_sw /= max(comm.allreduce(int(sel.sum())), 1)
        for k in range(1, 10_000):
            disp = [None, None]
            disp[load_nodes] = u_sw + sign * k * args.step
            res = dr.solve(0.0, displacement={"drive": tuple(disp)})
            force = sign * dr.reactions()["drive"][load_nodes]
            peak = max(peak, force)
            if comm.rank == 0:
                print(f"  {k * args.step:.2e} m: {force / p_la:.4f} of LP "
                      f"({res.iterations} iterations)", flush=True)
            if not res.converged:
                status = (f"not converged at {k * args.step:.2e} m (carried {peak:.1f} N, a "
                          "lower bound of the collapse load)")
                break
            if force < 0.95 * peak:
                status = f"peak passed: collapse load {peak:.1f} N (the load fell 5 % below it)"
                break
        else:
            status = f"displacement limit reached (carried {peak:.1f} N, a lower bound)"
    if comm.rank == 0:
        print(f"{args.case}, {args.control} control: {status}")
        print(f"FDEM {peak:.1f} N, LP {p_la:.1f} N, ratio {peak / p_la:.4f} "
              f"({time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    main()
