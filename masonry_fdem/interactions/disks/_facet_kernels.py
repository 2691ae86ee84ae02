"""Numba kernels of the contact between rigid disks and deformable polygonal blocks (2D).

A disk i has centre c, radius r, velocity v_d and angular velocity ω (counter-clockwise);
a block's boundary is a closed polygon of straight facets, counter-clockwise (interior on
the left, outward normal n = (t_y, −t_x)), node positions X + u. SI units throughout.

Arrays (local numbering, as in ``_kernels``):
    X: (n_nodes, 2) reference coordinates [m]; u, v: (2 n_nodes,) nodal displacement [m]
    and velocity [m/s]; facets: (n_f, 2) node pairs; fprev, fnext: (n_f,) neighbouring
    facet of the same boundary (fnext[f] starts at the node where f ends).
    xd, vd: (n_d, 2) disk centres [m] and velocities [m/s]; omega: (n_d,) [rad/s];
    rd: (n_d,) radii [m].
    pairs: (n_p, 2) candidate (disk, block) pairs; column 1 (the block id) is not read by
    the kernel: it is the caller's key of the pair's history row.
    ptr: (n_p + 1,), cand: (ptr[n_p],) candidate facets in CSR layout: pair k uses the
    global facet indices cand[ptr[k]:ptr[k + 1]], all on the boundary of block pairs[k, 1].
    params: (n_p, N_PARAM) per pair: P_EPS_A area penalty ε_a [N/m³ = Pa/m], P_WIDTH
    contact thickness w [m], P_KT tangential stiffness k_t [N/m], P_MU Coulomb
    coefficient μ, P_CN normal viscous coefficient c_n [N s/m] (0: none).
    hist: (n_p, N_HIST) per pair, in/out: H_FT tangential force F_t [N] along the contact
    tangent t = (−n_y, n_x) (n: the unit normal pushing the disk out of the block), H_SLIP
    frictional slip [m] accumulated since the contact began; both reset to 0 when the
    pair separates (overlap area 0).

Overlap split (reference paper, Figure 4: P_n,i = P_n A_i / A, direction from the centroid
of A_i). The overlap Ω = disk ∩ polygon is divided among the facets by the rays from the
disk centre ("fan" split, by *visibility*): a point p of Ω belongs to the facet through
which the segment c → p last entered the polygon. Seen from c, each ray through the disk
alternately enters and leaves the block; the stretch of the ray inside the block after an
entry belongs to the entry facet. When c itself is inside the block (overlap deeper than
the radius, a failed contact) the stretches starting at c belong to the facet nearest to
c. Properties:

* the A_i are the areas of a partition of Ω, so Σ A_i = A exactly, and every A_i ≥ 0;
* touching one facet (chord within the facet), A_1 is the circular segment, centroid on
  the facet normal through c;
* on a convex or concave vertex the boundary ray c → vertex separates the two facets'
  parts; as the disk moves, that ray and all the regions move continuously, and a facet
  enters or leaves the split only with zero area (a facet turns edge-on to c, or its
  chord shrinks to a point), so every A_i, every centroid, and the total force are
  continuous in the disk position; this also holds when c crosses a facet into the
  block, because the facet crossed keeps the stretches that start at c;
* a facet hidden behind another part of the block (c behind its line, e.g. the top of a
  block when the disk presses on its side near the corner) gets nothing: the simpler
  signed fan (Σ ± disk ∩ triangle(c, a, b), which also sums to A) would give it a
  negative part that pulls the disk and load the visible facet with area outside the
  block.

Each part is an exact sum, over the angular intervals between the directions of the
vertices and chord ends inside the disk, of four shapes: sector (c to arc), triangle (c
to a facet), quadrilateral (facet to facet) and quadrilateral + circular segment (facet
to arc); the thin shapes are built from differences along the rays, the segment from
x − sin x by series, so small overlaps keep their relative accuracy. An interval ends at
a facet's own vertex or chord end, and there that point itself is used (not a ray from
the angle, which would meet a line passing close to c at a grazing angle).

Normal force. The paper evaluates disk–disk contact with an analytical solution; for a
disk on a block it uses the overlap area, and so does this kernel: P_n = ε_a · w · A,
ε_a [Pa/m] an area penalty (traction per metre of overlap, as ε_n of the facet–facet
kernel; ε_a · w · A is the overlap volume times ε_a). On a flat facet at overlap δ,
P_n = ε_a w A_seg(δ) ≈ (4/3) ε_a w √(2r) δ^{3/2} (Hertz-like), tangent stiffness
dP_n/dδ = ε_a w · chord = 2 ε_a w √(δ(2r − δ)). :func:`area_penalty` sets ε_a from the
plane-strain modulus E* of the two materials so that this tangent stiffness per unit
thickness equals factor · E* at a reference overlap. The part of facet i,
F_i = P_n (A_i / A) (c − g_i)/|c − g_i| (g_i: centroid of A_i), acts on the disk at its
centre: its line passes through c, so the normal parts give no torque on the disk; the
reaction −F_i acts on the block where that line meets the facet (the central projection
of g_i onto the facet, inside the facet for every visible part since g_i lies in the
facet's angular sector; clamped to the facet otherwise) and goes to the facet's two nodes
by its linear shape functions. Disk and block forces are equal and opposite and have the
same line of action, so linear and angular momentum are conserved exactly.

Friction and damping (one state per (disk, block) pair, so the history survives a roll
over a vertex). n is the direction of the resultant normal force F_n = Σ F_i; the contact
point x_c = Σ (A_i/A) p_i is the area-weighted mean of the parts' application points; the
block velocity there is Σ (A_i/A) [N_1 v_1 + N_2 v_2]_i and the disk's is v_d + ω × (x_c − c).
With v_rel = v_disk − v_block, the tangential force is an incremental spring,
F_t ← F_t − k_t (v_rel·t) dt, returned to |F_t| ≤ μ |F_n| (|F_n| = P_n on a single facet);
the normal damper F_d = −c_n (v_rel·n) ≥ −|F_n| never pulls. T = F_d n + F_t t acts on the
disk at x_c (torque (x_c − c) × T) and −T on the block with the same weights and shape
functions as the normal parts, i.e. at the same point x_c.

Time step: |dF_n/dc| ≤ 2 ε_a w r (1 + O(δ/r)) (the overlap's area gradient is the chord
vector of the disk's arcs inside the block, never longer than 2 r; the turning of the
parts' directions adds O(P_n / r)), so the normal contact frequency is
ω_n² ≤ 2 ε_a w r / m; the tangential spring acting at arm ≈ r on a solid disk
(I = m r²/2) gives ω_t² ≤ 3 k_t / m. See :func:`stable_time_step`.

Caller's contract: cand[ptr[k]:ptr[k + 1]] must hold every facet of block pairs[k, 1]
that cuts the disk (a superset, e.g. from an ADT query with the disk's box, is fine;
no facet twice); hist rows must follow their (disk, block) key when the pair list is
rebuilt (new pairs start from zeros, pairs that left the list are dropped); forces are
added to f, f_disk, torque, which the caller zeroes.

Limitations:

* the paper's rule gives each part its own direction; on a straight vertex (a mesh node
  of a flat face under the disk) the parts' directions are not parallel, so the resultant
  is shorter than P_n by at most ≈ 0.14 δ/r and tilted by at most ≈ 0.0075 δ/r (measured
  for δ/r ≤ 0.03): a disk on a finely meshed flat face feels a tiny node-dependent
  tangential force;
* the normal law is not derived from a potential at vertices: W_NORMAL (ε_a w Σ A_i ×
  depth of g_i behind facet i) is the exact potential on a single facet only;
* with c inside the block (overlap deeper than r) the split stays exact and continuous
  across the facet crossed, but may jump where the facet nearest to c changes, and a
  block reaction may be clamped to its facet (then the pair's moment balance is only
  approximate); a disk entirely inside a block, with no facet cutting it, gets no force;
* the normal law is elastic (no restitution other than the damper c_n); no rolling
  resistance.
"""

