"""Disks sorted in space at pair-list rebuilds: the storage order is a function of the
disks, not of the order the user made them in, the physics does not see it, the friction
and rolling histories follow the disks, and what the user reads is in their numbering."""

from __future__ import annotations

import math
from pathlib import Path

from mpi4py import MPI

import numpy as np
from conftest import rectangle

from masonry_fdem import Material, Model
from masonry_fdem.geometry import mesh_blocks
from masonry_fdem.interactions.disks import DiskBlockContact, DiskMaterial, Disks
from masonry_fdem.interactions.disks import _kernels as DK
from masonry_fdem.interactions.disks.packing import pack_disks
from masonry_fdem.solvers import ExplicitSolver

W = 0.05  # out-of-plane thickness [m]
R = 0.01  # radius [m]
GRAIN = DiskMaterial(density=2600.0, E=1e8, nu=0.25, friction=0.5, restitution=0.5,
                     rolling_friction=0.3)


def _inverse(p: np.ndarray) -> np.ndarray:
    q = np.empty_like(p)
    q[p] = np.arange(p.size)
    return q


def test_cell_order_depends_on_the_disks_not_on_their_storage():
    rng = np.random.default_rng(1)
    n = 400
    x = rng.uniform(0.0, 0.5, (n, 2))
    r = rng.uniform(0.005, 0.01, n)
    x[:40, 0] = x[40:80, 0]  # ties in x: then by y
    perm, same = DK.cell_order(x, r, 0.002, np.arange(n))
    assert not same and np.array_equal(np.sort(perm), np.arange(n))
    # cells row by row, and by x, then y within a cell
    x0, y0, h, nx, ny = DK._grid(x, r, 0.002)
    cx = np.minimum(((x[:, 0] - x0) / h).astype(int), nx - 1)
    cell = np.minimum(((x[:, 1] - y0) / h).astype(int), ny - 1) * nx + cx
    assert np.array_equal(perm, np.lexsort((x[:, 1], x[:, 0], cell)))
    # the same disks stored and numbered otherwise: the same disks in the same places
    p = rng.permutation(n)
    perm2, _ = DK.cell_order(x[p], r[p], 0.002, rng.permutation(n))
    assert np.array_equal(p[perm2], perm)
    # sorted disks stay put
    again, same = DK.cell_order(x[perm], r[perm], 0.002, np.arange(n))
    assert same and np.array_equal(again, np.arange(n))
    # a crowded cell (a far disk coarsens the grid): merge sort, coincident centres by id
    y = np.r_[rng.uniform(0.0, 0.1, (200, 2)), [[50.0, 50.0]]]
    y[100:110] = y[0]
    ids = rng.permutation(201)
    perm3, _ = DK.cell_order(y, np.full(201, 0.001), 0.0, ids)
    assert np.array_equal(perm3[:-1], np.lexsort((ids[:-1], y[:-1, 1], y[:-1, 0])))


def test_pair_history_is_renumbered_with_the_disks():
    rng = np.random.default_rng(2)
    n = 300
    x = rng.uniform(0.0, 0.3, (n, 2))
    r = rng.uniform(0.008, 0.012, n)
    pairs = DK.disk_pairs_cell_list(x, r, 0.002)
    hist = rng.normal(size=(pairs.shape[0], DK.N_HIST))
    perm = rng.permutation(n)  # the disk now at k was at perm[k]
    new = DK.disk_pairs_cell_list(x[perm], r[perm], 0.002)
    got = np.full((new.shape[0], DK.N_HIST), np.nan)
    carried = DK.carry_history_renumbered(pairs, hist, perm, new, got)
    assert carried == pairs.shape[0] == new.shape[0]
    row = {(int(i), int(j)): k for k, (i, j) in enumerate(pairs)}
    swapped = 0
    for (a, b), h in zip(new, got, strict=True):
        i, j = perm[a], perm[b]
        want = hist[row[(min(i, j), max(i, j))]].copy()
        if i > j:  # roles swapped: the slip is the same, the rolling rotation reverses
            want[DK.H_ROLL] *= -1.0
            swapped += 1
        assert np.array_equal(h, want)
    assert swapped > 0
    # a pair that is new gets no history
    got2 = np.ones((new.shape[0], DK.N_HIST))
    assert DK.carry_history_renumbered(pairs[:0], hist[:0], perm, new, got2) == 0
    assert not got2.any()


