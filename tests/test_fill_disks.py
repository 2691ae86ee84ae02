"""Disk fill at rest (issue #22): the averaged (Love–Weber) stress of a disk assembly against
analytic values, Cundall's local damping, and the vertical stress at depth in a wide fill
settled to an unbalanced-force ratio, against the weight of the overburden."""

from __future__ import annotations

import math
import time

from mpi4py import MPI

import numpy as np
import pytest
from conftest import rectangle

from masonry_fdem import Material, Model
from masonry_fdem.constants import G
from masonry_fdem.geometry import mesh_blocks
from masonry_fdem.interactions.disks import DiskMaterial, Disks
from masonry_fdem.interactions.disks import _kernels as DK
from masonry_fdem.solvers import ExplicitSolver

W = 0.05  # out-of-plane thickness [m]
GRAVEL = dict(density=2600.0, E=1e9, nu=0.25, friction=0.5)
ALPHA = 0.7  # Cundall's local damping coefficient of the settling test


def _hertz(r, delta):
    """F = K δ^{3/2} of two equal GRAVEL disks of radius r [m] (written out, not the
    kernel): K = w/(2r) · 4/3 · E* √(r/2), E* = E / (2 (1 − ν²))."""
    e_star = GRAVEL["E"] / (2.0 * (1.0 - GRAVEL["nu"] ** 2))
    return W / (2 * r) * 4.0 / 3.0 * e_star * math.sqrt(r / 2) * delta**1.5


def test_stress_of_two_pressed_disks():
    """Two disks overlapping by δ along x: σ_xx = −F ℓ/(A w) for a cell holding both
    centres (ℓ the distance of the centres), −F (r − δ/2)/(A w) for one holding one."""
    r, delta = 0.01, 1e-5
    disks = Disks([[0.0, 0.0], [2 * r - delta, 0.0]], [r, r], {"g": DiskMaterial(**GRAVEL)},
                  "g", width=W, comm=MPI.COMM_SELF)
    f = _hertz(r, delta)
    both = disks.cell_stress((-0.02, -0.01), (0.04, 0.01))
    one = disks.cell_stress((-0.02, -0.01), (0.015, 0.01))
    print(f"\ntwo pressed disks, F = {f:.4f} N: σ_xx {both[0, 0]:.3f} Pa (both centres), "
          f"{one[0, 0]:.3f} Pa (one)")
    assert both[0, 0] == pytest.approx(-f * (2 * r - delta) / (0.06 * 0.02 * W), rel=1e-9)
    assert one[0, 0] == pytest.approx(-f * (r - delta / 2) / (0.035 * 0.02 * W), rel=1e-9)
    assert np.abs(both.ravel()[1:]).max() < 1e-9 * abs(both[0, 0])
    assert disks.bulk_density((-0.02, -0.01), (0.04, 0.01)) == pytest.approx(
        2 * 2600.0 * math.pi * r * r / (0.06 * 0.02), rel=1e-12)
    for lo, hi in (((0, 0), (0, 1)), ((0, 1), (1, 0)), ((0, 0), (1, np.nan)), ((0,), (1, 1))):
        with pytest.raises(ValueError):
            disks.cell_stress(lo, hi)
        with pytest.raises(ValueError):
            disks.bulk_density(lo, hi)


def test_stress_of_a_square_lattice_under_uniaxial_load():
    """Columns of disks pressed vertically by F each (spacing s_x, no horizontal contact):
    the uniaxial stress σ_yy = −F/(s_x w) exactly, in any cell of whole lattice cells,
    whatever the cell's edges cut; σ_xx = σ_xy = 0."""
    r, delta, gap = 0.005, 2e-6, 1e-4
    sx, sy = 2 * r + gap, 2 * r - delta
    i, j = np.meshgrid(np.arange(12), np.arange(10), indexing="ij")
    x = np.c_[i.ravel() * sx, j.ravel() * sy]
    disks = Disks(x, np.full(len(x), r), {"g": DiskMaterial(**GRAVEL)}, "g", width=W,
                  comm=MPI.COMM_SELF)
    f = _hertz(r, delta)
    p = -f / (sx * W)
    for lo, hi in (((1.5, 1.5), (9.5, 7.5)), ((2.5, 3.5), (3.5, 4.5)), ((0.7, 1.2), (10.7, 8.2))):
        sig = disks.cell_stress(np.array(lo) * [sx, sy], np.array(hi) * [sx, sy])
        print(f"\nsquare lattice, cell {lo}..{hi} lattice cells: σ_yy {sig[1, 1]:.4f} Pa "
              f"(analytic {p:.4f}), σ_xx {sig[0, 0]:.1e}, σ_xy {sig[0, 1]:.1e}")
        assert sig[1, 1] == pytest.approx(p, rel=1e-9)
        assert np.abs([sig[0, 0], sig[0, 1], sig[1, 0]]).max() < 1e-9 * abs(p)