import math

import numpy as np
from numba import njit

# columns of params (n_p, N_PARAM)
P_EPS_A = 0  # area penalty ε_a [N/m³]: P_n = ε_a · w · A
P_WIDTH = 1  # contact (out-of-plane) thickness w [m]
P_KT = 2  # tangential spring stiffness k_t [N/m]
P_MU = 3  # Coulomb friction coefficient μ [-]
P_CN = 4  # normal viscous damping coefficient c_n [N s/m]
N_PARAM = 5

# columns of hist (n_p, N_HIST)
H_FT = 0  # tangential force along t = (−n_y, n_x) [N]
H_SLIP = 1  # frictional slip accumulated since the contact began [m]
N_HIST = 2

# columns of out (n_p, N_OUT): results per pair (all 0 when not in contact)
O_AREA = 0  # overlap area A [m²]
O_FN = 1  # magnitude of the resultant elastic normal force |Σ F_i| [N]
O_NX = 2  # unit normal n (pushing the disk out of the block)
O_NY = 3
O_XC = 4  # contact point x_c [m]
O_YC = 5
O_FT = 6  # tangential force along t [N]
O_FD = 7  # normal damping force along n [N]
N_OUT = 8

# columns of parts (len(cand), N_PART): one row per CSR candidate entry
PT_AREA = 0  # A_i [m²]
PT_GX = 1  # centroid g_i of A_i [m]
PT_GY = 2
PT_FX = 3  # normal part F_i acting on the disk [N]
PT_FY = 4
PT_TAU = 5  # facet coordinate (0 at node 0, 1 at node 1) of the application point
N_PART = 6

# entries of work (N_WORK,)
W_NORMAL = 0  # normal elastic energy ε_a w Σ A_i · depth(g_i) [J] (exact on one facet)
W_TANGENT = 1  # tangential spring energy Σ F_t² / (2 k_t) [J]
W_FRICTION = 2  # frictional dissipation of this step [J]
W_DAMPING = 3  # viscous dissipation of this step [J]
N_WORK = 4

# columns of the per-candidate geometry scratch (relative to the disk centre)
G_AX = 0
G_AY = 1
G_TX = 2  # unit tangent (node 0 → node 1)
G_TY = 3
G_NX = 4  # outward unit normal
G_NY = 5
G_D = 6  # signed distance of the centre from the facet line, > 0 outside [m]
G_W = 7  # half chord of the disk on the facet line √(r² − d²) [m]
G_L = 8  # facet length [m]
G_P0X = 9  # part of the facet inside the disk: P0 → P1
G_P0Y = 10
G_P1X = 11
G_P1Y = 12
G_HIT = 13  # 1 when the facet cuts the open disk
G_A0 = 14  # directions of P0 and P1 seen from the centre [rad]
G_A1 = 15
N_GEO = 16

