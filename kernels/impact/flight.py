"""The flight loop: one free flight of a system from a state to its next terminal event.

``make_flight(system)`` specialises the loop to a ``System`` (kernels/impact/__init__.py) and
returns ``flight(t, y, p, data, settings, refine) -> Flight``. Per accepted step:

- events are located by the system's locator and polished by Newton on exact partial steps
  from the step's start (POLISH_ITERATIONS, atol-limited event times, H5); the system's
  ``on_event`` says whether the event ends the flight or is passed (the flight then goes on
  from the event, with updated system data and the same step size);
- the monitored angle's largest magnitude (the amplitude) is kept at step ends and, with
  ``refine``, at turning points inside a step or inside its part flown up to an event
  (polished like events);
- the monitored acceleration's largest magnitude is kept at step ends, and, with ``refine``,
  sampled inside every step on the interpolant (PEAK_SAMPLES), which picks the place; it is
  refined at the end by golden section around the largest sample, cut at the event, each
  point an exact partial step from its own step's start (the cubic interpolant is only
  third order in the derivative); where the flight's start (an impact) stays the largest
  value, the bracket is the first sample spacing after it. A peak between two step ends
  was once missed where the steps are long (2.8e-3 low at tol 1e-6 on a rotor design), and
  one just after the impact (5.7e-4 low at rtol 1e-6 on another).

Transient flights of an impact sequence run with ``refine`` off: they need only their end.

``make_timed_flight(rhs, scales)`` is the same steps and step-size control to a time known
beforehand (the variational equations through a flight already located), the last step
cut to land on it: no event search, nothing monitored.
"""

import math
from collections import namedtuple

from numba import njit

from kernels import INLINE_OPTIONS, INNER_OPTIONS
from kernels.extrema import peak_search
from kernels.impact.events import make_bisection, make_locator
from kernels.impact.outcomes import (FLIGHT_EVENT, FLIGHT_HORIZON, FLIGHT_MAX_STEPS,
                                     FLIGHT_NONFINITE, FLIGHT_UNDERFLOW, Counters)
from kernels.impact.runge_kutta import (METHOD_DOP853, METHOD_EXACT, OTHER_METHODS,
                                        accepted_step_size,
                                        ballistic_cap, initial_step, make_stepper,
                                        low_order, rejected_step_size)
from kernels.impact.tuples import hermite, hermite_slope

POLISH_ITERATIONS = 4
PEAK_SAMPLES = 3  # interior samples of |acceleration| per step, where the peak matters
#: DOP853: interior samples taken again on exact partial steps where the interpolant's come
#: within this fraction of the largest value so far (0.5 and 0.8 both mended the two misses
#: named in make_peak; every step on exact samples made the paper model's forced steady
#: states 1.6 times dearer at rtol 1e-12, 0.8 the least)
PEAK_EXACT_FRACTION = 0.8
TURNING_BISECTIONS = 55  # 2^-55 of a step: round-off
#: the longest exact step (System.exact_length) of a flight that refines nothing, where no
#: event can fire within it (System.clear_time): the reach over which the rigid pendulum's
#: closed-form step is tested against mpmath (elementary.jacobi_small)
EXACT_REACH = 1.0

#: what a flight returns: its outcome (outcomes.FLIGHT_*), the event that ended it (-1 if
#: none), the time, state, derivative and system data at its end, the amplitude and peak
#: acceleration of the monitored angle, and what it cost (outcomes.Counters)
Flight = namedtuple("Flight", ["outcome", "event", "t", "y", "f", "data", "amplitude",
                               "peak", "cost"])


@njit(**INLINE_OPTIONS)
def _no_length(y, p, length):
    return length


@njit(**INLINE_OPTIONS)
def _never_clear(y, values_now, data, p):
    return 0.0


