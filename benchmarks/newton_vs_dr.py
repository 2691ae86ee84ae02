"""Static Newton against dynamic relaxation: one dry-jointed arch loaded to its peak by
both solvers in the same run.

The arch (as ``_quarter_span_arch`` in ``tests/test_path.py``): 20 voussoirs, intrados
radius 1 m, ring thickness 0.15 m, μ = 0.8, E = 10 GPa voussoirs (30 GPa abutments),
contact penalty factor 20, mesh size 0.1 m, a point load at the midpoint of the extrados
of the voussoir over the quarter span. Each solver gets its own model instance; its wall
time runs from after the model's construction and includes its self-weight equilibrium.

* Newton (:meth:`StaticSolver.follow`): ``settle()`` (self-weight), then arc length on
  the load point's displacement, increment ``--step`` (growing to 64 × it), until the
  load has fallen 25 % below its peak. Times printed: to the first converged point past
  the peak, to the first point 5 % below the peak (DR's stopping rule) and of the whole
  run, with the Newton iterations per increment.
* Dynamic relaxation (:class:`DynamicRelaxation`, as the displacement control of
  ``benchmarks/collapse_vs_limit_analysis.py``): self-weight equilibrium, then the mesh
  node at the load point is prescribed and driven down in steps of ``--step`` metres;
  the peak reaction is the collapse load once the reaction has fallen 5 % below it
  (*peak passed*). A step without equilibrium within ``--dr-max-iter`` iterations, or
  the wall-time cap ``--dr-max-time`` [s], ends the run: its peak is then only a lower
  bound of the collapse load (printed so, never as a collapse).

Also printed: the limit-analysis (LP) load of the same arch and the ratio DR time /
Newton time (the issue's acceptance: Newton reaches the peak in at most 1/10 of DR's
wall time in the same run). Timings are printed, never asserted. Newton runs
``--newton-repeat`` times (fresh model each time; the median time is quoted).

    python benchmarks/newton_vs_dr.py [--step 2e-5] [--dr-max-iter 100000] [--dr-max-time 780]
    mpirun -n 2 python benchmarks/newton_vs_dr.py

Measured (this machine, 2 cores, serial run with the defaults; 42 s in all):

* LP 1460.9 N. Newton: peak passed, collapse load 1397 N (0.956 of LP), 16 converged
  increments (3 failed and halved), Newton iterations per increment median 3, max 8;
  wall time (median of 3) 0.55 s to the first point past the peak, 0.61 s to 5 % below
  it, 1.08 s for the whole run (a first trial run: 1.05 / 1.16 / 1.93 s).
* DR (velocity damping, rtol 1e-6): self-weight 12 015 iterations, then 33 078 and
  75 139 iterations for the first two steps (reactions 927.9 N at 0.02 mm, 1184.4 N at
  0.04 mm, where Newton's path carries 1160 N and 1305 N), and the third step (0.06 mm)
  not converged in 100 000 iterations (|r|/|f| = 1.8e-6): *not converged*, 1184 N a
  lower bound (0.81 of LP), after 37.0 s. DR did not reach the peak (Newton finds it
  near 0.33 mm, i.e. some 17 DR steps, and 5 % below it past 1.1 mm).
* DR time / Newton time: 61 against Newton's time to 5 % past its peak, 34 against its
  whole run; lower bounds of the ratio, since DR stopped short of its peak.
* ``--dr-max-iter 300000 --dr-max-time 300 --newton-repeat 1``: DR steps 3–5 converged
  (105 430, 99 523, 170 546 iterations; 1275.8, 1315.5, 1337.4 N at 0.06–0.10 mm), the
  sixth (0.12 mm) not in 300 000 iterations (|r|/|f| = 1.3e-6): *not converged*, 1337 N
  a lower bound (0.915 of LP), 139.5 s; Newton (one run, the process's first, slower)
  0.99 / 1.09 / 1.67 s; ratios 128 and 84, again lower bounds.
"""

from __future__ import annotations

import argparse
import math
import statistics
import time

from mpi4py import MPI

import numpy as np

from masonry_fdem import Material, Model
from masonry_fdem.geometry import arch_layout
from masonry_fdem.interactions import BlockContact, ContactSettings
from masonry_fdem.solvers import DynamicRelaxation
from masonry_fdem.solvers.limit_analysis import limit_analysis
from masonry_fdem.solvers.static import StaticSolver

T = 0.15  # ring thickness [m] (intrados radius 1 m)
FRICTION = 0.8


