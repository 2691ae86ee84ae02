"""Consistent tangents of the bonded joints and the anchors (static Newton solver).

``add_tangent`` must give −∂f/∂u of the forces ``add_forces`` computes, at the same
committed history (a static State: ``v`` is the displacement since the last commit). The
reference is the central difference of the interaction's whole force vector, one global
dof at a time, each evaluation returning from the committed state exactly as the solver's
would: the tangent assembled through ``add_tangent`` must match it to 1e-5 of its largest
entry, in states chosen away from state transitions (kinks of the laws):

* a joint (Lourenço–Rots law): elastic; softening in tension, in shear and at the
  tension–shear corner (committed state past the peak, loading on); open and rocking
  (tension softened to nothing: open at one end, closed and frictional at the other);
  sliding under compression on the residual friction, with dilatancy;
* an anchor across a joint: elastic bar and bond; the bar yielding (hardening steel, end
  plates bearing); the bond slipping on the plateau and on the softening branch of its
  envelope (with a dowel at its strength); the joint dowel of the bar (B sliding along
  the joint), elastic and at its strength.

Each case also checks that the state is the one it claims (plastic loading where it
should be), so that a drifting set-up cannot pass on an elastic tangent. The elastic
joint and the elastic bar must be symmetric. Under mpirun the tangent assembled over
ranks (ghost nodes of the joints, bond points on their host's rank, bars on rank 0) must
equal the serial one. Units SI (m, N, Pa).
"""

from __future__ import annotations

from mpi4py import MPI

import numpy as np
import pytest
from test_anchors import grid_blocks

from masonry_fdem import Material, Model
from masonry_fdem.geometry import build_stack
from masonry_fdem.interactions import JointMaterial, Joints
from masonry_fdem.interactions.anchors import (Anchor, Anchors, BondLaw, DowelLaw, JointDowel,
                                               SteelLaw)
from masonry_fdem.interactions.anchors import _kernels as AK
from masonry_fdem.interactions.joints import _kernels as JK
from masonry_fdem.interactions.protocol import BLOCKS, State, Tangent

RTOL = 1e-5  # largest |K − K_fd| / largest |K|
H_FD = 1e-9  # [m] the reference's own step (not the kernels')

# ---------------------------------------------------------------------- joints
W, HB, T = 0.2, 0.1, 0.1  # block width, height, out-of-plane thickness [m]
MORTAR = dict(kn=1e11, ks=4e10, ft=0.3e6, GfI=12.0, c=0.4e6, GfII=50.0, tan_phi=0.75)
DILATANT = MORTAR | dict(tan_psi=0.05, psi_confinement=-3e6, psi_decay=1000.0)


def joint_model(jm: JointMaterial, comm=MPI.COMM_SELF):
    """Two blocks 0.2 × 0.1 m stacked, bonded by one bed joint at y = 0.1 m (4 segments)."""
    blocks = build_stack(2, width=W, height=HB, mesh_size=0.05, material="brick", comm=comm)
    model = Model(blocks, {"brick": Material(E=10e9, nu=0.2, density=2000.0)}, width=T,
                  comm=comm)
    return model, Joints(model, {("brick", "brick"): jm})


def joint_field(blocks, slide, lift, rot=0.0, pivot=0.07, noise=1e-8, seed=0):
    """Displacement (n_input_nodes, 2) [m]: the top block moved by (slide, lift) and turned
    by ``rot`` [rad] about (pivot, 0.1), the bottom one held; plus a fixed random field
    of amplitude ``noise`` so that no two points are alike."""
    x = blocks.x
    rng = np.random.default_rng(seed)
    u = noise * rng.uniform(-1.0, 1.0, x.shape)
    top = blocks.node_block == 1  # block:1 is the upper one
    r = x[top] - [pivot, HB]
    u[top, 0] += slide - rot * r[:, 1]
    u[top, 1] += lift + rot * r[:, 0]
    return u


