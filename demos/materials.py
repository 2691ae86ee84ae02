"""A strip footing on clay carrying a masonry pier through a rubber bearing pad: four
constitutive laws in ONE model and ONE compiled form, one of them written by the user.

* clay: Mohr–Coulomb with φ = 0 (Tresca, undrained), c = 20 kPa, meshed with crossed
  triangles (P1 without locking in isochoric plastic flow);
* footing: St. Venant–Kirchhoff concrete (the default law);
* bearing pad: a compressible neo-Hookean rubber, the user-defined law below (a few lines
  of UFL, written outside the package);
* pier: brick masonry as Rankine damage with crack-band softening.

The pier top is pushed down by dynamic relaxation under displacement control. The clay
fails in the Prandtl mechanism: the load levels off at the bearing capacity
(2 + π) c B per metre. Writes ``load_settlement.png``, ``history.csv`` and ParaView files
to ``--out``.

Run: ``mpirun -n 2 python demos/materials.py --out out_materials``.
"""

from __future__ import annotations

import argparse
import math
import time
from dataclasses import dataclass
from pathlib import Path

from mpi4py import MPI

import numpy as np
import ufl

from masonry_fdem import Material, Model
from masonry_fdem.materials import MohrCoulomb, RankineDamage


@dataclass(frozen=True)
class NeoHooke(Material):
    """Compressible neo-Hookean solid (plane strain): P = μ (F − F⁻ᵀ) + λ ln J F⁻ᵀ [Pa],
    with μ, λ from E and ν. A user-defined law: nothing in the package changes."""

    def first_piola(self, k):
        F = k.F
        Finv_T = ufl.inv(F).T
        return k.mu * (F - Finv_T) + k.lam * ufl.ln(ufl.det(F)) * Finv_T

    def energy_density(self, k):
        J = ufl.det(k.F)
        return (0.5 * k.mu * (ufl.tr(k.F.T * k.F) - 2) - k.mu * ufl.ln(J)
                + 0.5 * k.lam * ufl.ln(J) ** 2)


MATERIALS = {
    "clay": MohrCoulomb(density=1800.0, E=500e6, nu=0.3, c=20e3, phi=0.0),
    "concrete": Material(density=2400.0, E=30e9, nu=0.2),
    "rubber": NeoHooke(density=1100.0, E=20e6, nu=0.45),
    "masonry": RankineDamage(density=1900.0, E=3e9, nu=0.2, ft=0.25e6, Gf=20.0),
}
B = 1.0  # footing width [m]


def pier_on_clay(h: float = 0.1, comm=MPI.COMM_WORLD):
    """The model (plane strain, 1 m slice), symmetric about x = 0."""
    from masonry_fdem.geometry import BlockMesh, crossed_grid, graded

    half_soil, depth = 3.0 * B, 2.0 * B
    # refined towards the footing edges, where the plastic zone starts (a singular point)
    n_in = max(2, round(0.5 * B / h))
    inner = graded(0.0, 0.5 * B, n_in, 0.3)
    edge = inner[-1] - inner[-2]
    n_out = n_in + 3
    outer = graded(0.5 * B, half_soil, n_out, (half_soil - 0.5 * B) / n_out / edge * 2)
    xs = np.r_[inner, outer[1:]]
    xs = np.r_[-xs[:0:-1], xs]
    # layers: soil, footing 0.3 m, pad 0.05 m, pier 1.0 m
    ys = np.r_[graded(-depth, 0.0, round(depth / h) + 2, 0.15), [0.15, 0.3, 0.35],
               np.linspace(0.35, 1.35, round(1.0 / h) + 1)[1:]]
    x, cells = crossed_grid(xs, ys)
    c = x[cells].mean(axis=1)
    ax = np.abs(c[:, 0])
    mat = np.full(len(cells), -1)
    mat[c[:, 1] < 0] = 0
    mat[(c[:, 1] > 0) & (c[:, 1] < 0.3) & (ax < 0.5 * B)] = 1
    mat[(c[:, 1] > 0.3) & (c[:, 1] < 0.35) & (ax < 0.3 * B)] = 2
    mat[(c[:, 1] > 0.35) & (ax < 0.3 * B)] = 3
    keep = mat >= 0
    blocks = BlockMesh.from_arrays(x, cells[keep], np.zeros(keep.sum(), dtype=np.int64),
                                   block_names=["pier_on_clay"],
                                   material_names=["clay", "concrete", "rubber", "masonry"],
                                   cell_material=mat[keep], mixed_materials=True)
    model = Model(blocks, MATERIALS, hypothesis="plane_strain", width=1.0, comm=comm)
    tol = 1e-9
    model.fix(lambda X: np.isclose(X[1], -depth, atol=tol), name="base")
    model.fix(lambda X: np.isclose(np.abs(X[0]), half_soil, atol=tol), components=(0,),
              name="sides")
    model.prescribe_nodes(lambda X: np.isclose(X[1], ys[-1], atol=tol), (0.0, 0.0), name="top")
    return model


