"""`assess`: arch to collapse against limit analysis, increment halving, ring separation,
the command line on bad case files, one process against two (issue #8); the status of a
run: a stall is not a collapse.

The dry arch: span 2 m, one ring of 0.2 m in 12 voussoirs (E = 10 GPa), dry joints with
tan φ = 10 (no tension, no sliding), a point load at quarter span. Its limit-analysis load
is 5.11 kN. Load control in 2000 N increments stalls at 4 kN, where the arch is nearly
a mechanism; the run goes on from there under displacement control and finds the peak.
"""

from __future__ import annotations

import copy
import json
import math
import re
from pathlib import Path

from mpi4py import MPI

import numpy as np
import pytest

from masonry_fdem.assessment.assess import assess
from masonry_fdem.assessment.case import CaseError, load_case
from masonry_fdem.assessment.report import read_curve
from masonry_fdem.cli import main as cli_main
from masonry_fdem.solvers import Status

DRY_ARCH = {
    "arch": {"span": 2.0, "ring_thickness": 0.2, "voussoirs": 12, "abutment_height": 0.3,
             "abutment_width": 0.4, "mesh_size": 0.2},
    "materials": {"brick": {"density": 2000.0, "E": 10e9, "nu": 0.2},
                  "abutment": {"density": 2000.0, "E": 30e9, "nu": 0.2}},
    "joints": {"mortar": {"tan_phi": 10.0}},
    "loading": {"position": 0.25, "increment": 2000.0, "displacement_increment": 1e-4},
    "analysis": {"dr_rtol": 1e-4, "max_iterations": 40000, "refinements": 0,
                 "post_peak_steps": 1},
}


def _case(data, increment=None, comm=MPI.COMM_WORLD):
    """The case with the load increment [N] (dynamic relaxation's) and the displacement
    increment (the Newton path's first arc-length step) scaled by increment / 2000."""
    d = copy.deepcopy(data)
    if increment is not None:
        d["loading"]["increment"] = increment
        d["loading"]["displacement_increment"] *= increment / 2000.0
    return load_case(d, name="dry_arch")


def _on_own_rank(jobs):
    """Run independent jobs (callables of a communicator) with one rank each on
    COMM_SELF, side by side under mpirun (all of them on one process when serial); every
    rank gets every result."""
    comm = MPI.COMM_WORLD
    mine = {k: job(MPI.COMM_SELF) for k, job in enumerate(jobs) if k % comm.size == comm.rank}
    out = {}
    for part in comm.allgather(mine):
        out.update(part)
    return [out[k] for k in range(len(jobs))]


@pytest.fixture(scope="module")
def dry_runs(tmp_path_factory):
    """The dry arch in 2000 N increments on all ranks of COMM_WORLD (it writes its run
    folder); then, side by side on one rank each, the same in 1000 N increments and (under
    mpirun, for the one-against-two test) in 2000 N increments on one process."""
    comm = MPI.COMM_WORLD
    root = comm.bcast(str(tmp_path_factory.mktemp("dry")) if comm.rank == 0 else None)
    from pathlib import Path

    out = Path(root) / "run"
    runs = {2000.0: assess(_case(DRY_ARCH, 2000.0), out=out, progress=False)}
    jobs = [lambda c: assess(_case(DRY_ARCH, 1000.0), write=False, progress=False, comm=c)]
    if comm.size > 1:
        jobs.append(lambda c: assess(_case(DRY_ARCH, 2000.0), write=False, progress=False,
                                     comm=c))
    done = _on_own_rank(jobs)
    runs[1000.0] = done[0]
    runs["one process"] = done[1] if comm.size > 1 else None
    return runs


