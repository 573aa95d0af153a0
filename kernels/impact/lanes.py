"""Lanes: the steps of several flights taken together, so that LLVM vectorises them.

A driver that holds many flights at once (the pendulum's block, kernels/pendulum/systems.py)
keeps each one's state (flight.FlightState) and, for its next step, the step's inputs in a
lane-minor buffer: field by field, ``lanes`` values each (one per flight), in one flat
array. ``make_trial(flier, lanes, methods)`` returns ``trial(buf, method, y, p)``, the step
of every lane from its inputs to its outputs in the same buffer, and ``layout(y, p)`` the
buffer's rows (Layout); ``y`` and ``p`` are a state and a parameter tuple of the system,
for their sizes. The step is the system's own (``Flier.lane_step``: the same function,
inlined into the loop), so a flight's bits do not depend on its lane or on the other
lanes; everything but the step (events, polish, impacts, the step-size control) is the
flight's own ``after``, lane by lane. What vectorises: one flat buffer (separate arrays
per field do not), and a step without calls (no libm: the rotor model's sine and cosine
are kernels/elementary.sincos_lane).

Lanes that hold no flight take their step on whatever their inputs were: the driver reads
no output of theirs.
"""

from collections import namedtuple

from numba import njit

from kernels import INLINE_OPTIONS, INNER_OPTIONS
from kernels.impact.runge_kutta import METHOD_DOP853, METHOD_DOPRI5, METHOD_RK4
from kernels.impact.tuples import gather, scatter

#: the rows of a lane buffer (each ``lanes`` long): the step's inputs, the state, its
#: derivative, the step size, the time, the system data, the parameters and the
#: tolerances, and its outputs, the state and derivative at the step's end, the error
#: measure and whether no event can fire in the step (1.0, Flier.lane_clear); ``size``
#: rows in all
Layout = namedtuple("Layout", ["y", "f", "h", "t", "data", "p", "rtol", "atol", "y1", "f1",
                               "err", "clear", "size"])


@njit(**INLINE_OPTIONS)
def layout(y, p, data):
    """The rows of the lane buffer of a system whose states are like ``y``, parameters like
    ``p`` and system data like ``data``."""
    n, n_p, n_d = len(y), len(p), len(data)
    d = 2 * n + 2
    rtol = d + n_d + n_p
    return Layout(y=0, f=n, h=2 * n, t=2 * n + 1, data=d, p=d + n_d, rtol=rtol,
                  atol=rtol + 1, y1=rtol + 2, f1=rtol + 2 + n, err=rtol + 2 + 2 * n,
                  clear=rtol + 3 + 2 * n, size=rtol + 4 + 2 * n)


def make_trial(flier, lanes, methods):
    """``trial(buf, method, y, p, data)``: the step of each of ``lanes`` flights by
    ``method`` (DOPRI5, or one of ``methods`` compiled in beside it) from the inputs in
    ``buf`` to the outputs there (Layout), with the bound on its events (Flier.lane_clear).
    With one lane the step is called; with more it is inlined into one loop per method,
    which LLVM vectorises."""
    step = flier.step if lanes == 1 else flier.lane_step
    lane_clear = flier.lane_clear
    high_order, fixed_step = METHOD_DOP853 in methods, METHOD_RK4 in methods

    def loop(fixed, step=step):
        """The steps of all lanes, by the method ``fixed`` (a constant, folded into the
        step) or, where it is None, by the one asked for. A loop of its own for each
        method (in one function with another method's loop, the loop's variables met at
        the branches' end, and LLVM did not vectorise it), its body written out here
        (inlined from a function of its own, it was not vectorised either)."""
        @njit(**INNER_OPTIONS)
        def steps(buf, method, like_y, like_p, like_data):
            rows = layout(like_y, like_p, like_data)
            for lane in range(lanes):
                y = gather(like_y, buf, rows.y * lanes + lane, lanes)
                f = gather(like_y, buf, rows.f * lanes + lane, lanes)
                p = gather(like_p, buf, rows.p * lanes + lane, lanes)
                h = buf[rows.h * lanes + lane]
                y1, f1, err = step(method if fixed is None else fixed, y, f, h, p,
                                   buf[rows.rtol * lanes + lane],
                                   buf[rows.atol * lanes + lane])
                clear = lane_clear(buf[rows.t * lanes + lane], h, y, f, y1, f1,
                                   gather(like_data, buf, rows.data * lanes + lane, lanes))
                scatter(y1, buf, rows.y1 * lanes + lane, lanes)
                scatter(f1, buf, rows.f1 * lanes + lane, lanes)
                buf[rows.err * lanes + lane] = err
                buf[rows.clear * lanes + lane] = 1.0 if clear else 0.0
        return steps

    if lanes == 1:  # the step called, by the method asked for (the exact flow too)
        return loop(None)
    by_dopri5 = loop(METHOD_DOPRI5)
    # DOP853's twelve stages, inlined, took LLVM minutes to vectorise: its lanes call its
    # step (the same operations), one lane after another
    by_dop853 = loop(METHOD_DOP853, flier.step) if high_order else by_dopri5
    by_rk4 = loop(METHOD_RK4) if fixed_step else by_dopri5

    @njit(**INNER_OPTIONS)
    def trial(buf, method, like_y, like_p, like_data):
        if high_order and method == METHOD_DOP853:
            by_dop853(buf, method, like_y, like_p, like_data)
        elif fixed_step and method == METHOD_RK4:
            by_rk4(buf, method, like_y, like_p, like_data)
        else:
            by_dopri5(buf, method, like_y, like_p, like_data)

    return trial


@njit(**INLINE_OPTIONS)
def load(buf, lane, lanes, st, p, settings):
    """A flight's state ``st`` (its state, derivative, next step, time and system data) and
    its parameters and tolerances into lane ``lane`` of a buffer of ``lanes`` lanes."""
    rows = layout(st.y, p, st.data)
    advance(buf, lane, lanes, st)
    scatter(p, buf, rows.p * lanes + lane, lanes)
    buf[rows.rtol * lanes + lane] = settings.rtol
    buf[rows.atol * lanes + lane] = settings.atol


@njit(**INLINE_OPTIONS)
def advance(buf, lane, lanes, st):
    """A flight's next step into its lane: its state, derivative, step size, time and
    system data (the parameters and tolerances stay)."""
    rows = layout(st.y, st.y, st.data)  # (the rows before the parameters')
    scatter(st.y, buf, rows.y * lanes + lane, lanes)
    scatter(st.f, buf, rows.f * lanes + lane, lanes)
    buf[rows.h * lanes + lane] = st.h
    buf[rows.t * lanes + lane] = st.t
    scatter(st.data, buf, rows.data * lanes + lane, lanes)


@njit(**INLINE_OPTIONS)
def outcome(buf, lane, lanes, like_y, like_p, like_data):
    """The step's end state, derivative, error measure, and whether no event can fire in
    it, in lane ``lane``."""
    rows = layout(like_y, like_p, like_data)
    return (gather(like_y, buf, rows.y1 * lanes + lane, lanes),
            gather(like_y, buf, rows.f1 * lanes + lane, lanes),
            buf[rows.err * lanes + lane], buf[rows.clear * lanes + lane] != 0.0)
