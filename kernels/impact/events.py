"""Event location inside an accepted step: the one event search of the package.

Events are the zero crossings of functions g_e(t, y), each in its own direction (+1: g
rising through 0, -1: falling), given as ``values(t, y, data)`` -> a tuple of g_e and
``rates(t, y, dy, data)`` -> a tuple of dg_e/dt. ``make_locator(values, rates, directions,
step)`` returns ``locate(step, context, start) -> (event, s, end)``: the earliest crossing in
(0, h] of a step, found on the step's cubic Hermite interpolant (event = -1: none); start and
end are the events' values and rates at the step's two ends:

1. a chord bound skips a step whose g stays on one side: the cubic's distance from its chord
   is at most 4/27 h (|g'_0| + |g'_1|) (NaN rates: no bound, the step is sampled);
2. sign samples inside the step (SUBSTEP_SAMPLES of them): a flight shorter than a step is
   seen;
3. an extremum check: where g' changes sign between samples towards the level, g at the
   interpolant's extremum (by bisection on g') is tested first, on an exact partial step,
   so a grazing contact that lasts less than the sample spacing, or passes the level by
   less than the interpolant's error, is not stepped over (H3);
4. Illinois regula falsi on the bracket, which returns whether it converged (where it does
   not, g jumps inside the bracket, and its estimate is still inside it for the polish);
5. the step's start never counts: a crossing needs g strictly on the far side before it
   (no event at the restart point, H4); but a flight that starts on the level and is past
   it again at the first sign sample is checked for a return inside that interval (a
   restart at zero normal speed leaves the level and may come back before the sample: no
   ballistic cap bounds it), at the interpolant's turn, on exact partial steps;
6. a step that starts beyond the level by more than ``slack`` (rounding at a restart is
   far less) has no crossing of it: the flight cannot be inside the tool, and where the
   state grows fast the cubic overshoots and reads as one (a blow-up read as a contact).

The flight polishes the located time by Newton on exact partial steps (kernels/impact/
flight.py): the interpolant is only O(h^4) accurate.
"""

from numba import njit

from kernels import INNER_OPTIONS, INLINE_OPTIONS
from kernels.impact.tuples import hermite, hermite_slope

SUBSTEP_SAMPLES = 4  # interior sign samples per step
BISECTIONS = 60  # for an extremum inside a sample interval: 2^-60 of it
ILLINOIS_ITERATIONS = 100


@njit(**INLINE_OPTIONS)
def crossed(before, after, direction):
    """Does g cross 0 from ``before`` to ``after`` in ``direction``?"""
    if direction > 0:
        return before < 0.0 <= after
    return before > 0.0 >= after


def make_bisection(rate):
    """The sign-change search specialised to rate(s, data): ``turn(data, lo, hi,
    start_positive, iterations) -> s``, where the rate, positive at lo iff start_positive,
    changes sign in (lo, hi): bisection, keeping the half whose left end has the start's
    sign. The one search for where an interpolant turns (an event function's extremum, the
    monitored angle's turning point)."""

    @njit(**INNER_OPTIONS)
    def turn(data, lo, hi, start_positive, iterations):
        for _ in range(iterations):
            mid = 0.5 * (lo + hi)
            if (rate(mid, data) > 0.0) == start_positive:
                lo = mid
            else:
                hi = mid
        return 0.5 * (lo + hi)

    return turn


def make_illinois(f):
    """The bracketing root finder specialised to f(x, data): ``root(data, lo, hi, flo, fhi,
    tol) -> (x, converged)`` by the Illinois variant of regula falsi, where flo and fhi
    have opposite signs. Converged means the bracket fell below ``tol`` or f vanished;
    otherwise the best estimate after ILLINOIS_ITERATIONS."""

    @njit(**INNER_OPTIONS)
    def root(data, lo, hi, flo, fhi, tol):
        side = 0
        mid = hi
        for _ in range(ILLINOIS_ITERATIONS):
            mid = hi - fhi * (hi - lo) / (fhi - flo)
            fm = f(mid, data)
            if (fm < 0.0) == (flo < 0.0):
                lo, flo = mid, fm
                if side == -1:
                    fhi *= 0.5
                side = -1
            else:
                hi, fhi = mid, fm
                if side == 1:
                    flo *= 0.5
                side = 1
            if hi - lo <= tol or fm == 0.0:
                return mid, True
        return mid, False

    return root


def make_event_roots(values, rates, step):
    """The searches of the locator: ``on_partial_step`` (g of an event on an exact partial
    step), Illinois on the interpolant and on exact partial steps, and ``extremum`` (where
    g turns inside an interval, by bisection on the interpolant's g')."""

    @njit(**INLINE_OPTIONS)
    def on_interpolant(s, data):
        """g of event e on the step's interpolant at s; data = (e, step, context)."""
        e, (t, h, y0, f0, y1, f1), (system, p, method, slack) = data
        return values(t + s, hermite(s, h, y0, f0, y1, f1), system)[e]

    @njit(**INLINE_OPTIONS)
    def on_partial_step(s, data):
        """g of event e on the exact partial step of length s from the step's start; data =
        (e, step, context)."""
        e, (t, h, y0, f0, y1, f1), (system, p, method, slack) = data
        ys, fs, _ = step(method, y0, f0, s, p, 1.0, 1.0)
        return values(t + s, ys, system)[e]

    root_on_interpolant = make_illinois(on_interpolant)
    root_on_partial_steps = make_illinois(on_partial_step)

    @njit(**INLINE_OPTIONS)
    def rate_on_interpolant(s, data):
        e, st, system = data
        t, h, y0, f0, y1, f1 = st
        return rates(t + s, hermite(s, h, y0, f0, y1, f1),
                     hermite_slope(s, h, y0, f0, y1, f1), system)[e]

    turn_on_interpolant = make_bisection(rate_on_interpolant)

    @njit(**INNER_OPTIONS)
    def extremum(e, lo, hi, up, st, system):
        """Where g_e turns in (lo, hi) (g' from + to - for a maximum)."""
        return turn_on_interpolant((e, st, system), lo, hi, up, BISECTIONS)

    return on_partial_step, root_on_interpolant, root_on_partial_steps, extremum