def test_run_folder_is_complete(dry_runs):
    res = dry_runs[2000.0]
    folder = res.folder
    names = sorted(p.name for p in folder.iterdir())
    assert names == ["curve.csv", "first_hinge.png", "hinges.csv", "hinges.png",
                     "load_displacement.png", "mechanism.png", "paraview", "peak_load.png",
                     "report.md", "summary.json"]
    # the ParaView series: self-weight, every 10th increment and the last, as .vtu files
    # (and the ADIOS2 .bp series)
    n = len(res.loads) - 1
    steps = sorted({0, n} | set(range(0, n + 1, 10)))
    pvd = (folder / "paraview" / "model.pvd").read_text(encoding="utf-8")
    assert [float(t) for t in re.findall(r'timestep="([^"]+)"', pvd)] == steps
    assert (folder / "paraview" / "displacement.bp").is_dir()
    import meshio

    first, last = (meshio.read(folder / "paraview" / f"model_{k:06d}.vtu")
                   for k in (0, len(steps) - 1))
    assert 0 < np.abs(first.point_data["displacement"]).max() < np.abs(
        last.point_data["displacement"]).max()
    assert "ParaView: `paraview/model.pvd`" in (folder / "report.md").read_text(encoding="utf-8")
    assert not any(p.name.endswith(".partial") for p in folder.parent.iterdir())
    text = (folder / "report.md").read_text(encoding="utf-8")
    assert f"**Status: peak passed — collapse load {res.collapse_load / 1e3:.2f} kN.**" in text
    assert f"**{res.collapse_load / 1e3:.2f} kN**" in text
    assert f"{res.limit_load / 1e3:.2f} kN" in text
    first = res.events[0]
    assert first.kind == "hinge"
    assert (f"At the first hinge: {first.load / 1e3:.2f} kN, {first.displacement * 1e3:.3f} mm"
            in text)
    assert f"At the peak load: {res.peak_load / 1e3:.2f} kN" in text
    assert "![first hinge](first_hinge.png)" in text and "![peak load](peak_load.png)" in text
    status, curve = read_curve(folder / "curve.csv")
    assert status.startswith("peak passed — collapse load") and "% of its peak" in status, status
    assert (folder / "curve.csv").read_text(encoding="utf-8").startswith("# status: peak passed")
    np.testing.assert_allclose(curve[:, 0], res.loads, rtol=1e-5)
    summary = json.loads((folder / "summary.json").read_text())
    assert summary["status"]["status"] == "peak passed"
    assert summary["collapse_load"] == pytest.approx(res.collapse_load)
    assert len((folder / "hinges.csv").read_text().splitlines()) == 1 + len(res.events)


def test_dry_arch_four_hinges_and_limit_analysis(dry_runs):
    res = dry_runs[2000.0]
    print(f"\ndry arch: FDEM {res.collapse_load:.1f} N (resolution {res.resolution:.1f} N), "
          f"LP {res.limit_load:.1f} N, ratio {res.ratio:.4f}; open at collapse: "
          + ", ".join(f"{e.joint} {e.kind} opens {e.side}" for e in res.hinges_at_collapse)
          + f"; Newton iterations per step {res.iterations}")
    assert res.limit_status == "collapse"
    assert res.status.status is Status.PEAK_PASSED and res.collapsed
    assert res.collapse_load == res.peak_load == res.status.peak
    # within 5 % of the rigid-block LP, and not above it
    assert 0.95 <= res.ratio <= 1.0 + 1e-3, res.ratio
    # four hinges, at the joints of the LP mechanism, about the same edge
    hinges = [e for e in res.hinges_at_collapse if e.kind == "hinge"]
    assert len(hinges) == 4, [(e.joint, e.kind) for e in res.hinges_at_collapse]
    assert len(res.hinges_at_collapse) == 4
    fdem = {tuple(sorted(e.blocks)): e.position for e in hinges}
    lp = {tuple(sorted(b)): p for b, p in res.limit_hinges}
    assert set(fdem) == set(lp)
    for key, p in lp.items():
        assert np.allclose(fdem[key], p, atol=1e-9), (key, fdem[key], p)
    # the curve: rising to the peak, then falling (post-peak branch traced)
    k = int(np.argmax(res.loads))
    assert res.loads[k] == pytest.approx(res.collapse_load)
    assert 0 < k < len(res.loads) - 1
    assert res.loads[-1] < res.collapse_load
    assert np.all(np.diff(res.displacements[: k + 1]) > 0)


