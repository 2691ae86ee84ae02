"""Issue #22 acceptance: a masonry arch bridge whose fill is at least 5 000 disks settles
under self-weight to an unbalanced-force ratio below 1e-3 within 10 minutes on 2 cores.

The bridge is ``cases/bridge_single_span.toml`` (a 6 m segmental stone arch, rise 1.5 m,
ring 0.4 m, 24 voussoirs, abutments 3 m wide and 0.8 m high, 0.4 m of fill over the crown,
a 1 m strip of barrel). Its fill region (:func:`masonry_fdem.geometry.fill.fill_layout`:
extrados and abutment tops up to the road, between the abutments' outer faces; 17.0 m²)
is packed with disks (:func:`masonry_fdem.interactions.disks.fill.fill_disks`: the
region's bounding box packed at porosity 0.2, the disks wholly inside the region kept,
a clearance of 1 % r_min to the blocks). Blocks: the voussoirs, the abutments (fixed) and
two end walls on the abutments' outer faces up to the road (fixed). The fill settles in
two stages: (1) on the held arch (every block fixed: the arch, E = 10 GPa, is far
stiffer than the fill, so holding it changes little while the fill, the slow part,
comes to rest at the disks' own time step); (2) with ``--free-arch``, the voussoirs are
then released (joined by the case's mortar joints and block contact as
``assessment.assess.build_model`` does, self-weight on the blocks) and the whole
settles again, now also until the free block dofs' unbalanced ratio Σ|f_ext + f_con −
f_int| / Σ|f_ext| is below the tolerance.

Disks (gravel in sand, angular: rolling resistance): solid density 2500 kg/m³ (bulk
≈ 2000 kg/m³ at porosity 0.2, the case's fill), E = ``--e-disk`` (default 100 MPa, in the
50 MPa-1 GPa of DEM fill), ν = 0.25, μ = 0.5, rolling friction 0.3, restitution 0.5;
disk–block friction tan δ of the case's fill interface (tan(2/3 φ) = 0.43). Settled by
``ExplicitSolver(local_damping=0.7)`` (Cundall's local damping), no mass scaling, until
``disks.unbalanced_ratio([coupling]) < 1e-3`` (checked every ``--every`` steps).

Printed: disk count, time step and what limits it, steps, wall time (settling loop only,
and total), final ratio, a per-step time breakdown (block internal forces / disk–disk /
disk–block / integration) and the vertical stress in cells of the fill against
ρ_bulk g h (ρ_bulk h: the mass of the disks above the cell's mid-height in its column,
per area, as tests/test_fill_disks.py).

Time step. Stage 1 is limited by the disk contacts alone (held blocks do not limit it):
5.1e-5 s at E = 100 MPa, 1.7e-5 s at 1 GPa. The fill comes to rest after about 1.7 s of
simulated time whatever E (34 000 steps at 100 MPa, 99 000 at 1 GPa): the steps scale as
√E, so the soft end of the physical range is the cheap one. Stage 2 is limited by the
block contact's penalty (the case's penalty_factor 20: ω² 5.4e10 1/s², dt 5.7e-6 s),
not by the elements (2.9e-5 s) nor the joints; it needs some 39 000 steps (0.22 s).

Measured (2 cores shared with another CI job, so ~1.5x slower than idle; 5 278 disks,
the settling loop): stage 1 alone, serial 23-35 s, ``mpirun -n 2`` 53-60 s (disks are
replicated, so a second rank adds the disk–block force allreduce and no speed-up); both
stages, serial 82-88 s, ``mpirun -n 2`` 162-181 s. Final ratio 5.5e-4 (stage 1),
9.9e-4 (both), identical serially and on 2 ranks.

Run: ``mpirun -n 2 python benchmarks/bridge_disks.py`` (or serially); ``--count``
(default 5 600 asked, about 5 300 kept), ``--e-disk``, ``--free-arch``, ``--max-steps``.
"""

from __future__ import annotations

import argparse
import math
import os
import time
from pathlib import Path