def layout_and_point():
    """The arch's block layout and the loaded point (the midpoint of the extrados chord of
    the voussoir over the quarter span: a node of the mesh, inside one block)."""
    lay = arch_layout(span=2.0, ring_thickness=T, voussoirs=20, abutment_height=0.3,
                      abutment_width=0.4)
    r = (1.0 + T) * math.cos(math.radians(4.5))
    point = (r * math.cos(math.radians(112.5)), r * math.sin(math.radians(112.5)))
    return lay, point


def build(comm, live_load: bool):
    """A fresh model and its contact (the point load (0, −1) N as live load if asked)."""
    lay, point = layout_and_point()
    mats = {"voussoir": Material(2000.0, 10e9, 0.2), "abutment": Material(2000.0, 30e9, 0.2)}
    model = Model(lay.mesh(0.1, comm), mats, width=1.0, comm=comm)
    model.fix_blocks("abutment:*")
    model.add_gravity()
    if live_load:
        model.add_point_load(point, (0.0, -1.0), blocks="voussoir:*")
    contact = BlockContact(model, ContactSettings(friction=FRICTION, penalty_factor=20.0))
    return model, contact, point


def run_newton(comm, step: float):
    """One Newton run: (run, times [s] of the converged points after the start)."""
    model, contact, _ = build(comm, live_load=True)
    comm.Barrier()
    t0 = time.perf_counter()
    times: list[float] = []
    s = StaticSolver(model, interactions=contact)
    settled = s.settle()
    run = s.follow(step, max_increment=64 * step, max_displacement=0.05, stop_drop=0.25,
                   callback=lambda p: times.append(time.perf_counter() - t0))
    total = time.perf_counter() - t0
    return run, settled, times, total


def newton_times(run, times, total):
    """(time to the first point past the peak, to the first point 5 % below it, total);
    None where the run did not get there. ``times[i]`` belongs to ``run.loads[i + 1]``."""
    loads = np.asarray(run.loads)
    k = int(np.argmax(loads))
    past = times[k] if k + 1 < loads.size else None
    below = np.flatnonzero(loads[k + 1:] < 0.95 * loads[k])
    drop = times[k + int(below[0])] if below.size else None
    return past, drop, total