def test_stress_kernels_against_a_loop():
    """Pair forces rebuild the forces of the last evaluation (friction included), and the
    cell stress equals the sum over disks written as a loop."""
    rng = np.random.default_rng(7)
    n = 60
    x = rng.uniform(0, 0.1, (n, 2))
    r = rng.uniform(0.008, 0.012, n)
    mat = DiskMaterial(**GRAVEL, restitution=0.5, rolling_friction=0.1)
    disks = Disks(x, r, {"g": mat}, "g", width=W, comm=MPI.COMM_SELF, margin=0.05)
    v = rng.normal(size=(n, 2)) * 0.01
    om = rng.normal(size=n)
    for _ in range(2):  # two calls: slip and δ_max histories set
        f = np.zeros((n, 2))
        DK.disk_disk_forces(disks.x, v, om, disks.r, disks.mat, disks.table, disks.pairs,
                            disks.hist, W, 1e-4, f, np.zeros(n), np.zeros(DK.N_WORK))
        disks.x += v * 1e-4
    disks.x -= v * 1e-4  # back where the forces were evaluated
    fc = disks.pair_forces()
    g = np.zeros((n, 2))
    np.add.at(g, disks.pairs[:, 1], fc)
    np.add.at(g, disks.pairs[:, 0], -fc)
    lo, hi = np.array([0.02, 0.03]), np.array([0.08, 0.07])
    ref = np.zeros((2, 2))
    for (a, b), fk in zip(disks.pairs, fc, strict=True):
        d = disks.x[b] - disks.x[a]
        dist = np.linalg.norm(d)
        xc = disks.x[a] + (r[a] - 0.5 * (r[a] + r[b] - dist)) * d / dist
        for p, fp in ((a, -fk), (b, fk)):
            if np.all((disks.x[p] >= lo) & (disks.x[p] < hi)):
                ref += np.outer(fp, xc - disks.x[p])
    ref /= np.prod(hi - lo) * W
    sig = disks.cell_stress(lo, hi)
    print(f"\n{n} random disks, {int((np.abs(fc).sum(1) > 0).sum())} contacts: forces "
          f"{np.abs(g - f).max() / np.abs(f).max():.1e}, stress "
          f"{np.abs(sig - ref).max() / np.abs(ref).max():.1e} (relative)")
    assert np.abs(g - f).max() < 1e-12 * np.abs(f).max()
    assert np.abs(sig - ref).max() < 1e-12 * np.abs(ref).max()


def _far_block(comm=MPI.COMM_SELF):
    blocks = mesh_blocks([rectangle(5.0, 5.0, 5.1, 5.1)], materials="stone", mesh_size=0.1,
                         comm=comm)
    m = Model(blocks, {"stone": Material(density=2400.0, E=1e9, nu=0.2)}, width=W, comm=comm)
    m.fix_blocks(0)
    return m


def test_local_damping_of_a_falling_disk():
    """A free disk under gravity with local damping α: the first step starts from rest
    (sign 0, no damping), later ones accelerate at (1 − α) g; the energy account closes with
    the damping's work; the critical step is divided by √(1 + α); the default (α = 0) is
    the undamped fall."""
    alpha, steps = 0.7, 200
    out = {}
    for a in (0.0, alpha):
        disks = Disks([[0.0, 0.0]], [0.01], {"g": DiskMaterial(**GRAVEL)}, "g", width=W,
                      comm=MPI.COMM_SELF)
        disks.add_gravity()
        s = ExplicitSolver(_far_block(), interactions=disks,
                           local_damping={"disks": a} if a else 0.0)
        assert s.run(steps=steps, every=50) == steps
        out[a] = (disks.v[0, 1], s.energies(), s.dt, s.dt_critical)
    v, e, dt, crit = out[alpha]
    v_exact = -G * dt * (1 + (steps - 1) * (1 - alpha))
    print(f"\nfalling disk with local damping {alpha}: v {v:.6f} m/s (analytic {v_exact:.6f}); "
          f"damping work {e.damping:.3e} J, balance {e.balance:.1e} J; critical step "
          f"{crit:.3e} s (undamped {out[0.0][3]:.3e} s); undamped v {out[0.0][0]:.6f} m/s")
    assert v == pytest.approx(v_exact, rel=1e-12)
    assert out[0.0][0] == pytest.approx(-G * out[0.0][2] * steps, rel=1e-12)
    assert crit == pytest.approx(out[0.0][3] / math.sqrt(1 + alpha), rel=1e-14)
    assert out[0.0][1].damping == 0.0
    assert e.damping > 0 and abs(e.balance) < 1e-9 * e.damping
    for bad in (1.0, -0.1, {"nope": 0.5}):
        with pytest.raises(ValueError):
            ExplicitSolver(_far_block(), interactions=disks, local_damping=bad)


@pytest.mark.skipif(MPI.COMM_WORLD.size > 1, reason="one process (the suite's "
                    "budget: 20 s under mpirun against 11 s); "
                    "the disks' ranks are compared in tests/test_disks.py")
