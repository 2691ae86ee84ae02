"""Cost of the block laws: one internal-force evaluation per law against the default
St. Venant–Kirchhoff law on the same mesh (same process, medians of interleaved rounds).

The mesh is a crossed grid of P1 triangles (one quadrature point each). For each law the
displacement is a random field of about 10x the yield strain, so that the return mappings
do real work; the committed state is virgin each call (a trial evaluation, as dynamic
relaxation does every iteration). Prints ns per cell and the ratio to St. Venant–Kirchhoff.
Run: ``python benchmarks/material_cost.py [--cells 2e4]``.
"""

import argparse
import statistics
import time

import numpy as np

import masonry_fdem  # noqa: F401
from masonry_fdem import Material, Model
from masonry_fdem.geometry import BlockMesh, crossed_grid
from masonry_fdem.materials import DruckerPrager, MohrCoulomb, RankineDamage

LAWS = {
    "St. Venant–Kirchhoff": Material(density=2000.0, E=10e9, nu=0.2),
    "Rankine damage": RankineDamage(density=2000.0, E=10e9, nu=0.2, ft=1e6, Gf=100.0),
    "Mohr–Coulomb": MohrCoulomb(density=2000.0, E=10e9, nu=0.2, c=1e6, phi=30.0, psi=5.0),
    "Drucker–Prager": DruckerPrager(density=2000.0, E=10e9, nu=0.2, c=1e6, phi=30.0),
    "Perzyna (DP)": DruckerPrager(density=2000.0, E=10e9, nu=0.2, c=1e6, phi=30.0,
                                  viscosity=1e6),
}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cells", type=float, default=2e4)
    ap.add_argument("--hypothesis", default="plane_strain")
    args = ap.parse_args()
    n = max(2, int(round(np.sqrt(args.cells / 4))))
    x, cells = crossed_grid(np.linspace(0, 1, n + 1), np.linspace(0, 1, n + 1))
    blocks = BlockMesh.from_arrays(x, cells, np.zeros(len(cells), dtype=np.int64),
                                   block_names=["b"], material_names=["m"])
    rng = np.random.default_rng(0)
    models = {}
    for name, law in LAWS.items():
        m = Model(blocks, {"m": law}, hypothesis=args.hypothesis)
        m.rate_time_step = 1e-4
        m.u.x.array[:] = 1e-3 / n * rng.standard_normal(m.u.x.array.size)
        models[name] = m
    fns = [m.internal_force for m in models.values()]
    for f in fns:
        f()
    samples = [[] for _ in fns]
    reps = max(3, int(2e6 / blocks.n_cells))
    for _ in range(9):
        for k, f in enumerate(fns):
            t0 = time.perf_counter()
            for _ in range(reps):
                f()
            samples[k].append((time.perf_counter() - t0) / reps)
    med = [statistics.median(s) for s in samples]
    print(f"{blocks.n_cells} cells, {args.hypothesis}; internal force, median of 9 rounds")
    for (name, m), t in zip(models.items(), med, strict=True):
        plastic = ""
        if m.qstate.has_return_mapping:
            frac = float(np.mean(m.qstate.s1[:, 4] > 0))
            plastic = f", {frac:.0%} of the points yield"
        print(f"  {name:22s} {1e9 * t / blocks.n_cells:7.1f} ns/cell  "
              f"x{t / med[0]:5.2f} of St. Venant–Kirchhoff{plastic}")


if __name__ == "__main__":
    main()
