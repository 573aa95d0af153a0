"""One revolution between blows on the integration core (kernels/impact/flight.py), with
the crank angle as the independent variable and the kinetic energy as the state:
dT/dphi1 = M(omega1) + Q(phi1), with the time and the works of the motor, gravity and the
load as quadratures (docs/machine.md §3). The blow is the end of the interval; a stall (T
reaching 0) and the speed extrema (d omega1/dphi1 = 0) are events.

The state y = (phi1, T, t, W_motor, int M^2 dt, W_Q) is scaled by T_ref and 1/omega_ref
(the Machine's tref and wref); the constants below name its components.
"""

import math
from collections import namedtuple

from numba import njit

from kernels import INLINE_OPTIONS, INNER_OPTIONS
from kernels.impact import System
from kernels.impact.flight import make_flight, make_timed_flight
from kernels.impact.outcomes import FLIGHT_EVENT, FLIGHT_MAX_STEPS, FLIGHT_UNDERFLOW
from kernels.impact.tuples import relative_scales
from kernels.machine.dynamics import motor_torque, reduced, speed_of

#: the components of the revolution's state: the crank angle, the kinetic energy over
#: T_ref, the time times omega_ref, the motor's work, int M^2 dt and the work of Q (over
#: T_ref, T_ref omega_ref and T_ref)
ANGLE, ENERGY, TIME, MOTOR_WORK, TORQUE_SQUARED, LOAD_WORK = range(6)
#: a stall: the scaled kinetic energy falling through this (T = 0 itself has no crossing)
STALL_LEVEL = 1e-13
#: the first crank angle of a start from rest, flown in closed form [rad]
RESTART_ANGLE = 1e-10
#: a revolution longer than this many reference periods is too slow to be a machine
TOO_SLOW = 1e6
#: how a revolution ends
REV_BLOW, REV_STALL, REV_MAX_STEPS, REV_UNDERFLOW, REV_NONFINITE, REV_TOO_SLOW = range(6)
#: a revolution: how it ended, the speed before the blow, the slowest and fastest speed
#: (one-sided ends included), its time, the motor's work, the integral of M^2 dt, the work
#: of gravity and the load, the integration steps it took, and the crank angle where it
#: ended (the blow's, or a stall's)
Revolution = namedtuple("Revolution", ["end", "w_minus", "w_min", "w_max", "period",
                                       "motor_work", "torque_squared", "load_work",
                                       "steps", "angle"])


@njit(**INNER_OPTIONS)
def revolution_rhs(y, m):
    j, dj, q, u31 = reduced(y[ANGLE], m)
    w = speed_of(y[ENERGY], j, m)
    torque = motor_torque(w, m)
    tref, wref = m.tref, m.wref
    inv_w = 1.0 / w if w > 0.0 else math.inf
    return (1.0, (torque + q) / tref, wref * inv_w, torque / tref,
            torque * torque * inv_w / (tref * wref), q / tref)


@njit(**INLINE_OPTIONS)
def _speed_slope(y, m):
    """d omega1/dphi1 up to the positive factor 1/(J omega1): M + Q - J' omega1^2 / 2."""
    j, dj, q, u31 = reduced(y[ANGLE], m)
    w = speed_of(y[ENERGY], j, m)
    return motor_torque(w, m) + q - 0.5 * dj * w * w


@njit(**INLINE_OPTIONS)
def revolution_values(t, y, data):
    """Events: 0 the blow (phi1 reaches the end of the cycle), 1 a stall (T falls to 0),
    2 the next speed extremum: d omega1/dphi1 through 0, its sign in data flipped at each
    (so that the extremum just passed is not found again at the restart)."""
    end, m, w_min, w_max, sign = data
    return t - end, y[ENERGY] - STALL_LEVEL, sign * _speed_slope(y, m)


@njit(**INLINE_OPTIONS)
def revolution_rates(t, y, dy, data):
    return 1.0, dy[ENERGY], math.nan


@njit(**INLINE_OPTIONS)
def revolution_on_event(e, t, y, f, data, p):
    """The blow and a stall end the revolution; a speed extremum is kept and passed."""
    if e <= 1:
        return True, data
    end, m, w_min, w_max, sign = data
    j, dj, q, u31 = reduced(y[ANGLE], m)
    w = speed_of(y[ENERGY], j, m)
    return False, (end, m, min(w_min, w), max(w_max, w), -sign)