# ---------------------------------------------------------------------- anchors
BRICK = Material(density=2000.0, E=5e9, nu=0.2)
BOND = BondLaw((2e-4, 1e-3, 3e-3), (3e6, 3e6, 0.5e6))  # rise, plateau, softening
STEEL = SteelLaw(E=200e9, yield_stress=500e6, hardening=2e9, rupture_strain=0.05)
A_START, A_END = np.array([0.11, 0.09]), np.array([0.49, 0.11])


def anchor_model(comm=MPI.COMM_SELF, **kw):
    """Blocks A = [0, 0.3] × [0, 0.2] and B = [0.3, 0.6] × [0, 0.2] with an inclined
    12 mm anchor from (0.11, 0.09) to (0.49, 0.11) across the joint between them."""
    blocks = grid_blocks([(0, 0, 0.3, 0.2), (0.3, 0, 0.6, 0.2)], 0.04)
    model = Model(blocks, {"brick": BRICK}, width=0.2, comm=comm)
    anchor = Anchor(np.array([A_START, A_END]), diameter=0.012, segment=0.02,
                    **({"bond": BOND, "steel": STEEL} | kw))
    return model, Anchors(model, [anchor])


def anchor_field(blocks, anchors, open_, slip, transverse=0.0, end_slip=0.0, noise=1e-8,
                 seed=1, lift=0.0):
    """Displacements [m] of the block nodes (n_input_nodes, 2) and of the bar nodes
    (flat): block B moved by ``open_`` along x and ``lift`` along y (sliding along the
    joint), A held; each bar node moves with the block around it, plus ``slip`` along
    the bar and ``transverse`` across it; the first and last node by ±``end_slip`` more
    (into their plates); plus random ``noise``."""
    rng = np.random.default_rng(seed)
    ub = noise * rng.uniform(-1.0, 1.0, blocks.x.shape)
    ub[blocks.node_block == 1, 0] += open_  # block B
    ub[blocks.node_block == 1, 1] += lift
    t = (A_END - A_START) / np.linalg.norm(A_END - A_START)
    n = np.array([-t[1], t[0]])
    xa = anchors.x
    ua = noise * rng.uniform(-1.0, 1.0, xa.shape)
    ua[xa[:, 0] > 0.3, 0] += open_
    ua[xa[:, 0] > 0.3, 1] += lift
    ua += slip * t + transverse * n
    ua[0] += end_slip * t
    ua[-1] -= end_slip * t
    return ub, ua.ravel()


# ---------------------------------------------------------------------- the check
class Probe:
    """An interaction's forces as a function of all dofs (blocks, then bar nodes) on a
    model of one rank, from its committed history (static States)."""

    def __init__(self, model, inter, na: int = 0):
        self.model, self.inter = model, inter
        self.nb = model.u.x.array.size
        self.na = na
        self.xc = np.zeros(self.nb + na)  # the committed dofs

    def dofs(self, ub_input: np.ndarray, ua: np.ndarray | None = None) -> np.ndarray:
        """All dofs from a block field by input node (n_input, 2) and the bar nodes'."""
        x = np.zeros(self.nb + self.na)
        x[:self.nb] = ub_input[self.model.node_input].ravel()
        if self.na:
            x[self.nb:] = ua
        return x

    def forces(self, x: np.ndarray) -> tuple[np.ndarray, State]:
        nb = self.nb
        u = {BLOCKS: x[:nb].copy()}
        v = {BLOCKS: x[:nb] - self.xc[:nb]}
        f = {BLOCKS: np.zeros(nb)}
        if self.na:
            u["anchors"] = x[nb:].copy()
            v["anchors"] = x[nb:] - self.xc[nb:]
            f["anchors"] = np.zeros(self.na)
        st = State(u, v, f, 1.0, False, static=True)
        self.inter.update(st)
        self.inter.add_forces(st)
        return np.concatenate([f[BLOCKS], f.get("anchors", np.zeros(0))]), st

    def commit(self, x: np.ndarray) -> None:
        self.forces(x)
        self.inter.commit()
        self.xc = x.copy()

    def tangent(self, x: np.ndarray) -> np.ndarray:
        """The dense tangent assembled through add_tangent (serial numbering)."""
        _, st = self.forces(x)
        m = self.model
        node_dof = np.full(m.blocks.n_nodes, -1, dtype=np.int64)
        node_dof[m.node_input] = 2 * np.arange(m.n_nodes)
        K = Tangent({BLOCKS: np.arange(self.nb), "anchors": self.nb + np.arange(self.na)},
                    node_dof, rank=0)
        self.inter.add_tangent(K, st)
        r, c, v = K.coo()
        out = np.zeros((x.size, x.size))
        np.add.at(out, (r, c), v)
        return out

    def finite_difference(self, x: np.ndarray, h: float = H_FD) -> np.ndarray:
        n = x.size
        out = np.zeros((n, n))
        for j in range(n):
            xp, xm = x.copy(), x.copy()
            xp[j] += h
            xm[j] -= h
            fp, _ = self.forces(xp)
            fm, _ = self.forces(xm)
            out[:, j] = -(fp - fm) / (xp[j] - xm[j])
        self.forces(x)  # back to the trial state at x
        return out


