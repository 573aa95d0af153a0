"""Kinetostatics of the impact four-bar and of GUIM-1's additional rocker (seed 001;
linkages.md §5).

Per crank angle: the joint reactions by the Assur-dyad route of §5.3 (tangential parts from
moments about C, normal parts from the dyad force balance, then the crank), and the balancing
moment M_b. M_b is taken from virtual work (§5.5), which needs no reactions: the reaction
route gives it as infinity times zero at a special position (H11), the virtual-work route stays
finite and exact. Over a cycle: windowed peaks, the RMS of M_b and the cycle work by
Gauss-Legendre quadrature (one-sided at the node, H13).

GUIM-1 variant: the base (the main rocker) turns with angular velocity Omega_b and
acceleration E_b about a pivot O, with A at r_OA in the base frame; absolute accelerations add
the transport and Coriolis terms a = a_rel + 2 Omega_b k x v_rel + E_b k x r - Omega_b^2 r
(all in base-frame components; gravity enters through the instantaneous tilt).
"""

import math

import numpy as np
from numba import njit

from kernels import KERNEL_OPTIONS
from kernels import status as st
from kernels.crank_rocker import impact_branch
from kernels.elementary import golden_points, golden_shrink
from kernels.fourbar import (
    CHANGE_POINT_A,
    CHANGE_POINT_B,
    CHANGE_POINT_C,
    change_point_identities,
    crank_turns_fully,
    vector_kinematics,
)

PARAMETERS = (
    "l0", "l1", "l2", "l3", "m1", "m2", "m3", "s1", "s2", "s3", "q1", "q2", "q3",
    "J1", "J2", "J3", "omega1", "epsilon1", "tilt", "g", "sigma",
    "external_force", "external_force_normal", "external_force_arm", "external_moment",
    "base_motion", "base_omega", "base_epsilon", "crank_pivot_x", "crank_pivot_y",
)
OUTPUTS = (
    "force_peak_A", "force_peak_B", "force_peak_C", "force_peak_D",
    "balancing_moment_peak", "balancing_moment_rms", "cycle_work", "assembly_branch",
)
PROFILES = (
    "F21_n", "F21_t", "F34_n", "F34_t", "F32_n", "F32_t", "F14_n", "F14_t", "balancing_moment",
)
METHOD = ("geometry_tol", "special_window", "quadrature_points", "peak_samples",
          "profile_points")

SIGMA_IMPACT = 0.0
BASE_FIXED, BASE_ROTATING = 0, 1

_I = {name: i for i, name in enumerate(PARAMETERS)}

#: layout of the per-angle result vector of ``joint_forces``
R_F14X, R_F14Y, R_F21X, R_F21Y, R_F32X, R_F32Y, R_F34X, R_F34Y = range(8)
R_MB, R_MB_REACTION = 8, 9
R_F21N, R_F21T, R_F34N, R_F34T, R_F32N, R_F32T, R_F14N, R_F14T = range(10, 18)
N_RESULT = 18


@njit(**KERNEL_OPTIONS)
def _cross(ax, ay, bx, by):
    return ax * by - ay * bx


@njit(**KERNEL_OPTIONS)
def joint_forces(phi1, pr, sigma, res, snap=0.0):
    """Joint reactions and balancing moment at crank angle phi1 (see _joint_forces)."""
    tilt, g = pr[18], pr[19]
    return _joint_forces(phi1, pr, sigma, res, snap, -g * math.sin(tilt), -g * math.cos(tilt))


