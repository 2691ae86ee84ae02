"""A bridge of :class:`~masonry_fdem.geometry.bridge.Bridge` as an FDEM model, and a
vehicle driven onto it to collapse.

The masonry (voussoirs, piers, abutments, end walls) is deformable blocks in plane stress
with mortar joints between voussoirs and on the skewbacks; the fill, the surfacing and the
soil are Mohr–Coulomb (or elastic) continua in plane strain; every interface between the
fill (or surfacing, soil) and another body is friction-only and opens freely. The
vehicle's axles bear on the road through guided steel loading beams (one per axle,
``patch`` wide). Self-weight first (Newton, with the fill's interfaces held stuck while it
takes its weight, then released), then the axle loads in proportion, under arc-length
control of their mean vertical displacement, past the peak. Units: SI.
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

from mpi4py import MPI

import numpy as np

from masonry_fdem.assessment.specs import joint_or_contact
from masonry_fdem.constants import G
from masonry_fdem.geometry.bridge import Bridge, BridgeError
from masonry_fdem.geometry.layout import BlockLayout
from masonry_fdem.interactions.joints import JointMaterial
from masonry_fdem.materials.elastic import Material
from masonry_fdem.solvers.status import RunStatus, Status

__all__ = ["BridgeRun", "Vehicle", "bridge_model", "joint_share_of_width", "load_bridge",
           "part_materials", "share_of_width"]

#: Newton iterations from the state dynamic relaxation leaves when Newton could not settle
#: the dead loads itself
SETTLE_ITERATIONS = 100

#: the loading beam under each axle: steel, 0.05 m thick
BEAM = (0.05, Material(density=7850.0, E=210e9, nu=0.3))


@dataclass(frozen=True)
class Vehicle:
    """Axles of a vehicle: ``offsets`` [m] from its reference point (the first axle at
    0, the others behind it at negative offsets, or ahead), ``loads`` their relative
    weights (the collapse load is their sum), ``patch`` [m] the tyre contact length along
    the road of every axle."""

    offsets: tuple[float, ...] = (0.0,)
    loads: tuple[float, ...] = (1.0,)
    patch: float = 0.3

    def __post_init__(self) -> None:
        object.__setattr__(self, "offsets", tuple(float(x) for x in self.offsets))
        object.__setattr__(self, "loads", tuple(float(x) for x in self.loads))
        if not self.offsets or len(self.offsets) != len(self.loads):
            raise BridgeError(f"vehicle: one load per axle offset, got {len(self.offsets)} "
                              f"offsets and {len(self.loads)} loads")
        if not all(math.isfinite(w) and w > 0 for w in self.loads):
            raise BridgeError(f"vehicle: axle loads must be > 0, got {self.loads}")
        if not (math.isfinite(self.patch) and self.patch > 0):
            raise BridgeError(f"vehicle: patch must be > 0 m, got {self.patch}")
        xs = sorted(self.offsets)
        if any(b - a < self.patch for a, b in zip(xs[:-1], xs[1:], strict=True)):
            raise BridgeError(f"vehicle: axles {self.offsets} closer than the patch "
                              f"{self.patch} m overlap")

    def axles(self, x: float) -> list[tuple[float, float]]:
        """``(x, share)`` of each axle with the vehicle at ``x`` [m] (shares sum to 1)."""
        total = sum(self.loads)
        return [(x + o, w / total) for o, w in zip(self.offsets, self.loads, strict=True)]


def part_materials(bridge: Bridge, layout: BlockLayout,
                   materials: Mapping[str, Material]) -> tuple[BlockLayout, dict, dict]:
    """The model's material names by part: the joints between blocks are chosen by the
    pair of their materials, so the piers and abutments, the backing and the end walls
    each get a name of their own where their material is one an earlier part (the ring,
    the piers, the backing) has too: ``<material>:<part>`` (the same
    :class:`~masonry_fdem.materials.Material`). Without it a ring and piers of one stone
    had the piers' dry contact for the ring's mortar joints.

    Returns:
        ``(layout, materials, names)``: the layout relabelled, the materials with the new
        names added, and the model's material name per part of ``bridge.materials`` (with
        "backing").
    """
    m = dict(bridge.materials)
    m["backing"] = bridge.backing_material
    mats = dict(materials)
    new = dict(m)
    taken = [m["masonry"]]
    for part in ("pier", "backing", "wall"):
        if m[part] in taken:
            new[part] = f"{m[part]}:{part}"
            mats[new[part]] = mats[m[part]] if m[part] in mats else None
        taken.append(m[part])
    mats = {k: v for k, v in mats.items() if v is not None}

    def label(name: str, mat: str) -> str:
        part = "backing" if name.startswith("backing:") else Bridge.part_of(name)
        return new[part] if part in ("pier", "backing", "wall") and mat == m[part] else mat

    lay = BlockLayout(layout.polygons, tuple(
        label(n, mat) for n, mat in zip(layout.names, layout.materials, strict=True)),
        layout.names)
    return lay, mats, new


def _layout(bridge: Bridge, vehicle: Vehicle, x: float) -> tuple[BlockLayout, list]:
    half = 0.5 * vehicle.patch
    axles = vehicle.axles(x)
    for k, (xa, _) in enumerate(axles):
        bridge.check_on_deck(xa, half, f"axle {k} of the vehicle")
    road = bridge.road_level()
    lay = bridge.layout(road_points=[v for xa, _ in axles for v in (xa - half, xa + half)])
    t = BEAM[0]
    beams = [np.array([[xa - half, road], [xa + half, road], [xa + half, road + t],
                       [xa, road + t], [xa - half, road + t]]) for xa, _ in axles]
    names = tuple(f"beam:{k}" for k in range(len(axles)))
    return lay + BlockLayout(tuple(beams), ("beam",) * len(beams), names), axles


def bridge_model(
    bridge: Bridge,
    materials: Mapping[str, Material],
    mortar: JointMaterial,
    interface: JointMaterial,
    vehicle: Vehicle,
    x: float,
    *,
    mesh_size: float | Mapping[str, float] = 0.2,
    penalty_factor: float | None = None,
    crossed: bool = False,
    spandrel_joint: JointMaterial | None = None,
    comm: MPI.Comm = MPI.COMM_WORLD,
):
    """The FDEM model of ``bridge`` with ``vehicle`` at ``x`` (collective).

    Args:
        bridge: the geometry.
        materials: :class:`~masonry_fdem.materials.Material` per name of
            ``bridge.materials`` (fill and soil usually
            :class:`~masonry_fdem.materials.MohrCoulomb`).
        mortar: the joints between voussoirs and on the skewbacks.
        interface: the friction-only interface of the fill, surfacing and soil with every
            other body (needs explicit ``kn``, ``ks``).
        vehicle: its axles; ``x`` [m] where its reference point stands.
        mesh_size: element size [m], one value or per part name ("masonry", "pier",
            "fill", "surfacing", "soil", "wall").
        penalty_factor: contact penalty factor (default: the contact's own).
        crossed: mesh the fill, the surfacing and the soil with crossed triangles
            (quadrilaterals split by their diagonals: no locking in their isochoric
            plastic flow; :func:`~masonry_fdem.geometry.meshing.mesh_blocks`).
        spandrel_joint: the joints of the spandrel walls (between their blocks, and on the
            ring and the piers) as they are in the walls (default: ``mortar``); the model
            takes the walls' share of the width of it. It must have a compressive strength
            ``fc``: the walls' blocks are elastic, and the walls between the end walls would
            otherwise carry any thrust.

    Returns:
        ``(model, [contact, joints], axles)``: ``axles`` the ``(x, share)`` per axle.
        With spandrel walls, ``model.width_shares`` maps the fill's and the walls'
        material names to their shares of the width: the model's stresses in them (e.g.
        in ParaView) are averages over the whole width, their own are these divided by
        their share (:class:`BridgeRun` ``sigma_yy`` is).
    """
    from masonry_fdem.interactions import BlockContact, ContactSettings, Joints
    from masonry_fdem.model import Model

    m = dict(bridge.materials)
    mats = dict(materials)
    needed = {m["masonry"], m["pier"], m["wall"], m["fill"]}
    share = bridge.spandrel_share
    if share > 0:
        needed.add(bridge.spandrel_material)
    if bridge.surfacing > 0:
        needed.add(m["surfacing"])
    if bridge.soil_depth > 0:
        needed.add(m["soil"])
    if bridge.backing > 0:
        needed.add(bridge.backing_material)
    missing = sorted(needed - set(mats))
    if missing:
        raise BridgeError(f"no material given for {missing}")
    if interface.kn is None or interface.ks is None:
        raise BridgeError("the fill's interface needs explicit kn and ks")
    if share > 0 and (spandrel_joint or mortar).fc is None:
        raise BridgeError("the spandrel walls' joints need a compressive strength fc "
                          "(spandrel_joint, or the mortar): walls of elastic blocks between "
                          "the end walls would carry any thrust")
    mats["beam"] = BEAM[1]
    lay, axles = _layout(bridge, vehicle, x)
    # the piers, the backing and the end walls by names of their own (their joints)
    lay, mats, m = part_materials(bridge, lay, mats)
    walls = None  # the spandrel walls' material in the model, if any
    if share > 0:
        # the model is of the whole width: the fill between the walls and the walls each
        # take their share of it, as materials of their own
        inner, walls = f"{m['fill']}:between-spandrels", f"{bridge.spandrel_material}:spandrels"
        mats[inner] = share_of_width(mats[m["fill"]], 1.0 - share)
        mats[walls] = share_of_width(mats[bridge.spandrel_material], share)
        lay = BlockLayout(lay.polygons, tuple(
            inner if n == "fill" else walls if n.startswith("spandrel:") else mat
            for n, mat in zip(lay.names, lay.materials, strict=True)), lay.names)
        m["fill"], m["spandrel"] = inner, walls
    if isinstance(mesh_size, Mapping):
        def size(p: str) -> float:
            if p == "spandrel":  # the fill's outline: its mesh by default
                return float(mesh_size.get(p, mesh_size.get("fill", 0.2)))
            return float(mesh_size.get(p, 0.2))

        # each block's part by its name (parts may share a material)
        sizes = [size("beam" if n.startswith("beam:") else bridge.part_of(n) or "masonry")
                 for n in lay.names]
    else:
        sizes = [float(mesh_size)] * len(lay)
    sizes = [0.5 * BEAM[0] if n.startswith("beam:") else s
             for n, s in zip(lay.names, sizes, strict=True)]
    soils = [n for n in lay.names if n in ("fill", "surfacing", "soil")]
    mesh = lay.mesh(sizes, comm, crossed=soils if crossed else ())
    continua = {m["fill"], m["surfacing"], m["soil"]}
    hyp = {name: "plane_strain" for name in continua if name in lay.materials}
    model = Model(mesh, mats, hypotheses=hyp, width=bridge.width, comm=comm)
    #: the share of the width of each material that has one (the fill between spandrel
    #: walls and the walls; see :func:`share_of_width`)
    model.width_shares = {m["fill"]: 1.0 - share, m["spandrel"]: share} if share > 0 else {}
    model.fix_blocks("wall:*", name="walls")
    fix_soil(model, bridge)
    rigid = [n for n in bridge.foundations() if not bridge.on_soil(n)]
    if rigid:
        model.fix_blocks(rigid, name="foundations")
    for k in range(len(axles)):
        model.prescribe_velocity(f"beam:{k}", (0.0, None), name=f"beam guide {k}")
    model.add_gravity()
    friction = {}
    table: dict[tuple[str, str], JointMaterial | None] = {
        (m["masonry"], m["masonry"]): mortar, (m["masonry"], m["pier"]): mortar,
        # the end walls against the abutments: dry contact
        (m["pier"], m["pier"]): None, (m["pier"], m["wall"]): None}
    back = m["backing"]
    if bridge.backing > 0:
        # the backing on the ring as the ring on its skewbacks; on the piers, the
        # abutments and against the end walls dry
        table[tuple(sorted((m["masonry"], back)))] = mortar
        table[tuple(sorted((m["pier"], back)))] = None
        table[tuple(sorted((m["wall"], back)))] = None
    others = set(lay.materials)
    soft = [n for n in (m["fill"], m["surfacing"], m["soil"]) if n in others]
    for s in soft:
        for o in others:
            if o != s and not (s == m["fill"] and o == walls):
                table[tuple(sorted((s, o)))] = interface
    if walls is not None:
        # the spandrel walls on the ring and the piers, in their share of the mortar; dry
        # against the end walls (unless those are of the piers' material); the fill beside
        # them never touches them
        wall_mortar = joint_share_of_width(spandrel_joint or mortar, share)
        table[tuple(sorted((walls, m["wall"])))] = None
        table[(walls, walls)] = wall_mortar  # the head joints
        table[tuple(sorted((walls, m["masonry"])))] = wall_mortar
        table[tuple(sorted((walls, m["pier"])))] = wall_mortar
        if bridge.backing > 0:
            table[tuple(sorted((walls, back)))] = wall_mortar
    # the bonded interfaces: the piers and abutments on the soil, the surfacing on the fill
    bonds = {}
    if m["soil"] in others:
        bonds[m["soil"]] = [m["pier"]]
    if m["surfacing"] in others:
        bonds[m["fill"]] = [m["surfacing"]]
        # the loading beams bedded on the road; the road's ends on the end walls' tops
        # (and the road on the spandrel walls' tops)
        bonds[m["surfacing"]] = ["beam", m["wall"]] + ([walls] if walls else [])
    else:
        bonds[m["fill"]] = ["beam"]
        if walls:
            bonds[walls] = ["beam"]
    for weak, parts in bonds.items():
        jm = adhesive_interface(interface, mats[weak])
        for o in parts:
            table[tuple(sorted((weak, o)))] = jm
    # the ring's own joints slide at the contact's default friction (the mortar's)
    ring = {tuple(sorted((m["masonry"], o))) for o in (m["masonry"], m["pier"], back)}
    for pair, jm in table.items():
        if jm is not None and tuple(sorted(pair)) not in ring:
            friction[pair] = jm.tan_phi
    contact = BlockContact(model, ContactSettings(
        friction=mortar.tan_phi, friction_table=friction,
        apart=((m["fill"], walls),) if walls else (),
        **({} if penalty_factor is None else {"penalty_factor": penalty_factor})))

    joints = Joints(model, {k: joint_or_contact(v) for k, v in table.items()}, contact=contact)
    return model, [contact, joints], axles


#: material fields that scale with the share of the width (forces per unit of the model's
#: area: stiffnesses, densities, strengths, fracture energies, viscosities); the others
#: (angles, Poisson's ratio, lengths, ratios) do not
_SCALED = {"density", "E", "c", "hardening", "c_min", "ft", "Gf", "viscosity"}
_KEPT = {"nu", "phi", "psi", "d_max", "fit"}
_JOINT_SCALED = {"kn", "ks", "ft", "GfI", "c", "GfII", "psi_confinement", "fc", "Gfc"}


def share_of_width(material: Material, share: float) -> Material:
    """``material`` as a part of a plane model of width B that fills only ``share`` of it
    (0 < share <= 1): its stiffness, density, strengths (and the like) times ``share``,
    so its forces per unit of the model's area are those of the part; its angles and
    Poisson's ratio unchanged. A Mohr–Coulomb body keeps its yield surface exactly (the
    cohesion scales with the stresses)."""
    from dataclasses import fields, replace

    from masonry_fdem.checks import expert

    if not 0.0 < share <= 1.0:
        raise BridgeError(f"a share of the width must be in (0, 1], got {share}")
    change = {}
    for f in fields(material):
        if f.name in _SCALED:
            change[f.name] = getattr(material, f.name) * share
        elif f.name not in _KEPT:
            raise BridgeError(f"{type(material).__name__}.{f.name}: unknown how it scales "
                              "with a share of the width")
    with expert():  # derived from checked inputs: no magnitude check of its own
        return replace(material, **change)


def joint_share_of_width(joint: JointMaterial, share: float) -> JointMaterial:
    """A joint of a part that fills ``share`` of the model's width (see
    :func:`share_of_width`): stiffnesses, strengths and fracture energies times
    ``share``; friction, dilatancy and lengths unchanged."""
    from dataclasses import fields, replace

    from masonry_fdem.checks import expert

    change = {f.name: getattr(joint, f.name) * share for f in fields(joint)
              if f.name in _JOINT_SCALED and getattr(joint, f.name) is not None}
    with expert():
        return replace(joint, **change)


def fix_soil(model, bridge: Bridge) -> None:
    """The soil (if any) fixed at its base and on rollers at its sides ("soil base",
    "soil sides")."""
    if bridge.soil_depth <= 0:
        return
    lo, hi = bridge.soil_extent
    yd = bridge.foundation_level - bridge.soil_depth
    tol = 1e-6 * (hi - lo)
    model.fix(lambda X: np.isclose(X[1], yd, atol=tol), name="soil base")
    model.fix(lambda X: (np.isclose(X[0], lo, atol=tol) | np.isclose(X[0], hi, atol=tol))
              & (X[1] < bridge.foundation_level - tol), components=(0,), name="soil sides")


def adhesive_interface(interface: JointMaterial, weaker: Material) -> JointMaterial:
    """The interface of a foundation on the soil, or of the surfacing on the fill: the
    friction-only ``interface`` with an adhesion of the weaker body's cohesion c [Pa] (a
    tensile strength and a cohesion c, softening over 1 mm in tension and 10 mm in shear;
    c = 1 kPa for a cohesionless or elastic body). Besides being what a buried foundation
    or a laid road base has, it gives the interface a stiffness at zero stress, which
    Newton needs from the unloaded state: a body held only by friction-only interfaces has
    none there, as they sit at their kink between open and closed."""
    from dataclasses import replace

    from masonry_fdem.checks import expert

    c = float(getattr(weaker, "c", 0.0)) or 1e3
    with expert():  # derived from checked inputs: no magnitude check of its own
        return replace(interface, ft=c, GfI=c * 1e-3, c=c, GfII=c * 1e-2)


@dataclass
class BridgeRun:
    """Result of :func:`load_bridge`: ``status`` (peak passed, not converged, ...),
    ``loads`` [N] (the vehicle's total) against ``displacements`` [m] (the axles' mean
    settlement under the live load), ``peak`` [N], ``sigma_yy`` per cell [Pa] (gathered
    on rank 0, over the BlockMesh cells; in the fill between spandrel walls and in the
    walls their own, not the width's average), the displacement (local dofs) and the support
    reactions ``(R_x, R_y)`` [N] per prescription at the peak, ``seconds``."""

    status: RunStatus
    loads: list[float] = field(default_factory=list)
    displacements: list[float] = field(default_factory=list)
    sigma_yy: np.ndarray | None = None
    u_peak: np.ndarray | None = None
    reactions: dict = field(default_factory=dict)
    seconds: float = 0.0

    @property
    def peak(self) -> float:
        return float(max(self.loads, default=0.0))

    @property
    def collapsed(self) -> bool:
        return self.status.status is Status.PEAK_PASSED

    def line(self) -> str:
        """The outcome in words, with the load in kN and tonnes."""
        t = self.peak / (1000.0 * G)
        if self.collapsed:
            return f"peak passed — collapse load {self.peak / 1e3:.1f} kN ({t:.2f} t)"
        return (f"{self.status.status.value} — carried {self.peak / 1e3:.1f} kN ({t:.2f} t), a "
                f"lower bound of the collapse load ({self.status.detail})")


def load_bridge(
    model,
    interactions: list,
    axles: Sequence[tuple[float, float]],
    interface: JointMaterial,
    road: float,
    *,
    increment: float = 2e-4,
    max_displacement: float = 0.1,
    max_steps: int = 300,
    stop_drop: float = 0.2,
    grow: float = 1.5,
    rtol: float = 1e-6,
    callback=None,
    comm: MPI.Comm = MPI.COMM_WORLD,
) -> BridgeRun:
    """Self-weight, then the axle loads to collapse (collective).

    Args:
        model, interactions, axles: from :func:`bridge_model`.
        interface: the fill's interface (held stuck while the fill settles).
        road: y [m] of the road (the loads act on the beams' tops).
        increment: first arc-length increment of the axles' mean settlement [m].
        max_displacement: stop there [m] (status "displacement limit").
        max_steps: at most this many increments.
        stop_drop: stop once the load has fallen this fraction below its peak (the peak
            is then proven passed; see :meth:`StaticSolver.follow`).
        grow: an increment that converges easily lets the next grow this many times
            (1: a fixed increment, the same path whatever the iteration counts).
        rtol: Newton's tolerance on the forces.
        callback: ``callback(load, displacement)`` [N, m] after each converged increment
            of the live load, the model in that state (e.g. to write a ParaView frame).
    """
    from masonry_fdem.solvers.static import StaticSolver

    t0 = time.perf_counter()
    joints = interactions[1]
    solver = StaticSolver(model, interactions=interactions, rtol=rtol)

    def relax(why: str) -> RunStatus:
        """Dynamic relaxation to the current loads and friction, then Newton from its
        state: where Newton from the last equilibrium cycles (interfaces at their kink
        between open and closed, or between stick and slip), as the arch assessment
        does."""
        from masonry_fdem.solvers import DynamicRelaxation

        DynamicRelaxation(model, interactions=interactions, rtol=1e-6, ke_tol=math.inf,
                          max_iter=200_000, damping="velocity").solve(0.0)
        solver.dead_factor = 1.0
        solver.commit()
        # from the relaxed state (near equilibrium, not at it) Newton may need more than
        # its usual iterations: the two-span case at 4.5 m converged in 32
        r0 = solver.solve(0.0, max_it=SETTLE_ITERATIONS)
        if r0.converged:
            return RunStatus(Status.LOAD_REACHED, 0.0, 0.0, None,
                             f"{why}: dynamic relaxation, then Newton")
        return RunStatus(Status.NOT_CONVERGED, 0.0, 0.0, 0.0,
                         f"{why}: Newton did not converge, nor after dynamic relaxation "
                         f"({r0.reason})")

    mu = interface.tan_phi
    f = max(10.0, 4.0 * mu)
    joints.set_friction(interface, f)
    st = solver.settle()
    if st.status is not Status.LOAD_REACHED:
        # Newton from the unloaded state, where the bodies only touch, can cycle
        st = relax("the dead loads")
    while st.status is Status.LOAD_REACHED and f > mu:
        f = max(mu, 0.5 * f)
        joints.set_friction(interface, f)
        r = solver.solve_retrying(solver.load_factor)
        if r.converged:
            solver.commit()
        else:
            st = relax(f"the fill's interfaces released to tan δ = {f:.3g}")
    if st.status is not Status.LOAD_REACHED:
        return BridgeRun(replace_detail(st, "self-weight: " + st.detail),
                         seconds=time.perf_counter() - t0)
    solver.commit()
    for k, (x, share) in enumerate(axles):
        model.add_point_load((x, road + BEAM[0]), (0.0, -share), blocks=f"beam:{k}")
    nodes = [model.nearest_node((x, road + BEAM[0]), f"beam:{k}") for k, (x, _) in
             enumerate(axles)]
    shares = [s for _, s in axles]
    u0 = _mean_uy(model, nodes, shares, comm)
    run = BridgeRun(st)
    best = {"load": -math.inf}

    def on_point(p) -> None:
        run.loads.append(float(p.load))
        run.displacements.append(u0 - _mean_uy(model, nodes, shares, comm))
        if p.load > best["load"]:
            best["load"] = p.load
            model.update_stress()
            n = model.dmesh.cell_input.size
            syy = model.stress.x.array.reshape(-1, 4)[:n, 3].copy()
            parts = comm.gather((model.dmesh.cell_input, syy), root=0)
            if comm.rank == 0:
                cells = np.zeros(model.blocks.n_cells)
                for idx, vals in parts:
                    cells[idx] = vals
                run.sigma_yy = cells / cell_shares(model)
            run.u_peak = model.u.x.array.copy()
            run.reactions = {k: v.copy() for k, v in solver.reactions().items()}
        if callback is not None:
            callback(run.loads[-1], run.displacements[-1])

    res = solver.follow(increment, max_displacement=max_displacement, max_steps=max_steps,
                        peak_drop=min(0.05, stop_drop), stop_drop=stop_drop, grow=grow,
                        min_increment=increment / 1024.0, callback=on_point)
    run.status = res.status
    run.seconds = time.perf_counter() - t0
    return run


def cell_shares(model) -> np.ndarray:
    """Per cell of the BlockMesh, the share of the width its material takes (1 but in the
    fill between spandrel walls and in the walls)."""
    b = model.blocks
    shares = getattr(model, "width_shares", {})
    per = np.array([shares.get(n, 1.0) for n in b.material_names])
    return per[b.block_material[b.cell_block]]


def replace_detail(st: RunStatus, detail: str) -> RunStatus:
    from dataclasses import replace

    return replace(st, detail=detail)


def _mean_uy(model, nodes: Sequence[int], shares: Sequence[float], comm) -> float:
    """Share-weighted mean vertical displacement [m] of the nodes (-1: another rank's)."""
    u = model.u.x.array.reshape(-1, 2)
    local = sum(s * float(u[n, 1]) for n, s in zip(nodes, shares, strict=True) if n >= 0)
    return comm.allreduce(local, op=MPI.SUM)