# One BLAS thread per process (set before numpy is imported): OpenBLAS threads large
# dot products, and on 2 cores shared by MPI ranks (and here another job) its threads
# made a step of this fill 5-50x slower (0.7 ms -> 7-34 ms) when the explicit solver's
# work bookkeeping used np.dot (it now uses a one-thread numba kernel).
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

from mpi4py import MPI  # noqa: E402

import numpy as np  # noqa: E402

from masonry_fdem.constants import G  # noqa: E402

CASE = Path(__file__).resolve().parents[1] / "cases" / "bridge_single_span.toml"


class _Timer:
    """Wall time spent in a bound method (wrapped on the instance)."""

    def __init__(self, obj, name: str, bucket: dict, key: str):
        self.f = getattr(obj, name)
        self.bucket, self.key = bucket, key
        bucket.setdefault(key, 0.0)
        setattr(obj, name, self)

    def __call__(self, *a, **k):
        t = time.perf_counter()
        out = self.f(*a, **k)
        self.bucket[self.key] += time.perf_counter() - t
        return out


def build(args, comm):
    from masonry_fdem.assessment.parse import load_case
    from masonry_fdem.geometry import polygon_area
    from masonry_fdem.geometry.fill import fill_layout
    from masonry_fdem.interactions import DiskBlockContact
    from masonry_fdem.interactions.disks import DiskMaterial, Disks
    from masonry_fdem.interactions.disks.fill import fill_disks, radii_for_count
    from masonry_fdem.model import Model

    case = load_case(args.case)
    structure = case.layout()
    cover = case.fill.cover
    fill_poly = fill_layout(structure, cover=cover).polygons[0]
    area = polygon_area(fill_poly)
    r_min, r_max = radii_for_count(area, args.count, args.porosity)
    t = time.perf_counter()
    x, r, walls = fill_disks(structure, cover=cover, r_min=r_min, r_max=r_max,
                             porosity=args.porosity, seed=args.seed,
                             wall_thickness=case.fill.wall_thickness)
    t_pack = time.perf_counter() - t
    layout = structure + walls
    sizes = [case.fill.wall_thickness if n.startswith("wall:") else case.arch.mesh_size
             for n in layout.names]
    mesh = layout.mesh(sizes, comm)
    model = Model(mesh, case.materials(), width=case.arch.width, comm=comm)
    model.fix_blocks("abutment:*", name="abutments")
    model.fix_blocks("wall:*", name="walls")
    inter = []
    # the voussoirs are held while the fill settles; --free-arch releases them after
    arch = model.fix_blocks("voussoir:*", name="arch")
    if args.free_arch:
        from masonry_fdem.interactions import BlockContact, ContactSettings, Joints

        model.add_gravity()  # (the held blocks' weight goes to their reactions)
        contact = BlockContact(model, ContactSettings(friction=case.analysis.friction,
                                                      penalty_factor=case.analysis.penalty_factor))
        jm = case.joint_materials()
        v, a = case.arch.voussoir_material, case.arch.abutment_material
        table = {(v, v): jm[(v, v)], (v, a): jm[(v, a)], (a, a): None}
        inter += [contact, Joints(model, table, where=case.joint_rules(layout),
                                  contact=contact)]
    rho_bulk = case.materials()[case.fill.material].density
    mat = DiskMaterial(density=rho_bulk / (1.0 - args.porosity), E=args.e_disk, nu=0.25,
                       friction=0.5, restitution=0.5, rolling_friction=0.3)
    disks = Disks(x, r, {"fill": mat}, "fill", width=case.arch.width,
                  max_overlap=args.max_overlap, comm=comm)
    disks.add_gravity()
    coupling = DiskBlockContact(disks, model, friction=case.fill.interface_friction)
    return case, structure, fill_poly, model, disks, coupling, inter, t_pack, arch


