"""The verdict on a sequence of section states: periodic (the smallest period whose states
repeat), not periodic early (a quasi-periodic sequence that settles nowhere, by weighted
Birkhoff averages), or at the end of the budget (not periodic where the map stopped
contracting, else still converging)."""

import math

import numpy as np
from numba import njit

from kernels import KERNEL_OPTIONS
from kernels.impact.attractors import relative_distance
from kernels.impact.outcomes import SEQUENCE_MAX_STEPS, SEQUENCE_NOT_PERIODIC

MAX_PERIOD = 8  # the longest period classified
PERIOD_SEPARATION = 1000.0  # see classify_period


@njit(**KERNEL_OPTIONS)
def classify_period(history, count, tol, max_period):
    """Smallest p <= max_period such that the last cycle of p states of an impact map
    repeats the cycle before it (within tol, relative); 0 if none (yet). history rows
    0..count-1 are the states at successive sections.

    A p > 1 counts only when its p states lie apart by more than PERIOD_SEPARATION times
    the repeat's residual and tol: a period-1 transient whose multiplier mu is near -1
    alternates, and its two-step residual is |1 + mu| times its one-step difference, so it
    would pass as period 2 long before it converges (a period-1 design with mu = -0.94 was
    reported as period_n with the two-fold map's mu^2); and where the map's rounding
    exceeds tol, a period-2 cycle failed its own repeat and passed as period 4 (with mu^2).
    A genuine p-cycle's residual keeps falling while its states stay apart: it is
    classified a little later."""
    last = count - 1
    for p in range(1, max_period + 1):
        if last - 2 * p < 0:
            return 0
        residual = 0.0
        for q in range(p):
            a, b = last - q, last - q - p
            residual = max(residual, relative_distance(history[a], history[b], history[a]))
        if residual > tol:
            continue
        spread = math.inf  # the closest two states of the p-cycle
        for j in range(1, p):
            spread = min(spread, relative_distance(history[last], history[last - j],
                                                   history[last]))
        if spread > PERIOD_SEPARATION * max(residual, tol):
            return p
        return 0  # a lower period still converging: go on iterating
    return 0


#: an early verdict needs the weighted Birkhoff averages of the section states over the
#: last two quarters to agree to this, relative to the states' spread
BIRKHOFF_AGREEMENT = 1e-6


@njit(**KERNEL_OPTIONS)
def birkhoff_average(history, first, last, i):
    """The weighted Birkhoff average of component i of rows first .. last - 1 of
    ``history``, weights exp(-1/(s (1 - s))) at s = (j + 1/2)/(last - first) (Das, Saiki,
    Sander and Yorke, Nonlinearity 30, 2017): on a quasi-periodic orbit it converges faster
    than any power of the length, on a chaotic one like its square root."""
    total = weights = 0.0
    for j in range(first, last):
        s = (j - first + 0.5) / (last - first)
        w = math.exp(-1.0 / (s * (1.0 - s)))
        total += w * history[j, i]
        weights += w
    return total / weights


@njit(**KERNEL_OPTIONS)
def settles_nowhere(history, count, settings, repeat_tol):
    """The early verdict "not periodic" for a quasi-periodic sequence, at section counts n
    that are powers of two from settings.verdict_from, below the budget N =
    settings.max_impacts. Over the last half of the sequence, split into two quarters:
    (1) each component's weighted Birkhoff averages over the quarters agree to
    BIRKHOFF_AGREEMENT of its spread (a quasi-periodic orbit, or a periodic one; a chaotic
    one's agree to about 1e-2: it flies the budget, as it may still end without an
    impact, as 3 of 120 random blade designs did); (2) for every period p <= MAX_PERIOD,
    the differences of states p sections apart (relative, as classify_period takes them)
    stay above 1000 repeat_tol, and over the last quarter are, on average and at their
    largest, at least 0.1^(n/(4N)) of those over the quarter before: no cycle is near (9
    designs of the stability example, converging slowly to a period-n cycle, passed (1)
    and the steps of p = 1 alone). A transient whose differences shrink geometrically by
    rho a section passes (2) only where rho >= 0.1^(1/N), which the budget's own verdict
    (not_periodic: the step at N over a tenth of the one at N/2, rho > 0.1^(2/N)) calls
    not periodic too."""
    n, budget = count, settings.max_impacts
    if settings.verdict_from <= 0 or n < settings.verdict_from or n >= budget or (
            n & (n - 1)) != 0:
        return False
    quarter = n // 4
    for i in range(history.shape[1]):
        spread = 0.0
        for j in range(n - 2 * quarter, n):
            spread = max(spread, abs(history[j, i] - history[n - 1, i]))
        drift = abs(birkhoff_average(history, n - 2 * quarter, n - quarter, i)
                    - birkhoff_average(history, n - quarter, n, i))
        if not drift <= BIRKHOFF_AGREEMENT * spread:
            return False
    floor = 0.1 ** (n / (4.0 * budget))
    for p in range(1, MAX_PERIOD + 1):
        mean, largest, smallest = np.zeros(2), np.zeros(2), math.inf
        for half in range(2):
            for j in range(n - (2 - half) * quarter, n - (1 - half) * quarter):
                step = relative_distance(history[j], history[j - p], history[j])
                mean[half] += step / quarter
                largest[half] = max(largest[half], step)
                if half == 1:
                    smallest = min(smallest, step)
        if not (smallest > 1000.0 * repeat_tol and mean[1] >= floor * mean[0]
                and largest[1] >= floor * largest[0]):
            return False
    return True


@njit(**KERNEL_OPTIONS)
def not_periodic(history, count):
    """How a sequence that found no cycle within its budget ended: not periodic where its
    map has stopped contracting (its last step is over a tenth of the one half-way), else
    still converging (max_steps)."""
    recent = older = 0.0
    for i in range(history.shape[1]):
        recent = max(recent, abs(history[count - 1, i] - history[count - 2, i]))
        older = max(older, abs(history[count // 2, i] - history[count // 2 - 1, i]))
    return (SEQUENCE_NOT_PERIODIC if count >= 20 and recent > 0.1 * older else
            SEQUENCE_MAX_STEPS)
