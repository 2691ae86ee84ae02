# # A masonry chimney felled by a notch cut at its base (the reference paper's Figure 2a)
#
# This demo illustrates how to:
#
# - build a tall masonry structure of courses of units that can crack (each unit two
#   triangles rejoined by a cohesive crack law) bonded by mortar joints that crack too (the
#   Lourenço–Rots interface law), standing on a rigid ground;
# - bring it to rest under its own weight, then cut a notch at its base at t = 0 by
#   carrying that state over to a model without the notch's units;
# - follow its fall by explicit dynamics with frictional contact and restitution between
#   the pieces and with the ground, and gravity, until it lies broken on the ground;
# - report the fall direction (the angle of the chimney's axis, from the hinge to where
#   the top lands, measured from the notch direction: 0° is a fall flat towards the
#   notch), the time the top takes to reach the ground, the spread of the debris and the
#   energy account; draw the fall (`chimney_fall.png`, a panel a second, and a picture
#   of the stresses and cracks at each of those times) and write a ParaView series.
#
# Run with `python demos/chimney.py` or `mpirun -n 2 python demos/chimney.py --out DIR`.
#
# ## The model and why
#
# The chimney is a tapered brick tube 30 m tall, 2.8 m outer diameter at its base and 1.8 m
# at its top, with walls 0.4 m thick (an ordinary industrial brick chimney of that height).
# It is modelled by a *solid* 2D section through its axis, of the full outer width, in
# plane stress, with an out-of-plane thickness that gives the section the tube's weight:
# w = π t (D_m − t) / D_m at the mean diameter D_m (1.04 m); along the height the section's
# weight per metre is then within 7 % of the tube's, its bending stiffness and section
# modulus within about 25 %. Why a solid section and not two walls: a notch demolition
# works because the tube acts as one beam. The notch takes about two thirds of the
# circumference on one side; the third left (the hinge) takes the whole weight behind the
# centre of gravity, and the tube turns about it, as one body, towards the notch. A section
# through two walls loses the ring that ties them (it is out of the plane): the wall under
# the notch would drop, the other would stand, and nothing would turn. (The hinge of a
# tube, an arc behind the axis, is a band behind the centre in the section.)
#
# The masonry is lumped into units one course (1 m, about thirteen brick courses) tall,
# three or four to a course in running bond. Each unit is two triangles (the diagonals
# alternate from unit to unit) rejoined by the crack law of brickwork, so units crack
# through; the head joints between units cross bonded brickwork and get the same law;
# the bed joints (horizontal) are lime-mortar joints, the weaker planes along which a
# falling chimney breaks. A joint or crack that has softened and opened, has slid by half
# its length, or whose two faces have turned against each other by more than 30°, goes
# to the frictional contact. The brickwork (E = 3 GPa) carries the flexibility of the
# mortar, so the interfaces are stiff penalties (4 E/h, h the facet length): with them
# the settled chimney shortens by about 1.3 times what a solid column of E would.
#
# The notch is the second course (1–2 m above the ground) cut over two thirds of the
# width on the +x side: the hinge left is the third of the section on the −x side. The
# chimney is first brought to rest under its own weight, intact (Newton: it is elastic and
# bonded throughout); at t = 0 the notch's units vanish (as at the blast of the charges in
# a pre-cut notch) and the rest starts from that stressed state at rest. It stands on a
# rigid ground (a fixed block, 105 m long) to which its lowest course is bonded by mortar.
#
# Contact: facet-to-facet penalty contact between all pieces and with the ground
# (penalty 0.5 E/h), friction 0.6, restitution e = 0.2 (falling masonry hardly bounces;
# the damper this takes is below critical, ζ = 0.73, and leaves the time step large). No
# mass damping: friction, the contact dampers and the fracture of joints and units
# dissipate the energy. The time step, 0.9 of the critical one, is about 5e-5 s, set by
# the interface penalties and the contact dampers.

# +
import argparse
import logging
import math
import time
from dataclasses import dataclass
from pathlib import Path

from mpi4py import MPI

import numpy as np