@njit(**KERNEL_OPTIONS)
def _joint_forces(phi1, pr, sigma, res, snap, gx, gy):
    """Joint reactions and balancing moment at crank angle phi1 (linkages.md §5.3).

    pr holds one point's parameters in the order of PARAMETERS; res (length N_RESULT) gets the
    vectors F14, F21, F32, F34 (force on link i by link j, mechanism frame), M_b from virtual
    work and from the reactions, and the normal/tangential components relative to the coupler
    (F21), rocker (F34, F32) and crank (F14). Returns False where the loop cannot close.
    snap: see kernels.fourbar.dyad_factors (the point kernel passes geometry_tol).
    (gx, gy): gravity in the base frame, -g (sin tilt, cos tilt), computed once per point.
    """
    l0, l1, l2, l3 = pr[0], pr[1], pr[2], pr[3]
    m1, m2, m3 = pr[4], pr[5], pr[6]
    p1, p2, p3 = pr[7] * l1, pr[8] * l2, pr[9] * l3  # centroid along each link [m]
    q1, q2, q3 = pr[10], pr[11], pr[12]
    j1, j2, j3 = pr[13], pr[14], pr[15]
    w1, e1 = pr[16], pr[17]
    f_t, f_n, arm, m_ext = pr[21], pr[22], pr[23], pr[24]
    rotating = pr[25] == BASE_ROTATING
    wb = pr[26] if rotating else 0.0
    eb = pr[27] if rotating else 0.0
    oax = pr[28] if rotating else 0.0
    oay = pr[29] if rotating else 0.0

    c1, s1, c2, s2, c3, s3, u21, u31, du21, du31 = vector_kinematics(phi1, l0, l1, l2, l3,
                                                                       sigma, snap)
    if math.isnan(c3) or math.isnan(u31):
        return False
    w2, w3 = u21 * w1, u31 * w1
    e2 = du21 * w1 * w1 + u21 * e1
    e3 = du31 * w1 * w1 + u31 * e1
    # positions (origin A): centroid offsets rho_i = p_i e_i + q_i n_i
    r1x, r1y = p1 * c1 - q1 * s1, p1 * s1 + q1 * c1
    r2x, r2y = p2 * c2 - q2 * s2, p2 * s2 + q2 * c2
    r3x, r3y = p3 * c3 - q3 * s3, p3 * s3 + q3 * c3
    bx, by = l1 * c1, l1 * s1
    cx, cy = l0 + l3 * c3, l3 * s3
    sx1, sy1 = r1x, r1y
    sx2, sy2 = bx + r2x, by + r2y
    sx3, sy3 = l0 + r3x, r3y
    # relative velocities and accelerations (base frame)
    vx1, vy1 = -w1 * r1y, w1 * r1x
    vbx, vby = -w1 * by, w1 * bx
    vx2, vy2 = vbx - w2 * r2y, vby + w2 * r2x
    vx3, vy3 = -w3 * r3y, w3 * r3x
    ax1, ay1 = -e1 * r1y - w1 * w1 * r1x, e1 * r1x - w1 * w1 * r1y
    abx, aby = -e1 * by - w1 * w1 * bx, e1 * bx - w1 * w1 * by
    ax2, ay2 = abx - e2 * r2y - w2 * w2 * r2x, aby + e2 * r2x - w2 * w2 * r2y
    ax3, ay3 = -e3 * r3y - w3 * w3 * r3x, e3 * r3x - w3 * w3 * r3y
    if rotating:  # transport + Coriolis, r measured from the base pivot O
        wb2 = wb * wb
        ox, oy = oax + sx1, oay + sy1
        ax1 += -2.0 * wb * vy1 - eb * oy - wb2 * ox
        ay1 += 2.0 * wb * vx1 + eb * ox - wb2 * oy
        ox, oy = oax + sx2, oay + sy2
        ax2 += -2.0 * wb * vy2 - eb * oy - wb2 * ox
        ay2 += 2.0 * wb * vx2 + eb * ox - wb2 * oy
        ox, oy = oax + sx3, oay + sy3
        ax3 += -2.0 * wb * vy3 - eb * oy - wb2 * ox
        ay3 += 2.0 * wb * vx3 + eb * ox - wb2 * oy
    ea1, ea2, ea3 = e1 + eb, e2 + eb, e3 + eb  # absolute angular accelerations

    # applied + inertia loads (d'Alembert), excluding joint forces
    w1x, w1y = m1 * (gx - ax1), m1 * (gy - ay1)
    w2x, w2y = m2 * (gx - ax2), m2 * (gy - ay2)
    w3x, w3y = m3 * (gx - ax3), m3 * (gy - ay3)
    fex = f_n * c3 - f_t * s3  # external force on the rocker, given in the rocker frame
    fey = f_n * s3 + f_t * c3
    px, py = l0 + arm * c3, arm * s3
    mom1 = -j1 * ea1
    mom2 = -j2 * ea2
    mom3 = -j3 * ea3 + m_ext

    # tangential parts from moments about C (eqs. 1-2)
    f21t = (_cross(sx2 - cx, sy2 - cy, w2x, w2y) + mom2) / l2
    f34t = (_cross(sx3 - cx, sy3 - cy, w3x, w3y) + _cross(px - cx, py - cy, fex, fey)
            + mom3) / l3
    # normal parts from the dyad balance F21 + F34 + W2 + W3 = 0 (eqs. 3-4)
    w3x_all, w3y_all = w3x + fex, w3y + fey
    vx = -(f21t * -s2 + f34t * -s3 + w2x + w3x_all)
    vy = -(f21t * c2 + f34t * c3 + w2y + w3y_all)
    det = _cross(c2, s2, c3, s3)  # sin(phi3 - phi2)
    f21n = _cross(vx, vy, c3, s3) / det
    f34n = _cross(c2, s2, vx, vy) / det
    f21x, f21y = f21n * c2 - f21t * s2, f21n * s2 + f21t * c2
    f34x, f34y = f34n * c3 - f34t * s3, f34n * s3 + f34t * c3
    f32x, f32y = -(f34x + w3x_all), -(f34y + w3y_all)
    # the crank (eq. 8 and 9-11)
    mb_reaction = -(_cross(bx, by, -f21x, -f21y) + _cross(sx1, sy1, w1x, w1y) + mom1)
    f14x, f14y = f21x - w1x, f21y - w1y

    # M_b by virtual work: sum of m (a - g).dr/dphi1 + J eps u - Q_ext; no reactions needed
    d1x, d1y = -r1y, r1x
    d2x, d2y = -by - u21 * r2y, bx + u21 * r2x
    d3x, d3y = -u31 * r3y, u31 * r3x
    dpx, dpy = -u31 * arm * s3, u31 * arm * c3
    mb = (m1 * ((ax1 - gx) * d1x + (ay1 - gy) * d1y) + j1 * ea1
          + m2 * ((ax2 - gx) * d2x + (ay2 - gy) * d2y) + j2 * ea2 * u21
          + m3 * ((ax3 - gx) * d3x + (ay3 - gy) * d3y) + j3 * ea3 * u31
          - (fex * dpx + fey * dpy) - m_ext * u31)

    res[R_F14X], res[R_F14Y], res[R_F21X], res[R_F21Y] = f14x, f14y, f21x, f21y
    res[R_F32X], res[R_F32Y], res[R_F34X], res[R_F34Y] = f32x, f32y, f34x, f34y
    res[R_MB], res[R_MB_REACTION] = mb, mb_reaction
    res[R_F21N], res[R_F21T] = f21n, f21t
    res[R_F34N], res[R_F34T] = f34n, f34t
    res[R_F32N], res[R_F32T] = f32x * c3 + f32y * s3, -f32x * s3 + f32y * c3
    res[R_F14N], res[R_F14T] = f14x * c1 + f14y * s1, -f14x * s1 + f14y * c1
    return True