def test_the_first_hinge_is_counted_at_wider_openings_too(dry_runs):
    """The first hinge at the case's opening (the sequence's) and at 1e-3 and 1e-2 of the
    ring thickness: each where an end of its joint had opened that far, none before the
    narrower opening's, and the table in the report."""
    from masonry_fdem.assessment.assess import HINGE_OPENINGS

    res = dry_runs[2000.0]
    fh = res.first_hinges
    print("\nfirst hinge: " + "; ".join(
        f"{x['ratio']:g}: {x['joint']} at step {x['step']}, {x['load']:.1f} N, opened "
        f"{x['opening'] * 1e3:.3f} mm" for x in fh if x["step"] is not None))
    t = DRY_ARCH["arch"]["ring_thickness"]
    assert [x["ratio"] for x in fh] == sorted({1e-4, *HINGE_OPENINGS})
    first = next(e for e in res.events if e.kind == "hinge")
    assert fh[0]["load"] == first.load and fh[0]["displacement"] == first.displacement
    steps = [x["step"] for x in fh]
    assert all(s is not None for s in steps), steps  # the dry arch turns to a mechanism
    assert steps == sorted(steps) and steps[-1] > steps[0], steps
    for x in fh:
        assert x["opening"] > x["ratio"] * t, x
        assert res.loads[x["step"]] == x["load"] and x["side"] in ("intrados", "extrados")
    text = (res.folder / "report.md").read_text(encoding="utf-8")
    assert "| opening / ring thickness | first hinge |" in text
    assert "| load [kN] | of the collapse load |" in text  # (a peak passed)
    assert f"| 0.01 | {fh[-1]['joint']} | {fh[-1]['side']} |" in text
    assert json.loads((res.folder / "summary.json").read_text())["first_hinges"][-1][
        "step"] == steps[-1]
    # the limit analysis's mechanism in words (its four hinges drawn in hinges.png)
    assert "Limit analysis: a mechanism with 4 hinges." in text


def test_dry_arch_fdem_thrust_line_touches_the_faces_at_its_hinges(dry_runs):
    """The FDEM's line of thrust at the peak (where the resultant of the contact forces
    across each radial joint crosses it): inside the ring at every joint, and at the
    face the hinge turns about at each of the four hinges (the outer 5 % of the
    thickness), as the limit analysis's line of thrust at its hinges."""
    from masonry_fdem.geometry.arches import arch_circle

    res = dry_runs[2000.0]
    radius, yc, _ = arch_circle("semicircular", 2.0)
    t = 0.2
    (line,) = res.fdem_thrust  # one ring
    q = np.asarray(line)
    assert q.shape == (13, 2)  # 11 joints and 2 springings, all in compression
    ecc = (np.hypot(q[:, 0], q[:, 1] - yc) - radius - 0.5 * t) / t  # −½ intrados … ½
    print("\nFDEM thrust line at the peak, eccentricity / thickness at the joints: "
          + " ".join(f"{e:+.3f}" for e in ecc))
    assert np.all(np.abs(ecc) <= 0.5 + 1e-6)
    hinges = [e for e in res.hinges_at_collapse if e.kind == "hinge"]
    for h in hinges:
        ph = np.asarray(h.position)
        k = int(np.argmin(np.linalg.norm(q - ph, axis=1)))
        face = 0.5 if np.hypot(ph[0], ph[1] - yc) > radius + 0.5 * t else -0.5
        print(f"  {h.joint}: eccentricity {ecc[k]:+.3f} t (face {face:+.1f})")
        assert abs(ecc[k] - face) <= 0.05, (h.joint, ecc[k])
    # elsewhere the line stays off the faces
    others = np.ones(len(q), dtype=bool)
    others[[int(np.argmin(np.linalg.norm(q - np.asarray(h.position), axis=1)))
            for h in hinges]] = False
    assert np.all(np.abs(ecc[others]) < 0.45)


def test_halving_the_load_increment(dry_runs):
    assert dry_runs[1000.0].status.status is Status.PEAK_PASSED
    a, b = dry_runs[2000.0].collapse_load, dry_runs[1000.0].collapse_load
    print(f"\nfirst arc-length step 0.1 mm: {a:.2f} N, 0.05 mm: {b:.2f} N, change "
          f"{abs(a - b) / a:.2e}")
    assert abs(a - b) / a < 0.03, (a, b)


@pytest.mark.skipif(MPI.COMM_WORLD.size > 1, reason="one process (the suite's budget: 17 s "
                    "under mpirun); dynamic relaxation on two ranks is compared with one in "
                    "test_parallel.py and in test_one_process_and_two_give_the_same_collapse_load")
