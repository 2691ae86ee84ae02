"""Bonded joints: mortar joints between units and potential cracks inside units.

At set-up, boundary facets of different blocks that coincide (collinear, facing each other,
overlapping, within a tolerance) are paired into joint *segments*. Each segment carries two
integration points at the ends of the overlap (Lobatto/nodal integration, which keeps
interface tractions free of the oscillations Gauss points give), and each point carries the
composite interface law of Lourenço & Rots (:mod:`._kernels`): tension cut-off with
exponential softening (G_fI), Coulomb friction with softening cohesion (G_fII) and
dilatancy, and a compression cap with hardening and softening.

The joint material of a pair of blocks is chosen, first match wins, by

1. ``where`` rules: a predicate of the segment midpoint [m] (a ring interface, a zone of
   decayed mortar);
2. ``cracks``: pieces of the same fractured unit (:meth:`BlockMesh.fractured`) get the
   crack law of the unit's material;
3. ``materials``: the pair of block material names, in either order.

``None`` as a joint material means a dry joint: no bond, the facets are left to the
frictional contact (:class:`~masonry_fdem.interactions.BlockContact`).

A fully softened joint is Coulomb friction without tension, i.e. frictional contact with
the joint's stiffness. A segment whose points have all softened (to ``release_ratio`` of
their strength) and opened is handed over to the block contact, so no force jumps; so is one that
has slid by more than half its length (the two agree where the contact's penalty is the
joint's k_n: with ``ContactSettings(through_layers=True)`` the contact through a joint
layer takes the layer's k_n and k_s where softer than its own; by default a segment
handed over while pressed meets the contact's penalty), and one whose two facets have
turned against each other by more than ``release_turn`` (a piece swung open about one
closed end). While a segment is bonded, the block contact ignores its facet pair, and
every facet pair of two blocks joined only by bonded segments.

Parallel: every rank knows every segment; a segment is evaluated by every rank holding one
of its two blocks (the nodes of the other side exchanged every step), and each rank sums
the forces on its own nodes over their points in global order — the same sums, to the
bit, on any number of ranks. The rank of the block of its lower facet id counts it (in
the energies, the tangent and the hand-over to the contact).

Consistent tangent (``add_tangent``, static Newton solver): per integration point, central
differences of the point's own force kernel in its 8 dofs, at the committed history (a
numerical algorithmic tangent, Miehe 1996; step and accuracy in :mod:`._kernels`). The
rank computing a point adds its entries, the ghost nodes by their global dof numbers.

Units: SI — stiffnesses in Pa/m, strengths in Pa, fracture energies in N/m (J/m²).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

from mpi4py import MPI

import numpy as np

from masonry_fdem.checks import ImplausibleValueError, check_magnitude, is_allowed
from masonry_fdem.geometry.blockmesh import unit_name
from masonry_fdem.interactions._sums import gather_rows, node_lists
from masonry_fdem.interactions.joints import _kernels as JK
from masonry_fdem.interactions.protocol import BLOCKS, Interaction, State, Tangent

__all__ = ["JointMaterial", "Joints", "JOINT_STATES"]

log = logging.getLogger(__name__)

#: names of the status codes in the joint state field
JOINT_STATES = ("intact", "softening", "open", "sliding", "crushed")


@dataclass(frozen=True)
class JointMaterial:
    """A zero-thickness interface (mortar joint, ring interface, potential crack in a unit).

    Attributes:
        kn, ks: normal and shear stiffness [Pa/m]. For a mortar joint of thickness h_m
            between units, k_n = E_u E_m / (h_m (E_u − E_m)). ``None``: ``penalty`` times
            E/h with E the smaller Young's modulus of the two blocks and h the shorter facet
            (for cracks inside fractured units: the stiffness then scales with the mesh,
            so the elastic compliance the cracks add does not depend on it); k_s = k_n / (2(1+ν)).
        ft: tensile strength [Pa] (0: no tension).
        GfI: mode-I fracture energy [N/m].
        c: cohesion [Pa].
        tan_phi: friction coefficient tan φ.
        GfII: mode-II fracture energy [N/m].
        tan_psi: dilatancy tan ψ0 at zero normal stress and zero slip.
        psi_confinement: σ_u < 0 [Pa], the compressive stress at which dilatancy vanishes
            (None: no effect of confinement).
        psi_decay: δ [1/m], dilatancy decays as exp(−δ κ_slip).
        fc: compressive strength of the cap [Pa] (None: no cap).
        Cs: shear contribution to the cap.
        kappa_p: plastic relative displacement at the cap peak [m].
        Gfc: compressive fracture energy [N/m] (area between the post-peak cap curve and
            the residual strength f_c/7).
        penalty: factor of the default stiffness (see kn).
    """

    kn: float | None = None
    ks: float | None = None
    ft: float = 0.0
    GfI: float = 0.0
    c: float = 0.0
    tan_phi: float = 0.6
    GfII: float = 0.0
    tan_psi: float = 0.0
    psi_confinement: float | None = None
    psi_decay: float = 0.0
    fc: float | None = None
    Cs: float = 9.0
    kappa_p: float = 1e-4
    Gfc: float = 5000.0
    penalty: float = 20.0

    def __post_init__(self) -> None:
        def need(ok, msg):
            if not ok:
                raise ValueError(f"JointMaterial: {msg}")

        for name in ("ft", "GfI", "c", "tan_phi", "GfII", "tan_psi", "psi_decay", "Cs",
                     "kappa_p", "Gfc", "penalty"):
            val = getattr(self, name)
            need(np.isfinite(val) and val >= 0, f"{name} must be finite and >= 0, got {val}")
        for name in ("kn", "ks"):
            val = getattr(self, name)
            need(val is None or (np.isfinite(val) and val > 0), f"{name} must be > 0 Pa/m")
        need(self.ft == 0 or self.GfI > 0, "a tensile strength ft > 0 needs GfI > 0 N/m")
        need(self.c == 0 or self.GfII > 0, "a cohesion c > 0 needs GfII > 0 N/m")
        need(self.penalty > 0, "penalty must be > 0")
        if self.fc is not None:
            need(np.isfinite(self.fc) and self.fc > 0, f"fc must be > 0 Pa, got {self.fc}")
            need(self.kappa_p > 0 and self.Gfc > 0, "a cap needs kappa_p > 0 and Gfc > 0")
        if self.psi_confinement is not None:
            need(self.psi_confinement < 0, "psi_confinement must be < 0 Pa (compression)")
        # magnitudes (off inside masonry_fdem.checks.expert())
        for name, kind in (("kn", "stiffness"), ("ks", "stiffness"), ("ft", "ft"), ("c", "c"),
                           ("fc", "fc"), ("tan_phi", "tan_phi"), ("GfI", "Gf"),
                           ("GfII", "Gf")):
            check_magnitude(name, getattr(self, name), kind, "JointMaterial")
        if self.fc is not None:
            check_magnitude("Gfc", self.Gfc, "Gfc", "JointMaterial")
            if not self.ft < self.fc and not is_allowed("ft", "fc"):
                raise ImplausibleValueError(
                    f"JointMaterial: ft = {self.ft:.4g} Pa is not below fc = {self.fc:.4g} Pa: "
                    "a tensile strength is a small fraction of the compressive one (if you "
                    "mean it: masonry_fdem.checks.expert('ft'))", "ft", self.ft)

    @property
    def bonded(self) -> bool:
        return self.ft > 0 or self.c > 0

    def row(self, E: float, nu: float, h: float) -> np.ndarray:
        """The kernel's property row; E [Pa], ν and h [m] give the default stiffness."""
        kn = self.kn if self.kn is not None else self.penalty * E / h
        ks = self.ks if self.ks is not None else kn / (2.0 * (1.0 + nu))
        if self.ft > 0 and not kn > self.ft**2 / self.GfI:
            raise ValueError(
                f"JointMaterial: kn = {kn:.4g} Pa/m is below ft²/GfI = "
                f"{self.ft**2 / self.GfI:.4g} Pa/m: the softening would snap back")
        if self.c > 0 and not ks > self.c**2 / self.GfII:
            raise ValueError(
                f"JointMaterial: ks = {ks:.4g} Pa/m is below c²/GfII = "
                f"{self.c**2 / self.GfII:.4g} Pa/m: the softening would snap back")
        p = np.zeros(JK.N_PROPS)
        p[JK.P_KN] = kn
        p[JK.P_KS] = ks
        p[JK.P_FT] = self.ft
        p[JK.P_GF1] = self.GfI
        p[JK.P_C] = self.c
        p[JK.P_TANPHI] = self.tan_phi
        p[JK.P_GF2] = self.GfII
        p[JK.P_TANPSI] = self.tan_psi
        p[JK.P_SIGU] = self.psi_confinement if self.psi_confinement is not None else 0.0
        p[JK.P_DELTA] = self.psi_decay
        p[JK.P_FC] = self.fc if self.fc is not None else 0.0
        p[JK.P_CS] = self.Cs
        p[JK.P_KP] = self.kappa_p
        p[JK.P_GFC] = self.Gfc
        return p


