"""Numba kernels of the facet-to-facet penalty contact between deformable blocks (2D).

Arrays (local numbering):
    X: (n_nodes, 2) reference coordinates [m]; u, v: (2 n_nodes,) displacement [m] and
    velocity [m/s]; facets: (n_f, 2) node pairs, counter-clockwise around their block
    (block interior on the left, outward normal n = (t_y, -t_x)); pairs: (n_p, 2) facet
    indices; tau: (n_p, 2) tangential traction history [Pa] of the two passes of each pair.

A pair is evaluated in two passes, each facet in turn the *slave* whose points are
checked against the *master* facet's half-plane; each pass carries half the penalty
(the symmetric two-pass treatment). In a pass the penetration g(s) = (x_s(s) − p1)·n_m ≤ 0
is linear along the slave facet, so the contact zone (slave points projecting inside the
master facet, behind it, facing it) is an interval [s0, s1] found exactly, and the normal
traction ε_n (−g) is integrated exactly by two-point Gauss with the linear shape functions
of both facets (reference paper, eq. 4).

The spring force of a pass is the gradient of the pass's energy
Π = share · w ℓ_s ∫_{s0}^{s1} ε_n g(s)²/2 ds (w the width, ℓ_s the slave's length),
the energy the account stores, so the work it does depends on the end state only. The
Gauss sum is the part of the gradient with the zone and the share held; the rest is
added: (a) the ends of the zone that move with the facets while the penetration there is
not zero (ε_n g²/2 times the rate of the end), (b) ℓ_s, (c) the share where it fades.
The reason for (a): at a convex corner of the master block a slave point inside the
corner goes to the nearer of the corner's two facets, so the zone on one facet ends at
the corner's bisector, where g ≠ 0. If the other facet's pass took the point over with
the same share, the two end terms would cancel and could be left out; but the share
belongs to the pass — the other facet of a corner sharper than 90° driven into a face
does not face the slave and takes nothing — so the energy density jumps at the bisector
and, without (a), the force is not the gradient of the energy: a 35° corner dropped
elastic and frictionless at 10 m/s gained 11 % of its energy, and the pieces of the
chimney demo gained energy as they landed. (a) is preferred to smoothing the split
(weights of both facets that vary continuously across the corner, which spoil the exact
Gauss sum of a uniform penetration near every convex corner and add forces on the
neighbours' nodes): it keeps the zones, the traction and the energy as they were, and
adds to a face resting flat on a face forces of order ε_n g² w only (a fraction g/ℓ of
its contact force). The end's rate is exact for a line of the master facet itself (its
ends); the bisector and "behind the neighbour" lines also turn with the neighbouring
facet, and there the corner is taken as rigid (the neighbour turns with the master
facet): the pair's forces stay on its four nodes, in balance in force and moment, and
are the exact gradient under any rigid motion of the corner; only the corner's own
deformation (its angle changing, a strain of the block) is left out. Where the slave
turns parallel to the line that ends its zone (within 6°, END_SIN), the end's force,
which grows as 1/sin of that angle, is ramped down to nothing (see :func:`_end_force`).
At a straight
vertex (turn below CONVEX) the end terms of the two passes that meet there cancel under
any rigid motion and are left out: kept, the end would switch between the slave's node
(no term) and the master's vertex (a term) by round-off where the nodes of flush faces
coincide. The depth limit (no point deeper than ``depth`` counts) has no end term
either: the energy falls as a slave goes past it, and its gradient would pull the slave
in.

Restitution is viscous: a normal damper acts beside the penalty spring, the normal
traction t_n = max(ε_n (−g) + c_n (−ġ), 0) with ġ the rate of the gap (the normal
relative velocity of the slave point and the master point it faces). The sum is clipped
at zero, so the damper never pulls: a contact separates when spring and damper together
stop pushing. Friction is capped by μ times that clipped traction. A contact that is
closed and loaded keeps its spring force and its friction: no gap is shifted, and the
damper lowers the traction only while the gap opens, to zero only if it opens faster
than ε_n (−g)/c_n (the old hysteretic law, an unloading branch stiffer by 1/e², opened a
loaded pivot as a rocking block lifted off it, and the block slid off its corner).

Friction is an elastic predictor and a Coulomb return on the traction history of each
pass, the tangential spring ε_t storing F t/(2 ε_t) (F the pass's friction force, t its
traction). What it dissipates in a step is the work its force did over the step's slip
increment, taken at the mean of its old and new values as central difference counts the
work of a force, less the change of that stored energy (Itasca's slip energy); a spring
that lets go as its pass separates has its energy counted as dissipated. This closes the
account whatever the zone's area does in the step; the return's own t_max Δγ_p did not
(a zone that grows under a held traction stores energy no force put in: a frictional
corner impact left +0.9 % of the energy put through, the chimney demo +4.9 %).

The damping coefficient c_n [Pa s/m] is set per pair of blocks so that the two blocks,
moving as rigid bodies on the springs of their contact, form a spring–dashpot of damping
ratio ζ (see :func:`contact_damping`): c = 2 ζ √(K m), with K [N/m] the total normal
stiffness of the contact between the two blocks now and m [kg] the blocks' effective mass
at its centre along its normal. ζ comes from the restitution coefficient e through the
impact of that clipped spring–dashpot (:func:`clipped_restitution`), for the shape of the
contact: uniform penetration for a face on a face, a wedge (force ∝ penetration²) for a
vertex on a face (2D).
"""

import math

import numpy as np
from numba import njit

GAUSS = 0.5 / math.sqrt(3.0)
# a pass acts fully when the facets are within 60° of facing each other (−cos ≥ 0.5)
# and fades linearly to nothing as they become perpendicular
FACING = 0.5
# sine of the smallest turn at a boundary vertex that makes it a corner (0.06°)
CONVEX = 1e-3
# sine of the angle between a slave facet and the line that ends its zone below which
# the force of that end is ramped down to nothing (see _end_force)
END_SIN = 0.1

# results of one pass, in a small work array
Z_S0 = 0
Z_S1 = 1
Z_LEN = 2  # zone length [m]
Z_ACTIVE = 3
Z_PEN = 4  # largest penetration in the zone [m]
# the line that bounds the zone at s0 and at s1: its normal c (x, y) and the master
# vertex it passes through (1: p1, 2: p2; 0: no line, or one on which the penetration
# is zero, so the end needs no term; see _clip)
Z_C0X = 5
Z_C0Y = 6
Z_V0 = 7
Z_C1X = 8
Z_C1Y = 9
Z_V1 = 10
N_WORK = 11

# the energies of one call of facet_facet_forces
N_ENERGY = 4  # normal, tangential stored; friction, damper dissipated this step [J]

# per pair of blocks (slot), the sums of contact_damping
A_K = 0  # Σ k: the passes' normal stiffnesses [N/m]
A_X = 1  # Σ k x: zone centres, x and y [N]
A_Y = 2
A_NX = 3  # Σ k n: normals, from the slot's first block to its second [N/m]
A_NY = 4
A_XX = 5  # Σ k n nᵀ: the contact's stiffness tensor, xx, xy, yy [N/m]
A_XY = 6
A_YY = 7
A_F = 8  # Σ k δ_mean: spring force [N]
A_PEN = 9  # Σ k δ_max [N]
A_COEF = 10  # result: 2 ζ √(m/K) [s]
N_ACC = 11


