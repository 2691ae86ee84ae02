"""Case files of ``masonry-fdem assess``: the example loads, bad cases fail with messages
naming the problem, nothing is written by loading, damage and anchors reach the model."""

from __future__ import annotations

import copy
import math
import tomllib

from mpi4py import MPI

import numpy as np
import pytest

from masonry_fdem.assessment.case import (
    EXAMPLE_CASE,
    TONNE_FORCE,
    ArchCase,
    CaseError,
    DamageKind,
    load_case,
    prepare_run_folder,
)
from masonry_fdem.interactions.joints.joints import JointMaterial
from masonry_fdem.geometry import arch_layout
from masonry_fdem.solvers.limit_analysis import find_interfaces


def example() -> dict:
    """A fresh dict of the example case (tests mutate it)."""
    return copy.deepcopy(tomllib.loads(EXAMPLE_CASE))


def problems_of(data, **kw) -> str:
    with pytest.raises(CaseError) as info:
        load_case(data, **kw)
    return str(info.value)


# ---------------------------------------------------------------------- the example
def test_example_case_builds_the_three_ring_arch():
    case = load_case(example())
    assert isinstance(case, ArchCase)
    assert case.arch.rings == 3 and case.arch.voussoirs == (26, 28, 30)
    layout = case.layout()
    names = layout.names
    # stagger 0.5: ring 1 is shifted by half a voussoir (n + 1 blocks), ring 2 by a whole one
    per_ring = [sum(n.startswith(f"voussoir:{k}:") for n in names) for k in range(3)]
    assert per_ring == [26, 29, 30]
    assert len(layout) == 26 + 29 + 30 + 2
    assert names[-2:] == ("abutment:left", "abutment:right")
    assert set(layout.materials) == {"brick", "abutment"}
    mats = case.materials()
    assert mats["brick"].E == 10e9 and mats["abutment"].density == 2400.0
    assert case.mortar.ft == 0.1e6 and case.mortar.bonded
    assert case.ring_joint_type == "sand"
    assert case.ring_joint.ft == 0.0 and case.ring_joint.c == 0.0
    assert case.ring_joint.tan_phi == 0.5 and not case.ring_joint.bonded
    assert case.loading.increment == pytest.approx(TONNE_FORCE) == 9806.65
    assert case.loading.spreader_width == 0.1
    assert case.analysis.output.as_posix() == "runs/case"
    assert case.anchors() == []


def test_load_point_is_on_the_extrados_at_quarter_span():
    case = load_case(example())
    x, y = case.load_point()
    assert x == pytest.approx(-0.75)  # 0.75 m from the left springing, origin at mid-span
    r_out = 1.5 + 3 * 0.11
    # on the extrados polyline: inside the exact circle by at most the sagitta of a chord
    sagitta = r_out * (1 - math.cos(math.pi / 30 / 2))
    assert math.sqrt(r_out**2 - x**2) - sagitta - 1e-12 <= y <= math.sqrt(r_out**2 - x**2)
    pts = case.load_points()
    assert pts.shape == (2, 2)
    np.testing.assert_allclose(pts[:, 0], [-0.8, -0.7])
    # the same load given as x [m] from the left springing
    data = example()
    del data["loading"]["position"]
    data["loading"]["x"] = 0.75
    assert load_case(data).load_point() == pytest.approx((x, y))


def test_loading_from_a_file_and_default_output(tmp_path):
    path = tmp_path / "trl_arch.toml"
    path.write_text(EXAMPLE_CASE)
    case = load_case(path)
    assert case.name == "trl_arch" and case.source == path
    assert case.analysis.output.as_posix() == "runs/trl_arch"
    assert case.analysis.friction == 0.6 and case.analysis.limit_analysis


# ---------------------------------------------------------------------- bad cases
def test_unknown_key_gets_a_suggestion():
    data = example()
    data["arch"]["spna"] = data["arch"].pop("span")
    msg = problems_of(data)
    assert "unknown key 'spna' in [arch] (did you mean 'span'?)" in msg
    assert "arch.span: missing" in msg


def test_unknown_joint_field_and_unknown_table():
    data = example()
    data["joints"]["mortar"]["tan_ph"] = 0.7
    data["anlysis"] = {}
    msg = problems_of(data)
    assert "unknown key 'tan_ph' in [joints.mortar] (did you mean 'tan_phi'?)" in msg
    assert "unknown key 'anlysis' in the case (did you mean 'analysis'?)" in msg