def make_flight(system):
    """The flight loop of a system (see the module docstring): ``(flight, step)``."""
    rhs, monitor, on_event = system.rhs, system.monitor, system.on_event
    step = make_stepper(rhs, system.scales, system.exact, system.methods)
    locate = make_locator(system.event_values, system.event_rates, system.directions, step)
    polish = make_polish(system.event_values, system.event_rates, step)
    turning_angle = make_turning_angle(monitor, step)
    track_peak, final_peak = make_peak(monitor, step, METHOD_DOP853 in system.methods)
    start_step, next_step, events_at, coast_on = make_step_control(system)

    # one loop, the adaptive step and its events, amplitude, peak and coast: its state is
    # a dozen scalars carried from step to step, which numba keeps in registers
    @njit(**INNER_OPTIONS)
    def flight(t0, y0, p, data, settings, refine):
        method, rtol, atol = settings.method, settings.rtol, settings.atol
        slack = max(100.0 * atol, 1e-10)  # how far beyond a level a step may start (events.py)
        t, y, f = t0, y0, rhs(y0, p)
        angle, rate, accel = monitor(t, y, f)
        h = start_step(t, y, f, data, p, settings, rate)
        steps = rejected = events = 0
        amplitude, peak = abs(angle), abs(accel)
        # with refine, where |accel| is largest: the step, its end state, and a bracket
        # (from the step's start) around its largest sample, interior or at the end
        best, best_value = (y, f, y, f, 0.0, t, 0.0, 0.0), abs(accel)
        after_reject, err_prev = bool(False), 1.0
        # zero crossings of the angle, the last one's time and the step that held it (the
        # bound of that time's error), the coast's memo
        crossings, t_cross, h_cross, memo = 0, t0, 0.0, (math.nan, math.nan)
        # the events' values and rates at the step's start: the last step's end, or anew
        # where the flight moved otherwise (an event passed, a coast)
        start = events_at(t, y, f, data)
        while steps + rejected < settings.max_steps:
            if t - t0 > settings.horizon:
                return Flight(FLIGHT_HORIZON, -1, t, y, f, data, amplitude, peak,
                              Counters(steps, rejected, events))
            y1, f1, err = step(method, y, f, h, p, rtol, atol)
            if not err <= 1.0:  # NaN too: a step into a blow-up is rejected, not taken
                rejected += 1
                after_reject = bool(True)
                h, underflow = rejected_step_size(method, h, err, err_prev, t)
                if underflow:
                    return Flight(FLIGHT_UNDERFLOW, -1, t, y, f, data, amplitude, peak,
                                  Counters(steps, rejected, events))
                continue
            steps += 1
            e, s, end = locate((t, h, y, f, y1, f1), (data, p, method, slack), start)
            if e >= 0:
                s, ys, fs = polish(e, (t, h, y, f), s, p, data, settings)
                events += 1
                terminal, new_data = on_event(e, t + s, ys, fs, data, p)
                angle_e, rate_e, accel_e = monitor(t + s, ys, fs)
                amplitude, peak = max(amplitude, abs(angle_e)), max(peak, abs(accel_e))
                # a turn before the event, in the part of the step flown (a pendulum that
                # turns just before it passes the blade's edge level); the step's rest is
                # flown again from the event
                if refine and (monitor(t, y, f)[1] < 0.0) != (rate_e < 0.0):
                    amplitude = max(amplitude, abs(turning_angle(t, s, y, f, ys, fs, p,
                                                                 settings)))
                if terminal:
                    if refine:  # the largest |accel|, refined by golden section
                        best, best_value = track_peak(best, best_value, t, h, y, f, y1, f1,
                                                      s, -1.0, p, method)
                        peak = final_peak(best, peak, t + s, p, method, rtol)
                    return Flight(FLIGHT_EVENT, e, t + s, ys, fs, new_data, amplitude, peak,
                                  Counters(steps, rejected, events))
                # passed (the striker goes by the tool): on from the event, state as it is
                t, y, f, data, angle = t + s, ys, fs, new_data, angle_e
                start = events_at(t, y, f, data)
                continue
            angle1, rate1, accel1 = monitor(t + h, y1, f1)
            if not (math.isfinite(angle1) and math.isfinite(rate1)):  # RK4 has no error
                return Flight(FLIGHT_NONFINITE, -1, t, y, f, data, amplitude, peak,
                              Counters(steps, rejected, events))
            amplitude, peak = max(amplitude, abs(angle1)), max(peak, abs(accel1))
            if refine and (monitor(t, y, f)[1] < 0.0) != (rate1 < 0.0):
                amplitude = max(amplitude, abs(turning_angle(t, h, y, f, y1, f1, p,
                                                             settings)))
            if refine:
                best, best_value = track_peak(best, best_value, t, h, y, f, y1, f1, h,
                                              abs(accel1), p, method)
            skip, crossings, t_cross, h_cross, y1, f1, data, memo, coasted = coast_on(
                angle, angle1, crossings, t_cross, h_cross, t, h, y1, f1, data, p,
                t0 + settings.horizon, memo, method == METHOD_EXACT)
            steps += coasted
            t, y, f, angle = t + skip + h, y1, f1, angle1
            if skip != 0.0:
                angle = monitor(t, y, f)[0]
                start = events_at(t, y, f, data)
            else:
                start = end
            values_now, rates_now = start
            h, err_prev = next_step(y, values_now, data, p, settings, refine, h, err,
                                    after_reject, err_prev)
            after_reject = bool(False)
        return Flight(FLIGHT_MAX_STEPS, -1, t, y, f, data, amplitude, peak,
                      Counters(steps, rejected, events))

    return flight, step


