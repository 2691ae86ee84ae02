"""Spandrel walls of a plane bridge (:class:`~masonry_fdem.geometry.bridge.Bridge`
``spandrel_thickness``): blocks with the fill's outline, beside the fill out of the plane,
each part taking its share of the bridge's width (:func:`share_of_width`)."""

from __future__ import annotations

import dataclasses
import math

from mpi4py import MPI

import numpy as np
import pytest

from masonry_fdem.assessment.bridge import (
    Vehicle,
    bridge_model,
    joint_share_of_width,
    load_bridge,
    share_of_width,
)
from masonry_fdem.assessment.bridge_case import load_bridge_case
from masonry_fdem.assessment.specs import CaseError
from masonry_fdem.checks import expert
from masonry_fdem.geometry.bridge import Bridge, BridgeError, Span
from masonry_fdem.geometry.polygons import polygon_area
from masonry_fdem.interactions.joints import JointMaterial
from masonry_fdem.materials import MohrCoulomb
from masonry_fdem.materials.elastic import Material

SPAN = Span(2.0, 0.5, 0.15, 12)
MATS = {"masonry": Material(2000.0, 5e9, 0.2), "pier": Material(2200.0, 10e9, 0.2),
        "fill": MohrCoulomb(density=1900.0, E=30e6, nu=0.3, c=2e3, phi=35.0),
        "surfacing": MohrCoulomb(density=2300.0, E=1e9, nu=0.3, c=100e3, phi=35.0)}
MORTAR = JointMaterial(kn=5e10, ks=2e10, tan_phi=0.6)
with expert():
    # the walls' joints: the mortar with a compressive cap of 5 MPa
    WALL_JOINT = dataclasses.replace(MORTAR, fc=5e6)
ITF = JointMaterial(kn=6e9, ks=6e9 / 2.6, tan_phi=math.tan(math.radians(2 / 3 * 35.0)))
SIZES = {"masonry": 0.15, "pier": 0.15, "fill": 0.15, "surfacing": 0.05, "wall": 0.3}
ROOT = __import__("pathlib").Path(__file__).resolve().parents[1]


def one_span(t: float, **kw) -> Bridge:
    return Bridge(spans=(SPAN,), pier_height=0.5, abutment_width=0.4, cover=0.3,
                  surfacing=0.05, width=3.0, spandrel_thickness=t, **kw)


def test_spandrel_blocks_tile_the_fill():
    """The walls' blocks cover the fill's outline exactly, each within its length of the
    deck, from one end wall to the other."""
    b = one_span(0.3, spandrel_block=0.45)
    lay = b.layout()
    fill = lay.polygons[lay.names.index("fill")]
    pieces = [(n, p) for n, p in zip(lay.names, lay.polygons, strict=True)
              if n.startswith("spandrel:")]
    x0, x1 = b.deck()
    n = math.ceil((x1 - x0) / 0.45)
    assert [k for k, _ in pieces] == [f"spandrel:{k}" for k in range(n)]
    assert sum(polygon_area(p) for _, p in pieces) == pytest.approx(polygon_area(fill),
                                                                    rel=1e-12)
    cuts = np.linspace(x0, x1, n + 1)
    for k, (_, p) in enumerate(pieces):
        assert p[:, 0].min() == pytest.approx(cuts[k]) and p[:, 0].max() == pytest.approx(
            cuts[k + 1])
        assert polygon_area(p) > 0.0
    assert b.spandrel_share == pytest.approx(0.2)
    assert lay.materials[lay.names.index("spandrel:0")] == "pier"  # the piers' by default
    assert not any(n.startswith("spandrel") for n in one_span(0.0).layout().names)


@pytest.mark.parametrize("kw, expected", [
    (dict(spandrel_thickness=1.5), "two spandrel walls .* as wide as the bridge"),
    (dict(spandrel_thickness=-0.1), "spandrel_thickness"),
    (dict(spandrel_thickness=0.3, spandrel_block=0.0), "spandrel_block"),
])
def test_bad_spandrels_are_named(kw, expected):
    args = dict(spans=(SPAN,), cover=0.3, width=3.0)
    args.update(kw)
    with pytest.raises(BridgeError, match=expected):
        Bridge(**args)


def test_a_share_of_the_width_scales_forces_not_angles():
    """A part filling a share s of the width: stiffness, weight and strengths times s, its
    friction angle and Poisson's ratio kept, so a Mohr–Coulomb yield surface is the same
    in its own stresses; a joint's stiffnesses and strengths times s, its friction kept."""
    mc = share_of_width(MATS["fill"], 0.25)
    assert (mc.E, mc.density, mc.c) == pytest.approx((7.5e6, 475.0, 500.0))
    assert (mc.phi, mc.nu, mc.psi) == (35.0, 0.3, 0.0)
    j = joint_share_of_width(WALL_JOINT, 0.25)
    assert (j.kn, j.ks, j.fc, j.tan_phi) == pytest.approx((1.25e10, 5e9, 1.25e6, 0.6))
    with pytest.raises(BridgeError, match="share"):
        share_of_width(MATS["fill"], 0.0)


def _run(t: float, comm, x: float = 0.5, **kw):
    b = one_span(t)
    model, inter, axles = bridge_model(b, MATS, MORTAR, ITF, Vehicle(patch=0.2), x,
                                       mesh_size=SIZES, spandrel_joint=WALL_JOINT, comm=comm)
    args = dict(increment=1e-3, max_displacement=0.04, stop_drop=0.05, grow=1.0)
    args.update(kw)
    run = load_bridge(model, inter, axles, ITF, b.road_level(), comm=comm, **args)
    return b, model, inter, run