Rule = tuple[Callable[[np.ndarray], bool], "JointMaterial | None"]


def coincident_facets(x: np.ndarray, facets: np.ndarray, facet_block: np.ndarray,
                      tol: float) -> np.ndarray:
    """Overlaps of facets of different blocks that lie on each other.

    Returns:
        (k, 4) float array: facet a, facet b (a < b), overlap start and end as
        arclengths [m] along a.
    """
    from masonry_fdem.interactions.search.adt import self_pairs

    p0 = x[facets[:, 0]]
    p1 = x[facets[:, 1]]
    boxes = np.c_[np.minimum(p0, p1) - tol, np.maximum(p0, p1) + tol]
    pairs = np.asarray(self_pairs(np.ascontiguousarray(boxes),
                                  np.asarray(facet_block, dtype=np.int64)),
                       dtype=np.int64).reshape(-1, 2)
    if pairs.size == 0:
        return np.zeros((0, 4))
    pairs = np.sort(pairs, axis=1)
    a, b = pairs[:, 0], pairs[:, 1]
    da = p1[a] - p0[a]
    la = np.linalg.norm(da, axis=1)
    ta = da / la[:, None]
    na = np.c_[ta[:, 1], -ta[:, 0]]
    db = p1[b] - p0[b]
    tb = db / np.linalg.norm(db, axis=1)[:, None]
    anti = np.einsum("ij,ij->i", ta, tb) < -(1.0 - 1e-8)
    dist0 = np.abs(np.einsum("ij,ij->i", p0[b] - p0[a], na))
    dist1 = np.abs(np.einsum("ij,ij->i", p1[b] - p0[a], na))
    s0 = np.einsum("ij,ij->i", p0[b] - p0[a], ta)
    s1 = np.einsum("ij,ij->i", p1[b] - p0[a], ta)
    lo = np.maximum(0.0, np.minimum(s0, s1))
    hi = np.minimum(la, np.maximum(s0, s1))
    ok = anti & (dist0 <= tol) & (dist1 <= tol) & (hi - lo > tol)
    return np.c_[a[ok], b[ok], lo[ok], hi[ok]]