def test_wide_fill_at_rest_vertical_stress_is_the_overburden():
    """Issue #22: a fill 10 times wider than deep, settled under gravity by explicit
    dynamics with Cundall's local damping until the unbalanced-force ratio (rattlers left
    out) is below 1e-3. In a cell at mid-depth, well away from the walls, the averaged
    vertical stress is −ρ_bulk g h within 10 %, with ρ_bulk h the overburden mass per area
    measured directly: the mass of the disks whose centres lie above the cell's mid-height
    in the cell's column, over the column's width × w (the same centre convention as the
    stress). The base and the (frictional) walls carry the weight, the walls a few
    per cent; over the whole fill, walls included, σ_yy A w =
    Σ_walls f_y y − Σ m g y (the average-stress identity in equilibrium: the disk–disk
    terms cancel in pairs)."""
    from masonry_fdem.interactions import DiskBlockContact
    from masonry_fdem.interactions.disks.packing import pack_disks

    comm = MPI.COMM_WORLD
    L, H = 1.0, 0.1  # fill width and depth [m]
    polys = [rectangle(-0.02, -0.02, L + 0.02, 0.0), rectangle(-0.02, 0.0, 0.0, 1.5 * H),
             rectangle(L, 0.0, L + 0.02, 1.5 * H)]
    blocks = mesh_blocks(polys, materials="steel", mesh_size=0.05, comm=comm)
    model = Model(blocks, {"steel": Material(density=7800.0, E=2e10, nu=0.3)}, width=W,
                  comm=comm)
    model.fix_blocks(0, name="base")
    model.fix_blocks([1, 2], name="walls")
    x, r = pack_disks(rectangle(0.0, 0.0, L, H), 0.004, 0.006, 0.22, seed=1)
    # angular gravel: rolling resistance (round disks without it creep for long)
    mat = DiskMaterial(**GRAVEL, restitution=0.5, rolling_friction=0.3)
    disks = Disks(x, r, {"g": mat}, "g", width=W, max_overlap=0.005, comm=comm)
    disks.add_gravity()
    walls = DiskBlockContact(disks, model, friction=0.5)
    s = ExplicitSolver(model, interactions=[disks, walls], local_damping=ALPHA)
    t0 = time.perf_counter()
    steps = s.run(steps=200_000, every=1000,
                  until=lambda s: disks.unbalanced_ratio([walls]) < 1e-3)
    ratio = disks.unbalanced_ratio([walls])
    wall_time = time.perf_counter() - t0
    rb, rw = s.reactions()["base"], s.reactions()["walls"]
    # cells: the middle 60 % of the width (two depths from each wall), 3 diameters tall
    x0, x1, dh = 0.2 * L, 0.8 * L, 0.015

    def stress_and_overburden(yc):
        sig = disks.cell_stress((x0, yc - dh), (x1, yc + dh), [walls])
        col = (disks.x[:, 0] >= x0) & (disks.x[:, 0] < x1) & (disks.x[:, 1] >= yc)
        return sig, disks.m[col].sum() / ((x1 - x0) * W)  # ρ_bulk h [kg/m²]

    yc = 0.45 * H
    sig, rho_h = stress_and_overburden(yc)
    rho = disks.bulk_density((x0, yc - dh), (x1, yc + dh))
    profile = [(y, -sg[1, 1] / (rh * G)) for y in (0.15 * H, 0.3 * H, 0.6 * H, 0.75 * H)
               for sg, rh in [stress_and_overburden(y)]]
    whole = disks.cell_stress((-0.01, -0.01), (L + 0.01, 2 * H), [walls])
    _, fw, xw = walls.disk_contacts()  # the walls' part: Σ f_y y over wall contacts
    identity = (comm.allreduce(float(fw[:, 1] @ xw[:, 1]))
                - (disks.m * G * disks.x[:, 1]).sum()) / ((L + 0.02) * (2 * H + 0.01) * W)
    print(f"\nwide fill, {disks.n} disks, {comm.size} rank(s): unbalanced ratio {ratio:.1e} "
          f"after {steps} steps ({wall_time:.1f} s)\n  cell at y = {yc:.3f} m: σ_yy "
          f"{sig[1, 1]:.1f} Pa, ρ_bulk g h {rho_h * G:.1f} Pa "
          f"({-sig[1, 1] / (rho_h * G) - 1:+.2%}); σ_xx {sig[0, 0]:.1f} Pa, σ_xy "
          f"{sig[0, 1]:.1f} Pa; bulk density in the cell {rho:.0f} kg/m³ (h = "
          f"{rho_h / rho:.4f} m)\n  σ_yy / ρ_bulk g h at other depths (not asserted): "
          + ", ".join(f"y = {y:.3f} m {q:.3f}" for y, q in profile)
          + f"\n  base and walls carry {rb[1] / disks.weight:.4f} and "
          f"{rw[1] / disks.weight:.4f} of the weight; whole fill σ_yy {whole[1, 1]:.2f} Pa, "
          f"identity {identity:.2f} Pa")
    assert ratio < 1e-3
    assert abs(-sig[1, 1] / (rho_h * G) - 1.0) < 0.10
    assert abs((rb[1] + rw[1]) / disks.weight - 1.0) < 0.005 and rw[1] < 0.03 * rb[1]
    assert abs(whole[1, 1] / identity - 1.0) < 0.01
    assert comm.allreduce(disks.x.tobytes() == comm.bcast(disks.x.tobytes()), op=MPI.LAND)