@njit(cache=True, inline="always")
def _pos(X, u, node, ox, oy):
    """Current position of ``node`` relative to the origin (ox, oy) [m]: the reference
    offset first, then the displacement. Every rule of a pass is translation invariant;
    with the origin at a reference node of the pair, the offsets between the nodes of a
    joint are exact (zero for coincident nodes) and the gaps keep the full precision of
    the displacements, instead of the ~1e-16 m of an absolute coordinate near 1 m (which
    times a stiff penalty gave a force round-off floor near 1e-7 of the loads)."""
    return (X[node, 0] - ox) + u[2 * node], (X[node, 1] - oy) + u[2 * node + 1]


@njit(cache=True, inline="always")
def _clip(a, b, lim, cx, cy, vertex):
    """Restrict [lim[0], lim[1]] to {s : a + b s >= 0}; False when it becomes empty.

    ``lim`` is the work array of ``_zone`` (its first two entries are s0, s1). The clip
    is a + b s = (q(s) − p_vertex)·c ≥ 0 up to a positive factor and a constant,
    c = (cx, cy), vertex 1 or 2 for p1 or p2 (3, 4: the same at an end of the master,
    see ``_zone``; 0: no end term); they are kept as those of the end the clip moves.
    """
    if b == 0.0:
        return a >= 0.0
    if b > 0.0:
        if -a / b > lim[Z_S0]:
            lim[Z_S0] = -a / b
            lim[Z_C0X] = cx
            lim[Z_C0Y] = cy
            lim[Z_V0] = vertex
    elif -a / b < lim[Z_S1]:
        lim[Z_S1] = -a / b
        lim[Z_C1X] = cx
        lim[Z_C1Y] = cy
        lim[Z_V1] = vertex
    return lim[1] > lim[0]


@njit(cache=True, inline="always")
def _gap_line(qx, qy, ax, ay, bx, by):
    """Signed distance of q from the line a→b, negative behind it (block side) [m]."""
    lx = bx - ax
    ly = by - ay
    ln = math.hypot(lx, ly)
    return ((qx - ax) * ly - (qy - ay) * lx) / ln


@njit(cache=True, inline="always")
def _neighbour_rule(q1x, q1y, q2x, q2y, ax, ay, bx, by, g1, g2, nx, ny, vertex, lim):
    """Clip the zone to slave points behind the neighbouring facet a→b and no nearer to
    the master facet's line than to its line (g ≥ h); False if the zone empties.

    (nx, ny): the master's unit normal; ``vertex`` the master vertex the neighbour shares
    (1: p1 = b, 2: p2 = a), through which both lines of the rule pass."""
    lb = math.hypot(bx - ax, by - ay)
    mx = (by - ay) / lb  # the neighbour's unit normal
    my = -(bx - ax) / lb
    h1 = (q1x - ax) * mx + (q1y - ay) * my  # signed distances from its line
    h2 = (q2x - ax) * mx + (q2y - ay) * my
    if not _clip(-h1, -(h2 - h1), lim, -mx, -my, vertex):  # h ≤ 0
        return False
    return _clip(g1 - h1, (g2 - h2) - (g1 - h1), lim, nx - mx, ny - my, vertex)  # g ≥ h


@njit(cache=True, inline="always")
def _zone(q1x, q1y, q2x, q2y, p0x, p0y, p1x, p1y, p2x, p2y, p3x, p3y, depth, out):
    """Contact zone of slave segment q1→q2 on master facet p1→p2 (see module doc).

    p0→p1 and p2→p3 are the master's neighbouring facets. A slave point is in the zone
    when it lies behind the master facet (gap g ≤ 0, g ≥ −depth), projects onto
    it, faces it, and — at a convex vertex — is also behind the neighbouring facet and no
    closer to it than to the master facet (so a point near a corner is assigned to the
    facet it is nearest to, and points under another face of the block are not counted).
    All conditions are linear in the slave parameter s, so the zone is an interval
    [s0, s1] found exactly.

    out: [s0, s1, zone length, active, largest penetration −g]; active = 0 when empty.
    """
    out[Z_ACTIVE] = 0.0
    lm = math.hypot(p2x - p1x, p2y - p1y)
    ls = math.hypot(q2x - q1x, q2y - q1y)
    if lm <= 0.0 or ls <= 0.0:
        return
    tx = (p2x - p1x) / lm
    ty = (p2y - p1y) / lm
    # the slave must face the master: outward normals opposed
    if (q2y - q1y) * ty + (q2x - q1x) * tx >= 0.0:
        return
    lim = out  # s0, s1 live in out[0], out[1] (Z_S0, Z_S1)
    lim[Z_S0] = 0.0
    lim[Z_S1] = 1.0
    lim[Z_V0] = 0.0  # the slave's own ends: fixed in s
    lim[Z_V1] = 0.0
    xi1 = (q1x - p1x) * tx + (q1y - p1y) * ty
    xi2 = (q2x - p1x) * tx + (q2y - p1y) * ty
    g1 = _gap_line(q1x, q1y, p1x, p1y, p2x, p2y)
    g2 = _gap_line(q2x, q2y, p1x, p1y, p2x, p2y)
    # ξ ≥ 0 and ξ ≤ ℓ_m (3, 4: the master's ends, p1 and p2; see below)
    if not _clip(xi1, xi2 - xi1, lim, tx, ty, 3.0):
        return
    if not _clip(lm - xi1, -(xi2 - xi1), lim, -tx, -ty, 4.0):
        return
    # g ≤ 0: no penetration at the end, no term
    if not _clip(-g1, -(g2 - g1), lim, 0.0, 0.0, 0.0):
        return
    # g ≥ −depth: no term either. The points deeper than that leave the energy, so its
    # gradient there would pull the slave in: a corner past the depth would be drawn
    # further in and held (seen in the chimney demo: corners jammed at the depth)
    if not _clip(depth + g1, g2 - g1, lim, 0.0, 0.0, 0.0):
        return
    # the turns of the boundary at p1 and p2 (> 0: convex) and their thresholds
    turn1 = (p1x - p0x) * (p2y - p1y) - (p1y - p0y) * (p2x - p1x)
    turn2 = (p2x - p1x) * (p3y - p2y) - (p2y - p1y) * (p3x - p2x)
    conv1 = CONVEX * math.hypot(p1x - p0x, p1y - p0y) * lm
    conv2 = CONVEX * lm * math.hypot(p3x - p2x, p3y - p2y)
    # an end of the zone at an end of the master: where the boundary goes straight on,
    # the neighbour's pass takes over with the same penetration and the two end terms
    # would cancel (left out); else it is an end at p1 or p2
    for e in range(2):
        ve = Z_V0 if e == 0 else Z_V1
        if lim[ve] == 3.0:
            lim[ve] = 0.0 if abs(turn1) <= conv1 else 1.0
        elif lim[ve] == 4.0:
            lim[ve] = 0.0 if abs(turn2) <= conv2 else 2.0
    # at a convex vertex (a left turn), the neighbouring facet's rule applies too; a
    # straight vertex (turn below CONVEX) is not a corner: there the two lines coincide
    # and "nearer to which facet" would be decided by round-off, switching the zone on
    # and off (seen: dynamic relaxation of an arch cycling for ever at a springing)
    if turn1 > conv1:
        if not _neighbour_rule(q1x, q1y, q2x, q2y, p0x, p0y, p1x, p1y, g1, g2, ty, -tx,
                               1.0, lim):
            return
    if turn2 > conv2:
        if not _neighbour_rule(q1x, q1y, q2x, q2y, p2x, p2y, p3x, p3y, g1, g2, ty, -tx,
                               2.0, lim):
            return
    out[Z_LEN] = (lim[Z_S1] - lim[Z_S0]) * ls
    out[Z_PEN] = -min(g1 + lim[Z_S0] * (g2 - g1), g1 + lim[Z_S1] * (g2 - g1))
    out[Z_ACTIVE] = 1.0