def test_missing_material():
    data = example()
    del data["materials"]["brick"]
    msg = problems_of(data)
    assert "materials: no material 'brick' (used by arch.voussoir_material)" in msg


def test_softening_integration_reaches_the_joints():
    """``[analysis] softening``: "implicit" by default, "imex" sets the joints' IMEX
    integration (their strengths then come from the extrapolation, not the materials),
    anything else is named."""
    from masonry_fdem.assessment.assess import build_model
    from masonry_fdem.interactions.joints import _kernels as JK

    assert load_case(example()).analysis.softening == "implicit"
    data = example()
    data.setdefault("analysis", {})["softening"] = "imex"
    case = load_case(data)
    assert case.analysis.softening == "imex"
    _, inter, _ = build_model(case, MPI.COMM_WORLD)
    joints = next(i for i in inter if i.name == "joints")
    assert joints.imex
    ipmat, props = joints._law()
    assert np.isinf(props[:, JK.P_GF1]).all()  # the law's own softening is off
    data["analysis"]["softening"] = "explicit"
    assert "analysis.softening" in problems_of(data)


def test_through_layers_reaches_the_contact():
    """``[analysis] through_layers``: off by default; true gives the block contact the
    joint layers' stiffness (a pair with a facet on the sand layer takes its k_n where
    softer than the penalty), and the report says so; a non-boolean is named."""
    from masonry_fdem.assessment.assess import build_model
    from masonry_fdem.assessment.report import _solver_text

    assert load_case(example()).analysis.through_layers is False
    data = example()
    data["joints"]["ring"] = {"type": "sand", "tan_phi": 0.5, "kn": 5e9, "ks": 2e9}
    kn = []
    for on in (False, True):
        data.setdefault("analysis", {})["through_layers"] = on
        case = load_case(data)
        assert case.analysis.through_layers is on
        model, inter, _ = build_model(case, MPI.COMM_WORLD)
        contact = next(i for i in inter if i.name == "contact")
        assert contact.settings.through_layers is on
        contact.rebuild(np.zeros_like(model.v))  # the candidate pairs and their penalties
        kn.append(MPI.COMM_WORLD.allreduce(float(contact.eps_n.min()) if contact.eps_n.size
                                           else np.inf, op=MPI.MIN))
        assert ("joint layer at the layer's stiffness" in _solver_text(case)) is on
    print(f"\nsmallest contact penalty: {kn[0]:.3g} Pa/m off, {kn[1]:.3g} Pa/m on")
    assert kn[1] == pytest.approx(5e9)  # the sand layer's k_n on its facets' pairs
    assert kn[0] > 100 * 5e9  # the contact's own penalty, E/h
    data["analysis"]["through_layers"] = "yes"
    assert "analysis.through_layers" in problems_of(data)


@pytest.mark.parametrize(
    ("key", "value", "expected"),
    [("position", 1.3, "loading.position: 1.3 is off the arch (0..1 of the span)"),
     ("x", 3.5, "loading.x: 3.5 m is off the arch (0..3 m from the left springing)"),
     ("x", -0.2, "loading.x: -0.2 m is off the arch")],
)
def test_load_off_the_arch(key, value, expected):
    data = example()
    del data["loading"]["position"]
    data["loading"][key] = value
    assert expected in problems_of(data)


def test_spreader_running_off_the_span():
    data = example()
    data["loading"]["position"] = 0.01
    assert "loading.spreader_width: a 0.1 m spreader" in problems_of(data)


@pytest.mark.parametrize(
    ("key", "value", "expected"),
    [("ring_thickness", -0.1, "arch.ring_thickness: must be > 0, got -0.1"),
     ("span", -3.0, "arch.span: must be > 0, got -3.0"),
     ("span", "3 m", "arch.span: must be a finite number, got '3 m'"),
     ("voussoirs", [26, 28], "arch.voussoirs: 2 values but the arch has 3 rings"),
     ("kind", "gothic", "arch.kind: must be one of"),
     ("rise", 1.0, "arch.rise: a semicircular arch has rise span/2 = 1.5 m")],
)
def test_bad_arch_values(key, value, expected):
    data = example()
    data["arch"][key] = value
    assert expected in problems_of(data)


