"""Slow, obviously correct references the fast code is checked against."""

from __future__ import annotations

import numpy as np
import scipy.sparse.linalg as spla

import dolfinx.fem
import ufl


def linear_static_solution(model, load_factor: float = 1.0) -> np.ndarray:
    """Small-strain linear elastic solution on the model's mesh, with the same materials,
    loads and supports, by a direct sparse solve; returns u (n_nodes, 2) in BlockMesh node
    order on every rank. Blocks never share nodes and never span ranks, so each rank's
    local matrix is complete and is solved on its own."""
    V = model.V
    u, w = ufl.TrialFunction(V), ufl.TestFunction(V)

    def eps(z):
        return ufl.sym(ufl.grad(z))

    a = 0
    for mid in model.lam:
        lam, mu = model.lam[mid], model.mu[mid]
        sig = lam * ufl.tr(eps(u)) * ufl.Identity(2) + 2 * mu * eps(u)
        a += ufl.inner(sig, eps(w)) * model.w_const * model.dx(mid)
    A = dolfinx.fem.assemble_matrix(dolfinx.fem.form(a)).to_scipy().tocsr()
    n = model.f_int.size
    A = A[:n, :n]
    mask, _ = model.prescribed_arrays(0.0)
    free = np.flatnonzero(mask == 0)
    b = model.external_force(load_factor)
    x = np.zeros(n)
    if free.size:
        x[free] = spla.spsolve(A[free][:, free].tocsc(), b[free])
    return model.gather_nodal(x)


def sweep_pairs(boxes: np.ndarray, group: np.ndarray | None = None) -> np.ndarray:
    """All pairs i < j of meeting boxes (closed), excluding equal groups: sort-and-sweep
    along the first axis, an exact method independent of the ADT. (m, 2) sorted."""
    b = np.asarray(boxes, dtype=float)
    n = b.shape[0]
    g = np.full(n, -1) if group is None else np.asarray(group)
    return _sweep(b, np.asarray(g, dtype=np.int64))


def _sweep(b, g):
    from numba import njit

    @njit(cache=False)
    def kernel(b, g, order):
        d = b.shape[1] // 2
        out = []
        n = b.shape[0]
        for a in range(n):
            i = order[a]
            for c in range(a + 1, n):
                j = order[c]
                if b[j, 0] > b[i, d]:
                    break
                if g[i] >= 0 and g[i] == g[j]:
                    continue
                ok = True
                for k in range(d):
                    if b[i, k] > b[j, d + k] or b[j, k] > b[i, d + k]:
                        ok = False
                        break
                if ok:
                    out.append((min(i, j), max(i, j)))
        return out

    order = np.argsort(b[:, 0], kind="stable")
    pairs = np.array(kernel(b, g, order), dtype=np.int64).reshape(-1, 2)
    return pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))]