class Joints(Interaction):
    """The bonded joints of a model (collective constructor).

    Args:
        model: the :class:`~masonry_fdem.model.Model`.
        materials: joint material per pair of block material names, e.g.
            ``{("brick", "brick"): mortar, ("brick", "base"): mortar}``; None: dry.
        cracks: crack law per material of fractured units (pieces of one unit).
        where: ``[(predicate(midpoint) -> bool, material or None), ...]``, checked first.
        contact: the :class:`~masonry_fdem.interactions.BlockContact` that takes over broken
            joints (and must ignore bonded ones); may be None.
        tolerance: distance [m] within which facets coincide (default 1e-6 of the mean
            boundary facet length).
        check_every: commits between hand-over checks (collective).
        release_ratio: an open joint goes to the contact once its strength has softened
            to this fraction (the force then jumps by at most this fraction of the peak).
        release_turn: a joint whose two facets have turned against each other by more
            than this angle [rad] goes to the contact too: it can only have turned that
            far by breaking (a hinge that opened about one closed end), and a
            zero-thickness interface in the turning frame of the two facets means nothing
            once they are far from parallel (at 180° the frame flips).

    Raises:
        ValueError: two blocks touch along a facet and no joint material is given for them.

    An :class:`~masonry_fdem.interactions.protocol.Interaction`: forces are trial states
    from the committed one; ``commit`` accepts them (``restore`` has nothing to undo).
    """

    name = "joints"
    state_attributes = ("s0", "s1", "alive", "released", "n_commits", "energy", "kprev",
                        "imex_ratio")

    def __init__(
        self,
        model,
        materials: Mapping[tuple[str, str], JointMaterial | None] | None = None,
        *,
        cracks: Mapping[str, JointMaterial] | None = None,
        where: Sequence[Rule] = (),
        contact=None,
        tolerance: float | None = None,
        check_every: int = 10,
        release_ratio: float = 1e-4,
        release_turn: float = math.radians(30.0),
    ):
        self.model = model
        self.comm = comm = model.comm
        self.contact = contact
        self.check_every = int(check_every)
        self.release_ratio = float(release_ratio)
        self.release_cos = math.cos(float(release_turn))
        if self.check_every < 1 or not 0 < self.release_ratio < 1:
            raise ValueError("check_every must be >= 1 and release_ratio in (0, 1)")
        if not 0 < release_turn <= math.pi:
            raise ValueError(f"release_turn must be in (0, pi] rad, got {release_turn}")
        blocks = model.blocks
        names = blocks.material_names
        table: dict[tuple[str, str], JointMaterial | None] = {}
        for (ma, mb), jm in (materials or {}).items():
            for nm in (ma, mb):
                if nm not in names:
                    raise ValueError(f"joint materials name unknown block material {nm!r}; "
                                     f"the model has {list(names)}")
            if jm is not None and not isinstance(jm, JointMaterial):
                raise TypeError(f"joint material of {(ma, mb)} must be a JointMaterial or None")
            table[(ma, mb)] = table[(mb, ma)] = jm
        cracks = dict(cracks or {})
        for nm, jm in cracks.items():
            if nm not in names:
                raise ValueError(f"cracks name unknown block material {nm!r}")
            if not isinstance(jm, JointMaterial):
                raise TypeError(f"crack law of {nm!r} must be a JointMaterial")
        gf = np.asarray(blocks.boundary_facets, dtype=np.int64)
        fblock = np.asarray(blocks.facet_block, dtype=np.int64)
        x = blocks.x
        flen = np.linalg.norm(x[gf[:, 1]] - x[gf[:, 0]], axis=1)
        self.tolerance = tol = float(tolerance) if tolerance is not None else 1e-6 * flen.mean()
        seg = coincident_facets(x, gf, fblock, tol)
        fa = seg[:, 0].astype(np.int64)
        fb = seg[:, 1].astype(np.int64)
        ba, bb = fblock[fa], fblock[fb]
        mat_a = blocks.block_material[ba]
        mat_b = blocks.block_material[bb]
        unit = blocks.block_unit
        la = flen[fa]
        mid = x[gf[fa, 0]] + (0.5 * (seg[:, 2] + seg[:, 3]) / la)[:, None] * (
            x[gf[fa, 1]] - x[gf[fa, 0]])
        # ---- joint material of each segment
        chosen: list[JointMaterial | None] = []
        missing = set()
        for k in range(seg.shape[0]):
            jm = ...
            for pred, rule_mat in where:
                if pred(mid[k]):
                    jm = rule_mat
                    break
            if jm is ...:
                na, nb = names[mat_a[k]], names[mat_b[k]]
                if unit[ba[k]] == unit[bb[k]]:
                    if na not in cracks:
                        raise ValueError(
                            f"unit {unit_name(blocks.block_names[ba[k]])!r} is fractured but "
                            f"no crack law is given for its material {na!r} (cracks=...)")
                    jm = cracks[na]
                elif (na, nb) in table:
                    jm = table[(na, nb)]
                else:
                    missing.add(tuple(sorted((na, nb))))
                    continue
            chosen.append(jm)
        if missing:
            raise ValueError(
                "blocks touch along joints but no joint material is given for the material "
                f"pair(s) {sorted(missing)}; give a JointMaterial, or None for a dry joint")
        bonded = np.array([jm is not None for jm in chosen], dtype=bool)
        # blocks with a dry joint keep their contact with every neighbour
        self.dry_blocks = np.unique(np.r_[ba[~bonded], bb[~bonded]]).astype(np.int64)
        nbk = blocks.n_blocks
        self._dry_pairs = np.unique(np.minimum(ba[~bonded], bb[~bonded]) * nbk
                                    + np.maximum(ba[~bonded], bb[~bonded])).astype(np.int64)
        seg, fa, fb, mid = seg[bonded], fa[bonded], fb[bonded], mid[bonded]
        mats = [jm for jm in chosen if jm is not None]
        #: the joint material of each bonded segment (``seg_mid`` gives where it is)
        self.segment_materials = tuple(mats)
        ba, bb = fblock[fa], fblock[fb]
        # ---- property rows (default stiffness from the blocks' E and the facet length)
        E = np.array([model.materials[n].E for n in names])
        nu = np.array([model.materials[n].nu for n in names])
        ma_, mb_ = blocks.block_material[ba], blocks.block_material[bb]
        use_b = E[mb_] < E[ma_]
        emin = np.where(use_b, E[mb_], E[ma_])
        numin = np.where(use_b, nu[mb_], nu[ma_])
        h = np.minimum(flen[fa], flen[fb])
        rows = np.array([jm.row(emin[k], numin[k], h[k]) for k, jm in enumerate(mats)]
                        ).reshape(-1, JK.N_PROPS)
        self.props, seg_mat = np.unique(rows, axis=0, return_inverse=True)
        if self.props.shape[0] == 0:
            self.props = np.zeros((1, JK.N_PROPS))
        seg_mat = np.asarray(seg_mat, dtype=np.int64).ravel()
        # ---- two integration points per segment, at the ends of the overlap
        nseg = seg.shape[0]
        self.n_segments = nseg
        self.seg_facets = np.c_[fa, fb]
        self.seg_length = seg[:, 3] - seg[:, 2]
        self.seg_mid = mid
        n_g = gf.shape[0]
        self.seg_key = np.minimum(fa, fb) * n_g + np.maximum(fa, fb)
        s_ip = np.c_[seg[:, 2], seg[:, 3]].ravel()
        q_seg = np.repeat(np.arange(nseg), 2)
        qa, qb = fa[q_seg], fb[q_seg]
        ga = s_ip / flen[qa]
        pa = x[gf[qa, 0]] + ga[:, None] * (x[gf[qa, 1]] - x[gf[qa, 0]])
        db = x[gf[qb, 1]] - x[gf[qb, 0]]
        gb = np.einsum("ij,ij->i", pa - x[gf[qb, 0]], db) / np.einsum("ij,ij->i", db, db)
        self.g_ipa = gf[qa]
        self.g_ipb = gf[qb]
        self.g_xia = np.clip(ga, 0.0, 1.0)
        self.g_xib = np.clip(gb, 0.0, 1.0)
        self.g_w = np.repeat(0.5 * self.seg_length, 2) * model.width
        self.g_mat = seg_mat[q_seg]
        self.q_seg = q_seg
        # ---- this rank's points: those of the segments with a block here, in global
        # order; a segment across ranks is held and evaluated by both (each sums the
        # forces on its own nodes over all their points in that order: the same sum
        # as on one rank), counted in the energies, the tangent and the hand-over by
        # the rank of its side-A block (seg_rank)
        block_rank = model.block_ranks()
        self.seg_rank = block_rank[fblock[fa]]
        own_seg = (self.seg_rank == comm.rank) | (block_rank[fblock[fb]] == comm.rank)
        self.local_seg = np.flatnonzero(own_seg)
        self.local_ip = np.flatnonzero(own_seg[q_seg])
        self.counted = np.ascontiguousarray(
            self.seg_rank[q_seg[self.local_ip]] == comm.rank, dtype=float)
        self._counted_i8 = self.counted.astype(np.int8)
        self._setup_nodes(block_rank)
        m = self.local_ip.size
        self.fq = np.zeros((m, 8))
        self._gnodes, self._gptr, self._gidx = node_lists(np.c_[self.ipa, self.ipb],
                                                          self.n_local_nodes)
        self.xia = np.ascontiguousarray(self.g_xia[self.local_ip])
        self.xib = np.ascontiguousarray(self.g_xib[self.local_ip])
        self.w = np.ascontiguousarray(self.g_w[self.local_ip])
        self.ipmat = np.ascontiguousarray(self.g_mat[self.local_ip])
        self._seg_local = np.ascontiguousarray(q_seg[self.local_ip], dtype=np.int64)
        self._seg_done = np.zeros(nseg, dtype=np.int64)  # scratch of _hand_over
        self._seg_turned = np.zeros(nseg, dtype=np.bool_)
        self.alive = np.ones(m, dtype=np.int8)
        self.s0 = JK.empty_state(m)
        self.s1 = JK.empty_state(m)
        self.energy = np.zeros(2)
        self.n_commits = 0
        #: softening integrated implicit–explicit (:meth:`set_softening`)
        self.imex = False
        #: κ1, κ2, κ3 of each point one commit before (the IMEX extrapolation)
        self.kprev = np.zeros((m, 3))
        #: the IMEX extrapolation factor Δt_{n+1}/Δt_n of the next increment
        self.imex_ratio = 1.0
        self._props_x = np.zeros((m, JK.N_PROPS))
        self._ipmat_x = np.arange(m, dtype=self.ipmat.dtype)
        self.released = np.zeros(nseg, dtype=bool)
        self.seg_blocks = np.c_[fblock[fa], fblock[fb]]
        if contact is not None and hasattr(contact, "set_layers"):
            contact.set_layers(*self.facet_layers(gf.shape[0]))
        self._tell_contact()
        # facet -> cell, for the state field
        self._facet_cell = _facet_cells(blocks, gf)
        if comm.rank == 0:
            log.info("joints: %d bonded segments (%d integration points), %d dry",
                     nseg, 2 * nseg, int((~bonded).sum()))

    # ------------------------------------------------------------------ set-up
    def _setup_nodes(self, block_rank: np.ndarray) -> None:
        model = self.model
        comm = self.comm
        blocks = model.blocks
        nloc = model.n_nodes
        in2loc = np.full(blocks.n_nodes, -1, dtype=np.int64)
        in2loc[model.node_input] = np.arange(nloc)
        node_rank = block_rank[blocks.node_block]
        # ghosts: nodes of my points held by other ranks, by owner, sorted
        recv = []
        mine = np.unique(np.r_[self.g_ipa[self.local_ip].ravel(),
                               self.g_ipb[self.local_ip].ravel()])
        for r in range(comm.size):
            recv.append(mine[node_rank[mine] == r] if r != comm.rank
                        else np.zeros(0, np.int64))
        ghosts = np.concatenate(recv) if recv else np.zeros(0, np.int64)
        node_map = in2loc.copy()
        node_map[ghosts] = nloc + np.arange(ghosts.size)
        self.ipa = np.ascontiguousarray(node_map[self.g_ipa[self.local_ip]])
        self.ipb = np.ascontiguousarray(node_map[self.g_ipb[self.local_ip]])
        if np.any(self.ipa < 0) or np.any(self.ipb < 0):
            raise RuntimeError("a joint node is neither local nor a ghost")
        nn = nloc + ghosts.size
        self.n_local_nodes = nloc
        # input ids of the extended nodes (local, then ghosts): global dofs of the tangent
        self.ext_input = np.r_[model.node_input, ghosts].astype(np.int64)
        self.X = np.ascontiguousarray(np.r_[model.X, blocks.x[ghosts]])
        self.u = np.zeros(2 * nn)
        self.f = np.zeros(2 * nn)
        self.exchange = None
        if comm.size > 1:
            from masonry_fdem.parallel import NodeExchange

            send = []
            for r in range(comm.size):
                if r == comm.rank:
                    send.append(np.zeros(0, np.int64))
                    continue
                # r's points: those of the segments with a block on r
                fb_rank = node_rank[self.g_ipb[:, 0]]
                theirs = (self.seg_rank[self.q_seg] == r) | (fb_rank == r)
                nb = np.unique(np.r_[self.g_ipa[theirs].ravel(), self.g_ipb[theirs].ravel()])
                nb = nb[node_rank[nb] == comm.rank]
                send.append(in2loc[nb])
            self.exchange = NodeExchange(comm, send, [len(g) for g in recv])
            self._ghost_u = np.zeros((self.exchange.n_ghost, 2))

    # ------------------------------------------------------------------ solver interface
    def _local_node_bound(self) -> np.ndarray:
        """Per local node Σ_ip max(k_n, k_s) w N_i [N/m] over all points (any rank)."""
        m = self.model
        k = np.zeros(m.blocks.n_nodes)
        alive = np.ones(self.g_w.size, dtype=np.int8)
        alive[np.repeat(self.released, 2)] = 0
        JK.node_spring_bound(self.g_ipa, self.g_ipb, self.g_xia, self.g_xib, self.g_w,
                             self.g_mat, self.props, alive, k)
        return k[m.node_input]

    def stable_omega2(self) -> dict[str, float]:
        """Gerschgorin bound of the ω² [1/s²] the joint springs add (collective)."""
        m = self.model
        rowsum = 2.0 * math.sqrt(2.0) * self._local_node_bound()
        mask, _ = m.prescribed_arrays(0.0)
        free = (mask[0::2] == 0) | (mask[1::2] == 0)
        w2 = rowsum[free] / m.mass[0::2][free] if free.any() else np.zeros(1)
        return {BLOCKS: self.comm.allreduce(float(w2.max()) if w2.size else 0.0, op=MPI.MAX)}

    def add_rowsum(self, rows) -> None:
        """Bound of Σ_j |K_ij| [N/m] of the joint springs into the block rows."""
        rows[BLOCKS] += np.repeat(2.0 * math.sqrt(2.0) * self._local_node_bound(), 2)

    def set_softening(self, integration: str) -> None:
        """How the softening of the joints' law is integrated in a static increment:

        * ``"implicit"`` (the default): backward Euler, every force evaluation returning
          from the committed state with the law's own softening (the consistent
          tangent of the softening branch);
        * ``"imex"``: implicit–explicit (Oliver, Huespe & Cante 2008): the softening
          variables of the increment are extrapolated from the last two committed states
          (:func:`._kernels.explicit_softening_props`) and the strengths held there, so
          within the increment the law is perfectly plastic and Newton cannot cycle
          between a point's softening branch and its unloading; at a converged increment
          the committed state is the implicit return mapping at the converged
          displacement. The error is of the first order in the increment (the softening
          lags one increment): halve the increment to check it.
        """
        if integration not in ("implicit", "imex"):
            raise ValueError(f"softening integration must be 'implicit' or 'imex', got "
                             f"{integration!r}")
        on = integration == "imex"
        if on and not self.imex:
            self.kprev[:] = self.s0[:, [JK.S_K1, JK.S_K2, JK.S_K3]]
        self.imex = on
        self._extrapolate()

    def set_extrapolation(self, ratio: float) -> None:
        """The IMEX extrapolation factor of the next increment, its size over the last
        committed one's (≥ 0; no effect under implicit integration)."""
        if not (math.isfinite(ratio) and ratio >= 0):
            raise ValueError(f"extrapolation ratio must be finite and >= 0, got {ratio}")
        if ratio != self.imex_ratio:
            self.imex_ratio = float(ratio)
            self._extrapolate()

    def _extrapolate(self) -> None:
        if self.imex:
            JK.explicit_softening_props(self.props, self.ipmat, self.s0, self.kprev,
                                        self.imex_ratio, self._props_x)

    def _law(self) -> tuple[np.ndarray, np.ndarray]:
        """(ipmat, props) the force kernels use: the materials, or under IMEX each
        point's row with its strengths frozen."""
        if self.imex:
            return self._ipmat_x, self._props_x
        return self.ipmat, self.props

    def _point_forces(self, u: np.ndarray) -> None:
        """Each point's forces into ``fq`` at the block displacements ``u`` (this rank's
        nodes; the ghosts' exchanged; trial state; collective)."""
        nloc = 2 * self.n_local_nodes
        self.u[:nloc] = u[:nloc]
        if self.exchange is not None:
            self.exchange.forward(self.u[:nloc].reshape(-1, 2), self._ghost_u)
            self.u[nloc:] = self._ghost_u.ravel()
        ipmat, props = self._law()
        JK.joint_forces(self.X, self.u, self.ipa, self.ipb, self.xia, self.xib, self.w,
                        ipmat, props, self.alive, self.counted, self.s0, self.s1,
                        self.fq, self.energy)

    def add_forces(self, state: State) -> None:
        """Add the joint forces [N] at the current displacement (trial state; collective)."""
        self._point_forces(state.u[BLOCKS])
        gather_rows(self.fq, self._gnodes, self._gptr, self._gidx, state.f[BLOCKS])

    def add_tangent(self, K: Tangent, state: State) -> None:
        """The consistent tangent −∂f/∂u [N/m] of the live integration points into ``K``
        (at the displacement of the last :meth:`add_forces`, with the same committed
        history). Each point is added by the rank counting it, its side-B columns and
        rows by the global numbers of the ghost nodes (PETSc sends the rows to their
        owner). Central differences of the force kernel, see :func:`._kernels.joint_tangent`.
        """
        m = self.ipa.shape[0]
        rows = np.empty(64 * m, dtype=np.int64)
        cols = np.empty(64 * m, dtype=np.int64)
        vals = np.empty(64 * m)
        ipmat, props = self._law()
        nent = JK.joint_tangent(self.X, self.u, self.ipa, self.ipb, self.xia, self.xib,
                                self.w, ipmat, props,
                                self.alive * self._counted_i8, self.s0,
                                JK.FD_STEP, rows, cols, vals)
        dofs = K.node_dofs(self.ext_input)
        K.add(dofs[rows[:nent]], dofs[cols[:nent]], vals[:nent])

    def dissipation(self, state: State) -> tuple[float, np.ndarray]:
        """The energy [J] the joints dissipate from the committed state to the current
        displacement, and its gradient [J/m] over this rank's block dofs (collective;
        the static solver's dissipation control). Only the joints' own laws count."""
        nloc = 2 * self.n_local_nodes
        self.u[:nloc] = state.u[BLOCKS][:nloc]
        if self.exchange is not None:
            self.exchange.forward(self.u[:nloc].reshape(-1, 2), self._ghost_u)
            self.u[nloc:] = self._ghost_u.ravel()
        g = np.zeros_like(self.f)
        ipmat, props = self._law()
        d = JK.dissipation_gradient(self.X, self.u, self.ipa, self.ipb, self.xia, self.xib,
                                    self.w, ipmat, props,
                                    self.alive * self._counted_i8, self.s0,
                                    JK.FD_STEP, g)
        out = np.zeros(state.u[BLOCKS].size)
        out[:nloc] = g[:nloc]
        if self.exchange is not None:
            self.exchange.reverse(g[nloc:].reshape(-1, 2), out[:nloc].reshape(-1, 2))
        return float(self.comm.allreduce(d)), out

    def commit(self) -> None:
        """Accept the trial state (every explicit step; a converged DR increment).

        Every ``check_every`` commits, broken open segments (and segments slid by more than
        half their length) are handed over to the block contact (collective).
        """
        if self.imex:
            # the implicit return mapping at the converged displacement (the last
            # evaluated) writes the state committed; its κ's drive the next extrapolation
            JK.joint_forces(self.X, self.u, self.ipa, self.ipb, self.xia, self.xib, self.w,
                            self.ipmat, self.props, self.alive, self.counted, self.s0,
                            self.s1, self.fq, self.energy)
            live = self.alive != 0
            self.kprev[live] = self.s0[live][:, [JK.S_K1, JK.S_K2, JK.S_K3]]
        JK.commit(self.alive, self.s0, self.s1)
        self.n_commits += 1
        self._extrapolate()
        if self.n_commits % self.check_every == 0:
            self._hand_over()

    def _hand_over(self) -> None:
        # a segment goes when both its points are spent (open and softened to
        # release_ratio, or slid by half the segment), or when its facets have turned
        # against each other by more than release_turn
        JK.hand_over_flags(self.X, self.u, self.ipa, self.ipb, self.ipmat, self.props,
                           self.s0, self._seg_local, self.seg_length, self.release_ratio,
                           self.release_cos, self._seg_done, self._seg_turned)
        new = np.flatnonzero(((self._seg_done == 2) | self._seg_turned) & ~self.released
                             & (self.seg_rank == self.comm.rank))
        allnew = np.concatenate(self.comm.allgather(new)).astype(np.int64)
        if allnew.size == 0:
            return
        self.released[allnew] = True
        self.alive[self.released[self._seg_local]] = 0
        self._tell_contact()

    def _tell_contact(self) -> None:
        """The contact ignores the bonded facet pairs, and every facet pair of two blocks
        joined by intact segments only (their joints carry their contact, corners
        included); two blocks with a segment handed over, or a dry joint, between them
        keep their contact, and so do blocks that no segment joins (two fragments, each
        held together by intact cracks, meet by contact)."""
        c = self.contact
        if c is None:
            return
        nb = self.model.blocks.n_blocks
        sb = self.seg_blocks
        key = np.minimum(sb[:, 0], sb[:, 1]) * nb + np.maximum(sb[:, 0], sb[:, 1])
        joined = np.setdiff1d(np.unique(key[~self.released]),
                              np.r_[key[self.released], self._dry_pairs])
        c.exclude(self.seg_key[~self.released], joined)

    def facet_layers(self, n_facets: int) -> tuple[np.ndarray, np.ndarray]:
        """(n_facets,) k_n and k_s [Pa/m] of the joint layer on each global boundary facet
        (the softest of the segments on it), NaN where no segment lies on it; the contact
        takes them for pairs through a layer (:meth:`BlockContact.set_layers`)."""
        seg_mat = self.g_mat[::2]
        f = self.seg_facets.T.ravel()
        out = []
        for col in (JK.P_KN, JK.P_KS):
            k = np.tile(self.props[seg_mat, col], 2)
            lo = np.full(n_facets, np.inf)
            np.minimum.at(lo, f, k)
            out.append(np.where(np.isfinite(lo), lo, np.nan))
        return out[0], out[1]

    def set_friction(self, material: JointMaterial, tan_phi: float) -> int:
        """Give the joints of ``material`` the friction coefficient ``tan_phi`` from now
        on (a continuation in friction: a backfill's interfaces held stuck while it takes
        its weight, then released to their own friction in steps). ``material`` needs an
        explicit ``kn`` and ``ks`` (its joints are then told by their properties).

        Returns:
            The number of property rows changed (0: no joint of that material).
        """
        if material.kn is None or material.ks is None:
            raise ValueError("set_friction needs a joint material with explicit kn and ks")
        if not (np.isfinite(tan_phi) and tan_phi >= 0):
            raise ValueError(f"tan_phi must be finite and >= 0, got {tan_phi}")
        ref = material.row(1.0, 0.0, 1.0)
        other = np.arange(JK.N_PROPS) != JK.P_TANPHI
        rows = np.flatnonzero(np.all(self.props[:, other] == ref[other], axis=1))
        self.props[rows, JK.P_TANPHI] = float(tan_phi)
        self._extrapolate()
        return int(rows.size)

    # ------------------------------------------------------------------ results
    def energies(self) -> dict[str, float]:
        """Elastic energy stored in the joints and energy dissipated by them [J]."""
        el, dis = self.comm.allreduce(np.array([self.energy[JK.E_ELASTIC],
                                                self.energy[JK.E_DISSIPATED]]))
        return {"stored": float(el), "dissipated": float(dis), "joint_elastic": float(el),
                "joint_dissipated": float(dis)}

    def _state_changed(self) -> None:
        self._tell_contact()
        self._extrapolate()

    def _gather(self, cols) -> np.ndarray:
        """(n_points, len(cols)) committed state columns on every rank, global order."""
        parts = self.comm.allgather((self.local_ip, self.s0[:, cols]))
        out = np.zeros((self.g_w.size, len(cols)))
        for idx, vals in parts:
            out[idx] = vals
        return out

    def point_status(self) -> np.ndarray:
        """(n_points,) committed status of each integration point, two per segment in
        segment order (codes: :data:`JOINT_STATES`; collective)."""
        return self._gather([JK.S_STATUS])[:, 0].astype(np.int64)

    def point_positions(self) -> np.ndarray:
        """(n_points, 2) reference positions [m] of the integration points (on side A)."""
        x = self.model.blocks.x
        a = self.g_ipa
        xi = self.g_xia[:, None]
        return (1.0 - xi) * x[a[:, 0]] + xi * x[a[:, 1]]

    def status(self) -> np.ndarray:
        """(n_segments,) worst status of each segment (codes: :data:`JOINT_STATES`)."""
        st = self._gather([JK.S_STATUS])[:, 0].reshape(-1, 2).max(axis=1).astype(np.int64)
        return st

    def counts(self) -> dict[str, int]:
        """Number of segments in each state (collective)."""
        st = self.status()
        return {name: int(np.sum(st == k)) for k, name in enumerate(JOINT_STATES)}

    def forces_on(self, on, by=None) -> tuple[np.ndarray, np.ndarray]:
        """The forces [N] that the bonded points between the blocks ``by`` and the blocks
        ``on`` exert on ``on``, at the current displacement (collective).

        Args:
            on, by: blocks as :meth:`~masonry_fdem.geometry.BlockMesh.select` takes them
                (names, shell patterns, a centroid predicate); ``by`` None: every other
                block.

        Returns:
            ``(points, forces)``: ``(k, 2)`` reference positions [m] of the integration
            points and ``(k, 2)`` the force each puts on its ``on`` side (x, y), in global
            point order on every rank. Points handed over to the block contact carry no
            joint force and are left out.
        """
        bm = self.model.blocks
        a = np.zeros(bm.n_blocks, dtype=bool)
        a[bm.select(on)] = True
        b = ~a if by is None else np.zeros(bm.n_blocks, dtype=bool)
        if by is not None:
            b[bm.select(by)] = True
        self._point_forces(self.model.u.x.array)  # as add_forces computes them
        sb = self.seg_blocks[self.q_seg[self.local_ip]]
        on_a = a[sb[:, 0]] & b[sb[:, 1]]
        on_b = a[sb[:, 1]] & b[sb[:, 0]]
        # each point once (the rank that counts it), alive
        keep = (on_a | on_b) & (self.counted > 0) & (self.alive > 0)
        f = np.where(on_a[:, None], self.fq[:, 0:4].reshape(-1, 2, 2).sum(axis=1),
                     self.fq[:, 4:8].reshape(-1, 2, 2).sum(axis=1))
        parts = self.comm.allgather((self.local_ip[keep], f[keep]))
        idx = np.concatenate([p[0] for p in parts]).astype(np.int64)
        order = np.argsort(idx, kind="stable")
        forces = np.concatenate([p[1] for p in parts]).reshape(-1, 2)[order]
        return self.point_positions()[idx[order]], forces

    def tractions(self) -> np.ndarray:
        """(n_points, 2) committed normal and shear traction [Pa] (tension > 0)."""
        return self._gather([JK.S_SN, JK.S_TS])

    def cell_state(self) -> np.ndarray:
        """(n_cells,) worst state of the joints along each cell (BlockMesh order)."""
        st = self.status()
        out = np.zeros(self.model.blocks.n_cells)
        for side in (0, 1):
            np.maximum.at(out, self._facet_cell[self.seg_facets[:, side]], st)
        return out

    def segments(self, scale: float = 1.0) -> np.ndarray:
        """(n_segments, 2, 2) end points [m] of each segment on side A, displaced by
        ``scale`` times the displacement (collective)."""
        blocks = self.model.blocks
        u = self.model.displacement()
        xy = blocks.x + scale * u
        a = self.g_ipa.reshape(-1, 2, 2)
        xi = self.g_xia.reshape(-1, 2)
        return (1 - xi)[..., None] * xy[a[..., 0]] + xi[..., None] * xy[a[..., 1]]


def _facet_cells(blocks, gf: np.ndarray) -> np.ndarray:
    """Cell of each boundary facet (BlockMesh ids)."""
    cells = blocks.cells
    n = blocks.n_nodes
    edges = np.concatenate([cells[:, [0, 1]], cells[:, [1, 2]], cells[:, [2, 0]]])
    owner = np.tile(np.arange(cells.shape[0]), 3)
    key = edges[:, 0] * n + edges[:, 1]
    order = np.argsort(key)
    fk = gf[:, 0] * n + gf[:, 1]
    pos = np.searchsorted(key[order], fk)
    return owner[order][pos]