from masonry_fdem import Material, Model
from masonry_fdem.geometry import mesh_blocks
from masonry_fdem.interactions import BlockContact, ContactSettings, JointMaterial, Joints
from masonry_fdem.io import History, ProgressBar, VTXOutput, plot_blocks
from masonry_fdem.solvers import ExplicitSolver, StaticSolver

# -

# ## Materials (SI)
#
# Brickwork as a continuum: old clay brick in lime mortar, E = 3 GPa, ν = 0.2, 1800 kg/m³.
# Cracks through brickwork (units, head joints): f_t = 0.4 MPa, G_fI = 30 N/m,
# c = 0.6 MPa, tan φ = 0.8, G_fII = 300 N/m. Lime-mortar bed joints: f_t = 0.1 MPa,
# G_fI = 10 N/m, c = 0.15 MPa, tan φ = 0.7, G_fII = 50 N/m. Penalty stiffness of both:
# 4 E/h [Pa/m], h the facet length.

BRICKWORK = Material(density=1800.0, E=3e9, nu=0.2)
GROUND = Material(density=2400.0, E=30e9, nu=0.2)
CRACK = JointMaterial(ft=0.4e6, GfI=30.0, c=0.6e6, tan_phi=0.8, GfII=300.0, penalty=4.0)
MORTAR = JointMaterial(ft=0.1e6, GfI=10.0, c=0.15e6, tan_phi=0.7, GfII=50.0, penalty=4.0)


@dataclass(frozen=True)
class Chimney:
    """A tapered chimney as a solid section through its axis (all lengths in m).

    Attributes:
        height: height above the ground.
        d_base, d_top: outer diameter at the base and at the top.
        wall: wall thickness of the tube (sets the equivalent out-of-plane thickness).
        course: height of a course of units.
        notch_course: index of the course cut by the notch (0 is the lowest).
        notch_depth: fraction of the width the notch takes, from the notch side.
        side: +1 for a notch on the +x side, -1 on the -x side.
        ground: x extent of the rigid ground.
        ground_mesh: triangle size of the ground's mesh (its facets are contact facets).
    """

    height: float = 30.0
    d_base: float = 2.8
    d_top: float = 1.8
    wall: float = 0.4
    course: float = 1.0
    notch_course: int = 1
    notch_depth: float = 2.0 / 3.0
    side: int = 1
    ground: tuple[float, float] = (-15.0, 90.0)
    ground_mesh: float = 1.5

    @property
    def courses(self) -> int:
        return int(round(self.height / self.course))

    def half_width(self, y: float) -> float:
        return 0.5 * (self.d_base + (self.d_top - self.d_base) * y / self.height)

    @property
    def thickness(self) -> float:
        """Out-of-plane thickness [m] that gives the section the tube's weight per metre
        (at the mean diameter)."""
        dm = 0.5 * (self.d_base + self.d_top)
        return math.pi * self.wall * (dm - self.wall) / dm

    @property
    def hinge_edge(self) -> float:
        """x [m] of the notch's inner face (at the notch course's mid-height)."""
        c = self.notch_course
        a = self.half_width((c + 0.5) * self.course)
        return self.side * (a - 2.0 * a * self.notch_depth)

    def layout(self):
        """The units: polygons, names and whether each lies in the notch.

        Course c has three units (head joints at 1/3 and 2/3 of its mid-height width) when
        c is even, four (halves at the ends, head joints at 1/6, 1/2, 5/6) when odd:
        running bond. In the notch course, a unit that the notch's inner face crosses is
        cut there into two parts of one unit (``<unit>#keep``, ``<unit>#notch``), bonded
        by the brickwork's crack law until the notch is cut."""
        polys, names, notch = [], [], []
        xn = self.hinge_edge
        for c in range(self.courses):
            y0, y1 = c * self.course, min((c + 1) * self.course, self.height)
            a0, a1 = self.half_width(y0), self.half_width(y1)
            am = self.half_width(0.5 * (y0 + y1))
            fr = [1 / 3, 2 / 3] if c % 2 == 0 else [1 / 6, 1 / 2, 5 / 6]
            # (x of the piece's left face or None for the outer face, unit index)
            faces = [(None, 0)] + [((f - 0.5) * 2.0 * am, k + 1) for k, f in enumerate(fr)]
            split = c == self.notch_course and all(abs(x - xn) > 1e-9 for x, _ in faces[1:])
            if split:
                k = max(u for x, u in faces if x is None or x < xn)
                faces = sorted(faces + [(xn, k)], key=lambda f: -np.inf if f[0] is None
                               else f[0])
            faces.append((None, None))
            for (xl, k), (xr, _) in zip(faces[:-1], faces[1:], strict=True):
                p = [[-a0 if xl is None else xl, y0], [a0 if xr is None else xr, y0],
                     [a1 if xr is None else xr, y1], [-a1 if xl is None else xl, y1]]
                mid = 0.25 * sum(q[0] for q in p)
                cut = c == self.notch_course and self.side * (mid - xn) > 0
                name = f"unit:{c}:{k}"
                if split and sum(1 for _, u in faces if u == k) == 2:
                    name += "#notch" if cut else "#keep"
                polys.append(np.array(p, dtype=float))
                names.append(name)
                notch.append(cut)
        return polys, names, notch


