"""The crank's dynamics between blows (docs/machine.md §1): the linkage on the closed
cycle, regular at both ends; the reduced inertia J(phi1) about the crank and its
derivative; the generalised force Q(phi1) of gravity and the load; the motor's torque.

The machine cycle is the open interval (phi1*, phi1* + 2 pi) on the impact branch, where
every kinematic quantity is smooth and has one-sided limits at both ends; the one-sided
rocker ratio u31 is evaluated in a desingularised closed form that is regular at both
ends (the vanishing factor of P or Q set to zero, sin phi1 / sqrt(PQ) cancelled
analytically), its derivative by a complex step.
"""

import cmath
import math

from numba import njit

from kernels import INLINE_OPTIONS, INNER_OPTIONS
from kernels.fourbar import CHANGE_POINT_C, closure_vectors
from kernels.machine.declaration import MOTOR_CONSTANT

#: complex-step width for u31' (no cancellation: any small step is exact to round-off)
COMPLEX_STEP = 1e-30


@njit(**INNER_OPTIONS)
def u31_on_cycle(sh, ch, lk):
    """The rocker ratio u31 of the Linkage ``lk`` on the closed cycle, regular at both
    ends (docs/machine.md §1.1): the stable closed form with the vanishing factor of P or
    Q exactly 0 and sin phi1 / sqrt(PQ) cancelled: s cos(phi1/2)/(sqrt(P) sqrt(l0 l1)) for
    types a, b (s = +1 on (0, 2 pi)), s sin(phi1/2)/(sqrt(Q) sqrt(l0 l1)) for c (s = -1 on
    (pi, 3 pi)). sh, ch: sin and cos of phi1/2 as complex numbers (a complex step gives
    u31')."""
    l0, l1, l2, l3 = lk.l0, lk.l1, lk.l2, lk.l3
    four = 4.0 * l0 * l1
    d2 = (l0 - l1) * (l0 - l1) + four * sh * sh
    c1 = (ch - sh) * (ch + sh)
    root = math.sqrt(l0 * l1)
    if lk.kind == CHANGE_POINT_C:
        q = _factor_q(lk) + four * sh * sh
        ratio = -sh / (cmath.sqrt(q) * root)
    else:
        p = _factor_p(lk) + four * ch * ch
        ratio = ch / (cmath.sqrt(p) * root)
    return (l1 * (l1 - l0 * c1) / d2
            - lk.sigma * l0 * l1 * (d2 + l2 * l2 - l3 * l3) / d2 * ratio)


@njit(**INLINE_OPTIONS)
def _factor_p(lk):
    """The constant part of P, exactly 0 for type c: (l2 + l3 - l0 - l1)(l0 + l1 + l2 + l3)."""
    if lk.kind == CHANGE_POINT_C:
        return 0.0
    l0, l1, l2, l3 = lk.l0, lk.l1, lk.l2, lk.l3
    return (l2 + l3 - l0 - l1) * (l2 + l3 + l0 + l1)


@njit(**INLINE_OPTIONS)
def _factor_q(lk):
    """The constant part of Q, exactly 0 for types a and b."""
    if lk.kind != CHANGE_POINT_C:
        return 0.0
    l0, l1, l2, l3 = lk.l0, lk.l1, lk.l2, lk.l3
    return (l0 - l1 - l2 + l3) * (l0 - l1 + l2 - l3)


@njit(**INNER_OPTIONS)
def kinematics(phi, lk):
    """The Linkage ``lk`` on the closed cycle at crank angle phi: (c1, s1, c2, s2, c3, s3,
    u21, u31, u21', u31'), regular at both ends (docs/machine.md §1.1): u31
    desingularised, u31' by a complex step, u21 and u21' from the loop's real part (no
    division by sin(phi3 - phi2))."""
    l1, l2, l3 = lk.l1, lk.l2, lk.l3
    sh, ch = math.sin(0.5 * phi), math.cos(0.5 * phi)
    c1, s1, c2, s2, c3, s3, d2, root = closure_vectors(sh, ch, lk.l0, l1, l2, l3, lk.sigma,
                                                       lk.snap)
    # one complex evaluation gives both: f(x + ih) = f(x) + ih f'(x) + O(h^2)
    z = complex(0.5 * phi, 0.5 * COMPLEX_STEP)
    value = u31_on_cycle(cmath.sin(z), cmath.cos(z), lk)
    u31, du31 = value.real, value.imag / COMPLEX_STEP
    c32, s32 = c3 * c2 + s3 * s2, s3 * c2 - c3 * s2  # cos, sin of phi3 - phi2
    c12, s12 = c1 * c2 + s1 * s2, s1 * c2 - c1 * s2  # cos, sin of phi1 - phi2
    u21 = (l3 * u31 * c32 - l1 * c12) / l2
    du21 = (l3 * du31 * c32 - l3 * u31 * s32 * (u31 - u21) + l1 * s12 * (1.0 - u21)) / l2
    return c1, s1, c2, s2, c3, s3, u21, u31, du21, du31


