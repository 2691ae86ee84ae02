"""Crack band: a bar pulled apart cracks across one band of elements; the energy it
dissipates per unit crack area equals the fracture energy G_f, whatever the element size.

A 100 × 50 mm bar (plane stress, 50 mm thick) of Rankine-damage concrete, on a structured
mesh of squares halved by alternating diagonals, with a column of squares at mid-length
3 % weaker so that the crack forms there. Displacement control by dynamic relaxation;
dissipation = external work − elastic energy left at the end.
"""

from __future__ import annotations

from mpi4py import MPI

import numpy as np
import pytest
from conftest import alternating_grid

from masonry_fdem import Model
from masonry_fdem.geometry import BlockMesh
from masonry_fdem.materials import RankineDamage
from masonry_fdem.solvers import DynamicRelaxation

L, D, T = 0.1, 0.05, 0.05  # bar length, depth, thickness [m]
CONCRETE = dict(density=2400.0, E=30e9, Gf=100.0)
FT = 3e6


def bar(h: float) -> BlockMesh:
    x, cells, col = alternating_grid(L, D, h)
    weak = col == round(L / h) // 2
    return BlockMesh.from_arrays(x, cells, np.zeros(len(cells), dtype=np.int64),
                                 block_names=["bar"],
                                 material_names=["concrete", "weak"],
                                 cell_material=weak.astype(np.int64), mixed_materials=True)


def pull(h: float, nu: float):
    """Dissipated energy per crack area [J/m²], peak stress [Pa], final/peak load."""
    mats = {"concrete": RankineDamage(**CONCRETE, nu=nu, ft=FT),
            "weak": RankineDamage(**CONCRETE, nu=nu, ft=0.97 * FT)}
    m = Model(bar(h), mats, width=T)
    tol = 1e-9
    m.fix(lambda X: np.isclose(X[0], 0.0, atol=tol), components=(0,), name="left")
    m.fix(lambda X: np.isclose(X[0], 0.0, atol=tol) & np.isclose(X[1], 0.0, atol=tol),
          components=(1,), name="pin")
    m.prescribe_nodes(lambda X: np.isclose(X[0], L, atol=tol), (0.0, None), name="pull")
    dr = DynamicRelaxation(m, rtol=1e-6, max_iter=200_000)
    e0 = FT / CONCRETE["E"]
    w_s = CONCRETE["Gf"] / FT  # crack-opening scale of the exponential softening [m]
    d_peak = 0.97 * e0 * L
    path = np.r_[np.linspace(0.25, 1.0, 4) * d_peak, d_peak + w_s * np.geomspace(0.02, 9.0, 30)]
    disp, force = [0.0], [0.0]
    for d in path:
        res = dr.solve(0.0, displacement={"pull": (d, None)})
        assert res.converged, res
        disp.append(d)
        force.append(dr.reactions()["pull"][0])
    disp, force = np.array(disp), np.array(force)
    work = float(np.sum(0.5 * (force[1:] + force[:-1]) * np.diff(disp)))
    dissipated = work - m.strain_energy()
    kappa = m.history("kappa")
    cracked = m.comm.allreduce(int(np.sum(kappa > 2 * e0)))
    return dissipated / (D * T), force.max() / (D * T), force[-1] / force.max(), cracked


@pytest.mark.skipif(MPI.COMM_WORLD.size > 1, reason="one process (the suite's budget: 9 s "
                    "under mpirun); the damage law on two ranks is compared with one in "
                    "test_materials_model.py::test_same_material_response_on_any_number_of_ranks")
@pytest.mark.parametrize("nu", [0.0, 0.2])
def test_crack_band_dissipates_the_fracture_energy_on_any_mesh(nu):
    """With ν = 0 the band is in uniaxial stress and the law gives G_f exactly; with
    ν = 0.2 the unloading neighbours hold the band laterally, which changes its path
    slightly (a few per cent less energy)."""
    g1, s1, r1, n1 = pull(D / 4, nu)
    g2, s2, r2, n2 = pull(D / 8, nu)
    Gf = CONCRETE["Gf"]
    print(f"\ncrack band, nu = {nu}: h = {1e3 * D / 4:.2f} mm: {g1:.2f} J/m2 ({g1 / Gf - 1:+.2%}), "
          f"peak {s1 / 1e6:.3f} MPa, {n1} cracked cells; h = {1e3 * D / 8:.2f} mm: "
          f"{g2:.2f} J/m2 ({g2 / Gf - 1:+.2%}), peak {s2 / 1e6:.3f} MPa, {n2} cracked cells; "
          f"meshes differ by {g2 / g1 - 1:+.2%}")
    for g, s, r, n, ny in ((g1, s1, r1, n1, 4), (g2, s2, r2, n2, 8)):
        assert abs(g / Gf - 1.0) < 0.05
        assert s == pytest.approx(0.97 * FT, rel=0.01)  # the weak band's strength
        assert r < 0.01  # fully softened
        assert n == 2 * ny  # one band of cells across the bar, nothing else
    assert abs(g2 / g1 - 1.0) < 0.05