# boundary kinds of a piece (facet lines are candidate indices ≥ 0)
K_CENTRE = -1
K_ARC = -2

# a centre nearer than NUDGE · r to the boundary is moved out to 2 NUDGE · r
NUDGE = 1e-12
TWO_PI = 2.0 * math.pi


@njit(cache=True)
def _pos(X, u, node):
    return X[node, 0] + u[2 * node], X[node, 1] + u[2 * node + 1]


@njit(cache=True)
def xms(x):
    """x − sin x, accurate to round-off also for small |x| (odd series below 0.5)."""
    ax = abs(x)
    if ax >= 0.5:
        return x - math.sin(x)
    x2 = x * x
    # x³/3! − x⁵/5! + ... − x¹⁵/15! (next term < 1e-18 relative at |x| = 0.5)
    s = 1.0 / 1307674368000.0
    s = 1.0 / 6227020800.0 - x2 * s
    s = 1.0 / 39916800.0 - x2 * s
    s = 1.0 / 362880.0 - x2 * s
    s = 1.0 / 5040.0 - x2 * s
    s = 1.0 / 120.0 - x2 * s
    s = 1.0 / 6.0 - x2 * s
    return x * x2 * s


@njit(cache=True)
def segment_from_angle(r, theta):
    """Circular segment of a disk of radius r [m] cut by a chord subtending theta [rad].

    theta ∈ [0, 2π] is the full central angle of the arc. Returns (area [m²], distance of
    the segment's centroid from the centre [m], along the arc's bisector):
    A = r² (θ − sin θ)/2, ḡ = 4 r sin³(θ/2) / (3 (θ − sin θ)).
    """
    if theta <= 0.0:
        return 0.0, r
    f = xms(theta)
    if f <= 0.0:
        return 0.0, r
    s = math.sin(0.5 * theta)
    return 0.5 * r * r * f, 4.0 * r * s * s * s / (3.0 * f)


@njit(cache=True)
def circular_segment(r, h):
    """Part of a disk of radius r [m] beyond a chord at signed distance h [m] from the centre.

    h ∈ [−r, r] (h ≥ r: empty; h ≤ −r: the whole disk; h = 0: half disk). Returns
    (area [m²], distance of the centroid from the centre [m], on the side of the chord).
    The half angle β = 2 asin(√((r − h)/(2r))) is well conditioned at tangency (h → r).
    """
    if h >= r:
        return 0.0, r
    if h <= -r:
        return math.pi * r * r, 0.0
    beta = 2.0 * math.asin(math.sqrt(0.5 * (r - h) / r))
    return segment_from_angle(r, 2.0 * beta)


@njit(cache=True)
def _sector(r, th1, dth):
    """Sector of radius r [m] from angle th1 over dth > 0 [rad]: (area, first moment x, y)
    about the centre [m², m³]."""
    a = 0.5 * r * r * dth
    g = 4.0 * r * math.sin(0.5 * dth) / (3.0 * dth)
    tm = th1 + 0.5 * dth
    return a, a * g * math.cos(tm), a * g * math.sin(tm)


@njit(cache=True)
def disk_triangle(r, ax, ay, bx, by):
    """Disk of radius r centred at the origin ∩ triangle (origin, a, b) [m].

    Returns (area [m²], first moment about the origin x, y [m³]), signed: positive when
    (0, a, b) is counter-clockwise. Summed over the facets a → b of any closed polygon,
    with a, b relative to the disk centre, these give the area and first moment of
    disk ∩ polygon (the signed fan; used here as an independent check). The triangle is
    split where the segment a → b enters and leaves the disk: sector, triangle, sector.
    """
    cr = ax * by - ay * bx
    if cr == 0.0:
        return 0.0, 0.0, 0.0
    dx = bx - ax
    dy = by - ay
    l2 = dx * dx + dy * dy
    t0 = 1.0
    t1 = 0.0
    h2 = cr * cr / l2  # squared distance of the centre from the line a-b
    if h2 < r * r:
        tf = -(ax * dx + ay * dy) / l2
        hw = math.sqrt((r * r - h2) / l2)
        t0 = max(0.0, tf - hw)
        t1 = min(1.0, tf + hw)
    area = 0.0
    mx = 0.0
    my = 0.0
    if t1 <= t0:  # the segment misses the disk: one sector from a to b
        phi = math.atan2(cr, ax * bx + ay * by)
        th = math.atan2(ay, ax)
        if phi > 0.0:
            return _sector(r, th, phi)
        a, x, y = _sector(r, th + phi, -phi)
        return -a, -x, -y
    p0x = ax + t0 * dx
    p0y = ay + t0 * dy
    p1x = ax + t1 * dx
    p1y = ay + t1 * dy
    sgn = 1.0 if cr > 0.0 else -1.0
    if t0 > 0.0:  # sector from a to P0
        phi = abs(math.atan2(ax * p0y - ay * p0x, ax * p0x + ay * p0y))
        th = math.atan2(ay, ax) if sgn > 0.0 else math.atan2(p0y, p0x)
        a, x, y = _sector(r, th, phi)
        area += sgn * a
        mx += sgn * x
        my += sgn * y
    a = 0.5 * (p0x * p1y - p0y * p1x)
    area += a
    mx += a * (p0x + p1x) / 3.0
    my += a * (p0y + p1y) / 3.0
    if t1 < 1.0:  # sector from P1 to b
        phi = abs(math.atan2(p1x * by - p1y * bx, p1x * bx + p1y * by))
        th = math.atan2(p1y, p1x) if sgn > 0.0 else math.atan2(by, bx)
        a, x, y = _sector(r, th, phi)
        area += sgn * a
        mx += sgn * x
        my += sgn * y
    return area, mx, my