@njit(**KERNEL_OPTIONS)
def _peak_quantity(q, res):
    """|F_A|, |F_B|, |F_C|, |F_D| or |M_b| from a kinetostatic solution."""
    if q == 0:
        return math.sqrt(res[R_F14X] ** 2 + res[R_F14Y] ** 2)
    if q == 1:
        return math.sqrt(res[R_F21X] ** 2 + res[R_F21Y] ** 2)
    if q == 2:
        return math.sqrt(res[R_F32X] ** 2 + res[R_F32Y] ** 2)
    if q == 3:
        return math.sqrt(res[R_F34X] ** 2 + res[R_F34Y] ** 2)
    return abs(res[R_MB])


@njit(**KERNEL_OPTIONS)
def _refine_peak(q, a, b, sampled, pr, sigma, res, tol, gx, gy):
    """Golden section for the maximum of quantity q on [a, b] (one sample spacing either
    side of the best sample), to 1e-10 of the interval: a location error d costs O(d^2) in
    the value. Never below the sampled maximum."""
    def value(phi):
        if not _joint_forces(phi, pr, sigma, res, tol, gx, gy):
            return -1.0
        return _peak_quantity(q, res)

    c, d = golden_points(a, b)
    fc, fd = value(c), value(d)
    while b - a > 1e-10 * (1.0 + abs(a)):
        a, b, c, d, fc, fd, left = golden_shrink(a, b, c, d, fc, fd)
        if left:
            fc = value(c)
        else:
            fd = value(d)
    return max(sampled, fc, fd)