@njit(cache=True, inline="always")
def _pass_points(X, u, facets, fs, fm):
    """The end points of slave facet fs and master facet fm relative to the reference
    position of the master's first node (as :func:`_pass_zone` returns them)."""
    ox = X[facets[fm, 0], 0]
    oy = X[facets[fm, 0], 1]
    q1x, q1y = _pos(X, u, facets[fs, 0], ox, oy)
    q2x, q2y = _pos(X, u, facets[fs, 1], ox, oy)
    p1x, p1y = _pos(X, u, facets[fm, 0], ox, oy)
    p2x, p2y = _pos(X, u, facets[fm, 1], ox, oy)
    return q1x, q1y, q2x, q2y, p1x, p1y, p2x, p2y


@njit(cache=True, inline="always")
def _pass_zone(X, u, facets, fprev, fnext, fs, fm, depth, work):
    """Zone of slave facet fs on master facet fm; returns the four facet end points
    relative to the reference position of the master's first node."""
    q1x, q1y, q2x, q2y, p1x, p1y, p2x, p2y = _pass_points(X, u, facets, fs, fm)
    ox = X[facets[fm, 0], 0]
    oy = X[facets[fm, 0], 1]
    p0x, p0y = _pos(X, u, facets[fprev[fm], 0], ox, oy)
    p3x, p3y = _pos(X, u, facets[fnext[fm], 1], ox, oy)
    _zone(q1x, q1y, q2x, q2y, p0x, p0y, p1x, p1y, p2x, p2y, p3x, p3y, depth, work)
    return q1x, q1y, q2x, q2y, p1x, p1y, p2x, p2y


@njit(cache=True, inline="always")
def _far_apart(X, u, facets, fa, fb, dk):
    """Whether the boxes of facets fa and fb are further apart than dk [m] (a pair that
    cannot be in contact: no penetration deeper than dk is considered)."""
    ox = X[facets[fa, 0], 0]
    oy = X[facets[fa, 0], 1]
    ax1, ay1 = _pos(X, u, facets[fa, 0], ox, oy)
    ax2, ay2 = _pos(X, u, facets[fa, 1], ox, oy)
    bx1, by1 = _pos(X, u, facets[fb, 0], ox, oy)
    bx2, by2 = _pos(X, u, facets[fb, 1], ox, oy)
    return (min(ax1, ax2) > max(bx1, bx2) + dk or min(bx1, bx2) > max(ax1, ax2) + dk
            or min(ay1, ay2) > max(by1, by2) + dk or min(by1, by2) > max(ay1, ay2) + dk)


@njit(cache=True, inline="always")
def _pass_share(q1x, q1y, q2x, q2y, tx, ty):
    """The share of the pair's traction a pass carries: half, faded out smoothly as the
    two facets turn from facing each other (within FACING of anti-parallel) to
    perpendicular, so a pass never switches on or off with a jump in force (the force
    of its gradient, where it fades, is added in :func:`_pair_forces`)."""
    ls = math.hypot(q2x - q1x, q2y - q1y)
    cosf = ((q2x - q1x) * tx + (q2y - q1y) * ty) / ls  # < 0 when facing
    return 0.5 * min(1.0, -cosf / FACING)


@njit(cache=True, inline="always")
def _end_force(coef, se, cx, cy, vertex, q1x, q1y, q2x, q2y, p1x, p1y, p2x, p2y, nx, ny,
               lm, f, sb, mb):
    """Add −coef ∂s_e/∂x into ``f``: the force of a zone end s_e that moves with the
    facets while the penetration there is not zero (coef = ± the potential per unit s at
    the end, + at s1, − at s0).

    The end is where the slave crosses the line (x − v)·c = 0, v the master vertex
    ``vertex`` (1: p1, 2: p2), c turning with the master facet (exact for the master's
    own lines; for the neighbour's lines of :func:`_neighbour_rule`, the corner is taken
    as rigid: the neighbour turns with the master, which puts the force of the
    neighbour's far node on the master's nodes and keeps the forces on the four nodes of
    the pair, in balance in force and moment).
    """
    dx = q2x - q1x
    dy = q2y - q1y
    b = dx * cx + dy * cy  # ℓ_s |c| sin φ, φ the angle between the slave and the line
    # the end moves along the slave by 1/sin φ per unit motion across the line: as the
    # slave turns parallel to the line, the energy's jump at the end sweeps its whole
    # length at once and its gradient grows without bound, an impulse no explicit step
    # resolves (seen: a face along the bisector of a 16° corner, 2e8 N, the chimney demo
    # thrown apart); below sin φ = END_SIN the force is ramped down to nothing at φ = 0
    # (continuous; the energy is then not conserved in that narrow range)
    bmin = END_SIN * math.hypot(dx, dy) * math.hypot(cx, cy)
    if abs(b) >= bmin:
        k = coef / b
    else:
        k = coef * b / (bmin * bmin)
    if k == 0.0:
        return
    vx = p1x if vertex == 1.0 else p2x
    vy = p1y if vertex == 1.0 else p2y
    # (q_e − v)·J c, J the turn by +90°: ∂/∂θ of the line's function as the master turns
    r = -(q1x + se * dx - vx) * cy + (q1y + se * dy - vy) * cx
    f[sb] += k * (1.0 - se) * cx
    f[sb + 1] += k * (1.0 - se) * cy
    f[sb + 2] += k * se * cx
    f[sb + 3] += k * se * cy
    vb = mb if vertex == 1.0 else mb + 2
    f[vb] -= k * cx
    f[vb + 1] -= k * cy
    # dθ = −n·d(p2 − p1)/ℓ_m
    kr = k * r / lm
    f[mb] += kr * nx
    f[mb + 1] += kr * ny
    f[mb + 2] -= kr * nx
    f[mb + 3] -= kr * ny


@njit(cache=True)
def _pair_forces(k, X, u, v, facets, fprev, fnext, pairs, eps_n, eps_t, mu, cdamp, depth,
                 width, dt, tau, tforce, f, fdamp, work, stick):
    """Forces of candidate pair ``k`` on its four nodes added into ``f`` (8,), their
    dampers' part also into ``fdamp`` (8,): x, y on the nodes of facet ``pairs[k, 0]``
    (first, second), then on those of ``pairs[k, 1]`` (see :func:`facet_facet_forces`).

    ``stick``: the friction branch of each pass, two bits per pass (pass p in bits 2p,
    2p + 1; 0 everywhere: the Coulomb return decides): 1 stick (no return: the tangent at
    the apex of the friction cone), 2 slip forward (τ = +μ p̄), 3 slip backward (τ = −μ p̄)
    — the branch a tangent's perturbed evaluations hold (:func:`facet_facet_tangent`).

    Returns (normal penalty energy, tangential elastic energy, frictional dissipation,
    damper dissipation [J], whether a pass is active, the largest penetration of an
    active pass [m], −1 if none).
    """
    # cheap rejection: facets whose boxes are further apart than the largest
    # penetration considered cannot be in contact
    if _far_apart(X, u, facets, pairs[k, 0], pairs[k, 1], depth[k]):
        d_f = _release(k, 0, tau, tforce, eps_t) + _release(k, 1, tau, tforce, eps_t)
        return 0.0, 0.0, d_f, 0.0, False, -1.0
    return _pair_passes(k, X, u, v, facets, fprev, fnext, pairs, eps_n, eps_t, mu, cdamp,
                        depth, width, dt, tau, tforce, f, fdamp, work, stick, work, False)


