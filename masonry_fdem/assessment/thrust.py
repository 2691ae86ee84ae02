"""The line of thrust of an FDEM state.

:class:`JointThrust` (the report's): at each radial joint of the ring, the
resultant of the contact and joint forces that one voussoir exerts on the next — summed
term by term from the interactions' own forces (contact pairs, joint integration
points), so it is exact whatever the mesh — acts along a line that crosses the joint at
one point; joined from springing to springing per ring, those points are the line of
thrust of the FDEM solution, the counterpart of the limit analysis's. A joint that
carries no compression has no point.

:class:`SectionCuts`: at a radial section of the ring — a straight cut from the intrados to the extrados,
through the circle's centre, across every ring — the normal stresses σ_nn [Pa] of the
elements it crosses give the normal force N = w ∫ σ_nn ds [N] and its moment about the
section's middle M = w ∫ σ_nn (s − s_mid) ds [N m] (w the width); the resultant acts at
s_mid + M / N; it needs several elements across the ring to see a bending moment (a
two-triangle voussoir cannot). A section where N is not compressive (a section opened right through, or one whose
element stresses pull) has no point. The stresses are the elements' Cauchy stresses
(constant per P1 triangle); the sections are sampled at the middles of ``samples``
equal pieces, in the reference configuration (the small displacements of an arch up to
its peak). Place cuts off the joints (a sample on a joint takes one side's stress).

Collective: every rank integrates the samples that fall in its own cells (a sample on
the boundary of two blocks on different ranks is counted once, by the lower rank).
"""

from __future__ import annotations

from mpi4py import MPI

import numpy as np

__all__ = ["JointThrust", "SectionCuts", "block_pair_resultants"]


class SectionCuts:
    """Radial sections of a circular arch ring, located in a model's cells.

    Args:
        model: the :class:`~masonry_fdem.model.Model` (its mesh and stresses).
        centre: (x, y) of the intrados circle's centre [m].
        radius: intrados radius [m]; thickness: total ring thickness [m].
        angles: angles of the sections [rad], measured from the vertical through the
            centre (0 at the crown, negative towards x < 0).
        samples: sample points per section.
    """

    def __init__(self, model, centre, radius: float, thickness: float, angles,
                 samples: int = 40):
        import dolfinx.geometry

        self.model = model
        comm = model.comm
        self.angles = np.asarray(angles, dtype=float)
        self.centre = np.asarray(centre, dtype=float)
        self.radius = float(radius)
        self.thickness = float(thickness)
        n = self.angles.size
        # unit vectors along each section (outwards) and its points
        self.dir = np.c_[np.sin(self.angles), np.cos(self.angles)]
        ds = self.thickness / samples
        s = (np.arange(samples) + 0.5) * ds  # from the intrados
        self.ds = ds
        self.s_rel = s - 0.5 * self.thickness  # from the section's middle
        pts = (self.centre[None, None, :]
               + (self.radius + s)[None, :, None] * self.dir[:, None, :])
        self.points = pts.reshape(-1, 2)
        mesh = model.mesh
        tree = dolfinx.geometry.bb_tree(mesh, mesh.topology.dim)
        p3 = np.c_[self.points, np.zeros(len(self.points))]
        cand = dolfinx.geometry.compute_collisions_points(tree, p3)
        hits = dolfinx.geometry.compute_colliding_cells(mesh, cand, p3)
        cell = np.full(len(self.points), -1, dtype=np.int64)
        for i in range(len(self.points)):
            links = hits.links(i)
            if len(links):
                cell[i] = links[0]
        # a sample found by several ranks is the lowest rank's
        found = np.where(cell >= 0, comm.rank, comm.size)
        owner = np.empty_like(found)
        comm.Allreduce(found, owner, op=MPI.MIN)
        self.mine = np.flatnonzero((cell >= 0) & (owner == comm.rank))
        self.cell = cell[self.mine]
        self.section = self.mine // samples
        self.sample = self.mine % samples
        self.n_sections = n

    def resultants(self) -> tuple[np.ndarray, np.ndarray]:
        """(N [N], M [N m]) of each section at the model's current stresses (collective:
        the stresses are evaluated here)."""
        model = self.model
        model.update_stress()
        sig = model.stress.x.array.reshape(-1, 4)[self.cell]  # xx, xy, yx, yy
        # the section's normal: across the cut, perpendicular to its direction d
        n = self.dir[self.section][:, ::-1] * np.array([1.0, -1.0])
        snn = (sig[:, 0] * n[:, 0] * n[:, 0] + (sig[:, 1] + sig[:, 2]) * n[:, 0] * n[:, 1]
               + sig[:, 3] * n[:, 1] * n[:, 1])
        w = model.width * self.ds
        nm = np.zeros((2, self.n_sections))
        np.add.at(nm[0], self.section, w * snn)
        np.add.at(nm[1], self.section, w * snn * self.s_rel[self.sample])
        model.comm.Allreduce(MPI.IN_PLACE, nm, op=MPI.SUM)
        return nm[0], nm[1]

    def thrust_points(self) -> list[tuple[float, float]]:
        """The point [m] where each compressed section's resultant acts, springing to
        springing (collective)."""
        N, M = self.resultants()
        out = []
        for k in range(self.n_sections):
            if not N[k] < 0.0:
                continue
            e = M[k] / N[k]  # from the middle of the section, outwards
            p = self.centre + (self.radius + 0.5 * self.thickness + e) * self.dir[k]
            out.append((float(p[0]), float(p[1])))
        return out


