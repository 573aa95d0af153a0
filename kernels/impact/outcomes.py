"""How a flight or an impact sequence ended, and what it cost: one enumeration, one record."""

import math
from collections import namedtuple

from numba import njit

from kernels import INNER_OPTIONS

#: how a flight ended
FLIGHT_EVENT = 0  # a terminal event (a contact, an escape): the flight's event says which
FLIGHT_HORIZON = 1  # no terminal event within the horizon
FLIGHT_MAX_STEPS = 2  # the step budget ran out
FLIGHT_UNDERFLOW = 3  # the step size fell below round-off
FLIGHT_NONFINITE = 4  # a fixed step (RK4) reached a state that is not finite

#: what a flight or a whole impact sequence cost: accepted and rejected steps, located events
Counters = namedtuple("Counters", ["steps", "rejected", "events"])
NO_COST = Counters(0, 0, 0)

#: the settings of a solve, by the names the spec gives them: the method
#: (runge_kutta.METHOD_*), its tolerances, the fixed step (RK4's ``dt``, or the exact flow's
#: step), a flight's step budget and horizon (in the flight's time), and for an impact
#: sequence its budget of impacts, the starting states per case, and the first section
#: count at which it may be called not periodic before its budget (verdicts.settles_nowhere;
#: 0: only at the budget); ``finer_by`` > 1: each sequence that reaches a cycle goes on from
#: it at rtol and atol finer_by times smaller to the cycle there (a second solve that need
#: not fly the transient again; 0: one solve); where the first start's two stages differ by
#: an estimated error over ``accept`` (pendulum/accuracy.cycle_error; ``margins``: the
#: cycle's margins count in it), the case is to be solved again finer, and its other starts
#: are not flown
Settings = namedtuple("Settings", ["method", "rtol", "atol", "dt", "max_steps", "horizon",
                                   "max_impacts", "starts", "verdict_from", "finer_by",
                                   "accept", "margins"],
                      defaults=(1000, 1, 64, 0.0, math.inf, False))


@njit(**INNER_OPTIONS)
def add(a, b):
    """The sum of two Counters records."""
    return Counters(a.steps + b.steps, a.rejected + b.rejected, a.events + b.events)

#: how an impact sequence ended
SEQUENCE_CYCLE = 0  # it settled into a cycle of impacts (its period and chatter say which)
SEQUENCE_ESCAPE = 1  # the flight went over the top (relative rotation)
SEQUENCE_NO_IMPACT = 2  # a flight met no tool within the horizon
SEQUENCE_NOT_PERIODIC = 3  # no cycle within the budget of impacts, and no contraction
SEQUENCE_MAX_STEPS = 4  # a flight's step budget ran out, or the map still contracts
SEQUENCE_UNDERFLOW = 5  # a flight's step size fell below round-off
SEQUENCE_DEGENERATE = 6  # the contact does not open after the impact law
SEQUENCE_SEPARATRIX = 7  # the cycle's launch speed is the escape threshold, to rounding
SEQUENCE_NONFINITE = 8  # a flight reached a state that is not finite