def compare(K: np.ndarray, Kfd: np.ndarray, label: str, rows=None) -> float:
    scale = np.abs(K).max()
    assert scale > 0.0, f"{label}: empty tangent"
    err = np.abs(K - Kfd).max() / scale
    msg = f"{label}: max|K - K_fd| / max|K| = {err:.2e} (max|K| = {scale:.3e} N/m)"
    if rows is not None:  # rows of small entries, on their own scale
        sub = np.abs(K[rows]).max()
        err_rows = np.abs(K[rows] - Kfd[rows]).max() / sub
        msg += f"; block rows {err_rows:.2e} of {sub:.3e} N/m"
        err = max(err, err_rows)
    print(msg)
    return err


# ---------------------------------------------------------------------- joint cases
def _joint_case(case: str):
    """(probe, x, check): the joint with its committed state set and the dofs x at which
    the tangent is taken; ``check(joints)`` asserts the trial state at x."""
    jm = JointMaterial(**(DILATANT if case == "sliding" else MORTAR))
    model, joints = joint_model(jm)
    pr = Probe(model, joints)
    bx = model.blocks
    ft, kn, GfI = jm.ft, jm.kn, jm.GfI
    c, ks, GfII = jm.c, jm.ks, jm.GfII
    s0 = joints.s0

    def plastic_on(col):
        return lambda j: np.all(j.s1[:, col] > j.s0[:, col])

    if case == "elastic":
        x = pr.dofs(joint_field(bx, 2e-6, 1e-6, rot=2e-6))

        def check(j):
            assert np.all(j.s1[:, [JK.S_DNP, JK.S_DSP, JK.S_K1, JK.S_K2]] == 0.0)
            assert np.all(j.s1[:, JK.S_SN] > 0.0)
    elif case == "softening-tension":
        d0 = ft / kn + 0.5 * GfI / ft
        pr.commit(pr.dofs(joint_field(bx, 0.0, d0)))
        assert np.all(s0[:, JK.S_K1] > 0.3 * GfI / ft)
        x = pr.dofs(joint_field(bx, 1e-6, d0 + 5e-6, rot=1e-5))
        check = plastic_on(JK.S_K1)
    elif case == "softening-shear":
        d0 = c / ks + 0.5 * GfII / c
        pr.commit(pr.dofs(joint_field(bx, d0, -2e-6)))
        assert np.all(s0[:, JK.S_K2] > 0.3 * GfII / c)
        x = pr.dofs(joint_field(bx, d0 + 1e-5, -2e-6, rot=1e-5))
        check = plastic_on(JK.S_K2)
    elif case == "softening-corner":
        pr.commit(pr.dofs(joint_field(bx, 3e-5, 2e-5)))
        x = pr.dofs(joint_field(bx, 3.3e-5, 2.2e-5, rot=1e-5))

        def check(j):
            assert plastic_on(JK.S_K1)(j) and plastic_on(JK.S_K2)(j)
            r = np.exp(-ft * j.s1[:, JK.S_K1] / GfI)
            assert np.all((r > 0.05) & (r < 0.95))
    elif case == "open":
        d0 = 30.0 * GfI / ft  # R = e^-30: tension and cohesion are gone
        pr.commit(pr.dofs(joint_field(bx, 0.0, d0)))
        assert np.all(s0[:, JK.S_STATUS] == JK.OPEN)
        # closed back and rocking about x = 0.07 m: open beyond it, closed (compressed,
        # sticking) before — a spent crack's faces meet where they met before it opened
        x = pr.dofs(joint_field(bx, 0.0, 0.0, rot=2e-4))

        def check(j):
            st = j.s1[:, JK.S_STATUS]
            assert np.any(st == JK.OPEN) and np.any(st == JK.SLIDING)
            closed = st == JK.SLIDING
            assert np.all(j.s1[closed, JK.S_SN] < -1e5)  # in compression
            assert np.all(np.abs(j.s1[~closed, JK.S_SN]) < 1e-3)  # open: no traction
    elif case == "sliding":
        # slide by 1 mm in steps, the lift following the dilatancy's uplift so that the
        # normal stress stays near -0.5 MPa
        lift = -5e-6
        for slide in np.linspace(1e-4, 1e-3, 10):
            pr.commit(pr.dofs(joint_field(bx, slide, lift)))
            lift = float(s0[:, JK.S_DNP].mean()) - 5e-6
        assert np.all(s0[:, JK.S_STATUS] == JK.SLIDING)
        x = pr.dofs(joint_field(bx, 1.02e-3, lift, rot=1e-5))

        def check(j):
            assert plastic_on(JK.S_K2)(j)
            assert np.all(j.s1[:, JK.S_SN] < -1e5) and np.all(j.s1[:, JK.S_SN] > -3e6)
            assert np.all(j.s1[:, JK.S_DNP] > j.s0[:, JK.S_DNP])  # dilatant
    else:
        raise ValueError(case)
    return pr, x, check


