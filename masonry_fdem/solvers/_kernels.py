"""Numba kernels of the solvers: flat arrays in, flat arrays out, no allocation per step.

Array conventions (2D, block size 2): a nodal vector of ``n`` local nodes is a float64
array of length ``2 n`` ordered (x0, y0, x1, y1, ...). ``presc`` is an int8 mask of the
prescribed degrees of freedom; ``vp`` their prescribed velocities [m/s].
"""

import numpy as np
from numba import njit

# indices into the energy accumulator of the explicit step
E_KINETIC = 0  # ½ m v² at the half step [J]
E_INTERNAL = 1  # work done against internal forces (= strain energy if elastic) [J]
E_EXTERNAL = 2  # work of applied loads [J]
E_DAMPING = 3  # energy dissipated by mass-proportional damping [J]
E_SUPPORT = 4  # work of the reactions at prescribed dofs [J]
E_CONTACT = 5  # work of the contact forces [J]
E_EXCHANGED = 6  # Σ over the steps of |work of the loads| + |work of the reactions| [J]
N_ENERGY = 7


@njit(cache=True)
def central_difference_step(u, v, f_int, f_ext, f_con, mass, minv, presc, vp, damping, dt,
                            reaction, energy, du, local=0.0):
    """One central-difference step with lumped mass and mass-proportional damping: the
    one integrator of every dof set (block nodes, disk centres and rotations, anchor bar
    nodes; for a rotation read torque for force and inertia for mass).

    ``local`` is the coefficient α ∈ [0, 1) of Cundall's local non-viscous damping: the
    unbalanced force g = f_ext + f_con − f_int of each free dof is reduced by
    α |g| sign(v(n−½)) (the damping energy counts its work); 0 for none.

    On entry ``v`` holds v(n-1/2) and ``u`` holds u(n); on exit v(n+1/2) and u(n+1).
    ``f_int``, ``f_ext``, ``f_con`` are the internal, applied and contact forces at u(n)
    [N]. For prescribed dofs the velocity is
    overwritten by ``vp`` and ``reaction`` receives the force the support applies [N].
    ``energy`` (N_ENERGY,) accumulates the energy account; with the half-step kinetic
    energy and midpoint work increments the discrete balance
    K + W_int + W_damp − W_ext − W_support − W_contact = K(0) holds to round-off.
    ``energy[E_EXCHANGED]`` adds the step's |W_ext| + |W_support| (the energy the loads
    and supports put through the set, however its sign changes: the scale of the
    account's residual).
    ``du`` receives the midpoint displacement increment (v(n−½) + v(n+½)) dt/2 of each dof,
    over which any force's work in the step is ``f · du``.

    Returns the step's work of ``f_con`` [J] (also added to ``energy[E_CONTACT]``).
    """
    a1 = 1.0 - 0.5 * damping * dt
    a2 = 1.0 / (1.0 + 0.5 * damping * dt)
    kin = 0.0
    w_int = 0.0
    w_ext = 0.0
    w_damp = 0.0
    w_sup = 0.0
    w_con = 0.0
    # one add per accumulator and dof (the sums are chains of dependent adds: the loop
    # waits on their latency, not on memory; two adds into w_damp per dof made it 1.7x
    # slower); the ½ of the kinetic energy is taken once
    for i in range(u.size):
        vo = v[i]
        g = f_ext[i] + f_con[i] - f_int[i]
        m = mass[i]
        fd = 0.0
        if presc[i]:
            vn = vp[i]
            r = m * (vn - vo) / dt + 0.5 * damping * m * (vn + vo) - g
            reaction[i] = r
            w_sup += r * 0.5 * (vn + vo) * dt
        else:
            if local > 0.0 and vo != 0.0:
                fd = local * abs(g) if vo > 0.0 else -local * abs(g)
            vn = (a1 * vo + dt * (g - fd) * minv[i]) * a2
        vb = 0.5 * (vo + vn) * dt
        du[i] = vb
        w_int += f_int[i] * vb
        w_ext += f_ext[i] * vb
        w_con += f_con[i] * vb
        w_damp += (fd + damping * m * 0.5 * (vn + vo)) * vb
        kin += m * vn * vn
        v[i] = vn
        u[i] += dt * vn
    energy[E_KINETIC] = 0.5 * kin
    energy[E_INTERNAL] += w_int
    energy[E_EXTERNAL] += w_ext
    energy[E_DAMPING] += w_damp
    energy[E_SUPPORT] += w_sup
    energy[E_CONTACT] += w_con
    energy[E_EXCHANGED] += abs(w_ext) + abs(w_sup)
    return w_con