def run_dr(comm, args, say):
    """Displacement control by dynamic relaxation. Returns (status line, peak [N],
    whether the peak is a collapse load, steps, DR iterations per step, time [s])."""
    model, contact, point = build(comm, live_load=False)
    comm.Barrier()
    t0 = time.perf_counter()
    kw = dict(interactions=contact, rtol=args.dr_rtol, ke_tol=math.inf,
              max_iter=args.dr_max_iter, damping=args.damping)
    dr = DynamicRelaxation(model, **kw)
    res = dr.solve(0.0)
    its_sw = res.iterations
    if not res.converged:
        return (f"not converged under self-weight ({res.iterations} iterations)", 0.0, False,
                0, [], its_sw, time.perf_counter() - t0)
    # the driven node: the mesh node nearest the loaded point, over all ranks
    d = np.hypot(model.X[:, 0] - point[0], model.X[:, 1] - point[1])
    i = int(np.argmin(d)) if d.size else -1
    best = comm.allgather((float(d[i]) if d.size else math.inf,
                           tuple(model.X[i]) if d.size else (0.0, 0.0)))
    x0 = min(best)[1]
    model.prescribe_nodes(lambda X: np.hypot(X[0] - x0[0], X[1] - x0[1]) < 1e-9, (None, 0.0),
                          "drive")
    dr = DynamicRelaxation(model, **kw)
    drive = next(p for p in model.prescriptions if p.name == "drive")
    sel = drive.components == 1
    u_sw = comm.allreduce(float(model.u.x.array[drive.dofs[sel]].sum()))
    u_sw /= max(comm.allreduce(int(sel.sum())), 1)
    peak, collapse, iters = 0.0, False, []
    status = ""
    k = 0
    while True:
        k += 1
        res = dr.solve(0.0, displacement={"drive": (None, u_sw - k * args.step)})
        iters.append(res.iterations)
        force = -float(dr.reactions()["drive"][1])
        elapsed = time.perf_counter() - t0
        if not res.converged:
            status = (f"not converged at displacement {k * args.step * 1e3:.4g} mm "
                      f"({res.iterations} DR iterations, |r|/|f| = "
                      f"{res.relative_residual:.1e}; carried {peak:.4g} N, a lower bound "
                      "of the collapse load)")
            break
        peak = max(peak, force)
        say(f"  DR step {k}: {k * args.step * 1e3:.3f} mm, reaction {force:.2f} N, "
            f"{res.iterations} iterations, {elapsed:.0f} s")
        if force < 0.95 * peak:
            collapse = True
            status = (f"peak passed: collapse load {peak:.4g} N; the reaction fell 5 % below "
                      f"it at displacement {k * args.step * 1e3:.4g} mm")
            break
        if elapsed > args.dr_max_time:
            status = (f"stopped at the time cap {args.dr_max_time:g} s at displacement "
                      f"{k * args.step * 1e3:.4g} mm, the reaction not yet 5 % below its "
                      f"peak (carried {peak:.4g} N, a lower bound of the collapse load)")
            break
    return status, peak, collapse, k, iters, its_sw, time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--step", type=float, default=2e-5,
                    help="displacement step [m] (Newton's first arc-length increment, DR's step)")
    ap.add_argument("--newton-repeat", type=int, default=3,
                    help="Newton runs (the median time is quoted)")
    ap.add_argument("--dr-max-iter", type=int, default=100_000,
                    help="DR iterations per displacement step")
    ap.add_argument("--dr-max-time", type=float, default=780.0,
                    help="wall-time cap of the DR run [s] (checked after each step)")
    ap.add_argument("--dr-rtol", type=float, default=1e-6)
    ap.add_argument("--damping", choices=["displacement", "velocity"], default="velocity")
    ap.add_argument("--skip-dr", action="store_true", help="Newton only")
    args = ap.parse_args()
    comm = MPI.COMM_WORLD

    def say(line: str) -> None:
        if comm.rank == 0:
            print(line, flush=True)

    lay, point = layout_and_point()
    la = limit_analysis(lay, density=2000.0, width=1.0, supports="abutment:*",
                        live_loads=[(point, (0.0, -1.0))], friction=FRICTION)
    p_la = float(la.load_factor)
    say(f"arch: 20 voussoirs, t = {T} m, mu = {FRICTION}, E = 10 GPa, penalty factor 20; "
        f"{comm.size} process(es)")
    say(f"limit analysis: {p_la:.1f} N")

    runs = [run_newton(comm, args.step) for _ in range(max(args.newton_repeat, 1))]
    run, settled, times, total = runs[0]
    t_past, t_drop, t_total = (statistics.median(v) if None not in v else None
                               for v in zip(*(newton_times(r, t, tt) for r, _, t, tt in runs)))
    its = [r.iterations for r in run.results if r.converged]
    peak_n = run.status.peak
    say(f"Newton: {run.status.describe('N')}")
    say(f"  self-weight: {settled.status} ({settled.detail}); peak/LP {peak_n / p_la:.4f}")
    say(f"  {len(its)} converged increments ({len(run.results) - len(its)} failed and "
        f"halved); Newton iterations per increment: median {np.median(its):g}, "
        f"max {max(its)}")

    def fmt(t):
        return "not reached" if t is None else f"{t:.2f} s"

    say(f"  wall time (median of {len(runs)}, incl. self-weight): to the first point past "
        f"the peak {fmt(t_past)}, to 5 % below the peak {fmt(t_drop)}, whole run "
        f"{fmt(t_total)}")
    if args.skip_dr:
        return

    say(f"dynamic relaxation: displacement control, step {args.step:g} m, rtol "
        f"{args.dr_rtol:g}, damping {args.damping}, at most {args.dr_max_iter} iterations "
        f"per step and {args.dr_max_time:g} s")
    status, peak_dr, collapse, steps, iters, its_sw, t_dr = run_dr(comm, args, say)
    say(f"DR: {status}")
    say(f"  self-weight {its_sw} DR iterations; {steps} steps, DR iterations per step "
        f"median {np.median(iters):g}, max {max(iters)}; peak/LP {peak_dr / p_la:.4f}"
        + ("" if collapse else " (a lower bound)"))
    say(f"  wall time (incl. self-weight): {t_dr:.1f} s")
    say("summary:")
    say(f"  collapse load: Newton {peak_n:.1f} N ({run.status.status}), DR {peak_dr:.1f} N "
        f"({'peak passed' if collapse else 'no collapse proved: a lower bound'}), "
        f"LP {p_la:.1f} N")
    ref = t_drop if t_drop is not None else t_total
    say(f"  wall time: DR {t_dr:.1f} s ({'to 5 % past its peak' if collapse else 'stopped'}),"
        f" Newton {fmt(t_drop)} to 5 % past its peak ({fmt(t_past)} to the first point "
        f"past it, {fmt(t_total)} whole run)")
    say(f"  DR time / Newton time: {t_dr / ref:.0f} (same stopping rule), "
        f"{t_dr / t_total:.0f} (Newton's whole run)"
        + ("" if collapse else "; DR did not reach its peak: a lower bound of the ratio"))


if __name__ == "__main__":
    main()