@njit(cache=True, inline="always")
def _end_pair(f, b, gx, gy):
    """Add (gx, gy) [N] on the second node of the facet whose slots in ``f`` start at b,
    and its opposite on the first (a force pair along the facet's two ends)."""
    f[b] -= gx
    f[b + 1] -= gy
    f[b + 2] += gx
    f[b + 3] += gy


@njit(cache=True, inline="always")
def _release(k, p, tau, tforce, eps_t):
    """Pass p of pair k separated: its tangential spring lets go (history zeroed); the
    energy it held, F t / (2 ε_t) [J], is returned, to be counted as dissipated."""
    e = 0.5 * tforce[k, p] * tau[k, p] / eps_t[k]
    tau[k, p] = 0.0
    tforce[k, p] = 0.0
    return e


@njit(cache=True, inline="always")
def _pair_passes(k, X, u, v, facets, fprev, fnext, pairs, eps_n, eps_t, mu, cdamp, depth,
                 width, dt, tau, tforce, f, fdamp, work, stick, zones, use_zones):
    """:func:`_pair_forces` of a pair that the box test did not reject: its two passes.

    Inlined (as are the small functions it calls) into the loops over pairs, which test
    the boxes first: a call per pair cost more than the pass itself (~150 ns, measured:
    the pair loop of a 14 500-facet wall went from 21 to 6 ms per step).

    ``use_zones``: take each pass's zone from ``zones[k, p]`` (:func:`contact_damping`
    found them at the same positions) instead of finding it again."""
    e_n = 0.0
    e_t = 0.0
    d_f = 0.0
    d_v = 0.0
    active = False
    apex = -1.0
    fa = pairs[k, 0]
    fb = pairs[k, 1]
    for p in range(2):
        fs = fb if p == 0 else fa
        fm = fa if p == 0 else fb
        s1n = facets[fs, 0]
        s2n = facets[fs, 1]
        m1n = facets[fm, 0]
        m2n = facets[fm, 1]
        sb = 4 if p == 0 else 0  # the slave's and the master's slots in f
        mb = 4 - sb
        if use_zones:
            if zones[k, p, Z_ACTIVE] == 0.0:  # separated
                d_f += _release(k, p, tau, tforce, eps_t)
                continue
            q1x, q1y, q2x, q2y, p1x, p1y, p2x, p2y = _pass_points(X, u, facets, fs, fm)
            for c in range(N_WORK):
                work[c] = zones[k, p, c]
        else:
            q1x, q1y, q2x, q2y, p1x, p1y, p2x, p2y = _pass_zone(
                X, u, facets, fprev, fnext, fs, fm, depth[k], work
            )
        if work[Z_ACTIVE] == 0.0:  # separated
            d_f += _release(k, p, tau, tforce, eps_t)
            continue
        active = True
        s0 = work[Z_S0]
        s1 = work[Z_S1]
        zlen = work[Z_LEN]
        lm = math.hypot(p2x - p1x, p2y - p1y)
        tx = (p2x - p1x) / lm
        ty = (p2y - p1y) / lm
        nx = ty
        ny = -tx
        # each pass carries half of the pair's traction (faded as the facets turn)
        half = _pass_share(q1x, q1y, q2x, q2y, tx, ty)
        # --- normal: spring ε_n (−g) and damper c_n (−ġ), their sum clipped at zero,
        # integrated by two-point Gauss against N_i over the zone (exact for the spring)
        fs1 = 0.0  # slave node 1, 2 normal force magnitudes (along +n_m)
        fs2 = 0.0
        fm1 = 0.0  # master node 1, 2
        fm2 = 0.0
        pot = 0.0
        pbar = 0.0
        ds1 = 0.0  # the dampers' part of fs1, fs2, fm1, fm2
        ds2 = 0.0
        dm1 = 0.0
        dm2 = 0.0
        cd = cdamp[k]
        for gp in range(2):
            s = 0.5 * (s0 + s1) + (GAUSS if gp == 0 else -GAUSS) * (s1 - s0)
            qx = q1x + s * (q2x - q1x)
            qy = q1y + s * (q2y - q1y)
            g = (qx - p1x) * nx + (qy - p1y) * ny
            xi = ((qx - p1x) * tx + (qy - p1y) * ty) / lm
            wgt = 0.5 * zlen * width * half  # Gauss weight x length x width x pass
            ts = -eps_n[k] * g  # spring traction, >= 0
            tr = ts
            if cd > 0.0:
                # gap rate: normal velocity of the slave point relative to the master's
                gd = ((1.0 - s) * v[2 * s1n] + s * v[2 * s2n]
                      - (1.0 - xi) * v[2 * m1n] - xi * v[2 * m2n]) * nx + (
                    (1.0 - s) * v[2 * s1n + 1] + s * v[2 * s2n + 1]
                    - (1.0 - xi) * v[2 * m1n + 1] - xi * v[2 * m2n + 1]) * ny
                # a point that entered the contact during this step has approached by
                # −g, not by −ġ dt: the damper's impulse in the step is held to c (−g)
                # (else the step in which contact begins gets the full c ġ dt whatever
                # part of it was in contact: an error of up to 2 ζ ω dt of the impact
                # momentum, seen as ±4 % scatter of e = 0.2 with the phase of the onset)
                if gd * dt < g:
                    gd = g / dt
                tr = ts - cd * gd
                if tr < 0.0:
                    tr = 0.0  # the damper never pulls
                # the damper's part of the traction, tr − ts, and its forces
                td = wgt * (tr - ts)
                d_v += td * (-gd) * dt
                ds1 += td * (1.0 - s)
                ds2 += td * s
                dm1 += td * (1.0 - xi)
                dm2 += td * xi
            fs1 += wgt * tr * (1.0 - s)
            fs2 += wgt * tr * s
            fm1 += wgt * tr * (1.0 - xi)
            fm2 += wgt * tr * xi
            pot += wgt * 0.5 * eps_n[k] * g * g
            pbar += 0.5 * tr
        # --- relative tangential velocity at the zone centre
        sc = 0.5 * (s0 + s1)
        qcx = q1x + sc * (q2x - q1x)
        qcy = q1y + sc * (q2y - q1y)
        xic = ((qcx - p1x) * tx + (qcy - p1y) * ty) / lm
        vt = ((1.0 - sc) * v[2 * s1n] + sc * v[2 * s2n]
              - (1.0 - xic) * v[2 * m1n] - xic * v[2 * m2n]) * tx + (
            (1.0 - sc) * v[2 * s1n + 1] + sc * v[2 * s2n + 1]
            - (1.0 - xic) * v[2 * m1n + 1] - xic * v[2 * m2n + 1]) * ty
        # --- friction: elastic predictor, Coulomb return on the mean normal traction
        # (spring and damper, clipped)
        t_old = tau[k, p]
        t_trial = t_old + eps_t[k] * vt * dt
        t_max = mu[k] * pbar
        apex = max(apex, work[Z_PEN])
        branch = (stick >> (2 * p)) & 3
        if branch == 0:
            if abs(t_trial) > t_max:
                t_new = t_max if t_trial > 0.0 else -t_max
            else:
                t_new = t_trial
        elif branch == 1:
            t_new = t_trial
        else:
            t_new = t_max if branch == 2 else -t_max
        tau[k, p] = t_new
        # the friction force [N] and its dissipation in the step: the work it did over
        # the slip increment vt dt at the mean of its old and new values (as central
        # difference counts the work of a force) less the change of the tangential
        # spring's energy F t / (2 ε_t) — Itasca's slip energy; exact for the scheme
        # whatever the zone's area does (a zone that grows or shrinks under a held
        # traction changes the spring's energy: a return on t alone missed that)
        f_new = t_new * zlen * width * half
        f_old = tforce[k, p]
        d_f += (0.5 * vt * dt * (f_new + f_old)
                - 0.5 * (f_new * t_new - f_old * t_old) / eps_t[k])
        tforce[k, p] = f_new
        e_t += 0.5 * f_new * t_new / eps_t[k]
        e_n += pot
        # friction traction, uniform over the zone, opposes the slave's slip
        a = zlen * width * half * t_new
        f[sb] += fs1 * nx - (1.0 - sc) * a * tx
        f[sb + 1] += fs1 * ny - (1.0 - sc) * a * ty
        f[sb + 2] += fs2 * nx - sc * a * tx
        f[sb + 3] += fs2 * ny - sc * a * ty
        f[mb] -= fm1 * nx - (1.0 - xic) * a * tx
        f[mb + 1] -= fm1 * ny - (1.0 - xic) * a * ty
        f[mb + 2] -= fm2 * nx - xic * a * tx
        f[mb + 3] -= fm2 * ny - xic * a * ty
        # --- the rest of the gradient of the pass's spring potential
        # Π = share · w ℓ_s ∫_{s0}^{s1} ε g²/2 ds (the Gauss sum above is its partial
        # derivative with the zone and the share held): the ends of the zone where the
        # penetration is not zero, the slave's length ℓ_s and the share
        ls = zlen / (s1 - s0)  # the slave's length (s1 > s0 in an active zone)
        if work[Z_V0] != 0.0 or work[Z_V1] != 0.0:
            for e in range(2):
                se = s0 if e == 0 else s1
                vtx = work[Z_V0] if e == 0 else work[Z_V1]
                if vtx == 0.0:
                    continue
                g = (q1x + se * (q2x - q1x) - p1x) * nx + (q1y + se * (q2y - q1y) - p1y) * ny
                coef = 0.5 * eps_n[k] * g * g * width * half * ls
                if e == 0:
                    _end_force(-coef, se, work[Z_C0X], work[Z_C0Y], vtx, q1x, q1y, q2x,
                               q2y, p1x, p1y, p2x, p2y, nx, ny, lm, f, sb, mb)
                else:
                    _end_force(coef, se, work[Z_C1X], work[Z_C1Y], vtx, q1x, q1y, q2x,
                               q2y, p1x, p1y, p2x, p2y, nx, ny, lm, f, sb, mb)
        tsx = (q2x - q1x) / ls
        tsy = (q2y - q1y) / ls
        # ∂ℓ_s: Π ∝ ℓ_s
        _end_pair(f, sb, -pot / ls * tsx, -pot / ls * tsy)
        cosf = ((q2x - q1x) * tx + (q2y - q1y) * ty) / ls  # as in _pass_share: < 0
        if -FACING < cosf < 0.0:
            # share = −cos/(2 FACING): −∂Π/∂x = Π/(−cos) ∂cos/∂x
            a = pot / -cosf
            _end_pair(f, sb, a * (tx - cosf * tsx) / ls, a * (ty - cosf * tsy) / ls)
            _end_pair(f, mb, a * (tsx - cosf * tx) / lm, a * (tsy - cosf * ty) / lm)
        if cd > 0.0:
            fdamp[sb] += ds1 * nx
            fdamp[sb + 1] += ds1 * ny
            fdamp[sb + 2] += ds2 * nx
            fdamp[sb + 3] += ds2 * ny
            fdamp[mb] -= dm1 * nx
            fdamp[mb + 1] -= dm1 * ny
            fdamp[mb + 2] -= dm2 * nx
            fdamp[mb + 3] -= dm2 * ny
    return e_n, e_t, d_f, d_v, active, apex


