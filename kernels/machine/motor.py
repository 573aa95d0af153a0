"""The motor sized for a crank speed (the inverted input ``omega1``): the idle speed
omega_idle of a linear motor law M0 (1 - omega1/omega_idle) whose steady cycle runs at a
given mean crank speed, its exact root (docs/machine.md §3).

The mean speed grows with omega_idle: from the constant-speed balance 2 pi M(omega) =
c omega^2 (c the blow's loss at unit speed) the first guess is omega / (1 - c omega^2 /
(2 pi M0)), and the secant method in (log omega_idle, log mean speed) takes it to the
steady cycle's own mean speed. No idle speed reaches a speed above sqrt(2 pi M0 / c), the
constant-speed limit of a motor that gives M0 at every speed: unreachable."""

import math

from numba import njit

from kernels import INNER_OPTIONS
from kernels.machine.blow import blow, node
from kernels.machine.cycle import CYCLE_STEADY, solve
from kernels.machine.data import Machine, Motor, with_flywheel
from kernels.machine.flywheel import sized_flywheel

#: how the search for the idle speed ends: found; the speed is beyond the motor's reach;
#: no steady state on the way (a solve that did not converge)
MOTOR_FOUND, MOTOR_UNREACHABLE, MOTOR_NO_ROOT = range(3)
#: the mean speed is the target's to this (relative): the steady cycle's own values hold to
#: about the integration's tolerance (method.tol, 1e-10 by default)
SPEED_TOL = 1e-10


@njit(**INNER_OPTIONS)
def with_idle(m, idle):
    """The Machine with another idle speed of its motor."""
    return Machine(linkage=m.linkage, masses=m.masses, loads=m.loads,
                   motor=Motor(law=m.motor.law, stall_torque=m.motor.stall_torque,
                               idle_speed=idle),
                   ja=m.ja, tref=m.tref, wref=m.wref)


@njit(**INNER_OPTIONS)
def flywheel_at(m, crank_own, flywheel, sized, r, law, settings, max_revolutions,
                start_mode, delta):
    """The flywheel of the machine ``m``: ``flywheel`` as given, or sized for delta."""
    if sized:
        return sized_flywheel(m, crank_own, r, law, settings, max_revolutions, start_mode,
                              delta)
    return flywheel


@njit(**INNER_OPTIONS)
def _log_speed_ratio(m, idle, crank_own, flywheel, sized, r, law, settings,
                     max_revolutions, start_mode, delta, target):
    mi = with_idle(m, idle)
    fw = flywheel_at(mi, crank_own, flywheel, sized, r, law, settings, max_revolutions,
                     start_mode, delta)
    if not math.isfinite(fw):
        return math.nan
    cycle, nd, mm = solve(mi, crank_own, fw, r, law, settings, max_revolutions, start_mode)
    if cycle.outcome != CYCLE_STEADY:
        return math.nan
    return math.log(2.0 * math.pi / cycle.rev.period / target)


@njit(**INNER_OPTIONS)
def idle_for_speed(m, crank_own, flywheel, sized, r, law, settings, max_revolutions,
                   start_mode, delta, target):
    """(outcome MOTOR_*, the idle speed whose steady cycle's mean crank speed is
    ``target``); ``flywheel`` as given, or sized for delta at each idle speed tried."""
    nd = node(with_flywheel(m, 1.0 if sized else flywheel, crank_own, 1.0, 1.0))
    c = blow(1.0, r, law, nd, m).loss
    m0 = m.motor.stall_torque
    if not (c > 0.0 and target * target * c < 2.0 * math.pi * m0):
        return MOTOR_UNREACHABLE, math.nan
    x0 = math.log(target / (1.0 - c * target * target / (2.0 * math.pi * m0)))
    f0 = _log_speed_ratio(m, math.exp(x0), crank_own, flywheel, sized, r, law, settings,
                          max_revolutions, start_mode, delta, target)
    if not math.isfinite(f0):
        return MOTOR_NO_ROOT, math.nan
    if abs(f0) <= SPEED_TOL:
        return MOTOR_FOUND, math.exp(x0)
    x1 = x0 - f0  # the mean speed about proportional to the idle speed near the guess
    for _ in range(40):
        f1 = _log_speed_ratio(m, math.exp(x1), crank_own, flywheel, sized, r, law,
                              settings, max_revolutions, start_mode, delta, target)
        if not math.isfinite(f1):
            return MOTOR_NO_ROOT, math.nan
        if abs(f1) <= SPEED_TOL or abs(x1 - x0) <= 1e-13:
            return MOTOR_FOUND, math.exp(x1)
        if f1 == f0:
            return MOTOR_NO_ROOT, math.nan
        x0, x1, f0 = x1, x1 - f1 * (x1 - x0) / (f1 - f0), f1
    return MOTOR_NO_ROOT, math.nan