def _fall(comm, order: np.ndarray | None, steps: int = 700, sort: bool = True):
    """Disks of a packing dropped with random velocities and spins into a box of fixed
    blocks, sorted at every rebuild (or never); ``order``: the order they are given in
    (None: the packing's)."""
    polys = [rectangle(-0.02, -0.02, 0.14, 0.0), rectangle(-0.02, 0.0, 0.0, 0.14),
             rectangle(0.12, 0.0, 0.14, 0.14)]
    blocks = mesh_blocks(polys, materials="stone", mesh_size=0.02, comm=comm)
    model = Model(blocks, {"stone": Material(density=2400.0, E=1e9, nu=0.2)}, width=W,
                  comm=comm)
    model.fix_blocks([0, 1, 2], name="box")
    x, r = pack_disks(np.array([[0.0, 0.0], [0.12, 0.0], [0.12, 0.1], [0.0, 0.1]]), 0.005,
                      0.008, 0.35, seed=3)
    rng = np.random.default_rng(5)
    v = rng.normal(0.0, 0.3, x.shape)
    omega = rng.normal(0.0, 30.0, r.size)
    p = np.arange(r.size) if order is None else order
    disks = Disks(x[p], r[p], {"g": GRAIN}, "g", width=W, comm=comm, sort=sort,
                  sort_every=1)
    disks.v[:] = v[p]
    disks.omega[:] = omega[p]
    disks.fix(p == 0)  # the packing's disk 0, wherever it was given
    disks.add_gravity()
    coupling = DiskBlockContact(disks, model, damping_ratio=0.1)
    s = ExplicitSolver(model, interactions=[disks, coupling], local_damping=0.2)
    gens = []
    for _ in range(steps // 100):
        s.run(steps=100, every=100)
        gens.append(disks.generation)
    inv = _inverse(p)  # packing disk k is user disk inv[k]
    state = {k: disks.by_id(getattr(disks, k))[inv] for k in ("x", "theta", "v", "omega")}
    return state, s.energies(), disks, coupling, gens


def test_random_and_spatial_creation_order_give_the_same_run():
    """The same disks given in the packing's (spatial) order and at random: after the
    first step both are stored alike, so the runs are bitwise equal by original id; the
    energy accounts differ only by the initial kinetic energy, summed before the first
    step in the order given (round-off)."""
    comm = MPI.COMM_WORLD
    spatial, e_s, d_s, c_s, gens = _fall(comm, None)
    n = d_s.n
    shuffle = np.random.default_rng(9).permutation(n)
    rand, e_r, d_r, c_r, _ = _fall(comm, shuffle)
    print(f"\n{n} disks falling into a box: {d_s.rebuilds} rebuilds, storage permuted "
          f"{d_s.generation} times (by step 100, 200, ...: {gens}); kinetic "
          f"{e_s.kinetic:.6g} J, residual "
          f"{e_s.residual:.2e} J")
    assert gens[-1] > gens[0] >= 1  # sorted at the first step, and again later
    touching = comm.allreduce(bool(np.any(c_s.hist != 0.0)), op=MPI.LOR)  # any rank's
    assert touching  # disk-block friction springs were carried through the sorts
    assert np.array_equal(shuffle[d_r.ids], d_s.ids)  # stored alike
    for k in spatial:
        assert np.array_equal(spatial[k], rand[k]), k
    for name in ("kinetic", "damping", "external", "residual"):
        a, b = getattr(e_s, name), getattr(e_r, name)
        assert abs(a - b) <= 1e-12 * max(abs(a), e_s.scale), name
    for key in e_s.stored:
        assert abs(e_s.stored[key] - e_r.stored[key]) <= 1e-12 * e_s.scale, key
    # never sorted: the same physics to round-off (the sums over a disk's contacts run in
    # another order); the disk-block pairs' friction followed the disks (without the
    # renumbering, 1.8e-8 m and 0.07 rad/s)
    kept, e_k, d_k, *_ = _fall(comm, None, sort=False)
    assert d_k.generation == 0
    for k, tol in (("x", 1e-12), ("theta", 1e-9), ("v", 1e-9), ("omega", 1e-9)):
        scale = np.abs(spatial[k]).max()
        assert np.abs(kept[k] - spatial[k]).max() <= tol * scale, k
    assert abs(e_k.kinetic - e_s.kinetic) <= 1e-9 * e_s.scale
    # the same on one rank (each rank runs the serial copy): 1e-10
    if comm.size > 1:
        serial, e_1, *_ = _fall(MPI.COMM_SELF, shuffle)
        scale = np.abs(spatial["x"]).max()
        dx = np.abs(serial["x"] - spatial["x"]).max() / scale
        print(f"  {comm.size} ranks vs 1: positions {dx:.1e}")
        assert dx < 1e-10
        assert abs(e_1.kinetic - e_s.kinetic) <= 1e-10 * e_s.scale


def test_a_resting_disk_keeps_its_friction_through_a_resort():
    """Disk B rests on a fixed disk A, 5 degrees off the top, held by its tangential and
    rolling springs; a third disk falling past them changes the cell order while the
    springs are loaded. Sorted at every rebuild or never, the runs agree, and B stays."""
    a = math.radians(5.0)
    top = np.array([2 * R * math.sin(a), 2 * R * math.cos(a)])
    xs = np.array([top, [0.0, 0.0], [0.15, 0.06]])  # B, A, C: B first, above A

    def run(sort):
        d = Disks(xs, np.full(3, R), {"g": GRAIN}, "g", width=W, comm=MPI.COMM_SELF,
                  sort=sort, sort_every=1)
        d.fix([1])
        d.v[2] = (0.0, -1.0)
        d.add_gravity()
        blocks = mesh_blocks([rectangle(5.0, 5.0, 5.1, 5.1)], materials="stone",
                             mesh_size=0.1, comm=MPI.COMM_SELF)
        far = Model(blocks, {"stone": Material(density=2400.0, E=1e9, nu=0.2)}, width=W,
                    comm=MPI.COMM_SELF)
        far.fix_blocks(0)
        s = ExplicitSolver(far, interactions=d, local_damping=0.5)
        loaded = None
        for _ in range(3000):
            gen = d.generation
            slip = d.hist[:, DK.H_SLIP].copy() if d.pairs.shape[0] else np.zeros(1)
            s.step()
            if d.generation > gen and s.n > 500 and loaded is None:
                loaded = (s.n, np.abs(slip).max(), d.by_id(d.x)[0])
        return d.by_id(d.x), d.by_id(d.theta), d, loaded

    xa, ta, da, loaded = run(True)
    xb, tb, db, _ = run(False)
    assert loaded is not None, "no resort while B rested"
    step, slip, then = loaded
    moved = np.linalg.norm(xa[0] - then)
    print(f"\nresort at step {step} with B's friction spring at slip {slip:.3e} m; "
          f"B moved {moved:.1e} m from then to the end (settling before: "
          f"{np.linalg.norm(then - top):.1e} m); sorted vs not: {np.abs(xa - xb).max():.1e} m")
    assert slip > 1e-8  # the spring was loaded
    assert not np.array_equal(da.ids, np.arange(3))  # the storage did change
    assert np.array_equal(db.ids, np.arange(3))
    assert np.abs(xa - xb).max() <= 1e-15 and np.abs(ta - tb).max() <= 1e-12
    assert moved < 1e-5 * R  # B stays on A (losing the history at the resort: 2.7e-5 m)


def test_user_numbering_of_fix_outputs_and_files(tmp_path):
    """After a resort, fix(), contact_counts(), save/load and the disk output speak the
    numbering the disks were given in."""
    import base64
    import xml.etree.ElementTree as ET

    from masonry_fdem.io import DiskOutput

    n = 40
    rng = np.random.default_rng(7)
    k = rng.permutation(n)
    x = np.c_[(k % 8) * 2.2 * R, (k // 8) * 2.2 * R]  # a lattice given at random
    r = R * (1.0 + 0.01 * np.arange(n) / n)
    disks = Disks(x, r, {"g": GRAIN}, "g", width=W, comm=MPI.COMM_SELF)
    disks.v[:] = rng.normal(size=(n, 2))
    disks.rebuild()  # the first rebuild sorts
    assert disks.generation == 1 and not np.array_equal(disks.ids, np.arange(n))
    assert np.array_equal(disks.ids[disks.slot], np.arange(n))
    assert np.array_equal(disks.by_id(disks.x), x)
    disks.fix([3, 5])
    assert np.flatnonzero(disks.by_id(disks.fixed)).tolist() == [3, 5]
    mask = np.zeros(n, dtype=bool)
    mask[7] = True
    disks.fix(mask)
    assert np.flatnonzero(disks.by_id(disks.fixed)).tolist() == [3, 5, 7]
    assert disks.contact_counts().shape == (n,)
    out = Path(tmp_path)
    disks.save(out / "d.npz")
    back = Disks.load(out / "d.npz", comm=MPI.COMM_SELF)
    assert np.array_equal(back.x, x) and np.array_equal(back.fixed, disks.by_id(disks.fixed))
    assert np.array_equal(back.v, disks.by_id(disks.v))
    w = DiskOutput(disks, out / "vtk")
    w.write(0.0)
    root = ET.parse(out / "vtk" / "disks_00000.vtp").getroot()
    arrays = {a.get("Name"): a for a in root.iter("DataArray")}
    pts = np.frombuffer(base64.b64decode(arrays["Points"].text[12:]), dtype="<f8")
    assert np.array_equal(pts.reshape(-1, 3)[:, :2], x)
    ids = np.frombuffer(base64.b64decode(arrays["id"].text[12:]), dtype="<i8")
    assert np.array_equal(ids, np.arange(n))
    # a state taken before and given back after a resort restores the order with it
    st = disks.state()
    x_then = disks.by_id(disks.x)
    disks.x[:] = disks.x[::-1]  # move the disks so that the order changes
    disks.sort_every = 1
    disks.rebuild()
    assert disks.generation == 2
    disks.set_state(st)
    assert np.array_equal(disks.ids, st["ids"]) and np.array_equal(disks.by_id(disks.x),
                                                                   x_then)
    assert np.array_equal(disks.by_id(disks.r), r)
    assert np.array_equal(disks.by_id(disks.m), back.m)


def test_dynamic_relaxation_follows_the_sort():
    """Two disks on a deformable block, given right one first: dynamic relaxation's own
    per-dof arrays (fictitious masses, velocities, start of the increment) follow the sort
    of its first iteration, and the equilibrium is that of the unsorted run."""
    from masonry_fdem.solvers import DynamicRelaxation

    def solve(sort):
        blocks = mesh_blocks([rectangle(0.0, 0.0, 0.2, 0.05)], materials="stone",
                             mesh_size=0.02, comm=MPI.COMM_WORLD)
        model = Model(blocks, {"stone": Material(density=2400.0, E=1e9, nu=0.2)}, width=W)
        model.fix(lambda X: np.isclose(X[1], 0.0), name="base")
        x = [[0.121, 0.05 + 0.999 * R], [0.083, 0.05 + 0.999 * 1.5 * R]]
        disks = Disks(x, [R, 1.5 * R], {"g": GRAIN}, "g", width=W, sort=sort)
        disks.add_gravity()
        dr = DynamicRelaxation(model, interactions=[disks, DiskBlockContact(disks, model)],
                               rtol=1e-6, max_iter=20_000)
        res = dr.solve(1.0)
        return res, disks, dr.reactions()["base"], model.displacement()

    res_s, d_s, r_s, u_s = solve(True)
    res_u, d_u, r_u, u_u = solve(False)
    print(f"\nDR with a sort: {res_s.iterations} iterations (unsorted {res_u.iterations}), "
          f"ids {d_s.ids}, base reaction {r_s[1]:.6f} N vs {r_u[1]:.6f} N")
    assert res_s.converged and res_u.converged and res_s.iterations == res_u.iterations
    assert d_s.generation == 1 and d_s.ids.tolist() == [1, 0]
    assert np.abs(d_s.by_id(d_s.x) - d_u.x).max() < 1e-12
    assert abs(r_s[1] - r_u[1]) < 1e-9 * abs(r_u[1])
    assert np.abs(u_s - u_u).max() <= 1e-9 * np.abs(u_u).max()