def test_abutment_narrower_than_the_springing_joint():
    data = example()
    data["arch"]["abutment_width"] = 0.2  # the springing joint is 3 x 0.11 = 0.33 m wide
    assert "arch: abutment_width 0.2 m is narrower than the springing joint" in problems_of(data)


@pytest.mark.parametrize(
    ("entry", "expected"),
    [({"type": "missing_brick", "ring": 3, "index": 0},
      "damage[0].ring: 3 but the arch has 3 rings (0..2)"),
     ({"type": "missing_brick", "ring": 0, "index": 26},
      "damage[0].index: 26 but ring 0 has 26 voussoirs (0..25)"),
     ({"type": "open_joint", "ring": 1, "index": 31},
      "damage[0].index: 31 but ring 1 has joints 0..29"),
     ({"type": "ring_separation", "rings": [0, 5]},
      "damage[0].rings: 5 but the arch has 3 rings (0..2)"),
     ({"type": "decayed_mortar", "factor": 1.5},
      "damage[0].factor: must be <= 1, got 1.5"),
     ({"type": "ring_separation", "from": 0.6, "to": 0.4},
      "damage[0].to: must be > from (0.6), got 0.4"),
     ({"type": "crack"}, "damage[0].type: must be one of")],
)
def test_damage_out_of_range(entry, expected):
    data = example()
    data["damage"] = [entry]
    assert expected in problems_of(data)


def test_bad_joint_field_is_named_by_its_table():
    data = example()
    data["joints"]["mortar"]["GfI"] = 0.0  # ft > 0 without a fracture energy
    msg = problems_of(data)
    assert "joints.mortar: JointMaterial: a tensile strength ft > 0 needs GfI > 0 N/m" in msg
    data = example()
    data["joints"]["ring"] = {"type": "bonded", "kn": -1.0}
    assert "joints.ring.kn: must be > 0, got -1.0 [Pa/m]" in problems_of(data)
    data = example()
    data["joints"]["ring"]["c"] = 1e5
    assert "joints.ring.c: a sand layer (type = 'sand') is friction only" in problems_of(data)
    data = example()
    data["joints"]["mortar"]["kn"] = 1e8  # below ft²/GfI = 1e9: snap-back
    assert "joints.mortar: JointMaterial: kn = 1e+08 Pa/m is below ft²/GfI" in problems_of(data)


def test_toml_syntax_error_names_file_and_line(tmp_path):
    path = tmp_path / "broken.toml"
    path.write_text("[arch]\nspan = 3.0\nrings = = 3\n")
    msg = problems_of(path)
    assert str(path) in msg and "line 3" in msg and "TOML syntax error" in msg


def test_missing_file():
    assert "cannot read the case file" in problems_of("no/such/case.toml")


def test_all_problems_are_reported_together():
    data = example()
    data["arch"]["ring_thickness"] = -0.1
    data["arch"]["spna"] = 3.0
    data["materials"]["brick"]["nu"] = 0.7
    data["loading"]["position"] = 1.3
    data["joints"]["mortar"]["GfII"] = 0.0
    data["damage"] = [{"type": "missing_brick", "ring": 7, "index": 0}]
    with pytest.raises(CaseError) as info:
        load_case(data)
    err = info.value
    lines = str(err).splitlines()
    assert lines[0] == f"{len(err.problems)} problems:"
    assert len(lines) == len(err.problems) + 1
    for expected in ("arch.ring_thickness: must be > 0, got -0.1",
                     "unknown key 'spna' in [arch]",
                     "materials.brick.nu: must be < 0.5, got 0.7",
                     "loading.position: 1.3 is off the arch",
                     "joints.mortar: JointMaterial: a cohesion c > 0 needs GfII > 0",
                     "damage[0].ring: 7"):
        assert sum(expected in line for line in lines) == 1, expected


