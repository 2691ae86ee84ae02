"""A bridge case run as an engineer asks it (``masonry-fdem bridge CASE.toml``): with a
continuum fill, the vehicle loaded to collapse at each of its positions (RING's question:
the critical position and the collapse load there); with a disk fill, the vehicle driven
across the bridge at its fixed load, equilibrium at each position.

:func:`sweep_bridge` (``[bridge] fill_model = "continuum"``): one run per position
(:meth:`BridgeCase.run`), the positions shared among the ranks, one rank per run. Writes to
``out``: ``sweep.md`` and ``sweep.png`` (collapse load against position, each run's
status; a run that found no peak gives a lower bound, drawn open), for the critical
position and the one nearest the first pier (or the span's end) ``vertical_stress_<x>.png``
(σ_yy in the fill, the soil and the arches at the peak: the reference paper's Figure 6) and
``mechanism_<x>.png``, and per position a ParaView series ``paraview_<x>/`` (``model.pvd``;
time = the live load's increment, every ``paraview_every`` increments and the last; time 0
is the model as built, before its self-weight).

:func:`traverse_bridge` (``fill_model = "disks"``;
:class:`~masonry_fdem.assessment.disk_bridge.DiskBridge`): the disks settled under
self-weight, then the vehicle at ``[vehicle] load`` driven through ``[vehicle] positions``.
Writes ``traverse.md``, ``traverse.png`` (the road's settlement under each axle against
the position), for two positions ``vertical_stress_<x>.png`` (σ_yy in the disk fill
averaged from the contact forces over ``cell``-wide cells: the load paths) and
``blocks_stress_<x>.png``, and ``paraview/`` (the blocks' ``model.pvd`` and the disks'
``disks.pvd``, one frame per position, time = x [m], -1 under self-weight).

With a disk fill the collapse load at each position is :func:`collapse_bridge` (``masonry-fdem
bridge --collapse --increment N``): for each position the bridge is built and settled
afresh, then the vehicle's load raised in steps of ``increment``, each held to equilibrium,
until the ring runs on (:meth:`DiskBridge.collapse`). Writes ``collapse.md`` (per position
the status, the collapse load or the largest load carried, the steps), ``collapse.png``
(load against the road's settlement under the vehicle) and ``vertical_stress_<x>.png`` (the
fill's σ_yy at the last load carried, for every position that carried one).

Units: SI (N, m, Pa); tables in kN and tonnes.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from mpi4py import MPI

import numpy as np

from masonry_fdem.constants import G
from masonry_fdem.solvers.status import Status

__all__ = ["BridgeSweep", "collapse_bridge", "sweep_bridge", "traverse_bridge"]


def _say(comm: MPI.Comm, quiet: bool) -> Callable[..., None]:
    if quiet:
        return lambda *a, **k: None
    return lambda *a, **k: print(*a, **{"flush": True, **k})


@dataclass
class BridgeSweep:
    """Result of :func:`sweep_bridge` (the same on every rank): one row per position
    (``x`` [m], ``load`` [N], ``collapsed``, ``status``, ``line``, ``seconds``), sorted by
    x; ``critical`` the row of the lowest collapse load among the runs that proved one
    (*peak passed*), or None."""

    rows: list[dict] = field(default_factory=list)
    critical: dict | None = None
    pictures: list[str] = field(default_factory=list)
    seconds: float = 0.0


def _positions(case, positions) -> list[float]:
    """``positions`` (default ``case.positions``) as floats, every axle checked on the deck."""
    xs = [float(x) for x in (case.positions if positions is None else positions)]
    if not xs:
        raise ValueError(f"{case.name}: no vehicle positions (vehicle.positions, or give "
                         "them)")
    half = 0.5 * case.vehicle.patch
    for x in xs:
        for k, (xa, _) in enumerate(case.vehicle.axles(x)):
            case.bridge.check_on_deck(xa, half, f"at x = {x:g} m, axle {k} of the vehicle")
    return xs


def _check_disk_args(cell: float, max_steps: int) -> None:
    if not cell > 0:
        raise ValueError(f"cell must be > 0 m, got {cell}")
    if not (isinstance(max_steps, int) and max_steps >= 1):
        raise ValueError(f"max_steps must be an integer >= 1, got {max_steps!r}")


def _folder(out, comm: MPI.Comm) -> Path:
    """``out`` as a Path, created by rank 0 (collective)."""
    out = Path(out)
    if comm.rank == 0:
        out.mkdir(parents=True, exist_ok=True)
    comm.barrier()
    return out


def _pier_x(bridge) -> float:
    """x [m] of the first pier's centre, or of the last span's far springing."""
    sp = bridge.springings()
    return 0.5 * (sp[0][1] + sp[1][0]) if len(sp) > 1 else sp[0][1]


def sweep_bridge(case, out: str | Path, positions: Sequence[float] | None = None, *,
                 paraview_every: int = 5, comm: MPI.Comm = MPI.COMM_WORLD,
                 quiet: bool = False) -> BridgeSweep:
    """Load the bridge of ``case`` (a continuum fill) to collapse with the vehicle at each
    of ``positions`` [m] (default ``case.positions``); write the module doc's files to
    ``out`` (collective; one rank per run). ``paraview_every``: 0 writes no ParaView
    series."""
    from masonry_fdem.io.plot import plot_blocks
    from masonry_fdem.io.vtx import VTXOutput

    if case.fill_model != "continuum":
        raise ValueError(f"{case.name}: bridge.fill_model is {case.fill_model!r}: a sweep "
                         "to collapse needs the continuum fill (a disk fill traverses at a "
                         "fixed load: traverse_bridge)")
    positions = _positions(case, positions)  # checked before any run
    if not (isinstance(paraview_every, int) and paraview_every >= 0):
        raise ValueError(f"paraview_every must be an integer >= 0, got {paraview_every!r}")
    say = _say(comm, quiet)
    out = _folder(out, comm)
    t0 = time.perf_counter()
    rows, drawn = [], {}
    for k in range(comm.rank, len(positions), comm.size):
        x = positions[k]
        vtx: dict = {}

        def on_model(model, inter, x=x, vtx=vtx):
            vtx["joints"] = inter[1]  # for the mechanism's picture
            if paraview_every == 0:
                return None
            w = VTXOutput(model, out / f"paraview_{x:g}", joints=inter[1])
            w.write(0.0)
            vtx.update(writer=w, n=0, last=0)

            def frame(load, disp):
                vtx["n"] += 1
                if vtx["n"] % paraview_every == 0:
                    w.write(float(vtx["n"]))
                    vtx["last"] = vtx["n"]
            return frame

        model, run = case.run(x, comm=MPI.COMM_SELF, on_model=on_model)
        joints = vtx.pop("joints", None)
        if vtx:
            if vtx["last"] != vtx["n"]:
                vtx["writer"].write(float(vtx["n"]))
            vtx["writer"].close()
        rows.append(dict(x=x, load=run.peak, collapsed=run.collapsed,
                         status=run.status.status.value, line=run.line(),
                         seconds=run.seconds, cells=model.blocks.n_cells))
        say(f"[rank {comm.rank}] vehicle at x = {x:g} m: {run.line()} ({run.seconds:.0f} s)")
        drawn[x] = (model, run, joints)
    rows = sorted((r for part in comm.allgather(rows) for r in part), key=lambda r: r["x"])
    proved = [r for r in rows if r["collapsed"]]
    crit = min(proved, key=lambda r: r["load"]) if proved else None
    x_pier = _pier_x(case.bridge)
    picks = {min(positions, key=lambda p: abs(p - x_pier))}
    if crit is not None:
        picks.add(crit["x"])
    mine = []
    for x, (model, run, joints) in drawn.items():
        if x not in picks or run.sigma_yy is None:
            continue
        now = model.u.x.array.copy()
        model.u.x.array[:] = run.u_peak
        names = model.blocks.block_names
        hide = [i for i, n in enumerate(names) if n.startswith("spandrel:")]
        # the colour scale of the fill (and the surfacing, the soil): the load's paths
        # through it; the masonry's higher stresses saturate
        soft = np.isin(model.blocks.cell_block, [i for i, n in enumerate(names)
                                                 if n in ("fill", "surfacing", "soil")])
        kpa = run.sigma_yy / 1e3
        lo, hi = np.percentile(kpa[soft] if soft.any() else kpa, [1.0, 99.0])
        plot_blocks(model, out / f"vertical_stress_{x:g}.png", field=kpa,
                    cmap="viridis_r", clim=(lo, min(hi, 0.0) if lo < 0 else hi), hide=hide,
                    title=f"vehicle at x = {x:g} m: σ_yy [kPa] at the peak, "
                          f"{run.peak / 1e3:.0f} kN\n(compression < 0; the fill's scale, "
                          "1 % to 99 %: the masonry saturates"
                          + ("; the spandrel walls outlined" if hide else "") + ")")
        model.u.x.array[:] = now
        plot_blocks(model, out / f"mechanism_{x:g}.png", scale=5.0, hide=hide, joints=joints,
                    title=f"vehicle at x = {x:g} m: deformed ×5 at the end of the run\n"
                          f"{run.line().split(' (')[0]}")
        mine += [f"vertical_stress_{x:g}.png", f"mechanism_{x:g}.png"]
    pictures = sorted(p for part in comm.allgather(mine) for p in part)
    res = BridgeSweep(rows, crit, pictures, time.perf_counter() - t0)
    if comm.rank == 0:
        text = _sweep_text(case, res, comm.size, paraview_every)
        (out / "sweep.md").write_text(text, encoding="utf-8")
        say(text)
        _sweep_plot(case, res, out / "sweep.png")
    comm.barrier()
    return res


def _sweep_text(case, res: BridgeSweep, size: int, every: int) -> str:
    b, rows, crit = case.bridge, res.rows, res.critical
    s0 = b.spans[0]
    v = case.vehicle
    lines = [
        f"# {case.name}: collapse load against the vehicle's position", "",
        f"{len(rows)} positions, {res.seconds:.0f} s on {size} rank(s); {rows[0]['cells']} "
        f"triangles. {len(b.spans)} span(s), the first {s0.span:g} m (rise {s0.rise:g} m, "
        f"ring {s0.ring_thickness:g} m); road {b.road_level():.2f} m, cover {b.cover:g} m "
        f"(surfacing {b.surfacing:g} m). Vehicle: axles at {list(v.offsets)} m from its "
        f"reference point, relative loads {list(v.loads)}, {v.patch:g} m patches; the load "
        f"is the vehicle's total, per {b.width:g} m of barrel width.", "",
        "| vehicle x [m] | / first span | collapse load [kN] | [t] | status | time [s] |",
        "|---|---|---|---|---|---|"]
    x0 = b.springings()[0][0]
    for r in rows:
        mark = "" if r["collapsed"] else "≥ "
        lines.append(f"| {r['x']:g} | {(r['x'] - x0) / s0.span:.3f} | {mark}"
                     f"{r['load'] / 1e3:.1f} | {mark}{r['load'] / (1e3 * G):.2f} | "
                     f"{r['status']} | {r['seconds']:.0f} |")
    lines.append("")
    if crit is None:
        lines.append("No run proved a collapse load (*peak passed*): no critical position; "
                     "the loads above are lower bounds.")
    else:
        lower = [r for r in rows if not r["collapsed"] and r["load"] < crit["load"]]
        lines.append(f"Critical position among those run: x = {crit['x']:g} m "
                     f"({(crit['x'] - x0) / s0.span:.3f} of the first span), "
                     f"{crit['load'] / 1e3:.1f} kN ({crit['load'] / (1e3 * G):.2f} t).")
        if lower:
            lines.append("Not proved: the runs at " + ", ".join(f"{r['x']:g} m" for r in lower)
                         + " found no peak below that load (lower bounds); the critical "
                         "position may lie there.")
    lines += ["", "Pictures: " + (", ".join(res.pictures) or "none") + "."]
    if every:
        lines.append(f"ParaView: paraview_<x>/model.pvd per position (every {every} "
                     "increments and the last; time = increment, 0 the model as built).")
    return "\n".join(lines) + "\n"


def _sweep_plot(case, res: BridgeSweep, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = res.rows
    xs = np.array([r["x"] for r in rows])
    ys = np.array([r["load"] for r in rows]) / 1e3
    ok = np.array([r["collapsed"] for r in rows])
    fig, ax = plt.subplots(figsize=(6.5, 4))
    ax.plot(xs, ys, "-", color="C0", lw=1)
    if ok.any():
        ax.plot(xs[ok], ys[ok], "o", color="C0", label="collapse (peak passed)")
    if (~ok).any():
        ax.plot(xs[~ok], ys[~ok], "^", mfc="none", color="C0", label="lower bound (no peak)")
    for (a, c) in case.bridge.springings():
        ax.axvspan(a, c, color="0.9", zorder=0)
    if len(case.bridge.spans) > 1:
        ax.axvline(_pier_x(case.bridge), color="0.5", ls=":", lw=1, label="pier")
    sp = case.bridge.springings()
    ax.set_xlim(min(xs.min(), sp[0][0]) - 0.3, max(xs.max(), sp[0][1]) + 0.3)
    ax.set_ylim(bottom=0.0)
    ax.set_xlabel("vehicle position x [m] (spans shaded)")
    ax.set_ylabel(f"collapse load, all axles [kN per {case.bridge.width:g} m]")
    ax.set_title(f"{case.name}: collapse load against the vehicle's position", fontsize=9)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def traverse_bridge(case, out: str | Path, *, pictures: Sequence[float] | None = None,
                    cell: float = 0.25, max_steps: int = 300_000,
                    comm: MPI.Comm = MPI.COMM_WORLD, quiet: bool = False):
    """Settle the disk-filled bridge of ``case`` and drive its vehicle at ``case.load``
    [N] through ``case.positions`` (collective; the disks on every rank, the blocks
    distributed). ``pictures``: the positions [m] whose stress is pictured (default: the
    first and the one nearest the first pier); ``cell`` [m] the stress-averaging cells.
    Returns the :class:`~masonry_fdem.assessment.disk_bridge.DiskTraverse`; a fill that
    does not settle is a ``RuntimeError`` (nothing to traverse)."""
    from masonry_fdem.assessment.disk_bridge import draw_bridge_stress
    from masonry_fdem.assessment.disk_fill import stress_grid
    from masonry_fdem.io import DiskOutput
    from masonry_fdem.io.plot import plot_blocks
    from masonry_fdem.io.vtx import VTXOutput

    if case.fill_model != "disks":
        raise ValueError(f"{case.name}: bridge.fill_model is {case.fill_model!r}: a traverse "
                         'at a fixed load is run with fill_model = "disks"')
    if not case.positions:
        raise ValueError(f"{case.name}: no vehicle.positions to traverse")
    _check_disk_args(cell, max_steps)
    say = _say(comm, quiet or comm.rank != 0)
    out = _folder(out, comm)
    t0 = time.perf_counter()
    b = case.disk_bridge(comm)
    say(f"{b.disks.n} disks (r {b.disks.r.min() * 1e3:.0f}–{b.disks.r.max() * 1e3:.0f} mm), "
        f"{b.model.blocks.n_cells} triangles, blocks' inertia ×{b.inertia_scale:.0f}; "
        "settling under self-weight ...")
    tol = case.disks.tol
    ok = b.settle(tol=tol, max_steps=max_steps)
    rd, rb = b.ratios()
    settle_s = time.perf_counter() - t0
    say(f"self-weight: {'equilibrium' if ok else 'NOT settled'} (ratios disks {rd:.1e}, "
        f"blocks {rb:.1e}; {b.steps_held} + {b.steps_free} steps, {b.trimmed} disks trimmed "
        f"above the fill, {settle_s:.0f} s)")
    if not ok:
        raise RuntimeError(f"{case.name}: the disk fill did not settle under self-weight "
                           f"within {max_steps} steps (ratios disks {rd:.1e}, blocks {rb:.1e},"
                           f" tol {tol:g}): no traverse")
    want = ([case.positions[0], min(case.positions, key=lambda p: abs(p - _pier_x(
        case.bridge)))] if pictures is None else list(pictures))
    picks = {min(case.positions, key=lambda p, x=x: abs(p - x)) for x in want}
    drawn: list[str] = []
    pv = out / "paraview"
    blocks_out = VTXOutput(b.model, pv, joints=b.blocks[1])
    disks_out = DiskOutput(b.disks, pv)
    blocks_out.write(-1.0)
    disks_out.write(-1.0)
    ref = b.model.u.x.array.copy()
    ring0 = b.ring_state()

    def at(br, x):
        blocks_out.write(x)
        disks_out.write(x)
        s = ", ".join(f"{v * 1e3:.2f}" for v in br.axle_settlements(ref))
        say(f"  vehicle at x = {x:g} m: equilibrium in {br.last_steps} steps; road settlement "
            f"under the axles {s} mm, the ring moved {br.ring_motion(ring0) * 1e3:.2f} mm "
            f"({time.perf_counter() - t0:.0f} s)")
        if x not in picks:
            return
        grid = stress_grid(br, cell)
        road = br.road_profile()
        name = f"vertical_stress_{x:g}.png"
        if comm.rank == 0:
            draw_bridge_stress(br, grid, (br.disks.x, br.disks.r), out / name, road=road, title=(
                f"{case.name}: vehicle at x = {x:g} m, {case.load / 1e3:.0f} kN; σ_yy in "
                "the disk fill"))
        top = float(br.slab[:, 1].max())
        blocks = f"blocks_stress_{x:g}.png"
        plot_blocks(br.model, out / blocks, field="sigma_yy", disks=br.disks,
                    loads=np.array([(xa, top) for xa, _ in br.axles]),
                    load_label=" + ".join(f"{p / 1e3:.0f}" for _, p in br.axles) + " kN",
                    title=f"vehicle at x = {x:g} m: σ_yy in the blocks, the disks drawn")
        drawn.extend([name, blocks])

    run = b.traverse(case.vehicle, case.positions, case.load, tol=tol, max_steps=max_steps,
                     runaway=case.disks.runaway, callback=at)
    blocks_out.close()
    say(run.line())
    if comm.rank == 0:
        text = _traverse_text(case, b, run, drawn, comm.size, time.perf_counter() - t0,
                              settle_s, tol)
        (out / "traverse.md").write_text(text, encoding="utf-8")
        say(text)
        _traverse_plot(case, run, out / "traverse.png")
    comm.barrier()
    return run


def _traverse_text(case, b, run, drawn, size, seconds, settle_s, tol) -> str:
    br = case.bridge
    lines = [
        f"# {case.name}: the vehicle traversing the disk-filled bridge", "",
        f"{b.disks.n} disks (radii {b.disks.r.min() * 1e3:.0f}–{b.disks.r.max() * 1e3:.0f} "
        f"mm, porosity {case.disks.porosity:g}), {b.model.blocks.n_cells} triangles; "
        f"{size} rank(s), {seconds:.0f} s in all, of which {settle_s:.0f} s settling under "
        f"self-weight ({b.steps_held} + {b.steps_free} explicit steps, ratios below "
        f"{tol:g}). {len(br.spans)} span(s) of {br.spans[0].span:g} m, cover {br.cover:g} m "
        f"(surfacing {br.surfacing:g} m). The vehicle: axles at {list(case.vehicle.offsets)} "
        f"m from its reference point, {case.load / 1e3:.0f} kN in all over the "
        f"{br.width:g} m strip, {case.vehicle.patch:g} m tyre patches.", "",
        f"**Status: {run.line()}**", "",
        "| vehicle x [m] | explicit steps | settlement under each axle [mm] | "
        "ring's largest displacement [mm] | ratios (disks, blocks) |", "|---|---|---|---|---|"]
    for x, n, s, g, r in zip(run.positions, run.steps, run.settlements, run.ring, run.ratios,
                             strict=True):
        lines.append(f"| {x:g} | {n} | {', '.join(f'{v * 1e3:.2f}' for v in s)} | "
                     f"{g * 1e3:.2f} | {r[0]:.1e}, {r[1]:.1e} |")
    lines += ["", "Settlement: the surfacing's top under each tyre patch; the ring's: the "
              "largest displacement of a voussoir node; both from the state under "
              "self-weight. Pictures: " + (", ".join(drawn) or "none") + ". ParaView: "
              "paraview/model.pvd (blocks) and paraview/disks.pvd, one frame per position "
              "(time: x [m]; -1 under self-weight)."]
    return "\n".join(lines) + "\n"


def _traverse_plot(case, run, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.5, 3.8))
    if run.positions:
        s = np.array(run.settlements) * 1e3
        for k, o in enumerate(case.vehicle.offsets):
            ax.plot(run.positions, s[:, k], "o-", label=f"axle {k} ({o:+g} m)")
        ax.set_xlim(min(run.positions) - 1.0, max(run.positions) + 1.0)
        ax.legend(fontsize=8)
    for a, c in case.bridge.springings():
        ax.axvspan(a, c, color="0.9", zorder=0)
    ax.set_xlabel("vehicle position x [m] (spans shaded)")
    ax.set_ylabel("road settlement under the axle [mm]")
    ok = "" if run.status.status is Status.LOAD_REACHED else f" ({run.status.status.value})"
    ax.set_title(f"{case.name}: {case.load / 1e3:.0f} kN vehicle traversing{ok}", fontsize=9)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def collapse_bridge(case, out: str | Path, increment: float,
                    positions: Sequence[float] | None = None, *, max_load: float = math.inf,
                    cell: float = 0.25, max_steps: int = 300_000,
                    comm: MPI.Comm = MPI.COMM_WORLD, quiet: bool = False) -> list:
    """The disk-filled bridge of ``case`` loaded to collapse with the vehicle at each of
    ``positions`` [m] (default ``case.positions``), a fresh bridge settled for each, the
    load raised in steps of ``increment`` [N] up to ``max_load`` (collective; every rank
    works on every run). Returns the :class:`~masonry_fdem.assessment.disk_fill.DiskFillRun`
    of each position; writes the module doc's files to ``out``."""
    from masonry_fdem.assessment.disk_bridge import draw_bridge_stress
    from masonry_fdem.assessment.disk_fill import stress_grid

    if case.fill_model != "disks":
        raise ValueError(f"{case.name}: bridge.fill_model is {case.fill_model!r}: the "
                         "continuum fill's collapse loads come from sweep_bridge")
    positions = _positions(case, positions)
    if not (math.isfinite(increment) and increment > 0):
        raise ValueError(f"increment must be > 0 N, got {increment}")
    _check_disk_args(cell, max_steps)
    say = _say(comm, quiet or comm.rank != 0)
    out = _folder(out, comm)
    t0 = time.perf_counter()
    runs, counts = [], []
    for x in positions:
        b = case.disk_bridge(comm)
        ok = b.settle(tol=case.disks.tol, max_steps=max_steps)
        rd, rb = b.ratios()
        if not ok:
            raise RuntimeError(f"{case.name}: the disk fill did not settle under self-weight "
                               f"within {max_steps} steps (ratios disks {rd:.1e}, blocks "
                               f"{rb:.1e}, tol {case.disks.tol:g}): no collapse run at "
                               f"x = {x:g} m")
        say(f"vehicle at x = {x:g} m: {b.disks.n} disks settled ({b.steps_held} + "
            f"{b.steps_free} steps); raising the load by {increment / 1e3:g} kN ...")

        last: dict = {}

        def at(br, load, x=x, last=last):
            say(f"  {load / 1e3:g} kN carried at x = {x:g} m in {br.last_steps} steps "
                f"({time.perf_counter() - t0:.0f} s)")
            # the fill's stress at this equilibrium (the run ends beyond the last one)
            last.update(grid=stress_grid(br, cell), disks=(br.disks.x.copy(), br.disks.r),
                        axles=list(br.axles), road=br.road_profile())

        run = b.collapse(case.vehicle, x, increment, max_load=max_load, tol=case.disks.tol,
                         max_steps=max_steps, runaway=case.disks.runaway, callback=at)
        say(f"vehicle at x = {x:g} m: {run.line()}")
        runs.append(run)
        counts.append(b.disks.n)
        if last and comm.rank == 0:
            b.axles = last["axles"]
            draw_bridge_stress(b, last["grid"], last["disks"], out / f"vertical_stress_{x:g}.png",
                               road=last["road"], title=f"{case.name}: vehicle at x = {x:g} m, "
                                     f"{run.loads[-1] / 1e3:.0f} kN (the last load carried); "
                                     "σ_yy in the disk fill")
    if comm.rank == 0:
        text = _collapse_text(case, positions, runs, counts, increment, comm.size,
                              time.perf_counter() - t0)
        (out / "collapse.md").write_text(text, encoding="utf-8")
        say(text)
        _collapse_plot(case, positions, runs, out / "collapse.png")
    comm.barrier()
    return runs