def make_locator(values, rates, directions, step):
    """The event search of a system: ``values``, ``rates``, the ``directions`` tuple and
    the system's Runge-Kutta step (runge_kutta.make_stepper), for exact values at a grazing
    extremum. A step is the tuple (t, h, y0, f0, y1, f1); the context (system data, p,
    method, slack)."""
    n_events = len(directions)

    on_partial_step, root_on_interpolant, root_on_partial_steps, extremum = (
        make_event_roots(values, rates, step))

    @njit(**INNER_OPTIONS)
    def first_crossing(e, g, r, st, context):
        """The first crossing of event e in (0, h], or -1; g and r: the event's values and
        rates at the step's two ends."""
        t, h, y0, f0, y1, f1 = st
        system, p, method, slack = context
        g0, g1 = g
        r0, r1 = r
        direction = directions[e]
        up = direction > 0
        if (g0 > slack) if up else (g0 < -slack):
            return -1.0
        data = (e, st, context)
        prev_s, prev, prev_rate = 0.0, g0, r0
        n = SUBSTEP_SAMPLES + 1
        for j in range(1, n + 1):
            s = h * j / n
            if j < n:
                ys = hermite(s, h, y0, f0, y1, f1)
                val = values(t + s, ys, system)[e]
                rate = rates(t + s, ys, hermite_slope(s, h, y0, f0, y1, f1), system)[e]
            else:
                val, rate = g1, r1
            if (prev_rate > 0.0 > rate) if up else (prev_rate < 0.0 < rate):
                # g turns towards the level inside this interval: its value at the turn,
                # on an exact partial step (the interpolant's error can hide a contact
                # shallower than itself), bracketed on exact partial steps if it crossed
                at = extremum(e, prev_s, s, up, st, system)
                g_at = on_partial_step(at, data)
                if crossed(prev, g_at, direction):
                    g_prev = on_partial_step(prev_s, data) if prev_s > 0.0 else g0
                    if crossed(g_prev, g_at, direction):
                        return root_on_partial_steps(data, prev_s, at, g_prev, g_at,
                                                     1e-15 * h)[0]
            if crossed(prev, val, direction):
                return root_on_interpolant(data, prev_s, s, prev, val, 1e-15 * h)[0]
            if j == 1 and not ((val < 0.0) if up else (val > 0.0)):
                # a start on the level, past it again at the first sample: where the flight
                # left the level (a restart at zero normal speed) and came back within the
                # first sample interval, the return is a crossing
                s_back = return_to_level(e, s, st, context)
                if s_back >= 0.0:
                    return s_back
            prev_s, prev, prev_rate = s, val, rate
        return -1.0

    @njit(**INNER_OPTIONS)
    def return_to_level(e, s, st, context):
        """The return to event e's level inside (0, s] of a flight that starts on it: where
        g is on the near side (strictly) at the interpolant's turn away from the level in
        (0, s) and on the far side at s, each on an exact partial step, the crossing between
        them, on exact partial steps; else -1."""
        t, h, y0, f0, y1, f1 = st
        system, p, method, slack = context
        direction = directions[e]
        up = direction > 0
        data = (e, st, context)
        at = extremum(e, 0.0, s, not up, st, system)
        g_at = on_partial_step(at, data)
        if not ((g_at < 0.0) if up else (g_at > 0.0)):
            return -1.0
        g_s = on_partial_step(s, data)
        if not crossed(g_at, g_s, direction):
            return -1.0
        return root_on_partial_steps(data, at, s, g_at, g_s, 1e-15 * h)[0]

    @njit(**INNER_OPTIONS)
    def locate(st, context, start):
        """(event, s, end) of the earliest crossing in (0, h] of the step st = (t, h, y0,
        f0, y1, f1), or (-1, -1.0, end); context = (system data, p, method, slack); start
        and end = (values, rates) of the events at the step's two ends (the flight passes
        a step's end on as the next step's start)."""
        t, h, y0, f0, y1, f1 = st
        system, p, method, slack = context
        v0, r0 = start
        v1, r1 = values(t + h, y1, system), rates(t + h, y1, f1, system)
        best_e, best_s = -1, -1.0
        for e in range(n_events):
            # the chord bound first, here: it settles almost every step without the call
            g0, g1 = v0[e], v1[e]
            reach = 4.0 / 27.0 * h * (abs(r0[e]) + abs(r1[e]))
            if (max(g0, g1) + reach < 0.0) if directions[e] > 0 else (min(g0, g1) - reach
                                                                      > 0.0):
                continue
            s = first_crossing(e, (g0, g1), (r0[e], r1[e]), st, context)
            if s >= 0.0 and (best_e < 0 or s < best_s):
                best_e, best_s = e, s
        return best_e, best_s, (v1, r1)

    return locate