# ---------------------------------------------------------------------- nothing written
def test_loading_writes_nothing_and_prepare_run_folder(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # the default output runs/<name> would land here
    out = tmp_path / "run"
    data = example()
    data["analysis"]["output"] = str(out)
    bad = copy.deepcopy(data)
    bad["arch"]["span"] = -3.0
    with pytest.raises(CaseError):
        load_case(bad)
    del bad["analysis"]["output"]
    with pytest.raises(CaseError):
        load_case(bad)
    case = load_case(data)
    assert list(tmp_path.iterdir()) == [] and not out.exists()
    assert prepare_run_folder(case) == out and out.is_dir()
    assert prepare_run_folder(case) == out  # empty: fine
    (out / "history.csv").write_text("old")
    with pytest.raises(CaseError, match="analysis.output: the folder .* is not empty"):
        prepare_run_folder(case)
    assert prepare_run_folder(case, overwrite=True) == out
    assert (out / "history.csv").read_text() == "old"


def test_prepare_run_folder_collective(tmp_path):
    comm = MPI.COMM_WORLD
    root = comm.bcast(str(tmp_path), root=0)
    data = example()
    data["analysis"]["output"] = f"{root}/collective/run"
    case = load_case(data)
    out = prepare_run_folder(case, comm=comm)
    comm.barrier()
    assert out.is_dir()
    if comm.rank == 0:
        (out / "x").write_text("x")
    comm.barrier()
    with pytest.raises(CaseError, match="not empty"):  # every rank raises, none hangs
        prepare_run_folder(case, comm=comm)


# ---------------------------------------------------------------------- damage, anchors
def test_missing_brick_removes_that_block():
    data = example()
    data["damage"] = [{"type": "missing_brick", "ring": 0, "index": 12},
                      {"type": "missing_brick", "ring": 2, "index": 29}]
    case = load_case(data)
    full = arch_layout(**case.arch.layout_kwargs())
    layout = case.layout()
    assert len(layout) == len(full) - 2
    assert set(full.names) - set(layout.names) == {"voussoir:0:12", "voussoir:2:29"}
    kept = full.names.index("voussoir:0:13")
    np.testing.assert_array_equal(layout.polygons[layout.names.index("voussoir:0:13")],
                                  full.polygons[kept])


def test_radial_anchors_lie_inside_the_ring_band():
    data = example()
    angles = [30.0, 60.0, 90.0, 120.0, 150.0]
    data["anchors"] = [{"layout": "radial", "angles": angles, "diameter": 0.016, "count": 2,
                        "cover": 0.03, "steel": {"yield_stress": 460e6},
                        "bond": {"slip": [2e-4, 2e-3], "stress": [2e6, 1e6]}},
                       {"layout": "stitch", "start_angle": 60.0, "end_angle": 120.0,
                        "depth": 0.165, "diameter": 0.012}]
    case = load_case(data)
    anchors = case.anchors()
    assert len(anchors) == len(angles) + 1
    r_in, r_out = 1.5, 1.5 + 3 * 0.11
    for a, ang in zip(anchors[:-1], angles, strict=True):
        r = np.linalg.norm(a.points, axis=1)
        assert np.all(r > r_in) and np.all(r < r_out)
        np.testing.assert_allclose(r, [r_in + 0.03, r_out - 0.03])
        np.testing.assert_allclose(np.degrees(np.arctan2(a.points[:, 1], a.points[:, 0])), ang)
        assert a.count == 2 and a.steel.yield_stress == 460e6 and a.bond.strength == 2e6
    np.testing.assert_allclose(np.linalg.norm(anchors[-1].points, axis=1), 1.665)
    assert all(a.shear is None for a in anchors)  # no dowel unless asked for


def test_anchor_shear_gives_the_joint_dowel():
    """``[anchors.shear]``: ``fc`` gives JointDowel.from_bar of the anchor's bar and steel;
    ``stiffness``/``strength`` give it directly; mixing them is refused, with the key."""
    from masonry_fdem.interactions.anchors import JointDowel

    data = example()
    data["anchors"] = [{"layout": "radial", "angles": [60.0], "diameter": 0.016,
                        "steel": {"E": 200e9, "yield_stress": 460e6}, "shear": {"fc": 12e6}},
                       {"layout": "radial", "angles": [120.0], "diameter": 0.016,
                        "shear": {"stiffness": 2e7, "strength": 1e4}}]
    a0, a1 = load_case(data).anchors()
    assert a0.shear == JointDowel.from_bar(0.016, 200e9, 460e6, 12e6)
    assert a1.shear == JointDowel(2e7, 1e4)
    data["anchors"] = [{"layout": "radial", "angles": [60.0], "diameter": 0.016,
                        "shear": {"fc": 12e6, "strength": 1e4}},
                       {"layout": "radial", "angles": [90.0], "diameter": 0.016,
                        "shear": {"c1": 0.6}},
                       {"layout": "radial", "angles": [120.0], "diameter": 0.016,
                        "shear": {"stiffness": 2e7, "c0": 1.0}}]
    msg = problems_of(data)
    assert "anchors[0].shear.strength: computed from the bar with fc" in msg
    assert "anchors[1].shear: give fc" in msg
    assert "anchors[2].shear.c0: used only with fc" in msg


def test_bad_anchors():
    data = example()
    data["anchors"] = [{"layout": "radial", "angles": [200.0], "diameter": 0.016},
                       {"layout": "stitch", "start_angle": 60.0, "end_angle": 120.0,
                        "depth": 0.5, "diameter": 0.012},
                       {"layout": "radial", "angles": [90.0], "diameter": 0.016,
                        "steel": {"E": 200e9, "yield_stress": 500e6, "rupture_strain": 1e-4}}]
    msg = problems_of(data)
    assert "anchors[0]: anchor angle 200.0 deg is outside the arch (0..180 deg)" in msg
    assert "anchors[1]: depth 0.5 m is outside the arch (0..0.33 m)" in msg
    assert "anchors[2].steel: rupture_strain 0.0001 must exceed the yield strain" in msg


def test_damage_becomes_joint_rules():
    data = example()
    data["damage"] = [{"type": "open_joint", "ring": 0, "index": 5},
                      {"type": "ring_separation", "rings": [0, 1], "from": 0.0, "to": 0.5},
                      {"type": "decayed_mortar", "rings": [2], "from": 0.5, "to": 1.0,
                       "factor": 0.5}]
    case = load_case(data)
    assert [d.kind for d in case.damage] == [DamageKind.OPEN_JOINT,
                                             DamageKind.RING_SEPARATION,
                                             DamageKind.DECAYED_MORTAR]
    layout = case.layout()
    rules = case.joint_rules(layout)
    itf = find_interfaces(layout)

    def material(point):
        for pred, mat in rules:
            if pred(point):
                return mat
        return "mortar"  # no rule: the materials table

    counts = {"dry": 0, "decayed": 0}
    for a, b, p0, p1 in zip(*itf, strict=True):
        na, nb = layout.names[a], layout.names[b]
        if na.startswith("abutment") and nb.startswith("abutment"):
            continue
        # a quarter along the interface, as a joint segment of the mesh would be
        point = 0.75 * p0 + 0.25 * p1
        mid = 0.5 * (p0 + p1)
        got = material(point)
        ka, kb = (int(n.split(":")[1]) if n.startswith("voussoir") else -1 for n in (na, nb))
        if {na, nb} == {"voussoir:0:4", "voussoir:0:5"}:
            assert got is None
            counts["dry"] += 1
        elif -1 < ka != kb > -1 and {ka, kb} == {0, 1} and mid[0] < -1e-9:
            assert got is None  # separated rings 0/1 on the left half
            counts["dry"] += 1
        elif -1 < ka != kb > -1:
            assert got is case.ring_joint  # the sand
        elif max(ka, kb) == 2 and mid[0] > -1e-9:
            assert isinstance(got, JointMaterial)
            assert got.ft == pytest.approx(0.5 * case.mortar.ft)
            assert got.c == pytest.approx(0.5 * case.mortar.c)
            assert got.fc == pytest.approx(0.5 * case.mortar.fc)
            counts["decayed"] += 1
        else:
            assert got == "mortar", (na, nb)
    assert counts["dry"] > 10 and counts["decayed"] == 16  # joints 15..29 + right springing


def test_limit_analysis_of_the_case():
    """The rigid-block collapse load of the case (a monolithic 0.33 m ring: the three rings
    of the example glued into one), positive and below the cap."""
    data = example()
    data["arch"].update(rings=1, ring_thickness=0.33, voussoirs=26)
    data["joints"].pop("ring")
    case = load_case(data)
    res = case.limit_analysis()
    assert res.status == "collapse"
    assert 0.5 * TONNE_FORCE < res.load_factor < case.loading.max_load
    hinge_blocks = {b for h in res.hinges for b in h.blocks}
    assert len(res.hinges) >= 4 and "abutment:right" in hinge_blocks