@njit(cache=True)
def facet_facet_forces(X, u, v, facets, fprev, fnext, pairs, eps_n, eps_t, mu, cdamp, depth,
                       width, dt, tau, tforce, counted, fp, fdp, energy, work, zones,
                       use_zones):
    """Penalty normal, viscous normal and Coulomb friction forces of all candidate pairs,
    pair by pair (summed into the nodes by :func:`masonry_fdem.interactions._sums.gather_rows`,
    in an order that does not depend on how the blocks are spread over ranks).

    Args:
        eps_n, eps_t, mu, depth: (n_p,) normal and tangential penalty [Pa/m], friction
            coefficient and largest penetration considered [m] of each pair.
        cdamp: (n_p,) normal damping coefficient c_n [Pa s/m] of each pair (0: none;
            :func:`contact_damping`).
        width: out-of-plane width [m].
        dt: time step [s] (tangential slip increment = relative velocity · dt).
        tau: (n_p, 2) in/out tangential traction history [Pa] of the two passes.
        tforce: (n_p, 2) in/out the friction force [N] of each pass at the last call (for
            its dissipation; zero where tau is).
        counted: (n_p,) weight of each pair in ``energy`` (1; 0 for the copy of a pair
            another rank counts).
        fp: (n_p, 8) out: the contact forces of each pair on its four nodes [N], x and y
            on the nodes of facet ``pairs[k, 0]``, then on those of ``pairs[k, 1]``.
        fdp: (n_p, 8) out: the dampers' part of them [N] (the traction spring + damper,
            clipped, less the spring's), for the energy account.
        energy: (N_ENERGY,) out: [normal penalty energy, tangential elastic energy,
            frictional dissipation this step, damper dissipation this step with the
            velocities the dampers see (the half step before)] [J].
        work: (N_WORK,) scratch.
        zones: (n_p, 2, N_WORK) the zones of the pairs' passes at these positions, as
            :func:`contact_damping` leaves them, used when ``use_zones`` (else not read).
    """
    e_n = 0.0
    e_t = 0.0
    d_f = 0.0
    d_v = 0.0
    for k in range(pairs.shape[0]):
        for j in range(8):
            fp[k, j] = 0.0
            fdp[k, j] = 0.0
        if use_zones:
            off = zones[k, 0, Z_ACTIVE] == 0.0 and zones[k, 1, Z_ACTIVE] == 0.0
        else:
            off = _far_apart(X, u, facets, pairs[k, 0], pairs[k, 1], depth[k])
        if off:  # separated, or out of reach (see _pair_forces)
            if tau[k, 0] != 0.0 or tau[k, 1] != 0.0:
                d_f += counted[k] * (_release(k, 0, tau, tforce, eps_t)
                                     + _release(k, 1, tau, tforce, eps_t))
            continue
        a, b, c, d, _, _ = _pair_passes(k, X, u, v, facets, fprev, fnext, pairs, eps_n,
                                        eps_t, mu, cdamp, depth, width, dt, tau, tforce,
                                        fp[k], fdp[k], work, 0, zones, use_zones)
        w = counted[k]
        e_n += w * a
        e_t += w * b
        d_f += w * c
        d_v += w * d
    energy[0] = e_n
    energy[1] = e_t
    energy[2] = d_f
    energy[3] = d_v