# ## Building the models
#
# Both models come from one block mesh: the intact chimney (to settle) and the notched one
# (its subset without the notch's pieces). A subset keeps each block's nodes in order, so
# the settled displacement carries over node by node.


def build(ch: Chimney, comm=MPI.COMM_WORLD, *, restitution=0.2, friction=0.6,
          penalty_factor=2.0):
    """The intact and the notched chimney on the ground (collective).

    The contact penalty is 2 E/h (``penalty_factor``): at 0.5 E/h the pieces of the
    lower shaft, crushed under the falling chimney, sank up to 80 mm into each other
    (120 MPa of contact pressure), and a corner that deep, crossing the end of its contact
    zone by a millimetre a step, moved a kilojoule in and out of the contact in single
    steps: the explicit step does not resolve that, and the energy account was left with
    1.4 % of the work done. At 2 E/h the account closes to 0.4 % (the stable step is
    1.5 times shorter).

    Returns a dict: ``intact`` (model, joints) to settle, ``model``, ``contact`` and
    ``joints`` of the notched chimney, ``blocks`` (its BlockMesh), ``node_map`` (the
    intact BlockMesh node of each notched one) and ``top`` (block ids of the top course's
    pieces); the top's middle is monitored as "top"."""
    polys, names, notch = ch.layout()
    x0, x1 = ch.ground
    ground = np.array([[x0, -1.0], [x1, -1.0], [x1, 0.0], [x0, 0.0]])
    # every unit cut along a diagonal into two triangles, the pieces of one unit
    pieces, piece_names = [], []
    for i, (p, n) in enumerate(zip(polys, names, strict=True)):
        tri = ((0, 1, 2), (0, 2, 3)) if i % 2 == 0 else ((0, 1, 3), (1, 2, 3))
        for j, t in enumerate(tri):
            pieces.append(p[list(t)])
            piece_names.append(f"{n}#{j}")
    blocks = mesh_blocks([ground, *pieces], materials=["ground"] + ["brickwork"] * len(pieces),
                         names=["ground", *piece_names],
                         mesh_size=[ch.ground_mesh] + [1e3] * len(pieces), comm=comm)
    cut = {n for n, z in zip(names, notch, strict=True) if z}
    keep = np.array([b for b, n in enumerate(blocks.block_names) if _layout_name(n) not in cut],
                    dtype=np.int64)
    notched = blocks.subset(keep)
    off = blocks.node_offsets
    node_map = np.concatenate([np.arange(off[b], off[b + 1]) for b in keep])
    materials = {"ground": GROUND, "brickwork": BRICKWORK}
    laws = {("brickwork", "brickwork"): MORTAR, ("brickwork", "ground"): MORTAR}

    # head joints (vertical) cross bonded brickwork: the crack law; bed joints (at
    # multiples of the course height) are the mortar joints
    def head_joint(mid):
        k = mid[1] / ch.course
        return abs(k - round(k)) > 1e-6

    rules = [(head_joint, CRACK)]
    intact = Model(blocks, materials, width=ch.thickness, comm=comm)
    intact.fix_blocks("ground")
    intact.add_gravity()
    out = {"intact": (intact, Joints(intact, laws, cracks={"brickwork": CRACK}, where=rules)),
           "blocks": notched, "node_map": node_map}
    model = Model(notched, materials, width=ch.thickness, comm=comm)
    model.fix_blocks("ground")
    model.add_gravity()
    contact = BlockContact(model, ContactSettings(friction=friction, restitution=restitution,
                                                  penalty_factor=penalty_factor,
                                                  margin=0.1, rebuild_every=200))
    joints = Joints(model, laws, cracks={"brickwork": CRACK}, where=rules, contact=contact)
    out["top"] = notched.select(f"unit:{ch.courses - 1}:*")
    model.monitor("top", (0.0, ch.height), blocks=out["top"])
    out.update(model=model, contact=contact, joints=joints)
    return out