@njit(cache=True)
def _line_point(geo, j, th):
    """Where the ray at angle th from the centre meets facet j's line: (s, ξ, x, y, ex, ey),
    s the distance along the ray, ξ the coordinate along the tangent from the foot of the
    perpendicular from the centre (the point is −d n + ξ t), (ex, ey) the ray's direction.

    When th is the direction of one of the facet's own critical points (a vertex or a chord
    end), that point itself is returned: a ray from cos/sin(th) would meet a line passing
    close to the centre at a grazing angle, with a large relative error.
    """
    tx = geo[j, G_TX]
    ty = geo[j, G_TY]
    if th == geo[j, G_A0] or th == geo[j, G_A1]:
        if th == geo[j, G_A0]:
            qx = geo[j, G_P0X]
            qy = geo[j, G_P0Y]
        else:
            qx = geo[j, G_P1X]
            qy = geo[j, G_P1Y]
        s = math.hypot(qx, qy)
        return s, qx * tx + qy * ty, qx, qy, qx / s, qy / s
    nx = geo[j, G_NX]
    ny = geo[j, G_NY]
    d = geo[j, G_D]
    ex = math.cos(th)
    ey = math.sin(th)
    s = -d / (ex * nx + ey * ny)
    xi = s * (ex * tx + ey * ty)
    return s, xi, -d * nx + xi * tx, -d * ny + xi * ty, ex, ey


@njit(cache=True)
def _quad(q1x, q1y, ux, uy, p1x, p1y, p2x, p2y):
    """Quadrilateral Q1, Q2 = Q1 + u, Q2 + p2, Q1 + p1 (the inner edge Q1 → Q2 counter-
    clockwise about the origin, p1, p2 outward along the rays): (area, moment x, y)."""
    q2x = q1x + ux
    q2y = q1y + uy
    t1 = 0.5 * (ux * p2y - uy * p2x)
    t2 = 0.5 * ((ux + p2x) * p1y - (uy + p2y) * p1x)
    # both triangles of the fan from Q1 are clockwise: the area is −(t1 + t2)
    mx = t1 * (q1x + 2.0 * q2x + p2x) / 3.0 + t2 * (2.0 * q1x + q2x + p2x + p1x) / 3.0
    my = t1 * (q1y + 2.0 * q2y + p2y) / 3.0 + t2 * (2.0 * q1y + q2y + p2y + p1y) / 3.0
    return -(t1 + t2), -mx, -my


@njit(cache=True)
def _piece(r, geo, lower, upper, th1, th2, raw2):
    """Area and first moment (about the centre) of the region between boundaries lower
    (K_CENTRE or a facet line) and upper (a facet line or K_ARC) over the angles
    [th1, th2] seen from the centre; raw2 is th2 as stored (th2 − 2π for the interval
    that wraps around)."""
    dth = th2 - th1
    if lower == K_CENTRE and upper == K_ARC:
        return _sector(r, th1, dth)
    if lower == K_CENTRE:  # triangle (c, Q1, Q2)
        _, _, q1x, q1y, _, _ = _line_point(geo, upper, th1)
        _, _, q2x, q2y, _, _ = _line_point(geo, upper, raw2)
        a = 0.5 * (q1x * q2y - q1y * q2x)
        return a, a * (q1x + q2x) / 3.0, a * (q1y + q2y) / 3.0
    s1, xi1, q1x, q1y, e1x, e1y = _line_point(geo, lower, th1)
    s2, xi2, q2x, q2y, e2x, e2y = _line_point(geo, lower, raw2)
    ux = (xi2 - xi1) * geo[lower, G_TX]
    uy = (xi2 - xi1) * geo[lower, G_TY]
    if upper == K_ARC:
        # quadrilateral facet → chord R1 R2, then the circular segment beyond the chord;
        # r − s = (w² − ξ²)/(r + s) keeps the thin side accurate
        w = geo[lower, G_W]
        g1 = max(0.0, (w - xi1) * (w + xi1)) / (r + s1)
        g2 = max(0.0, (w - xi2) * (w + xi2)) / (r + s2)
        a, mx, my = _quad(q1x, q1y, ux, uy, g1 * e1x, g1 * e1y, g2 * e2x, g2 * e2y)
        sa, sg = segment_from_angle(r, dth)
        tm = th1 + 0.5 * dth
        return a + sa, mx + sa * sg * math.cos(tm), my + sa * sg * math.sin(tm)
    _, _, v1x, v1y, _, _ = _line_point(geo, upper, th1)
    _, _, v2x, v2y, _, _ = _line_point(geo, upper, raw2)
    return _quad(q1x, q1y, ux, uy, v1x - q1x, v1y - q1y, v2x - q2x, v2y - q2y)


@njit(cache=True)
def _add(pieces, j, a, mx, my):
    pieces[j, 0] += a
    pieces[j, 1] += mx
    pieces[j, 2] += my


