"""Contact between disks (granular fill) and deformable blocks, as in the reference
paper's Figure 4: one normal force from the disk's overlap with the block, split among
the touching facets by overlap area, P_n,i = P_n A_i/A, each part directed through the
centroid of its overlap area; Coulomb friction with an incremental spring; the reactions
distributed to the facet nodes (:mod:`masonry_fdem.interactions.disks._facet_kernels`).

Candidate (disk, facet) pairs come from the alternating digital tree of the local facets'
boxes queried with the disks' boxes, both inflated by a travel margin; they are found
again when a disk or a facet node has moved by half the margin. The friction history is
kept per (disk, block) pair, so a disk rolling over a vertex keeps it. When the disks
sort themselves (:class:`~masonry_fdem.interactions.disks.Disks`, a new ``generation``),
the pairs are renumbered to the new storage positions of their disks, with their
history, at the next ``update()``; ``disk_ids`` holds the disks' ``ids`` the pair
numbers refer to (part of the state, so a restored state is renumbered too).

Every rank computes the contacts of the blocks it owns; the forces on the disks are
summed over ranks (every rank holds every disk). Units SI.
"""

from __future__ import annotations

import math

from mpi4py import MPI

import numpy as np

from masonry_fdem.interactions.disks import _facet_kernels as DF
from masonry_fdem.interactions.disks import _kernels as DK
from masonry_fdem.interactions.disks.disks import add_disk_rowsum
from masonry_fdem.interactions.protocol import BLOCKS, Interaction, State
from masonry_fdem.interactions.search import facet_boxes
from masonry_fdem.interactions.search.adt import build_adt, query_adt

__all__ = ["DiskBlockContact"]


