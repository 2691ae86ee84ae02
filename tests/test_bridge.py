"""An arch with continuum fill (the ``[fill]`` of a case): the fill's geometry, bad input
named, and a small single-span bridge that carries more with its fill than bare, the same
on any number of ranks."""

from __future__ import annotations

import copy
import json
import math
import runpy
import sys
from dataclasses import replace
from pathlib import Path

from mpi4py import MPI

import numpy as np
import pytest

from masonry_fdem.assessment.assess import assess, build_model
from masonry_fdem.assessment.case import CaseError, load_case
from masonry_fdem.geometry import arch_layout, polygon_area
from masonry_fdem.geometry.fill import extrados_vertices, fill_layout, fill_loads, fill_passive
from masonry_fdem.geometry.fill import passive_coefficient, upper_envelope
from masonry_fdem.materials import MohrCoulomb

ROOT = Path(__file__).resolve().parents[1]

#: a small single-span bridge: a 2 m segmental ring (rise span/4) under 0.2 m of fill
SMALL = {
    "arch": dict(kind="segmental", span=2.0, rise=0.5, rings=1, ring_thickness=0.15,
                 voussoirs=15, abutment_height=0.3, abutment_width=0.4, mesh_size=0.15),
    "materials": {"brick": dict(density=2000.0, E=5e9, nu=0.2),
                  "abutment": dict(density=2400.0, E=30e9, nu=0.2),
                  "fill": dict(density=1900.0, E=30e6, nu=0.3, c=2e3, phi=35.0)},
    "joints": {"mortar": dict(kn=5e10, ks=2e10, tan_phi=0.6)},
    "loading": dict(position=0.25, spreader_width=0.2),
    "fill": dict(cover=0.2, mesh_size=0.1),
}


def small(**changes) -> dict:
    d = copy.deepcopy(SMALL)
    for path, value in changes.items():
        table, key = path.split("__")
        if value is None:
            d[table].pop(key, None)
        else:
            d.setdefault(table, {})[key] = value
    return d


def test_fill_lies_on_the_extrados_up_to_the_road():
    arch = arch_layout(kind="segmental", span=2.0, rise=0.5, ring_thickness=0.15,
                       voussoirs=15, abutment_height=0.3, abutment_width=0.4)
    fl = fill_layout(arch, cover=0.2, road_points=(-0.6, -0.4))
    assert fl.names == ("fill", "wall:left", "wall:right")
    fill = fl.polygons[0]
    xmin, ymin, xmax, _ = arch.bounds
    # cover over the crown's extrados (its highest vertex: 15 voussoirs, a chord at the top)
    road = max(p[:, 1].max() for p in arch.polygons) + 0.2
    assert road == pytest.approx(0.5 + 0.15 * math.cos(math.pi / 2 / 15 * 0) + 0.2, abs=0.01)
    assert np.isclose(fill[:, 1].max(), road) and np.isclose(fill[:, 0].min(), xmin)
    # its area is the box under the road less what the arch and abutments take of it
    y0 = upper_envelope(arch, np.array([xmin]))[0]  # the abutment tops
    xs = np.linspace(xmin, xmax, 20001)
    under = np.trapezoid(road - np.maximum(upper_envelope(arch, xs), y0), xs)
    assert polygon_area(fill) == pytest.approx(under, rel=1e-6)
    # every vertex of the fill's underside is a vertex of the arch or an abutment: the
    # meshes meet node to node; no two vertices closer than a millimetre (no slivers)
    verts = np.vstack(arch.polygons)
    low = fill[fill[:, 1] < road - 1e-9]
    assert all(np.min(np.linalg.norm(verts - p, axis=1)) < 1e-9 for p in low)
    gaps = np.linalg.norm(np.diff(np.vstack([fill, fill[:1]]), axis=0), axis=1)
    assert gaps.min() > 1e-3
    # the road points are vertices; the walls stand on the abutments' outer faces
    assert any(np.allclose(p, (-0.6, road)) for p in fill)
    assert np.isclose(fl.polygons[1][:, 0].max(), xmin)
    assert np.isclose(fl.polygons[2][:, 0].min(), xmax)