@njit(cache=True)
def _local_side(X, u, facets, fprev, fnext, f, t, cx, cy):
    """Is (cx, cy) inside the block, given that the nearest boundary point is at parameter
    t ∈ [0, 1] of facet f? Returns (inside, outward unit direction at that point)."""
    if 0.0 < t < 1.0:
        ax, ay = _pos(X, u, facets[f, 0])
        bx, by = _pos(X, u, facets[f, 1])
        ln = math.hypot(bx - ax, by - ay)
        nx = (by - ay) / ln
        ny = -(bx - ax) / ln
        return (cx - ax) * nx + (cy - ay) * ny < 0.0, nx, ny
    if t <= 0.0:
        fi = fprev[f]
        fo = f
    else:
        fi = f
        fo = fnext[f]
    ax, ay = _pos(X, u, facets[fi, 0])
    vx, vy = _pos(X, u, facets[fi, 1])
    bx, by = _pos(X, u, facets[fo, 1])
    li = math.hypot(vx - ax, vy - ay)
    lo = math.hypot(bx - vx, by - vy)
    nix = (vy - ay) / li
    niy = -(vx - ax) / li
    nox = (by - vy) / lo
    noy = -(bx - vx) / lo
    di = (cx - vx) * nix + (cy - vy) * niy
    do = (cx - vx) * nox + (cy - vy) * noy
    turn = (vx - ax) * (by - vy) - (vy - ay) * (bx - vx)
    if turn >= 0.0:  # convex (or straight) vertex: the interior is the intersection
        inside = di < 0.0 and do < 0.0
    else:  # reflex vertex: the union of the two half-planes
        inside = di < 0.0 or do < 0.0
    mx = nix + nox
    my = niy + noy
    mn = math.hypot(mx, my)
    if mn < 1e-12:
        return inside, nox, noy
    return inside, mx / mn, my / mn


@njit(cache=True)
def overlap_split(cx, cy, r, X, u, facets, fprev, fnext, cand, lo, hi, geo, ang, crs_s,
                  crs_j, pieces):
    """Split of disk ∩ block among the candidate facets cand[lo:hi] (see module doc).

    The candidates must include every facet of the block that cuts the disk (more are
    harmless, none twice). Scratch: geo (≥ n, N_GEO), ang (≥ 2n), crs_s (≥ n) float,
    crs_j (≥ n) int, with n = hi − lo.

    Returns (A [m²], cx, cy, inside, j*): the total overlap area, the centre actually used
    (moved by at most 2e-12 r when it lies on the boundary), whether it is inside the
    block, and the candidate (local index) nearest to it. pieces[j] = (A_j, first moment
    of A_j about that centre x, y) for the local candidate j = 0 .. n − 1.
    """
    n = hi - lo
    for j in range(n):
        pieces[j, 0] = 0.0
        pieces[j, 1] = 0.0
        pieces[j, 2] = 0.0
    # --- nearest facet, inside/outside, and the nudge off the boundary
    best = math.inf
    jst = -1
    tst = 0.0
    qbx = 0.0
    qby = 0.0
    for j in range(n):
        f = cand[lo + j]
        ax, ay = _pos(X, u, facets[f, 0])
        bx, by = _pos(X, u, facets[f, 1])
        dx = bx - ax
        dy = by - ay
        l2 = dx * dx + dy * dy
        if l2 <= 0.0:
            continue
        t = ((cx - ax) * dx + (cy - ay) * dy) / l2
        tc = min(1.0, max(0.0, t))
        qx = ax + tc * dx
        qy = ay + tc * dy
        dist = math.hypot(qx - cx, qy - cy)
        if dist < best:
            best = dist
            jst = j
            tst = t
            qbx = qx
            qby = qy
    if jst < 0:
        return 0.0, cx, cy, False, -1
    inside, mx, my = _local_side(X, u, facets, fprev, fnext, cand[lo + jst], tst, cx, cy)
    if best < NUDGE * r:
        cx = qbx + 2.0 * NUDGE * r * mx
        cy = qby + 2.0 * NUDGE * r * my
        inside = False
    # --- facet geometry relative to the centre; critical directions
    m = 0
    for j in range(n):
        f = cand[lo + j]
        ax, ay = _pos(X, u, facets[f, 0])
        bx, by = _pos(X, u, facets[f, 1])
        ax -= cx
        ay -= cy
        bx -= cx
        by -= cy
        geo[j, G_HIT] = 0.0
        ln = math.hypot(bx - ax, by - ay)
        geo[j, G_L] = ln
        if ln <= 0.0:
            continue
        tx = (bx - ax) / ln
        ty = (by - ay) / ln
        # the line through the end nearer to the centre: with the centre close to a vertex,
        # both facets' lines then pass through it to round-off relative to its distance
        if ax * ax + ay * ay <= bx * bx + by * by:
            d = -(ax * ty - ay * tx)
        else:
            d = -(bx * ty - by * tx)
        geo[j, G_AX] = ax
        geo[j, G_AY] = ay
        geo[j, G_TX] = tx
        geo[j, G_TY] = ty
        geo[j, G_NX] = ty
        geo[j, G_NY] = -tx
        geo[j, G_D] = d
        h = abs(d)
        if h >= r:
            continue
        w = math.sqrt((r - h) * (r + h))
        geo[j, G_W] = w
        tf = -(ax * tx + ay * ty)  # foot of the perpendicular, along the facet from a
        s0 = max(0.0, tf - w)
        s1 = min(ln, tf + w)
        if s1 <= s0:
            continue
        geo[j, G_HIT] = 1.0
        if s0 == 0.0:
            geo[j, G_P0X] = ax
            geo[j, G_P0Y] = ay
        else:
            geo[j, G_P0X] = ax + s0 * tx
            geo[j, G_P0Y] = ay + s0 * ty
        if s1 == ln:
            geo[j, G_P1X] = bx
            geo[j, G_P1Y] = by
        else:
            geo[j, G_P1X] = ax + s1 * tx
            geo[j, G_P1Y] = ay + s1 * ty
        geo[j, G_A0] = math.atan2(geo[j, G_P0Y], geo[j, G_P0X])
        geo[j, G_A1] = math.atan2(geo[j, G_P1Y], geo[j, G_P1X])
        ang[m] = geo[j, G_A0]
        ang[m + 1] = geo[j, G_A1]
        m += 2
    if m == 0:
        if inside:  # the whole disk inside the block
            pieces[jst, 0] = math.pi * r * r
            return math.pi * r * r, cx, cy, True, jst
        return 0.0, cx, cy, False, jst
    for i in range(1, m):  # insertion sort of the critical directions
        a = ang[i]
        k = i - 1
        while k >= 0 and ang[k] > a:
            ang[k + 1] = ang[k]
            k -= 1
        ang[k + 1] = a
    # --- sweep the angular intervals
    for k in range(m):
        th1 = ang[k]
        raw2 = ang[k + 1] if k + 1 < m else ang[0]
        th2 = raw2 if k + 1 < m else raw2 + TWO_PI
        if th2 <= th1:
            continue
        thm = 0.5 * (th1 + th2)
        ex = math.cos(thm)
        ey = math.sin(thm)
        nc = 0
        for j in range(n):  # facets crossed by the mid ray, sorted by distance
            if geo[j, G_HIT] == 0.0:
                continue
            p0x = geo[j, G_P0X]
            p0y = geo[j, G_P0Y]
            ddx = geo[j, G_P1X] - p0x
            ddy = geo[j, G_P1Y] - p0y
            den = ex * ddy - ey * ddx
            if den == 0.0:
                continue
            s = (p0x * ddy - p0y * ddx) / den
            t = (p0x * ey - p0y * ex) / den
            if s <= 0.0 or t < 0.0 or t > 1.0:
                continue
            i = nc
            while i > 0 and crs_s[i - 1] > s:
                crs_s[i] = crs_s[i - 1]
                crs_j[i] = crs_j[i - 1]
                i -= 1
            crs_s[i] = s
            crs_j[i] = j
            nc += 1
        if nc == 0:
            if inside:
                a, x, y = _piece(r, geo, K_CENTRE, K_ARC, th1, th2, raw2)
                _add(pieces, jst, a, x, y)
            continue
        q = crs_j[0]
        ins = ex * geo[q, G_NX] + ey * geo[q, G_NY] >= 0.0  # first crossing leaves the block
        lower = K_CENTRE
        owner = jst
        for i in range(nc):
            q = crs_j[i]
            entering = ex * geo[q, G_NX] + ey * geo[q, G_NY] < 0.0
            if entering:
                if ins:  # inconsistent boundary (overlapping facets): close and restart
                    a, x, y = _piece(r, geo, lower, q, th1, th2, raw2)
                    _add(pieces, owner, a, x, y)
                ins = True
                lower = q
                owner = q
            elif ins:
                a, x, y = _piece(r, geo, lower, q, th1, th2, raw2)
                _add(pieces, owner, a, x, y)
                ins = False
        if ins:
            a, x, y = _piece(r, geo, lower, K_ARC, th1, th2, raw2)
            _add(pieces, owner, a, x, y)
    total = 0.0
    for j in range(n):
        total += pieces[j, 0]
    return total, cx, cy, inside, jst