def make_step_control(system):
    """The flight loop's step sizes and its moves other than a step: ``start_step`` (the
    first: the exact flow's length or the method's initial step, capped by the ballistic
    return time of the gap the flight leaves, H4), ``next_step`` (after an accepted one),
    ``events_at`` (the events' values and rates at a point) and ``coast_on`` (past the
    time no event can end, once the monitored angle has crossed zero twice, the system's
    ``coast``)."""
    values, rates, start_gap, coast = (system.event_values, system.event_rates,
                                       system.start_gap, system.coast)
    has_exact = system.exact is not None
    exact_length = system.exact_length if has_exact else _no_length
    has_clear = has_exact and system.clear_time is not None
    clear_time = system.clear_time if has_clear else _never_clear

    @njit(**INLINE_OPTIONS)
    def start_step(t, y, f, data, p, settings, rate):
        # exact steps (runge_kutta.METHOD_EXACT) are as long as the event search allows
        if has_exact and settings.method == METHOD_EXACT:
            h = exact_length(y, p, settings.dt)
        else:
            h = initial_step(settings.method, settings.dt, rate, settings.rtol)
        gap_rate, gap_acceleration = start_gap(t, y, f, data, p)
        return ballistic_cap(h, gap_rate, gap_acceleration)

    @njit(**INLINE_OPTIONS)
    def next_step(y, values_now, data, p, settings, refine, h, err, after_reject, err_prev):
        if has_exact and settings.method == METHOD_EXACT:
            h = exact_length(y, p, settings.dt)
            # a step no event can end needs no search: as long as the events stay clear,
            # within the exact flow's reach (EXACT_REACH); not where turning points and
            # peaks are refined, whose search is on the step's interpolant too
            if has_clear and not refine:
                h = max(h, min(clear_time(y, values_now, data, p),
                               exact_length(y, p, EXACT_REACH)))
            return h, err_prev
        return accepted_step_size(settings.method, h, settings.dt, err, after_reject,
                                  err_prev)

    @njit(**INLINE_OPTIONS)
    def events_at(t, y, f, data):
        """The events' values and rates at a point of the flight: a step's start (the
        locator returns them at the step's end, passed on as the next start)."""
        return values(t, y, data), rates(t, y, f, data)

    @njit(**INLINE_OPTIONS)
    def coast_on(angle, angle1, crossings, t_cross, h_cross, t, h, y1, f1, data, p,
                 horizon_end, memo, closed_form):
        """After a step from t to t + h in which the monitored angle went from ``angle``
        to ``angle1``: (time skipped, crossings, the last crossing's time and the step
        that held it, the state after the skip, data, memo, the exact steps taken)."""
        if (angle < 0.0) != (angle1 < 0.0):
            crossings += 1
            t_cross, h_cross = t + h * angle / (angle - angle1), h  # the chord's zero
        if crossings < 2:
            return 0.0, crossings, t_cross, h_cross, y1, f1, data, memo, 0
        skip, t_cross, y1, f1, data, memo, steps = coast(
            t_cross, crossings, h_cross, t + h, y1, f1, data, p, horizon_end - (t + h), memo,
            closed_form)
        return skip, crossings, t_cross, h_cross, y1, f1, data, memo, steps

    return start_step, next_step, events_at, coast_on


