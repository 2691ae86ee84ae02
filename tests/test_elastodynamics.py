"""Explicit dynamics of the deformable blocks against analytic values."""

from mpi4py import MPI

import numpy as np
import pytest
from conftest import rectangle

from masonry_fdem import Material, Model, checks
from masonry_fdem.geometry import mesh_blocks
from masonry_fdem.solvers import DynamicRelaxation, ExplicitSolver, UnstableTimeStepError

comm = MPI.COMM_WORLD


def test_lumped_mass_equals_rho_area_width():
    """Total lumped mass = ρ · area · width to 1e-12 (several blocks and materials)."""
    polys = [rectangle(0, 0, 0.3, 0.1), rectangle(0.5, 0, 0.9, 0.25), rectangle(0, 1, 1, 1.2)]
    blocks = mesh_blocks(polys, materials=["brick", "brick", "stone"], mesh_size=0.04, comm=comm)
    mats = {"brick": Material(1800.0, 5e9, 0.2), "stone": Material(2600.0, 30e9, 0.25)}
    width = 0.44
    model = Model(blocks, mats, width=width, comm=comm)
    expected = width * (1800.0 * (0.03 + 0.1) + 2600.0 * 0.2)
    print(f"lumped mass {model.total_mass():.15g} kg vs rho A w {expected:.15g} kg "
          f"({abs(model.total_mass() / expected - 1):.1e} relative)")
    assert model.total_mass() == pytest.approx(expected, rel=1e-12)
    # and per block, from the mesh areas
    assert np.sum(blocks.block_area) == pytest.approx(0.33, rel=1e-12)


def test_wave_speed_in_long_bar():
    """Plane stress, ν = 0: a step load travels at c = √(E/ρ) within 1 %."""
    E, rho = 1.0e6, 1.0
    c = np.sqrt(E / rho)  # 1000 m/s
    L, H, h = 10.0, 0.1, 0.025
    blocks = mesh_blocks([rectangle(0, 0, L, H)], materials="bar", mesh_size=h, comm=comm)
    with checks.expert("density"):  # a unit bar (1 kg/m³), on purpose
        bar = Material(rho, E, 0.0)
    model = Model(blocks, {"bar": bar}, comm=comm)
    sigma = 1.0e3  # applied traction [Pa] -> particle velocity σ/(ρc) = 1 m/s
    model.add_line_load(lambda x: np.isclose(x[0], 0.0), (sigma * model.width, 0.0))
    stations = (2.5, 7.5)
    for k, xs in enumerate(stations):
        model.monitor(f"s{k}", (xs, H / 2))
    solver = ExplicitSolver(model)
    v_star = sigma / (rho * c)
    times, vel = [], []
    nodes = {}
    for name, (owner, node) in model.monitors.items():
        nodes[name] = (owner, node)

    def sample(s):
        vals = []
        for owner, node in nodes.values():
            val = s.model.v[2 * node] if comm.rank == owner else None
            vals.append(comm.bcast(val, root=owner))
        times.append(s.t - 0.5 * s.dt)  # v is the half-step velocity
        vel.append(vals)

    solver.run(t_end=0.95 * L / c, every=1, callback=sample)
    times = np.asarray(times)
    vel = np.asarray(vel)
    arrivals = []
    for k in range(2):
        i = int(np.argmax(vel[:, k] >= 0.5 * v_star))
        assert i > 0, "the wave never reached the station"
        t0, t1, v0, v1 = times[i - 1], times[i], vel[i - 1, k], vel[i, k]
        arrivals.append(t0 + (0.5 * v_star - v0) * (t1 - t0) / (v1 - v0))
    c_measured = (stations[1] - stations[0]) / (arrivals[1] - arrivals[0])
    print(f"wave speed: measured {c_measured:.2f} m/s, sqrt(E/rho) = {c:.2f} m/s "
          f"({100 * (c_measured / c - 1):+.3f} %)")
    assert c_measured == pytest.approx(c, rel=0.01)
    # the plateau behind the front is the analytic particle velocity
    assert vel[-1, 0] == pytest.approx(v_star, rel=0.05)


