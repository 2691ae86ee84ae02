"""The command line's conventions and outputs (issue #24): plain-text help, --version,
-v/-q, one progress line per increment when stdout is not a terminal; `settle` with
contact and with joints named by the mesh's physical line groups; the ParaView .vtu/.pvd
series read back by meshio; `model.u` assignable."""

from __future__ import annotations

import copy
import csv
import os
import re
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

from mpi4py import MPI

import gmsh
import numpy as np
import pytest
from conftest import rectangle

from masonry_fdem import Material, Model
from masonry_fdem.cli import build_parser, main
from masonry_fdem.geometry import interface_rules, mesh_blocks, read_msh, read_msh_lines
from masonry_fdem.interactions import BlockContact, JointMaterial, Joints

comm = MPI.COMM_WORLD
ROOT = Path(__file__).resolve().parents[1]
SUBCOMMANDS = ["info", "settle", "assess", "repair", "example", "precompile"]
MORTAR = dict(ft=1e5, GfI=10.0, c=1.5e5, GfII=50.0, tan_phi=0.75)


@pytest.fixture
def shared_tmp(tmp_path):
    """One temporary folder for all ranks (rank 0's)."""
    return Path(comm.bcast(str(tmp_path), root=0))


@pytest.mark.parametrize("command", [[], *([c] for c in SUBCOMMANDS)])
def test_help_is_plain_text(command, capsys):
    with pytest.raises(SystemExit) as exc:
        build_parser().parse_args([*command, "--help"])
    assert exc.value.code == 0
    text = capsys.readouterr().out
    for markup in ("``", ":class:", ":mod:", ":func:", ":meth:"):
        assert markup not in text, f"{markup!r} in the help of {command}"
    assert "-v, --verbose" in text and "-q, --quiet" in text


def test_version_and_verbosity(capsys):
    from importlib.metadata import version

    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0
    assert capsys.readouterr().out.strip() == f"masonry-fdem {version('masonry_fdem')}"
    p = build_parser()
    a = p.parse_args(["-q", "info", "x.msh"])
    assert a.quiet and a.verbose == 0
    a = p.parse_args(["info", "x.msh", "-vv"])
    assert not a.quiet and a.verbose == 2
    a = p.parse_args(["-v", "assess", "c.toml"])
    assert a.verbose == 1 and not a.quiet


@pytest.mark.skipif(comm.size > 1, reason="runs the command line in a subprocess")
def test_assess_prints_one_line_per_increment(tmp_path):
    """The dry arch of test_assess (~3 s): stdout a pipe, so one progress line per
    converged increment, as many as the curve's points after the self-weight state."""
    sys.path.insert(0, str(ROOT / "tests"))
    from test_assess import DRY_ARCH, _toml

    data = copy.deepcopy(DRY_ARCH)
    data["analysis"]["output"] = str(tmp_path / "run")
    case = tmp_path / "dry.toml"
    case.write_text(_toml(data))
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(ROOT), *filter(None, [os.environ.get("PYTHONPATH")])])}
    run = subprocess.run([sys.executable, "-m", "masonry_fdem.cli", "assess", str(case)],
                         capture_output=True, text=True, env=env, timeout=300)
    assert run.returncode == 0, run.stderr
    pattern = re.compile(r"^dry: increment (\d+): load factor [\d.]+, load [\d.]+ kN, "
                         r"displacement [\d.]+ mm, iterations \d+, converged")
    lines = [x for x in run.stdout.splitlines() if pattern.match(x)]
    with open(tmp_path / "run" / "curve.csv") as fh:
        rows = [r for r in csv.reader(x for x in fh if not x.startswith("#"))][1:]
    print(f"\n{len(lines)} progress lines, {len(rows)} curve points; first: {lines[0]}")
    assert len(lines) == len(rows) - 1 > 3
    assert [int(pattern.match(x).group(1)) for x in lines] == list(range(1, len(lines) + 1))
    assert "\r" not in run.stdout and "\r" not in run.stderr  # no bar off a terminal


def _stack_msh(path: Path) -> None:
    """A base slab (y in [-0.2, 0]) with two stones stacked on it, meshed conformingly
    (Gmsh fragments); physical surfaces "base", "stone:lower", "stone:upper" and one
    physical line, "bed", on the interface between the two stones (y = 0.3)."""
    def work():
        gmsh.initialize(readConfigFiles=False)
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("stack")
        occ = gmsh.model.occ
        base = occ.addRectangle(0.0, -0.2, 0, 2.0, 0.2)
        lower = occ.addRectangle(0.5, 0.0, 0, 1.0, 0.3)
        upper = occ.addRectangle(0.5, 0.3, 0, 1.0, 0.3)
        occ.fragment([(2, base)], [(2, lower), (2, upper)])
        occ.synchronize()
        surf = {}
        for _, tag in gmsh.model.getEntities(2):
            y = occ.getCenterOfMass(2, tag)[1]
            surf["base" if y < 0 else "stone:lower" if y < 0.3 else "stone:upper"] = tag
        for name, tag in surf.items():
            gmsh.model.addPhysicalGroup(2, [tag], name=name)
        bed = [tag for _, tag in gmsh.model.getEntities(1)
               if abs(occ.getCenterOfMass(1, tag)[1] - 0.3) < 1e-9]
        gmsh.model.addPhysicalGroup(1, bed, name="bed")
        gmsh.option.setNumber("Mesh.MeshSizeMax", 0.15)
        gmsh.model.mesh.generate(2)
        gmsh.write(str(path))
        gmsh.finalize()

    if comm.rank == 0:
        work()
    comm.barrier()