def make_polish(values, rates, step):
    """Newton's polish of a located event on exact partial steps."""

    @njit(**INNER_OPTIONS)
    def polish(e, st, s, p, data, settings):
        """Newton on exact partial steps from the step's start: the event time and state
        (the event's rate from the system, or, where it has none, a forward difference of
        exact partial steps); st = (t, h, y, f) of the step."""
        t, h, y, f = st
        method, rtol, atol = settings.method, settings.rtol, settings.atol
        for _ in range(POLISH_ITERATIONS):
            ys, fs, _ = step(method, y, f, s, p, rtol, atol)
            value = values(t + s, ys, data)[e]
            rate = rates(t + s, ys, fs, data)[e]
            if not math.isfinite(rate):
                ds = 1e-7 * h
                yd, fd, _ = step(method, y, f, s + ds, p, rtol, atol)
                rate = (values(t + s + ds, yd, data)[e] - value) / ds
            if not (rate != 0.0 and math.isfinite(rate)):
                break
            s_new = s - value / rate
            if not (0.0 < s_new <= h) or abs(s_new - s) <= 1e-16 * max(1.0, abs(t)):
                s = s_new if 0.0 < s_new <= h else s
                break
            s = s_new
        ys, fs, _ = step(method, y, f, s, p, rtol, atol)
        return s, ys, fs

    return polish


def make_turning_angle(monitor, step):
    """The monitored angle at its turning point inside a step."""

    @njit(**INNER_OPTIONS)
    def angle_rate_on_interpolant(s, st):
        t, h, y, f, y1, f1 = st
        return monitor(t + s, hermite(s, h, y, f, y1, f1), hermite_slope(s, h, y, f, y1, f1))[1]

    turn_of_angle = make_bisection(angle_rate_on_interpolant)

    @njit(**INNER_OPTIONS)
    def turning_angle(t, h, y, f, y1, f1, p, settings):
        """The monitored angle where its rate vanishes inside a step: bisection on the
        interpolant's rate, then Newton on exact partial steps."""
        s = turn_of_angle((t, h, y, f, y1, f1), 0.0, h, monitor(t, y, f)[1] > 0.0,
                          TURNING_BISECTIONS)
        for _ in range(POLISH_ITERATIONS):
            ys, fs, _ = step(settings.method, y, f, s, p, 1.0, 1.0)
            angle, rate, accel = monitor(t + s, ys, fs)
            if accel == 0.0:
                return angle
            s_new = min(h, max(0.0, s - rate / accel))
            if abs(s_new - s) <= 1e-15 * h:  # converged: the angle at s is the answer
                return angle
            s = s_new
        ys, fs, _ = step(settings.method, y, f, s, p, 1.0, 1.0)
        return monitor(t + s, ys, fs)[0]

    return turning_angle


