"""The chimney demolition demo (demos/chimney.py) at small size: a 6 m chimney of 0.5 m
courses on its ground, settled intact, then notched at t = 0 on its +x side.

(a) it starts to turn towards the notch: over 2 000 steps (0.05 s) the top moves
    towards +x, steadily and faster over the second half, more across than down;
(b) its first 1 000 steps are the same on every rank count as on one process, to 1e-10
    (the model built on COMM_WORLD and again on COMM_SELF, as the parallel tests do);
(c) the demo script runs a few steps and writes its report and files.
"""

import runpy
from pathlib import Path

from mpi4py import MPI

import numpy as np
import pytest

from masonry_fdem.solvers import ExplicitSolver

ROOT = Path(__file__).resolve().parents[1]
SMALL = {"height": 6.0, "d_base": 1.2, "d_top": 0.9, "wall": 0.25, "course": 0.5,
         "ground": (-3.0, 8.0), "ground_mesh": 1.0}


@pytest.fixture(scope="module")
def demo():
    """The demo's functions (its ``main`` is not run)."""
    return runpy.run_path(str(ROOT / "demos" / "chimney.py"), run_name="chimney_demo")


def _run(demo, comm, steps, every):
    """Top position, velocity and kinetic energy every ``every`` steps of the small
    notched chimney on ``comm``."""
    ch = demo["Chimney"](**SMALL)
    parts = demo["build"](ch, comm)
    demo["settle"](parts)
    model = parts["model"]
    solver = ExplicitSolver(model, interactions=[parts["contact"], parts["joints"]])
    rows = []

    def record(s):
        pos, vel = demo["top_state"](model)
        rows.append([s.t, *pos, *vel, s.energies().kinetic])

    record(solver)
    solver.run(steps=steps, every=every, callback=record)
    return np.array(rows), parts


def test_notched_chimney_turns_towards_the_notch(demo):
    # each rank runs its own serial model (the rank count is the next test's business)
    hist, parts = _run(demo, MPI.COMM_SELF, 2000, 250)
    t, x, y = hist[:, 0], hist[:, 1] - hist[0, 1], hist[:, 2] - hist[0, 2]
    print(f"\nsmall chimney after {t[-1]:.3f} s: top moved {1e3 * x[-1]:+.3f} mm across, "
          f"{1e3 * y[-1]:+.3f} mm up (notch on +x)")
    assert x[-1] > 0.0
    # over the second half it moves steadily towards +x, and more than over the first
    # (the turn accelerates; the first steps are the elastic response to the cut)
    half = x.size // 2
    assert np.all(np.diff(x[half:]) > 0.0)
    assert x[-1] - x[half] > x[half] - x[0]
    # it turns, not sinks: the top moves across more than it goes down
    assert x[-1] > 2.0 * abs(y[-1])


def test_chimney_same_history_on_any_rank_count(demo):
    world, parts = _run(demo, MPI.COMM_WORLD, 1000, 10)
    serial, _ = _run(demo, MPI.COMM_SELF, 1000, 10)
    if MPI.COMM_WORLD.size > 1:
        ranks = parts["model"].block_ranks()
        assert len(set(ranks[1:].tolist())) > 1  # the chimney is split between ranks
    scale = np.abs(serial).max(axis=0)
    diff = np.abs(world - serial).max(axis=0)
    print(f"\nchimney, {MPI.COMM_WORLD.size} ranks vs 1, 1000 steps: largest differences "
          f"{diff[1:3].max():.1e} m, {diff[3:5].max():.1e} m/s, {diff[5]:.1e} J "
          f"(kinetic up to {scale[5]:.3g} J)")
    assert np.array_equal(world[:, 0], serial[:, 0])
    assert np.all(diff[1:] <= 1e-10 * np.maximum(scale[1:], 1e-30))


def test_chimney_demo_small(demo, tmp_path, capsys):
    out = Path(MPI.COMM_WORLD.bcast(str(tmp_path), root=0)) / "chimney"
    argv = ["--height", "6", "--d-base", "1.2", "--d-top", "0.9", "--wall", "0.25",
            "--course", "0.5", "--ground", "-3", "8", "--steps", "300", "--record-steps",
            "50", "--vtx", "0.005", "--out", str(out)]
    res = demo["main"](argv)
    text = capsys.readouterr().out
    assert res["solver"].n == 300
    if MPI.COMM_WORLD.rank == 0:
        for start in ("chimney 6 m tall", "explicit: dt", "the top has not reached",
                      "debris: pieces from x", "energy account", "energy residual"):
            assert any(line.startswith(start) for line in text.splitlines()), start
        line = [x for x in text.splitlines() if x.startswith("energy residual")][0]
        assert abs(float(line.split(":")[1].split("%")[0])) < 1.0
        for name in ("history.csv", "displacement.bp", "joints.bp"):
            assert (out / name).exists()
        assert list(out.glob("chimney_00_t00.00.png"))
