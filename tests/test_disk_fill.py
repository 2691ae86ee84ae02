"""A bridge's fill as disks loaded to collapse quasi-statically (issue #22, item 4;
:mod:`masonry_fdem.assessment.disk_fill`): explicit dynamics with Cundall's local damping,
each load held until the unbalanced-force ratios fall below 1e-3; a load with no
equilibrium (the beam running on under it) is a mechanism, and the collapse load is the
last load carried, within one increment.

The bridge is the small single span of ``tests/test_bridge.py`` (a 2 m segmental ring,
0.15 m thick, dry joints, 0.2 m of fill over the crown, the load at quarter span on a
0.2 m beam), its fill packed with about 300 disks."""

from __future__ import annotations

import math

from mpi4py import MPI

import numpy as np
import pytest

from masonry_fdem.assessment.assess import assess
from masonry_fdem.assessment.case import CaseError, load_case
from masonry_fdem.assessment.disk_fill import DiskFillBridge
from masonry_fdem.assessment.report import read_curve
from masonry_fdem.constants import G
from masonry_fdem.io.checkpoint import CheckpointError
from masonry_fdem.solvers.status import Status

from test_bridge import small

INCREMENT = 10e3  # [N]
MAX_STEPS = 400_000
RUNAWAY = 0.015  # [m]


def _run(comm, increment=INCREMENT, tol=1e-3, **kw):
    case = load_case(small())
    b = DiskFillBridge(case, count=300, seed=1, comm=comm)
    assert b.settle(tol=tol)
    seen = {}

    def at(br, p):
        # the vertical reactions (abutments, end walls) against the weight of the blocks
        # and disks and the load, at every equilibrium
        react = sum(v[1] for v in br.solver.reactions().values())
        dead = -br.comm.allreduce(float(br.model.f_dead[1::2].sum()))
        seen[p] = react / (dead + br.disks.weight + p)

    run = b.load(increment, max_steps=MAX_STEPS, tol=tol, callback=at, **kw)
    return case, b, run, seen


def disk_case(**disks) -> dict:
    """The small bridge's case with ``[fill] model = "disks"`` and its ``[fill.disks]``."""
    d = small(loading__increment=INCREMENT)
    d["fill"].pop("mesh_size")  # (the continuum's)
    d["fill"].update(model="disks", disks={"count": 300, "max_steps": MAX_STEPS, **disks})
    return d


@pytest.mark.skipif(MPI.COMM_WORLD.size > 1, reason="one process (the suite's budget); "
                    "under mpirun the same run is compared across ranks instead")