def block_pair_resultants(interactions, pairs: np.ndarray) -> np.ndarray:
    """(m, 3): the force (Fx, Fy) [N] and its moment about the origin Mz [N m] that block
    ``pairs[i, 0]`` exerts on block ``pairs[i, 1]`` through the contact and joint terms
    between them, at the last force evaluation, with the nodes at their reference
    positions (collective). Anchors crossing the joint are not in it: the resultant is
    the masonry's. Each pair of blocks is given once.

    The interactions that keep their terms' forces (contact pairs ``fp`` over
    ``pairs``/``facets``; joint points ``fq`` over ``ipa``/``ipb``) are used; each term
    is counted by one rank.
    """
    pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    out = np.zeros((pairs.shape[0], 3))
    if pairs.size == 0:
        return out
    nb = int(pairs.max()) + 1
    qkey = pairs[:, 0] * nb + pairs[:, 1]
    order = np.argsort(qkey)
    skey = qkey[order]
    comm = None

    def add(ta, tb, f, nodes, x, counted):
        # terms from block ta to tb; f (k, 8): forces on the 4 nodes (ta's two, tb's two)
        ok = counted > 0
        for (frm, to, slots) in ((ta, tb, slice(4, 8)), (tb, ta, slice(0, 4))):
            inside = ok & (frm < nb) & (to < nb)
            key = np.where(inside, frm * nb + to, -1)
            pos = np.minimum(np.searchsorted(skey, key), skey.size - 1)
            hit = inside & (skey[pos] == key)
            if not hit.any():
                continue
            fn = f[hit][:, slots].reshape(-1, 2, 2)  # (k, node, xy)
            nd = nodes[hit][:, 2:4] if slots.start == 4 else nodes[hit][:, 0:2]
            xn = x[nd]  # (k, 2, 2)
            fx = fn[..., 0].sum(axis=1)
            fy = fn[..., 1].sum(axis=1)
            mz = (xn[..., 0] * fn[..., 1] - xn[..., 1] * fn[..., 0]).sum(axis=1)
            np.add.at(out, order[pos[hit]], np.c_[fx, fy, mz])

    for it in interactions:
        if hasattr(it, "fp") and hasattr(it, "pairs") and hasattr(it, "facets"):
            comm = it.comm
            fb = it.facet_block
            nodes = np.c_[it.facets[it.pairs[:, 0]], it.facets[it.pairs[:, 1]]]
            x = it.X  # (reference configuration, as the joint lines)
            add(fb[it.pairs[:, 0]], fb[it.pairs[:, 1]], it.fp, nodes, x, it.counted)
        elif hasattr(it, "fq") and hasattr(it, "ipa"):
            comm = it.comm
            blocks = it.seg_blocks[it.q_seg[it.local_ip]]
            nodes = np.c_[it.ipa, it.ipb]
            x = it.X  # (reference configuration, as the joint lines)
            add(blocks[:, 0], blocks[:, 1], it.fq, nodes, x, it.counted)
    if comm is not None:
        comm.Allreduce(MPI.IN_PLACE, out, op=MPI.SUM)
    return out


class JointThrust:
    """The FDEM's line of thrust across the radial joints of ``case``'s arch in
    ``model`` (the joints found once; :meth:`lines` at any state)."""

    def __init__(self, case, model):
        from masonry_fdem.assessment.specs import classify_interface
        from masonry_fdem.solvers.limit_analysis import find_interfaces

        layout = case.layout()
        itf = find_interfaces(layout)
        index = {n: k for k, n in enumerate(model.blocks.block_names)}
        cent = model.blocks.block_centroid
        self.rows = []
        for i in range(itf.size):
            na, nb = layout.names[itf.block_a[i]], layout.names[itf.block_b[i]]
            where = classify_interface(na, nb, case.arch)
            if where is None or where[0] != "joint" or na not in index or nb not in index:
                continue
            a, b = index[na], index[nb]
            p0, p1 = np.asarray(itf.start[i], float), np.asarray(itf.end[i], float)
            d = p1 - p0
            n = np.array([d[1], -d[0]]) / np.hypot(*d)
            if np.dot(cent[b] - p0, n) < 0:
                n = -n  # from a towards b
            self.rows.append((where[1], where[2], a, b, p0, d, n))
        self.pairs = np.array([[r[2], r[3]] for r in self.rows], dtype=np.int64)

    def lines(self, interactions) -> list[list[tuple[float, float]]]:
        """Per ring, the point [m] where the resultant of the forces across each radial
        joint crosses it (springing to springing, reference configuration); joints
        without compression are left out, and so are those whose resultant crosses the
        joint's line more than the joint's length beyond its ends: a small thrust against
        the bending that the mortar's bond carries there, no point of a line of thrust (on
        the TRL arch's rings up to 2 m away, drawn across the figure) (collective)."""
        if not self.rows:
            return []
        res = block_pair_resultants(interactions, self.pairs)
        rings: dict[int, list] = {}
        for (ring, j, _, _, p0, d, n), (fx, fy, mz) in zip(self.rows, res, strict=True):
            cross = d[0] * fy - d[1] * fx
            if not (fx * n[0] + fy * n[1] > 0.0 and abs(cross) > 0.0):
                continue  # no compression across the joint
            t = (mz - (p0[0] * fy - p0[1] * fx)) / cross
            if not -1.0 <= t <= 2.0:
                continue  # far outside the joint: the bond's bending, not a thrust
            p = p0 + t * d
            rings.setdefault(ring, []).append((j, (float(p[0]), float(p[1]))))
        return [[p for _, p in sorted(r)] for _, r in sorted(rings.items())]
