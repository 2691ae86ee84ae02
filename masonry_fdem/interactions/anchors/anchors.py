"""Repairs: grouted steel anchors embedded in the masonry, with bond–slip and prestress.

An :class:`Anchor` is a polyline (usually straight) through the blocks with a steel bar of
diameter ``d`` in a grouted hole. :class:`Anchors` discretises every anchor into 1D bar
elements (truss elements, axial force only) whose nodes are located once, at set-up, in
a host triangle of the block mesh (reference barycentric coordinates of the containing
element). The bar nodes have their own degrees of freedom: they move with the bar, not
with the masonry, and the two are tied by

* **bond** along the bar: force ``count·π·d_b·L_i·τ(s)`` on node ``i`` with tributary
  length ``L_i``, where the slip ``s`` is the displacement of the bar node relative to its
  host material point, along the current bar tangent. ``τ(s)`` is a :class:`BondLaw`:
  a piecewise-linear envelope from a pull-out test (rising, then softening), with elastic
  unloading at the initial stiffness (plastic slip);
* a **transverse tie** across the bar: stiff and elastic by default (stiffness per metre of
  bar equal to the host block's Young's modulus, the modulus of a Winkler foundation of a
  bar in an elastic continuum), or a :class:`DowelLaw` (elastic–perfectly plastic);
* optional **end plates**, bearing (compression only) between a bar end and its block;
* optional **dowel action across joints** (``Anchor.shear``, a :class:`JointDowel`): where
  a bar element bridges two blocks, a shear spring between the two blocks' material points
  at the crossing, across the bar (Lorig 1985): the bars are trusses, so without it a bar
  resists a joint's opening but not its sliding.

The bar is elasto-plastic steel with linear hardening and rupture (:class:`SteelLaw`).
Anchors cross joints, cracks and ring interfaces: a bar element whose two nodes are hosted
by different blocks is what carries tension across an opening joint.

**Prestress.** An anchor with ``prestress = P > 0`` needs end plates at both ends. It starts
*jacking*: every bar element holds the force P whatever its length, the bond is inactive
(the bar slides in its duct) and the plates push the blocks together. After the structure
has come to equilibrium under the jacking force (one dynamic-relaxation solve, or a damped
explicit run), :meth:`Anchors.lock_off` locks the bar at its current length with force P and
grouts it: the bond acts from then on, its slip measured from the locked-off position.

**Out-of-plane.** In a plane model of width ``w`` an anchor stands for a row of ``count``
identical bars across the width; the forces on the blocks are ``count`` times a bar's.
Reported forces (:meth:`Anchors.axial_force`) are per bar.

**Parallel.** Every rank holds every anchor node (they are few). The rank owning a node's
host block computes its bond, dowel and plate forces; one ``Allreduce`` per step sums the
anchor-node forces; the bar forces and the anchor-node update are then computed
identically on every rank.

**Consistent tangent** (``add_tangent``, static Newton solver): per bond point and per bar
element, central differences of the item's own force kernel in its dofs, at the committed
history (a numerical algorithmic tangent, Miehe 1996; step and accuracy in
:mod:`._kernels`). Bond points are added by their host's rank, bar elements by rank 0.

Units: SI (m, N, Pa, kg).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from mpi4py import MPI

import numpy as np

from masonry_fdem.geometry.locate import locate_in_block, locate_points
from masonry_fdem.interactions.anchors import _kernels as AK
from masonry_fdem.interactions.anchors.laws import (Anchor, BondLaw, DowelLaw, JointDowel,
                                                     SteelLaw)
from masonry_fdem.interactions.protocol import BLOCKS, DofSet, Interaction, State, Tangent

__all__ = [
    "SteelLaw",
    "BondLaw",
    "DowelLaw",
    "JointDowel",
    "Anchor",
    "Anchors",
    "straight_anchor",
    "wall_ties",
]

# a spring of any direction adds at most this times its stiffness to a dof's row sum
_DIR = 0.5 * (1.0 + math.sqrt(2.0))
_PLATES = {"none": (0, 0), "start": (1, 0), "end": (0, 1), "both": (1, 1)}


def _boundary_crossings(blocks, p: np.ndarray, q: np.ndarray, seg: float) -> list[float]:
    """Parameters t in (0, 1) of the forced bar nodes of the segment p→q.

    Where the segment enters or leaves the masonry there is a node on the surface, so that
    every bar element is wholly inside or wholly outside. Where it crosses a joint or a
    crack (masonry on both sides) there is one bar element centred on the joint, so that
    its halves bond to the blocks on either side and the bar bridges the opening.
    Crossings closer than a fifth of a bar element to an earlier one or to an end are
    dropped.
    """
    f = blocks.boundary_facets
    a, b = blocks.x[f[:, 0]], blocks.x[f[:, 1]]
    r = q - p
    ell = float(np.linalg.norm(r))
    e = b - a
    den = r[0] * e[:, 1] - r[1] * e[:, 0]
    ok = np.abs(den) > 1e-12 * ell * np.linalg.norm(e, axis=1)
    w = a - p
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (w[:, 0] * e[:, 1] - w[:, 1] * e[:, 0]) / den
        v = (w[:, 0] * r[1] - w[:, 1] * r[0]) / den
    hit = ok & (t > 0) & (t < 1) & (v >= -1e-9) & (v <= 1 + 1e-9)
    merge = 0.2 * seg / ell
    ts: list[float] = []
    for tt in np.sort(t[hit]):
        if tt - (ts[-1] if ts else 0.0) >= merge and 1.0 - tt >= merge:
            ts.append(float(tt))
    eps = 1e-7
    out: list[float] = []
    for k, tt in enumerate(ts):
        sides = locate_points(blocks, np.array([p + (tt - eps) * r, p + (tt + eps) * r]))[0] >= 0
        if sides[0] != sides[1]:
            out.append(tt)
            continue
        lo = ts[k - 1] if k else 0.0
        hi = ts[k + 1] if k + 1 < len(ts) else 1.0
        half = min(0.5 * seg / ell, 0.45 * (tt - lo), 0.45 * (hi - tt))
        out += [tt - half, tt + half]
    return out


class Anchors(Interaction):
    """The anchors of a model: bar elements, their nodes and their ties to the blocks.

    Args:
        model: the :class:`~masonry_fdem.model.Model` whose blocks host the anchors.
        anchors: the :class:`Anchor` definitions.

    Raises:
        ValueError: an anchor lies wholly outside the blocks, or only its end nodes are
            inside (nothing to bond to), or a definition is invalid.

    An :class:`~masonry_fdem.interactions.protocol.Interaction` that owns the dof set
    ``"anchors"`` (the bar nodes): ``ExplicitSolver(model, interactions=[..., a])``
    advances the bar nodes with the blocks; ``DynamicRelaxation(model, interactions=[...,
    a])`` makes them unknowns of the equilibrium iteration. Bond and steel states are
    trial states from the committed one, accepted by ``commit`` (every explicit step, a
    converged increment).
    """

    name = "anchors"
    state_attributes = ("u", "v", "es", "et", "ns", "nt", "dref", "axial", "strain",
                        "bond_out", "jacking", "npr", "ep", "reaction", "cw", "cwt", "cout",
                        "dowel_work")

    def __init__(self, model, anchors: Sequence[Anchor]):
        anchors = list(anchors) if not isinstance(anchors, Anchor) else [anchors]
        if not anchors:
            raise ValueError("no anchors given")
        for a in anchors:
            if not isinstance(a, Anchor):
                raise TypeError(f"expected Anchor objects, got {type(a).__name__}")
        self.model = model
        self.comm = model.comm
        self.anchors = anchors
        blocks = model.blocks
        h_med = float(np.median(np.sqrt(2.0 * blocks.cell_area)))
        # ---- discretise
        xs, conn, elem_anchor, node_anchor = [], [], [], []
        laws, law_index = [], {}
        n0 = 0
        self.anchor_nodes: list[np.ndarray] = []
        self.anchor_elements: list[np.ndarray] = []
        for k, a in enumerate(anchors):
            seg = a.segment or h_med
            pts = [a.points[0]]
            for p, q in zip(a.points[:-1], a.points[1:], strict=True):
                # nodes where the anchor crosses a block boundary (enters or leaves the
                # masonry, crosses a joint), so that every bar element lies in one block
                # or outside all of them
                cuts = [0.0, *_boundary_crossings(blocks, p, q, seg), 1.0]
                for t0, t1 in zip(cuts[:-1], cuts[1:], strict=True):
                    m = max(1, math.ceil(np.linalg.norm(q - p) * (t1 - t0) / seg - 1e-9))
                    for j in range(1, m + 1):
                        pts.append(p + (q - p) * (t0 + (t1 - t0) * j / m))
            pts = np.array(pts)
            nn = pts.shape[0]
            xs.append(pts)
            conn.append(np.c_[np.arange(nn - 1), np.arange(1, nn)] + n0)
            self.anchor_nodes.append(np.arange(n0, n0 + nn))
            e0 = sum(c.shape[0] for c in conn[:-1])
            self.anchor_elements.append(np.arange(e0, e0 + nn - 1))
            elem_anchor += [k] * (nn - 1)
            node_anchor += [k] * nn
            if a.bond not in law_index:
                law_index[a.bond] = len(laws)
                laws.append(a.bond)
            n0 += nn
        self.x = np.ascontiguousarray(np.vstack(xs))
        self.conn = np.ascontiguousarray(np.vstack(conn), dtype=np.int64)
        self.elem_anchor = np.array(elem_anchor, dtype=np.int64)
        self.node_anchor = np.array(node_anchor, dtype=np.int64)
        n, ne = self.x.shape[0], self.conn.shape[0]
        self.n, self.n_elements = n, ne
        self.L0 = np.linalg.norm(self.x[self.conn[:, 1]] - self.x[self.conn[:, 0]], axis=1)
        trib = np.zeros(n)  # tributary length (mass)
        np.add.at(trib, self.conn[:, 0], 0.5 * self.L0)
        np.add.at(trib, self.conn[:, 1], 0.5 * self.L0)
        # ---- bond points: the halves of the bar elements that lie in a block, each hosted
        # by that block (the two halves of an element bridging a joint bond to the blocks
        # on either side)
        xa, xb = self.x[self.conn[:, 0]], self.x[self.conn[:, 1]]
        quarter = np.vstack([0.75 * xa + 0.25 * xb, 0.25 * xa + 0.75 * xb])
        qcell, _ = locate_points(blocks, quarter)
        qblock = np.where(qcell >= 0, blocks.cell_block[np.maximum(qcell, 0)], -1)
        half_block = qblock.reshape(2, ne).T  # (element, side)
        self.bonded_element = np.any(half_block >= 0, axis=1)
        for k, a in enumerate(anchors):
            if not self.bonded_element[self.anchor_elements[k]].any():
                raise ValueError(f"{a.name or f'anchor {k}'} lies wholly outside the blocks")
        he, hs = np.nonzero(half_block >= 0)
        self.helem = he.astype(np.int64)
        self.hnode = self.conn[he, hs].astype(np.int64)
        nh = self.hnode.size
        self.n_bond = nh
        hblock = half_block[he, hs]
        gcell = np.empty(nh, dtype=np.int64)
        bary = np.empty((nh, 3))
        for h in range(nh):
            gcell[h], bary[h] = locate_in_block(blocks, int(hblock[h]), self.x[self.hnode[h]])
        self.host_block = hblock
        inv = np.full(blocks.n_nodes, -1, dtype=np.int64)
        inv[model.node_input] = np.arange(model.n_nodes)
        rank = self.comm.rank
        block_rank = model.block_ranks()
        self.hosts = np.full((nh, 3), -1, dtype=np.int64)
        self.hw = np.zeros((nh, 3))
        local = block_rank[hblock] == rank
        for h in np.flatnonzero(local):
            self.hosts[h] = inv[blocks.cells[gcell[h]]]
            self.hw[h] = bary[h]
        if np.any(self.hosts[local] < 0):
            raise RuntimeError("an anchor host node is missing on its owner rank")
        self.local = local
        mats = blocks.material_names
        e_host = np.array([model.materials[mats[blocks.cell_material[c]]].E for c in gcell])
        # ---- element and bond-point properties
        self.ep = np.zeros((ne, AK.N_EP))
        self.count_e = np.zeros(ne)
        for e in range(ne):
            a = anchors[self.elem_anchor[e]]
            self.ep[e] = (a.count * a.area, a.steel.E, a.steel.yield_stress,
                          a.steel.hardening, a.steel.rupture_strain, a.count * a.prestress)
            self.count_e[e] = a.count
        self.jacking = np.array([anchors[k].prestress > 0 for k in self.elem_anchor],
                                dtype=np.int8)
        self.mass = np.zeros(2 * n)
        for i in range(n):
            a = anchors[self.node_anchor[i]]
            self.mass[2 * i:2 * i + 2] = a.steel.density * a.area * a.count * trib[i]
        self.npr = np.zeros((nh, AK.N_NP))
        for h in range(nh):
            k = self.elem_anchor[self.helem[h]]
            a = anchors[k]
            ell = 0.5 * self.L0[self.helem[h]]
            row = self.npr[h]
            row[AK.NP_LAW] = law_index[a.bond]
            row[AK.NP_BONDED] = 0.0 if a.prestress > 0 else 1.0
            row[AK.NP_BOND] = a.count * a.perimeter * ell
            dowel = a.dowel or DowelLaw(stiffness=e_host[h])
            row[AK.NP_KT] = a.count * dowel.stiffness * ell
            row[AK.NP_QY] = a.count * dowel.strength * ell
            start, end = _PLATES[a.plates]
            nodes = self.anchor_nodes[k]
            i = self.hnode[h]
            side = start if i == nodes[0] else (-end if i == nodes[-1] else 0)
            if side:
                row[AK.NP_PLATE] = side
                row[AK.NP_KP] = a.count * (a.plate_stiffness or e_host[h] * 0.1)
        for k, a in enumerate(anchors):
            start, end = _PLATES[a.plates]
            elems = self.anchor_elements[k]
            for flag, e, side, where in ((start, elems[0], 0, "start"),
                                         (end, elems[-1], 1, "end")):
                if flag and half_block[e, side] < 0:
                    raise ValueError(f"{a.name or f'anchor {k}'}: its {where} plate is "
                                     "outside the blocks")
        # ---- joint dowels: the bar elements bridging two blocks, of anchors with a shear
        # law; the crossing (the element's midpoint: it is centred on the joint) located in
        # each of the two blocks
        cross = np.flatnonzero((half_block[:, 0] >= 0) & (half_block[:, 1] >= 0)
                               & (half_block[:, 0] != half_block[:, 1])
                               & np.array([anchors[k].shear is not None
                                           for k in self.elem_anchor], dtype=bool))
        nc = self.n_cross = int(cross.size)
        self.celem = cross.astype(np.int64)
        self.cblock = half_block[cross].astype(np.int64).reshape(nc, 2)
        self.cpoint = 0.5 * (xa[cross] + xb[cross]).reshape(nc, 2)
        self.cinput = np.zeros((nc, 2, 3), dtype=np.int64)
        self.chost = np.full((nc, 2, 3), -1, dtype=np.int64)
        self.chw = np.zeros((nc, 2, 3))
        self.cprop = np.zeros((nc, 2))
        self.cgrad = np.zeros((nc, 2, 3, 2))
        tb = (xb[cross] - xa[cross]).reshape(nc, 2)
        tb /= np.linalg.norm(tb, axis=1)[:, None]
        self.cn0 = np.ascontiguousarray(np.c_[-tb[:, 1], tb[:, 0]])  # reference normal
        for c in range(nc):
            a = anchors[self.elem_anchor[cross[c]]]
            self.cprop[c] = (a.count * a.shear.stiffness, a.count * a.shear.strength)
            for side in range(2):
                cell, w = locate_in_block(blocks, int(self.cblock[c, side]), self.cpoint[c])
                self.cinput[c, side] = blocks.cells[cell]
                self.chw[c, side] = w
                p = blocks.x[blocks.cells[cell]]  # ∇N of the linear triangle
                jac = np.array([p[1] - p[0], p[2] - p[0]]).T
                inv_t = np.linalg.inv(jac).T
                self.cgrad[c, side] = np.array([[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]]) @ inv_t.T
                if block_rank[self.cblock[c, side]] == rank:
                    self.chost[c, side] = inv[self.cinput[c, side]]
        if np.any(self.chost[block_rank[self.cblock] == rank] < 0):
            raise RuntimeError("a joint dowel's host node is missing on its owner rank")
        self.cw = np.zeros(nc)
        self.cwt = np.zeros(nc)
        self.cout = np.zeros((nc, AK.N_CO))
        self.dowel_work = np.zeros(1)  # plastic work of the joint dowels [J]
        self._uc = np.zeros((nc, 6))
        kmax = max(len(b.slip) for b in laws)
        self.laws_s = np.zeros((len(laws), kmax))
        self.laws_t = np.zeros((len(laws), kmax))
        self.laws_n = np.array([len(b.slip) for b in laws], dtype=np.int64)
        self.laws_k0 = np.array([b.k0 for b in laws])
        for j, b in enumerate(laws):
            self.laws_s[j, :len(b.slip)] = b.slip
            self.laws_t[j, :len(b.slip)] = b.stress
        # ---- state
        self.u = np.zeros(2 * n)
        self.v = np.zeros(2 * n)
        self.f = np.zeros(2 * n)
        self._fbond = np.zeros(2 * n)
        self.es = np.zeros((ne, AK.N_ES))
        self.et = np.zeros((ne, AK.N_ES))
        self.ns = np.zeros((nh, AK.N_NS))
        self.nt = np.zeros((nh, AK.N_NS))
        self.dref = np.zeros((nh, 2))
        self.axial = np.zeros(ne)
        self.strain = np.zeros(ne)
        self.bond_out = np.zeros((nh, AK.N_NO))
        self.presc = np.zeros(2 * n, dtype=np.int8)
        self.vp = np.zeros(2 * n)
        self.reaction = np.zeros(2 * n)
        self.prescriptions: dict[str, np.ndarray] = {}
        self._dofset = DofSet("anchors", self.u, self.v, self.mass, self.f, presc=self.presc,
                              vp=self.vp, reaction=self.reaction,
                              prescriptions=self.prescriptions)
        # ---- stiffness bounds (row sums of |K|) for time steps and DR masses
        k_h = self.npr[:, AK.NP_BOND] * self.laws_k0[self.npr[:, AK.NP_LAW].astype(int)]
        k_h += self.npr[:, AK.NP_KT] + self.npr[:, AK.NP_KP]
        rows = np.zeros(n)
        ke = self.ep[:, AK.EP_E] * self.ep[:, AK.EP_AREA] / self.L0
        np.add.at(rows, self.conn[:, 0], 2.0 * _DIR * ke)
        np.add.at(rows, self.conn[:, 1], 2.0 * _DIR * ke)
        np.add.at(rows, self.hnode, 2.0 * _DIR * k_h)
        self.rowsum = np.repeat(rows, 2)
        self.host_rowsum = np.zeros_like(model.f_int)
        for h in np.flatnonzero(local):
            for j, w in zip(self.hosts[h], self.hw[h], strict=True):
                self.host_rowsum[2 * j:2 * j + 2] += 2.0 * _DIR * k_h[h] * w
        for c in range(nc):  # a dowel's row: K w_m (Σ w of both sides) = 2 K w_m
            for side in range(2):
                for j, w in zip(self.chost[c, side], self.chw[c, side], strict=True):
                    if j >= 0:
                        self.host_rowsum[2 * j:2 * j + 2] += 2.0 * _DIR * self.cprop[c, 0] * w

    # ------------------------------------------------------------------ set-up
    def prescribe(self, name: str, anchor: int = 0, node: str | int = "end",
                  velocity: Sequence[float] = (0.0, 0.0)) -> None:
        """Prescribe the motion of one anchor node (e.g. the pulled end of a pull-out test).

        Args:
            name: name of the prescription (for ``DynamicRelaxation.solve(displacement=
                {name: (ux, uy)})`` and :meth:`reactions`); must not clash with the model's.
            anchor: index of the anchor.
            node: "start", "end" or the index of the node along the anchor.
            velocity: prescribed velocity (vx, vy) [m/s] in explicit runs.
        """
        if name in self.prescriptions or name in {p.name for p in self.model.prescriptions}:
            raise ValueError(f"a prescription named {name!r} exists already")
        if not 0 <= anchor < len(self.anchors):
            raise ValueError(f"anchor index {anchor} out of range 0..{len(self.anchors) - 1}")
        nodes = self.anchor_nodes[anchor]
        if node == "start":
            i = nodes[0]
        elif node == "end":
            i = nodes[-1]
        elif isinstance(node, int | np.integer) and 0 <= node < nodes.size:
            i = nodes[node]
        else:
            raise ValueError(f"node must be 'start', 'end' or 0..{nodes.size - 1}, got {node!r}")
        dofs = np.array([2 * i, 2 * i + 1])
        self.presc[dofs] = 1
        self.vp[dofs] = np.asarray(velocity, dtype=float)
        self.prescriptions[name] = dofs

    def set_displacement(self, name: str, value: Sequence[float | None]) -> None:
        """Set the prescribed node of ``name`` to total displacement (ux, uy) [m]."""
        dofs = self.prescriptions[name]
        if len(value) != 2:
            raise ValueError(f"displacement of {name!r} needs two components (ux, uy)")
        for c in (0, 1):
            if value[c] is not None:
                self.u[dofs[c]] = float(value[c])

    # ------------------------------------------------------------------ interaction API
    def dofsets(self) -> tuple[DofSet, ...]:
        """The bar nodes (x, y per node), held where prescribed (:meth:`prescribe`)."""
        return (self._dofset,)

    def stable_omega2(self) -> dict[str, float]:
        """Bound of ω² [1/s²] the anchors add (Gershgorin on M⁻¹K of their springs, at the
        bar nodes and at the host nodes), global."""
        w2 = float(np.max(self.rowsum / self.mass))
        free = self.host_rowsum > 0
        if free.any():
            w2 = max(w2, float(np.max(self.host_rowsum[free] / self.model.mass[free])))
        w2 = self.comm.allreduce(w2, op=MPI.MAX)
        return {BLOCKS: w2, "anchors": w2}

    def add_rowsum(self, rows) -> None:
        """Σ_j |K_ij| [N/m] of the bars and ties into the block and bar-node rows."""
        rows[BLOCKS] += self.host_rowsum
        rows["anchors"] += self.rowsum

    def add_forces(self, state: State) -> None:
        """Bond, dowel and plate forces on the local host nodes, the joint dowels' forces on
        the local nodes of their two blocks, and the total force on every bar node (bond
        summed over ranks, then the bars'; collective)."""
        self._fbond.fill(0.0)
        ua, fa = state.u["anchors"], state.f["anchors"]
        AK.bond_forces(self.x, ua, state.u[BLOCKS], self.conn, self.hnode,
                       self.helem, self.hosts, self.hw, self.npr, self.laws_s, self.laws_t,
                       self.laws_n, self.laws_k0, self.dref, self.ns, self.nt, self.bond_out,
                       self._fbond, state.f[BLOCKS])
        if self.comm.size > 1:
            self.comm.Allreduce(MPI.IN_PLACE, self._fbond, op=MPI.SUM)
        fa += self._fbond
        if self.n_cross:
            AK.crossing_displacements(state.u[BLOCKS], self.chost, self.chw, self.cgrad,
                                      self._uc)
            if self.comm.size > 1:
                self.comm.Allreduce(MPI.IN_PLACE, self._uc, op=MPI.SUM)
            AK.dowel_forces(self.celem, self.jacking, self.cn0, self._uc, self.cprop, self.cw,
                            self.cwt, self.cout, self.chost, self.chw, state.f[BLOCKS])
        AK.bar_forces(self.x, ua, self.conn, self.L0, self.ep, self.jacking, self.es,
                      self.et, self.axial, self.strain, fa)

    def add_tangent(self, K: Tangent, state: State) -> None:
        """The consistent tangent −∂f/∂u [N/m] of the bond points with a local host (rows
        of their bar node and host nodes; columns of their bar element's nodes and host
        nodes) and, on rank 0 alone, of the bar elements (computed alike on every rank)
        into ``K``, at the positions of the last :meth:`add_forces`. Central differences
        of the force kernels, see :func:`._kernels.bond_tangent`, :func:`._kernels.bar_tangent`.
        """
        ua, ub = state.u["anchors"], state.u[BLOCKS]
        nb = int(np.count_nonzero(self.local))
        rows = np.empty(80 * nb, dtype=np.int64)
        cols = np.empty(80 * nb, dtype=np.int64)
        vals = np.empty(80 * nb)
        nent = AK.bond_tangent(self.x, ua, ub, self.conn, self.L0, self.hnode, self.helem,
                               self.hosts, self.hw, self.npr, self.laws_s, self.laws_t,
                               self.laws_n, self.laws_k0, self.dref, self.ns, AK.FD_STEP,
                               rows, cols, vals)
        if nent:
            glob = np.r_[K.index["anchors"], K.index[BLOCKS][:ub.size]]
            K.add(glob[rows[:nent]], glob[cols[:nent]], vals[:nent])
        if self.n_cross:
            nc = self.n_cross
            glob = K.node_dofs(self.cinput.reshape(-1)).reshape(nc, 2, 3, 2)[..., 0]
            rows = np.empty(144 * nc, dtype=np.int64)
            cols = np.empty(144 * nc, dtype=np.int64)
            vals = np.empty(144 * nc)
            nent = AK.dowel_tangent(self.cout, self.cprop, self.chost, self.chw, self.cgrad,
                                    np.ascontiguousarray(glob), rows, cols, vals)
            if nent:
                K.add(rows[:nent], cols[:nent], vals[:nent])
        if K.rank == 0:
            ne = self.n_elements
            rows = np.empty(16 * ne, dtype=np.int64)
            cols = np.empty(16 * ne, dtype=np.int64)
            vals = np.empty(16 * ne)
            nent = AK.bar_tangent(self.x, ua, self.conn, self.L0, self.ep, self.jacking,
                                  self.es, AK.FD_STEP, rows, cols, vals)
            ia = K.index["anchors"]
            K.add(ia[rows[:nent]], ia[cols[:nent]], vals[:nent])

    def set_state(self, state) -> None:
        """As :meth:`Interaction.set_state`; a state saved before joint dowels existed
        (no ``cw``, ``cwt``, ``cout``, ``dowel_work``) is taken when there are none."""
        new = ("cw", "cwt", "cout", "dowel_work")
        if self.n_cross == 0 and not all(k in state for k in new):
            state = dict(state)
            for k in new:
                state.setdefault(k, getattr(self, k))
        super().set_state(state)

    def commit(self) -> None:
        """Accept the trial bond and steel state."""
        self.es[:] = self.et
        self.ns[:] = self.nt
        if self.n_cross:  # plastic work of the dowels: q · Δw_p (q = ±Q_y while it slips)
            self.dowel_work[0] += float(np.dot(self.cout[:, AK.CO_Q], self.cwt - self.cw))
        self.cw[:] = self.cwt

    def energies(self) -> dict[str, float]:
        """Elastic energy of the bars, ½ Σ N² L0/(E A), and of the joint dowels, ½ Σ q²/K
        [J], the part of the anchors' energy held now; dissipated: the dowels' plastic
        work Σ q Δw_p; bond and dissipated energies are not tracked (the work the
        anchors' forces do is in the solver's energy account)."""
        area = self.ep[:, AK.EP_AREA]
        bar = 0.5 * float(np.sum(self.axial**2 * self.L0 / (self.ep[:, AK.EP_E] * area)))
        dow = 0.5 * float(np.sum(self.cout[:, AK.CO_Q] ** 2 / np.maximum(self.cprop[:, 0],
                                                                          1e-300)))
        return {"stored": bar + dow, "dissipated": float(self.dowel_work[0]),
                "bar_elastic": bar, "dowel_elastic": dow,
                "dowel_dissipated": float(self.dowel_work[0])}

    def lock_off(self) -> None:
        """Lock the jacked anchors off at their prestress and grout them (collective).

        Every jacking bar element keeps force P at its current length (its stress-free
        length is set accordingly) and the bond starts to act, with slip measured from
        the current position. Call it once the structure is in equilibrium under the
        jacking forces.
        """
        jack = np.flatnonzero(self.jacking)
        if jack.size == 0:
            return
        ua = self.u.reshape(-1, 2)
        dX = self.x[self.conn[jack, 1]] - self.x[self.conn[jack, 0]]
        du = ua[self.conn[jack, 1]] - ua[self.conn[jack, 0]]
        ell = np.linalg.norm(dX + du, axis=1)
        L0 = self.L0[jack]
        eps = (2.0 * (dX * du).sum(axis=1) + (du * du).sum(axis=1)) / ((ell + L0) * L0)
        sig = self.ep[jack, AK.EP_JACK] / self.ep[jack, AK.EP_AREA]
        self.es[jack, AK.ES_EPSP] = eps - sig / self.ep[jack, AK.EP_E]
        self.et[jack] = self.es[jack]
        self.jacking[jack] = 0
        pts = np.flatnonzero(np.isin(self.helem, jack))
        d = np.zeros((self.n_bond, 2))
        AK.relative_displacements(self.u, self.model.u.x.array, self.hnode, self.hosts,
                                  self.hw, d)
        self.dref[pts] = d[pts]
        self.npr[pts, AK.NP_BONDED] = 1.0

    def reset(self) -> None:
        """Back to the unloaded, unjacked state."""
        for arr in (self.u, self.v, self.f, self.es, self.et, self.ns, self.nt, self.dref,
                    self.axial, self.strain, self.bond_out, self.reaction, self.cw, self.cwt,
                    self.cout, self.dowel_work):
            arr[...] = 0.0
        self.jacking[:] = [self.anchors[k].prestress > 0 for k in self.elem_anchor]
        self.npr[:, AK.NP_BONDED] = 1.0 - self.jacking[self.helem]

    # ------------------------------------------------------------------ results
    def reactions(self) -> dict[str, np.ndarray]:
        """Force (Fx, Fy) [N] each anchor prescription applies to its node (the pull).

        Valid after a converged DR solve (then −f) or an explicit step (support force)."""
        return {name: self._reaction(dofs) for name, dofs in self.prescriptions.items()}

    def _reaction(self, dofs) -> np.ndarray:
        return -self.f[dofs].copy()

    def axial_force(self) -> np.ndarray:
        """Axial force of each bar element [N] per bar (tension positive)."""
        return self.axial / self.count_e

    def stress(self) -> np.ndarray:
        """Axial stress [Pa] of each bar element."""
        return self.axial / self.ep[:, AK.EP_AREA]

    def plastic_strain(self) -> np.ndarray:
        """Committed plastic strain of each bar element."""
        return self.es[:, AK.ES_EPSP].copy()

    def yielded(self) -> np.ndarray:
        """Committed flag of each bar element: the steel has yielded."""
        return self.es[:, AK.ES_ALPHA] > 0

    def ruptured(self) -> np.ndarray:
        """Committed rupture flag of each bar element."""
        return self.es[:, AK.ES_RUPT] > 0.5

    def bond_results(self) -> dict[str, np.ndarray]:
        """Per bond point (half of a bonded bar element; collective): "node" (its bar
        node), "element", "slip" [m], "bond_stress" [Pa], "transverse" [m],
        "transverse_force" [N per bar], "plate_force" [N per bar]."""
        out = self.bond_out.copy()
        if self.comm.size > 1:
            self.comm.Allreduce(MPI.IN_PLACE, out, op=MPI.SUM)
        count = self.count_e[self.helem]
        return {
            "node": self.hnode, "element": self.helem,
            "slip": out[:, AK.NO_SLIP],
            "bond_stress": out[:, AK.NO_TAU],
            "transverse": out[:, AK.NO_W],
            "transverse_force": out[:, AK.NO_Q] / count,
            "plate_force": out[:, AK.NO_PLATE] / count,
        }

    def dowel_results(self) -> dict[str, np.ndarray]:
        """Per joint dowel (a bar element bridging two blocks, of an anchor with a
        ``shear`` law; every rank): "element", "anchor", "position" [m] (reference),
        "slip" [m] across the bar, "force" [N per bar], "strength" [N per bar], "plastic"
        (on the plateau), at the last force evaluation."""
        count = self.count_e[self.celem]
        return {
            "element": self.celem, "anchor": self.elem_anchor[self.celem],
            "position": self.cpoint,
            "slip": self.cout[:, AK.CO_W].copy(),
            "force": self.cout[:, AK.CO_Q] / count,
            "strength": self.cprop[:, 1] / count,
            "plastic": self.cout[:, AK.CO_PLASTIC] > 0.5,
        }

    def node_results(self) -> dict[str, np.ndarray]:
        """Per bar node (collective): "slip" [m] and "bond_stress" [Pa] (means over the
        node's bond points; 0 at a free node), "position" [m] (current), "bonded"."""
        b = self.bond_results()
        w = np.zeros(self.n)
        np.add.at(w, b["node"], 1.0)
        out = {"position": self.x + self.u.reshape(-1, 2), "bonded": w > 0}
        for key in ("slip", "bond_stress"):
            acc = np.zeros(self.n)
            np.add.at(acc, b["node"], b[key])
            out[key] = np.where(w > 0, acc / np.maximum(w, 1), 0.0)
        return out

    def summary(self) -> dict[str, float]:
        """Scalars for a history row (collective): largest bar force [N] and |slip| [m],
        number of yielded and of ruptured bar elements."""
        res = self.node_results()
        return {
            "anchor_force_max": float(np.max(self.axial_force())),
            "anchor_slip_max": float(np.max(np.abs(res["slip"]))),
            "anchor_elements_yielded": float(np.count_nonzero(self.yielded())),
            "anchor_elements_ruptured": float(np.count_nonzero(self.ruptured())),
        }

    def segments(self, scale: float = 1.0) -> np.ndarray:
        """(n_elements, 2, 2) end points of the bar elements, displaced ×scale [m]."""
        xa = self.x + scale * self.u.reshape(-1, 2)
        return np.stack([xa[self.conn[:, 0]], xa[self.conn[:, 1]]], axis=1)

    @property
    def total_length(self) -> float:
        """Σ count × length of the anchors [m] (the metres of anchor installed)."""
        return float(sum(a.count * a.length for a in self.anchors))

    def __repr__(self) -> str:
        return (f"Anchors({len(self.anchors)} anchors, {self.n} nodes, "
                f"{self.n_elements} bar elements, {self.total_length:.3g} m)")


# ---------------------------------------------------------------------- layouts
def straight_anchor(start: Sequence[float], end: Sequence[float], diameter: float,
                    **kw) -> Anchor:
    """A straight anchor from ``start`` to ``end`` [m] (other arguments as :class:`Anchor`)."""
    return Anchor(np.array([start, end], dtype=float), diameter, **kw)


def wall_ties(
    positions: Sequence[float],
    *,
    extent: tuple[float, float],
    direction: str = "vertical",
    diameter: float,
    **kw,
) -> list[Anchor]:
    """Straight ties across a wall's joints.

    Args:
        positions: x [m] of vertical ties (across the bed joints), or y [m] of horizontal
            ties (across the head joints).
        extent: (from, to) [m]: the y range of vertical ties, the x range of horizontal ones.
        direction: "vertical" or "horizontal".
        diameter: bar diameter [m]; other keywords go to :class:`Anchor`.
    """
    if direction not in ("vertical", "horizontal"):
        raise ValueError(f"direction must be 'vertical' or 'horizontal', got {direction!r}")
    a, b = (float(v) for v in extent)
    if not b > a:
        raise ValueError(f"extent must be (from, to) with to > from, got {extent}")
    name = kw.pop("name", "tie")
    out = []
    for k, p in enumerate(positions):
        pts = [[p, a], [p, b]] if direction == "vertical" else [[a, p], [b, p]]
        out.append(Anchor(np.array(pts, dtype=float), diameter, name=f"{name}:{k}", **kw))
    return out
