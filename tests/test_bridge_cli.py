"""``masonry-fdem bridge CASE.toml``: a bridge case run from the command line — with a
continuum fill, the vehicle loaded to collapse at each position, the critical one
reported (:func:`masonry_fdem.assessment.bridge_runs.sweep_bridge`); bad input named
before any run."""

from __future__ import annotations

import re
from pathlib import Path

from mpi4py import MPI

import pytest

from masonry_fdem.cli import main

# a 2 m single span (rise 0.5 m, 0.15 m ring) under 0.3 m of fill and surfacing, on
# rigid ground; one axle, a 0.2 m patch, at 0.25 and 0.35 of the span
CASE = """
[bridge]
piers = []
pier_height = 0.5
abutment_width = 0.4
cover = 0.3
surfacing = 0.05
soil_depth = 0.0

[[bridge.spans]]
span = 2.0
rise = 0.5
ring_thickness = 0.15
voussoirs = 12

[bridge.materials]
masonry = "stone"
fill = "fill"
surfacing = "road"

[bridge.mesh]
masonry = 0.15
pier = 0.15
wall = 0.3
fill = 0.15
surfacing = 0.05

[materials.stone]
density = 2000.0
E = 5e9
nu = 0.2

[materials.fill]
density = 1900.0
E = 30e6
nu = 0.3
phi = 35.0
c = 2e3

[materials.road]
density = 2300.0
E = 1e9
nu = 0.3
phi = 35.0
c = 100e3

[joints.mortar]
kn = 5e10
ks = 2e10
tan_phi = 0.6

[vehicle]
offsets = [0.0]
patch = 0.2
positions = [0.5, 0.7]

[analysis]
increment = 1e-3
max_displacement = 0.03
stop_drop = 0.05
"""


def _write(tmp_path: Path, text: str) -> Path:
    comm = MPI.COMM_WORLD
    folder = Path(comm.bcast(str(tmp_path) if comm.rank == 0 else None, root=0))
    path = folder / "small_bridge.toml"
    if comm.rank == 0:
        path.write_text(text, encoding="utf-8")
    comm.barrier()
    return path


@pytest.mark.skipif(MPI.COMM_WORLD.size == 1, reason="under mpirun, one rank per position "
                    "(the suite's budget: 20 s on one process, 10 s on two)")
def test_bridge_sweep_reports_the_critical_position(tmp_path, capsys):
    """Two positions, one per rank: each run passes its peak; sweep.md lists
    both with their loads, and the critical position it names is the one with the lower
    collapse load; the pictures of the critical position and a ParaView series per
    position are written."""
    case = _write(tmp_path, CASE)
    out = case.parent / "out"
    assert main(["bridge", str(case), "--out", str(out), "--paraview-every", "10"]) == 0
    MPI.COMM_WORLD.barrier()
    text = (out / "sweep.md").read_text(encoding="utf-8")
    rows = re.findall(r"^\| ([\d.]+) \| [\d.]+ \| (≥ )?([\d.]+) \| .*? \| (\S[^|]*?) \|",
                      text, flags=re.M)
    assert [float(r[0]) for r in rows] == [0.5, 0.7], text
    assert all(r[1] == "" and r[3] == "peak passed" for r in rows), text
    loads = {float(r[0]): float(r[2]) for r in rows}
    crit = min(loads, key=loads.get)
    assert f"Critical position among those run: x = {crit:g} m" in text, text
    for name in (f"vertical_stress_{crit:g}.png", f"mechanism_{crit:g}.png", "sweep.png"):
        assert (out / name).stat().st_size > 1000, name
    for x in (0.5, 0.7):
        assert (out / f"paraview_{x:g}" / "model.pvd").exists()
    if MPI.COMM_WORLD.rank == 0:
        said = capsys.readouterr().out
        assert f"critical position x = {crit:g} m" in said


DISKS = (("[bridge]\n", '[bridge]\nfill_model = "disks"\n'), ("[vehicle]", "[vehicle]\nload = 1e4"))