JOINT_CASES = ["elastic", "softening-tension", "softening-shear", "softening-corner", "open",
               "sliding"]


@pytest.mark.parametrize("case", JOINT_CASES)
def test_joint_tangent_matches_finite_differences_of_the_forces(case):
    pr, x, check = _joint_case(case)
    K = pr.tangent(x)
    check(pr.inter)
    Kfd = pr.finite_difference(x)
    err = compare(K, Kfd, f"joint {case}")
    assert err < RTOL
    # the kernel's trial state is left as at x
    s1 = pr.inter.s1.copy()
    pr.tangent(x)
    assert np.array_equal(pr.inter.s1, s1)


def test_elastic_joint_tangent_is_symmetric():
    """Symmetric up to the turning of the joint frame, terms of relative size |Δ|/L
    (relative displacement over facet length, ~1e-5 here)."""
    pr, x, _ = _joint_case("elastic")
    K = pr.tangent(x)
    asym = np.abs(K - K.T).max() / np.abs(K).max()
    print(f"elastic joint: max|K - K^T| / max|K| = {asym:.2e}")
    assert asym < 1e-4


# ---------------------------------------------------------------------- anchor cases
def _anchor_case(case: str):
    kw = {}
    if case == "bond-softening":
        kw = {"dowel": DowelLaw(stiffness=5e9, strength=2e4)}
    if case == "bar-yielding":
        kw = {"plates": "both"}
    if case.startswith("joint-dowel"):
        kw = {"shear": JointDowel(stiffness=2e8, strength=1e3)}
    model, anchors = anchor_model(**kw)
    pr = Probe(model, anchors, anchors.u.size)
    bx = model.blocks
    crossing = int(np.argmin(np.abs(anchors.x[anchors.conn].mean(axis=1)[:, 0] - 0.3)))
    if case == "elastic":
        x = pr.dofs(*anchor_field(bx, anchors, 2e-5, 2e-5, transverse=1e-6))

        def check(a):
            assert np.all(a.et[:, AK.ES_ALPHA] == 0.0)
            assert np.all(a.nt[:, AK.NS_KAPPA] < 1e-15)  # (round-off of the bond return)
            assert np.abs(a.axial).max() > 0.0
    elif case.startswith("joint-dowel"):
        plastic = case == "joint-dowel-plastic"
        if plastic:  # slid past the dowel's strength (Q_y / K = 5 um), still sliding
            pr.commit(pr.dofs(*anchor_field(bx, anchors, 1e-6, 0.0, lift=8e-6)))
        x = pr.dofs(*anchor_field(bx, anchors, 2e-6, 1e-7, lift=9e-6 if plastic else 3e-6))

        def check(a):
            assert a.n_cross == 1
            assert bool(a.cout[0, AK.CO_PLASTIC]) == plastic
            q = abs(a.cout[0, AK.CO_Q])
            assert (q == pytest.approx(1e3, rel=1e-12)) if plastic else (200.0 < q < 1e3)
    elif case == "bar-yielding":
        pr.commit(pr.dofs(*anchor_field(bx, anchors, 1e-4, 0.0, end_slip=1e-5)))
        assert anchors.es[crossing, AK.ES_ALPHA] > 0.0
        x = pr.dofs(*anchor_field(bx, anchors, 1.2e-4, 0.0, end_slip=1e-5))

        def check(a):
            assert a.et[crossing, AK.ES_ALPHA] > a.es[crossing, AK.ES_ALPHA]  # loading
            assert np.all(a.nt[:, AK.NS_KAPPA] < 1e-15)  # the bond holds
            assert np.count_nonzero(a.bond_out[:, AK.NO_PLATE]) == 2  # both plates bear
    else:
        sl0, sl1 = (5e-4, 6e-4) if case == "bond-plateau" else (1.5e-3, 1.6e-3)
        tr0, tr1 = (0.0, 0.0) if case == "bond-plateau" else (1e-5, 1.1e-5)
        pr.commit(pr.dofs(*anchor_field(bx, anchors, 0.0, sl0, transverse=tr0)))
        x = pr.dofs(*anchor_field(bx, anchors, 0.0, sl1, transverse=tr1))

        def check(a):
            bonded = a.local
            assert np.all(a.nt[bonded, AK.NS_KAPPA] > a.ns[bonded, AK.NS_KAPPA])
            slip = a.bond_out[bonded, AK.NO_SLIP]
            lo, hi = (2e-4, 1e-3) if case == "bond-plateau" else (1e-3, 3e-3)
            assert np.all((slip > lo) & (slip < hi))
            if case == "bond-softening":  # the dowels at their strength
                q = np.abs(a.bond_out[bonded, AK.NO_Q])
                assert np.allclose(q, a.npr[bonded, AK.NP_QY], rtol=1e-12)
    return pr, x, check