def _layout_name(name: str) -> str:
    """The layout unit a piece comes from ("unit:1:1#keep#0" -> "unit:1:1#keep")."""
    return name.rsplit("#", 1)[0] if "#" in name else name


def settle(parts):
    """Bring the intact chimney to rest under its own weight (Newton: it is elastic and
    bonded throughout) and start the notched one from that state, at rest (collective).
    Returns the static run's status."""
    intact, joints = parts["intact"]
    status = StaticSolver(intact, interactions=joints).settle(steps=1)
    if status.status.name != "LOAD_REACHED":
        raise RuntimeError(f"the intact chimney found no equilibrium: {status.describe()}")
    U = intact.displacement()  # on every rank, in the intact BlockMesh's node order
    model = parts["model"]
    n = model.n_nodes
    model.u.x.array[: 2 * n] = U[parts["node_map"][model.node_input]].ravel()
    model.u.x.scatter_forward()
    model.v[:] = 0.0
    return status


# ## Watching the fall


def top_state(model) -> tuple[np.ndarray, np.ndarray]:
    """Position [m] and velocity [m/s] of the middle of the top face (the monitored node),
    the same on every rank (collective)."""
    owner, node = model.monitors["top"]
    val = None
    if model.comm.rank == owner:
        val = (model.X[node] + model.u.x.array[2 * node:2 * node + 2],
               model.v[2 * node:2 * node + 2].copy())
    return model.comm.bcast(val, root=owner)


def lowest(model, blocks) -> float:
    """Lowest point [m] of the given blocks (collective)."""
    nodes = np.flatnonzero(np.isin(model.node_block, blocks))
    y = model.X[nodes, 1] + model.u.x.array[2 * nodes + 1]
    return model.comm.allreduce(float(y.min()) if y.size else np.inf, op=MPI.MIN)


def chimney_mass(parts) -> float:
    """Mass of the notched chimney [kg] (collective)."""
    model = parts["model"]
    own = ~np.isin(model.node_block, parts["blocks"].select("ground"))
    return model.comm.allreduce(float(model.mass[0:2 * model.n_nodes:2][own].sum()))


def debris_extent(parts, share=0.95) -> tuple[float, float, float, float, float]:
    """Where the chimney's pieces lie (collective): smallest and largest x [m] of all
    their nodes, the x range [m] that holds the middle ``share`` of the chimney's mass
    (by the nodes' lumped masses) and the highest point [m]."""
    model = parts["model"]
    nodes = np.flatnonzero(~np.isin(model.node_block, parts["blocks"].select("ground")))
    x = model.X[nodes] + model.u.x.array[:2 * model.n_nodes].reshape(-1, 2)[nodes]
    parts_ = model.comm.allgather((x, model.mass[2 * nodes]))
    x = np.concatenate([p[0] for p in parts_])
    m = np.concatenate([p[1] for p in parts_])
    order = np.argsort(x[:, 0], kind="stable")
    cum = np.cumsum(m[order]) / m.sum()
    tail = 0.5 * (1.0 - share)
    lo = x[order[np.searchsorted(cum, tail)], 0]
    hi = x[order[min(np.searchsorted(cum, 1.0 - tail), cum.size - 1)], 0]
    return float(x[:, 0].min()), float(x[:, 0].max()), float(lo), float(hi), float(x[:, 1].max())


