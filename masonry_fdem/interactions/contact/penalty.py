"""Frictional facet-to-facet penalty contact between deformable blocks.

:class:`BlockContact` finds candidate facet pairs with the alternating digital tree every
few steps (boxes inflated by a travel margin), evaluates the penalty kernel on them every
step and keeps the tangential (stick/slip) history of each pair across neighbour updates,
keyed by the pair's global facet ids.

Parameters (SI): the normal penalty ε_n [Pa/m] is traction per metre of penetration; by
default ``penalty_factor · E_min / h`` with E_min the smaller Young's modulus of the pair
and h the mean boundary facet length of the model, so a facet node's contact spring is
comparable with the stiffness of its element. The tangential penalty is
``tangential_ratio · ε_n``. With ``through_layers``, through a joint layer (a pair with a
facet the joints bonded: a crack's or a mortar joint's faces once handed over, a ring's
face slid along the sand layer onto the next, a corner pressed through it) the penalties
are the softest layer's k_n and k_s where softer (:meth:`BlockContact.set_layers`).
Normal energy loss follows from the restitution coefficient e through a normal viscous
damper that never pulls (see ``_kernels``): the damper of two blocks is the fraction ζ(e)
of critical for the blocks as rigid bodies on the springs of their contact, so a rigid
impact rebounds with e times its approach velocity, flat or on a corner, and a contact
that stays closed keeps its force and its friction.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import lru_cache

from mpi4py import MPI

import numpy as np

from masonry_fdem.interactions._sums import gather_rows, node_lists
from masonry_fdem.interactions.contact import _kernels as K
from masonry_fdem.interactions.protocol import BLOCKS, Interaction, State
from masonry_fdem.interactions.search import (
    boxes_on_cells,
    facet_boxes,
    mark_cells,
    max_speed,
    self_pairs,
)
from masonry_fdem.parallel import exchange_ids

__all__ = ["ContactSettings", "BlockContact", "restitution_damping_ratio",
           "INELASTIC_DAMPING_RATIO"]

log = logging.getLogger(__name__)

#: Damping ratio ζ of the perfectly inelastic impact (e = 0) and the largest used. A
#: damper that never pulls cannot stop a rebound completely (once the body recedes,
#: every force left pushes it out; e ≈ 1/(4ζ²) for large ζ), so e = 0 is approached:
#: ζ = 2 leaves e = 0.048 on a face (a rebound to 0.23 % of the drop height); a
#: restitution coefficient below what it gives is taken as e = 0. A larger ζ costs time
#: step (the stable step falls as 1/ζ).
INELASTIC_DAMPING_RATIO = 2.0


@lru_cache(maxsize=64)
def restitution_damping_ratio(e: float, vertex: bool = False) -> float:
    """Damping ratio ζ of the contact damper that gives the restitution coefficient e.

    The damper is c = 2 ζ √(K m) beside the penalty springs, the traction clipped at
    zero so it never pulls (``_kernels.clipped_restitution``), for a face impacting a
    face or (``vertex``) a vertex impacting a face: ζ solves e(ζ) = e by bisection. e = 1
    gives 0; e = 0, and any e below what :data:`INELASTIC_DAMPING_RATIO` gives, gives
    that ratio.
    """
    if not 0.0 <= e <= 1.0:
        raise ValueError(f"restitution coefficient must be in [0, 1], got {e}")
    if e == 1.0:
        return 0.0
    def restitution(zeta):  # closed form on a face, the impact integrated on a vertex
        return (K.clipped_restitution(zeta, True) if vertex
                else K.clipped_restitution_linear(zeta))

    zmax = INELASTIC_DAMPING_RATIO
    if e <= restitution(zmax):
        return zmax
    lo, hi = 0.0, zmax
    for _ in range(40):  # e(ζ) decreases with ζ; 2⁻⁴⁰ ζmax
        mid = 0.5 * (lo + hi)
        if restitution(mid) > e:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


@dataclass(frozen=True)
class ContactSettings:
    """Settings of the block contact.

    Attributes:
        friction: Coulomb friction coefficient μ = tan φ of every material pair not in
            ``friction_table``.
        friction_table: μ per pair of material names, e.g. ``{("brick", "base"): 0.4}``.
        restitution: normal restitution coefficient e in [0, 1] of an impact between
            two blocks (1: elastic, 0: perfectly inelastic, see
            :data:`INELASTIC_DAMPING_RATIO`); a normal damper that never pulls, set per
            pair of blocks from their rigid-body masses (``_kernels.contact_damping``).
        penalty: normal penalty ε_n [Pa/m]; None → ``penalty_factor · E_min / h``.
        penalty_factor: factor of the default penalty.
        tangential_ratio: ε_t / ε_n.
        depth_factor: penetrations deeper than this fraction of the shorter facet of a
            pair, or of the thinner of the two blocks (thickness 2·area/perimeter), are
            ignored: a point that deep is nearer another face of the block, and counting
            it would pull it through (seen: a tumbling brick's corner taken for 8 cm
            inside a 6.5 cm brick).
        margin: travel margin [m] of the neighbour list; None → half the mean facet length.
        rebuild_every: steps between neighbour-list rebuilds (sooner if the accumulated
            travel could exceed the margin, which is what keeps every contact in the
            list; the forces do not depend on it: a candidate out of reach adds zero).
        apart: pairs of material names whose blocks never touch: bodies that overlap in
            the plane because they lie side by side out of it (a bridge's spandrel walls
            and the fill between them).
        through_layers: a pair with a facet on a joint layer takes the softest layer's
            k_n, k_s where softer than the penalties (:meth:`BlockContact.set_layers`).
            Off by default: on the TRL arch it removes the force jump of a sand layer
            handed over under compression, but the anchored coarse runs of the
            sensitivity study then stop *not converged* on their falling branch in 5 of
            9 variants (docs/design.md, "The contact through a joint layer").
    """

    friction: float = 0.6
    friction_table: Mapping[tuple[str, str], float] = field(default_factory=dict)
    restitution: float = 1.0
    penalty: float | None = None
    penalty_factor: float = 1.0
    tangential_ratio: float = 1.0
    depth_factor: float = 0.5
    margin: float | None = None
    rebuild_every: int = 50
    apart: tuple[tuple[str, str], ...] = ()
    through_layers: bool = False

    def __post_init__(self) -> None:
        if self.friction < 0:
            raise ValueError(f"friction coefficient must be >= 0, got {self.friction}")
        for pair, mu in self.friction_table.items():
            if mu < 0:
                raise ValueError(f"friction coefficient of {pair} must be >= 0, got {mu}")
        if not 0.0 <= self.restitution <= 1.0:
            raise ValueError(f"restitution coefficient must be in [0, 1], got "
                             f"{self.restitution}")
        if self.penalty is not None and not self.penalty > 0:
            raise ValueError(f"penalty must be > 0 Pa/m, got {self.penalty}")
        if not self.penalty_factor > 0 or not self.tangential_ratio > 0:
            raise ValueError("penalty_factor and tangential_ratio must be > 0")
        if self.margin is not None and not self.margin > 0:
            raise ValueError(f"margin must be > 0 m, got {self.margin}")
        if self.rebuild_every < 1:
            raise ValueError("rebuild_every must be >= 1")


class BlockContact(Interaction):
    """Contact between the blocks of a model, across ranks too.

    Every rank evaluates the pairs of its own facets, with the facets of other ranks that
    fall within its inflated bounding box (*ghost* facets): a pair across two ranks is
    evaluated by both, each summing the forces on its own nodes (in the pairs' key
    order: the same sums as on one rank), and counted in the energies and the tangent by
    the lower. Ghost facets and nodes are found again at each neighbour-list rebuild;
    their positions and velocities are refreshed every step.

    Args:
        model: the :class:`~masonry_fdem.model.Model`.
        settings: contact settings.

    An :class:`~masonry_fdem.interactions.protocol.Interaction`: its history, the
    tangential spring of every pair by pair key, evolves in place in explicit and
    dynamic-relaxation runs; ``commit`` keeps a copy, from which a
    static (Newton) evaluation starts (backward Euler: the slip is the displacement since
    the commit) and to which ``restore`` returns; ``set_state`` brings a saved state back
    and finds the candidates again. ``add_tangent``: the consistent tangent, by central
    differences of the pair kernel (stick and slip; see ``_kernels.facet_facet_tangent``).

    Restitution (e < 1): each step of explicit dynamics first sets the normal damper of
    every pair of blocks in contact from the two blocks' rigid-body masses (M, I from the
    lumped nodal masses, computed once; centroids at the current positions, every step)
    and the contact's current stiffness (``_kernels.contact_damping``), then evaluates
    springs, dampers and friction together. The dampers are off in dynamic relaxation
    and in static solutions. ``stable_damping`` bounds their rate for the stable step;
    ``energies()["damper_dissipated"]`` is their dissipation.
    """

    name = "contact"
    state_attributes = ("keys", "tau", "tau_c", "excluded", "bonded_pairs", "energy",
                        "dissipated", "damped", "rebuilds")

    def __init__(self, model, settings: ContactSettings | None = None):
        self.model = model
        self.settings = settings or ContactSettings()
        s = self.settings
        comm = model.comm
        blocks = model.blocks
        self.comm = comm
        # ---- global facet tables (every rank knows the whole BlockMesh)
        gf = np.asarray(blocks.boundary_facets, dtype=np.int64)
        self.g_facets = gf
        first = np.full(blocks.n_nodes, -1, dtype=np.int64)
        first[gf[:, 0]] = np.arange(gf.shape[0])
        self.g_next = first[gf[:, 1]]
        if np.any(self.g_next < 0):
            raise ValueError("block boundaries are not closed loops of facets")
        self.g_prev = np.empty_like(self.g_next)
        self.g_prev[self.g_next] = np.arange(gf.shape[0])
        self.g_block = np.asarray(blocks.facet_block, dtype=np.int64)
        self.g_material = blocks.block_material[self.g_block].astype(np.int64)
        # the normal and shear stiffness [Pa/m] of the joint layer on each facet (NaN: no
        # layer); see :meth:`set_layers`
        self.g_layer_kn = np.full(gf.shape[0], np.nan)
        self.g_layer_ks = np.full(gf.shape[0], np.nan)
        self.g_length = np.linalg.norm(blocks.x[gf[:, 1]] - blocks.x[gf[:, 0]], axis=1)
        perimeter = np.bincount(self.g_block, weights=self.g_length, minlength=blocks.n_blocks)
        self.block_thickness = 2.0 * np.asarray(blocks.block_area) / perimeter
        self.block_rank = model.block_ranks()
        # ---- local facets: those of the blocks on this rank, by global id
        self.local_gid = np.flatnonzero(self.block_rank[self.g_block] == comm.rank)
        self.n_local_nodes = model.n_nodes
        self.h = float(self.g_length.mean())
        names = blocks.material_names
        nm = len(names)
        E = np.array([model.materials[n].E for n in names])
        emin = np.minimum.outer(E, E)
        self.eps_table = (
            np.full((nm, nm), float(s.penalty)) if s.penalty else s.penalty_factor * emin / self.h
        )
        self.mu_table = np.full((nm, nm), s.friction)
        for (a, b), mu in s.friction_table.items():
            for name in (a, b):
                if name not in names:
                    raise ValueError(f"friction_table names unknown material {name!r}")
            i, j = names.index(a), names.index(b)
            self.mu_table[i, j] = self.mu_table[j, i] = mu
        self.apart_table = np.zeros((nm, nm), dtype=bool)
        for a, b in s.apart:
            for name in (a, b):
                if name not in names:
                    raise ValueError(f"apart names unknown material {name!r}")
            i, j = names.index(a), names.index(b)
            self.apart_table[i, j] = self.apart_table[j, i] = True
        # damping ratios of an impact on a face and on a vertex
        self.zeta = (restitution_damping_ratio(s.restitution, False),
                     restitution_damping_ratio(s.restitution, True))
        self._block_inertia()
        self.margin = s.margin if s.margin is not None else 0.5 * self.h
        # ---- state
        self._work = np.zeros(K.N_WORK)
        self._input_to_local = np.full(blocks.n_nodes, -1, dtype=np.int64)
        self._input_to_local[model.node_input] = np.arange(model.n_nodes)
        self.pairs = np.zeros((0, 2), dtype=np.int64)
        self.tau = np.zeros((0, 2))
        self.tau_c = np.zeros((0, 2))
        self.tforce = np.zeros((0, 2))
        self.keys = np.zeros(0, dtype=np.int64)
        self.counted = np.zeros(0)
        self.fp = np.zeros((0, 8))
        self.fdp = np.zeros((0, 8))
        self._zones = np.zeros((0, 2, K.N_WORK))
        self._gnodes = np.zeros(0, dtype=np.int64)
        self._gptr = np.zeros(1, dtype=np.int64)
        self._gidx = np.zeros(0, dtype=np.int64)
        # the committed history by key, as at the last commit (None before one): a
        # rebuild between commits (a failed Newton iterate far from the committed state)
        # may drop a pair that is in contact in the committed state; its history comes
        # back from here, not as zero
        self._committed: tuple[np.ndarray, np.ndarray] | None = None
        # facet-pair keys (min·n + max of global facet ids) left out: bonded joints
        self.excluded = np.zeros(0, dtype=np.int64)
        # pairs of blocks joined by intact bonded joints (keys min·n + max of block ids):
        # no contact between the two
        self.bonded_pairs = np.zeros(0, dtype=np.int64)
        self.energy = np.zeros(K.N_ENERGY)
        self.dissipated = 0.0  # by friction [J]
        self.damped = 0.0  # by the normal dampers [J]
        # the dampers' forces on the local nodes at the last evaluation and the
        # displacements of the two before, for their work over each step's midpoint
        # increment (the solver's measure of work: exact in the energy account)
        nloc2 = 2 * model.n_nodes
        self._fd = np.zeros(nloc2)
        self._u1 = np.zeros(nloc2)
        self._u2 = np.zeros(nloc2)
        self._fd_nodes = np.zeros(0, dtype=np.int64)  # where _fd may be non-zero
        self._fd_live = False
        self.travel = math.inf
        self.since = 0
        self.rebuilds = 0
        self.exchange = None
        self._u_rebuild = np.zeros(2 * model.n_nodes)
        self._build_extended(np.zeros(0, dtype=np.int64), [np.zeros(0, np.int64)] * comm.size)

    # ------------------------------------------------------------------ extended arrays
    def _build_extended(self, ghost_gid_sets, send_sets) -> None:
        """Facet and node tables of local + ghost facets (and the ghosts' neighbours)."""
        model = self.model
        comm = self.comm
        nloc = self.n_local_nodes
        # (kept for a checkpoint: a resume builds the same tables again)
        self._ext_args = (np.array(ghost_gid_sets, dtype=np.int64, copy=True),
                          [np.array(x, dtype=np.int64, copy=True) for x in send_sets])
        ghost_gid = np.unique(np.asarray(ghost_gid_sets, dtype=np.int64))
        # phantom facets: the neighbours of ghost facets (needed by the corner rules)
        extra = np.setdiff1d(np.r_[self.g_prev[ghost_gid], self.g_next[ghost_gid]],
                             np.r_[ghost_gid, self.local_gid])
        gids = np.r_[self.local_gid, ghost_gid, extra].astype(np.int64)
        self.n_candidates = self.local_gid.size + ghost_gid.size
        self.ext_gid = gids
        self._ext_dofs = None  # global dof numbers of the extended nodes (static solver)
        # ghost nodes, grouped by owner rank in sorted input order (the owner agrees)
        recv_nodes = []
        for r in range(comm.size):
            if r == comm.rank:
                recv_nodes.append(np.zeros(0, np.int64))
                continue
            mine = gids[self.block_rank[self.g_block[gids]] == r]
            recv_nodes.append(np.unique(self.g_facets[mine]))
        ghost_nodes = np.concatenate(recv_nodes) if recv_nodes else np.zeros(0, np.int64)
        node_map = self._input_to_local.copy()
        node_map[ghost_nodes] = nloc + np.arange(ghost_nodes.size)
        self.ext_input = np.r_[self.model.node_input, ghost_nodes].astype(np.int64)
        self.facets = np.ascontiguousarray(node_map[self.g_facets[gids]])
        pos = np.full(self.g_facets.shape[0], -1, dtype=np.int64)
        pos[gids] = np.arange(gids.size)
        nxt = pos[self.g_next[gids]]
        prv = pos[self.g_prev[gids]]
        own = np.arange(gids.size)
        # phantoms are never masters: their own neighbours may be absent
        self.fnext = np.where(nxt >= 0, nxt, own).astype(np.int64)
        self.fprev = np.where(prv >= 0, prv, own).astype(np.int64)
        self.facet_block = self.g_block[gids]
        self.facet_material = self.g_material[gids]
        self.facet_length = self.g_length[gids]
        self.facet_rank = self.block_rank[self.facet_block]
        nn = nloc + ghost_nodes.size
        self.X = np.zeros((nn, 2))
        self.X[:nloc] = model.X
        self.X[nloc:] = model.blocks.x[ghost_nodes]
        self.u = np.zeros(2 * nn)
        self.v = np.zeros(2 * nn)
        self.boxes = np.zeros((gids.size, 4))
        if comm.size > 1:
            # what this rank sends to r: the nodes of the facets r takes as ghosts,
            # in r's order (sorted input ids)
            send = []
            for r in range(comm.size):
                ids = send_sets[r]
                nodes = np.unique(self.g_facets[np.r_[ids, self.g_prev[ids], self.g_next[ids]]])
                nodes = nodes[self._input_to_local[nodes] >= 0]
                send.append(self._input_to_local[nodes])
            from masonry_fdem.parallel import NodeExchange

            self.exchange = NodeExchange(comm, send, [len(n) for n in recv_nodes])
            self._uv = np.zeros((nloc, 4))
            self._ghost_uv = np.zeros((self.exchange.n_ghost, 4))

    def _ghosts_for(self, nl: int, half: float) -> list[np.ndarray]:
        """The local facets each rank needs as ghosts (collective): those whose boxes
        (the first ``nl`` rows of ``self.boxes``, grown by the half margin ``half`` [m])
        overlap a cell of a coarse grid over the model that a box of that rank, grown by
        another half margin, overlaps. Two boxes that meet share a cell, so no pair is
        missed; unlike one bounding box per rank, a rank holding a long block (a base
        under the whole wall) does not take every facet of the others as ghosts."""
        comm = self.comm
        b = self.boxes[:nl]
        lo = np.array([b[:, 0].min(), b[:, 1].min()]) if nl else np.full(2, np.inf)
        hi = np.array([b[:, 2].max(), b[:, 3].max()]) if nl else np.full(2, -np.inf)
        lo = lo - half
        hi = hi + half
        comm.Allreduce(MPI.IN_PLACE, lo, op=MPI.MIN)
        comm.Allreduce(MPI.IN_PLACE, hi, op=MPI.MAX)
        ext = np.maximum(hi - lo, 0.0)
        # about four facets a cell, at most 2**20 cells
        cells = min(max(self.g_facets.shape[0] // 4, 64), 1 << 20)
        h = max(math.sqrt(ext[0] * ext[1] / cells), (ext[0] + ext[1]) / cells, 1e-12)
        gx, gy = (int(min(max(math.ceil(e / h), 1), cells)) for e in ext)
        occ = np.zeros((gy, gx), dtype=np.uint8)
        mark_cells(self.boxes, nl, lo, 1.0 / h, gx, gy, half, occ)
        occs = comm.allgather(occ)
        hit = np.zeros(nl, dtype=np.bool_)
        send = []
        for r in range(comm.size):
            if r == comm.rank or nl == 0:
                send.append(np.zeros(0, np.int64))
                continue
            boxes_on_cells(self.boxes, nl, lo, 1.0 / h, gx, gy, occs[r], hit)
            send.append(self.local_gid[hit])
        return send

    def _sync(self, v: np.ndarray) -> None:
        """Current displacement and velocity of local and ghost nodes."""
        nloc = 2 * self.n_local_nodes
        self.u[:nloc] = self.model.u.x.array[:nloc]
        self.v[:nloc] = v[:nloc]
        if self.exchange is not None and self.comm.size > 1:
            self._uv[:, :2] = self.model.u.x.array[:nloc].reshape(-1, 2)
            self._uv[:, 2:] = v[:nloc].reshape(-1, 2)
            self.exchange.forward(self._uv, self._ghost_uv)
            self.u[nloc:] = self._ghost_uv[:, :2].ravel()
            self.v[nloc:] = self._ghost_uv[:, 2:].ravel()

    # ------------------------------------------------------------------ time step
    def stable_omega2(self) -> dict[str, float]:
        """Bound of ω² [1/s²] the contact springs add to the block nodes (collective).

        A boundary node's contact springs are at most ε w L_adj (L_adj: the length of
        its two facets, ε the stiffer of the normal and the tangential penalty its
        material has with any material), coupling its mass to the lightest boundary
        node of the model.
        """
        m = self.model
        nodes, k = self._local_spring_bound()
        k = k * max(1.0, self.settings.tangential_ratio)
        mask, _ = m.prescribed_arrays(0.0)
        free = (mask[2 * nodes] == 0) | (mask[2 * nodes + 1] == 0)
        nodes = nodes[free]  # a node whose motion is prescribed is not integrated
        mn = m.mass[2 * nodes]
        m_min = self.comm.allreduce(float(mn.min()) if mn.size else np.inf, op=MPI.MIN)
        w2 = k[nodes] * (1.0 / mn + 1.0 / m_min) if nodes.size else np.zeros(1)
        return {BLOCKS: self.comm.allreduce(float(np.max(w2)), op=MPI.MAX)}

    def _local_spring_bound(self):
        """Boundary nodes of this rank and ε_n w L_adj [N/m] per local node (the normal
        springs' bound)."""
        m = self.model
        fl = self._input_to_local[self.g_facets[self.local_gid]]
        eps = self.eps_table.max(axis=1)[self.g_material[self.local_gid]]
        k = np.zeros(m.n_nodes)
        w = eps * m.width * self.g_length[self.local_gid]
        np.add.at(k, fl[:, 0], w)
        np.add.at(k, fl[:, 1], w)
        return np.unique(fl), k

    def stable_damping(self) -> dict[str, float]:
        """Bound of the rate γ [1/s] the restitution's dampers add to the block nodes
        (the largest eigenvalue of M⁻¹C; collective; none for e = 1).

        The dampers between two blocks add up to c = 2 ζ √(K m) (``_kernels.
        contact_damping``), each pass taking the share of its stiffness k = ε_n w ℓ s, and
        a node the part of a pass its shape function gives. For a node whose two facets
        (lengths h_j) carry zones covering the fractions λ_j of them, the node's share of
        a zone is at most 1 − λ_j/2 (a zone starting at the node), so (Cauchy–Schwarz)
        c_node ≤ 2 ζ √m Σ k_j (1 − λ_j/2) / √(Σ k_j) ≤ 2 ζ √(m ε_n w Σ h_j λ_j
        (1 − λ_j/2)²) ≤ √(8/27) · 2 ζ √(k m), k = ε_n w Σ h_j the node's spring bound
        (``stable_omega2``; λ(1 − λ/2)² is largest, 8/27, at λ = 2/3), and m ≤ M, the
        mass of the node's own block (1/m ≥ 1/M). The largest ζ is that of a face. A
        damper couples the node to a node of another block, at least the lightest free
        boundary node m_o of the other blocks (none when every other block is held):
        γ ≤ c_node (1/m_node + 1/m_o). The bound is approached by a block landing on one
        facet at its corner; a flat contact of n facets stays near 1/√n of it. (A node
        in contact with J other blocks at once could exceed it by up to √J.)
        """
        zeta = max(self.zeta)
        if zeta == 0.0:
            return {}
        m = self.model
        nb = m.blocks.n_blocks
        nodes, k = self._local_spring_bound()
        mask, _ = m.prescribed_arrays(0.0)
        free = (mask[2 * nodes] == 0) | (mask[2 * nodes + 1] == 0)
        nodes = nodes[free]
        mn = m.mass[2 * nodes]
        blk = m.node_block[nodes]
        # the lightest free boundary node of each block, then of the other blocks
        lightest = np.full(nb, np.inf)
        np.minimum.at(lightest, blk, mn)
        self.comm.Allreduce(MPI.IN_PLACE, lightest, op=MPI.MIN)
        order = np.argsort(lightest)
        first = order[0]
        other = np.full(nb, lightest[first])
        if nb > 1:
            other[first] = lightest[order[1]]
        c = math.sqrt(8.0 / 27.0) * 2.0 * zeta * np.sqrt(k[nodes] * self.block_mass[blk])
        gamma = float(np.max(c * (1.0 / mn + 1.0 / other[blk]))) if nodes.size else 0.0
        return {BLOCKS: self.comm.allreduce(gamma, op=MPI.MAX)}

    def _block_inertia(self) -> None:
        """Mass M [kg], reference centroid [m] and polar moment of inertia I [kg m²] about
        it of every block, from the lumped nodal masses (every rank, collective)."""
        m = self.model
        nb = m.blocks.n_blocks
        mass = m.mass[0 : 2 * m.n_nodes : 2]
        # every sum over a block's nodes in their input order: the same on any number of
        # ranks (a block lies on one rank; the others add zeros)
        o = np.argsort(m.node_input, kind="stable").astype(np.int64)
        # each block's nodes in input order, block after block (for _block_centroids)
        self._block_nodes = o[np.argsort(m.node_block[o], kind="stable")]
        self._block_ptr = np.zeros(nb + 1, dtype=np.int64)
        np.cumsum(np.bincount(m.node_block, minlength=nb), out=self._block_ptr[1:])
        sums = np.zeros((nb, 3))
        np.add.at(sums, m.node_block[o], np.c_[mass, mass[:, None] * m.X][o])
        sums = self.comm.allreduce(sums)
        self.block_mass = sums[:, 0]
        g = sums[:, 1:] / np.where(sums[:, :1] > 0, sums[:, :1], 1.0)
        inertia = np.zeros(nb)
        np.add.at(inertia, m.node_block[o],
                  (mass * np.sum((m.X - g[m.node_block]) ** 2, axis=1))[o])
        self.block_polar = self.comm.allreduce(inertia)
        self.centroid = np.ascontiguousarray(g)
        self._moments = np.zeros((nb, 2))
        self._mass_safe = np.where(self.block_mass > 0, self.block_mass, 1.0)[:, None]
        self.inv_mass = np.zeros(nb)
        self.inv_inertia = np.zeros(nb)

    def _moving_blocks(self) -> None:
        """Which blocks move (collective): a block with a prescribed dof counts as
        immovable for the dampers (1/M = 1/I = 0)."""
        m = self.model
        n = m.n_nodes
        mask, _ = m.prescribed_arrays(0.0)
        held = np.bincount(m.node_block, weights=mask[0 : 2 * n : 2] + mask[1 : 2 * n : 2],
                           minlength=m.blocks.n_blocks).astype(float)
        held = self.comm.allreduce(held)
        moving = (held == 0) & (self.block_mass > 0)
        self.inv_mass = np.where(moving, 1.0 / self._mass_safe[:, 0], 0.0)
        self.inv_inertia = np.where(moving & (self.block_polar > 0),
                                    1.0 / np.where(self.block_polar > 0, self.block_polar,
                                                   1.0), 0.0)

    def _block_centroids(self, parallel: bool) -> None:
        """The blocks' current centroids [m] (collective in parallel; no allocation)."""
        m = self.model
        K.block_moments(m.X, m.u.x.array, m.mass, self._block_ptr, self._block_nodes,
                        self._moments)
        if parallel:
            self.comm.Allreduce(MPI.IN_PLACE, self._moments, op=MPI.SUM)
        np.divide(self._moments, self._mass_safe, out=self.centroid)

    def add_rowsum(self, rows) -> None:
        """Bound of Σ_j |K_ij| [N/m] of the contact springs into the block rows (for the
        fictitious masses of dynamic relaxation): twice the node's spring bound."""
        _, k = self._local_spring_bound()
        rows[BLOCKS] += np.repeat(2.0 * max(1.0, self.settings.tangential_ratio) * k, 2)

    # ------------------------------------------------------------------ neighbours
    def rebuild(self, v: np.ndarray | None = None) -> None:
        """New candidate pairs from the ADT; tangential history carried over by key.

        Collective: ghost facets are exchanged between ranks.
        """


        comm = self.comm
        v = self.model.v if v is None else v
        half = 0.5 * self.margin
        if comm.size > 1:
            # local facet boxes at the current positions -> this rank's inflated bbox
            self._build_extended(np.zeros(0, np.int64), [np.zeros(0, np.int64)] * comm.size)
            self._sync(v)
            facet_boxes(self.X, self.u, self.facets, half, self.boxes)
            nl = self.local_gid.size
            send = self._ghosts_for(nl, half)
            received = exchange_ids(comm, send)
            self._build_extended(np.concatenate(received), send)
        self._sync(v)
        facet_boxes(self.X, self.u, self.facets, half, self.boxes)
        nc = self.n_candidates
        pairs = np.asarray(self_pairs(np.ascontiguousarray(self.boxes[:nc]),
                                      self.facet_block[:nc]), dtype=np.int64).reshape(-1, 2)
        # a cross-rank pair is in the lists of both ranks (each sums the forces on its
        # own nodes over all their pairs, in the pairs' key order: the same sum as on one
        # rank), counted in the energies and the tangent by the lower; ghost-ghost never
        ra = self.facet_rank[pairs[:, 0]]
        rb = self.facet_rank[pairs[:, 1]]
        me = comm.rank
        keep = (ra == me) | (rb == me)
        pairs, ra, rb = pairs[keep], ra[keep], rb[keep]
        counted = np.minimum(ra, rb) == me
        nb = self.model.blocks.n_blocks
        ba = self.facet_block[pairs[:, 0]]
        bb = self.facet_block[pairs[:, 1]]
        both = np.isin(np.minimum(ba, bb) * nb + np.maximum(ba, bb), self.bonded_pairs)
        if self.apart_table.any():
            bm = self.model.blocks.block_material
            both |= self.apart_table[bm[ba], bm[bb]]
        pairs, counted = pairs[~both], counted[~both]
        # orient each pair by global facet id, so its two passes keep their meaning
        ga = self.ext_gid[pairs[:, 0]]
        gb = self.ext_gid[pairs[:, 1]]
        swap = ga > gb
        pairs[swap] = pairs[swap][:, ::-1]
        n_g = self.g_facets.shape[0]
        keys = np.minimum(ga, gb) * n_g + np.maximum(ga, gb)
        if self.excluded.size and keys.size:
            free = ~np.isin(keys, self.excluded)
            pairs, keys, counted = pairs[free], keys[free], counted[free]
        hist = [np.zeros((pairs.shape[0], 2)) for _ in range(3)]
        # the trial history from the current pairs; the committed one from the last
        # commit's pairs when there was one (the current pair set may come from a
        # rebuild at a failed iterate that lost some of them)
        sources = [(self.keys, (self.tau, self.tforce), (hist[0], hist[2]))]
        if self._committed is None:
            sources.append((self.keys, (self.tau_c,), hist[1:2]))
        else:
            sources.append((self._committed[0], self._committed[1:], hist[1:2]))
        for old_keys, olds, news in sources:
            if not (old_keys.size and keys.size):
                continue
            pos = np.minimum(np.searchsorted(old_keys, keys), old_keys.size - 1)
            hit = old_keys[pos] == keys
            for new, old in zip(news, olds, strict=True):
                if old.shape[0] == old_keys.size:
                    new[hit] = old[pos[hit]]
        order = np.argsort(keys, kind="stable")
        self._install(pairs[order], keys[order], counted[order], hist[0][order],
                      hist[1][order], hist[2][order])
        self.travel = 0.0
        self.since = 0
        self.rebuilds += 1
        self._u_rebuild[:] = self.model.u.x.array[: self._u_rebuild.size]

    def _install(self, pairs, keys, counted, tau, tau_c, tforce=None) -> None:
        """Take the candidate pairs (sorted by key), which of them this rank counts, their
        history, and the arrays that follow from them."""
        self.pairs = np.ascontiguousarray(pairs, dtype=np.int64).reshape(-1, 2)
        self.keys = np.asarray(keys, dtype=np.int64)
        self.counted = np.ascontiguousarray(counted, dtype=float)
        # the pairs' forces on their nodes, and the lists that sum them into this rank's
        self.fp = np.zeros((self.pairs.shape[0], 8))
        self.fdp = np.zeros((self.pairs.shape[0], 8))
        self._zones = np.zeros((self.pairs.shape[0], 2, K.N_WORK))
        self._gnodes, self._gptr, self._gidx = node_lists(
            np.c_[self.facets[self.pairs[:, 0]], self.facets[self.pairs[:, 1]]],
            self.n_local_nodes)
        self.tau, self.tau_c = (np.ascontiguousarray(h, dtype=float).reshape(-1, 2)
                                for h in (tau, tau_c))
        # the passes' friction forces at the last evaluation [N] (their dissipation)
        self.tforce = (np.zeros_like(self.tau) if tforce is None else
                       np.ascontiguousarray(tforce, dtype=float).reshape(-1, 2))
        self._pair_stiffness()
        ma = self.facet_material[self.pairs[:, 0]]
        mb = self.facet_material[self.pairs[:, 1]]
        self.mu = np.ascontiguousarray(self.mu_table[ma, mb])
        self._no_damping = np.zeros(self.pairs.shape[0])
        self.cdamp = np.zeros(self.pairs.shape[0])
        # the pairs of blocks in contact (slots of the damper)
        ba = self.facet_block[self.pairs[:, 0]]
        bb = self.facet_block[self.pairs[:, 1]]
        nb = self.model.blocks.n_blocks
        bkeys, self.slot = np.unique(np.minimum(ba, bb) * nb + np.maximum(ba, bb),
                                     return_inverse=True)
        self.slot = np.ascontiguousarray(self.slot, dtype=np.int64)
        self.slot_block = np.ascontiguousarray(np.c_[bkeys // nb, bkeys % nb],
                                               dtype=np.int64)
        self._acc = np.zeros((bkeys.size, K.N_ACC))
        if self.zeta[0] > 0.0:
            self._moving_blocks()
        la = self.facet_length[self.pairs[:, 0]]
        lb = self.facet_length[self.pairs[:, 1]]
        ta = self.block_thickness[self.facet_block[self.pairs[:, 0]]]
        tb = self.block_thickness[self.facet_block[self.pairs[:, 1]]]
        self.depth = self.settings.depth_factor * np.minimum(np.minimum(la, lb),
                                                             np.minimum(ta, tb))

    def update(self, state: State) -> None:
        """Rebuild when due, or when the relative travel could exceed the margin (the
        block velocities of ``state`` [m/s] over its step ``dt`` [s]; collective)."""
        v, dt = state.v[BLOCKS], state.dt
        if state.static:
            # a static evaluation: the travel is the displacement since the last rebuild
            moved = 2.0 * max_speed(state.u[BLOCKS][: self._u_rebuild.size] - self._u_rebuild)
            if (self.since >= self.settings.rebuild_every or self.travel == math.inf
                    or self.comm.allreduce(moved, op=MPI.MAX) > self.margin):
                self.rebuild(v)
            self.since += 1
            return
        step_travel = 2.0 * max_speed(v) * dt
        step_travel = self.comm.allreduce(step_travel, op=MPI.MAX)
        if (self.since >= self.settings.rebuild_every
                or self.travel + step_travel > self.margin):
            self.rebuild(v)
        self.travel += step_travel
        self.since += 1

    # ------------------------------------------------------------------ forces
    def add_forces(self, state: State) -> None:
        """Add the contact forces [N] at the current displacement to ``state.f`` (the
        velocities give the tangential slip increment v·dt and the dampers' gap rates;
        ``state.damping`` switches the restitution's dampers, off in dynamic relaxation
        and static solutions; collective)."""
        f, v, dt = state.f[BLOCKS], state.v[BLOCKS], state.dt
        self._sync(v)
        if state.static:  # backward Euler from the committed history
            self.tau[:] = self.tau_c
            dt = 1.0
        cdamp = self._no_damping
        live = state.damping and not state.static and self.zeta[0] > 0.0
        if live:
            self._block_centroids(self.comm.size > 1)
            K.contact_damping(
                self.X, self.u, self.facets, self.fprev, self.fnext, self.pairs,
                self.facet_block, self.eps_n, self.depth, self.model.width, self.slot,
                self.slot_block, self.inv_mass, self.inv_inertia, self.centroid,
                self.zeta[0], self.zeta[1], self._acc, self.cdamp, self._work, self._zones)
            cdamp = self.cdamp
        # the dampers' kernel found every pass's zone at these positions: reused
        K.facet_facet_forces(
            self.X, self.u, self.v, self.facets, self.fprev, self.fnext, self.pairs,
            self.eps_n, self.eps_t, self.mu, cdamp, self.depth, self.model.width, dt,
            self.tau, self.tforce, self.counted, self.fp, self.fdp, self.energy, self._work,
            self._zones, live,
        )
        nloc = 2 * self.n_local_nodes
        gather_rows(self.fp, self._gnodes, self._gptr, self._gidx, f)
        self.dissipated += self.energy[2]
        self._account_dampers(live, v[:nloc], dt)

    def _account_dampers(self, live: bool, v: np.ndarray, dt: float) -> None:
        """Add the dampers' dissipation of the step before: minus the work of their forces
        fd(n−1) over its midpoint increment (u(n) − u(n−2))/2, as the explicit solver
        counts work, so the energy account closes (evaluated with the velocity the damper
        sees, v(n−½), it would be off by O(ζ ω dt) of the impact energy: 10-20 % at the
        default step); keep fd(n), u(n) and u(n−1) = u(n) − dt v(n−½) for the next call
        (collective when ``live``)."""
        nloc = 2 * self.n_local_nodes
        u_now = self.model.u.x.array[:nloc]
        if self._fd_live:
            self.damped -= K.nodal_midpoint_work(self._fd, self._fd_nodes, u_now, self._u2)
        # u(n−1) as the solver had it (not the u of the last call: there was none before
        # the first step, and a static evaluation in between is no step), kept at the
        # nodes the dampers act on (fd is zero elsewhere, and is zeroed where it was)
        K.keep_damper_terms(self._fd, self._fd_nodes, self._gnodes, u_now, v, dt,
                            self._u1, self._u2)
        self._fd_nodes = self._gnodes
        self._fd_live = live
        if live:
            gather_rows(self.fdp, self._gnodes, self._gptr, self._gidx, self._fd)

    def add_tangent(self, tangent, state: State) -> None:
        """The consistent tangent −∂f/∂u [N/m] of the pairs in contact into ``tangent`` (the
        positions of the last ``add_forces``; a cross-rank pair by the rank counting it,
        its rows of the other rank's nodes sent by PETSc)."""
        if self._ext_dofs is None or self._ext_dofs.size != self.u.size:
            self._ext_dofs = tangent.node_dofs(self.ext_input)
        n = self.pairs.shape[0]
        rows = np.empty(128 * n, dtype=np.int64)
        cols = np.empty(128 * n, dtype=np.int64)
        vals = np.empty(128 * n)
        fbuf = np.zeros(8)
        nent = K.facet_facet_tangent(
            self.X, self.u, self.v, self.facets, self.fprev, self.fnext, self.pairs,
            self.eps_n, self.eps_t, self.mu, self.depth, self.model.width, self.tau_c,
            self.tau, self.fd_step, self.counted, fbuf, self._work, rows, cols, vals)
        tangent.add(self._ext_dofs[rows[:nent]], self._ext_dofs[cols[:nent]], vals[:nent])

    @property
    def fd_step(self) -> float:
        """Finite-difference step [m] of the tangent: 1e-10 of the mean facet length. It
        must lie well below the penetrations and the contact zones' slivers (at a stiff
        penalty, ε_n ~ 1e13 Pa/m, lightly loaded joints penetrate ~1e-10 m, and a step
        of 1e-9 of the facet length straddled the kinks there: the tangent missed the
        normal stiffness of those pairs and Newton stalled); the force is piecewise
        polynomial in the positions, so the truncation error is nil, and the round-off
        of X + u (~1e-16 m per metre of coordinate) costs ~1e-5 of the stiffness."""
        return 1e-10 * self.h

    def commit(self) -> None:
        """Keep the tangential history as the committed one (static evaluations start
        from it)."""
        self.tau_c[:] = self.tau
        self._committed = (self.keys.copy(), self.tau_c.copy())

    def restore(self) -> None:
        """Back to the committed tangential history."""
        self.tau[:] = self.tau_c

    def energies(self) -> dict[str, float]:
        """Stored normal/tangential penalty energy, and the energy dissipated by friction
        and by the normal dampers of the restitution [J] (collective), all at the last
        evaluation, u(n): the dampers' dissipation up to u(n) is minus the work of their
        forces over the solver's midpoint increments, the last one's up to u(n) only,
        fd(n)·(u(n) − u(n−1))/2 (the explicit solver's account carries every store to
        the half step by the work of its forces over the other half)."""
        pending = (-K.nodal_midpoint_work(self._fd, self._fd_nodes, self._u1, self._u2)
                   if self._fd_live else 0.0)
        n, t, d, c = self.comm.allreduce(np.array([self.energy[0], self.energy[1],
                                                   self.dissipated, self.damped + pending]))
        return {"stored": float(n + t), "dissipated": float(d + c),
                "contact_normal": float(n), "contact_tangential": float(t),
                "friction_dissipated": float(d), "damper_dissipated": float(c)}

    def _state_changed(self) -> None:
        # the committed history is the one just set
        self._committed = (self.keys.copy(), self.tau_c.copy())
        self._fd_live = False
        self.tforce = np.zeros_like(self.tau)
        self.rebuild(np.zeros_like(self.model.v))

    #: what :meth:`checkpoint_state` keeps beyond :meth:`state`
    _checkpoint_extra = ("travel", "since", "_u_rebuild", "_fd", "_u1", "_u2", "_fd_nodes",
                         "_fd_live", "_work", "_acc", "cdamp", "fp", "fdp", "inv_mass",
                         "inv_inertia", "tforce")

    def checkpoint_state(self) -> dict:
        """:meth:`state` and what a resumed run needs to go on exactly as the run would
        have: the candidate pairs and the ghost facets they were found among (no rebuild
        on resume), the rebuild counters (travel [m], steps since the last rebuild, the
        displacement [m] there), the committed history by key and the dampers' work
        terms."""
        st = self.state()
        st["__ext_args"] = self._ext_args
        st["__pairs"] = self.pairs.copy()
        st["__counted"] = self.counted.copy()
        st["__committed"] = (None if self._committed is None
                             else tuple(a.copy() for a in self._committed))
        for k in self._checkpoint_extra:
            v = getattr(self, k)
            st["__" + k] = v.copy() if isinstance(v, np.ndarray) else v
        return st

    def set_checkpoint_state(self, st) -> None:
        """Take a state of :meth:`checkpoint_state` (collective in parallel: the ghost
        exchange is set up again)."""
        st = dict(st)
        ghost, send = st.pop("__ext_args")
        pairs = st.pop("__pairs")
        counted = st.pop("__counted")
        committed = st.pop("__committed")
        extra = {k: st.pop("__" + k) for k in self._checkpoint_extra}
        for k in self.state_attributes:
            if k not in st:
                raise KeyError(f"{type(self).__name__}: state lacks {k!r}")
        self.excluded = np.array(st["excluded"], dtype=np.int64)
        self.bonded_pairs = np.array(st["bonded_pairs"], dtype=np.int64)
        self.energy[...] = st["energy"]
        self.dissipated = float(st["dissipated"])
        self.damped = float(st["damped"])
        self.rebuilds = int(st["rebuilds"])
        self._build_extended(ghost, send)
        self._install(pairs, st["keys"], counted, st["tau"], st["tau_c"])
        self._committed = None if committed is None else tuple(a.copy() for a in committed)
        for k, v in extra.items():
            cur = getattr(self, k)
            if isinstance(cur, np.ndarray) and isinstance(v, np.ndarray) \
                    and cur.shape == v.shape:
                cur[...] = v
            else:
                setattr(self, k, v.copy() if isinstance(v, np.ndarray) else v)
        self._sync(self.model.v)

    def set_layers(self, kn: np.ndarray, ks: np.ndarray) -> None:
        """The stiffness of the joint layer on each global facet: ``kn``, ``ks`` [Pa/m],
        NaN where no joint bonds the facet (the joints tell it, :class:`Joints`).

        With ``ContactSettings.through_layers`` (off by default), a pair with a facet on
        a joint layer is a contact through that layer (the faces of a joint handed over;
        a face slid along the layer onto the next; a corner pressed through the layer
        onto the face beside it): its penalties are the softest layer's k_n and k_s of
        its two facets where these are softer than its own. So a joint handed over under
        compression keeps its force (a 10 mm sand layer, k_n = 5e9 Pa/m, compressed 40 µm
        under 0.2 MPa, met the block penalty of 4e12 Pa/m as 160 MPa) and the layer keeps
        its compliance after it breaks. Never stiffer than the contact's own penalty,
        whose stable time step the explicit solver takes.
        """
        kn = np.asarray(kn, dtype=float)
        ks = np.asarray(ks, dtype=float)
        if kn.shape != self.g_layer_kn.shape or ks.shape != kn.shape:
            raise ValueError("set_layers needs one kn and one ks per boundary facet")
        if np.any(kn <= 0) or np.any(ks <= 0):
            raise ValueError("layer stiffnesses must be > 0 (NaN: no layer)")
        self.g_layer_kn = kn.copy()
        self.g_layer_ks = ks.copy()
        if hasattr(self, "ext_gid"):  # pairs installed: their penalties again
            self._pair_stiffness()

    def _pair_stiffness(self) -> None:
        """The pairs' penalties ``eps_n``, ``eps_t`` [Pa/m]: the materials' table, and
        with ``ContactSettings.through_layers`` a joint layer's where softer
        (:meth:`set_layers`)."""
        ma = self.facet_material[self.pairs[:, 0]]
        mb = self.facet_material[self.pairs[:, 1]]
        self.eps_n = np.ascontiguousarray(self.eps_table[ma, mb])
        self.eps_t = self.settings.tangential_ratio * self.eps_n
        if not self.settings.through_layers or self.pairs.shape[0] == 0:
            return
        ga = self.ext_gid[self.pairs[:, 0]]
        gb = self.ext_gid[self.pairs[:, 1]]
        # fmin: NaN (no layer) gives way to a number
        self.eps_n = np.fmin(self.eps_n, np.fmin(self.g_layer_kn[ga], self.g_layer_kn[gb]))
        self.eps_t = np.fmin(self.eps_t, np.fmin(self.g_layer_ks[ga], self.g_layer_ks[gb]))

    def exclude(self, keys: np.ndarray, bonded_pairs: np.ndarray) -> None:
        """Leave out the facet pairs ``keys`` (min·n + max of global facet ids: bonded
        joints) and every facet pair between two blocks of ``bonded_pairs`` (min·n + max
        of block ids: blocks joined by intact joints, which carry their contact); the
        candidates are found again before the next step."""
        self.excluded = np.sort(np.asarray(keys, dtype=np.int64))
        self.bonded_pairs = np.sort(np.asarray(bonded_pairs, dtype=np.int64))
        self.since = self.settings.rebuild_every

    def active_pairs(self) -> np.ndarray:
        """(k, 2) global facet ids of the pairs in contact now, on every rank (diagnostic,
        collective)."""
        self._sync(self.model.v)
        active = np.zeros(self.pairs.shape[0], dtype=bool)
        for k, (a, b) in enumerate(self.pairs):
            for fs, fm in ((b, a), (a, b)):
                K._pass_zone(self.X, self.u, self.facets, self.fprev, self.fnext, fs, fm,
                             self.depth[k], self._work)
                active[k] |= self._work[K.Z_ACTIVE] > 0
        mine = self.ext_gid[self.pairs[active & (self.counted > 0)]].reshape(-1, 2)
        allp = np.concatenate(self.comm.allgather(mine))
        return allp[np.lexsort((allp[:, 1], allp[:, 0]))] if allp.size else allp