def test_disk_fill_carries_the_ring_to_a_mechanism(tmp_path):
    """The case file's ``[fill] model = "disks"`` run by ``assess``: a mechanism, more
    than the bare ring's limit load, every load carried an equilibrium (reactions =
    weight + load within 2 %), the ring itself moving at the collapse (a bridge
    mechanism, not the beam alone sinking), and the run folder of any assessment with
    the disks' stress picture."""
    comm = MPI.COMM_WORLD
    seen, held = {}, {}

    def at(state):
        # the vertical reactions (abutments, end walls) against the weight of the blocks
        # and disks and the load, at every equilibrium
        br, p = state["bridge"], state["load"]
        react = sum(v[1] for v in br.solver.reactions().values())
        dead = -br.comm.allreduce(float(br.model.f_dead[1::2].sum()))
        seen[p] = react / (dead + br.disks.weight + p)
        held["bridge"] = br

    # the ring's runaway at 15 mm, a tenth of its thickness (the suite's budget: the
    # default quarter took some 250000 steps at the load that found no equilibrium)
    case = load_case(disk_case(runaway=RUNAWAY))
    res = assess(case, out=tmp_path / "run", progress=False, comm=comm, callback=at)
    b = held["bridge"]
    bare = load_case({k: v for k, v in small().items() if k != "fill"}).limit_analysis()
    vous = np.isin(b.model.node_block, b.model.select_blocks("voussoir:*"))
    u = b.model.u.x.array.reshape(-1, 2)[: b.model.n_nodes][vous]
    moved = comm.allreduce(float(np.linalg.norm(u, axis=1).max(initial=0.0)), op=MPI.MAX)
    t = res.collapse_load / (1000 * G) if res.collapse_load else math.nan
    print(f"\ndisk fill ({b.disks.n} disks, {b.trimmed} trimmed above the road, inertia "
          f"×{b.inertia_scale:.0f}): {res.status_line} ({t:.2f} t; {res.status.detail}); "
          f"bare ring limit analysis {bare.load_factor / 1e3:.2f} kN, with fill "
          f"{res.limit_load / 1e3:.2f} kN; reactions / (weight + load) "
          + ", ".join(f"{p / 1e3:.0f} kN {v:.4f}" for p, v in seen.items())
          + f"; ring moved {moved * 1e3:.1f} mm; steps {res.iterations}; "
          f"{res.elapsed:.1f} s")
    assert res.status.status is Status.MECHANISM
    assert res.collapse_load == res.loads[-1] == res.peak_load and res.collapse_load > 0
    assert res.resolution == INCREMENT and list(res.loads) == [
        k * INCREMENT for k in range(len(res.loads))]
    # the fill spreads the load and holds the haunches: more than the bare ring
    assert res.collapse_load > 1.5 * bare.load_factor
    assert sorted(seen) == list(res.loads[1:])
    for p, ratio in seen.items():
        # (the ratios bound the mean imbalance of a disk, not the sum over the fill)
        assert ratio == pytest.approx(1.0, abs=0.02), p
    # (the run stops the load once a voussoir has moved RUNAWAY under it; measured here
    # from the unloaded geometry)
    assert moved > 0.8 * RUNAWAY
    # a ring mechanism: hinges open at the end of the run on both sides of the crown,
    # turning about the intrados and about the extrados (found from the joints' openings)
    hinges = [e for e in res.hinges_at_collapse if e.kind == "hinge"]
    assert len(hinges) >= 4, hinges
    assert {e.side for e in hinges} == {"intrados", "extrados"}
    assert min(e.s for e in hinges) < 0.25 < 0.5 < max(e.s for e in hinges)
    # the run folder, as for any case
    names = {p.name for p in res.folder.iterdir()}
    assert {"report.md", "curve.csv", "summary.json", "load_displacement.png",
            "mechanism.png", "vertical_stress.png"} <= names
    text = res.report.read_text(encoding="utf-8")
    assert f"**Status: mechanism — collapse load {res.collapse_load / 1e3:.2f} kN.**" in text
    assert "disks (300 asked of the packer" in text and "Cundall" in text
    assert "![last load carried: the disks' vertical stress](vertical_stress.png)" in text
    status, rows = read_curve(res.folder / "curve.csv")
    assert status.startswith("mechanism") and np.allclose(rows[:, 0], res.loads)


def test_disk_fill_same_on_any_number_of_ranks():
    """The issue's line: with disks, the same status on two ranks as on one, and a
    collapse load within one increment."""
    comm = MPI.COMM_WORLD
    if comm.size == 1:
        pytest.skip("compares ranks: run under mpirun -n 2")
    # cheaper than the test above (the suite's budget): 15 kN steps, the ring's runaway
    # at 5 mm instead of a quarter of its 0.15 m, and equilibrium at ratios below 3e-3
    # (66 s for both runs where the defaults took 213 s; the looser ratio carries 30 kN,
    # which at 1e-3 found no equilibrium: the same on any number of ranks either way)
    kw = dict(increment=15e3, runaway=0.005, tol=3e-3)
    _, _, world, _ = _run(comm, **kw)
    _, _, one, _ = _run(MPI.COMM_SELF, **kw)
    print(f"\ndisk fill, {comm.size} ranks: {world.line()}; 1 rank: {one.line()}")
    assert world.status.status is one.status.status
    assert abs(world.status.peak - one.status.peak) <= kw["increment"] * (1 + 1e-12)


def test_bad_input():
    case = load_case(small())
    with pytest.raises(ValueError, match=r"\[fill\]"):
        DiskFillBridge(load_case({k: v for k, v in small().items() if k != "fill"}))
    with pytest.raises(ValueError, match="overfill"):
        DiskFillBridge(case, count=150, overfill=-0.1)
    with pytest.raises(ValueError, match="local_damping"):
        DiskFillBridge(case, count=150, local_damping=1.0)
    with pytest.raises(ValueError, match="surfacing must be"):
        DiskFillBridge(case, count=150, surfacing=0.2)  # as thick as the cover
    with pytest.raises(ValueError, match="surfacing_material"):
        DiskFillBridge(case, count=150, surfacing=0.05)
    b = DiskFillBridge(case, count=150)
    with pytest.raises(RuntimeError, match="settle"):
        b.load(INCREMENT)