@pytest.mark.parametrize("kw, expected", [
    (dict(cover=0.0), "cover must be > 0"),
    (dict(cover=0.2, wall_thickness=-1.0), "wall_thickness"),
    (dict(cover=0.2, road_points=(5.0,)), "off the fill"),
])
def test_bad_fill_geometry(kw, expected):
    arch = arch_layout(kind="segmental", span=2.0, rise=0.5, ring_thickness=0.15,
                       voussoirs=15, abutment_height=0.3, abutment_width=0.4)
    with pytest.raises(ValueError, match=expected):
        fill_layout(arch, **kw)
    with pytest.raises(ValueError, match="no voussoir"):
        fill_layout(arch_layout(kind="segmental", span=2.0, rise=0.5, ring_thickness=0.15,
                                voussoirs=15, abutment_height=0.3).__class__(
            (arch.polygons[-1],), ("abutment",), ("abutment:left",)), cover=0.2)


def test_fill_case_loads_and_builds():
    case = load_case(small())
    f = case.fill
    assert isinstance(case.materials()["fill"], MohrCoulomb)
    assert f.interface_friction == pytest.approx(math.tan(math.radians(2 / 3 * 35.0)))
    assert f.interface_stiffness == pytest.approx(20 * 30e6 / 0.1)
    (x, y), = case.load_points()
    assert x == pytest.approx(-0.5) and y == pytest.approx(case.road_level() + 0.05)
    assert case.load_blocks() == "spreader"
    model, inter, _ = build_model(case, MPI.COMM_WORLD)
    names = model.blocks.block_names
    assert {"fill", "wall:left", "wall:right", "spreader"} <= set(names)
    assert model.hypotheses["fill"].value == "plane_strain"
    assert model.hypotheses["brick"].value == "plane_stress"
    assert {p.name for p in model.prescriptions} == {"abutments", "walls", "beam guide"}
    # the limit analysis loads the ring with the fill's weight and the dispersed axle
    assert case.limit_analysis().status == "collapse"
    # [fill] crossed: the fill's triangles in fours about the centres of quadrilaterals,
    # the rest of the mesh as before
    assert not f.crossed
    crossed = load_case(small(fill__crossed=True))
    assert crossed.fill.crossed
    cm, _, _ = build_model(crossed, MPI.COMM_WORLD)

    def cells(m, name):
        b = m.blocks
        i = b.block_names.index(name)
        return b.cells[b.cell_offsets[i]:b.cell_offsets[i + 1]]

    assert len(cells(cm, "fill")) % 4 == 0
    assert len(cells(cm, "fill")) != len(cells(model, "fill"))
    assert np.array_equal(cells(cm, "voussoir:0:3").shape, cells(model, "voussoir:0:3").shape)


@pytest.mark.parametrize("changes, expected", [
    (dict(materials__fill=dict(density=1900.0, E=30e6, nu=0.3)), "is elastic"),
    (dict(fill__material="soil"), "no [materials.soil]"),
    (dict(fill__material="brick"), "arch's own material"),
    (dict(fill__cover=-0.1), "fill.cover"),
    (dict(loading__spreader_width=0.0), "a load on the fill needs a loading beam"),
    (dict(fill__depth=0.3), "depth"),
    (dict(materials__fill=dict(density=1900.0, E=30e6, nu=0.3, c=2e3, phi=30.0, psi=35.0)),
     "dilatancy angle"),
])
def test_bad_fill_cases_are_named(changes, expected):
    with pytest.raises(CaseError) as info:
        load_case(small(**changes))
    assert expected in str(info.value)


def _run(fill: bool, comm):
    d = small()
    if not fill:
        d.pop("fill")
    return assess(load_case(d), write=False, progress=False, comm=comm)


