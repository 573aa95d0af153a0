"""Flywheel sizing for a speed fluctuation delta (docs/machine.md §3): the classical energy
method at constant mean speed, and the exact root of delta(J_f) = target on the steady
cycle."""

import math

import numpy as np
from numba import njit

from kernels import INNER_OPTIONS
from kernels.machine.cycle import CYCLE_STEADY, solve, speed_fluctuation
from kernels.machine.dynamics import reduced

#: samples of the cycle for the classical flywheel estimate: each interval integrated by
#: five-point Gauss-Legendre, the extrema refined by a parabola through three samples
CLASSICAL_SAMPLES = 2048
_GL5_X = (-0.9061798459386640, -0.5384693101056831, 0.0, 0.5384693101056831,
          0.9061798459386640)
_GL5_W = (0.2369268850561891, 0.4786286704993665, 0.5688888888888889, 0.4786286704993665,
          0.2369268850561891)


@njit(**INNER_OPTIONS)
def classical_flywheel(nd, r, m, crank_own, delta, w):
    """The flywheel for speed fluctuation delta by the classical energy method at the
    constant mean speed w of the running machine (docs/machine.md §3): the loss of law G
    at J_f -> infinity at w, the mean torque that pays it, the energy the flywheel must
    store and give back over the cycle (the cumulative work of that torque and Q against
    the linkage's own kinetic energy), J_A = (its range)/(delta w^2), less the crank's own
    inertia. 0 where the crank alone holds delta."""
    jm, jp, jpm = nd.j_before, nd.j_after, nd.j_cross
    ja = m.ja
    c = 0.5 * (jm - jp) - (jpm - jp) + (1.0 + r) * nd.m33 * nd.u31_after * nd.u31_before
    if not c > 0.0:
        return math.nan
    torque = c * w * w / (2.0 * math.pi)
    start, h = m.linkage.start, 2.0 * math.pi / CLASSICAL_SAMPLES
    j_start = jp - ja
    work = 0.0
    values = np.empty(CLASSICAL_SAMPLES + 1)
    values[0] = 0.0
    for k in range(CLASSICAL_SAMPLES):
        left = start + h * k
        for i in range(5):
            j, dj, q, u31 = reduced(left + 0.5 * h * (1.0 + _GL5_X[i]), m)
            work += 0.5 * h * _GL5_W[i] * (torque + q)
        if k == CLASSICAL_SAMPLES - 1:
            j = jm
        else:
            j, dj, q, u31 = reduced(left + h, m)
        values[k + 1] = work - 0.5 * ((j - ja) - j_start) * w * w
    top = _refined_extreme(values, 1.0)
    bottom = -_refined_extreme(values, -1.0)
    return max(0.0, (top - bottom) / (delta * w * w) - crank_own)


@njit(**INNER_OPTIONS)
def _refined_extreme(values, sign):
    """The largest of sign * values, refined by the parabola through the largest sample and
    its neighbours (the ends as they are)."""
    k = 0
    for i in range(values.shape[0]):
        if sign * values[i] > sign * values[k]:
            k = i
    best = sign * values[k]
    if 0 < k < values.shape[0] - 1:
        a, b, c = sign * values[k - 1], best, sign * values[k + 1]
        curvature = a - 2.0 * b + c
        if curvature < 0.0:
            best = b - 0.125 * (c - a) * (c - a) / curvature
    return best


@njit(**INNER_OPTIONS)
def exact_flywheel(m, crank_own, r, law, settings, max_revolutions, start_mode, delta, guess):
    """The flywheel J_f with delta(J_f) = delta: the secant method in (log J_f, log delta)
    from the classical estimate; 0 where the crank alone holds delta, NaN where a steady
    state is not found."""
    def log_delta(flywheel):
        cycle, nd, mm = solve(m, crank_own, flywheel, r, law, settings, max_revolutions,
                              start_mode)
        if cycle.outcome != CYCLE_STEADY:
            return math.nan
        return math.log(speed_fluctuation(cycle) / delta)

    if not log_delta(0.0) > 0.0:
        return 0.0
    x0 = math.log(max(guess, 1e-3 * max(crank_own, 1e-9)))
    f0 = log_delta(math.exp(x0))
    x1 = x0 + 0.1
    for _ in range(40):
        f1 = log_delta(math.exp(x1))
        if not (math.isfinite(f0) and math.isfinite(f1)):
            return math.nan
        if abs(x1 - x0) <= 1e-10 or f1 == 0.0:
            return math.exp(x1)
        x0, x1, f0 = x1, x1 - f1 * (x1 - x0) / (f1 - f0), f1
    return math.nan


@njit(**INNER_OPTIONS)
def sized_flywheel(m, crank_own, r, law, settings, max_revolutions, start_mode, delta):
    """The flywheel whose steady state has speed fluctuation delta (the inverted input of
    flywheel_inertia = "for_delta_target"): the classical estimate at the mean speed of a
    first solve with a unit flywheel, then the exact root; NaN where none is found."""
    cycle, nd, mm = solve(m, crank_own, 1.0, r, law, settings, max_revolutions, start_mode)
    if cycle.outcome != CYCLE_STEADY:
        return math.nan
    guess = classical_flywheel(nd, r, mm, crank_own, delta, 2.0 * math.pi / cycle.rev.period)
    if not math.isfinite(guess):
        return math.nan
    return exact_flywheel(m, crank_own, r, law, settings, max_revolutions, start_mode, delta,
                          guess)