@njit(**KERNEL_OPTIONS)
def _point(pr, tol, window, gl_x, gl_w, n_peak, prof_angles, out, prof, res):
    """One grid point: status, the scalar outputs (out) and the profiles (prof[k, j])."""
    nan = math.nan
    for k in range(out.shape[0]):
        out[k] = nan
    for k in range(prof.shape[0]):
        for j in range(prof.shape[1]):
            prof[k, j] = nan
    l0, l1, l2, l3 = pr[0], pr[1], pr[2], pr[3]
    w1 = pr[16]
    direction = -1.0 if w1 < 0.0 else 1.0
    if not crank_turns_fully(l0, l1, l2, l3, tol):
        return st.NOT_ASSEMBLABLE
    mask = change_point_identities(l0 / l1, l2 / l1, l3 / l1, tol)
    count = (mask & 1) + ((mask >> 1) & 1) + ((mask >> 2) & 1)
    kind = 0
    if mask & CHANGE_POINT_A:
        kind = CHANGE_POINT_A
    elif mask & CHANGE_POINT_B:
        kind = CHANGE_POINT_B
    elif mask & CHANGE_POINT_C:
        kind = CHANGE_POINT_C
    sigma = pr[20]
    if sigma == SIGMA_IMPACT:
        if kind == 0:
            return st.NO_SPECIAL_POSITION  # no impact branch to choose: give sigma
        sigma = impact_branch(kind, direction)
    out[7] = sigma
    if kind != 0 and kind != CHANGE_POINT_C and abs(l0 - l1) <= tol * (l0 + l1 + l2 + l3):
        return st.DEGENERATE
    start = math.pi if kind == CHANGE_POINT_C else 0.0  # cycle (phi1*, phi1* + 2 pi)
    gx, gy = -pr[19] * math.sin(pr[18]), -pr[19] * math.cos(pr[18])  # gravity, base frame

    # cycle work and RMS of M_b: Gauss-Legendre on the open cycle, one-sided at the node
    half = math.pi
    work = 0.0
    square = 0.0
    for k in range(gl_x.shape[0]):
        if not _joint_forces(start + half * (gl_x[k] + 1.0), pr, sigma, res, tol, gx, gy):
            return st.NOT_ASSEMBLABLE
        work += half * gl_w[k] * res[R_MB]
        square += half * gl_w[k] * res[R_MB] * res[R_MB]
    out[5] = math.sqrt(square / (2.0 * math.pi))
    out[6] = direction * work  # energy delivered by the drive per cycle

    # peaks outside |phi1 - node| < window (H11: F^n ~ 1/dphi1): a uniform sample finds
    # each maximum's basin, golden section on the exact kinetostatics refines it
    lo = start + (window if kind != 0 else 0.0)
    hi = start + 2.0 * math.pi - (window if kind != 0 else 2.0 * math.pi / n_peak)
    spacing = (hi - lo) / (n_peak - 1)
    best = np.full(5, -1.0)
    where = np.zeros(5)
    for k in range(n_peak):
        phi = lo + spacing * k
        if count > 1 and abs(phi - start - math.pi) < window:
            continue  # the second node at phi1* + pi (H10)
        if not _joint_forces(phi, pr, sigma, res, tol, gx, gy):
            return st.NOT_ASSEMBLABLE
        for q in range(5):
            value = _peak_quantity(q, res)
            if value > best[q]:
                best[q], where[q] = value, phi
    for q in range(5):
        a, b = where[q] - spacing, where[q] + spacing
        if kind != 0:  # stay out of the node's window (a smooth cycle is periodic)
            a, b = max(lo, a), min(hi, b)
        if count > 1:  # stay out of the second node's window
            if where[q] < start + math.pi:
                b = min(b, start + math.pi - window)
            else:
                a = max(a, start + math.pi + window)
        out[q] = _refine_peak(q, a, b, best[q], pr, sigma, res, tol, gx, gy)

    # profiles: the rigid-model values at every sampled angle (NaN only exactly at a node)
    for j in range(prof_angles.shape[0]):
        phi = prof_angles[j]
        at_node = False
        if kind != 0:
            for node in (start, start + 2.0 * math.pi, start - 2.0 * math.pi):
                if abs(phi - node) < 1e-12:
                    at_node = True
            if count > 1 and abs(phi - start - math.pi) < 1e-12:
                at_node = True
        if at_node or not _joint_forces(phi, pr, sigma, res, tol, gx, gy):
            continue
        prof[0, j], prof[1, j] = res[R_F21N], res[R_F21T]
        prof[2, j], prof[3, j] = res[R_F34N], res[R_F34T]
        prof[4, j], prof[5, j] = res[R_F32N], res[R_F32T]
        prof[6, j], prof[7, j] = res[R_F14N], res[R_F14T]
        prof[8, j] = res[R_MB]

    for k in range(7):
        if not math.isfinite(out[k]):
            return st.NONFINITE
    if count > 1:
        return st.SECOND_SPECIAL_POSITION
    if kind != 0:
        return st.SPECIAL_POSITION  # peaks are windowed: the rigid-model supremum is infinite
    return st.OK


