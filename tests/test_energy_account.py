"""The explicit solver's energy account closes (issue #23, item 3): kinetic + stored
(elements, contact) + every dissipation (friction, contact dampers, solver damping, damage,
plasticity) − the work of loads and supports = the total at the start, up to a residual.

* an elastic block bouncing flat on a floor (e = 1, no friction): the residual is below
  1e-3 of the energy put through at every apex, and below 3e-3 during the impacts (the
  penalty law is not exactly the gradient of the energy it reports: its contact zone is
  clipped at the facets' corners by an amount that grows with the penetration, an
  O(δ/h) part of the force; without the stores carried to the half step it is ~1.4e-2);
* a block sliding to rest on a floor from v0 under gravity (from where it touches the
  floor, or settled on it first, with energy stored at the start): the friction
  dissipates the kinetic energy ½ m v0² within 1 % and the account closes within 1e-3;
* a bar of damage material and one of Drucker–Prager plasticity pulled apart: the
  elements' dissipation (damage ∫ W̄ Δd, plastic work) closes the account.
"""

from __future__ import annotations

import math

from mpi4py import MPI

import numpy as np
import pytest
from conftest import alternating_grid, rectangle

from masonry_fdem import Material, Model
from masonry_fdem.constants import G
from masonry_fdem.geometry import BlockMesh, mesh_blocks
from masonry_fdem.interactions import BlockContact, ContactSettings
from masonry_fdem.materials import DruckerPrager, RankineDamage
from masonry_fdem.solvers import DynamicRelaxation, ExplicitSolver

comm = MPI.COMM_WORLD


def _block_on_floor(block, friction, restitution=1.0, penalty_factor=0.01, mesh=5.0):
    blocks = mesh_blocks([rectangle(-1.0, -0.2, 2.0, 0.0), block], materials="b",
                         names=["floor", "block"], mesh_size=[5.0, mesh], comm=comm)
    model = Model(blocks, {"b": Material(2000.0, 1e10, 0.2)}, comm=comm)
    model.fix_blocks("floor")
    model.add_gravity()
    contact = BlockContact(model, ContactSettings(friction=friction, restitution=restitution,
                                                  penalty_factor=penalty_factor))
    nodes = np.flatnonzero(model.node_block == 1)
    mass = comm.allreduce(float(model.mass[2 * nodes].sum()))
    return model, contact, nodes, mass


def _momentum(model, nodes, c):
    """The block's momentum, component c [kg m/s] (collective)."""
    return comm.allreduce(float(model.mass[2 * nodes + c] @ model.v[2 * nodes + c]))


def test_elastic_bounce_account_closes():
    """A block dropped flat from 2 cm, e = 1, frictionless: three bounces; the residual
    at the apexes < 1e-3 of the energy put through, during the impacts < 3e-3."""
    h = 0.02
    model, contact, nodes, mass = _block_on_floor(rectangle(-0.1, h, 0.1, h + 0.1), 0.0)
    solver = ExplicitSolver(model, interactions=contact)
    mgh = mass * G * h
    apexes, worst, p_prev = [], 0.0, 0.0
    while len(apexes) < 3:
        solver.run(steps=10)
        acc = solver.energies()
        worst = max(worst, abs(acc.residual) / acc.scale)
        p = _momentum(model, nodes, 1)
        if p_prev > 0.0 >= p:
            apexes.append(acc)
        p_prev = p
        assert solver.t < 1.0
    rel = [abs(a.residual) / a.scale for a in apexes]
    last = apexes[-1]
    print(f"\nbounce: {solver.n} steps, apexes at {[f'{a.exchanged / mgh:.2f}' for a in apexes]}"
          f" mgh put through, residual {[f'{r:.1e}' for r in rel]} of it; worst during the "
          f"impacts {worst:.1e}; kinetic at the last apex {last.kinetic / mgh:.3f} mgh, "
          f"work of gravity {last.external / mgh:+.4f} mgh")
    assert last.exchanged > 5.0 * mgh  # three falls and rises
    assert last.dissipated["contact friction"] == 0.0
    assert max(rel) < 1e-3
    assert worst < 3e-3