def make_peak(monitor, step, high_order=True):
    """The largest |monitored acceleration| of a flight, with ``refine``: ``track_peak``
    keeps, step by step, the step around the largest value and a bracket in it;
    ``final_peak`` refines it by golden section at the flight's end. ``high_order``: the
    stepper has DOP853, whose samples are taken again on exact partial steps (without it
    that code is not compiled)."""

    @njit(**INNER_OPTIONS)
    def acceleration_at(s, data):
        """|monitored acceleration| at s from the start of the step ending at the largest
        value (the next step's start beyond it): exact partial steps."""
        ya, fa, yb, fb, h, t, p, method = data
        if s <= 0.0:
            return abs(monitor(t, ya, fa)[2])
        if s <= h:
            ys, fs, _ = step(method, ya, fa, s, p, 1.0, 1.0)
        else:
            ys, fs, _ = step(method, yb, fb, s - h, p, 1.0, 1.0)
        return abs(monitor(t + s, ys, fs)[2])

    golden_acceleration, _ = peak_search(acceleration_at)

    @njit(**INNER_OPTIONS)
    def step_peak(t, h, y, f, y1, f1, upto, p, method, exact):
        """The largest |monitored acceleration| at PEAK_SAMPLES points inside (0, upto) of
        a step, and the bracket around it: (value, lo, hi). The samples only pick where to
        refine: on the step's interpolant (third order), or, with ``exact``, on exact
        partial steps."""
        best, where = -1.0, 0.0
        spacing = upto / (PEAK_SAMPLES + 1)
        for j in range(1, PEAK_SAMPLES + 1):
            s = spacing * j
            a = -1.0
            if high_order:  # a test of its own, so that without it numba prunes the branch
                if exact:
                    ys, fs, _ = step(method, y, f, s, p, 1.0, 1.0)
                    a = abs(monitor(t + s, ys, fs)[2])
            if a < 0.0:
                a = abs(monitor(t + s, hermite(s, h, y, f, y1, f1),
                                hermite_slope(s, h, y, f, y1, f1))[2])
            if a > best:
                best, where = a, s
        return best, where - spacing, where + spacing

    @njit(**INNER_OPTIONS)
    def track_peak(best, best_value, t, h, y, f, y1, f1, upto, at_end, p, method):
        """The step around the largest |monitored acceleration| so far, with a bracket in
        it (from the step's start), after the part (0, upto] of a step: its interior
        samples, its end value ``at_end`` (-1 if it has none), or where the flight's start
        (an impact) is still the largest, the first sample spacing after it."""
        inside, lo, hi = step_peak(t, h, y, f, y1, f1, upto, p, method, bool(False))
        # DOP853's steps are long: where the interpolant's samples come near the largest
        # value so far, they are taken again on exact partial steps (the interpolant's pick
        # missed the peak's bracket: 7.5e-5 low at rtol 1e-11 on a rotor design on the
        # blade, 6.9e-4 at rtol 1e-6 on its stop)
        if high_order:
            if method == METHOD_DOP853 and inside >= PEAK_EXACT_FRACTION * best_value:
                inside, lo, hi = step_peak(t, h, y, f, y1, f1, upto, p, method, bool(True))
        y_best, f_best, y1_best, f1_best, h_best, t_best, lo_best, hi_best = best
        if h_best == 0.0:  # still the start (an impact): a maximum just after it
            best = (y, f, y1, f1, h, t, 0.0, upto / (PEAK_SAMPLES + 1))
        if inside > best_value:
            best, best_value = (y, f, y1, f1, h, t, lo, hi), inside
        if at_end > best_value:  # at the step's end: refine across it
            spacing = h / (PEAK_SAMPLES + 1)
            best, best_value = (y, f, y1, f1, h, t, h - spacing, h + spacing), at_end
        return best, best_value

    @njit(**INNER_OPTIONS)
    def final_peak(best, peak, t_end, p, method, rtol):
        """The peak, refined by golden section in the bracket kept, cut at the flight's
        end t_end."""
        ya, fa, yb, fb, h_best, t_best, lo, hi = best
        hi = min(hi, t_end - t_best, 2.0 * h_best)
        lo = max(lo, 0.0)
        if hi > lo:
            stop = max(1e-7 * (hi - lo), 0.3 * math.sqrt(rtol))
            peak = max(peak, golden_acceleration((ya, fa, yb, fb, h_best, t_best, p, method),
                                                 lo, hi, stop))
        return peak

    return track_peak, final_peak


def make_timed_flight(rhs, scales, methods=OTHER_METHODS):
    """``timed_flight(t0, y0, t1, p, settings) -> (reached, y)``: the state at a known time
    t1 from y0 at t0, by the flight loop's steps and step-size control, the last step cut
    to land on t1. For an integration whose end is known (the variational equations
    through a flight whose end was located already): no event search, nothing monitored.
    ``reached`` is False where a step underflowed, the state stopped being finite, or the
    step budget ran out. DOP853 is not compiled in: asked for, these flights take DOPRI5
    at its rtol (the tangent's 20-component step made the stability example's first run
    1.17 times the code's before DOP853); RK4 only where ``methods`` has it."""
    step = make_stepper(rhs, scales, methods=tuple(m for m in methods if m != METHOD_DOP853))

    @njit(**INNER_OPTIONS)
    def timed_flight(t0, y0, t1, p, settings):
        method, rtol, atol = low_order(settings.method), settings.rtol, settings.atol
        t, y = t0, y0
        if not t1 > t0:
            return t1 == t0, y0
        f = rhs(y, p)
        h = initial_step(method, settings.dt, f[0], rtol)
        after_reject = bool(False)
        err_prev = 1.0
        steps = 0
        while steps < settings.max_steps:
            last = h >= t1 - t
            if last:
                h = t1 - t
            y1, f1, err = step(method, y, f, h, p, rtol, atol)
            steps += 1
            if not err <= 1.0:  # NaN too
                after_reject = bool(True)
                h, underflow = rejected_step_size(method, h, err, err_prev, t)
                if underflow:
                    return False, y
                continue
            finite = True
            for v in y1:
                finite = finite and math.isfinite(v)
            if not finite:  # RK4 has no error estimate to reject it
                return False, y
            if last:
                return True, y1
            t, y, f = t + h, y1, f1
            h, err_prev = accepted_step_size(method, h, settings.dt, err, after_reject,
                                             err_prev)
            after_reject = bool(False)
        return False, y

    return timed_flight