def test_rigid_rotation_is_stress_free():
    """A block spun rigidly through 90° keeps |σ| < 1e-6 E (St. Venant–Kirchhoff)."""
    E, rho = 1.0e9, 2000.0
    blocks = mesh_blocks([rectangle(-0.5, -0.25, 0.5, 0.25)], materials="b", mesh_size=0.25,
                         comm=comm)
    model = Model(blocks, {"b": Material(rho, E, 0.2)}, comm=comm)
    R = np.sqrt(0.5**2 + 0.25**2)
    omega = np.sqrt(1e-8 * E / rho) / R  # centrifugal stress ~ 1e-8 E
    X = model.X
    model.v[0::2] = -omega * X[:, 1]
    model.v[1::2] = omega * X[:, 0]
    solver = ExplicitSolver(model)
    peak = []

    def check(s):
        s.model.update_stress()
        local = np.abs(s.model.stress.x.array).max(initial=0.0)
        peak.append(comm.allreduce(local, op=MPI.MAX))

    solver.run(t_end=0.5 * np.pi / omega, every=2000, callback=check)
    u = model.displacement()
    # the block turned through 90°: the corner (0.5, 0.25) went to (-0.25, 0.5)
    corner = np.flatnonzero(np.all(np.isclose(blocks.x, [0.5, 0.25]), axis=1))[0]
    assert blocks.x[corner] + u[corner] == pytest.approx([-0.25, 0.5], abs=0.01)
    print(f"rigid rotation through 90 deg: max |sigma| / E = {max(peak) / E:.2e}")
    assert max(peak) < 1e-6 * E


def test_time_step_above_stable_is_refused():
    blocks = mesh_blocks([rectangle(0, 0, 1, 0.5)], materials="b", mesh_size=0.1, comm=comm)
    model = Model(blocks, {"b": Material(2000.0, 1e9, 0.2)}, comm=comm)
    dt_crit = model.stable_time_step()
    # sanity: the bound is below the CFL estimate h/c of the smallest altitude (P1 lumped)
    assert 0 < dt_crit < 0.1 / model.materials["b"].wave_speed(model.hypothesis)
    with pytest.raises(UnstableTimeStepError, match="exceeds the stable time step"):
        ExplicitSolver(model, dt=1.01 * dt_crit)
    ExplicitSolver(model, dt=0.99 * dt_crit)  # accepted
    with pytest.raises(ValueError, match="time step must be > 0"):
        ExplicitSolver(model, dt=-1.0)


def test_free_vibration_conserves_energy():
    """Undamped cantilever released from a static deflection: the total energy (exact
    strain energy + kinetic) drifts less than 0.5 % over 10 periods."""
    L, H = 2.0, 0.2
    blocks = mesh_blocks([rectangle(0, 0, L, H)], materials="b", mesh_size=0.05, comm=comm)
    model = Model(blocks, {"b": Material(2000.0, 1e9, 0.2)}, comm=comm)
    model.fix(lambda X: X[0] < 1e-9)
    model.add_point_load((L, H), (0.0, -2.0e3))
    model.monitor("tip", (L, H / 2))
    DynamicRelaxation(model, rtol=1e-8).solve(1.0)
    e0 = model.strain_energy()
    assert e0 > 0
    solver = ExplicitSolver(model, load_factor=0.0)
    t, tip, energy = [], [], []
    v_prev = model.v.copy()
    # f1 of a clamped beam: (1.875²/2π) √(EI/(ρ A L⁴))
    f1 = 1.875**2 / (2 * np.pi) * np.sqrt(1e9 * H**2 / 12 / 2000.0) / L**2
    n_steps = int(np.ceil(10.5 / f1 / solver.dt))
    every = 20
    for k in range(n_steps):
        sample = k % every == 0
        if sample:  # state at step n: u(n), v(n-1/2)
            v_prev[:] = model.v
            strain = model.strain_energy()
            t.append(solver.t)
            tip.append(model.monitor_values()["tip"][1])
        solver.step()
        if sample:  # v(n) = (v(n-1/2) + v(n+1/2)) / 2
            energy.append(strain + model.kinetic_energy(0.5 * (v_prev + model.v)))
    tip = np.asarray(tip)
    energy = np.asarray(energy)
    t = np.asarray(t)
    # at least 10 periods were simulated (count upward zero crossings of the tip)
    crossings = np.flatnonzero((tip[:-1] < 0) & (tip[1:] >= 0))
    assert crossings.size >= 9
    period = np.mean(np.diff(t[crossings]))
    assert 1 / period == pytest.approx(f1, rel=0.1)  # thick beam, coarse mesh: Timoshenko
    drift = np.abs(energy - e0).max() / e0
    print(f"free vibration: {crossings.size} periods, f = {1 / period:.3f} Hz "
          f"(Euler-Bernoulli {f1:.3f} Hz), max |E - E0| / E0 = {drift:.2e}")
    assert drift < 0.005


def test_dynamic_relaxation_reports_no_equilibrium_for_free_block():
    """A block with no support under gravity cannot be in equilibrium: DR says so."""
    blocks = mesh_blocks([rectangle(0, 0, 1, 0.5)], materials="b", mesh_size=0.5, comm=comm)
    model = Model(blocks, {"b": Material(2000.0, 1e9, 0.2)}, comm=comm)
    model.add_gravity()
    res = DynamicRelaxation(model, max_iter=300).load_steps([0.5, 1.0])
    assert len(res) == 1 and not res[0].converged and res[0].iterations == 300