def test_ring_separation_lowers_the_collapse_load():
    """Three rings of 0.15 m, dry radial joints; the ring interfaces bonded by a strong
    mortar, or separated (frictional contact). Both are loaded by dynamic relaxation
    (``solver = "dr"``) in 5 kN increments to 15 kN with the same iteration limit (the
    separated arch collapses near 11.6 kN when followed to its peak under displacement
    control; the bonded one carries 92 kN). The Newton solver does not yet trace this
    fully separated dry arch (its path stalls near 9 kN in sticking and slipping ring
    contacts): dynamic relaxation here."""
    base = {
        "arch": {"span": 2.0, "rings": 3, "ring_thickness": 0.15, "voussoirs": [8, 9, 10],
                 "abutment_height": 0.3, "abutment_width": 0.6, "mesh_size": 0.15},
        "materials": copy.deepcopy(DRY_ARCH["materials"]),
        "joints": {"mortar": {"tan_phi": 0.8},
                   "ring": {"type": "bonded", "ft": 1e6, "GfI": 100.0, "c": 1e6,
                            "GfII": 500.0, "tan_phi": 0.8}},
        "loading": {"position": 0.25, "increment": 5000.0, "max_load": 15000.0},
        "analysis": {"solver": "dr", "dr_rtol": 1e-4, "max_iterations": 40000,
                     "refinements": 0, "friction": 0.8, "limit_analysis": False,
                     "follow_peak": False},
    }
    sep = copy.deepcopy(base)
    sep["damage"] = [{"type": "ring_separation", "rings": "all"}]
    # side by side on one rank each under mpirun
    r_sep, r_bond = _on_own_rank([
        lambda c: assess(load_case(sep, name="separated"), write=False, progress=False,
                         comm=c),
        lambda c: assess(load_case(base, name="bonded"), write=False, progress=False,
                         comm=c)])
    print(f"\nring-separated: {r_sep.status_line}; bonded: {r_bond.status_line}")
    # the separated arch stalls (not followed): a lower bound, no collapse load
    assert r_sep.status.status is Status.NOT_CONVERGED and r_sep.collapse_load is None
    assert r_sep.peak_load < 15000.0 and r_sep.status.at == pytest.approx(
        r_sep.peak_load + 5000.0)
    assert r_bond.status.status is Status.LOAD_REACHED and r_bond.collapse_load is None
    assert r_bond.peak_load == pytest.approx(15000.0)
    assert r_sep.peak_load < r_bond.peak_load


BAD_CASES = [
    ("[arch]\nspan = 2.0\nring_thickness = 0.2\nvoussoirs = 8\nabutment_height = 0.3\n"
     "colour = 'red'\n[materials.brick]\ndensity = 2000.0\nE = 1e10\nnu = 0.2\n"
     "[materials.abutment]\ndensity = 2000.0\nE = 1e10\nnu = 0.2\n[joints.mortar]\n",
     "unknown key 'colour' in [arch]"),
    ("[arch]\nspan = 2.0\nring_thickness = 0.2\nvoussoirs = 8\nabutment_height = 0.3\n"
     "[materials.brick]\ndensity = 2000.0\nE = 1e10\nnu = 0.2\n[joints.mortar]\n",
     "abutment"),
    ("[arch]\nspan = 2.0\nring_thickness = 0.2\nvoussoirs = 8\nabutment_height = 0.3\n"
     "[materials.brick]\ndensity = 2000.0\nE = 1e10\nnu = 0.2\n"
     "[materials.abutment]\ndensity = 2000.0\nE = 1e10\nnu = 0.2\n[joints.mortar]\n"
     "[loading]\nposition = 1.4\n", "loading.position"),
    ("[arch]\nspan = 2.0\nring_thickness = -0.2\nvoussoirs = 8\nabutment_height = 0.3\n"
     "[materials.brick]\ndensity = 2000.0\nE = 1e10\nnu = 0.2\n"
     "[materials.abutment]\ndensity = 2000.0\nE = 1e10\nnu = 0.2\n[joints.mortar]\n",
     "arch.ring_thickness"),
]


