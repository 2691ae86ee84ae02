"""Bad inputs, table-driven (issue #24, items 3 and 7): each raises an error whose message
names the key (and, for magnitudes, the unit, the range and the likely slip), in the API
and in the case file; the command line prints one line and no traceback."""

from __future__ import annotations

import copy
import os
import subprocess
import sys
import tomllib
from pathlib import Path

from mpi4py import MPI

import pytest

from masonry_fdem import checks
from masonry_fdem.assessment.case import EXAMPLE_CASE, CaseError, load_case
from masonry_fdem.checks import ImplausibleValueError, NumericalError, numerical_failures
from masonry_fdem.geometry import arch_layout
from masonry_fdem.geometry.arches import build_arch
from masonry_fdem.interactions.joints import JointMaterial
from masonry_fdem.materials.elastic import Material
from masonry_fdem.materials.plasticity import MohrCoulomb

ROOT = Path(__file__).resolve().parents[1]


def example() -> dict:
    return copy.deepcopy(tomllib.loads(EXAMPLE_CASE))


def _set(data: dict, dotted: str, value) -> None:
    *head, leaf = dotted.split(".")
    d = data
    for k in head:
        d = d[int(k)] if isinstance(d, list) else d.setdefault(k, {})
    d[leaf] = value


_ANCHOR = {"layout": "radial", "angles": [90.0], "diameter": 0.016}

# (case-file key, value, texts the message must contain); the key itself is always checked
CASE_ROWS = [
    ("arch.span", 3000.0, ["= 3000 m", "0.2 to 100 m", "did you give millimetres?"]),
    ("arch.ring_thickness", 110.0, ["= 110 m", "did you give millimetres?"]),
    ("arch.abutment_height", 500.0, ["= 500 m", "millimetres"]),
    ("arch.width", 1000.0, ["= 1000 m", "millimetres"]),
    ("arch.mesh_size", 11.0, ["against the ring thickness", "times it"]),
    ("arch.span", "3 m", ["must be a finite number, got '3 m'"]),
    ("arch.rings", 2.5, ["must be an integer"]),
    ("arch.kind", "gothic", ["must be one of"]),
    ("materials.brick.E", 1.0, ["= 1 Pa", "1e+05 to 1e+12 Pa", "did you give MPa"]),
    ("materials.brick.E", 10e3, ["did you give MPa"]),
    ("materials.brick.density", 20.0, ["kg/m³", "a unit weight in kN/m³"]),
    ("materials.brick.density", 2.0, ["t/m³"]),
    ("materials.brick.nu", 0.7, ["must be < 0.5, got 0.7"]),
    ("joints.mortar.ft", 0.1, ["= 0.1 Pa", "did you give MPa"]),
    ("joints.mortar.fc", 10.0, ["= 10 Pa", "did you give MPa"]),
    ("joints.mortar.ft", 15e6, ["is not below fc"]),
    ("joints.mortar.tan_phi", 30.0, ["the angle φ in degrees"]),
    ("joints.mortar.kn", 250.0, ["Pa/m", "N/mm³"]),
    ("joints.mortar.GfI", 0.01, ["N/m", "did you give N/mm?"]),
    ("loading.increment", 9.8, ["against the arch's self-weight"]),
    ("loading.max_load", 1e9, ["against the arch's self-weight"]),
    ("loading.self_weight", 1, ["must be true or false"]),
    ("analysis.solver", "cg", ["must be one of"]),
    ("analysis.post_peak_drop", 1.5, ["must be < 1"]),
    ("damage", [{"type": "decayed_mortar", "factor": 1.5}], ["damage[0].factor",
                                                              "must be <= 1"]),
    ("anchors", [dict(_ANCHOR, diameter=16.0)], ["anchors[0].diameter = 16 m",
                                                "millimetres"]),
    ("anchors", [dict(_ANCHOR, steel={"E": 200e3})], ["anchors[0].steel.E", "MPa"]),
    ("checks.allow", "arch.span", ["must be a list"]),
]


def _case_id(row):
    return f"{row[0]}={row[1]!r}"[:40]


@pytest.mark.parametrize("key,value,texts", CASE_ROWS, ids=[_case_id(r) for r in CASE_ROWS])
def test_bad_case_file_value_names_its_key(key, value, texts):
    data = example()
    _set(data, key, value)
    with pytest.raises(CaseError) as info:
        load_case(data)
    msg = str(info.value)
    named = {"damage": "damage[0].factor", "anchors": "anchors[0]."}.get(key, key)
    assert named in msg, msg
    for text in texts:
        assert text in msg, msg