def push(model, settlement: float = 0.0015, steps: int = 12, callback=None):
    """Settlement [m] of the pier top by dynamic relaxation; (settlement, load [N]) arrays."""
    from masonry_fdem.solvers import DynamicRelaxation

    dr = DynamicRelaxation(model, rtol=1e-5, max_iter=100_000)
    disp, load = [0.0], [0.0]
    for i in range(1, steps + 1):
        d = settlement * i / steps
        res = dr.solve(0.0, displacement={"top": (0.0, -d)})
        disp.append(d)
        load.append(-dr.reactions()["top"][1])
        if callback is not None:
            callback(i, res, d, load[-1])
    return np.array(disp), np.array(load), dr


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="out_materials")
    ap.add_argument("--h", type=float, default=0.1, help="mesh size under the footing [m]")
    ap.add_argument("--steps", type=int, default=12)
    args = ap.parse_args()
    comm = MPI.COMM_WORLD
    out = Path(args.out)
    t0 = time.perf_counter()
    model = pier_on_clay(args.h, comm)
    qu = (2.0 + math.pi) * MATERIALS["clay"].c * B
    if comm.rank == 0:
        print(f"{model}; Prandtl bearing capacity (2 + pi) c B = {qu / 1e3:.1f} kN/m")

    def report(i, res, d, f):
        if comm.rank == 0:
            print(f"  settlement {1e3 * d:5.1f} mm: load {f / 1e3:7.1f} kN/m "
                  f"({f / qu:5.3f} of Prandtl), {res.iterations} DR iterations")

    disp, load, dr = push(model, steps=args.steps, callback=report)
    kappa = model.history("kappa")
    damaged = comm.allreduce(int(np.sum(kappa[np.isfinite(kappa)] > MATERIALS["masonry"].eps0)))
    if comm.rank == 0:
        out.mkdir(parents=True, exist_ok=True)
        np.savetxt(out / "history.csv", np.c_[disp, load], delimiter=",",
                   header="settlement_m,load_N_per_m", comments="")
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(6, 4))
        ax.plot(1e3 * disp, load / 1e3, "o-", label="masonry_fdem")
        ax.axhline(qu / 1e3, color="k", ls="--", label="Prandtl (2 + π) c B")
        ax.set_xlabel("settlement of the pier top [mm]")
        ax.set_ylabel("load [kN/m]")
        ax.legend()
        fig.tight_layout()
        fig.savefig(out / "load_settlement.png", dpi=120)
        print(f"final load {load[-1] / 1e3:.1f} kN/m = {load[-1] / qu:.3f} of Prandtl; "
              f"{damaged} damaged masonry cells; {time.perf_counter() - t0:.1f} s")
    from masonry_fdem.io import VTXOutput

    with VTXOutput(model, out) as vtx:
        vtx.write(0.0)


if __name__ == "__main__":
    main()