@pytest.mark.parametrize("text,names", BAD_CASES,
                         ids=["unknown_key", "missing_material", "load_off_arch",
                              "negative_thickness"])
def test_cli_rejects_bad_case_and_writes_nothing(tmp_path, capsys, text, names):
    comm = MPI.COMM_WORLD
    root = comm.bcast(str(tmp_path) if comm.rank == 0 else None, root=0)
    from pathlib import Path

    root = Path(root)
    f = root / "bad.toml"
    if comm.rank == 0:
        f.write_text(text + f"[analysis]\noutput = '{root / 'run'}'\n"
                     if "[analysis]" not in text else text)
    comm.barrier()
    code = cli_main(["assess", str(f), "--quiet"])
    err = capsys.readouterr().err
    assert code == 2
    if comm.rank == 0:
        assert names in err, err
        assert "error" in err
    comm.barrier()
    assert sorted(p.name for p in root.iterdir()) == ["bad.toml"]
    with pytest.raises(CaseError, match=re.escape(names)):
        load_case(f)


def test_one_process_and_two_give_the_same_collapse_load(dry_runs):
    """Under mpirun the dry arch is run again on one rank alone (COMM_SELF, in the
    fixture)."""
    comm = MPI.COMM_WORLD
    if comm.size == 1:
        pytest.skip("compares a parallel run with a serial one: run under mpirun -n 2")
    serial = dry_runs["one process"]
    par = dry_runs[2000.0]
    assert serial.status.status is par.status.status is Status.PEAK_PASSED
    print(f"\none process {serial.collapse_load:.3f} N, {comm.size} processes "
          f"{par.collapse_load:.3f} N")
    assert math.isclose(serial.collapse_load, par.collapse_load, rel_tol=2e-3), (
        serial.collapse_load, par.collapse_load)
    assert [e.joint for e in serial.hinges_at_collapse] == [
        e.joint for e in par.hinges_at_collapse]


def test_damage_scenarios_reach_the_model():
    """Each damage kind changes the FDEM model as the case says: a missing brick is one
    block fewer; an open joint, ring separation over a zone and decayed mortar leave the
    bonded joints of the undamaged arch fewer or weaker (the model is built, not run;
    here the ring interfaces are bonded by the mortar too)."""
    from masonry_fdem.assessment.assess import build_model

    base = {
        "arch": {"span": 2.0, "rings": 2, "ring_thickness": 0.15, "voussoirs": [8, 9],
                 "abutment_height": 0.3, "abutment_width": 0.5, "mesh_size": 0.15},
        "materials": copy.deepcopy(DRY_ARCH["materials"]),
        "joints": {"mortar": {"ft": 0.1e6, "GfI": 10.0, "c": 0.15e6, "GfII": 50.0}},
        "analysis": {"limit_analysis": False},
    }

    def build(damage):
        d = copy.deepcopy(base)
        d["damage"] = damage
        model, (contact, joints), _ = build_model(load_case(d, name="damaged"))
        ft = set(np.round(joints.props[:, 2]).tolist())  # tensile strengths in use [Pa]
        return model.blocks.n_blocks, joints.n_segments, ft

    nb0, ns0, st0 = build([])
    nb, ns, _ = build([{"type": "missing_brick", "ring": 0, "index": 3}])
    assert nb == nb0 - 1 and ns < ns0
    nb, ns, _ = build([{"type": "open_joint", "ring": 1, "index": 4}])
    assert nb == nb0 and ns < ns0
    _, ns_half, _ = build([{"type": "ring_separation", "from": 0.0, "to": 0.5}])
    _, ns_all, _ = build([{"type": "ring_separation"}])
    assert ns_all < ns_half < ns0
    _, ns, ft = build([{"type": "decayed_mortar", "factor": 0.5, "from": 0.2, "to": 0.6}])
    assert ns == ns0
    assert st0 == {0.1e6} and ft == {0.1e6, 0.05e6}