@njit(cache=True)
def contact_damping(X, u, facets, fprev, fnext, pairs, facet_block, eps_n, depth, width,
                    slot, slot_block, inv_mass, inv_inertia, centroid, zeta1, zeta2, acc,
                    cdamp, work, zones):
    """The normal damping coefficient c_n [Pa s/m] of every candidate pair.

    Restitution is a property of an impact between two bodies, so the damper is set per
    pair of blocks (``slot``), from the blocks as rigid bodies on the springs of their
    contact: a spring–dashpot of stiffness K, mass m and damper c = 2 ζ √(K m).

    * K [N/m]: the stiffness of the contact between the two blocks now along its mean
      normal n̄ (the stiffness-weighted mean of the passes' normals), n̄ᵀ (Σ k n nᵀ) n̄
      over their active passes, k = ε_n w ℓ s (ℓ the zone length, s the pass's share of
      the traction) the tangent stiffness of a pass along its normal n, for a face on a
      face (force ∝ penetration) and for a vertex on a face (force ∝ penetration² in 2D)
      alike (a vertex pressed into a face has passes along both the face's normal and
      its own faces' normals: only their part along n̄ resists the approach);
    * m [kg]: the two blocks' rigid-body effective mass at the centre of the contact x̄
      (the stiffness-weighted mean of the zone centres) along n̄:
      1/m = Σ_b (1/M_b + ((x̄ − G_b) × n̄)² / I_b), M_b, G_b, I_b the block's mass,
      centroid and polar moment of inertia from the lumped nodal masses (a block with
      a prescribed dof counts as immovable: 1/M = 1/I = 0). It is the mass Newton's
      impact law sees: a block landing flat has m = M, a block landing on a corner the
      smaller mass its rotation gives. The blocks' deformation is left out: restitution
      is a rigid-body concept, and the blocks must be stiff against the penalty for it
      to mean anything. The nodal masses at the contact would not do: they are a
      mesh-dependent fraction of the mass that moves (M/2 on the face of a block of two
      triangles, less on a finer mesh), so a damper set from them is ζ √(m_nodes/M) of
      critical for the block and e comes out too large, the more so the finer the mesh;
    * ζ = ζ1 + (p − 1)(ζ2 − ζ1), p = Σ k δ_max / Σ k δ_mean ∈ [1, 2] the exponent of the
      force law (δ_max and δ_mean the largest and the mean penetration of a pass's zone:
      p = 1 for a face on a face, 2 for a vertex on a face), ζ1 and ζ2 the damping
      ratios that give the restitution asked for on a face and on a vertex
      (:func:`clipped_restitution`).

    Each pair then gets the traction damper c_n = 2 ζ ε_n √(m / K) along its own
    normal, so that the dampers of all passes between two blocks add up to 2 ζ √(K m)
    on the rigid approach along n̄, however finely the contact is meshed.

    Args:
        facet_block: (n_f,) block id of each facet.
        slot: (n_p,) block-pair slot of each pair; slot_block: (n_slots, 2) its blocks.
        inv_mass, inv_inertia: (n_blocks,) 1/M [1/kg] and 1/I [1/(kg m²)] per block.
        centroid: (n_blocks, 2) block centroids [m].
        zeta1, zeta2: damping ratios of a face and of a vertex impact.
        acc: (n_slots, N_ACC) scratch; cdamp: (n_p,) out [Pa s/m].
        zones: (n_p, 2, N_WORK) out: the zone of each pass (:func:`_zone`'s results;
            inactive for a pair out of reach), for :func:`facet_facet_forces` at the same
            positions.
    """
    acc[:, :] = 0.0
    for k in range(pairs.shape[0]):
        fa = pairs[k, 0]
        fb = pairs[k, 1]
        if _far_apart(X, u, facets, fa, fb, depth[k]):
            zones[k, 0, Z_ACTIVE] = 0.0
            zones[k, 1, Z_ACTIVE] = 0.0
            continue
        sl = slot[k]
        for p in range(2):
            fs = fb if p == 0 else fa
            fm = fa if p == 0 else fb
            q1x, q1y, q2x, q2y, p1x, p1y, p2x, p2y = _pass_zone(
                X, u, facets, fprev, fnext, fs, fm, depth[k], work
            )
            for c in range(N_WORK):
                zones[k, p, c] = work[c]
            if work[Z_ACTIVE] == 0.0:
                continue
            lm = math.hypot(p2x - p1x, p2y - p1y)
            tx = (p2x - p1x) / lm
            ty = (p2y - p1y) / lm
            nx = ty
            ny = -tx
            kp = eps_n[k] * width * _pass_share(q1x, q1y, q2x, q2y, tx, ty) * work[Z_LEN]
            s0 = work[Z_S0]
            s1 = work[Z_S1]
            # gaps at the ends of the zone (g is linear along the slave facet)
            g1 = (q1x - p1x) * nx + (q1y - p1y) * ny
            g2 = (q2x - p1x) * nx + (q2y - p1y) * ny
            pen = -0.5 * (2.0 * g1 + (s0 + s1) * (g2 - g1))  # mean over the zone
            sc = 0.5 * (s0 + s1)
            ox = X[facets[fm, 0], 0]  # _pass_zone's origin
            oy = X[facets[fm, 0], 1]
            sg = 1.0 if facet_block[fm] == slot_block[sl, 0] else -1.0
            acc[sl, A_K] += kp
            acc[sl, A_X] += kp * (ox + q1x + sc * (q2x - q1x))
            acc[sl, A_Y] += kp * (oy + q1y + sc * (q2y - q1y))
            acc[sl, A_NX] += kp * sg * nx
            acc[sl, A_NY] += kp * sg * ny
            acc[sl, A_XX] += kp * nx * nx
            acc[sl, A_XY] += kp * nx * ny
            acc[sl, A_YY] += kp * ny * ny
            acc[sl, A_F] += kp * pen
            acc[sl, A_PEN] += kp * work[Z_PEN]
    for sl in range(acc.shape[0]):
        acc[sl, A_COEF] = 0.0
        nn = math.hypot(acc[sl, A_NX], acc[sl, A_NY])
        if acc[sl, A_K] <= 0.0 or nn <= 0.0:
            continue
        cx = acc[sl, A_X] / acc[sl, A_K]
        cy = acc[sl, A_Y] / acc[sl, A_K]
        nx = acc[sl, A_NX] / nn
        ny = acc[sl, A_NY] / nn
        K = acc[sl, A_XX] * nx * nx + 2.0 * acc[sl, A_XY] * nx * ny + acc[sl, A_YY] * ny * ny
        if K <= 0.0:
            continue
        inv_m = 0.0
        for j in range(2):
            b = slot_block[sl, j]
            cr = (cx - centroid[b, 0]) * ny - (cy - centroid[b, 1]) * nx
            inv_m += inv_mass[b] + inv_inertia[b] * cr * cr
        if inv_m <= 0.0:
            continue  # two immovable blocks
        p = acc[sl, A_PEN] / acc[sl, A_F] if acc[sl, A_F] > 0.0 else 1.0
        p = min(max(p, 1.0), 2.0)
        zeta = zeta1 + (p - 1.0) * (zeta2 - zeta1)
        acc[sl, A_COEF] = 2.0 * zeta / math.sqrt(K * inv_m)
    for k in range(pairs.shape[0]):
        cdamp[k] = eps_n[k] * acc[slot[k], A_COEF]


#: the ``stick`` code of :func:`_pair_passes` that holds both passes on the stick branch
STICK_BOTH = 1 | (1 << 2)


@njit(cache=True, inline="always")
def _held_branch(t_return, t_trial):
    """The friction branch code of one pass (:func:`_pair_passes`) from its traction
    with the Coulomb return and without: stick where they agree, else slip on the side
    of the return; none (0: the return decides) for a pass without traction (apart)."""
    if t_return == t_trial:
        return 0 if t_trial == 0.0 else 1
    return 2 if t_return > 0.0 else 3