@njit(**KERNEL_OPTIONS)
def linkage_forces_block(params, tol, window, gl_x, gl_w, n_peak, prof_angles, out, status,
                         prof):
    pr = np.empty(params.shape[0])
    res = np.empty(N_RESULT)
    out_i = np.empty(out.shape[0])
    prof_i = np.empty((prof.shape[0], prof.shape[2]))
    for i in range(params.shape[1]):
        for k in range(params.shape[0]):
            pr[k] = params[k, i]
        status[i] = _point(pr, tol, window, gl_x, gl_w, n_peak, prof_angles, out_i, prof_i,
                           res)
        for k in range(out.shape[0]):
            out[k, i] = out_i[k]
        for k in range(prof.shape[0]):
            for j in range(prof.shape[2]):
                prof[k, i, j] = prof_i[k, j]


def profile_angles(n):
    """The crank_angle coordinate of profiles: cell midpoints of [0, 2 pi)."""
    return 2.0 * np.pi * (np.arange(n) + 0.5) / n if n > 0 else np.empty(0)


def linkage_forces_run(params, method):
    """Registry entry point: (outputs, status, profiles[n_profiles, n, n_angles])."""
    tol, window = method[0], method[1]
    gl_x, gl_w = np.polynomial.legendre.leggauss(int(method[2]))
    angles = profile_angles(int(method[4]))
    n = params.shape[1]
    out = np.empty((len(OUTPUTS), n))
    status = np.empty(n, dtype=np.int8)
    prof = np.empty((len(PROFILES), n, angles.shape[0]))
    linkage_forces_block(np.ascontiguousarray(params), tol, window, gl_x, gl_w,
                         int(method[3]), angles, out, status, prof)
    return out, status, prof