@pytest.mark.skipif(MPI.COMM_WORLD.size > 1, reason="one process (the suite's budget); "
                    "under mpirun the fill case is compared across ranks instead")
def test_fill_raises_the_collapse_load_of_a_single_span():
    bare = _run(False, MPI.COMM_WORLD)
    filled = _run(True, MPI.COMM_WORLD)
    print(f"\nsingle span, load at quarter span: bare {bare.status_line} (limit analysis "
          f"{bare.limit_load / 1e3:.2f} kN); with fill {filled.status_line}")
    assert bare.status.status.value == "peak passed"
    assert filled.status.status.value == "peak passed"
    # the bare ring against its rigid-block limit load (the same arch and load)
    assert abs(bare.collapse_load / bare.limit_load - 1.0) < 0.05
    # the fill spreads the load and holds the haunches: several times the bare ring's
    assert filled.collapse_load > 3.0 * bare.collapse_load


def test_fill_case_same_on_any_number_of_ranks():
    if MPI.COMM_WORLD.size == 1:
        pytest.skip("compares ranks: run under mpirun -n 2")
    world = _run(True, MPI.COMM_WORLD)
    one = _run(True, MPI.COMM_SELF)
    # up to the peak (past it, round-off may pick another of the nearly equal paths of a
    # softening mechanism; both then fall past the peak)
    k = int(np.argmax(one.loads)) + 1
    dl = np.abs(world.loads[:k] - one.loads[:k]).max() / one.loads.max()
    print(f"\nfill case, {MPI.COMM_WORLD.size} ranks vs 1: collapse {world.collapse_load:.9g} "
          f"vs {one.collapse_load:.9g} N; curve to the peak {dl:.1e}; "
          f"{world.status.status.value} / {one.status.status.value}")
    assert world.status.status is one.status.status
    assert abs(world.collapse_load / one.collapse_load - 1.0) < 1e-8
    assert int(np.argmax(world.loads)) + 1 == k and dl < 1e-8


def _toml(d: dict) -> str:
    lines = []
    for table, body in d.items():
        for key, val in body.items():
            if isinstance(val, dict):
                lines.append(f"[{table}.{key}]")
                lines += [f"{k} = {json.dumps(v)}" for k, v in val.items()]
        plain = {k: v for k, v in body.items() if not isinstance(v, dict)}
        if plain:
            lines.append(f"[{table}]")
            lines += [f"{k} = {json.dumps(v)}" for k, v in plain.items()]
    return "\n".join(lines) + "\n"


@pytest.mark.skipif(MPI.COMM_WORLD.size > 1, reason="one process (the suite's budget); "
                    "`make demo` runs the bridge demo under mpirun")
def test_bridge_demo_sweeps_positions_and_draws_the_stress(tmp_path, monkeypatch):
    comm = MPI.COMM_WORLD
    tmp_path = Path(comm.bcast(str(tmp_path), root=0))  # (each rank has its own tmp_path)
    path = tmp_path / "small_bridge.toml"
    if comm.rank == 0:
        path.write_text(_toml(SMALL), encoding="utf-8")
    comm.barrier()
    out = tmp_path / "out"
    monkeypatch.setattr(sys, "argv", ["bridge.py", "--case", str(path), "--out", str(out),
                                      "--positions", "0.25"])
    runpy.run_path(str(ROOT / "demos" / "bridge.py"), run_name="__main__")
    if comm.rank == 0:
        text = (out / "sweep.md").read_text()
        row = next(line for line in text.splitlines() if line.startswith("| 0.25 |"))
        # the LP with the fill as RING models it (passive resistance × 0.33: the
        # limit-analysis test above gives 49.09 kN)
        assert "peak passed" in row and "| 49.1 |" in row
        assert "Critical position: 0.25 of the span" in text
        # the LP's own critical position on its grid of positions, with and without the
        # passive resistance
        assert "Limit analysis with fill on a grid of 19 positions" in text
        assert text.count(" of the span (") == 3
        # with the loads leaning on the steep extrados: a column of its own
        assert "LP, loads leaning [kN]" in text and "with the loads leaning" in text
        assert (out / "sweep.png").is_file()
        assert (out / "vertical_stress_0.25.png").is_file()
        assert (out / "fill_0.25" / "report.md").is_file()


