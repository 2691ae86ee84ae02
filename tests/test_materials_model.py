"""Laws side by side in one model: the user-defined law of the materials demo next to the
built-in ones, and the same results on any number of MPI ranks."""

from __future__ import annotations

import runpy
from pathlib import Path

from mpi4py import MPI

import numpy as np

from masonry_fdem import Material, Model
from masonry_fdem.geometry import BlockMesh, crossed_grid
from masonry_fdem.materials import DruckerPrager, MohrCoulomb, RankineDamage
from masonry_fdem.solvers import DynamicRelaxation, ExplicitSolver

ROOT = Path(__file__).resolve().parents[1]
DEMO = runpy.run_path(str(ROOT / "demos" / "materials.py"), run_name="materials_lib")


def test_user_law_carries_the_pier_next_to_the_built_in_laws():
    """The demo's pier on clay, coarse: its neo-Hookean bearing pad (a user law) carries
    the whole pier load into the concrete footing and the Mohr–Coulomb clay."""
    model = DEMO["pier_on_clay"](h=0.25)
    kinds = {type(m).__name__ for m in model.materials.values()}
    assert kinds == {"MohrCoulomb", "Material", "NeoHooke", "RankineDamage"}
    disp, load, dr = DEMO["push"](model, settlement=4e-4, steps=2)
    assert np.all(np.diff(load) > 0)
    # equilibrium through the pad: the mean vertical stress over its cells times its
    # width (0.6 m, 1 m slice) is the load on the pier top
    pad = model.dmesh.cell_material == model.blocks.material_names.index("rubber")
    sigma = model.update_stress().x.array.reshape(-1, 2, 2)[:, 1, 1]
    area = model.blocks.cell_area[model.dmesh.cell_input]
    layer = model.comm.allreduce(float(np.sum(sigma[pad] * area[pad]))) / 0.05
    print(f"\npier on clay: load {load[-1]:.1f} N/m, through the rubber pad {-layer:.1f} N/m")
    assert abs(-layer / load[-1] - 1.0) < 0.02
    assert model.plastic_work() >= 0.0
    fields = model.material_fields()
    assert {"kappa", "damage", "plastic_strain", "plastic_work_density"} <= set(fields)
    masonry = model.dmesh.cell_material == model.blocks.material_names.index("masonry")
    assert np.all(fields["damage"][masonry] >= 0.0) and np.all(fields["damage"] <= 1.0)


def _mixed_blocks():
    """Five 0.1 m squares (crossed 2 × 2 grids), one law each."""
    x, cells = crossed_grid(np.linspace(0, 0.1, 3), np.linspace(0, 0.1, 3))
    xs, cs, cb = [], [], []
    for b in range(5):
        xs.append(x + [0.15 * b, 0.0])
        cs.append(cells + b * len(x))
        cb.append(np.full(len(cells), b))
    names = ["svk", "rubber", "damage", "clay", "visco"]
    return BlockMesh.from_arrays(np.concatenate(xs), np.concatenate(cs), np.concatenate(cb),
                                 block_names=[f"b{b}" for b in range(5)],
                                 material_names=names, block_material=np.arange(5))


MATS = {
    "svk": Material(density=2000.0, E=10e9, nu=0.2),
    "rubber": DEMO["NeoHooke"](density=1100.0, E=20e6, nu=0.45),
    "damage": RankineDamage(density=2000.0, E=10e9, nu=0.2, ft=1e6, Gf=50.0),
    "clay": MohrCoulomb(density=1800.0, E=1e9, nu=0.3, c=1e5, phi=20.0, psi=5.0),
    "visco": DruckerPrager(density=1800.0, E=1e9, nu=0.3, c=1e5, phi=20.0, viscosity=1e7),
}


def _run(comm):
    out = []
    for solver in ("dr", "explicit"):
        m = Model(_mixed_blocks(), MATS, hypothesis="plane_strain", width=0.5, comm=comm)
        m.fix(lambda X: np.isclose(X[1], 0.0), name="base")
        if solver == "dr":
            m.prescribe_nodes(lambda X: np.isclose(X[1], 0.1), (0.0, 0.0), name="top")
            dr = DynamicRelaxation(m, rtol=1e-9, max_iter=100_000)
            for k in range(1, 5):
                dr.solve(0.0, displacement={"top": (4e-5 * k, 2e-5 * k)}, dt=1e-3)
            r = dr.reactions()["top"]
        else:
            m.prescribe_nodes(lambda X: np.isclose(X[1], 0.1), (0.05, 0.02), name="top")
            s = ExplicitSolver(m, damping=1e3)
            s.run(t_end=4e-3)
            r = s.reactions()["top"]
        out.append((m.displacement(), r, m.plastic_work(), m.strain_energy()))
    return out


def test_same_material_response_on_any_number_of_ranks():
    world = _run(MPI.COMM_WORLD)
    alone = _run(MPI.COMM_SELF)
    worst = 0.0
    for (uw, rw, pw, ew), (us, rs, ps, es) in zip(world, alone, strict=True):
        worst = max(worst, np.abs(uw - us).max() / np.abs(us).max(),
                    np.abs(rw - rs).max() / np.abs(rs).max(), abs(pw - ps) / ps,
                    abs(ew - es) / es)
        assert ps > 0  # the plastic laws yielded
    print(f"\nfive laws, {MPI.COMM_WORLD.size} rank(s) vs 1: largest relative difference "
          f"{worst:.2e}")
    assert worst < 1e-10
