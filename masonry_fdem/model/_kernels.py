"""Numba kernels of the model: packing of form coefficients and the element stiffness
bounds of the stable time step. Flat arrays in, flat arrays out."""

import numpy as np
from numba import njit


@njit(cache=True)
def gather_to(src, index, pos, out):
    """out[pos[k]] = src[index[k]] (coefficient packing of one function)."""
    for k in range(index.size):
        out[pos[k]] = src[index[k]]


@njit(cache=True)
def p1_element_bounds(xy, cells, lam, mu, rho, width, omega2, rowsum):
    """Stiffness bounds of linear elastic P1 triangles with lumped mass.

    Args:
        xy: (n_nodes, 2) reference coordinates [m] of the local nodes.
        cells: (n_cells, 3) local node indices (dof = 2 node + component).
        lam, mu, rho: (n_cells,) in-plane Lamé constants [Pa] and density [kg/m³].
        width: out-of-plane width [m].
        omega2: (n_cells,) out: largest ω² of the element (K_e φ = ω² M_e φ) [1/s²].
        rowsum: (2 n_nodes,) out, accumulated: Σ_j |K_ij| (Gerschgorin bound) [N/m].

    The largest element eigenvalue bounds the largest eigenvalue of the assembled system
    (Irons' element eigenvalue inequality), so 2/√max(ω²) is a safe explicit time step.
    """
    B = np.zeros((3, 6))
    D = np.zeros((3, 3))
    for c in range(cells.shape[0]):
        n0 = cells[c, 0]
        n1 = cells[c, 1]
        n2 = cells[c, 2]
        x0, y0 = xy[n0, 0], xy[n0, 1]
        x1, y1 = xy[n1, 0], xy[n1, 1]
        x2, y2 = xy[n2, 0], xy[n2, 1]
        det = (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0)
        area = 0.5 * abs(det)
        b = (y1 - y2, y2 - y0, y0 - y1)
        g = (x2 - x1, x0 - x2, x1 - x0)
        for k in range(3):
            B[0, 2 * k] = b[k] / det
            B[0, 2 * k + 1] = 0.0
            B[1, 2 * k] = 0.0
            B[1, 2 * k + 1] = g[k] / det
            B[2, 2 * k] = g[k] / det
            B[2, 2 * k + 1] = b[k] / det
        D[0, 0] = lam[c] + 2.0 * mu[c]
        D[1, 1] = lam[c] + 2.0 * mu[c]
        D[0, 1] = lam[c]
        D[1, 0] = lam[c]
        D[2, 2] = mu[c]
        K = (B.T @ D @ B) * (area * width)
        m = rho[c] * area * width / 3.0
        w = np.linalg.eigvalsh(K)
        omega2[c] = w[-1] / m
        for k in range(3):
            node = cells[c, k]
            for a in range(2):
                s = 0.0
                for j in range(6):
                    s += abs(K[2 * k + a, j])
                rowsum[2 * node + a] += s


def precompile() -> None:
    """Compile this module's kernels on tiny arrays of the production dtypes."""
    n = 6
    gather_to(np.zeros(n), np.zeros(n, dtype=np.int64), np.zeros(n, dtype=np.int64),
              np.zeros(n))
    xy = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    one = np.ones(1)
    p1_element_bounds(xy, np.array([[0, 1, 2]], dtype=np.int64), one, one, one, 1.0,
                      np.zeros(1), np.zeros(n))