@njit(cache=True)
def facet_facet_tangent(X, u, v, facets, fprev, fnext, pairs, eps_n, eps_t, mu, depth,
                        width, tau_c, tau, h, counted, fbuf, work, rows, cols, vals):
    """Consistent tangent −∂f/∂u of the pairs in contact, by central differences of
    :func:`_pair_forces` in each dof the pair's force depends on (its two facets' nodes
    and, through the corner rules, the far nodes of their neighbouring facets).

    Static solver convention: ``v`` is the displacement since the last commit (dt = 1),
    so a perturbation of u perturbs v alike, and each evaluation starts from the
    committed history ``tau_c``; ``tau`` is left as it was. No damper acts (a static
    state has no velocity). ``fbuf`` (8,) is scratch. Only the pairs ``counted`` (> 0)
    enter: a pair across ranks is in the lists of both and computed by one.

    At the apex of the friction cone — facets touching with no normal traction, as the
    joints of a dry structure at its unloaded start — the force is not differentiable:
    any slip slides, so the one-sided derivatives give no shear stiffness and the
    tangent of a structure on such joints is singular. There the tangent takes the stick
    branch, the limit of the tangents of the nearby compressed states that stick (an
    element of Clarke's generalised Jacobian, as a semismooth Newton method allows).

    Returns the number of COO entries written into ``rows``, ``cols`` (local extended dof
    numbers) and ``vals`` (each needs 128 entries per pair).
    """
    nodes = np.empty(8, dtype=np.int64)
    fp = np.empty(8)
    nodamp = np.zeros(pairs.shape[0])
    tforce = np.zeros(tau.shape)  # scratch: the tangent does not count dissipation
    nent = 0
    for k in range(pairs.shape[0]):
        if counted[k] <= 0.0:
            continue
        t0 = tau[k, 0]
        t1 = tau[k, 1]
        tau[k, 0] = tau_c[k, 0]
        tau[k, 1] = tau_c[k, 1]
        _, _, _, _, active, apex = _pair_forces(k, X, u, v, facets, fprev, fnext, pairs,
                                                eps_n, eps_t, mu, nodamp, depth, width, 1.0,
                                                tau, tforce, fbuf, fbuf, work, 0)
        fa = pairs[k, 0]
        fb = pairs[k, 1]
        nodes[0] = facets[fa, 0]
        nodes[1] = facets[fa, 1]
        nodes[2] = facets[fb, 0]
        nodes[3] = facets[fb, 1]
        # a pair out of reach of the perturbations has no tangent; one that is not in
        # contact but within reach (touching, up to round-off) is treated as at the apex
        near = not _far_apart(X, u, facets, fa, fb, depth[k] + 4.0 * h)
        # each pass's friction branch at the base state, held by the perturbations: a
        # pass sliding, or sticking, within ε_t h of the Coulomb limit would otherwise
        # get the mean of the two branches' stiffnesses (ε_t h ~ 30 Pa at ε_t ~ 4e12
        # Pa/m; on the full TRL arch a ring layer's contact sliding 12 Pa past its limit
        # got a tangent 18 times its stiffness along the Newton step). Touching within
        # the step, or not touching: the stick branch (the apex, above)
        stick = STICK_BOTH
        if near and apex >= 2.0 * h:
            # the base state again without the Coulomb return (the trial), against the
            # return above
            ret0 = tau[k, 0]
            ret1 = tau[k, 1]
            tau[k, 0] = tau_c[k, 0]
            tau[k, 1] = tau_c[k, 1]
            _pair_forces(k, X, u, v, facets, fprev, fnext, pairs, eps_n, eps_t, mu, nodamp,
                         depth, width, 1.0, tau, tforce, fbuf, fbuf, work, STICK_BOTH)
            stick = _held_branch(ret0, tau[k, 0]) | (_held_branch(ret1, tau[k, 1]) << 2)
        if near:
            nodes[4] = facets[fprev[fa], 0]
            nodes[5] = facets[fnext[fa], 1]
            nodes[6] = facets[fprev[fb], 0]
            nodes[7] = facets[fnext[fb], 1]
            nn = 4
            for j in range(4, 8):  # the distinct far nodes
                dup = False
                for i in range(nn):
                    if nodes[i] == nodes[j]:
                        dup = True
                if not dup:
                    nodes[nn] = nodes[j]
                    nn += 1
            for jc in range(nn):
                for c in range(2):
                    d = 2 * nodes[jc] + c
                    u0 = u[d]
                    v0 = v[d]
                    for side in range(2):
                        sg = 1.0 if side == 0 else -1.0
                        u[d] = u0 + sg * h
                        v[d] = v0 + sg * h
                        tau[k, 0] = tau_c[k, 0]
                        tau[k, 1] = tau_c[k, 1]
                        fbuf[:] = 0.0
                        _pair_forces(k, X, u, v, facets, fprev, fnext, pairs, eps_n, eps_t,
                                     mu, nodamp, depth, width, 1.0, tau, tforce, fbuf, fbuf,
                                     work, stick)
                        for i in range(4):
                            for ci in range(2):
                                if side == 0:
                                    fp[2 * i + ci] = fbuf[2 * i + ci]
                                else:
                                    fp[2 * i + ci] -= fbuf[2 * i + ci]
                    u[d] = u0
                    v[d] = v0
                    for i in range(4):
                        for ci in range(2):
                            rows[nent] = 2 * nodes[i] + ci
                            cols[nent] = d
                            vals[nent] = -fp[2 * i + ci] / (2.0 * h)
                            nent += 1
        tau[k, 0] = t0
        tau[k, 1] = t1
    return nent


@njit(cache=True)
def block_moments(X, u, mass, bptr, bnodes, out):
    """out[b] = Σ m (X + u) [kg m] over the nodes of block b: the first moments of the
    blocks' lumped masses at the current positions. ``bnodes[bptr[b]:bptr[b + 1]]`` are
    block b's nodes on this rank in their input order (the same sum on any number of
    ranks; zero for a block on another rank)."""
    for b in range(out.shape[0]):
        sx = 0.0
        sy = 0.0
        for j in range(bptr[b], bptr[b + 1]):
            i = bnodes[j]
            m = mass[2 * i]
            sx += m * (X[i, 0] + u[2 * i])
            sy += m * (X[i, 1] + u[2 * i + 1])
        out[b, 0] = sx
        out[b, 1] = sy


@njit(cache=True)
def nodal_midpoint_work(f, nodes, u_new, u_old):
    """Σ f_i (u_new,i − u_old,i)/2 [J] over the x and y dofs of ``nodes`` (ascending: the
    same sum, to the bit, as over every dof when f is zero elsewhere): the work of the
    forces f [N] of a step over its midpoint displacement increment, (u(n+1) − u(n−1))/2
    = (v(n−½) + v(n+½)) dt/2, as the explicit solver counts every force's work."""
    w = 0.0
    for n in nodes:
        w += f[2 * n] * (u_new[2 * n] - u_old[2 * n])
        w += f[2 * n + 1] * (u_new[2 * n + 1] - u_old[2 * n + 1])
    return 0.5 * w


@njit(cache=True)
def keep_damper_terms(fd, nodes_old, nodes, u_now, v, dt, u1, u2):
    """For the next step's damper work: zero ``fd`` at ``nodes_old`` (where it was
    written last), and at ``nodes`` keep u1 = u(n) and u2 = u(n) − dt v(n−½) [m]."""
    for n in nodes_old:
        fd[2 * n] = 0.0
        fd[2 * n + 1] = 0.0
    for n in nodes:
        for c in range(2):
            d = 2 * n + c
            u1[d] = u_now[d]
            u2[d] = u_now[d] - dt * v[d]