@njit(cache=True)
def dr_measure(u, u0, v, f_int, f_int0, f_ext, mfict, presc, out):
    """Quantities of one dynamic-relaxation iteration, before the update.

    out[0] = |r|² over free dofs; out[1] = Δxᵀ (f_int(u) − f_int(u0)) = Δxᵀ K_s Δx, the
    numerator of the Rayleigh quotient with the secant stiffness K_s; out[2] = Δxᵀ M Δx,
    its denominator; out[3] = fictitious kinetic energy ½ Σ m v². Δx = u − u0 is the
    displacement since the start of the load increment, the shape of the lowest mode the
    iteration is converging along.
    """
    r2 = 0.0
    num = 0.0
    den = 0.0
    ke = 0.0
    for i in range(u.size):
        if presc[i]:
            continue
        r = f_ext[i] - f_int[i]
        r2 += r * r
        dx = u[i] - u0[i]
        num += dx * (f_int[i] - f_int0[i])
        den += mfict[i] * dx * dx
        ke += 0.5 * mfict[i] * v[i] * v[i]
    out[0] = r2
    out[1] = num
    out[2] = den
    out[3] = ke


@njit(cache=True)
def dr_velocity_quotient(v, f, f_prev, mfict, presc, first, out):
    """The velocity Rayleigh quotient's parts over the free dofs, then ``f_prev = f``.

    out[0] = vᵀ (f − f_prev) = vᵀ K v (v = u − u_prev with dt = 1), out[1] = vᵀ M v; both
    zero on the ``first`` iteration, where there is no previous force yet.
    """
    num = 0.0
    den = 0.0
    for i in range(v.size):
        if not first and not presc[i]:
            num += v[i] * (f[i] - f_prev[i])
            den += mfict[i] * v[i] * v[i]
        f_prev[i] = f[i]
    out[0] = num
    out[1] = den


@njit(cache=True)
def dr_update(u, v, f_int, f_ext, mfict, presc, c, dt, first):
    """Underwood's DR update: v(n+1/2) = ((2 − c dt) v(n−1/2) + 2 dt r/m) / (2 + c dt).

    With ``first`` the start-up v(1/2) = dt r / (2 m) is used. Prescribed dofs stay put.
    """
    for i in range(u.size):
        if presc[i]:
            v[i] = 0.0
            continue
        r = f_ext[i] - f_int[i]
        if first:
            vn = 0.5 * dt * r / mfict[i]
        else:
            vn = ((2.0 - c * dt) * v[i] + 2.0 * dt * r / mfict[i]) / (2.0 + c * dt)
        v[i] = vn
        u[i] += dt * vn


@njit(cache=True)
def dot(a, b):
    """Σ a_i b_i of two 1D float arrays, one thread. The explicit step's work bookkeeping
    uses it instead of ``np.dot``: OpenBLAS threads a dot product above 10 000 entries (a
    disk set of 5 000 disks), and on 2 cores shared with MPI ranks those threads made the
    step of a 5 000-disk fill 5-50x slower (0.7 ms -> 7-34 ms, benchmarks/bridge_disks.py)."""
    # four partial sums (one chain of dependent adds waits on the add latency); the
    # order is fixed by the length alone, so a given pair of arrays always sums alike
    s0 = 0.0
    s1 = 0.0
    s2 = 0.0
    s3 = 0.0
    n = a.size
    m = n - n % 4
    for i in range(0, m, 4):
        s0 += a[i] * b[i]
        s1 += a[i + 1] * b[i + 1]
        s2 += a[i + 2] * b[i + 2]
        s3 += a[i + 3] * b[i + 3]
    for i in range(m, n):
        s0 += a[i] * b[i]
    return (s0 + s1) + (s2 + s3)


def precompile() -> None:
    """Compile this module's kernels on tiny arrays of the production dtypes."""
    n = 6
    u, v, f, m = np.zeros(n), np.zeros(n), np.zeros(n), np.ones(n)
    mask = np.zeros(n, dtype=np.int8)
    central_difference_step(u, v, f, f, f, m, m, mask, v, 0.0, 1e-3, f.copy(),
                            np.zeros(N_ENERGY), np.zeros(n), 0.0)
    dr_measure(u, u, v, f, f, f, m, mask, np.zeros(4))
    dr_update(u, v, f, f, m, mask, 0.0, 1.0, True)
    dr_velocity_quotient(v, f, f.copy(), m, mask, True, np.zeros(6)[4:])
    dot(u, v)
