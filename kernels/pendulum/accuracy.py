"""The accuracy policy of the integrated pendulum: what rtol, atol and step a requested
accuracy ``tol`` takes, and the error each solve reports (``error_estimate``).

``auto`` without a closed form solves by DOPRI5 (DOP853 at tight tol), goes on from each
cycle at a finer rtol and estimates the error from the difference; the exact flights (a
table row with ``exact_flow``) take their step from the event search's interpolant error
and report the section repeat tolerance; the rotor stop's closed form is exact to
round-off.
"""

import cmath
import math

import numpy as np
from numba import njit

from kernels import KERNEL_OPTIONS
from kernels.impact.outcomes import SEQUENCE_CYCLE
from kernels.impact.runge_kutta import METHOD_DOP853, METHOD_DOPRI5
from kernels.pendulum.cases import ROW

#: auto without a closed form: DOPRI5 at atol = rtol (psi and psi' are O(1), so the absolute
#: error is set on that scale, H5) and rtol = tol x a factor calibrated on 360 random rotor
#: designs (seeds 0-29 of tests/test_auto.py's sampler) against a 1e-13 reference: the
#: largest factor whose worst output error stayed below tol with a margin of 1.5-2.
#: Tolerance proportionality fails at loose tolerances (rtol = tol/10 gave 2.9 tol at
#: tol = 1e-3), hence the smaller factors there. DOPRI5 beat fixed-step RK4 at every
#: accuracy measured. Factors by log10(tol), linear in between.
AUTO_RTOL_FACTOR = ((-3.0, 0.01), (-4.0, 0.08), (-5.0, 0.1), (-6.0, 0.2), (-8.0, 0.3))
AUTO_ATOL_PER_RTOL = 1.0
#: at tol <= AUTO_DOP853_BELOW auto integrates by DOP853 at rtol = tol x AUTO_DOP853_FACTOR.
#: On 120 random rotor designs (seeds 0-9 of the sampler) against DOPRI5 at rtol 1e-13,
#: DOP853's worst output error was 4-8 rtol at rtol 1e-12 to 1e-9 (the acceleration peak
#: the largest; DOPRI5's 1.0-1.4 rtol) and 19 rtol at 1e-8, where DOPRI5 at its own
#: calibrated rtol needs as many right-hand sides,
#: and at tol 1e-9 auto by DOP853 took 1.17x fewer right-hand sides but as much CPU time
#: (benchmarks/bench_auto.py --dop853): DOP853 pays from 1e-10 on. The factor keeps that
#: worst error below tol/2.
AUTO_DOP853_BELOW = 1e-10
AUTO_DOP853_FACTOR = 0.07


def auto_method(tol):
    """The core's method auto integrates with at an accuracy tol: DOPRI5, or DOP853 where
    tol is tight (AUTO_DOP853_BELOW)."""
    return METHOD_DOP853 if tol <= AUTO_DOP853_BELOW else METHOD_DOPRI5


def auto_rtol(tol):
    """The rtol of auto's method for a requested output accuracy tol (AUTO_RTOL_FACTOR,
    AUTO_DOP853_FACTOR)."""
    if auto_method(tol) == METHOD_DOP853:
        return tol * AUTO_DOP853_FACTOR
    x, f = np.array(AUTO_RTOL_FACTOR).T
    return tol * float(np.interp(math.log10(tol), x[::-1], f[::-1]))


#: the values whose relative error auto estimates (and bounds by tol)
ESTIMATED = (ROW.amplitude, ROW.frequency, ROW.interval, ROW.speed, ROW.acceleration,
             ROW.rotor_speed)
#: auto without a closed form: each case is solved at AUTO_COARSE times the calibrated
#: rtol, and where it reaches a cycle goes on from it AUTO_REFINE times finer (Settings'
#: finer_by: the finer solve's own cycle, without flying the transient again); the finer
#: values are reported, with their error estimated as |coarse - fine| / (AUTO_REFINE - 1)
#: (the global error of DOPRI5 and DOP853 about proportional to rtol); a case whose estimate exceeds AUTO_ACCEPT
#: tol (a safety factor on that proportionality) is solved again, both stages
#: AUTO_REFINE times finer, at most AUTO_ROUNDS times in all
AUTO_ACCEPT = 0.1
AUTO_COARSE = 2.0
AUTO_REFINE = 8.0
AUTO_ROUNDS = 3
#: the finest rtol auto asks of its method (round-off): no round goes finer
AUTO_FINEST = 1e-14