@njit(cache=True)
def _impact_acceleration(x, v, zeta, wedge):
    """δ'' of the dimensionless impact of :func:`clipped_restitution`."""
    if x <= 0.0:
        return 0.0
    if not wedge:
        force = x + 2.0 * zeta * v
        return -force if force > 0.0 else 0.0
    # wedge: F = δ², K = 2δ, c = 2 ζ √K; receding, the damper takes the traction
    # ε τ off every point, τ = −c δ'/K in units of penetration
    k = 2.0 * x
    c = 2.0 * zeta * math.sqrt(k)
    if v >= 0.0:
        return -(0.5 * k * x + c * v)
    tau = -c * v / k
    if tau >= x:
        return 0.0
    return -k * (x - tau) ** 2 / (2.0 * x)


@njit(cache=True)
def clipped_restitution(zeta, wedge):
    """Restitution coefficient e of an impact on the contact law of the kernels, with the
    damper c = 2 ζ √(K m) (K the contact's tangent stiffness, m the mass), the traction
    spring + damper clipped at zero point by point (it never pulls): the body leaves
    when the force vanishes, with the velocity it has then.

    ``wedge`` False: a face on a face, uniform penetration δ: F = max(K δ + c δ', 0)
    with K constant (closed form :func:`clipped_restitution_linear`). ``wedge`` True: a
    vertex on a face (2D): the penetration falls linearly from δ to zero over a zone
    whose length grows with δ, so the spring force is F = a δ² and K = 2 a δ; the damper
    traction c δ'/ℓ is uniform over the zone of length ℓ, and once the body recedes the
    zone's shallow end clips first: with τ = c δ'/K (in units of penetration),
    F = K (δ − τ)²/(2δ) for 0 < τ < δ (K (δ/2 − τ) while approaching). The wedge keeps
    pushing longer than a lumped clip (which would stop at τ = δ/2), so its e is larger
    for the same ζ.

    Both impacts are self-similar (scaling δ and t leaves the equation unchanged), so e
    depends on ζ alone, not on the stiffness, the mass or the impact velocity. In units
    where m = a = 1 and the approach speed is 1 the equation is integrated by RK4 from
    δ = 0, δ' = 1 until the force vanishes (or δ returns to 0) while δ' < 0; e = −δ'.
    Clipping makes e larger than the textbook exp(−ζπ/√(1 − ζ²)) of the unclipped
    dashpot (0.572 against 0.527 at ζ = 0.2 on a face): there the damper pulls at the
    end of the contact. e falls from 1 at ζ = 0 and tends to zero only as ζ → ∞
    (e ≈ 1/(4ζ²) on a face): a damper that never pulls cannot stop a rebound completely
    (once the body recedes, every force left pushes it out).
    """
    if zeta <= 0.0:
        return 1.0
    h = 5e-4  # e to 1e-7 (against h = 1e-5)
    x = 0.0
    v = 1.0
    for _ in range(10_000_000):
        k1x = v
        k1v = _impact_acceleration(x, v, zeta, wedge)
        k2x = v + 0.5 * h * k1v
        k2v = _impact_acceleration(x + 0.5 * h * k1x, v + 0.5 * h * k1v, zeta, wedge)
        k3x = v + 0.5 * h * k2v
        k3v = _impact_acceleration(x + 0.5 * h * k2x, v + 0.5 * h * k2v, zeta, wedge)
        k4x = v + h * k3v
        k4v = _impact_acceleration(x + h * k3x, v + h * k3v, zeta, wedge)
        xn = x + h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x)
        vn = v + h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v)
        if vn < 0.0 and (xn <= 0.0 or _impact_acceleration(xn, vn, zeta, wedge) == 0.0):
            return -vn
        x = xn
        v = vn
    return 0.0


def clipped_restitution_linear(zeta: float) -> float:
    """Closed form of :func:`clipped_restitution` on a face (a linear spring).

    With ω² = k/m and the motion δ(t) of the damped oscillator from δ = 0 at speed v,
    the force k δ + c δ' vanishes where δ'' = 0. Underdamped (ζ < 1, ω_d = ω √(1 − ζ²)):
    at ω_d t = ψ = atan2(2 ζ √(1 − ζ²), 2 ζ² − 1), e = exp(−ζ ψ / √(1 − ζ²)) |cos ψ −
    ζ sin ψ / √(1 − ζ²)|. Critical: e = e⁻². Overdamped (roots r₁,₂ = −ζ ± √(ζ² − 1)):
    at t = ln(r₂²/r₁²)/(r₁ − r₂), e = (r₁/r₂) exp(r₁ t).
    """
    if zeta <= 0.0:
        return 1.0
    if zeta < 1.0:
        wd = math.sqrt(1.0 - zeta * zeta)
        psi = math.atan2(2.0 * zeta * wd, zeta * zeta - wd * wd)
        return math.exp(-zeta * psi / wd) * abs(math.cos(psi) - zeta / wd * math.sin(psi))
    if zeta == 1.0:
        return math.exp(-2.0)
    s = math.sqrt(zeta * zeta - 1.0)
    r1 = -zeta + s
    r2 = -zeta - s
    t = math.log(r2 * r2 / (r1 * r1)) / (r1 - r2)
    return r1 / r2 * math.exp(r1 * t)


def precompile() -> None:
    """Compile the facet–facet kernels on a unit square facing itself."""
    X = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    u = np.zeros(8)
    facets = np.array([[0, 1], [1, 2], [2, 3], [3, 0]], dtype=np.int64)
    fnext = np.array([1, 2, 3, 0], dtype=np.int64)
    fprev = np.array([3, 0, 1, 2], dtype=np.int64)
    pairs = np.array([[0, 2]], dtype=np.int64)
    p1 = np.ones(1)
    fp = np.zeros((1, 8))
    zones = np.zeros((1, 2, N_WORK))
    for use in (False, True):
        facet_facet_forces(X, u, u, facets, fprev, fnext, pairs, p1, p1, p1, p1, p1, 1.0,
                           1e-3, np.zeros((1, 2)), np.zeros((1, 2)), p1, fp, fp.copy(), np.zeros(N_ENERGY),
                           np.zeros(N_WORK), zones, use)
    blk = np.zeros(4, dtype=np.int64)
    contact_damping(X, u, facets, fprev, fnext, pairs, blk, p1, p1, 1.0,
                    np.zeros(1, dtype=np.int64), np.zeros((1, 2), dtype=np.int64), p1, p1,
                    np.zeros((1, 2)), 0.5, 0.4, np.zeros((1, N_ACC)), np.zeros(1),
                    np.zeros(N_WORK), zones)
    z = np.zeros((1, 2))
    facet_facet_tangent(X, u, u.copy(), facets, fprev, fnext, pairs, p1, p1, p1, p1, 1.0, z,
                        z.copy(), 1e-6, p1, np.zeros(8), np.zeros(N_WORK),
                        np.zeros(128, dtype=np.int64), np.zeros(128, dtype=np.int64),
                        np.zeros(128))
    nodes = np.arange(4, dtype=np.int64)
    nodal_midpoint_work(u, nodes, u, u)
    keep_damper_terms(u.copy(), nodes, nodes, u, u, 1e-6, u.copy(), u.copy())
    block_moments(X, u, np.ones(8), np.array([0, 4]), np.arange(4), np.zeros((1, 2)))
    clipped_restitution(0.5, False)
    clipped_restitution(0.5, True)