# (callable, parameter named, texts)
API_ROWS = [
    (lambda: Material(2000.0, 1.0, 0.2), "E", ["E = 1 Pa", "MPa"]),
    (lambda: Material(2.2, 1e9, 0.2), "density", ["density = 2.2 kg/m³", "t/m³"]),
    (lambda: Material(2000.0, -1.0, 0.2), "E", ["must be > 0"]),
    (lambda: MohrCoulomb(density=1800.0, E=20.0, nu=0.3, c=5e3, phi=30.0), "E", ["MPa"]),
    (lambda: JointMaterial(ft=0.25, GfI=18.0), "ft", ["ft = 0.25 Pa", "MPa"]),
    (lambda: JointMaterial(tan_phi=35.0), "tan_phi", ["degrees"]),
    (lambda: JointMaterial(ft=2e6, GfI=10.0, fc=1e6), "ft", ["not below fc"]),
    (lambda: JointMaterial(kn=82.0), "kn", ["N/mm³"]),
    (lambda: arch_layout(span=4000.0, ring_thickness=0.3, voussoirs=10), "span",
     ["span = 4000 m", "did you give millimetres?"]),
    (lambda: arch_layout(span=4.0, ring_thickness=300.0, voussoirs=10), "ring_thickness",
     ["millimetres"]),
    (lambda: build_arch(span=4.0, ring_thickness=0.3, voussoirs=10, mesh_size=30.0),
     "mesh_size", ["against the ring thickness"]),
]


@pytest.mark.parametrize("make,key,texts", API_ROWS,
                         ids=[f"api-{i}-{r[1]}" for i, r in enumerate(API_ROWS)])
def test_bad_api_value_names_its_parameter(make, key, texts):
    with pytest.raises(ValueError) as info:
        make()
    msg = str(info.value)
    assert key in msg
    for text in texts:
        assert text in msg, msg


def test_expert_overrides():
    with checks.expert("E"):
        assert Material(2000.0, 1.0, 0.2).E == 1.0
        with pytest.raises(ImplausibleValueError, match="density"):
            Material(2.2, 1.0, 0.2)  # only E is allowed
    with checks.expert():
        assert arch_layout(span=4000.0, ring_thickness=40.0, voussoirs=10)
    with pytest.raises(ImplausibleValueError):  # back on outside the block
        Material(2000.0, 1.0, 0.2)
    data = example()
    data["materials"]["brick"]["E"] = 1.0
    data["checks"] = {"allow": ["materials.brick.E"]}
    assert load_case(data).materials()["brick"].E == 1.0


def test_every_problem_is_listed():
    data = example()
    data["arch"]["span"] = 3000.0
    data["materials"]["brick"]["E"] = 1.0
    data["joints"]["mortar"]["tan_phi"] = 30.0
    with pytest.raises(CaseError) as info:
        load_case(data)
    assert len(info.value.problems) == 3
    for key in ("arch.span", "materials.brick.E", "joints.mortar.tan_phi"):
        assert key in str(info.value)


def test_numerical_failure_becomes_a_sentence():
    @numerical_failures("the test solve")
    def solve():
        raise FloatingPointError("dynamic relaxation diverged at load factor 0.0")

    with pytest.raises(NumericalError) as info:
        solve()
    msg = str(info.value)
    assert msg.startswith("the test solve broke down: a floating-point error")
    assert "diverged at load factor" in msg and "likely cause" in msg and "E, density" in msg
    assert isinstance(info.value, RuntimeError)  # the command line reports it in one line


# the command line: a subprocess per row, no traceback, nonzero exit, the key named
CLI_ROWS = [
    ("arch.span", 3000.0, "did you give millimetres?"),
    ("materials.brick.E", 1.0, "did you give MPa"),
    ("joints.mortar.tan_phi", "0.6", "must be a finite number"),
]


def _bad_file(key, value) -> str:
    """The example case file with one line changed."""
    lines = EXAMPLE_CASE.splitlines()
    table, leaf = key.rsplit(".", 1)
    start = next(i for i, x in enumerate(lines) if x.split("#")[0].strip() == f"[{table}]")
    k = next(i for i in range(start + 1, len(lines)) if lines[i].split("=")[0].strip() == leaf)
    lines[k] = f"{leaf} = {value!r}" if isinstance(value, str) else f"{leaf} = {value}"
    return "\n".join(lines) + "\n"


@pytest.fixture(scope="module")
def cli_runs(tmp_path_factory):
    """``masonry-fdem assess bad.toml`` for each row, the processes side by side."""
    root = tmp_path_factory.mktemp("cli")
    env = {k: v for k, v in os.environ.items()
           if not k.startswith(("OMPI_", "PMIX_", "PMI_"))}  # a fresh, serial process
    env["PYTHONPATH"] = str(ROOT)
    procs = []
    for n, (key, value, _) in enumerate(CLI_ROWS):
        folder = root / str(n)
        folder.mkdir()
        (folder / "bad.toml").write_text(_bad_file(key, value))
        procs.append((folder, subprocess.Popen(
            [sys.executable, "-m", "masonry_fdem.cli", "assess", str(folder / "bad.toml"),
             "--out", str(folder / "run")], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
            text=True, env=env)))
    out = []
    for folder, p in procs:
        _, err = p.communicate(timeout=180)
        out.append((folder, p.returncode, err))
    return out


@pytest.mark.skipif(MPI.COMM_WORLD.size > 1, reason="spawns the CLI: serial only")
@pytest.mark.parametrize("row", range(len(CLI_ROWS)), ids=[r[0] for r in CLI_ROWS])
def test_cli_reports_a_bad_case_in_one_line(cli_runs, row):
    key, _, text = CLI_ROWS[row]
    folder, code, err = cli_runs[row]
    assert code != 0
    assert "Traceback" not in err, err
    assert key in err and text in err, err
    assert not (folder / "run").exists()