def test_limit_analysis_with_the_fill_as_loads():
    """The fill as loads on the rigid ring (its weight over each chord of the extrados, the
    axle dispersed 2:1): the loads add up (the fill's weight over the voussoirs, 1 N of
    live load), the ring carries more than bare, less than the FDEM bridge does with the
    fill's strength and passive resistance (test above: 67 kN at quarter span)."""
    case = load_case(small())
    arch = case.layout()
    road = case.road_level()
    rho = SMALL["materials"]["fill"]["density"]
    dead, live = fill_loads(arch, road=road, unit_weight=rho * 9.81, patch=(-0.5, 0.2))
    assert sum(f[1] for _, f in live) == pytest.approx(-1.0)
    # the weight of the fill over the ring's extrados, from its own envelope
    vs = np.vstack([p for p, n in zip(arch.polygons, arch.names) if n.startswith("vous")])
    xs = np.linspace(vs[:, 0].min(), vs[:, 0].max(), 40001)
    column = np.trapezoid(road - upper_envelope(arch, xs, "voussoir:"), xs)
    assert -sum(f[1] for _, f in dead) == pytest.approx(rho * 9.81 * column, rel=1e-4)
    # the 2:1 spread: live load only on chords within b/2 + depth/2 of the patch centre
    for (x, y), _ in live:
        assert abs(x + 0.5) <= 0.1 + 0.5 * (road - y) + 0.1
    la = case.limit_analysis(passive=False)
    bare = load_case({k: v for k, v in small().items() if k != "fill"}).limit_analysis()
    print(f"\nlimit analysis at quarter span: bare {bare.load_factor / 1e3:.2f} kN, fill as "
          f"loads {la.load_factor / 1e3:.2f} kN")
    assert la.status == "collapse" and bare.status == "collapse"
    assert 2.0 * bare.load_factor < la.load_factor < 67e3
    with pytest.raises(ValueError, match="width > 0"):
        fill_loads(arch, road=road, unit_weight=1.0, patch=(0.0, 0.0))


def test_fill_loads_lean_on_chords_steeper_than_the_interface_friction():
    """With the interface friction given, a chord of the extrados inclined at θ > δ takes
    its loads inclined by θ − δ from the vertical, uphill (towards the crown); flatter
    chords keep them vertical; the vertical parts are those of RING's model. On the 6 m
    bridge of the demo (δ = 2φ/3 = 23.3°, extrados up to 53° at the springing) the LP with
    leaning loads falls most near the springing (measured: at 0.1 of the span 229.6 against
    354.5 kN, at quarter span 243.2 against 251.1 kN)."""
    case = load_case(small())
    arch = case.layout()
    road = case.road_level()
    mu = case.fill.interface_friction
    kw = dict(road=road, unit_weight=1900.0 * 9.81, patch=(-0.7, 0.2))
    dead0, live0 = fill_loads(arch, **kw)
    dead, live = fill_loads(arch, interface_friction=mu, **kw)
    xs = extrados_vertices(arch)[:, 0]
    ys = upper_envelope(arch, xs, "voussoir:")
    leaning = 0
    for (p, f), (_, f0) in zip(dead + live, dead0 + live0, strict=True):
        assert f[1] == f0[1] and f0[0] == 0.0
        k = int(np.searchsorted(xs, p[0]))  # the chord xs[k-1]..xs[k] holds p
        theta = math.atan(abs(ys[k] - ys[k - 1]) / (xs[k] - xs[k - 1]))
        lean = max(0.0, theta - math.atan(mu))
        assert f[0] == pytest.approx(math.copysign(math.tan(lean), ys[k] - ys[k - 1])
                                     * -f[1], rel=1e-9, abs=1e-12)
        leaning += lean > 0
    assert leaning >= 4
    # the 6 m bridge: leaning loads near the springing cut the LP's load most
    six = load_case(ROOT / "cases" / "bridge_single_span.toml")
    loads = {}
    for pos in (0.1, 0.25):
        c = replace(six, loading=replace(six.loading, position=pos))
        loads[pos] = [c.limit_analysis(incline=b).load_factor for b in (False, True)]
    print(f"\n6 m bridge, LP with fill (vertical / leaning loads): "
          + ", ".join(f"{p:g}: {a / 1e3:.1f} / {b / 1e3:.1f} kN" for p, (a, b) in loads.items()))
    # near the springing, where the extrados is steeper than δ under the load, a cut of
    # more than a fifth; at quarter span (extrados at 21° < δ under the axle) under 10 %
    assert loads[0.1][1] < 0.8 * loads[0.1][0]
    assert 0.9 * loads[0.25][0] < loads[0.25][1] <= loads[0.25][0]