def _collapse_text(case, positions, runs, counts, increment, size, seconds) -> str:
    br = case.bridge
    lines = [
        f"# {case.name}: collapse load of the disk-filled bridge against the vehicle's "
        "position", "",
        f"{len(runs)} position(s), {seconds:.0f} s on {size} rank(s); a fresh bridge "
        f"({counts[0]} disks) settled for each. {len(br.spans)} span(s) of "
        f"{br.spans[0].span:g} m, cover {br.cover:g} m (surfacing {br.surfacing:g} m). The "
        f"vehicle: axles at {list(case.vehicle.offsets)} m from its reference point, "
        f"relative loads {list(case.vehicle.loads)}, {case.vehicle.patch:g} m tyre patches; "
        f"its load raised in steps of {increment / 1e3:g} kN (the load is over the "
        f"{br.width:g} m strip), each held by explicit dynamics to equilibrium (ratios "
        f"below {case.disks.tol:g}).", "",
        "| vehicle x [m] | status | collapse load [kN] | [t] | road settlement at the last "
        "load carried [mm] | explicit steps |", "|---|---|---|---|---|---|"]
    for x, r in zip(positions, runs, strict=True):
        c = r.collapse_load
        load = f"{c / 1e3:.1f}" if c is not None else f"≥ {r.loads[-1] / 1e3:.1f}"
        t = f"{c / (1e3 * G):.2f}" if c is not None else f"≥ {r.loads[-1] / (1e3 * G):.2f}"
        lines.append(f"| {x:g} | {r.status.status.value} | {load} | {t} | "
                     f"{r.displacements[-1] * 1e3:.1f} | {sum(r.steps[1:])} |")
    proved = [(r.collapse_load, x) for x, r in zip(positions, runs, strict=True)
              if r.collapse_load is not None]
    lines.append("")
    if proved:
        c, x = min(proved)
        lines.append(f"Lowest collapse load proved: {c / 1e3:.1f} kN at x = {x:g} m (a "
                     f"mechanism one step above it, at {(c + increment) / 1e3:.1f} kN).")
    else:
        lines.append("No run proved a collapse load (a mechanism): the loads are lower "
                     "bounds.")
    lines += ["", "Status: *mechanism*: the ring ran on under the next load (the collapse "
              "load lies between the last load carried and the next); *load reached*: the "
              "largest load asked was carried; *not converged*: an equilibrium did not "
              "come within the steps allowed (a lower bound)."]
    for x, r in zip(positions, runs, strict=True):
        lines.append(f"- x = {x:g} m: {r.line()}")
    return "\n".join(lines) + "\n"


def _collapse_plot(case, positions, runs, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.5, 4))
    for k, (x, r) in enumerate(zip(positions, runs, strict=True)):
        d = np.array(r.displacements) * 1e3
        f = np.array(r.loads) / 1e3
        ax.plot(d, f, "o-", ms=3, color=f"C{k}", label=f"x = {x:g} m: {r.status.status.value}")
    ax.set_xlabel("road settlement under the vehicle [mm]")
    ax.set_ylabel(f"vehicle load [kN per {case.bridge.width:g} m]")
    ax.set_xlim(left=0.0)
    ax.set_ylim(bottom=0.0)
    ax.set_title(f"{case.name}: disk fill loaded to collapse", fontsize=9)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