def test_msh_line_group_names_the_joint_material(shared_tmp):
    path = shared_tmp / "stack.msh"
    _stack_msh(path)
    lines = read_msh_lines(path, comm=comm)
    assert list(lines) == ["bed"]
    np.testing.assert_allclose(lines["bed"][:, :, 1], 0.3, atol=1e-12)
    blocks = read_msh(path, comm=comm)
    model = Model(blocks, {n: Material(2000.0, 1e9, 0.2) for n in blocks.material_names},
                  comm=comm)
    mortar = JointMaterial(**MORTAR)
    dry = {(a, b): None for a in blocks.material_names for b in blocks.material_names}
    joints = Joints(model, dry, where=interface_rules(lines, {"bed": mortar}),
                    contact=BlockContact(model))
    # every bonded segment is on the bed line and has the mortar; the stone on the base
    # is dry (contact only)
    assert joints.n_segments > 0
    assert all(jm is mortar for jm in joints.segment_materials)
    np.testing.assert_allclose(joints.seg_mid[:, 1], 0.3, atol=1e-9)
    assert abs(joints.seg_length.sum() - 1.0) < 1e-9
    with pytest.raises(ValueError, match="not in the mesh: \\['head'\\]"):
        interface_rules(lines, {"head": mortar})


def test_settle_with_contact_and_pvd(shared_tmp, capsys):
    """Two stones on a fixed slab settle on it (contact; bonded bed joint from the line
    group); the .pvd series is read back by meshio with the model's points and cells."""
    import meshio

    path = shared_tmp / "stack.msh"
    _stack_msh(path)
    out = shared_tmp / "settle"
    joint = "bed:" + ",".join(f"{k}={v:g}" for k, v in MORTAR.items())
    code = main(["settle", str(path), "-q", "--material", "base=2400,30e9,0.2",
                 "--material", "stone=2000,5e9,0.2", "--joint", joint, "--fix-below", "-0.2",
                 "--steps", "1", "--rtol", "1e-4", "--out", str(out)])
    text = capsys.readouterr().out
    assert code == 0, text
    blocks = read_msh(path, comm=comm)
    if comm.rank == 0:
        assert "in equilibrium" in text
        with open(out / "history.csv") as fh:
            row = list(csv.DictReader(fh))[-1]
        stones = blocks.block_area[[blocks.block_names.index(n) for n in
                                    ("stone:lower", "stone:upper")]].sum()
        weight = 2000.0 * stones * 9.81 + 2400.0 * 0.4 * 9.81
        assert float(row["reaction_y"]) == pytest.approx(weight, rel=1e-2)
        root = ET.parse(out / "model.pvd").getroot()
        files = [d.get("file") for d in root.iter("DataSet")]
        assert len(files) == 1
        mesh = meshio.read(out / files[0])
        assert mesh.points.shape[0] == blocks.n_nodes
        assert sum(len(c.data) for c in mesh.cells) == blocks.n_cells
        u = mesh.point_data["displacement"]
        # the stones rest on the slab: settlement of the order of micrometres, not a fall
        assert u[:, 1].min() < 0 and np.abs(u).max() < 1e-4
        assert mesh.cell_data["stress"][0].shape == (blocks.n_cells, 4)
    assert main(["settle", str(path), "--material", "base=2400,30e9,0.2",
                 "--material", "stone=2000,5e9,0.2", "--joint", "head:dry",
                 "--out", str(out / "bad")]) == 2
    err = capsys.readouterr().err
    if comm.rank == 0:
        assert "'head'" in err and "bed" in err


def test_model_u_is_assignable():
    blocks = mesh_blocks([rectangle(0, 0, 1.0, 0.2)], materials="b", mesh_size=0.1, comm=comm)
    model = Model(blocks, {"b": Material(2000.0, 1e9, 0.2)}, comm=comm)
    values = np.arange(model.u.x.array.size, dtype=float) * 1e-6
    function = model.u
    model.u = values
    assert model.u is function  # the forms' Function stays; its values change
    np.testing.assert_array_equal(model.u.x.array, values)
    model.v = 2 * values
    np.testing.assert_array_equal(model.v, 2 * values)
    with pytest.raises(ValueError, match="model.u"):
        model.u = np.r_[values, 0.0]