@pytest.mark.parametrize("edits, args, expected", [
    ((("positions = [0.5, 0.7]", "positions = [2.5]"),), [],
     "vehicle.positions: at 2.5 m, axle 0"),
    ((), ["--positions", "-1.0"], "at x = -1 m, axle 0 of the vehicle"),
    ((), ["--pictures", "0.5"], "--pictures: a continuum fill's sweep"),
    ((), ["--paraview-every", "-2"], "paraview_every must be an integer >= 0"),
    ((("[bridge]\n", '[bridge]\nfill_model = "disks"\n'),), [], "vehicle.load: missing"),
    (DISKS, ["--positions", "0.5"], "--positions: a disk fill is traversed through"),
    (DISKS, ["--collapse"], "--collapse: give the load step, --increment N"),
    (DISKS, ["--increment", "5e3"], "--increment and --max-load go with --collapse"),
    ((), ["--collapse", "--increment", "5e3"], "--collapse: the continuum fill is always"),
    (DISKS, ["--collapse", "--increment=-5e3"], "increment must be > 0 N"),
    (DISKS, ["--collapse", "--increment", "5e3", "--positions", "9"],
     "at x = 9 m, axle 0 of the vehicle"),
])
def test_bad_bridge_command_is_named(tmp_path, capsys, edits, args, expected):
    text = CASE
    for old, new in edits:
        assert old in text
        text = text.replace(old, new, 1)
    case = _write(tmp_path, text)
    assert main(["bridge", str(case), "--out", str(case.parent / "o"), *args]) == 2
    assert expected in capsys.readouterr().err
    assert not (case.parent / "o").exists()


def test_missing_bridge_case_is_named(tmp_path, capsys):
    missing = Path(MPI.COMM_WORLD.bcast(str(tmp_path), root=0)) / "nowhere.toml"
    assert main(["bridge", str(missing)]) == 2
    assert "nowhere.toml" in capsys.readouterr().err


def test_disk_bridge_command_that_does_not_settle_says_so(tmp_path, capsys):
    """A disk fill given too few explicit steps to settle: exit status 1, the reason
    printed, no traverse and no report (the traverse itself:
    tests/test_disk_bridge_traverse.py)."""
    text = CASE
    for old, new in DISKS:
        text = text.replace(old, new, 1)
    text = text.replace("[bridge.mesh]", "[bridge.disks]\ncount = 220\n\n[bridge.mesh]")
    case = _write(tmp_path, text)
    out = case.parent / "o"
    assert main(["-q", "bridge", str(case), "--out", str(out), "--max-steps", "50"]) == 1
    if MPI.COMM_WORLD.rank == 0:
        assert "did not settle under self-weight within 50 steps" in capsys.readouterr().err
    assert not (out / "traverse.md").exists()


@pytest.mark.skipif(MPI.COMM_WORLD.size > 1, reason="one process (the suite's budget); the "
                    "disks' parallel part is checked in tests/test_disk_bridge_traverse.py")
def test_disk_bridge_loaded_in_steps(tmp_path, capsys):
    """--collapse on the small bridge with 220 disks, two steps of 5 kN: both carried
    (*load reached*), the road settling more under the second; the report, the curve and
    the fill's stress written."""
    text = CASE
    for old, new in DISKS:
        text = text.replace(old, new, 1)
    text = text.replace("[bridge.mesh]", "[bridge.disks]\ncount = 220\n\n[bridge.mesh]")
    case = _write(tmp_path, text)
    out = case.parent / "o"
    assert main(["-q", "bridge", str(case), "--out", str(out), "--collapse", "--increment",
                 "5e3", "--max-load", "1e4", "--positions", "0.5"]) == 0
    said = capsys.readouterr().out
    assert "vehicle at x = 0.5 m: load reached" in said, said
    text = (out / "collapse.md").read_text(encoding="utf-8")
    row = re.search(r"^\| 0.5 \| load reached \| ≥ 10.0 \| ≥ 1.02 \| ([\d.]+) \|", text,
                    flags=re.M)
    assert row is not None, text
    assert float(row.group(1)) > 0.0
    for name in ("collapse.png", "vertical_stress_0.5.png"):
        assert (out / name).stat().st_size > 1000, name