def test_a_run_starved_of_iterations_is_not_a_collapse(tmp_path, capsys):
    """The dry arch with 3000 DR iterations per step: self-weight (~1600) and 2 kN (~2500)
    converge, 4 kN (~27 000 with enough) does not. Under load control alone the run ends
    *not converged at 4 kN*, having carried 2 kN; with follow_peak the platen is then
    driven down and the first displacement step does not converge either. Neither is a
    collapse: no collapse load, 2 kN a lower bound — in the API, curve.csv, report.md,
    summary.json and the command line's output."""
    comm = MPI.COMM_WORLD
    starved = copy.deepcopy(DRY_ARCH)
    starved["analysis"].update(solver="dr", max_iterations=3000, limit_analysis=False,
                               follow_peak=False)
    res = assess(load_case(starved, name="starved"), write=False, progress=False)
    print(f"\nload control: {res.status_line} ({res.status.detail})")
    assert res.status.status is Status.NOT_CONVERGED and not res.collapsed
    assert res.collapse_load is None and res.ratio is None
    assert res.peak_load == pytest.approx(2000.0) and res.status.at == pytest.approx(4000.0)
    assert res.status_line == ("not converged at 4.00 kN — the arch carried 2.00 kN, a "
                               "lower bound of its collapse load")

    # the command line, load control followed under displacement control
    root = Path(comm.bcast(str(tmp_path) if comm.rank == 0 else None, root=0))
    starved["analysis"].update(follow_peak=True, output=str(root / "run"))
    case_file = root / "starved.toml"
    if comm.rank == 0:
        case_file.write_text(_toml(starved))
    comm.barrier()
    assert cli_main(["assess", str(case_file), "--quiet"]) == 0
    out = capsys.readouterr().out
    folder = root / "run"
    if comm.rank == 0:
        print(out)
        assert "status: not converged at" in out and "mm load-line displacement" in out
        assert "no collapse load; lower bound 2.00 kN" in out
        assert "collapse load 2.00" not in out
    text = (folder / "report.md").read_text(encoding="utf-8")
    assert "**Status: not converged at" in text
    assert "the arch carried 2.00 kN, a lower bound of its collapse load" in text
    assert "collapse reached" not in text and "FDEM collapse load" not in text
    assert "load control: no equilibrium at 4.00 kN within max_iterations = 3000" in text
    status, curve = read_curve(folder / "curve.csv")
    assert status.startswith("not converged at") and "a lower bound" in status
    np.testing.assert_allclose(curve[:, 0], [0.0, 2000.0], atol=1e-6)
    summary = json.loads((folder / "summary.json").read_text())
    assert summary["status"]["status"] == "not converged"
    assert summary["collapse_load"] is None
    assert summary["peak_load"] == pytest.approx(2000.0)


def _toml(data: dict) -> str:
    """A case dict as TOML (tables of scalars and lists)."""
    def value(v):
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, str):
            return json.dumps(v)
        if isinstance(v, list):
            return "[" + ", ".join(value(x) for x in v) + "]"
        return repr(v)

    lines = []

    def table(prefix, d):
        scalars = {k: v for k, v in d.items() if not isinstance(v, dict)}
        if scalars or not prefix:
            if prefix:
                lines.append(f"[{prefix}]")
            lines.extend(f"{k} = {value(v)}" for k, v in scalars.items())
        for k, v in d.items():
            if isinstance(v, dict):
                table(f"{prefix}.{k}" if prefix else k, v)

    table("", data)
    return "\n".join(lines) + "\n"