@pytest.mark.parametrize("change, message", [
    (lambda d: d["fill"].update(model="granular"), r"fill\.model"),
    (lambda d: d["fill"].update(model="continuum"),
     r'fill\.disks: given, but fill\.model is "continuum"'),
    (lambda d: d["loading"].update(control="displacement", displacement_increment=1e-4),
     r"loading\.control: a disk fill is loaded in load steps"),
    (lambda d: d["fill"]["disks"].update(surfacing=0.05),
     r"fill\.disks\.surfacing: a road layer needs its surfacing_material"),
    (lambda d: d["fill"]["disks"].update(surfacing=0.05, surfacing_material="road"),
     r"fill\.disks\.surfacing_material: no \[materials\.road\]"),
    (lambda d: d["fill"]["disks"].update(surfacing=0.3, surfacing_material="brick"),
     r"fill\.disks\.surfacing: 0\.3 m must be thinner than the cover"),
    (lambda d: d["fill"]["disks"].update(porosity=0.7), r"fill\.disks\.porosity"),
    (lambda d: d["loading"].update(self_weight=False), r"loading\.self_weight: a disk fill"),
    (lambda d: d["fill"].update(crossed=True), r"fill\.crossed: an option of the continuum"),
    (lambda d: d["fill"].update(mesh_size=0.1),
     r"fill\.mesh_size: an option of the continuum"),
    (lambda d: d.update(anchors=[dict(layout="radial", angles=[90.0], diameter=0.016)]),
     r"anchors: not modelled with a disk fill"),
    (lambda d: d["fill"]["disks"].update(radius=0.01),
     r"unknown key 'radius' in \[fill\.disks\]"),
])
def test_case_file_disk_fill_bad_input_names_the_key(change, message):
    d = disk_case()
    change(d)
    with pytest.raises(CaseError, match=message):
        load_case(d)


def test_case_file_picks_the_fill_model(tmp_path):
    """``[fill] model``: the continuum by default; "disks" with ``[fill.disks]`` (its
    defaults for what is not given), which ``DiskFillBridge.from_case`` follows."""
    assert load_case(small()).fill.model == "continuum"
    case = load_case(disk_case(friction=0.4))
    assert case.fill.model == "disks"
    assert (case.fill.disks.count, case.fill.disks.max_steps) == (300, MAX_STEPS)
    assert case.fill.disks.friction == 0.4 and case.fill.disks.porosity == 0.2
    b = DiskFillBridge.from_case(case)
    assert b.disks.materials["fill"].friction == 0.4 and b.disks.materials["fill"].E == 1e8
    assert b.local_damping == 0.7 and b.surfacing == 0.0
    with pytest.raises(CheckpointError, match="disk fill"):
        assess(case, write=True, resume=True, progress=False)
    # a stress picture of one column is refused before the run, not after it
    with pytest.raises(ValueError, match=r"fill\.disks\.cell 2 m is wider than half"):
        assess(load_case(disk_case(cell=2.0)), write=True, progress=False,
               out=tmp_path / "run")
    assert not (tmp_path / "run" / "report.md").exists()


def test_scale_inertia_lengthens_the_step_and_keeps_the_weight():
    """Density scaling (Model.scale_inertia): the mass and the elements' critical step
    grow by the factor and its square root; the self-weight added before stays."""
    from masonry_fdem import Material, Model
    from masonry_fdem.geometry.layout import BlockLayout

    sq = np.array([[0, 0], [0.4, 0], [0.4, 0.2], [0, 0.2]], float)
    mesh = BlockLayout((sq,), ("stone",), ("block",)).mesh(0.1, MPI.COMM_WORLD)
    model = Model(mesh, {"stone": Material(density=2000.0, E=1e10, nu=0.2)}, width=0.5)
    model.add_gravity()
    dt, mass = model.stable_time_step(), model.comm.allreduce(float(model.mass.sum()))
    weight = model.comm.allreduce(float(model.f_dead[1::2].sum()))
    model.scale_inertia(4.0)
    assert model.stable_time_step() == pytest.approx(2.0 * dt, rel=1e-12)
    assert model.comm.allreduce(float(model.mass.sum())) == pytest.approx(4.0 * mass,
                                                                          rel=1e-12)
    assert model.comm.allreduce(float(model.f_dead[1::2].sum())) == weight
    assert weight == pytest.approx(-2000.0 * 0.4 * 0.2 * 0.5 * G, rel=1e-12)
    for bad in (0.5, math.nan, math.inf):
        with pytest.raises(ValueError, match="inertia"):
            model.scale_inertia(bad)