ANCHOR_CASES = ["elastic", "bar-yielding", "bond-plateau", "bond-softening", "joint-dowel",
                "joint-dowel-plastic"]


@pytest.mark.parametrize("case", ANCHOR_CASES)
def test_anchor_tangent_matches_finite_differences_of_the_forces(case):
    pr, x, check = _anchor_case(case)
    K = pr.tangent(x)
    check(pr.inter)
    Kfd = pr.finite_difference(x)
    # the block rows hold the bond alone, far below the bars: check them on their scale
    err = compare(K, Kfd, f"anchor {case}", rows=slice(0, pr.nb))
    assert err < RTOL
    a = pr.inter
    saved = [arr.copy() for arr in (a.et, a.nt, a.bond_out, a.axial)]
    pr.tangent(x)
    for old, new in zip(saved, (a.et, a.nt, a.bond_out, a.axial), strict=True):
        assert np.array_equal(old, new)


def test_elastic_bar_tangent_is_symmetric():
    pr, x, _ = _anchor_case("elastic")
    a = pr.inter
    pr.forces(x)
    ne = a.n_elements
    rows = np.empty(16 * ne, dtype=np.int64)
    cols = np.empty(16 * ne, dtype=np.int64)
    vals = np.empty(16 * ne)
    n = AK.bar_tangent(a.x, x[pr.nb:], a.conn, a.L0, a.ep, a.jacking, a.es, AK.FD_STEP,
                       rows, cols, vals)
    K = np.zeros((pr.na, pr.na))
    np.add.at(K, (rows[:n], cols[:n]), vals[:n])
    asym = np.abs(K - K.T).max() / np.abs(K).max()
    print(f"elastic bars: max|K - K^T| / max|K| = {asym:.2e}")
    assert asym < 1e-7