def stress_cells(structure, road, disks, coupling, xs, half=0.3, dh=None):
    """σ_yy in a cell centred at mid-depth of the fill at each x, against ρ_bulk g h."""
    from masonry_fdem.geometry.fill import upper_envelope

    dh = 3.0 * float(disks.r.mean()) if dh is None else dh
    w = disks.width
    rows = []
    for xc in xs:
        base = float(upper_envelope(structure, np.linspace(xc - half, xc + half, 21)).max())
        yc = 0.5 * (base + road)
        lo, hi = (xc - half, yc - dh), (xc + half, yc + dh)
        sig = disks.cell_stress(lo, hi, [coupling])
        col = ((disks.x[:, 0] >= xc - half) & (disks.x[:, 0] < xc + half)
               & (disks.x[:, 1] >= yc))
        rho_h = disks.m[col].sum() / (2 * half * w)
        rho = disks.bulk_density(lo, hi)
        rows.append((xc, yc, road - yc, sig[1, 1], rho_h * G, rho, sig[0, 0]))
    return rows


def block_ratio(solver) -> float:
    """Unbalanced-force ratio of the free block dofs at the last step: Σ|f_ext + f_con −
    f_int| over Σ|f_ext| (collective; 0 when every block is held)."""
    b = solver.sets[0]
    free = b.presc == 0
    g = np.abs(b.f_ext + b.f_con - b.f_int)[free].sum()
    w = np.abs(b.f_ext)[free].sum()
    g, w = solver.model.comm.allreduce(np.array([g, w]))
    return float(g / w) if w > 0 else 0.0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--case", default=str(CASE))
    ap.add_argument("--count", type=int, default=5600, help="disks asked (about 6 %% fewer kept)")
    ap.add_argument("--porosity", type=float, default=0.2)
    ap.add_argument("--e-disk", type=float, default=1e8, help="disk Young's modulus [Pa]")
    ap.add_argument("--max-overlap", type=float, default=0.02,
                    help="δ/r_min bounding the Hertz stiffness in the time step")
    ap.add_argument("--free-arch", action="store_true",
                    help="then release the voussoirs (mortar joints, contact) and settle again")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--every", type=int, default=1000)
    ap.add_argument("--max-steps", type=int, default=200_000, help="per stage")
    ap.add_argument("--tol", type=float, default=1e-3)
    args = ap.parse_args()
    comm = MPI.COMM_WORLD
    say = print if comm.rank == 0 else (lambda *a, **k: None)
    from masonry_fdem.solvers import ExplicitSolver

    t_all = time.perf_counter()
    case, structure, fill_poly, model, disks, coupling, inter, t_pack, arch = build(args, comm)
    say(f"bridge: {disks.n} disks (r = {disks.r.min() * 1e3:.1f}..{disks.r.max() * 1e3:.1f} "
        f"mm, packed in {t_pack:.1f} s), {model.blocks.n_blocks} blocks, {comm.size} "
        f"rank(s); E_disk {args.e_disk:.3g} Pa; voussoirs "
        f"{'held, then released' if args.free_arch else 'held'}")
    times: dict[str, float] = {}
    _Timer(model, "internal_force", times, "blocks (internal forces)")
    _Timer(disks, "update", times, "disk–disk (pair search)")
    _Timer(disks, "add_forces", times, "disk–disk (forces)")
    _Timer(coupling, "update", times, "disk–block (search)")
    _Timer(coupling, "add_forces", times, "disk–block (forces + allreduce)")
    for c in inter:
        _Timer(c, "update", times, f"{c.name} (update)")
        _Timer(c, "add_forces", times, f"{c.name} (forces)")
    w2_dd = disks.stable_omega2()["disks"]
    w2_db = coupling.stable_omega2()["disks"]
    total = {"steps": 0, "wall": 0.0}

    def settle(s, label, with_blocks):
        for k in times:
            times[k] = 0.0
        hist = []
        t0 = time.perf_counter()
        t_check = [0.0]

        def check(sv):
            t = time.perf_counter()
            ratio = disks.unbalanced_ratio([coupling])
            rb = block_ratio(sv) if with_blocks else 0.0
            t_check[0] += time.perf_counter() - t
            hist.append((sv.n, time.perf_counter() - t0, ratio, rb))
            if sv.n % (10 * args.every) == 0:
                say(f"  step {sv.n}: ratio {ratio:.2e}"
                    + (f", blocks {rb:.2e}" if with_blocks else "")
                    + f", {time.perf_counter() - t0:.1f} s, KE(disks) "
                      f"{disks.kinetic_energy():.3e} J")
            return ratio < args.tol and rb < args.tol

        steps = s.run(steps=args.max_steps, every=args.every, until=check)
        wall = time.perf_counter() - t0
        ratio, rb = hist[-1][2], hist[-1][3]
        ok = ratio < args.tol and rb < args.tol
        total["steps"] += steps
        total["wall"] += wall
        say(f"  {label}: {steps} steps of {s.dt:.3e} s ({steps * s.dt:.3f} s simulated), "
            f"wall {wall:.1f} s ({wall / steps * 1e3:.3f} ms/step); disk ratio {ratio:.2e}"
            + (f", block ratio {rb:.2e}" if with_blocks else "")
            + f" ({'below' if ok else 'NOT below'} {args.tol:g})")
        other = wall - sum(times.values()) - t_check[0]
        say("    time per step: " + ", ".join(f"{k} {v / steps * 1e3:.3f} ms"
                                              for k, v in times.items() if v > 0)
            + f", ratio checks {t_check[0] / steps * 1e3:.3f} ms, integration + rest "
              f"{other / steps * 1e3:.3f} ms")
        return steps, ratio, ok

    # stage 1: the fill settles on the held arch
    s = ExplicitSolver(model, interactions=[disks, coupling], local_damping=0.7)
    dt_disks = 2.0 / math.sqrt(w2_dd + w2_db) / math.sqrt(1.7)
    say(f"  stage 1 dt = {s.dt:.3e} s (critical {s.dt_critical:.3e} s = that of the disk "
        f"contacts: disk–disk ω² {w2_dd:.3e}, disk–block ω² {w2_db:.3e} 1/s², "
        f"2/√(Σω²)/√1.7 = {dt_disks:.3e} s)")
    steps, ratio, ok = settle(s, "stage 1 (fill on the held arch)", False)
    if args.free_arch:
        # stage 2: the voussoirs released (their weight, the fill's thrust), settle again
        model.prescriptions.remove(arch)
        dt_el = model.stable_time_step() / math.sqrt(1.7)
        w2 = {c.name: c.stable_omega2().get("blocks", 0.0) for c in inter}
        s = ExplicitSolver(model, interactions=[disks, coupling, *inter], local_damping=0.7)
        say(f"  stage 2 dt = {s.dt:.3e} s (critical {s.dt_critical:.3e} s); free blocks' "
            f"elements alone {dt_el:.3e} s; block ω² bounds added by "
            + ", ".join(f"{k} {v:.3e}" for k, v in w2.items()) + " 1/s²")
        steps2, ratio, ok = settle(s, "stage 2 (arch released)", True)
        steps += steps2
    react = s.reactions()
    wsum = sum(react[k][1] for k in react)
    say("  reactions (vertical, fraction of the disks' weight): "
        + ", ".join(f"{k} {v[1] / disks.weight:.4f}" for k, v in react.items())
        + f"; sum {wsum / disks.weight:.4f}")
    road = float(fill_poly[:, 1].max())
    rows = stress_cells(structure, road, disks, coupling, (-2.6, -1.8, 0.0, 1.8, 2.6))
    for xc, yc, depth, syy, rgh, rho, sxx in rows:
        say(f"  cell x = {xc:+.1f} m, y = {yc:.3f} m (depth {depth:.2f} m): σ_yy {syy:.0f} Pa, "
            f"ρ_bulk g h {rgh:.0f} Pa (ratio {-syy / rgh:.3f}), σ_xx {sxx:.0f} Pa, bulk "
            f"density {rho:.0f} kg/m³")
    say(f"RESULT n_disks={disks.n} ranks={comm.size} free_arch={args.free_arch} "
        f"steps={total['steps']} wall_s={total['wall']:.1f} ratio={ratio:.3e} ok={ok} "
        f"total_s={time.perf_counter() - t_all:.1f}")


if __name__ == "__main__":
    main()