def broken(parts) -> tuple[int, int]:
    """Mortar-joint and brickwork-crack segments broken through (handed to the contact)."""
    j = parts["joints"]
    unit = j.model.blocks.block_unit
    head = np.array([abs(m[1] / parts["course"] - round(m[1] / parts["course"])) > 1e-6
                     for m in j.seg_mid], dtype=bool)
    crack = (unit[j.seg_blocks[:, 0]] == unit[j.seg_blocks[:, 1]]) | head
    return int(np.sum(j.released & ~crack)), int(np.sum(j.released & crack))


def fall_angle(pos: np.ndarray, hinge: tuple[float, float], side: int) -> float:
    """The fall direction [deg]: the angle of the chimney's axis, the line from the hinge
    (``hinge``, the notch's inner corner at its floor [m]) to the top's position ``pos``
    [m], measured from the notch direction (the horizontal towards the notch side, +x
    when ``side`` = +1), positive upwards: 0 is a fall flat towards the notch, 90 upright,
    180 a fall flat away from it (a top landing below the hinge's height gives a few
    degrees below 0)."""
    return math.degrees(math.atan2(pos[1] - hinge[1], side * (pos[0] - hinge[0])))


def fall_figure(model, frames, path, xlim, height, most=8):
    """The fall in one picture (rank 0 draws): ``frames`` are (time [s], node positions
    (n_nodes, 2) [m], label), at most ``most`` of them drawn (evenly picked, the first and
    the last kept), one panel each in two columns: the pieces' outlines over the ground,
    axes equal in metres, each panel labelled with its time in seconds."""
    if model.comm.rank != 0 or not frames:
        return None
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection, PolyCollection

    if len(frames) > most:
        frames = [frames[k] for k in np.unique(np.linspace(0, len(frames) - 1, most)
                                               .round().astype(int))]
    blocks = model.blocks
    cells = blocks.cells
    is_ground = np.isin(blocks.cell_block, blocks.select("ground"))
    ytop = 1.05 * height
    ncol = 2 if len(frames) > 1 else 1
    nrow = -(-len(frames) // ncol)
    w = 6.0
    h = w * (ytop + 1.5) / (xlim[1] - xlim[0])
    fig, axes = plt.subplots(nrow, ncol, figsize=(ncol * w + 0.6, nrow * h + 0.9),
                             sharex=True, sharey=True, squeeze=False)
    for ax in axes.ravel()[len(frames):]:
        ax.set_visible(False)
    for ax, (t, xy, label) in zip(axes.ravel(), frames, strict=False):
        tri = xy[cells]
        ax.add_collection(PolyCollection(tri[is_ground], facecolors="0.8", edgecolors="none"))
        ax.add_collection(PolyCollection(tri[~is_ground], facecolors="indianred",
                                         edgecolors="none"))
        ax.add_collection(LineCollection(xy[blocks.boundary_facets], colors="0.15",
                                         linewidths=0.3))
        ax.set_xlim(*xlim)
        ax.set_ylim(-1.5, ytop)
        ax.set_aspect("equal")
        ax.set_title(f"t = {t:.2f} s{label}", fontsize=9)
    for ax in axes[:, 0]:
        ax.set_ylabel("y [m]")
    for ax in axes[-1, :]:
        ax.set_xlabel("x [m] (notch on the +x side)")
    fig.suptitle("chimney felled by a notch: the fall (grey: the ground)")
    fig.tight_layout()
    fig.savefig(path, dpi=150)
    plt.close(fig)
    return path


def energy_row(e) -> dict[str, float]:
    """The energy account as history columns [J]."""
    row = {"kinetic": e.kinetic}
    row.update({f"stored_{k}".replace(" ", "_"): v for k, v in e.stored.items()})
    row.update({f"dissipated_{k}".replace(" ", "_"): v for k, v in e.dissipated.items()})
    row.update({"gravity_work": e.external, "residual": e.residual})
    return row


def main(argv=None):
    parser = argparse.ArgumentParser(description="a masonry chimney felled by a notch")
    parser.add_argument("--height", type=float, default=30.0, help="[m]")
    parser.add_argument("--d-base", type=float, default=2.8, help="outer diameter [m]")
    parser.add_argument("--d-top", type=float, default=1.8, help="outer diameter [m]")
    parser.add_argument("--wall", type=float, default=0.4, help="wall thickness [m]")
    parser.add_argument("--course", type=float, default=1.0, help="course height [m]")
    parser.add_argument("--ground", type=float, nargs=2, default=(-15.0, 90.0),
                        help="x extent of the ground [m]")
    parser.add_argument("--time", type=float, default=12.0, help="longest run [s]")
    parser.add_argument("--after", type=float, default=1.5,
                        help="time simulated after the top reaches the ground [s]")
    parser.add_argument("--steps", type=int, default=None,
                        help="run exactly this many steps instead (rank comparison)")
    parser.add_argument("--record", type=float, default=0.005, help="history interval [s]")
    parser.add_argument("--record-steps", type=int, default=None,
                        help="history interval in steps (overrides --record)")
    parser.add_argument("--snap", type=float, default=1.0, help="picture interval [s]")
    parser.add_argument("--vtx", type=float, default=0.05,
                        help="ParaView interval [s] (0: none)")
    parser.add_argument("--out", type=Path, default=Path("out_chimney"))
    args = parser.parse_args(argv)
    comm = MPI.COMM_WORLD
    logging.basicConfig(level=logging.INFO if comm.rank == 0 else logging.WARNING,
                        format="%(message)s")
    t_wall = time.perf_counter()
    ch = Chimney(height=args.height, d_base=args.d_base, d_top=args.d_top, wall=args.wall,
                 course=args.course, ground=tuple(args.ground))
    parts = build(ch, comm)
    parts["course"] = ch.course
    model, contact, joints = parts["model"], parts["contact"], parts["joints"]
    status = settle(parts)
    settled, _ = top_state(model)
    solver = ExplicitSolver(model, interactions=[contact, joints])
    out = args.out
    mass = chimney_mass(parts)
    if comm.rank == 0:
        out.mkdir(parents=True, exist_ok=True)
        units = {n.split("#")[0] for n in parts["blocks"].block_names} - {"ground"}
        print(f"chimney {ch.height:g} m tall, {ch.d_base:g} -> {ch.d_top:g} m wide, "
              f"{ch.courses} courses, {len(units)} units in {parts['blocks'].n_blocks - 1} "
              f"pieces; section {ch.thickness:.3f} m thick, {mass / 1e3:.1f} t; "
              f"{comm.size} rank(s)")
        print(f"settled intact under its weight by Newton ({status.detail}): top moved "
              f"({settled[0] * 1e3:+.2f}, {(settled[1] - ch.height) * 1e3:+.2f}) mm; "
              f"notch cut at t = 0: course {ch.notch_course} "
              f"({ch.notch_course * ch.course:g}-{(ch.notch_course + 1) * ch.course:g} m), "
              f"{ch.notch_depth:.0%} of the width from the {'+x' if ch.side > 0 else '-x'} "
              f"side, inner face at x = {ch.hinge_edge:+.2f} m")
        print(f"explicit: dt = {solver.dt:.3e} s; {solver.stability['blocks']}")
    every = (args.record_steps if args.record_steps
             else max(1, int(round(args.record / solver.dt))))
    history = History(out / "history.csv", comm)
    vtx = VTXOutput(model, out, joints=joints) if args.vtx > 0 else None
    bar = ProgressBar("chimney", comm=comm)
    state = {"landed": None, "next_snap": 0.0, "next_vtx": 0.0, "pngs": [], "frames": []}

    def snapshot(s, label=""):
        name = out / f"chimney_{len(state['pngs']):02d}_t{s.t:05.2f}.png"
        plot_blocks(model, name, field="von_mises", joints=joints, clim=(0.0, 3e6),
                    title=f"chimney at t = {s.t:.2f} s{label}")
        state["pngs"].append(name.name)
        state["frames"].append((s.t, model.blocks.x + model.displacement(), label))

    def record(s):
        pos, vel = top_state(model)
        low = lowest(model, parts["top"])
        history.append({"time": s.t, "top_x": pos[0], "top_y": pos[1], "top_vx": vel[0],
                        "top_vy": vel[1], "top_lowest": low, **energy_row(s.energies())})
        if vtx is not None and s.t >= state["next_vtx"] - 0.5 * s.dt:
            vtx.write(s.t)
            state["next_vtx"] += args.vtx
        if state["landed"] is None and low <= 0.01:
            state["landed"] = (s.t, pos.copy(), vel.copy())
            snapshot(s, ": the top reaches the ground")
        elif s.t >= state["next_snap"] - 0.5 * s.dt:
            snapshot(s)
        while state["next_snap"] <= s.t + 0.5 * s.dt:
            state["next_snap"] += args.snap
        bar.update(s.n / args.steps if args.steps else s.t / args.time,
                   f"top at ({pos[0]:+.1f}, {pos[1]:.1f}) m")

    def done(s):
        landed = state["landed"]
        return landed is not None and s.t >= landed[0] + args.after - 0.5 * s.dt

    record(solver)  # t = 0: the notch just cut
    if args.steps:
        solver.run(steps=args.steps, every=every, callback=record)
    else:
        solver.run(t_end=args.time, every=every, callback=record, until=done)
    bar.close()
    if not state["pngs"][-1].endswith(f"t{solver.t:05.2f}.png"):
        snapshot(solver, " (end)")
    if vtx is not None:
        vtx.write(solver.t)
        vtx.close()
    history.close()
    e = solver.energies()
    pos, vel = top_state(model)
    debris = debris_extent(parts)
    n_joints, n_cracks = broken(parts)
    # the panels show the debris and the chimney's length on the ground, within the ground
    xlim = (max(ch.ground[0], min(debris[0], -ch.d_base) - 2.0),
            min(ch.ground[1], max(debris[1], ch.height) + 2.0))
    fall_figure(model, state["frames"], out / "chimney_fall.png", xlim, ch.height)
    wall = time.perf_counter() - t_wall
    if comm.rank == 0:
        side = "+x" if ch.side > 0 else "-x"
        hinge = (ch.hinge_edge, ch.notch_course * ch.course)
        print(f"{solver.n} steps to t = {solver.t:.3f} s; wall time {wall:.1f} s on "
              f"{comm.size} rank(s)")
        if state["landed"] is not None:
            t, p, v = state["landed"]
            ang = fall_angle(p, hinge, ch.side)
            ok = abs(ang) <= 10.0
            print(f"top reaches the ground at t = {t:.3f} s, at ({p[0]:+.2f}, {p[1]:.2f}) m, "
                  f"{np.linalg.norm(v):.1f} m/s")
            print(f"fall direction: the axis from the hinge ({hinge[0]:+.2f}, {hinge[1]:.2f}) m "
                  f"to where the top lands is {ang:+.1f} deg from the notch direction ({side}, "
                  f"horizontal; 0 = flat towards the notch, 90 = upright); within 10 deg: "
                  f"{'yes' if ok else 'NO'}")
            status = f"status: the top reached the ground at t = {t:.3f} s"
        else:
            print(f"the top has not reached the ground by t = {solver.t:.3f} s (its axis "
                  f"{fall_angle(pos, hinge, ch.side):+.1f} deg from the notch direction)")
            status = f"status: the top had not reached the ground by t_end = {solver.t:.3f} s"
        print(f"top at the end: ({pos[0]:+.2f}, {pos[1]:.2f}) m, moving at "
              f"({vel[0]:+.2f}, {vel[1]:+.2f}) m/s")
        print(f"debris: pieces from x = {debris[0]:+.2f} to {debris[1]:+.2f} m (spread "
              f"{debris[1] - debris[0]:.2f} m), 95 % of the mass from {debris[2]:+.2f} to "
              f"{debris[3]:+.2f} m ({debris[3] - debris[2]:.2f} m), highest point "
              f"{debris[4]:.2f} m; {n_joints} mortar-joint and {n_cracks} brickwork-crack "
              "segments broken through")
        print(e.summary())
        print(f"energy residual {e.residual:.3e} J: {100 * e.relative_residual:.4f} % of the "
              f"work done ({e.scale:.4g} J)")
        files = ["history.csv", "chimney_fall.png", *state["pngs"]]
        if vtx is not None:
            files += ["displacement.bp", "stress.bp", "joints.bp"]
        print(f"outputs in {out.resolve()}: {', '.join(files)}")
        print(status)
    return {"solver": solver, "parts": parts, "landed": state["landed"], "debris": debris}


if __name__ == "__main__":
    main()