@pytest.mark.skipif(MPI.COMM_WORLD.size > 1, reason="one process (the suite's budget); "
                    "test_spandrel_walls_same_on_any_number_of_ranks runs them on two")
def test_spandrel_walls_carry_their_share_and_stiffen_the_bridge():
    """With spandrel walls (2 × 0.3 m of a 3 m wide bridge): the model's mass grows by the
    walls' share of the fill's outline times the difference of the two densities; at the
    peak the supports carry that weight and the load; the fill and the walls overlap in
    the plane and no contact pair joins them; the walls raise the collapse load."""
    b0, m0, _, r0 = _run(0.0, MPI.COMM_SELF)
    b, model, inter, run = _run(0.3, MPI.COMM_SELF)
    lay = b.layout()
    a_fill = polygon_area(lay.polygons[lay.names.index("fill")])
    s = b.spandrel_share
    dm = s * a_fill * b.width * (MATS["pier"].density - MATS["fill"].density)
    assert model.total_mass() - m0.total_mass() == pytest.approx(dm, rel=1e-9)
    ry = sum(r[1] for r in run.reactions.values())
    weight = model.total_mass() * 9.81
    print(f"\nspandrel walls: {run.line()}; without: {r0.line()}; reactions {ry / 1e3:.3f} "
          f"kN against weight + load {(weight + run.peak) / 1e3:.3f} kN")
    assert run.collapsed and r0.collapsed
    assert ry == pytest.approx(weight + run.peak, rel=5e-4)
    contact = inter[0]
    bm = model.blocks.block_material
    names = model.blocks.material_names
    fb = contact.g_block[contact.active_pairs()]
    touching = {tuple(sorted((names[bm[p]], names[bm[q]]))) for p, q in fb}
    assert not any("fill" in a.split(":")[0] and b_.endswith(":spandrels") or
                   "fill" in b_.split(":")[0] and a.endswith(":spandrels")
                   for a, b_ in touching), touching
    assert touching  # (the contact is live: joints handed over to it)
    assert run.peak > 2.0 * r0.peak


def test_spandrel_walls_same_on_any_number_of_ranks():
    """The first increments of the live load, small enough for Newton to converge at once
    on any number of ranks (at 1 mm the first increment is halved three times on one rank
    and once on two, a round-off apart, and the walls' crushing then follows two paths:
    the collapse loads differ by 6 %)."""
    if MPI.COMM_WORLD.size == 1:
        pytest.skip("compares ranks: run under mpirun -n 2")
    kw = dict(increment=1.25e-4, max_steps=6)
    *_, world = _run(0.3, MPI.COMM_WORLD, **kw)
    *_, one = _run(0.3, MPI.COMM_SELF, **kw)
    dl = np.abs(np.subtract(world.loads, one.loads)).max() / max(one.loads)
    print(f"\nspandrel walls, {MPI.COMM_WORLD.size} ranks vs 1: {len(world.loads)} increments,"
          f" to {max(one.loads) / 1e3:.1f} kN; curves apart by {dl:.1e} of it")
    assert len(world.loads) == len(one.loads) == 6
    assert dl < 1e-8


def test_spandrel_walls_in_a_case_file():
    import tomllib

    data = tomllib.loads((ROOT / "cases" / "bridge_two_span.toml").read_text())
    data["bridge"].update(width=5.0, spandrel_thickness=0.4, spandrel_block=0.6)
    data["bridge"]["materials"]["spandrel"] = "stone"
    data["joints"]["spandrel"] = dict(kn=1e11, ks=4e10, tan_phi=0.6, fc=5e6)
    c = load_bridge_case(data)
    assert c.bridge.spandrel_share == pytest.approx(0.16)
    assert c.spandrel_joint.fc == 5e6 and c.mesh["spandrel"] == c.mesh["fill"]
    bad = tomllib.loads((ROOT / "cases" / "bridge_two_span.toml").read_text())
    bad["joints"]["spandrel"] = dict(kn=1e11, ks=4e10, tan_phi=0.6)
    with pytest.raises(CaseError, match="joints.spandrel: given, but the bridge has no "
                                        "spandrel walls"):
        load_bridge_case(bad)
    bad = tomllib.loads((ROOT / "cases" / "bridge_two_span.toml").read_text())
    bad["bridge"].update(width=5.0, spandrel_thickness=0.4)
    with pytest.raises(CaseError, match="joints.spandrel: the spandrel walls' joints need a "
                                        "compressive strength fc"):
        load_bridge_case(bad)
    with pytest.raises(BridgeError, match="need a compressive strength fc"):
        bridge_model(one_span(0.3), MATS, MORTAR, ITF, Vehicle(patch=0.2), 0.5,
                     mesh_size=SIZES, comm=MPI.COMM_SELF)
    bad["bridge"].update(width=5.0, spandrel_thickness=3.0)
    with pytest.raises(CaseError, match="bridge: the two spandrel walls"):
        load_bridge_case(bad)
    disks = tomllib.loads((ROOT / "cases" / "bridge_two_span.toml").read_text())
    disks["bridge"].update(width=5.0, spandrel_thickness=0.4, fill_model="disks")
    disks["vehicle"]["load"] = 1e5
    with pytest.raises(CaseError, match="spandrel walls are modelled with a continuum fill "
                                        "only"):
        load_bridge_case(disks)
