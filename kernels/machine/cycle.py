"""The periodic steady state (docs/machine.md §3): the fixed point of the section map after
the blow (a revolution, then the blow), found by the secant method from the constant-speed
guess (a running machine), or from rest by plain revolutions first (the run-up; a motor
that cannot start the machine stalls)."""

import math
from collections import namedtuple

from numba import njit

from kernels import INNER_OPTIONS
from kernels.machine.blow import Blow, blow, node
from kernels.machine.data import with_flywheel
from kernels.machine.declaration import (LAW_KINEMATIC, MOTOR_CONSTANT, START_REST,
                                         START_RUNNING)
from kernels.machine.revolution import REV_BLOW, Revolution, revolution

#: the steady state: the section map's residual |Phi(w) - w| <= FIXED_POINT_TOL w
FIXED_POINT_TOL = 1e-11
#: run-up revolutions from rest before the secant takes over
RUNUP_REVOLUTIONS = 12
#: how the search for the steady cycle ends: the cycle found; a revolution that did not
#: reach the blow (its ``end`` says how); a blow that sends the crank backwards; no fixed
#: point within the revolutions allowed (or no speed to start from); a blow whose law
#: creates energy (the kinematic law at some designs: no motor can balance it)
CYCLE_STEADY, CYCLE_ENDED, CYCLE_REVERSES, CYCLE_NO_CONVERGENCE, CYCLE_GAINS_ENERGY = range(5)
#: the steady cycle: how the search ended, the speed after the blow and the revolution
#: from there, the Blow at its end, revolutions flown and integration steps
Cycle = namedtuple("Cycle", ["outcome", "w_plus", "rev", "blow", "revolutions", "steps"])


@njit(**INNER_OPTIONS)
def _no_revolution():
    nan = math.nan
    return Revolution(REV_BLOW, nan, nan, nan, nan, nan, nan, nan, 0, nan)


@njit(**INNER_OPTIONS)
def _no_blow():
    nan = math.nan
    return Blow(w_plus=nan, impulse=nan, loss=nan, tool=nan, capture=nan)


@njit(**INNER_OPTIONS)
def constant_speed_guess(nd, r, law, m):
    """The crank speed at which the motor's work per turn pays the blow's loss at constant
    speed, 2 pi M(omega) = dE(omega) (gravity and the load do no net work): the secant's
    start. NaN where there is none (a blow that gains energy)."""
    c = blow(1.0, r, law, nd, m).loss  # the loss is quadratic in the speed
    if not c > 0.0:
        return math.nan
    m0 = m.motor.stall_torque
    if m.motor.law == MOTOR_CONSTANT:
        return math.sqrt(2.0 * math.pi * m0 / c)
    a, b = c / (2.0 * math.pi), m0 / m.motor.idle_speed
    return 2.0 * m0 / (b + math.sqrt(b * b + 4.0 * a * m0))


@njit(**INNER_OPTIONS)
def steady(nd, r, law, m, settings, max_revolutions, start_mode):
    """The periodic steady state: the fixed point of the section map omega1+ -> omega1+
    (a revolution, then the blow), |Phi(w) - w| <= FIXED_POINT_TOL w, by the secant method
    from the constant-speed guess; from rest (start_mode START_REST) by plain revolutions
    first, the run-up. m carries the reference speed of the scaled state."""
    nan = math.nan
    revolutions = steps = 0
    w0 = m.wref if start_mode == START_RUNNING else 0.0
    w_prev = f_prev = nan
    plain = RUNUP_REVOLUTIONS if start_mode == START_REST else 1
    w = w0
    while revolutions < max_revolutions:
        rev = revolution(w, nd, m, settings)
        revolutions += 1
        steps += rev.steps
        if rev.end != REV_BLOW:
            return Cycle(CYCLE_ENDED, w, rev, _no_blow(), revolutions, steps)
        b = blow(rev.w_minus, r, law, nd, m)
        if not b.w_plus > 0.0:
            return Cycle(CYCLE_REVERSES, w, rev, b, revolutions, steps)
        f = b.w_plus - w
        # the cycle repeats: its speed to FIXED_POINT_TOL, and the kinetic energy it would
        # carry into the next cycle to FIXED_POINT_TOL of the blow's loss (the energy
        # balance of the cycle; with a heavy flywheel the second is the tighter)
        if abs(f) <= FIXED_POINT_TOL * min(w, b.loss / (nd.j_after * w)):
            return Cycle(CYCLE_STEADY, w, rev, b, revolutions, steps)
        if revolutions <= plain or not (f != f_prev):
            w_new = b.w_plus
        else:
            w_new = w - f * (w - w_prev) / (f - f_prev)
            if not (w_new > 0.0 and math.isfinite(w_new)):
                w_new = b.w_plus  # a secant step out of range: a plain revolution instead
        w_prev, f_prev = w, f
        w = w_new
    return Cycle(CYCLE_NO_CONVERGENCE, w, _no_revolution(), _no_blow(), revolutions, steps)


@njit(**INNER_OPTIONS)
def solve(m, crank_own, flywheel, r, law, settings, max_revolutions, start_mode):
    """The steady cycle of the Machine ``m`` with flywheel J_f: (Cycle, Node, the machine
    with that flywheel and the reference scales of the cycle's state)."""
    m = with_flywheel(m, flywheel, crank_own, 1.0, 1.0)
    nd = node(m)
    if law == LAW_KINEMATIC and not blow(1.0, r, law, nd, m).loss > 0.0:
        return Cycle(CYCLE_GAINS_ENERGY, math.nan, _no_revolution(), _no_blow(), 0, 0), nd, m
    wref = constant_speed_guess(nd, r, law, m)
    if not math.isfinite(wref):
        if m.motor.law == MOTOR_CONSTANT:
            return Cycle(CYCLE_NO_CONVERGENCE, math.nan, _no_revolution(), _no_blow(), 0,
                         0), nd, m
        wref = m.motor.idle_speed
    m = with_flywheel(m, flywheel, crank_own, 0.5 * nd.j_after * wref * wref, wref)
    return steady(nd, r, law, m, settings, max_revolutions, start_mode), nd, m


@njit(**INNER_OPTIONS)
def speed_fluctuation(cycle):
    """delta = (omega_max - omega_min) / omega_mean of a steady cycle, the one-sided speeds
    at the blow included."""
    rev = cycle.rev
    w_max = max(rev.w_max, cycle.w_plus, rev.w_minus)
    w_min = min(rev.w_min, cycle.w_plus, rev.w_minus)
    return (w_max - w_min) * rev.period / (2.0 * math.pi)
