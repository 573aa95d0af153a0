"""Explicit Runge-Kutta steps (DOPRI5 with its embedded error, classical RK4) and the step-size
controller: the one place a step is taken.

``make_stepper(rhs, scales)`` specialises the step to a vector field ``rhs(y, p)`` on a tuple
state and to its error scales ``scales(y0, y1, rtol, atol)`` (one per component); the
returned ``step(method, y, f0, h, p, rtol, atol)`` gives (y1, f1, err), with f1 = rhs(y1)
(DOPRI5's first-same-as-last stage) and err the RMS of the embedded error over the scales
(> 1: reject; 0 for RK4). A partial step of length s < h from the same start is the exact
(to the method's order) state at t + s: events and peaks are polished on those.
"""

import math

from numba import njit

from kernels import INNER_OPTIONS
from kernels.impact.tuples import error_norm, lincomb, weighted

#: METHOD_EXACT: the system's closed-form flow (``exact``), where it has one. The one rule
#: for the three: a method that is not RK4 is DOPRI5 (step, first step, controller) unless
#: the system has an exact flow and METHOD_EXACT is asked for (the slides and the tangent
#: of a closed-form flight are integrated by DOPRI5)
METHOD_RK4, METHOD_DOPRI5, METHOD_EXACT = 0, 1, 2

# Dormand-Prince 5(4): nodes are implicit in the stages; weights b (5th order), and the
# error weights e = b5 - b4
A21 = 1 / 5
A31, A32 = 3 / 40, 9 / 40
A41, A42, A43 = 44 / 45, -56 / 15, 32 / 9
A51, A52, A53, A54 = 19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729
A61, A62, A63, A64, A65 = 9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656
B1, B3, B4, B5, B6 = 35 / 384, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84
E1, E3, E4, E5, E6, E7 = (71 / 57600, -71 / 16695, 71 / 1920, -17253 / 339200, 22 / 525,
                          -1 / 40)


@njit(**INNER_OPTIONS)
def _no_exact(y, h, p):
    return y


def make_stepper(rhs, scales, exact=None):
    """The step of the methods, specialised to rhs, the error scales and, where the system
    has one, its exact flow ``exact(y, h, p)`` (its error estimate is 0); a system without
    one takes DOPRI5's step for METHOD_EXACT (the rule at METHOD_EXACT)."""
    has_exact = exact is not None
    exact = exact if has_exact else _no_exact

    @njit(**INNER_OPTIONS)
    def dopri5(y, f0, h, p):
        k1 = f0
        k2 = rhs(lincomb(y, h, (A21,), (k1,)), p)
        k3 = rhs(lincomb(y, h, (A31, A32), (k1, k2)), p)
        k4 = rhs(lincomb(y, h, (A41, A42, A43), (k1, k2, k3)), p)
        k5 = rhs(lincomb(y, h, (A51, A52, A53, A54), (k1, k2, k3, k4)), p)
        k6 = rhs(lincomb(y, h, (A61, A62, A63, A64, A65), (k1, k2, k3, k4, k5)), p)
        y1 = lincomb(y, h, (B1, B3, B4, B5, B6), (k1, k3, k4, k5, k6))
        k7 = rhs(y1, p)
        err = weighted(h, (E1, E3, E4, E5, E6, E7), (k1, k3, k4, k5, k6, k7))
        return y1, k7, err

    @njit(**INNER_OPTIONS)
    def rk4(y, f0, h, p):
        k2 = rhs(lincomb(y, h, (0.5,), (f0,)), p)
        k3 = rhs(lincomb(y, h, (0.5,), (k2,)), p)
        k4 = rhs(lincomb(y, h, (1.0,), (k3,)), p)
        y1 = lincomb(y, h / 6.0, (1.0, 2.0, 2.0, 1.0), (f0, k2, k3, k4))
        return y1, rhs(y1, p)

    @njit(**INNER_OPTIONS)
    def step(method, y, f0, h, p, rtol, atol):
        if has_exact and method == METHOD_EXACT:
            y1 = exact(y, h, p)
            return y1, rhs(y1, p), 0.0
        if method != METHOD_RK4:
            y1, f1, err = dopri5(y, f0, h, p)
            return y1, f1, error_norm(err, scales(y, y1, rtol, atol))
        y1, f1 = rk4(y, f0, h, p)
        return y1, f1, 0.0

    return step


@njit(**INNER_OPTIONS)
def initial_step(method, dt, speed, rtol):
    """First step: dt for RK4; for DOPRI5 rtol^(1/5) of the time to move a unit of the
    state at ``speed``, the step an order-5 method keeps at that tolerance (fewer rejections
    while ramping up)."""
    if method == METHOD_RK4:
        return dt
    return min(0.1, max(rtol, 1e-14) ** 0.2 / max(1.0, abs(speed)))


@njit(**INNER_OPTIONS)
def next_step(h, err, after_reject, err_prev):
    """Step-size control of DOPRI5: the PI controller 0.9 err^-0.17 err_prev^0.04 (Hairer's
    DOPRI5 with beta = 0.04; it damps the accept/reject see-saw where the step must keep
    shrinking), within [0.2, 5]; after a rejection only 0.9 err^(-1/5) and no growth
    (Hairer-Norsett-Wanner II.4)."""
    if after_reject or err > 1.0:
        return h * min(1.0, max(0.2, 0.9 * max(err, 1e-10) ** -0.2))
    factor = 0.9 * max(err, 1e-10) ** -0.17 * max(err_prev, 1e-4) ** 0.04
    return h * min(5.0, max(0.2, factor))


@njit(**INNER_OPTIONS)
def rejected_step_size(h, err, err_prev, t):
    """The step to retry after a rejection (the controller without growth), and whether it
    fell below round-off of t: the flight cannot go on (a blow-up, a discontinuity)."""
    h = next_step(h, err, bool(True), err_prev)
    return h, h < 1e-14 * max(1.0, abs(t))


@njit(**INNER_OPTIONS)
def accepted_step_size(method, h, dt, err, after_reject, err_prev):
    """The next step after an accepted one: (h, err_prev) from the DOPRI5 controller, or dt
    for RK4 (a first step cut short by the ballistic-return cap is the only short one)."""
    if method != METHOD_RK4:
        return next_step(h, err, after_reject, err_prev), err
    return dt, err_prev


@njit(**INNER_OPTIONS)
def ballistic_cap(h, rate, acceleration):
    """The first step after a restart on a surface, leaving at ``rate`` but pulled back by
    ``acceleration``: at most half the ballistic return time 2|rate|/|acceleration|, or a
    short flight falls between two sign samples of the first step (H4)."""
    if rate * acceleration < 0.0:
        return min(h, 0.5 * abs(rate) / abs(acceleration))
    return h
