"""Output files (CSV, VTX, PNG), the CLI and the demos at small size."""

import csv
import runpy
import sys
from pathlib import Path

from mpi4py import MPI

import numpy as np
import pytest
from conftest import rectangle

from masonry_fdem import Material, Model
from masonry_fdem.geometry import mesh_blocks, write_msh
from masonry_fdem.io import History, VTXOutput, plot_blocks
from masonry_fdem.solvers import ExplicitSolver

comm = MPI.COMM_WORLD
ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture
def shared_tmp(tmp_path):
    """One temporary folder for all ranks (rank 0's)."""
    return Path(comm.bcast(str(tmp_path), root=0))


def test_history_vtx_png(shared_tmp):
    blocks = mesh_blocks([rectangle(0, 0, 1.0, 0.2), rectangle(0, 0.5, 1.0, 0.7)],
                         materials="b", mesh_size=0.05, comm=comm)
    model = Model(blocks, {"b": Material(2000.0, 1e9, 0.2)}, comm=comm)
    model.fix(lambda X: X[0] < 1e-9)
    model.add_gravity()
    model.monitor("tip", (1.0, 0.1))
    solver = ExplicitSolver(model, damping=10.0)
    out = shared_tmp / "run"
    with History(out / "history.csv", comm) as hist, VTXOutput(model, out) as vtx:
        def record(s):
            e = s.energies()
            hist.append({"time": s.t, "tip": s.model.monitor_values()["tip"],
                         "kinetic": e.kinetic, "strain": e.internal,
                         "external": e.external, "damping": e.damping})
            vtx.write(s.t)
        solver.run(steps=500, every=100, callback=record)
    png = plot_blocks(model, out / "deformed.png", field="von_mises", scale=100.0)
    png2 = plot_blocks(model, out / "blocks.png", field="block")
    comm.barrier()
    if comm.rank == 0:
        with open(out / "history.csv") as f:
            rows = list(csv.reader(f))
        assert rows[0] == ["time", "tip_x", "tip_y", "kinetic", "strain", "external", "damping"]
        assert len(rows) == 6
        t = np.array([float(r[0]) for r in rows[1:]])
        assert t[-1] == pytest.approx(500 * solver.dt)
        assert float(rows[-1][2]) < 0  # the tip sags
        for p in (png, png2):
            data = Path(p).read_bytes()
            assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 10_000
        for name in ("displacement.bp", "stress.bp"):
            assert (out / name).is_dir() and any((out / name).iterdir())
    assert hist.column("tip_y")[-1] == pytest.approx(model.monitor_values()["tip"][1])


def test_settle_arch_demo_small(shared_tmp, monkeypatch, capsys):
    out = shared_tmp / "demo"
    monkeypatch.setattr(sys, "argv", ["settle_arch.py", "--mesh-size", "0.25", "--steps", "2",
                                      "--out", str(out)])
    runpy.run_path(str(ROOT / "demos" / "settle_arch.py"), run_name="__main__")
    text = capsys.readouterr().out
    if comm.rank == 0:
        assert "crown settlement under self-weight" in text
        line = [x for x in text.splitlines() if x.startswith("support reaction")][0]
        words = line.split()
        reaction, weight = float(words[2]), float(words[6])
        assert reaction == pytest.approx(weight, rel=1e-4)
        assert (out / "settled.png").exists() and (out / "history.csv").exists()


def test_topple_wall_demo_small(shared_tmp, monkeypatch, capsys):
    out = shared_tmp / "topple"
    monkeypatch.setattr(sys, "argv", ["topple_wall.py", "--courses", "3", "--bricks", "2",
                                      "--time", "0.03", "--out", str(out)])
    demo = runpy.run_path(str(ROOT / "demos" / "topple_wall.py"), run_name="__main__")
    n_points, n_cells = demo["blocks"].n_nodes, demo["blocks"].n_cells
    text = capsys.readouterr().out
    if comm.rank == 0:
        # the energy account closes: residual below 1 % of the work done (initial kinetic
        # energy + gravity's work), with the dampers' and friction's dissipation in it
        line = [x for x in text.splitlines() if x.startswith("energy residual")][0]
        percent = float(line.split(":")[1].split("%")[0])
        print(f"\ntopple demo (short): {line}")
        assert abs(percent) < 1.0
        account = "\n".join(x for x in text.splitlines() if x.strip().startswith(
            ("energy account", "dissipated")))
        for term in ("contact friction", "contact damper", "solver damping"):
            assert term in account
        assert (out / "toppled.png").exists() and (out / "history.csv").exists()
        # the demo's ParaView series (.pvd of .vtu, beside the .bp) read back by meshio:
        # every record with the model's points and cells
        import xml.etree.ElementTree as ET

        import meshio

        files = [d.get("file") for d in ET.parse(out / "model.pvd").getroot().iter("DataSet")]
        history = list(csv.DictReader(open(out / "history.csv")))
        assert len(files) == len(history) > 1
        for f in (files[0], files[-1]):
            mesh = meshio.read(out / f)
            print(f"  {f}: {mesh.points.shape[0]} points, "
                  f"{sum(len(c.data) for c in mesh.cells)} cells; the model {n_points}, "
                  f"{n_cells}")
            assert mesh.points.shape[0] == n_points
            assert sum(len(c.data) for c in mesh.cells) == n_cells
            assert mesh.point_data["displacement"].shape[0] == n_points


