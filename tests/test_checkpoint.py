"""Checkpoints and restarts (issue #24, items 1-2): a run stopped at a checkpoint and
resumed ends bitwise equal to the uninterrupted run (an explicit contact run and a
quasi-static collapse by path following), serial and under ``mpirun -n 2``; a process
killed while writing a checkpoint leaves the one before readable; SIGINT to a running
``masonry-fdem assess`` stops it with status 130 and no traceback, and ``--resume``
finishes it with the collapse load of an uninterrupted run."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

from mpi4py import MPI

import numpy as np
import pytest

from masonry_fdem import Material, Model
from masonry_fdem.geometry import mesh_blocks, rectangle
from masonry_fdem.interactions import BlockContact, ContactSettings
from masonry_fdem.io import checkpoint as ckpt
from masonry_fdem.io.checkpoint import Checkpointer, CheckpointError, Interrupted
from masonry_fdem.solvers import ExplicitSolver

STONE = Material(density=2400.0, E=2e9, nu=0.2)
ROOT = Path(__file__).resolve().parents[1]


def shared_tmp(tmp_path: Path, comm) -> Path:
    """One folder for every rank (rank 0's tmp_path)."""
    return Path(comm.bcast(str(tmp_path), root=0))


# ------------------------------------------------------------------------- explicit
def explicit_run(comm):
    """Three blocks: a base, a block sliding on it and one falling onto it."""
    blocks = mesh_blocks([rectangle(0.0, 0.0, 0.6, 0.1), rectangle(0.1, 0.1, 0.3, 0.2),
                          rectangle(0.32, 0.105, 0.5, 0.2)],
                         materials="stone", mesh_size=0.04, comm=comm)
    model = Model(blocks, {"stone": STONE}, hypothesis="plane_stress", width=0.1, comm=comm)
    model.fix_blocks(0, name="base")
    model.add_gravity()
    model.v[0::2] = np.where(model.node_block == 1, 0.4, 0.0)
    # (neighbour searches every 7 steps: not at a checkpoint's step, so a resume that
    # searched again at once would be caught)
    return ExplicitSolver(model, interactions=[BlockContact(model,
                                                            ContactSettings(rebuild_every=7))])


def state_of(solver) -> list[np.ndarray]:
    return ([s.u.copy() for s in solver.sets] + [s.v.copy() for s in solver.sets]
            + [s.energy.copy() for s in solver.sets]
            + [a for c in solver.interactions for a in c.state().values()]
            + [solver.work.copy()])


def test_explicit_contact_run_resumes_bitwise(tmp_path):
    comm = MPI.COMM_WORLD
    folder = shared_tmp(tmp_path, comm)
    steps, every = 600, 50
    ref = explicit_run(comm)
    ref.run(steps=steps, every=every)
    rebuilds = ref.interactions[0].rebuilds
    assert rebuilds > 2  # the neighbour lists were found again during the run

    run = explicit_run(comm)
    ck = Checkpointer(folder / "run", comm, kind="explicit", every=150)

    def stop(s):
        if s.n == 300:
            ckpt.request_stop()  # as the signal handler does

    try:
        with pytest.raises(Interrupted) as exc:
            run.run(steps=steps, every=every, callback=stop, checkpoint=ck)
    finally:
        ckpt.clear_stop()
    assert exc.value.step == 300 and run.n == 300

    again = explicit_run(comm)
    assert again.resume(Checkpointer(folder / "run", comm, kind="explicit")) == 300
    again.run(steps=steps - 300, every=every)
    for a, b in zip(state_of(ref), state_of(again), strict=True):
        assert np.array_equal(a, b)
    assert again.t == ref.t and again.n == ref.n
    # the neighbour lists were found again at the same steps, at the same positions
    c0, c1 = ref.interactions[0], again.interactions[0]
    assert (c1.rebuilds, c1.since, c1.travel) == (rebuilds, c0.since, c0.travel)
    assert np.array_equal(c1._u_rebuild, c0._u_rebuild)
    assert np.array_equal(c1.pairs, c0.pairs)
    assert again.energies() == ref.energies()


def mixed_run(comm):
    """Blocks, disks falling on them, a disk-block contact and an anchor (as the
    protocol's replay test)."""
    from masonry_fdem.interactions import (
        Anchor,
        Anchors,
        DiskBlockContact,
        DiskMaterial,
        Disks,
    )

    blocks = mesh_blocks([rectangle(0.0, 0.0, 0.4, 0.1), rectangle(0.1, 0.1, 0.3, 0.2)],
                         materials="stone", mesh_size=0.05, comm=comm)
    model = Model(blocks, {"stone": STONE}, hypothesis="plane_stress", width=0.05, comm=comm)
    model.fix_blocks(0, name="base")
    model.add_gravity()
    model.v[0::2] = np.where(model.node_block == 1, 0.3, 0.0)
    x = np.c_[[0.1, 0.1235, 0.26, 0.36], np.full(4, 0.2121)]
    disks = Disks(x, np.full(4, 0.012), {"g": DiskMaterial(density=2600.0, E=1e8, nu=0.25)},
                  "g", width=0.05, comm=comm)
    disks.add_gravity()
    disks.v[:, 1] = -0.2
    anchors = Anchors(model, [Anchor([[0.12, 0.15], [0.28, 0.15]], diameter=0.01)])
    return ExplicitSolver(model, interactions=[BlockContact(model), disks,
                                               DiskBlockContact(disks, model), anchors])


def test_explicit_run_with_disks_and_anchors_resumes_bitwise(tmp_path):
    comm = MPI.COMM_WORLD
    folder = shared_tmp(tmp_path, comm) / "run"
    ref = mixed_run(comm)
    ref.run(steps=400, every=50)
    run = mixed_run(comm)
    ck = Checkpointer(folder, comm, kind="explicit", every=200)
    run.run(steps=250, every=50, checkpoint=ck)  # the checkpoint of step 200 is current
    again = mixed_run(comm)
    assert again.resume(Checkpointer(folder, comm, kind="explicit")) == 200
    again.run(steps=200, every=50)
    assert min(abs(v["work"]) for v in again.energies().interactions.values()) > 0
    for a, b in zip(state_of(ref)[:-1] + [ref.work], state_of(again)[:-1] + [again.work],
                    strict=True):
        assert np.array_equal(a, b)
    assert again.energies() == ref.energies()


@pytest.mark.parametrize("where", ["rank file", "manifest"])
def test_killed_while_writing_keeps_the_previous_checkpoint(tmp_path, monkeypatch, where):
    """A writer that dies half way through the second generation — in its rank files
    (every rank), or in the manifest after them (rank 0; serial): the current generation
    stays the first, and a resume from it ends as the uninterrupted run."""
    comm = MPI.COMM_WORLD
    if where == "manifest" and comm.size > 1:
        pytest.skip("rank 0 alone dies there: the other ranks would wait for it")
    folder = shared_tmp(tmp_path, comm) / "run"
    ref = explicit_run(comm)
    ref.run(steps=300, every=50)
    run = explicit_run(comm)
    ck = Checkpointer(folder, comm, kind="explicit", every=100)
    real = ckpt._write_atomic
    calls = {"n": 0}

    class Killed(BaseException):
        pass

    target = "manifest.json" if where == "manifest" else f"rank{comm.rank}.pkl"

    def dying(path, data):
        if path.name == target:
            calls["n"] += 1
            if calls["n"] == 2:  # the second generation
                path.with_name(path.name + ".tmp").write_bytes(data[: len(data) // 2])
                raise Killed
        real(path, data)

    monkeypatch.setattr(ckpt, "_write_atomic", dying)
    with pytest.raises(Killed):
        run.run(steps=300, every=50, checkpoint=ck)
    monkeypatch.setattr(ckpt, "_write_atomic", real)
    comm.barrier()
    man = ckpt.read_manifest(folder) if comm.rank == 0 else None
    man = comm.bcast(man, root=0)
    assert man["step"] == 100
    again = explicit_run(comm)
    assert again.resume(Checkpointer(folder, comm, kind="explicit")) == 100
    again.run(steps=200, every=50)
    for a, b in zip(state_of(ref), state_of(again), strict=True):
        assert np.array_equal(a, b)


_KILLED_CHILD = """
import sys, time
from pathlib import Path
sys.path.insert(0, {tests!r})
from mpi4py import MPI
from masonry_fdem.io import checkpoint as ckpt
from masonry_fdem.io.checkpoint import Checkpointer
from test_checkpoint import explicit_run
real = ckpt._write_atomic
calls = {{"n": 0}}
def slow(path, data):
    if path.name == "rank0.pkl":
        calls["n"] += 1
        if calls["n"] == 2:  # the second generation: half written, then stuck
            with open(path.with_name(path.name + ".tmp"), "wb") as fh:
                fh.write(data[: len(data) // 2])
                fh.flush()
            Path({marker!r}).write_text("half")
            time.sleep(120)
    real(path, data)
ckpt._write_atomic = slow
run = explicit_run(MPI.COMM_SELF)
run.run(steps=300, every=50, checkpoint=Checkpointer(Path({folder!r}), MPI.COMM_SELF,
                                                    kind="explicit", every=100))
"""


def test_process_killed_while_writing_keeps_the_previous_checkpoint(tmp_path):
    """A real kill: a process writing its second checkpoint is killed (SIGKILL) half way
    through its rank file; the first checkpoint stays current, and a resume from it ends
    as the uninterrupted run, bit for bit."""
    comm = MPI.COMM_WORLD
    if comm.size > 1:
        pytest.skip("starts its own process (run the serial suite)")
    folder, marker = tmp_path / "run", tmp_path / "half_written"
    code = _KILLED_CHILD.format(tests=str(ROOT / "tests"), marker=str(marker),
                                folder=str(folder))
    env = {**os.environ, "PYTHONPATH": str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", "")}
    proc = subprocess.Popen([sys.executable, "-c", code], env=env, cwd=ROOT,
                            stderr=subprocess.PIPE)
    try:
        t0 = time.monotonic()
        while not marker.exists():
            assert proc.poll() is None, proc.stderr.read().decode()
            assert time.monotonic() - t0 < 240, "the child never reached its second write"
            time.sleep(0.05)
        proc.send_signal(signal.SIGKILL)
        assert proc.wait(timeout=30) == -signal.SIGKILL
    finally:
        if proc.poll() is None:
            proc.kill()
    assert list(folder.glob("checkpoint/*/rank0.pkl.tmp"))  # the torn write is there
    assert ckpt.read_manifest(folder)["step"] == 100
    ref = explicit_run(comm)
    ref.run(steps=300, every=50)
    again = explicit_run(comm)
    assert again.resume(Checkpointer(folder, comm, kind="explicit")) == 100
    again.run(steps=200, every=50)
    for a, b in zip(state_of(ref), state_of(again), strict=True):
        assert np.array_equal(a, b)


def test_checkpoint_errors(tmp_path):
    """Clear errors: no checkpoint, another number of ranks, a corrupt rank file."""
    comm = MPI.COMM_WORLD
    folder = shared_tmp(tmp_path, comm) / "run"
    ck = Checkpointer(folder, comm, kind="explicit")
    with pytest.raises(CheckpointError, match="no checkpoint"):
        ck.read()
    ck.write({"x": np.arange(3.0) + comm.rank}, 7)
    man, st = ck.read()
    assert man["step"] == 7 and np.array_equal(st["x"], np.arange(3.0) + comm.rank)
    with pytest.raises(CheckpointError, match="is of a .explicit. run"):
        Checkpointer(folder, comm, kind="assess").read()
    with pytest.raises(CheckpointError, match="case changed since the run began"):
        Checkpointer(folder, comm, kind="explicit", meta={"case_sha256": "x"}).read()
    if comm.rank == 0:
        gen = Path(man["generation"])
        import json

        m = json.loads((gen / "manifest.json").read_text())
        m["n_ranks"] = comm.size + 1
        (gen / "manifest.json").write_text(json.dumps(m))
    comm.barrier()
    with pytest.raises(CheckpointError, match=f"{comm.size + 1} MPI rank"):
        ck.read()
    if comm.rank == 0:
        m["n_ranks"] = comm.size
        (gen / "manifest.json").write_text(json.dumps(m))
        with open(gen / "rank0.pkl", "r+b") as f:
            f.seek(10)
            f.write(b"\x00\x01")
    comm.barrier()
    with pytest.raises(CheckpointError, match="corrupt"):
        ck.read()


# ------------------------------------------------------------------------- assess
DRY_ARCH = {
    "arch": {"span": 2.0, "ring_thickness": 0.2, "voussoirs": 12, "abutment_height": 0.3,
             "abutment_width": 0.4, "mesh_size": 0.2},
    "materials": {"brick": {"density": 2000.0, "E": 10e9, "nu": 0.2},
                  "abutment": {"density": 2000.0, "E": 30e9, "nu": 0.2}},
    "joints": {"mortar": {"tan_phi": 10.0}},
    "loading": {"position": 0.25, "increment": 2000.0, "displacement_increment": 1e-4},
    "analysis": {"limit_analysis": False, "post_peak_drop": 0.05},
}


def _dry_case():
    from masonry_fdem.assessment.case import load_case

    return load_case(DRY_ARCH, name="dry_arch")


@pytest.fixture
def deterministic_lu():
    """Under MPI, SuperLU_DIST for the Newton solver's factorization: MUMPS in
    parallel is not reproducible from run to run (its dynamic scheduling: two runs of
    the dry arch on 2 ranks differ by ~1e-11 of the load from the 9th increment on), so
    no restart can be bitwise equal to a run there. Serial runs keep MUMPS."""
    from petsc4py import PETSc

    key = "static_pc_factor_mat_solver_type"
    opts = PETSc.Options()
    if MPI.COMM_WORLD.size > 1:
        opts[key] = "superlu_dist"
    yield
    if MPI.COMM_WORLD.size > 1:
        opts.delValue(key)


@pytest.fixture(scope="module")
def dry_reference(tmp_path_factory):
    """The dry arch's uninterrupted run (checkpoints every 4 increments, in its folder
    while it runs)."""
    from petsc4py import PETSc

    from masonry_fdem.assessment.assess import assess

    comm = MPI.COMM_WORLD
    root = Path(comm.bcast(str(tmp_path_factory.mktemp("ref")) if comm.rank == 0 else None))
    key = "static_pc_factor_mat_solver_type"
    if comm.size > 1:
        PETSc.Options()[key] = "superlu_dist"  # see deterministic_lu
    try:
        ref = assess(_dry_case(), out=root / "ref", progress=False, checkpoint_every=4)
    finally:
        if comm.size > 1:
            PETSc.Options().delValue(key)
    assert not (root / "ref" / "checkpoint").exists()  # removed at the end
    return ref


def test_collapse_run_resumes_bitwise(tmp_path, deterministic_lu, dry_reference):
    """The dry arch traced past its peak by arc length (Newton): stopped at its 8th
    converged increment, resumed from the checkpoint, it ends as the run that was not
    stopped — the curve, the collapse load, the hinges, the status, bit for bit."""
    from masonry_fdem.assessment.assess import assess

    comm = MPI.COMM_WORLD
    root = shared_tmp(tmp_path, comm)
    ref = dry_reference
    assert ref.collapsed and len(ref.loads) > 12
    calls = []

    def stop(info):
        calls.append(info)
        if len(calls) == 8:
            ckpt.request_stop()

    try:
        with pytest.raises(Interrupted) as exc:
            assess(_dry_case(), out=root / "run", progress=False, checkpoint_every=4,
                   callback=stop)
    finally:
        ckpt.clear_stop()
    assert exc.value.step == 8
    assert "--resume" in str(exc.value)
    res = assess(_dry_case(), out=root / "run", progress=False, resume=True)
    print(f"\nresumed at increment 8 of {len(ref.loads) - 1}: {res.status_line}")
    assert np.array_equal(res.loads, ref.loads)
    assert np.array_equal(res.displacements, ref.displacements)
    assert res.iterations == ref.iterations
    assert res.peak_load == ref.peak_load and res.resolution == ref.resolution
    assert res.status == ref.status
    assert [e.joint for e in res.events] == [e.joint for e in ref.events]
    assert [e.joint for e in res.hinges_at_collapse] == [e.joint for e in ref.hinges_at_collapse]
    assert res.first_hinges == ref.first_hinges
    assert (root / "run" / "report.md").is_file()
    assert not (root / "run" / "checkpoint").exists()


def test_resume_refuses_a_changed_case(tmp_path):
    """A checkpoint of one case does not resume another."""
    import copy

    from masonry_fdem.assessment.assess import assess
    from masonry_fdem.assessment.case import load_case

    comm = MPI.COMM_WORLD
    root = shared_tmp(tmp_path, comm)

    def stop(info):
        if len(info) and info["load"] > 0:
            ckpt.request_stop()

    try:
        with pytest.raises(Interrupted):
            assess(_dry_case(), out=root / "run", progress=False, callback=stop)
    finally:
        ckpt.clear_stop()
    other = copy.deepcopy(DRY_ARCH)
    other["joints"]["mortar"]["tan_phi"] = 0.9
    with pytest.raises(CheckpointError, match="case changed since the run began"):
        assess(load_case(other, name="dry_arch"), out=root / "run", progress=False,
               resume=True)


# ------------------------------------------------------------------------- signals
CASE_TOML = """\
[arch]
span = 2.0
ring_thickness = 0.2
voussoirs = 12
abutment_height = 0.3
abutment_width = 0.4
mesh_size = 0.2

[materials.brick]
density = 2000.0
E = 10e9
nu = 0.2

[materials.abutment]
density = 2000.0
E = 30e9
nu = 0.2

[joints.mortar]
tan_phi = 10.0

[loading]
position = 0.25
increment = 2000.0
displacement_increment = 1e-4

[analysis]
limit_analysis = false
post_peak_drop = 0.05
"""

# the command line with every arc-length increment slowed down by argv[1] seconds, so
# that a signal sent once the first checkpoint is there arrives mid-run
SLOW_CLI = """\
import sys, time
from masonry_fdem.solvers.static import StaticSolver
real = StaticSolver._arc_increment
def slow(self, *a, **k):
    time.sleep(float(sys.argv[1]))
    return real(self, *a, **k)
StaticSolver._arc_increment = slow
from masonry_fdem.cli import main
sys.exit(main(sys.argv[2:]))
"""


def _summary(folder: Path) -> dict:
    import json

    return json.loads((folder / "summary.json").read_text())


@pytest.mark.parametrize(("ranks", "sig"), [(1, signal.SIGINT), (2, signal.SIGTERM)])
def test_sigint_stops_assess_with_130_and_resume_finishes(tmp_path, ranks, sig,
                                                           dry_reference):
    """SIGINT to a running ``masonry-fdem assess`` (serial), SIGTERM to ``mpiexec``
    running it on 2 ranks (it forwards the signal to both): exit status 130, no
    traceback, a message naming the resume command; ``--resume`` then finishes with the
    collapse load of the uninterrupted run (bit for bit serially; on 2 ranks MUMPS is
    not reproducible bit for bit from run to run, so to 1e-9)."""
    import shutil

    if MPI.COMM_WORLD.size > 1:
        pytest.skip("starts its own processes (run the serial suite)")
    mpirun = Path(sys.executable).with_name("mpirun")
    if ranks > 1 and not (mpirun.is_file() or shutil.which("mpirun")):
        pytest.skip("no mpirun")
    case = tmp_path / "case.toml"
    case.write_text(CASE_TOML)
    script = tmp_path / "slow_cli.py"
    script.write_text(SLOW_CLI)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(ROOT), *filter(None, [os.environ.get("PYTHONPATH")])])}
    launch = ([str(mpirun if mpirun.is_file() else shutil.which("mpirun")), "-n", str(ranks)]
              if ranks > 1 else [])
    ref = dry_reference  # the same case (from a dict), serial
    run = tmp_path / "run"
    proc = subprocess.Popen(
        [*launch, sys.executable, str(script), "0.1", "assess", str(case), "--out", str(run),
         "--quiet"], env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    t0 = time.monotonic()
    while not (run / "checkpoint" / "CURRENT").is_file():
        assert proc.poll() is None, proc.communicate()
        assert time.monotonic() - t0 < 120, "no checkpoint within 120 s"
        time.sleep(0.02)
    proc.send_signal(sig)
    out, err = proc.communicate(timeout=120)
    print(f"\n{sig.name} ({ranks} rank(s)): status {proc.returncode}; stderr: {err.strip()}")
    assert proc.returncode == 130
    assert "Traceback" not in err
    assert f"--resume {run}" in err
    assert not (run / "summary.json").exists()
    done = subprocess.run(
        [*launch, sys.executable, "-m", "masonry_fdem.cli", "assess", "--resume", str(run),
         "--quiet"], env=env, capture_output=True, text=True, timeout=300)
    print(done.stdout.strip())
    assert done.returncode == 0, done.stderr
    assert "Traceback" not in done.stderr
    got = _summary(run)["collapse_load"]
    print(f"collapse load: uninterrupted {ref.collapse_load!r} N, resumed {got!r} N")
    if ranks == 1:
        assert got == ref.collapse_load
    else:
        assert got == pytest.approx(ref.collapse_load, rel=1e-9)
    assert f"collapse load {ref.collapse_load / 1e3:.2f} kN" in done.stdout
    assert not (run / "checkpoint").exists()


def test_cli_resume_without_a_checkpoint(tmp_path, capsys):
    """``--resume`` of a folder without a checkpoint: a one-line error, status 1."""
    from masonry_fdem.cli import main as cli_main

    comm = MPI.COMM_WORLD
    folder = shared_tmp(tmp_path, comm) / "nothing"
    assert cli_main(["assess", "--resume", str(folder)]) == 1
    err = capsys.readouterr().err
    if comm.rank == 0:
        assert "no checkpoint in" in err and "Traceback" not in err