@njit(**KERNEL_OPTIONS)
def cycle_error(coarse, fine, margins):
    """The estimated relative error of the finer of two solves of one case, from their rows
    (ROW): the largest relative difference of the cycle's values over the finer one's error
    ratio; inf where the two disagree on the outcome, the period or the chatter; NaN where
    neither has a cycle. The leading multiplier (where asked for) counts on the unit
    circle's scale, |dmu|/max(1, |mu|): it may be 0, and a sensitive blade design's
    multiplier was 1.3e-5 off at tol 1e-8 while the other values met it. With ``margins``
    (asked for) the slowest-over-fastest impact ratio and the edge distance count too, on
    the scale of 1 (a ratio; radians): an edge distance was 1.6e-7 off at tol 1e-8 after a
    flight of ten rotor turns, where the values above met tol."""
    for j in (ROW.outcome, ROW.period, ROW.chatter):
        a, b = coarse[j], fine[j]
        if (0.0 if math.isnan(a) else a) != (0.0 if math.isnan(b) else b):
            return math.inf
    if fine[ROW.outcome] != SEQUENCE_CYCLE:
        return math.nan
    diff = -math.inf
    for j in ESTIMATED:
        d = abs(coarse[j] - fine[j]) / abs(fine[j])
        if not math.isnan(d):
            diff = max(diff, d)
    mu_coarse = coarse[ROW.modulus] * cmath.exp(1j * coarse[ROW.angle])
    mu_fine = fine[ROW.modulus] * cmath.exp(1j * fine[ROW.angle])
    d = abs(mu_coarse - mu_fine) / max(1.0, abs(mu_fine))
    if not math.isnan(d):
        diff = max(diff, d)
    if margins:
        for j in (ROW.speed_ratio, ROW.edge):
            d = abs(coarse[j] - fine[j]) / max(1.0, abs(fine[j]))
            if not math.isnan(d):
                diff = max(diff, d)
    return max(diff / (AUTO_REFINE - 1.0), 0.0)


@njit(**KERNEL_OPTIONS)
def estimated_error(coarse, fine, margins=False):
    """cycle_error of each case, from the rows of its two solves."""
    errors = np.empty(coarse.shape[0])
    for i in range(coarse.shape[0]):
        errors[i] = cycle_error(coarse[i], fine[i], margins)
    return errors


def solve_auto(solve, cases, tol, margins=False):
    """auto on a system without a closed form: auto_method at AUTO_COARSE times the calibrated
    rtol, going on from each cycle AUTO_REFINE times finer, both again AUTO_REFINE times
    finer where the estimate exceeds AUTO_ACCEPT tol (``margins``: the cycle's margins
    asked for count in it). ``solve(cases, method, rtol, atol, dt, finer_by, accept,
    margins) -> (rows, first-stage rows)``. Counters add up every solve."""
    rtol = AUTO_COARSE * auto_rtol(tol)
    rows = np.empty((cases.shape[0], len(ROW)))
    pending = np.arange(cases.shape[0])
    counters = [ROW.steps, ROW.rejected, ROW.events]
    spent = np.zeros((cases.shape[0], len(counters)))
    for round_ in range(AUTO_ROUNDS):
        # a case whose estimate misses accept is solved again; in the last round accept is
        # inf. The kernel reads the same accept (Settings.accept): it leaves what the next
        # round flies anyway to that round
        last = round_ == AUTO_ROUNDS - 1 or rtol / AUTO_REFINE ** 2 < AUTO_FINEST
        accept = math.inf if last else AUTO_ACCEPT * tol
        fine, coarse = solve(cases[pending], auto_method(tol), rtol, rtol * AUTO_ATOL_PER_RTOL,
                             0.0, AUTO_REFINE, accept, margins)
        spent[pending] += fine[:, counters]
        fine[:, ROW.error] = estimated_error(coarse, fine, margins)
        rows[pending] = fine
        pending = pending[fine[:, ROW.error] > accept]
        if not pending.size:
            break
        rtol /= AUTO_REFINE
    rows[:, counters] = spent
    return rows


#: the closed-form flight's longest step, in the pendulum's own time (at tol above 4e-6)
EXACT_STEP_MAX = 0.2
#: its section states repeat to 10 x this rtol (at most 1e-9), whatever tol: the flights are
#: exact, so a tighter test costs a few sections (1-3 % of the steps), and a looser one
#: takes a slowly drifting quasi-periodic sequence for a cycle (at rtol = tol/10 and tol
#: 1e-6, 45 of the blade example's 306 designs, quasi-periodic at DOPRI5 rtol 1e-12,
#: came out period_n)
EXACT_SECTION_RTOL = 1e-10


def exact_step_length(tol):
    """The closed-form flight's step, in the pendulum's own time, for an accuracy tol: the
    flow is exact, but the events are searched on a step's cubic Hermite interpolant
    (kernels/impact/events.py), whose error is about L^4/384 of the motion's scale; L =
    (384 tol)^(1/4) keeps it within tol, so that a contact is missed or invented only
    within tol of grazing (docs/impact_core.md). At most EXACT_STEP_MAX: on 200 random
    blade designs, steps of 0.5 (tol 1e-3) ended 6 more designs in another regime than
    DOPRI5 at rtol 1e-13 than steps of 0.1-0.3 did."""
    return min((384.0 * tol) ** 0.25, EXACT_STEP_MAX)


def exact_settings(tol):
    """(rtol, atol, step) of the closed-form flight for an accuracy tol: steps of
    exact_step_length(tol), section states repeating to 10 x min(tol/10,
    EXACT_SECTION_RTOL), and the tangent's and slides' flights, where integrated, by
    DOPRI5 at that rtol."""
    rtol = min(tol / 10.0, EXACT_SECTION_RTOL)
    return rtol, rtol * AUTO_ATOL_PER_RTOL, exact_step_length(tol)


def closed_form_estimate(rows, repeat_tol=0.0):
    """The error_estimate of rows solved in closed form: where there is a cycle, the
    relative error the solve allows: 0 for the rotor stop's closed form (its values are
    exact to round-off), the section repeat tolerance ``repeat_tol`` for exact flights
    (their cycle is accepted when its section states repeat to it, the values' only error
    left); NaN elsewhere."""
    return np.where(rows[:, ROW.outcome] == SEQUENCE_CYCLE, repeat_tol, np.nan)