@njit(cache=True)
def disk_overlap_pieces(cx, cy, r, X, u, facets, fprev, fnext, cand):
    """Convenience form of :func:`overlap_split` for all of ``cand`` (allocates).

    Returns (A [m²], pieces (n, 3)): per candidate its area A_j [m²] and the centroid of
    A_j [m] (the disk centre where A_j = 0).
    """
    n = cand.shape[0]
    geo = np.zeros((n, N_GEO))
    ang = np.empty(2 * n + 1)
    crs_s = np.empty(n + 1)
    crs_j = np.empty(n + 1, np.int64)
    pieces = np.zeros((n, 3))
    A, ccx, ccy, _, _ = overlap_split(cx, cy, r, X, u, facets, fprev, fnext, cand, 0, n, geo,
                                      ang, crs_s, crs_j, pieces)
    out = np.empty((n, 3))
    for j in range(n):
        a = pieces[j, 0]
        out[j, 0] = a
        if a != 0.0:
            out[j, 1] = ccx + pieces[j, 1] / a
            out[j, 2] = ccy + pieces[j, 2] / a
        else:
            out[j, 1] = ccx
            out[j, 2] = ccy
    return A, out


@njit(cache=True)
def disk_block_forces(X, u, v, facets, fprev, fnext, xd, vd, omega, rd, pairs, ptr, cand,
                      params, hist, dt, f, f_disk, torque, work, out, parts):
    """Normal (area-split), viscous and Coulomb friction forces of disk–block pairs.

    Args (layouts in the module doc):
        X, u, v, facets, fprev, fnext: block mesh, displacement, velocity, facets.
        xd, vd, omega, rd: disk centres, velocities, angular velocities, radii.
        pairs (n_p, 2): (disk, block); ptr (n_p + 1,), cand: CSR candidate facets.
        params (n_p, N_PARAM): ε_a [Pa/m], w [m], k_t [N/m], μ, c_n [N s/m] per pair.
        hist (n_p, N_HIST): in/out tangential force [N] and slip [m] per pair.
        dt: time step [s] (slip increment = relative tangential velocity · dt).
        f (2 n_nodes,), f_disk (n_d, 2) [N], torque (n_d,) [N m]: forces are ADDED.
        work (N_WORK,) out [J]: normal and tangential elastic energy, frictional and
            viscous dissipation of this step (set, not added).
        out (n_p, N_OUT) out: per pair area, normal force, normal, contact point, F_t, F_d.
        parts (len(cand), N_PART) out: per candidate entry A_i, g_i, F_i, facet coordinate.
    """
    n_p = pairs.shape[0]
    maxc = 1
    for k in range(n_p):
        maxc = max(maxc, ptr[k + 1] - ptr[k])
    geo = np.zeros((maxc, N_GEO))
    ang = np.empty(2 * maxc + 1)
    crs_s = np.empty(maxc + 1)
    crs_j = np.empty(maxc + 1, np.int64)
    pieces = np.zeros((maxc, 3))
    e_n = 0.0
    e_t = 0.0
    d_f = 0.0
    d_d = 0.0
    for k in range(n_p):
        i = pairs[k, 0]
        lo = ptr[k]
        hi = ptr[k + 1]
        r = rd[i]
        for q in range(lo, hi):
            for c in range(N_PART):
                parts[q, c] = 0.0
        for c in range(N_OUT):
            out[k, c] = 0.0
        A, cx, cy, _, _ = overlap_split(xd[i, 0], xd[i, 1], r, X, u, facets, fprev, fnext,
                                        cand, lo, hi, geo, ang, crs_s, crs_j, pieces)
        if A <= 0.0:  # separated: the contact's history ends
            for c in range(N_HIST):
                hist[k, c] = 0.0
            continue
        eps = params[k, P_EPS_A]
        wid = params[k, P_WIDTH]
        pn = eps * wid * A
        # --- normal parts: on the disk through its centre, on the block where that line
        # meets the facet; the weighted application points define the contact point
        fnx = 0.0
        fny = 0.0
        xcx = 0.0  # contact point relative to the centre
        xcy = 0.0
        vbx = 0.0  # block velocity at the contact point
        vby = 0.0
        amax = 0.0
        jmax = 0
        for j in range(hi - lo):
            aj = pieces[j, 0]
            if aj == 0.0:
                continue
            q = lo + j
            fac = cand[q]
            if aj > amax:
                amax = aj
                jmax = j
            gx = pieces[j, 1] / aj
            gy = pieces[j, 2] / aj
            nx = geo[j, G_NX]
            ny = geo[j, G_NY]
            tx = geo[j, G_TX]
            ty = geo[j, G_TY]
            ax = geo[j, G_AX]
            ay = geo[j, G_AY]
            ln = geo[j, G_L]
            d = geo[j, G_D]
            dist = math.hypot(gx, gy)
            if dist > NUDGE * r:
                dirx = -gx / dist
                diry = -gy / dist
            else:  # centroid at the centre (disk swallowed): push out along the normal
                dirx = nx
                diry = ny
            pj = pn * aj / A
            fx = pj * dirx
            fy = pj * diry
            gn = gx * nx + gy * ny
            if abs(gn) > 1e-12 * dist:  # central projection of g onto the facet line
                lam = -d / gn
                tau = ((lam * gx - ax) * tx + (lam * gy - ay) * ty) / ln
            else:
                tau = ((gx - ax) * tx + (gy - ay) * ty) / ln
            tau = min(1.0, max(0.0, tau))
            n0 = facets[fac, 0]
            n1 = facets[fac, 1]
            f[2 * n0] -= (1.0 - tau) * fx
            f[2 * n0 + 1] -= (1.0 - tau) * fy
            f[2 * n1] -= tau * fx
            f[2 * n1 + 1] -= tau * fy
            fnx += fx
            fny += fy
            wj = aj / A
            xcx += wj * (ax + tau * ln * tx)
            xcy += wj * (ay + tau * ln * ty)
            vbx += wj * ((1.0 - tau) * v[2 * n0] + tau * v[2 * n1])
            vby += wj * ((1.0 - tau) * v[2 * n0 + 1] + tau * v[2 * n1 + 1])
            e_n += eps * wid * aj * max(0.0, -(gn + d))
            parts[q, PT_AREA] = aj
            parts[q, PT_GX] = cx + gx
            parts[q, PT_GY] = cy + gy
            parts[q, PT_FX] = fx
            parts[q, PT_FY] = fy
            parts[q, PT_TAU] = tau
        fn = math.hypot(fnx, fny)
        if fn > 0.0:
            nx = fnx / fn
            ny = fny / fn
        else:
            nx = geo[jmax, G_NX]
            ny = geo[jmax, G_NY]
        tx = -ny
        ty = nx
        # --- relative velocity of the disk's material point at x_c against the block's
        vrx = vd[i, 0] - omega[i] * xcy - vbx
        vry = vd[i, 1] + omega[i] * xcx - vby
        vn = vrx * nx + vry * ny
        vt = vrx * tx + vry * ty
        # --- normal damper (never pulls the disk back)
        fd = -params[k, P_CN] * vn
        if fd < -fn:
            fd = -fn
        d_d += -fd * vn * dt
        # --- friction: elastic predictor, Coulomb return
        kt = params[k, P_KT]
        ft = 0.0
        if kt > 0.0:
            trial = hist[k, H_FT] - kt * vt * dt
            cap = params[k, P_MU] * fn
            if abs(trial) > cap:
                ft = cap if trial > 0.0 else -cap
                slip = (abs(trial) - cap) / kt
                d_f += cap * slip
                hist[k, H_SLIP] += slip
            else:
                ft = trial
            e_t += 0.5 * ft * ft / kt
        hist[k, H_FT] = ft
        tfx = fd * nx + ft * tx
        tfy = fd * ny + ft * ty
        f_disk[i, 0] += fnx + tfx
        f_disk[i, 1] += fny + tfy
        torque[i] += xcx * tfy - xcy * tfx
        # --- reaction of the tangential and damping force, with the parts' weights
        for j in range(hi - lo):
            aj = pieces[j, 0]
            if aj == 0.0:
                continue
            q = lo + j
            wj = aj / A
            tau = parts[q, PT_TAU]
            n0 = facets[cand[q], 0]
            n1 = facets[cand[q], 1]
            f[2 * n0] -= wj * (1.0 - tau) * tfx
            f[2 * n0 + 1] -= wj * (1.0 - tau) * tfy
            f[2 * n1] -= wj * tau * tfx
            f[2 * n1 + 1] -= wj * tau * tfy
        out[k, O_AREA] = A
        out[k, O_FN] = fn
        out[k, O_NX] = nx
        out[k, O_NY] = ny
        out[k, O_XC] = cx + xcx
        out[k, O_YC] = cy + xcy
        out[k, O_FT] = ft
        out[k, O_FD] = fd
    work[W_NORMAL] = e_n
    work[W_TANGENT] = e_t
    work[W_FRICTION] = d_f
    work[W_DAMPING] = d_d