@pytest.mark.parametrize("settled", [False, True])
def test_sliding_block_friction_dissipates_the_kinetic_energy(settled):
    """A block launched along a floor at v0 = 0.5 m/s, μ = 0.5, stops after v0/(μ g):
    friction has dissipated ½ m v0² (within 1 %), and the account closes within 1e-3.
    Launched from where it touches the floor, or (``settled``) from rest on it after
    dynamic relaxation: then the contact and the block start with stored energy, which
    the account's initial total holds."""
    v0, mu = 0.5, 0.5
    model, contact, nodes, mass = _block_on_floor(rectangle(0.0, 0.0, 0.2, 0.1), mu,
                                                  mesh=0.1)
    if settled:
        assert DynamicRelaxation(model, interactions=contact).solve(1.0).converged
        held = model.strain_energy() + contact.energies()["stored"]
        assert held > 0.0
    model.v[2 * nodes] = v0
    solver = ExplicitSolver(model, interactions=contact)
    assert solver.energies().initial == pytest.approx(
        0.5 * mass * v0**2 + (held if settled else 0.0), rel=1e-12)
    t_stop = v0 / (mu * G)
    solver.run(t_end=1.25 * t_stop)
    acc = solver.energies()
    ke0 = 0.5 * mass * v0**2
    friction = acc.dissipated["contact friction"]
    print(f"\nslide: stopped by {t_stop:.3f} s, velocity now "
          f"{_momentum(model, nodes, 0) / mass:+.4f} m/s; friction {friction:.5f} J of "
          f"½ m v0² = {ke0:.5f} J ({friction / ke0 - 1:+.2e}); residual "
          f"{acc.residual:+.2e} J ({acc.residual / ke0:+.1e} of ½ m v0²)")
    assert acc.kinetic < 1e-3 * ke0
    assert friction == pytest.approx(ke0, rel=0.01)
    assert abs(acc.residual) < 1e-3 * ke0
    if settled:  # the stores at the start, carried to the half step before the first
        assert acc.initial == pytest.approx(ke0 + held, rel=1e-3)
    else:
        assert acc.initial == pytest.approx(ke0, rel=1e-12)


def _pulled_bar(materials):
    """A 100 × 50 mm bar (50 mm thick) held at its left end and pulled at its right end
    by 0.3 mm at 0.5 m/s, then held: its explicit run, the account at the end."""
    L, D = 0.1, 0.05
    x, cells, col = alternating_grid(L, D, D / 4)
    weak = col == 4
    mesh = BlockMesh.from_arrays(x, cells, np.zeros(len(cells), dtype=np.int64),
                                 block_names=["bar"], material_names=["strong", "weak"],
                                 cell_material=weak.astype(np.int64), mixed_materials=True)
    model = Model(mesh, materials, width=0.05, comm=comm)
    tol = 1e-9
    model.fix(lambda X: np.isclose(X[0], 0.0, atol=tol), components=(0,), name="left")
    model.fix(lambda X: np.isclose(X[0], 0.0, atol=tol) & np.isclose(X[1], 0.0, atol=tol),
              components=(1,), name="pin")
    v, stroke = 0.5, 3e-4
    model.prescribe_nodes(lambda X: np.isclose(X[0], L, atol=tol),
                          lambda t: (v if t < stroke / v else 0.0, None), name="pull")
    solver = ExplicitSolver(model)
    solver.run(t_end=2.0 * stroke / v)
    return solver.energies()


@pytest.mark.parametrize("law", ["damage", "plasticity"])
def test_pulled_bar_account_closes_with_the_elements_dissipation(law):
    """Damage (crack band, one weaker column) or plasticity: the work of the pull goes
    into the elements' dissipation, the strain and kinetic energy left; the residual is
    1e-7 of the work for damage (its dissipation W̄ Δd with W̄ the bilinear energy of the
    strains at both ends of a step) and ~5e-4 for plasticity (the kernel's plastic work
    takes the stress at the end of the step)."""
    if law == "damage":
        mats = {"strong": RankineDamage(2400.0, 30e9, 0.0, ft=3e6, Gf=100.0),
                "weak": RankineDamage(2400.0, 30e9, 0.0, ft=2.9e6, Gf=100.0)}
        tol = 1e-5
    else:
        mats = {"strong": DruckerPrager(2400.0, 30e9, 0.2, c=2e6, phi=30.0),
                "weak": DruckerPrager(2400.0, 30e9, 0.2, c=1.9e6, phi=30.0)}
        tol = 2e-3
    acc = _pulled_bar(mats)
    lost = acc.dissipated["elements"]
    print(f"\n{law}: work of the pull {acc.support:.4f} J, elements dissipated {lost:.4f} J, "
          f"strain {acc.stored['strain']:.4f} J, kinetic {acc.kinetic:.4f} J; residual "
          f"{acc.residual:+.2e} J ({acc.relative_residual:+.1e} of the work)")
    assert acc.support > 0.0 and lost > 0.5 * acc.support
    assert acc.scale >= acc.support  # Σ |work of the step|: the pull also takes some back
    assert abs(acc.residual) < tol * acc.support
    assert math.isfinite(acc.residual)