def test_topple_wall_demo_same_history_on_one_and_two_ranks(shared_tmp, monkeypatch):
    """The topple demo (default wall, 0.03 s: about 3 800 steps, some 380 neighbour-list
    rebuilds, bricks sliding and impacting across the rank boundary) on all ranks and
    again on each rank alone: the same history. The state (the top's position) to the
    bit: every node's contact force is summed over its pairs in the order of their keys
    on any number of ranks; the energies to 1e-10 of their largest value (each is a sum
    over ranks, added in another order). Run it under mpirun -n 2."""
    if comm.size == 1:
        pytest.skip("compares ranks: run under mpirun -n 2")
    runs = {}
    for name, c in (("world", comm), ("self", MPI.COMM_SELF)):
        out = shared_tmp / (f"topple_self{comm.rank}" if name == "self" else "topple")
        # the demo takes MPI.COMM_WORLD: the second run sees each rank's own
        monkeypatch.setattr(MPI, "COMM_WORLD", c)
        monkeypatch.setattr(sys, "argv", ["topple_wall.py", "--time", "0.03",
                                          "--out", str(out)])
        runpy.run_path(str(ROOT / "demos" / "topple_wall.py"), run_name="__main__")
        monkeypatch.undo()
        comm.barrier()
        runs[name] = np.genfromtxt(out / "history.csv", delimiter=",", names=True)
    world, alone = runs["world"], runs["self"]
    assert world.size == alone.size >= 6
    assert np.array_equal(world["top_x"], alone["top_x"])
    assert np.array_equal(world["top_y"], alone["top_y"])
    worst = 0.0
    for col in ("kinetic", "strain", "contact", "friction", "contact_damper", "damping",
                "gravity_work"):
        scale = np.abs(alone[col]).max()
        worst = max(worst, np.abs(world[col] - alone[col]).max() / scale)
    if comm.rank == 0:
        print(f"\ntopple demo, {comm.size} ranks vs 1, {world.size} records: top position "
              f"equal to the bit, energies within {worst:.1e} of their largest values")
    assert worst <= 1e-10


def test_cli_info_and_settle(shared_tmp, capsys):
    from masonry_fdem.cli import main

    blocks = mesh_blocks([rectangle(0, 0, 1.0, 2.0), rectangle(2, 0, 3, 1)], materials="brick",
                         names=["pier", "stub"], mesh_size=0.2, comm=comm)
    path = shared_tmp / "piers.msh"
    write_msh(blocks, path, comm=comm)
    comm.barrier()
    assert main(["info", str(path)]) == 0
    out = capsys.readouterr().out
    if comm.rank == 0:
        assert "2 blocks" in out
    code = main(["settle", str(path), "--material", "pier=2000,5e9,0.2",
                 "--material", "stub=2000,5e9,0.2", "--steps", "1",
                 "--out", str(shared_tmp / "settle")])
    assert code == 0
    assert main(["settle", str(shared_tmp / "missing.msh")]) == 2
    err = capsys.readouterr().err
    if comm.rank == 0:
        assert "missing.msh" in err


def test_materials_demo_small(shared_tmp, monkeypatch, capsys):
    out = shared_tmp / "materials"
    monkeypatch.setattr(sys, "argv", ["materials.py", "--h", "0.25", "--steps", "2",
                                      "--out", str(out)])
    runpy.run_path(str(ROOT / "demos" / "materials.py"), run_name="__main__")
    text = capsys.readouterr().out
    if comm.rank == 0:
        line = [x for x in text.splitlines() if x.startswith("final load")][0]
        assert float(line.split()[2]) > 0
        assert (out / "load_settlement.png").exists() and (out / "history.csv").exists()
        for name in ("displacement.bp", "stress.bp", "materials.bp"):
            assert (out / name).is_dir() and any((out / name).iterdir())


def test_silo_demo_small(shared_tmp, monkeypatch, capsys):
    out = shared_tmp / "silo"
    monkeypatch.setattr(sys, "argv", ["silo.py", "--height", "0.15", "--time", "0.12",
                                      "--radius", "0.006", "--out", str(out)])
    runpy.run_path(str(ROOT / "demos" / "silo.py"), run_name="__main__")
    text = capsys.readouterr().out
    if comm.rank == 0:
        line = [x for x in text.splitlines() if x.startswith("discharge rate")][0]
        assert float(line.split()[2]) > 0
        line = [x for x in text.splitlines() if x.startswith("energy residual")][0]
        print(f"\nsilo demo (short): {line}")
        assert abs(float(line.split(":")[1].split("%")[0])) < 1.0
        for name in ("history.csv", "discharge.png", "silo_final.png", "disks.pvd"):
            assert (out / name).exists()


def test_a_crowd_of_hinge_labels_is_cut_short():
    """Labels of points closer than the radius share one text; a group of more than
    MAX_LABELS shows the first (by number) and how many more, instead of a line of 47
    numbers running over the colour bars (the TRL arch's anchored mechanism picture)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from masonry_fdem.io.plot import MAX_LABELS, label_points

    fig, ax = plt.subplots()
    crowd = np.c_[np.linspace(0.0, 0.1, 10), np.zeros(10)]  # 10 points 11 mm apart
    pair = np.array([[5.0, 0.0], [5.01, 0.0]])
    labels = [str(k) for k in (14, 19, 29, 1, 2, 39, 42, 7, 25, 33)] + ["3", "4"]
    label_points(ax, np.vstack([crowd, pair]), labels, np.tile([0.0, 1.0], (12, 1)), 0.05)
    texts = sorted(t.get_text() for t in ax.texts)
    plt.close(fig)
    print(f"\nlabels: {texts}")
    assert MAX_LABELS == 5
    assert texts == ["1, 2, 7, … +7", "3, 4"]