def test_limit_analysis_with_the_fills_passive_resistance():
    """RING's fill: the passive resistance on the extrados is Rankine's passive pressure
    times the mobilisation factor m, integrated over each chord's vertical extent; over a
    half ring from the springing (y0) to the crown (y1) it sums to
    m [K_p γ (road (y1 − y0) − (y1² − y0²) / 2) + 2 c √K_p (y1 − y0)] (pressure linear in
    depth: the trapezoidal rule is exact). With it the limit load rises, the more the
    larger m; m = 0 gives the LP without it."""
    case = load_case(small())
    arch, road = case.layout(), case.road_level()
    fm = SMALL["materials"]["fill"]
    gamma, c, phi = fm["density"] * 9.81, fm["c"], fm["phi"]
    kp = passive_coefficient(phi)
    assert kp == pytest.approx((1 + math.sin(math.radians(35))) / (1 - math.sin(math.radians(35))))
    assert kp == pytest.approx(3.690, abs=1e-3)
    m = 0.5
    forces = fill_passive(arch, road=road, unit_weight=gamma, phi=phi, cohesion=c, mobilisation=m)
    v = extrados_vertices(arch)
    y0, y1 = v[0, 1], v[:, 1].max()
    half = m * (kp * gamma * (road * (y1 - y0) - 0.5 * (y1**2 - y0**2))
                + 2 * c * math.sqrt(kp) * (y1 - y0))
    left = sum(f[2][1] for f in forces if f[1][0] > 0)
    right = sum(f[2][1] for f in forces if f[1][0] < 0)
    assert left == pytest.approx(half, rel=1e-9) and right == pytest.approx(half, rel=1e-9)
    # each acts on its chord, towards the span's middle, between its ends' heights
    for (x, y), (dx, dy), (lo, hi) in forces:
        assert dy == 0.0 and dx == -math.copysign(1.0, x) and lo == 0.0 and hi > 0.0
        assert y0 - 1e-12 <= y <= y1 + 1e-12
    none = case.limit_analysis(passive=False).load_factor
    loads = []
    for mob in (0.0, 0.33, 1.0):
        d = small(fill__passive_mobilisation=mob)
        loads.append(load_case(d).limit_analysis().load_factor)
    print("\nlimit analysis at quarter span, passive mobilisation 0 / 0.33 / 1: "
          + " / ".join(f"{x / 1e3:.2f}" for x in loads) + " kN")
    assert loads[0] == pytest.approx(none, rel=1e-9)
    assert loads[0] < loads[1] < loads[2]
    assert case.limit_analysis().load_factor == pytest.approx(loads[1], rel=1e-9)
    with pytest.raises(CaseError, match="passive_mobilisation"):
        load_case(small(fill__passive_mobilisation=1.5))
    with pytest.raises(ValueError, match="mobilisation"):
        fill_passive(arch, road=road, unit_weight=gamma, phi=phi, mobilisation=-0.1)