@njit(**INNER_OPTIONS)
def reduced(phi, m):
    """(J, J', Q, u31) of the Machine ``m`` at crank angle phi: the reduced inertia about
    the crank and its derivative, the generalised force of gravity and the load
    (docs/machine.md §1.1-1.2)."""
    c1, s1, c2, s2, c3, s3, u21, u31, du21, du31 = kinematics(phi, m.linkage)
    ms = m.masses
    l1 = m.linkage.l1
    c12, s12 = c1 * c2 + s1 * s2, s1 * c2 - c1 * s2
    p2, q2 = ms.p2, ms.q2
    c21 = p2 * c12 + q2 * s12  # (AB . rho2) / l1
    dc21 = (p2 * s12 - q2 * c12) * (u21 - 1.0)
    jb2, jd3, m2l1 = ms.jb2, ms.jd3, ms.m2l1
    j = (m.ja + m2l1 * l1 + 2.0 * m2l1 * c21 * u21 + jb2 * u21 * u21
         + jd3 * u31 * u31)
    dj = (2.0 * m2l1 * (dc21 * u21 + c21 * du21) + 2.0 * jb2 * u21 * du21
          + 2.0 * jd3 * u31 * du31)
    return j, dj, generalized_force(c1, s1, c2, s2, c3, s3, u21, u31, m), u31


@njit(**INNER_OPTIONS)
def generalized_force(c1, s1, c2, s2, c3, s3, u21, u31, m):
    """Q = Q_g + Q_ext: sum of m_i g . dr_Si/dphi1 and u31 (F . k x rho_P + M_ext)."""
    ms, ld = m.masses, m.loads
    gx, gy = ld.gx, ld.gy
    p1, q1, p2, q2, p3, q3 = ms.p1, ms.q1, ms.p2, ms.q2, ms.p3, ms.q3
    l1 = m.linkage.l1
    r1x, r1y = p1 * c1 - q1 * s1, p1 * s1 + q1 * c1
    r2x, r2y = p2 * c2 - q2 * s2, p2 * s2 + q2 * c2
    r3x, r3y = p3 * c3 - q3 * s3, p3 * s3 + q3 * c3
    d2x, d2y = -l1 * s1 - u21 * r2y, l1 * c1 + u21 * r2x
    qg = (ms.m1 * (-gx * r1y + gy * r1x) + ms.m2 * (gx * d2x + gy * d2y)
          + ms.m3 * u31 * (-gx * r3y + gy * r3x))
    arm, off = ld.arm, ld.offset
    rpx, rpy = arm * c3 - off * s3, arm * s3 + off * c3
    qe = u31 * (-ld.fx * rpy + ld.fy * rpx + ld.moment)
    return qg + qe


@njit(**INLINE_OPTIONS)
def motor_torque(w, m):
    """The motor's torque M(omega1): M0 (1 - omega1/omega_idle), or M0 for a constant
    torque."""
    if m.motor.law == MOTOR_CONSTANT:
        return m.motor.stall_torque
    return m.motor.stall_torque * (1.0 - w / m.motor.idle_speed)


@njit(**INLINE_OPTIONS)
def speed_of(energy, j, m):
    """omega1 from the scaled kinetic energy T/T_ref (0 at or below rest)."""
    return math.sqrt(max(2.0 * energy * m.tref / j, 0.0))


@njit(**INNER_OPTIONS)
def crank_motion(phi, energy, m):
    """At crank angle phi with scaled kinetic energy ``energy``: (omega1, epsilon1, the
    motor's torque): the crank's speed and its acceleration (M + Q - J' omega1^2 / 2) / J."""
    big_j, dj, q, u31 = reduced(phi, m)
    w = speed_of(energy, big_j, m)
    torque = motor_torque(w, m)
    return w, (torque + q - 0.5 * dj * w * w) / big_j, torque


@njit(**INNER_OPTIONS)
def inertia_is_singular(m):
    """Whether J(phi1) vanishes on the cycle. J >= J_A, so only without any inertia on the
    crank's side; then at the rocker's dead centres (u31 = 0, bisected from a sample) J is
    the coupler's alone and vanishes with it (a massless coupler)."""
    if m.ja > 0.0:
        return False
    start, top, bottom = m.linkage.start, 0.0, math.inf
    n = 720
    j, dj, q, u31_before = reduced(start, m)
    for k in range(1, n + 1):
        phi = start + 2.0 * math.pi * k / n
        j, dj, q, u31 = reduced(phi, m)
        top, bottom = max(top, j), min(bottom, j)
        if (u31_before > 0.0) != (u31 > 0.0):  # a dead centre of the rocker
            lo, hi = phi - 2.0 * math.pi / n, phi
            for _ in range(60):
                mid = 0.5 * (lo + hi)
                j_mid, dj, q, u31_mid = reduced(mid, m)
                if (u31_mid > 0.0) == (u31_before > 0.0):
                    lo = mid
                else:
                    hi = mid
            j_mid, dj, q, u31_mid = reduced(0.5 * (lo + hi), m)
            bottom = min(bottom, j_mid)
        u31_before = u31
    return not bottom > 1e-9 * top
