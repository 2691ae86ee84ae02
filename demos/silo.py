"""Silo discharge (the reference paper's Figure 2b): granular fill of rigid disks flowing
out of a hopper of deformable blocks.

A V-shaped hopper (two concrete walls at 60° to the horizontal, outlet width D) is filled
with a polydisperse packing of disks, which settles under gravity on a gate under the
outlet. The gate is then pulled aside and the fill flows out onto a floor below. The discharged mass is
recorded and its rate over the steady part of the flow is printed, next to the
two-dimensional Beverloo estimate W = C ρ_b √g (D − k d)^{3/2} (C ≈ 1.0, k ≈ 1.5; ρ_b the
bulk density per unit thickness, d the mean diameter) as an order-of-magnitude check,
and so is the energy account of the whole run (kinetic, the contacts' stored energy, the
disks' restitution, friction and rolling losses, the disk–wall contacts' friction and
damping, the damping of the settling stage, the work of gravity and of the gate's
drive, and the residual).
Writes ``history.csv``, ``discharge.png``, ``silo_*.png`` pictures and ParaView files
(``disks.pvd``; blocks in ``displacement.bp``) to ``--out``.

Run: ``mpirun -n 2 python demos/silo.py --out out_silo``.
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

from mpi4py import MPI

import numpy as np

from masonry_fdem import Material, Model
from masonry_fdem.interactions import DiskBlockContact
from masonry_fdem.interactions.disks import DiskMaterial, Disks
from masonry_fdem.geometry import mesh_blocks
from masonry_fdem.interactions.disks.packing import pack_disks
from masonry_fdem.solvers import ExplicitSolver

W = 0.05  # out-of-plane thickness [m]
GRAIN = DiskMaterial(density=2600.0, E=5e7, nu=0.25, friction=0.4, restitution=0.3)


def hopper(outlet: float = 0.07, height: float = 0.4, comm=MPI.COMM_WORLD):
    """The model (two walls and a gate) and the fill region (polygon) [m]."""
    t = 0.02  # wall thickness
    run = height / math.tan(math.radians(60.0))
    a = 0.5 * outlet
    left = np.array([[-a - t, 0.0], [-a, 0.0], [-a - run, height], [-a - run - t, height]])
    right = np.array([[a, 0.0], [a + t, 0.0], [a + run + t, height], [a + run, height]])
    gate = np.array([[-a - 0.02, -0.03], [a + 0.02, -0.03], [a + 0.02, -0.005],
                     [-a - 0.02, -0.005]])
    floor = np.array([[-0.6, -0.5], [0.6, -0.5], [0.6, -0.47], [-0.6, -0.47]])
    blocks = mesh_blocks([left, right, gate, floor], materials="concrete", mesh_size=0.03,
                         names=["left", "right", "gate", "floor"], comm=comm)
    model = Model(blocks, {"concrete": Material(density=2400.0, E=3e9, nu=0.2)}, width=W,
                  comm=comm)
    model.fix_blocks(["left", "right"], name="hopper")
    model.fix_blocks("floor", name="floor")
    # fill region: inside the V, a little clear of the walls, above the gate
    g = 0.003
    fill = np.array([[-a + g, 0.0], [a - g, 0.0], [a + run - g, height], [-a - run + g, height]])
    return model, fill


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="out_silo")
    ap.add_argument("--radius", type=float, default=0.005, help="mean disk radius [m]")
    ap.add_argument("--height", type=float, default=0.35, help="fill height [m]")
    ap.add_argument("--time", type=float, default=0.8, help="flow time after opening [s]")
    args = ap.parse_args()
    comm = MPI.COMM_WORLD
    out = Path(args.out)
    t0 = time.perf_counter()
    outlet = 0.07
    model, fill = hopper(outlet, args.height, comm)
    r0 = args.radius
    x, r = pack_disks(fill, 0.8 * r0, 1.2 * r0, 0.35, seed=7)
    disks = Disks(x, r, {"grain": GRAIN}, "grain", width=W, comm=comm)
    disks.add_gravity()
    coupling = DiskBlockContact(disks, model, damping_ratio=0.3)
    gate = model.prescribe_velocity("gate", lambda t: (0.0, 0.0), name="gate")
    # 1. settle on the closed gate (damped)
    s = ExplicitSolver(model, interactions=[disks, coupling], damping=10.0)
    s.run(t_end=0.25, every=2000)
    # 2. open: the gate slides aside at 2 m/s; flow undamped
    t_open = s.t
    gate.velocity = lambda t: (2.0 if t_open < t < t_open + 0.2 else 0.0, 0.0)
    s.damping = 0.0
    total = float(disks.m.sum())
    times, out_mass = [], []
    frames = []

    def record(solver):
        times.append(solver.t - t_open)
        out_mass.append(float(disks.m[disks.x[:, 1] < -0.01].sum()))

    for k in range(4):
        s.run(t_end=t_open + args.time * (k + 1) / 4, every=200, callback=record)
        frames.append((s.t - t_open, disks.x.copy()))
        if k == 1:
            from masonry_fdem.io import plot_blocks

            plot_blocks(model, out / "silo_flowing.png", field="block", disks=disks,
                        title=f"silo, {s.t - t_open:.2f} s after opening")
    times, out_mass = np.array(times), np.array(out_mass)
    energy = s.energies()  # collective
    # steady discharge: fit between 20 % and 70 % of the discharged mass at the end
    lo, hi = 0.2 * out_mass[-1], 0.7 * out_mass[-1]
    sel = (out_mass >= lo) & (out_mass <= hi)
    rate = float(np.polyfit(times[sel], out_mass[sel], 1)[0]) if sel.sum() > 3 else float("nan")
    rho_b = GRAIN.density * W * (1.0 - 0.2)  # bulk density per unit thickness x thickness
    d_mean = 2.0 * float(r.mean())
    beverloo = 1.0 * rho_b / W * math.sqrt(9.81) * max(outlet - 1.5 * d_mean, 0.0) ** 1.5 * W
    if comm.rank == 0:
        print(f"{disks.n} disks (r = {r.min() * 1e3:.1f}..{r.max() * 1e3:.1f} mm, "
              f"{total:.3f} kg), outlet {outlet * 1e3:.0f} mm; dt = {s.dt:.3g} s, "
              f"{s.n} steps, {disks.rebuilds} pair rebuilds")
        print(f"discharge rate {rate:.3f} kg/s (Beverloo 2D estimate {beverloo:.3f} kg/s); "
              f"{out_mass[-1] / total:.0%} discharged after {args.time:.2f} s; "
              f"{time.perf_counter() - t0:.1f} s")
        print(energy.summary())
        print(f"energy residual {energy.residual:.3e} J: "
              f"{100 * energy.relative_residual:.4f} % of the work done "
              f"({energy.scale:.4g} J)")
        out.mkdir(parents=True, exist_ok=True)
        np.savetxt(out / "history.csv", np.c_[times, out_mass], delimiter=",",
                   header="time_after_opening_s,discharged_mass_kg", comments="")
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(6, 4))
        ax.plot(times, out_mass, "-")
        ax.set_xlabel("time after opening [s]")
        ax.set_ylabel("discharged mass [kg]")
        ax.set_title(f"silo discharge: {rate:.3f} kg/s")
        fig.tight_layout()
        fig.savefig(out / "discharge.png", dpi=120)
        plt.close(fig)
    from masonry_fdem.io import DiskOutput, plot_blocks

    plot_blocks(model, out / "silo_final.png", field="block", disks=disks,
                title=f"silo, {args.time:.2f} s after opening")
    DiskOutput(disks, out).write(s.t)


if __name__ == "__main__":
    main()