@njit(cache=True)
def plane_strain_modulus(e1, nu1, e2, nu2):
    """Effective plane-strain modulus E* = 1 / ((1 − ν1²)/E1 + (1 − ν2²)/E2) [Pa];
    E = inf for a rigid body (the disks)."""
    c = 0.0
    if not math.isinf(e1):
        c += (1.0 - nu1 * nu1) / e1
    if not math.isinf(e2):
        c += (1.0 - nu2 * nu2) / e2
    if c == 0.0:
        return math.inf
    return 1.0 / c


@njit(cache=True)
def area_penalty(e_star, r, rel_overlap, factor):
    """Area penalty ε_a [Pa/m] for a disk of radius r [m] on a block of modulus E* [Pa].

    On a flat facet the area law has the tangent stiffness per unit thickness
    dP_n/(w dδ) = ε_a · 2 √(δ (2r − δ)). The elastic line contact of a cylinder on a
    half-plane has no size-independent stiffness (in 2D the approach depends on the
    logarithm of the body size over the contact width, Johnson, Contact Mechanics, 1985),
    but its stiffness per unit thickness is of the order of E*; ε_a is set so that the
    tangent stiffness equals factor · E* at the reference overlap δ_ref = rel_overlap · r
    (e.g. 1e-3 and 1). The block's own elasticity is in the finite elements, so factor is
    a penalty factor: larger makes the overlap smaller, the contact stiffer and the time
    step smaller (see :func:`stable_time_step`).
    """
    dref = rel_overlap * r
    return factor * e_star / (2.0 * math.sqrt(dref * (2.0 * r - dref)))


