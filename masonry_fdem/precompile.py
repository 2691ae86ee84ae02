"""Compile and cache every numba kernel once, before MPI ranks start.

Run ``python -m masonry_fdem.precompile`` serially (``make`` does) so that ranks of a
parallel run load the cache instead of racing to write it.
"""

from __future__ import annotations

import numpy as np
from mpi4py import MPI

__all__ = ["precompile"]


def precompile() -> None:
    """Call each kernel once on tiny arrays of the production dtypes."""
    from masonry_fdem.model import _kernels as MK
    from masonry_fdem.solvers import _kernels as K

    n = 6
    u = np.zeros(n)
    v = np.zeros(n)
    f = np.zeros(n)
    m = np.ones(n)
    mask = np.zeros(n, dtype=np.int8)

    MK.gather_to(u, np.zeros(n, dtype=np.int64), np.zeros(n, dtype=np.int64), v)
    from masonry_fdem.materials.quadrature import p1_gradients, scatter_rows

    p1_gradients(np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]), np.zeros(6),
                 np.array([[0, 1, 2]], dtype=np.int64), np.zeros(1, dtype=np.int32),
                 np.zeros(1, dtype=np.int64), np.zeros((1, 4)))
    scatter_rows(np.zeros((2, 3)), np.zeros(2, dtype=np.int64), np.zeros((3, 3)))
    K.central_difference_step(u, v, f, f, f, m, m, mask, v, 0.0, 1e-3, f.copy(),
                              np.zeros(K.N_ENERGY))
    K.dr_measure(u, u, v, f, f, f, m, mask, np.zeros(4))
    K.dr_update(u, v, f, f, m, mask, 0.0, 1.0, True)
    K.dr_velocity_quotient(v, f, f.copy(), m, mask, True, np.zeros(6)[4:])
    xy = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    cells = np.array([[0, 1, 2]], dtype=np.int64)
    one = np.ones(1)
    MK.p1_element_bounds(xy, cells, one, one, one, 1.0, np.zeros(1), np.zeros(n))

    from masonry_fdem.interactions.contact import _kernels as C

    X = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    uu = np.zeros(8)
    facets = np.array([[0, 1], [1, 2], [2, 3], [3, 0]], dtype=np.int64)
    fnext = np.array([1, 2, 3, 0], dtype=np.int64)
    fprev = np.array([3, 0, 1, 2], dtype=np.int64)
    pairs = np.array([[0, 2]], dtype=np.int64)
    p1 = np.ones(1)
    work = np.zeros(C.N_WORK)
    C.facet_facet_forces(X, uu, uu, facets, fprev, fnext, pairs, p1, p1, p1, p1, p1, 1.0, 1e-3,
                         np.zeros((1, 2)), np.zeros((1, 2)), np.zeros(8), np.zeros(3), work)
    from masonry_fdem.interactions.search import facet_boxes, max_speed

    facet_boxes(X, uu, facets, 0.1, np.zeros((4, 4)))
    max_speed(uu)

    from masonry_fdem.interactions.joints import _kernels as J

    props = np.zeros((1, J.N_PROPS))
    props[0, [J.P_FT, J.P_GF1, J.P_C, J.P_GF2, J.P_FC, J.P_KP, J.P_GFC]] = 1.0
    props[0, [J.P_KN, J.P_KS]] = 10.0
    ip = np.array([[0, 1]], dtype=np.int64)
    half = np.full(1, 0.5)
    s0 = J.empty_state(1)
    s1 = J.empty_state(1)
    alive = np.ones(1, dtype=np.int8)
    J.joint_forces(X, uu, ip, ip[:, ::-1].copy(), half, half, half, np.zeros(1, np.int64),
                   props, alive, s0, s1, np.zeros(8), np.zeros(2))
    J.commit(alive, s0, s1)
    J.node_spring_bound(ip, ip, half, half, half, np.zeros(1, np.int64), props, alive,
                        np.zeros(4))
    J.interface_law(props[0], 2.0, 1.0, s0[0], s1[0])
    J.interface_law(props[0], -2.0, 0.5, s0[0], s1[0])

    from masonry_fdem.materials import DruckerPrager, MohrCoulomb
    from masonry_fdem.materials import _plastic_kernels as PK

    strain = np.array([[1e-3, -2e-3, 5e-4], [1e-3, -2e-3, 5e-4]])
    qps = np.arange(2, dtype=np.int64)
    for law in (MohrCoulomb(density=1.0, E=1e6, nu=0.2, c=100.0, phi=30.0),
                DruckerPrager(density=1.0, E=1e6, nu=0.2, c=100.0, phi=30.0, viscosity=1.0)):
        for hyp in ("plane_strain", "plane_stress"):
            s0 = np.zeros((2, PK.N_STATE))
            PK.plastic_update(strain, s0, s0.copy(), np.zeros((2, 4)), np.zeros(2), qps,
                              law.kernel_params(hyp), 1e-3)
            law.return_map(np.zeros((2, 4)) + 1e-3, s0, s0.copy(), np.zeros((2, 4)),
                           np.zeros(2), qps, law.kernel_params(hyp), 1e-3)
    PK.yield_value(np.zeros(4), 0.0, law.kernel_params("plane_strain"))

    from masonry_fdem.interactions.disks import _kernels as DK
    from masonry_fdem.interactions.disks import DiskMaterial, Disks

    dm = DiskMaterial(density=1.0, E=1e6, nu=0.2, rolling_friction=0.1)
    dd = Disks(np.array([[0.0, 0.0], [1.9, 0.0], [9.0, 9.0]]), np.ones(3), {"d": dm}, "d",
               comm=MPI.COMM_SELF)
    dd.add_gravity()
    dd.compute_forces(1e-3)
    dd.advance(1e-3, 0.1)
    DK.brute_force_disk_pairs(dd.x, dd.r, 0.1)
    DK.hertz_force(1.0, 0.5, 0.1, 0.2)
    from masonry_fdem.interactions.disks import _facet_kernels as DF


    xd = np.array([[0.5, 1.05]])
    vd = np.zeros((1, 2))
    pairs1 = np.array([[0, 0]], dtype=np.int64)
    prm = np.zeros((1, DF.N_PARAM))
    prm[0, [DF.P_EPS_A, DF.P_WIDTH, DF.P_KT, DF.P_MU, DF.P_CN]] = [1e6, 1.0, 1e3, 0.5, 1.0]
    DF.disk_block_forces(X, uu, uu, facets, fprev, fnext, xd, vd, np.zeros(1), np.full(1, 0.1),
                         pairs1, np.array([0, 4], dtype=np.int64), np.arange(4, dtype=np.int64),
                         prm, np.zeros((1, DF.N_HIST)), 1e-3, np.zeros(8), np.zeros((1, 2)),
                         np.zeros(1), np.zeros(DF.N_WORK), np.zeros((1, DF.N_OUT)),
                         np.zeros((4, DF.N_PART)))
    DK.max_node_move(uu, uu, np.arange(4, dtype=np.int64))
    from masonry_fdem.interactions.disks.packing import pack_disks

    pack_disks(np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]), 0.1, 0.15, 0.5)

    from masonry_fdem.interactions.search.adt import brute_force_pairs, query_adt, self_pairs

    boxes = np.array([[0.0, 0.0, 1.0, 1.0], [0.5, 0.5, 2.0, 2.0], [3.0, 3.0, 4.0, 4.0]])
    self_pairs(boxes, np.array([0, 1, 1]))
    brute_force_pairs(boxes)
    from masonry_fdem.interactions.search.adt import build_adt

    query_adt(build_adt(boxes), boxes)

    from masonry_fdem.interactions.anchors import _kernels as AK

    xa = np.array([[0.0, 0.5], [0.5, 0.5]])
    ua = np.zeros(4)
    conn = np.array([[0, 1]], dtype=np.int64)
    ep = np.ones((1, AK.N_EP))
    es = np.zeros((1, AK.N_ES))
    AK.bar_forces(xa, ua, conn, np.full(1, 0.5), ep, np.zeros(1, np.int8), es, es.copy(),
                  np.zeros(1), np.zeros(1), np.zeros(4))
    hn = np.array([0, 1], dtype=np.int64)
    he = np.zeros(2, dtype=np.int64)
    hosts = np.array([[0, 1, 2], [-1, -1, -1]], dtype=np.int64)
    hw = np.full((2, 3), 1.0 / 3.0)
    npr = np.ones((2, AK.N_NP))
    npr[:, AK.NP_LAW] = 0.0
    ns = np.zeros((2, AK.N_NS))
    AK.bond_forces(xa, ua, uu, conn, hn, he, hosts, hw, npr, np.ones((1, 1)), np.ones((1, 1)),
                   np.ones(1, dtype=np.int64), np.ones(1), np.zeros((2, 2)), ns, ns.copy(),
                   np.zeros((2, AK.N_NO)), np.zeros(4), np.zeros(8))
    AK.relative_displacements(ua, uu, hn, hosts, hw, np.zeros((2, 2)))
    AK.anchor_step(ua, ua.copy(), ua.copy(), np.ones(4), np.zeros(4, np.int8), ua.copy(), 0.0,
                   1e-3, ua.copy())


if __name__ == "__main__":
    precompile()
    print("masonry_fdem: numba kernels compiled and cached")