class DiskBlockContact(Interaction):
    """Disk–block contact (see the module docstring).

    Args:
        disks: the :class:`~masonry_fdem.interactions.disks.Disks` set (give both to the
            solver: ``interactions=[disks, DiskBlockContact(disks, model)]``).
        model: the :class:`~masonry_fdem.model.Model` of the blocks.
        friction: Coulomb coefficient μ between disks and blocks (default: the disks').
        stiffness: penalty factor: the contact's tangent stiffness per unit thickness is
            ``stiffness · E*`` at the reference overlap ``rel_overlap · r`` (E* from the
            disk and block moduli, plane strain).
        rel_overlap: reference overlap δ/r of that stiffness.
        tangential_ratio: k_t / (ε_a w r) of the friction spring.
        damping_ratio: normal viscous damping as a fraction of critical for the disk on a
            rigid block at the reference overlap (0: elastic).
        margin: travel margin [m] of the candidate list (default 0.2 r_min).
    """

    name = "disk_block"
    state_attributes = ("pairs", "ptr", "cand", "params", "hist", "out", "parts", "work",
                        "dissipated", "u_ref", "x_ref", "rebuilds", "disk_ids")

    def __init__(self, disks, model, *, friction: float | None = None, stiffness: float = 1.0,
                 rel_overlap: float = 0.01, tangential_ratio: float = 0.5,
                 damping_ratio: float = 0.0, margin: float | None = None):
        if not (stiffness > 0 and 0 < rel_overlap < 1 and tangential_ratio >= 0
                and damping_ratio >= 0):
            raise ValueError("stiffness and rel_overlap must be > 0 (rel_overlap < 1), "
                             "tangential_ratio and damping_ratio >= 0")
        if disks.comm.size != model.comm.size:
            raise ValueError("disks and model must live on the same communicator")
        self.disks = disks
        self.model = model
        self.comm = model.comm
        blocks = model.blocks
        gf = np.asarray(blocks.boundary_facets, dtype=np.int64)
        first = np.full(blocks.n_nodes, -1, dtype=np.int64)
        first[gf[:, 0]] = np.arange(gf.shape[0])
        g_next = first[gf[:, 1]]
        g_block = np.asarray(blocks.facet_block, dtype=np.int64)
        mine = np.flatnonzero(model.block_ranks()[g_block] == self.comm.rank)
        local_of_input = np.full(blocks.n_nodes, -1, dtype=np.int64)
        local_of_input[model.node_input] = np.arange(model.n_nodes)
        renum = np.full(gf.shape[0], -1, dtype=np.int64)
        renum[mine] = np.arange(mine.size)
        self.facets = np.ascontiguousarray(local_of_input[gf[mine]])
        self.fnext = np.ascontiguousarray(renum[g_next[mine]])
        self.fprev = np.empty_like(self.fnext)
        self.fprev[self.fnext] = np.arange(mine.size)
        self.facet_block = np.ascontiguousarray(g_block[mine])
        self.nodes = np.unique(self.facets)
        self.X = np.ascontiguousarray(model.X)
        # constants per (disk material, block material)
        nd = len(disks.names)
        bnames = blocks.material_names
        self.block_mat = blocks.block_material.astype(np.int64)
        r_ref = math.fsum(disks.r) / disks.n  # exactly rounded: the same in any order
        self.table = np.zeros((nd, len(bnames), DF.N_PARAM))
        for a, dn in enumerate(disks.names):
            dm = disks.materials[dn]
            for b, bn in enumerate(bnames):
                bm = model.materials[bn]
                e_star = DF.plane_strain_modulus(dm.E, dm.nu, bm.E, bm.nu)
                eps = DF.area_penalty(e_star, r_ref, rel_overlap, stiffness)
                self.table[a, b, DF.P_EPS_A] = eps
                self.table[a, b, DF.P_WIDTH] = disks.width
                self.table[a, b, DF.P_KT] = tangential_ratio * eps * disks.width * r_ref
                self.table[a, b, DF.P_MU] = dm.friction if friction is None else friction
        self.damping_ratio = float(damping_ratio)
        self.rel_overlap = rel_overlap
        self.margin = 0.2 * float(disks.r.min()) if margin is None else float(margin)
        self.boxes = np.zeros((self.facets.shape[0], 4))
        self.u_ref = np.zeros_like(model.u.x.array)
        self.x_ref = disks.x.copy()
        self.pairs = np.zeros((0, 2), dtype=np.int64)
        self.ptr = np.zeros(1, dtype=np.int64)
        self.cand = np.zeros(0, dtype=np.int64)
        self.params = np.zeros((0, DF.N_PARAM))
        self.hist = np.zeros((0, DF.N_HIST))
        self.out = np.zeros((0, DF.N_OUT))
        self.parts = np.zeros((0, DF.N_PART))
        self.work = np.zeros(DF.N_WORK)
        self.dissipated = 0.0
        self.f_disk = np.zeros((disks.n, 2))
        self.torque = np.zeros(disks.n)
        self._sum = np.zeros(3 * disks.n)
        self.rebuilds = 0
        self._fresh = True
        self.disk_ids = disks.ids.copy()  # the disks' storage order the pairs refer to
        self._generation = disks.generation

    # ------------------------------------------------------------------ time step
    def stable_omega2(self) -> dict[str, float]:
        """ω² bound [1/s²] of a disk on a rigid block: max(2 ε_a w r, 3 k_t)/m over disk
        and block materials (smallest disk), plus the damping's effect."""
        d = self.disks
        k = int(np.argmin(d.m))
        w2 = 0.0
        for a in range(self.table.shape[0]):
            for b in range(self.table.shape[1]):
                p = self.table[a, b]
                kk = max(DF.stiffness_bound(p[DF.P_EPS_A], p[DF.P_WIDTH], d.r[k]),
                         3.0 * p[DF.P_KT])
                w2 = max(w2, kk / d.m[k])
        z = self.damping_ratio
        return {"disks": w2 / (math.sqrt(1.0 + z * z) - z) ** 2}

    def add_rowsum(self, rows) -> None:
        """The stiffest disk–block spring, ω² m_min [N/m], on every disk translation (r²
        times that on the rotations); the blocks' rows are bounded by their own
        stiffness."""
        add_disk_rowsum(rows, self.stable_omega2()["disks"] * float(self.disks.m.min()),
                        self.disks.r)

    # ------------------------------------------------------------------ per step
    def _rebuild(self, u: np.ndarray, xd: np.ndarray) -> None:
        d = self.disks
        nf = self.facets.shape[0]
        hist_old, keys_old = self.hist, self._keys() if self.pairs.size else np.zeros(0, np.int64)
        if keys_old.size > 1 and np.any(keys_old[1:] < keys_old[:-1]):  # renumbered
            by_key = np.argsort(keys_old, kind="stable")
            hist_old, keys_old = hist_old[by_key], keys_old[by_key]
        if nf == 0:
            qi = np.zeros(0, dtype=np.int64)
            it = np.zeros(0, dtype=np.int64)
        else:
            facet_boxes(self.X, u, self.facets, self.margin, self.boxes)
            tree = build_adt(self.boxes)
            rr = d.r + self.margin
            qboxes = np.c_[xd[:, 0] - rr, xd[:, 1] - rr, xd[:, 0] + rr, xd[:, 1] + rr]
            qi, it = query_adt(tree, qboxes)
        blk = self.facet_block[it]
        order = np.lexsort((it, blk, qi))
        qi, it, blk = qi[order], it[order], blk[order]
        if qi.size:
            new = np.r_[True, (qi[1:] != qi[:-1]) | (blk[1:] != blk[:-1])]
            starts = np.flatnonzero(new)
        else:
            starts = np.zeros(0, dtype=np.int64)
        self.pairs = np.ascontiguousarray(np.c_[qi[starts], blk[starts]], dtype=np.int64)
        self.ptr = np.r_[starts, qi.size].astype(np.int64)
        self.cand = np.ascontiguousarray(it, dtype=np.int64)
        npairs = starts.size
        self.params = np.zeros((npairs, DF.N_PARAM))
        if npairs:
            self.params[:] = self.table[d.mat[self.pairs[:, 0]], self.block_mat[self.pairs[:, 1]]]
            if self.damping_ratio > 0:
                mass = d.m[self.pairs[:, 0]]
                kref = 2.0 * self.params[:, DF.P_EPS_A] * self.params[:, DF.P_WIDTH] * np.sqrt(
                    self.rel_overlap * (2.0 - self.rel_overlap)) * d.r[self.pairs[:, 0]]
                self.params[:, DF.P_CN] = 2.0 * self.damping_ratio * np.sqrt(kref * mass)
        self.hist = np.zeros((npairs, DF.N_HIST))
        if keys_old.size and npairs:
            keys = self._keys()
            pos = np.searchsorted(keys_old, keys)
            pos = np.minimum(pos, keys_old.size - 1)
            hit = keys_old[pos] == keys
            self.hist[hit] = hist_old[pos[hit]]
        self.out = np.zeros((npairs, DF.N_OUT))
        self.parts = np.zeros((self.cand.size, DF.N_PART))
        self.u_ref[:] = u
        self.x_ref[:] = xd
        self.rebuilds += 1

    def _keys(self) -> np.ndarray:
        return self.pairs[:, 0] * (self.model.blocks.n_blocks + 1) + self.pairs[:, 1]

    def update(self, state: State) -> None:
        """Find the candidate (disk, facet) pairs again once a disk or a facet node has
        moved by half the margin (collective)."""
        u, xd = state.u[BLOCKS], state.u["disks"].reshape(-1, 2)
        self._follow_disks()
        if (self._fresh or DK.max_move(xd, self.x_ref) > 0.5 * self.margin
                or DK.max_node_move(u, self.u_ref, self.nodes) > 0.5 * self.margin):
            self._rebuild(u, xd)
            self._fresh = False

    def _follow_disks(self) -> None:
        """Renumber the pairs (and the disks' reference positions) if the disks were
        permuted since last seen; the pair order is restored at the next rebuild."""
        d = self.disks
        if self._generation == d.generation:
            return
        self._generation = d.generation
        if np.array_equal(self.disk_ids, d.ids):
            return
        new_of_old = d.slot[self.disk_ids]
        self.pairs[:, 0] = new_of_old[self.pairs[:, 0]]
        self.x_ref[new_of_old] = self.x_ref.copy()
        self.disk_ids[:] = d.ids

    def _state_changed(self) -> None:
        self._generation = -1  # a restored state may refer to another storage order

    def add_forces(self, state: State) -> None:
        """Contact forces on the local block nodes, and on the disks summed over ranks
        (collective)."""
        d = self.disks
        self.f_disk.fill(0.0)
        self.torque.fill(0.0)
        DF.disk_block_forces(self.X, state.u[BLOCKS], state.v[BLOCKS], self.facets, self.fprev,
                             self.fnext, state.u["disks"].reshape(-1, 2),
                             state.v["disks"].reshape(-1, 2), state.v["disk_rotations"], d.r,
                             self.pairs, self.ptr, self.cand, self.params, self.hist, state.dt,
                             state.f[BLOCKS], self.f_disk, self.torque, self.work, self.out,
                             self.parts)
        self.dissipated += self.work[DF.W_FRICTION] + self.work[DF.W_DAMPING]
        buf = self._sum
        n = d.n
        buf[: 2 * n] = self.f_disk.ravel()
        buf[2 * n:] = self.torque
        if self.comm.size > 1:
            self.comm.Allreduce(MPI.IN_PLACE, buf, op=MPI.SUM)
        state.f["disks"] += buf[: 2 * n]
        state.f["disk_rotations"] += buf[2 * n:]

    def disk_contacts(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """This rank's disk–block contacts of the last evaluation: (k,) disks (storage
        positions; ``disks.ids`` of them in the user's numbering), (k, 2) force on the
        disk [N] (normal, damping and friction), (k, 2) contact point x_c [m] (for
        :meth:`Disks.cell_stress` and :meth:`Disks.contact_counts`)."""
        touch = self.out[:, DF.O_AREA] > 0.0
        o = self.out[touch]
        n = o[:, [DF.O_NX, DF.O_NY]]
        t = np.c_[-n[:, 1], n[:, 0]]
        f = (o[:, DF.O_FN] + o[:, DF.O_FD])[:, None] * n + o[:, DF.O_FT][:, None] * t
        return (np.ascontiguousarray(self.pairs[touch, 0]), f,
                np.ascontiguousarray(o[:, [DF.O_XC, DF.O_YC]]))

    def checkpoint_state(self) -> dict:
        """:meth:`state` and whether the first search for pairs is still to come."""
        return {**self.state(), "__fresh": bool(self._fresh)}

    def set_checkpoint_state(self, st) -> None:
        """Take a state of :meth:`checkpoint_state`."""
        st = dict(st)
        fresh = st.pop("__fresh")
        self.set_state(st)
        self._fresh = fresh

    def energies(self) -> dict[str, float]:
        """Elastic energy in the disk–block contacts now and dissipated by friction and
        damping since the start [J] (collective)."""
        stored, lost = self.comm.allreduce(np.array(
            [self.work[DF.W_NORMAL] + self.work[DF.W_TANGENT], self.dissipated]))
        return {"stored": float(stored), "dissipated": float(lost)}