def test_reference_arch_hinges_from_mortar_states():
    """The reference case (three rings, sand between them, lime-mortar joints) traced
    over its peak: its hinges, read from the openings relative to the ring thickness and
    the mortar's state (cracked at the opening end), form the four-hinge mechanism of a
    load at quarter span through all three rings — under the load and at the far
    springing opening at the intrados, between them and near the near springing at the
    extrados."""
    import tomllib

    from masonry_fdem.assessment.case import EXAMPLE_CASE

    data = tomllib.loads(EXAMPLE_CASE)
    data["analysis"]["limit_analysis"] = False
    res = assess(load_case(data, name="reference"), write=False, progress=False)
    hinges = [e for e in res.events if e.kind == "hinge"]
    print("\n" + "; ".join(f"{e.joint} {e.side} s={e.s:.2f} at {e.load / 1e3:.2f} kN"
                           for e in hinges))
    assert res.status.status is Status.PEAK_PASSED
    # the mechanism at collapse: the hinges formed before the load fell to 2/3 of its
    # peak on the descending branch (further down the separated rings open elsewhere
    # too). Measured: three zones through the three rings by the peak (11.45 kN), the
    # near springing's extrados in rings 0 and 1 at 8.61 kN and in ring 2 at 7.75 kN on
    # the way down; the next hinges, at 6.61 and 5.92 kN, are in ring 2 alone
    loads, disps = np.asarray(res.loads), np.asarray(res.displacements)
    k = int(np.argmax(loads))
    below = np.flatnonzero(loads[k:] < 2.0 / 3.0 * res.status.peak)
    d_end = disps[k + below[0]] if below.size else disps[-1]
    at_collapse = [e for e in hinges if e.displacement < d_end]
    # cluster the hinges by position along the arch
    zones: list[list] = []
    for e in sorted(at_collapse, key=lambda e: e.s):
        if zones and e.s - zones[-1][-1].s < 0.06:
            zones[-1].append(e)
        else:
            zones.append([e])
    assert len(zones) == 4, [[(e.joint, round(e.s, 2)) for e in z] for z in zones]
    sides = [{e.side for e in z} for z in zones]
    assert sides == [{"extrados"}, {"intrados"}, {"extrados"}, {"intrados"}]
    s_mid = [float(np.mean([e.s for e in z])) for z in zones]
    assert 0.0 < s_mid[0] < 0.25 < s_mid[1] < 0.5 < s_mid[2] < 1.0
    assert s_mid[3] > 0.95  # the far springing
    # every zone through the three rings
    assert all({e.joint.split()[1] for e in z} == {"0", "1", "2"} for z in zones)


@pytest.mark.parametrize("delta,separated", [(2e-3, True), (1e-4, False)])
def test_ring_separation_measure_of_a_radial_lift(delta, separated):
    """Each ring r lifted radially by r·δ opens every layer between rings by exactly δ:
    the widest opening is δ (to the cosine of half an interface's angle), and the layer between rings r−1 and r is separated over
    the chord of its radius R + r t (2 (R + r t) / span of the span, semicircular arch)
    when δ exceeds the threshold of 1e-3 × t = 0.15 mm, over none of it below."""
    from masonry_fdem.assessment.assess import _RingMonitor, build_model
    from masonry_fdem.geometry.arches import arch_centre

    d = {"arch": {"span": 2.0, "rings": 3, "ring_thickness": 0.15, "voussoirs": [8, 9, 10],
                  "abutment_height": 0.3, "abutment_width": 0.6, "mesh_size": 0.15},
         "materials": copy.deepcopy(DRY_ARCH["materials"]),
         "joints": {"mortar": {"tan_phi": 0.8}}, "analysis": {"limit_analysis": False}}
    case = load_case(d, name="lift")
    model, _, _ = build_model(case, comm=MPI.COMM_SELF)
    mon = _RingMonitor(case, model)
    names = model.blocks.block_names
    ring = np.array([int(names[b].split(":")[1]) if names[b].startswith("voussoir") else 0
                     for b in model.node_block])
    a = case.arch
    x = model.X
    c = np.array([arch_centre(a.kind, a.span, a.rise, xi) for xi in x[:, 0]])
    radial = (x - c) / np.linalg.norm(x - c, axis=1)[:, None]
    model.u.x.array[:] = ((ring * delta)[:, None] * radial).ravel()
    out = mon.layers()
    R, t = a.span / 2, a.ring_thickness
    print(f"\nlift {delta * 1e3:.2f} mm: " + "; ".join(
        f"layer {x['layer']}: {x['max_opening'] * 1e3:.4f} mm over "
        f"{100 * x['span_fraction']:.2f} %" for x in out))
    assert [x["layer"] for x in out] == [1, 2]
    for x_ in out:
        assert x_["threshold"] == pytest.approx(1e-3 * t)
        # (an interface is a chord: its normal differs from the radial direction at its
        # ends by half its angle, a few degrees here)
        assert delta * np.cos(np.pi / 16) <= x_["max_opening"] <= delta * (1 + 1e-9)
        want = 2 * (R + x_["layer"] * t) / a.span if separated else 0.0
        assert x_["span_fraction"] == pytest.approx(want, rel=1e-9, abs=1e-12)