@njit(**INLINE_OPTIONS)
def revolution_start(t, y, f, data, p):
    return 0.0, 0.0


@njit(**INLINE_OPTIONS)
def revolution_monitor(t, y, f):
    return 0.0, 0.0, 0.0


@njit(**INLINE_OPTIONS)
def revolution_scales(y0, y1, rtol, atol):
    return relative_scales(y0, y1, rtol, atol)


#: the machine steps by DOPRI5 alone (its settings name no other method): DOP853 and RK4
#: are not compiled into its flights (methods=())
REVOLUTION = System(revolution_rhs, revolution_scales, revolution_values, revolution_rates,
                    (1, -1, -1), revolution_on_event, revolution_start,
                    revolution_monitor, methods=())
fly_revolution, _ = make_flight(REVOLUTION)
#: timed_revolution(phi0, y0, phi1, m, settings) -> (reached, y): the state at crank angle
#: phi1, the revolution's steps cut to land on it
timed_revolution = make_timed_flight(revolution_rhs, revolution_scales, methods=())


@njit(**INNER_OPTIONS)
def after_blow(w_plus, nd, m):
    """The revolution's state just after the blow, at crank speed w_plus."""
    return (m.linkage.start, 0.5 * nd.j_after * w_plus * w_plus / m.tref, 0.0, 0.0, 0.0,
            0.0)


@njit(**INNER_OPTIONS)
def revolution(w_plus, nd, m, settings):
    """One revolution from the blow's exit at crank speed w_plus to the next blow."""
    start, tref, wref = m.linkage.start, m.tref, m.wref
    jp, jm = nd.j_after, nd.j_before
    energy = 0.5 * jp * w_plus * w_plus / tref
    nan = math.nan
    y0 = (start, energy, 0.0, 0.0, 0.0, 0.0)
    if energy <= STALL_LEVEL:
        # at rest the machine moves only where the drive's torque beats the load there;
        # it then leaves as T = (M0 + Q) dphi, its time sqrt(2 J dphi/(M0 + Q)): a first
        # RESTART_ANGLE in closed form, where dt/dphi = 1/omega is singular
        j, dj, q, u31 = reduced(start, m)
        torque = motor_torque(0.0, m)
        if not torque + q > 0.0:
            return Revolution(REV_STALL, nan, nan, nan, nan, nan, nan, nan, 0, start)
        a = RESTART_ANGLE
        time = math.sqrt(2.0 * j * a / (torque + q))
        y0 = (start + a, (torque + q) * a / tref, time * wref, torque * a / tref,
              torque * torque * time / (tref * wref), q * a / tref)
    rising = 1.0 if _speed_slope(y0, m) > 0.0 else -1.0  # the next extremum: a maximum
    fl = fly_revolution(y0[ANGLE], y0, m, (start + 2.0 * math.pi, m, w_plus, w_plus, rising),
                        settings, bool(False))
    steps = fl.cost.steps + fl.cost.rejected
    if fl.outcome == FLIGHT_EVENT and fl.event == 0:
        y = fl.y
        w_minus = math.sqrt(max(2.0 * y[ENERGY] * tref / jm, 0.0))
        _, _, w_min, w_max, _ = fl.data
        period = y[TIME] / wref
        if not (period * wref < TOO_SLOW * 2.0 * math.pi):
            return Revolution(REV_TOO_SLOW, nan, nan, nan, nan, nan, nan, nan, steps,
                              y[ANGLE])
        return Revolution(REV_BLOW, w_minus, min(w_min, w_minus), max(w_max, w_minus),
                          period, y[MOTOR_WORK] * tref, y[TORQUE_SQUARED] * tref * wref,
                          y[LOAD_WORK] * tref, steps, y[ANGLE])
    end = (REV_STALL if fl.outcome == FLIGHT_EVENT else
           REV_MAX_STEPS if fl.outcome == FLIGHT_MAX_STEPS else
           REV_UNDERFLOW if fl.outcome == FLIGHT_UNDERFLOW else REV_NONFINITE)
    return Revolution(end, nan, nan, nan, nan, nan, nan, nan, steps, fl.y[ANGLE])