@njit(cache=True)
def stiffness_bound(eps_a, width, r):
    """Upper bound 2 ε_a w r [N/m] of |dF_n/dc| for any disk position (flat facet at
    overlap δ: 2 ε_a w √(δ (2r − δ)))."""
    return 2.0 * eps_a * width * r


@njit(cache=True)
def stable_time_step(mass, r, eps_a, width, kt):
    """Central-difference stability limit [s] of a solid disk of mass m [kg] on a fixed
    block: 2 / ω with ω² = max(2 ε_a w r, 3 k_t) / m. The caller applies a safety factor
    and uses for m the smaller of the disk mass and the lumped mass of the contacted
    facet nodes when the block is lighter; viscous damping lowers the limit further by
    √(1 + ζ²) − ζ."""
    k = max(stiffness_bound(eps_a, width, r), 3.0 * kt)
    if k <= 0.0:
        return math.inf
    return 2.0 * math.sqrt(mass / k)


def precompile() -> None:
    """Compile the disk–facet kernel on a disk resting on a unit square."""
    X = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    k = np.arange(4, dtype=np.int64)
    facets, fnext, fprev = np.c_[k, (k + 1) % 4], (k + 1) % 4, (k + 3) % 4
    u = np.zeros(8)
    prm = np.zeros((1, N_PARAM))
    prm[0, [P_EPS_A, P_WIDTH, P_KT, P_MU, P_CN]] = [1e6, 1.0, 1e3, 0.5, 1.0]
    disk_block_forces(X, u, u, facets, fprev, fnext, np.array([[0.5, 1.05]]),
                      np.zeros((1, 2)), np.zeros(1), np.full(1, 0.1),
                      np.array([[0, 0]], dtype=np.int64), np.array([0, 4], dtype=np.int64),
                      np.arange(4, dtype=np.int64), prm, np.zeros((1, N_HIST)), 1e-3,
                      np.zeros(8), np.zeros((1, 2)), np.zeros(1), np.zeros(N_WORK),
                      np.zeros((1, N_OUT)), np.zeros((4, N_PART)))