def test_backing_fills_the_haunches_up_to_its_level():
    """``backing`` h: the fill's bed below the level h above the springing becomes a block
    ``backing:<i>`` on each side, the fill lies on its top; fill and backing together take
    exactly the space of the fill without backing. The limit analysis takes it as a
    support: the higher the backing, the more the ring carries; the FDEM model fixes it
    with the abutments. A backing at the crown, or with disks, is refused by name."""
    arch = arch_layout(kind="segmental", span=2.0, rise=0.5, ring_thickness=0.15,
                       voussoirs=15, abutment_height=0.3, abutment_width=0.4)
    plain = fill_layout(arch, cover=0.2)
    fl = fill_layout(arch, cover=0.2, backing=0.2, backing_material="rubble")
    assert fl.names == ("fill", "wall:left", "wall:right", "backing:0", "backing:1")
    assert fl.materials[3:] == ("rubble", "rubble")
    total = sum(polygon_area(p) for p, n in zip(fl.polygons, fl.names, strict=True)
                if n[:4] in ("fill", "back"))
    assert total == pytest.approx(polygon_area(plain.polygons[0]), rel=1e-12)
    xmin, _, xmax, _ = arch.bounds
    for poly, side in zip(fl.polygons[3:], (xmin, xmax), strict=True):
        assert polygon_area(poly) > 0.0  # counter-clockwise
        # its top at the level (the springing at y = 0), but where it meets the extrados:
        # there on the chord the level crosses, at least a quarter of it from its ends (the
        # chords rise 0.1 m at most here), not at a joint of the ring
        top = poly[poly[:, 1] > 0.15]
        assert np.isclose(top[:, 1], 0.2, atol=1e-12).sum() >= 1
        assert np.abs(top[:, 1] - 0.2).max() < 0.25 * 0.1
        verts = np.vstack(arch.polygons)
        corner = top[np.argmin(np.abs(top[:, 0]))]
        assert np.min(np.linalg.norm(verts - corner, axis=1)) > 0.01
        assert np.isclose(poly[:, 0], side).any()  # from the end wall
    # the fill lies on the backing's top, none of it lower
    fill = fl.polygons[0]
    assert fill[:, 1].min() == pytest.approx(min(p[p[:, 1] > 0.15, 1].min()
                                                 for p in fl.polygons[3:]), abs=1e-12)
    for kw, expected in [(dict(backing=-0.1), "backing must be >= 0"),
                         (dict(backing=0.7), "reaches the crown")]:
        with pytest.raises(ValueError, match=expected):
            fill_layout(arch, cover=0.2, **kw)
    las = [load_case(small(fill__backing=b)).limit_analysis() for b in (0.0, 0.15)]
    loads = [la.load_factor for la in las]
    print("\nLP at quarter span, backing 0 / 0.15 m: "
          + " / ".join(f"{x / 1e3:.2f}" for x in loads) + " kN")
    # held on its extrados by the backing, the first voussoir no longer swings out with
    # the far haunch: the mechanism needs a hinge higher up, and the ring carries more
    assert [la.status for la in las] == ["collapse", "collapse"]
    assert loads[1] > 1.2 * loads[0]
    # a level under the abutments' tops adds nothing (no block)
    assert "backing:0" not in load_case(small(fill__backing=0.05)).fill_layout().names
    case = load_case(small(fill__backing=0.2))
    model, _, _ = build_model(case, MPI.COMM_WORLD)
    assert {"backing:0", "backing:1"} <= set(model.blocks.block_names)
    assert "backing" in {p.name for p in model.prescriptions}
    with pytest.raises(CaseError, match="reaches the crown"):
        load_case(small(fill__backing=0.7))
    with pytest.raises(CaseError, match="fill.backing: not with a disk fill"):
        load_case(small(fill__backing=0.2, fill__model="disks"))