# ---------------------------------------------------------------------- over ranks
def _by_input_id(model, inter, x_input: np.ndarray, ua: np.ndarray | None,
                 xc_input: np.ndarray | None, uac: np.ndarray | None) -> np.ndarray:
    """Dense tangent of ``inter`` on a model of any number of ranks, numbered by input node
    id (node i: dofs 2i, 2i+1; then the bar nodes), summed over ranks; after committing
    at (xc_input, uac) when given."""
    comm = model.comm
    nin = model.blocks.n_nodes
    na = 0 if ua is None else ua.size

    def state(xi, uai, base):
        ub = xi[model.node_input].ravel()
        u = {BLOCKS: ub}
        v = {BLOCKS: ub - base[0]}
        f = {BLOCKS: np.zeros_like(ub)}
        if na:
            u["anchors"] = uai.copy()
            v["anchors"] = uai - base[1]
            f["anchors"] = np.zeros(na)
        return State(u, v, f, 1.0, False, static=True)

    zero = (np.zeros(2 * model.n_nodes), np.zeros(na))
    base = zero
    if xc_input is not None:
        st = state(xc_input, uac, zero)
        inter.update(st)
        inter.add_forces(st)
        inter.commit()
        base = (st.u[BLOCKS].copy(), st.u["anchors"].copy() if na else None)
    st = state(x_input, ua, base)
    inter.update(st)
    inter.add_forces(st)
    ni = model.node_input
    index = {BLOCKS: np.c_[2 * ni, 2 * ni + 1].ravel(), "anchors": 2 * nin + np.arange(na)}
    K = Tangent(index, 2 * np.arange(nin, dtype=np.int64), rank=comm.rank)
    inter.add_tangent(K, st)
    out = np.zeros((2 * nin + na, 2 * nin + na))
    for r, c, v in comm.allgather(K.coo()):
        np.add.at(out, (r, c), v)
    return out


def test_tangent_over_ranks_equals_the_serial_one():
    """Joints (the side-B nodes of a point held by another rank are ghosts) and anchors
    (bond points on their host's rank, bars once) give the same tangent on every number
    of ranks."""
    world = MPI.COMM_WORLD
    out = []
    for comm in (MPI.COMM_SELF, world):
        model, joints = joint_model(JointMaterial(**MORTAR), comm=comm)
        if comm.size > 1:  # the two blocks on two ranks: side B by ghost nodes
            assert comm.allreduce(joints.ext_input.size - model.n_nodes) > 0
        bx = model.blocks
        Kj = _by_input_id(model, joints, joint_field(bx, 3.3e-5, 2.2e-5, rot=1e-5), None,
                          joint_field(bx, 3e-5, 2e-5), None)
        model, anchors = anchor_model(comm=comm, plates="both",
                                      shear=JointDowel(stiffness=2e8, strength=1e3))
        if comm.size > 1:  # bond points in both blocks, so on two ranks
            n_local = comm.allgather(int(anchors.local.sum()))
            assert sum(n_local) == anchors.n_bond and max(n_local) < anchors.n_bond
        bx = model.blocks
        ubc, uac = anchor_field(bx, anchors, 1e-4, 0.0, end_slip=1e-5)
        ub, ua = anchor_field(bx, anchors, 1.2e-4, 1e-6, end_slip=1e-5, lift=3e-6)
        Ka = _by_input_id(model, anchors, ub, ua, ubc, uac)
        out.append((Kj, Ka))
    for (ser, par), name in zip(zip(out[0], out[1], strict=True), ("joints", "anchors"),
                                strict=True):
        diff = np.abs(ser - par).max() / np.abs(ser).max()
        print(f"{name}: {world.size} rank(s) vs 1: max difference {diff:.2e} of max|K|")
        assert np.abs(ser).max() > 0.0
        assert diff < 1e-12
