"""The integration core (kernels/impact) on systems with known solutions, without any pendulum:
x'' = -c x - g between two levels (an oscillator for c = 1, g = 0; free fall for c = 0,
g = 1), and y' = y^2, which blows up at t = 1/y0.

Orders of RK4 and DOPRI5 measured by regression, event times against the analytic crossing,
a grazing contact found with a window of 1/100 of a step, a return to the level inside the
first sample interval of a restart at zero speed, no event at the restart point, the
ballistic first-step cap (H4), Newton polish limited by atol (H5), the direction filter, the
bracketing root finder's status, the step budget and the step-size underflow."""

import math

import numpy as np
import pytest
from numba import njit

from kernels import INLINE_OPTIONS
from kernels.impact import System
from kernels.impact.events import ILLINOIS_ITERATIONS, make_illinois
from kernels.impact.flight import make_flight, make_timed_flight
from kernels.impact.accelerators import (aitken, aitken_jump, fixed_point_jump,
                                         impacts_past_jump, secant_step)
from kernels.impact.verdicts import classify_period, not_periodic
from kernels.impact.outcomes import SEQUENCE_MAX_STEPS, SEQUENCE_NOT_PERIODIC
from kernels.impact.outcomes import (FLIGHT_EVENT, FLIGHT_HORIZON, FLIGHT_MAX_STEPS,
                                     FLIGHT_NONFINITE, FLIGHT_UNDERFLOW)
from kernels.cache import module_level
from kernels.impact.runge_kutta import make_stepper
from kernels.impact.tuples import relative_scales
from tests.probes import cached, fixed_steps_of, settings

OSCILLATOR, FREE_FALL = (1.0, 0.0), (0.0, 1.0)  # p = (c, g)
UPPER, LOWER = 0, 1  # the events: x rising through data[0], x falling through data[1]


@njit(**INLINE_OPTIONS)
def line_rhs(y, p):
    return y[1], -p[0] * y[0] - p[1]


@njit(**INLINE_OPTIONS)
def line_values(t, y, data):
    return y[0] - data[0], y[0] - data[1]


@njit(**INLINE_OPTIONS)
def line_rates(t, y, dy, data):
    return dy[0], dy[0]


@njit(**INLINE_OPTIONS)
def terminal(e, t, y, f, data, p):
    return True, data


@njit(**INLINE_OPTIONS)
def line_start(t, y, f, data, p):
    return f[0], f[1]


@njit(**INLINE_OPTIONS)
def line_monitor(t, y, f):
    return y[0], f[0], f[1]


LINE = System(line_rhs, relative_scales, line_values, line_rates, (1, -1), terminal,
              line_start, line_monitor)
_line_flight, _ = make_flight(LINE)
fixed_steps = cached(fixed_steps_of(line_rhs, relative_scales), "fixed_steps_line")


@njit(cache=True)
def line_flight(t, y, p, data, s, refine):
    return _line_flight(t, y, p, data, s, refine)


@njit(**INLINE_OPTIONS)
def blowup_rhs(y, p):
    return (y[0] * y[0],)


@njit(**INLINE_OPTIONS)
def blowup_values(t, y, data):
    return (y[0] + 1.0,)  # never crosses: the flight runs until its steps underflow


@njit(**INLINE_OPTIONS)
def blowup_rates(t, y, dy, data):
    return (dy[0],)


@njit(**INLINE_OPTIONS)
def blowup_start(t, y, f, data, p):
    return 0.0, 0.0


@njit(**INLINE_OPTIONS)
def blowup_monitor(t, y, f):
    return y[0], f[0], 0.0


_blowup_flight, _ = make_flight(System(blowup_rhs, relative_scales, blowup_values,
                                       blowup_rates, (1,), terminal, blowup_start,
                                       blowup_monitor))


@njit(cache=True)
def blowup_flight(t, y, s):
    return _blowup_flight(t, y, 0.0, 0.0, s, False)


@pytest.mark.parametrize("method, order, t_end, steps", [
    ("rk4", 4, 2.0, [10, 20, 40, 80]), ("dopri5", 5, 2.0, [10, 20, 40, 80]),
    ("dop853", 8, 8.0, [8, 12, 16, 24])])  # longer steps: DOP853's error reaches round-off
def test_order_of_each_method_measured_by_regression(method, order, t_end, steps):
    """Global error of the oscillator at t_end from (1, 0) over fixed step sizes: the
    fitted slope of log error against log h is the method's order."""
    code = settings(method).method
    steps = np.array(steps)
    errors = []
    for n in steps:
        x, v = fixed_steps(code, (1.0, 0.0), OSCILLATOR, t_end / n, n)
        errors.append(math.hypot(x - math.cos(t_end), v + math.sin(t_end)))
    slope = -np.polyfit(np.log(steps), np.log(errors), 1)[0]
    assert order - 0.25 < slope < order + 0.3, (slope, errors)


def test_dop853_tableau_is_scipys():
    """The DOP853 coefficients in the kernel are scipy's (Hairer's dop853.f), entry by
    entry: every nonzero one, at the stages each row names, and nothing else."""
    from scipy.integrate._ivp import dop853_coefficients as ref

    from kernels.impact import runge_kutta as rk

    def nonzero(row, n):
        return [(j, float(row[j])) for j in range(n) if row[j] != 0.0]

    # the stages each row weighs, as named above it in the kernel
    weighs = {}
    for line in open(rk.__file__):
        if line.startswith("# D_") and " weighs " in line:
            name, ks = line[2:].split(" weighs ")
            weighs[name] = [int(k.strip()[1:]) - 1 for k in ks.split(",")]
    for stage in range(1, ref.N_STAGES):
        name = f"D_A{stage + 1}"
        assert list(zip(weighs[name], getattr(rk, name))) == nonzero(ref.A[stage], stage)
    for name, row in (("D_B", ref.B), ("D_E3", ref.E3), ("D_E5", ref.E5)):
        assert list(zip(weighs[name], getattr(rk, name))) == nonzero(row, len(row))


@njit(cache=True)
def _one_step(method, h):
    y = (1.0, 0.0)
    return _oscillator_step(method, y, line_rhs(y, OSCILLATOR), h, OSCILLATOR, 1e-30, 1.0)


_oscillator_step = make_stepper(line_rhs, relative_scales)


@pytest.mark.parametrize("method, order", [("dopri5", 5), ("dop853", 8)])
def test_embedded_error_measure_has_the_order_of_the_step_it_controls(method, order):
    """One step of the oscillator from (1, 0) at atol 1: the error measure falls as
    h^order (DOP853's combined 5th/3rd-order measure as h^8, DOPRI5's as h^5) and stays
    above the step's true local error, so the controller never accepts more than it
    asks."""
    code = settings(method).method
    hs = np.array([0.8, 0.4, 0.2, 0.1])
    measured, true = [], []
    for h in hs:
        (x, v), _, err = _one_step(code, h)
        measured.append(err)
        true.append(math.hypot(x - math.cos(h), v + math.sin(h)) / math.sqrt(2.0))
    slope = np.polyfit(np.log(hs), np.log(measured), 1)[0]
    assert order - 0.2 < slope < order + 0.2, (slope, measured)
    assert np.all(np.array(measured) > np.array(true)), (measured, true)


@pytest.mark.parametrize("method", ["dopri5", "dop853"])
def test_step_and_its_control_inlined_over_lanes_give_the_called_bits(method):
    """make_stepper(inline=True) and make_step_size_rule(inline=True), inlined into one
    loop over 8 lanes of a flat lane-minor buffer (as benchmarks/bench_step.py's lanes),
    give each lane the bits of the step and control called one design at a time: the
    rigid pendulum from random states, step sizes, parameters and errors before, accepted
    and rejected steps among them."""
    from kernels.impact.runge_kutta import (libm_power, make_step_size_rule, next_step)
    from kernels.pendulum.models import rigid_rhs

    code = settings(method).method
    called = make_stepper(rigid_rhs, relative_scales)
    inlined = make_stepper(rigid_rhs, relative_scales, inline=True)
    rule = make_step_size_rule(libm_power, inline=True)

    def make_loop(step, control, name):
        @njit(error_model="numpy")
        def loop(buf, code):
            for lane in range(8):
                y = (buf[lane], buf[8 + lane])
                p = (1.0, buf[16 + lane])
                y1, f1, err = step(code, y, rigid_rhs(y, p), buf[24 + lane], p, 1e-6, 1e-9)
                buf[40 + lane], buf[48 + lane], buf[56 + lane] = y1[0], y1[1], f1[1]
                buf[64 + lane] = control(code, buf[24 + lane], err, buf[72 + lane] != 0.0,
                                         buf[32 + lane])
        return module_level(loop, name, globals(), dict(cache=True))

    lanes = make_loop(inlined, rule, "lanes_inlined")
    one_by_one = make_loop(called, next_step, "lanes_called")

    rng = np.random.default_rng(5)
    shrank = grew = 0
    for _ in range(20):
        buf = np.zeros(80)
        buf[:8], buf[8:16] = rng.uniform(-4, 4, 8), rng.uniform(-3, 3, 8)
        buf[16:24], buf[24:32] = rng.uniform(0.5, 3, 8), 10 ** rng.uniform(-3, 0, 8)
        buf[32:40], buf[72:80] = 10 ** rng.uniform(-6, 1, 8), rng.integers(0, 2, 8)
        a, b = buf.copy(), buf.copy()
        lanes(a, code), one_by_one(b, code)
        assert np.array_equal(a, b)
        shrank += np.sum(a[64:72] < a[24:32])
        grew += np.sum(a[64:72] > a[24:32])
    assert shrank >= 5 and grew >= 5, (shrank, grew)


@pytest.mark.slow
@pytest.mark.parametrize("level", [0.9, 0.3, -0.5, -0.99])
def test_event_time_matches_the_analytic_crossing(level):
    """The oscillator from (1, 0) falls through the level at t = arccos(level)."""
    fl = line_flight(0.0, (1.0, 0.0), OSCILLATOR, (2.0, level), settings(), False)
    assert fl.outcome == FLIGHT_EVENT and fl.event == LOWER
    assert fl.t == pytest.approx(math.acos(level), abs=1e-11)
    assert fl.y[0] == pytest.approx(level, abs=1e-12)


def test_direction_filter_passes_a_crossing_the_wrong_way():
    """From x = 0.5 falling, the level 0.2 is crossed downwards first (not an event of the
    rising level) and then upwards at t = pi/2 + arcsin(0.5) + arcsin(0.2) (relative to the
    start's phase)."""
    # x = cos(t + t0) with cos t0 = 0.5, falling: x = 0.2 rising again at 2 pi - arccos 0.2
    t0 = math.acos(0.5)
    fl = line_flight(0.0, (0.5, -math.sin(t0)), OSCILLATOR, (0.2, -2.0), settings(), False)
    assert fl.outcome == FLIGHT_EVENT and fl.event == UPPER
    assert fl.t == pytest.approx(2 * math.pi - math.acos(0.2) - t0, abs=1e-11)


@pytest.mark.parametrize("phase", np.arange(8) / 8)
def test_grazing_contact_is_found_with_a_window_of_a_hundredth_of_a_step(phase):
    """RK4 at the fixed step dt = 0.02: the oscillator's apex x = 1 passes a level 1 - eps
    for a window 2 delta = dt/100 (cos delta = 1 - eps). No step end and no sign sample
    falls inside it; the extremum check on the interpolant finds it from every phase of the
    step grid (its interpolation error, dt^4/384 = 4e-10, is below eps = 5e-9)."""
    dt = 0.02
    delta = dt / 200
    level = math.cos(delta)
    t0 = phase * dt  # the exact state at t0 on x = sin t
    fl = line_flight(t0, (math.sin(t0), math.cos(t0)), OSCILLATOR, (level, -2.0),
                     settings("rk4", dt=dt), False)
    assert fl.outcome == FLIGHT_EVENT and fl.event == UPPER
    assert abs(fl.t - (0.5 * math.pi - delta)) < 0.5 * delta  # on the window's near side


@njit(**INLINE_OPTIONS)
def cubic_rhs(y, p):
    return y[1], p[0] + p[1] * y[2], 1.0  # x'' = a + b t, with y[2] = t


@njit(**INLINE_OPTIONS)
def cubic_values(t, y, data):
    return (y[0],)


@njit(**INLINE_OPTIONS)
def cubic_rates(t, y, dy, data):
    return (dy[0],)


_cubic_flights = {direction: make_flight(System(
    cubic_rhs, relative_scales, cubic_values, cubic_rates, (direction,), terminal,
    line_start, line_monitor))[0] for direction in (1, -1)}  # x is the line's coordinate
_rising_flight, _falling_flight = _cubic_flights[1], _cubic_flights[-1]


@njit(cache=True)
def cubic_flight(rising, p, s):
    if rising:
        return _rising_flight(0.0, (0.0, 0.0, 0.0), p, 0.0, s, False)
    return _falling_flight(0.0, (0.0, 0.0, 0.0), p, 0.0, s, False)


@pytest.mark.parametrize("rising", [True, False])
def test_a_return_to_the_level_inside_the_first_sample_interval_is_found(rising):
    """x = a t^2/2 + b t^3/6 from rest on the level x = 0 (a restart at zero normal speed:
    no ballistic cap): it leaves to the near side and is back at t = -3a/b = 0.03, inside
    the first sample interval of an RK4 step of 0.5 (0.1), where no sample sees it below
    the level. RK4 and the cubic interpolant are exact on a cubic, so the crossing is
    found to round-off (the start's sample alone stepped over it, and the flight went on
    inside the tool)."""
    sign = 1.0 if rising else -1.0
    fl = cubic_flight(rising, (-0.01 * sign, sign), settings("rk4", dt=0.5, horizon=2.0))
    assert fl.outcome == FLIGHT_EVENT and fl.cost.events == 1
    assert fl.t == pytest.approx(0.03, abs=1e-14)


@pytest.mark.parametrize("rising", [True, False])
@pytest.mark.parametrize("cubic", [0.0, 1.0])
def test_a_start_pressed_past_the_level_is_no_return_to_it(rising, cubic):
    """From rest on the level, accelerated to its far side (pressed into the tool), with
    and without a cubic term: the motion never was on the near side, so there is no
    crossing (the check for a return does not invent one)."""
    sign = 1.0 if rising else -1.0
    fl = cubic_flight(rising, (0.01 * sign, cubic * sign), settings("rk4", dt=0.5,
                                                                     horizon=2.0))
    assert fl.outcome == FLIGHT_HORIZON and fl.cost.events == 0


def test_no_event_at_the_restart_point():
    """Free fall from exactly on the lower level, moving up: no event at the start; the
    fall back through the level at t = 2 v/g is the event. Moving down from the level:
    no event at the start either (the crossing needs the far side before it)."""
    fl = line_flight(0.0, (0.0, 1.0), FREE_FALL, (5.0, 0.0), settings(), False)
    assert fl.outcome == FLIGHT_EVENT and fl.event == LOWER
    assert fl.t == pytest.approx(2.0, rel=1e-12)
    fl = line_flight(0.0, (0.0, -1.0), FREE_FALL, (5.0, 0.0), settings(horizon=3.0), False)
    assert fl.outcome == FLIGHT_HORIZON and fl.cost.events == 0


@pytest.mark.parametrize("speed", [1e-2, 1e-4, 1e-6])
def test_H4_a_bounce_shorter_than_a_step_is_seen(speed):
    """Leaving the level at a small speed, pulled back: the first step is capped by the
    ballistic return time 2 v/g, so the bounce is found however short it is."""
    fl = line_flight(0.0, (0.0, speed), FREE_FALL, (5.0, 0.0), settings(), False)
    assert fl.outcome == FLIGHT_EVENT and fl.event == LOWER
    assert fl.t == pytest.approx(2.0 * speed, rel=1e-9)
    assert fl.y[1] == pytest.approx(-speed, rel=1e-9)


def test_H5_event_times_are_limited_by_atol_unless_it_is_on_the_variables_scale():
    """At rtol = 1e-12 the located time of x = 0.3 follows atol: 1e-6 (loose against x of
    size 1) limits it; 1e-14 gives round-off, the Newton polish on exact partial steps
    (the interpolant alone is O(h^4))."""
    exact = math.acos(0.3)
    errors = {}
    for atol in (1e-6, 1e-14):
        fl = line_flight(0.0, (1.0, 0.0), OSCILLATOR, (2.0, 0.3), settings(atol=atol), False)
        errors[atol] = abs(fl.t - exact)
    assert errors[1e-14] < 1e-13
    assert errors[1e-6] > 100 * errors[1e-14]


def test_the_step_budget_ends_a_flight():
    fl = line_flight(0.0, (1.0, 0.0), OSCILLATOR, (2.0, -2.0), settings(max_steps=7), False)
    assert fl.outcome == FLIGHT_MAX_STEPS and fl.cost.steps + fl.cost.rejected == 7


@pytest.mark.slow
def test_the_step_size_underflows_at_a_blowup():
    """y' = y^2 from y = 1 blows up at t = 1: DOPRI5's steps shrink until they fall below
    round-off of t, and the flight says so there instead of looping (a NaN error estimate
    is a rejection: it was once taken as a step, and the flight ran on NaN for its whole
    budget)."""
    fl = blowup_flight(0.0, (1.0,), settings(rtol=1e-8, atol=1e-10))
    assert fl.outcome == FLIGHT_UNDERFLOW
    assert 1.0 - fl.t < 1e-9 and fl.cost.rejected > 0
    # RK4 has no error estimate: it steps into the blow-up, and the flight ends there
    fl = blowup_flight(0.0, (1.0,), settings("rk4", dt=0.01))
    assert fl.outcome == FLIGHT_NONFINITE and 0.9 < fl.t < 1.1 and np.isfinite(fl.y[0])


_line_timed = make_timed_flight(line_rhs, relative_scales)
_blowup_timed = make_timed_flight(blowup_rhs, relative_scales)


@njit(cache=True)
def line_timed(t0, y0, t1, p, s):
    return _line_timed(t0, y0, t1, p, s)


@njit(cache=True)
def blowup_timed(t1, s):
    return _blowup_timed(0.0, (1.0,), t1, 0.0, s)


def test_a_timed_flight_lands_on_its_end_time_and_matches_the_oscillator():
    """The timed flight (the variational equations' integration to a flight's located end)
    at random end times: the oscillator from (cos t0, -sin t0) at t0 to t1 against (cos t1,
    -sin t1), to its tolerance with DOPRI5 and to RK4's global error at dt = 1e-3 (h^4/120
    per unit time, below the round-off of span/dt steps). The end time is the last step's end, not an overshoot interpolated
    back: at rtol 1e-13 the error is round-off's (a step past t1 would show as a phase
    error of that step's interpolation)."""
    rng = np.random.default_rng(7)
    for t0, span in zip(rng.uniform(-3.0, 3.0, 40), rng.uniform(1e-9, 20.0, 40)):
        t1 = t0 + span
        start = (math.cos(t0), -math.sin(t0))
        for s, tol in ((settings(rtol=1e-13, atol=1e-15), 5e-14 * max(1.0, span)),
                       (settings("rk4", dt=1e-3), 4e-16 * span / 1e-3 + 1e-14)):
            reached, y = line_timed(t0, start, t1, OSCILLATOR, s)
            assert reached
            assert abs(y[0] - math.cos(t1)) <= tol and abs(y[1] + math.sin(t1)) <= tol, (
                t0, span, y)


def test_a_timed_flight_of_no_length_is_the_identity_and_a_backward_one_fails():
    start = (0.3, -0.7)
    assert line_timed(1.5, start, 1.5, OSCILLATOR, settings()) == (True, start)
    reached, _ = line_timed(1.5, start, 1.4, OSCILLATOR, settings())
    assert not reached


def test_a_timed_flight_into_a_blowup_or_past_its_budget_fails():
    """y' = y^2 from y = 1 blows up at t = 1: an end time beyond it is not reached (DOPRI5's
    steps underflow; RK4 steps into non-finite values); one before it is, at y = 1/(1-t).
    A budget of 5 steps does not reach t = 0.9."""
    assert not blowup_timed(1.5, settings(rtol=1e-8, atol=1e-10))[0]
    assert not blowup_timed(1.5, settings("rk4", dt=0.01))[0]
    reached, y = blowup_timed(0.9, settings(rtol=1e-12, atol=1e-14))
    assert reached and y[0] == pytest.approx(10.0, rel=1e-10)
    assert not blowup_timed(0.9, settings(max_steps=5))[0]


@njit(**INLINE_OPTIONS)
def _linear(x, data):
    return x - data


@njit(**INLINE_OPTIONS)
def _step(x, data):
    return 1.0 if x > data else -1.0


_root_linear = make_illinois(_linear)
_root_step = make_illinois(_step)


@njit(cache=True)
def roots(a, tol):
    return _root_linear(a, 0.0, 1.0, -a, 1.0 - a, tol), _root_step(a, 0.0, 1.0, -1.0, 1.0,
                                                                    tol)


def test_the_bracketing_root_finder_returns_its_status():
    (x, ok), (x_step, ok_step) = roots(0.3, 1e-12)
    assert ok and x == pytest.approx(0.3, abs=1e-15)
    assert ok_step and abs(x_step - 0.3) < 1e-12  # a jump is bracketed like a root
    (x, ok), (x_step, ok_step) = roots(0.3, 0.0)  # a bracket of zero width is never reached
    assert ok  # f(x) = 0 exactly is reached on the linear function
    assert not ok_step and abs(x_step - 0.3) < 1e-12 and ILLINOIS_ITERATIONS >= 60


def test_period_classification_and_aitken():
    history = np.array([[0.0, 1.0], [0.5, 2.0], [0.2, 3.0], [0.5, 2.0], [0.2, 3.0]])
    assert classify_period(history, 5, 1e-12, 8) == 2
    assert classify_period(history, 4, 1e-12, 8) == 0
    # a geometric sequence x_j = 1 + 0.5^j: Aitken gives its limit from three terms
    assert aitken(2.0, 1.5, 1.25) == pytest.approx(1.0, rel=1e-15)
    assert aitken(1.0, 2.0, 4.0) == 4.0  # diverging: no extrapolation


def test_aitken_jump_finds_the_fixed_point_of_a_diagonal_affine_map_from_any_three_rows():
    """x -> a * (x - x*) + x* on each coordinate (|a| < 0.95): three successive sections at
    rows last - 2 .. last give x* to round-off, whichever rows they are; a coordinate that
    does not contract is left at its last value."""
    rng = np.random.default_rng(11)
    for _ in range(50):
        fixed, slope = rng.uniform(-3, 3, 2), rng.uniform(-0.9, 0.9, 2)
        history = np.empty((9, 2))
        history[0] = rng.uniform(-3, 3, 2)
        for j in range(1, 9):
            history[j] = fixed + slope * (history[j - 1] - fixed)
        last = int(rng.integers(2, 9))
        np.testing.assert_allclose(aitken_jump(history, last), fixed, rtol=1e-9, atol=1e-9)
    history = np.array([[1.0, 0.0], [2.0, 0.5], [4.0, 0.75]])  # the first doubles
    x = aitken_jump(history, 2)
    assert x[0] == 4.0 and x[1] == pytest.approx(1.0, rel=1e-15)


def test_a_budget_without_a_cycle_is_not_periodic_only_where_the_map_stopped_contracting():
    """not_periodic: a quasi-periodic sequence (a rotation by an irrational angle) keeps its
    step size: not periodic; a slowly contracting one (steps shrinking by 0.9) is still
    converging: max_steps; fewer than 20 sections never say not periodic."""
    angle = 2 * np.pi * (np.sqrt(5) - 1) / 2
    rotation = np.array([[np.cos(angle * j), np.sin(angle * j)] for j in range(60)])
    contracting = np.array([[0.9 ** j, 0.0] for j in range(60)])
    assert not_periodic(rotation, 60) == SEQUENCE_NOT_PERIODIC
    assert not_periodic(contracting, 60) == SEQUENCE_MAX_STEPS
    assert not_periodic(rotation, 19) == SEQUENCE_MAX_STEPS


def test_the_transient_jump_lands_on_the_fixed_point_of_an_affine_map():
    """fixed_point_jump on random 2-D affine maps x -> M x + b (the fixed point by numpy's
    solve, independently): with eigenvalues inside 0.95, real or a complex pair, or one of
    them zero (d0 and d1 parallel), four iterates land on the fixed point to round-off
    (1e-9 of the distance), unless the fixed point lies over 20 last differences away (the
    modes cancel in the last difference: no jump); with an eigenvalue outside 0.95, no jump
    (or one within 20 last differences)."""
    rng = np.random.default_rng(77)
    landed = refused = 0
    for trial in range(300):
        kind = trial % 4
        if kind == 0:  # real eigenvalues
            mu = np.diag(rng.uniform(-0.9, 0.9, 2))
        elif kind == 1:  # a complex pair of modulus < 0.9
            r, a = rng.uniform(0.1, 0.9), rng.uniform(0.2, 3.0)
            mu = r * np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
        elif kind == 2:  # one mode left
            mu = np.diag([rng.uniform(-0.9, 0.9), 0.0])
        else:  # one eigenvalue outside 0.95
            mu = np.diag([rng.uniform(0.96, 1.5) * rng.choice([-1, 1]),
                          rng.uniform(-0.9, 0.9)])
        basis = rng.normal(size=(2, 2))
        m = basis @ mu @ np.linalg.inv(basis)
        b = rng.normal(size=2)
        fixed = np.linalg.solve(np.eye(2) - m, b)
        history = np.empty((4, 2))
        history[0] = fixed + rng.normal(size=2)
        for j in range(1, 4):
            history[j] = m @ history[j - 1] + b
        jump, x, jac = fixed_point_jump(history, 4)
        away = np.max(np.abs(history[0] - fixed))
        if kind == 3:
            assert not jump or np.max(np.abs(np.array(x) - history[3])) <= 20 * np.max(
                np.abs(history[3] - history[2]))
            refused += not jump
            continue
        if not jump:  # only where the fixed point is over 20 last differences away
            assert np.hypot(*(history[3] - fixed)) > 20 * np.hypot(*(history[3] - history[2]))
            continue
        assert np.max(np.abs(np.array(x) - fixed)) <= 1e-9 * away, trial
        if kind != 2:  # the map's linear part, for Broyden's steps (secant_step)
            assert np.allclose(np.reshape(jac, (2, 2)), m - np.eye(2), rtol=0, atol=1e-7)
        landed += 1
    assert landed >= 200 and refused >= 60


def _random_contraction(rng, kind):
    """A 2 x 2 matrix with real (kind 0) or complex (kind 1) eigenvalues of modulus < 0.9."""
    if kind == 0:
        mu = np.diag(rng.uniform(-0.9, 0.9, 2))
    else:
        r, a = rng.uniform(0.1, 0.9), rng.uniform(0.2, 3.0)
        mu = r * np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    basis = rng.normal(size=(2, 2))
    return basis @ mu @ np.linalg.inv(basis)


def test_broyden_steps_from_the_jump_reach_a_smooth_maps_fixed_point_superlinearly():
    """The driver's transient on random smooth 2-D maps P(x) = x* + M u + c u0 u1 + q u0^2
    (u = x - x*): three sections from a start 0.03 away, fixed_point_jump, then secant_step
    after each section as the driver does. All but a few (where a residual grows, the
    driver goes on by plain sections: at most 20 of 200) land on x* to 1e-13 within 8
    steps,
    where plain iteration still is over 1e-9 away at most of them, the step sizes' ratio
    falls (superlinear: the last ratio below 0.2); a residual that grows stops the steps."""
    rng = np.random.default_rng(78)
    faster = refused = 0
    for trial in range(200):
        m = _random_contraction(rng, trial % 2)
        fixed, c, q = rng.normal(size=2), rng.normal(size=2), rng.normal(size=2)

        def section(x):
            u = x - fixed
            return fixed + m @ u + c * u[0] * u[1] + q * u[0] ** 2

        history = np.empty((4, 2))
        history[0] = fixed + 0.03 * rng.normal(size=2) / np.sqrt(2)
        for j in range(1, 4):
            history[j] = section(history[j - 1])
        jump, x, jac = fixed_point_jump(history, 4)
        if not jump:
            continue
        x_before, f_before = tuple(history[2]), tuple(history[3] - history[2])
        sizes = []
        for _ in range(8):
            f = tuple(section(np.array(x)) - np.array(x))
            ok, jac, step = secant_step(jac, x_before, f_before, x, f)
            if not ok:  # the residual did not shrink: at round-off, or a map not near
                # its linearisation (the driver goes on by plain sections)
                break
            x_before, f_before = x, f
            x = (x[0] + step[0], x[1] + step[1])
            sizes.append(max(abs(step[0]), abs(step[1])))
            if sizes[-1] <= 1e-15:
                break
        if not np.max(np.abs(np.array(x) - fixed)) <= 1e-13:
            refused += 1
            continue
        ratios = [b / a for a, b in zip(sizes, sizes[1:]) if a > 1e-12]
        if len(ratios) >= 2:
            assert ratios[-1] < 0.2, (trial, sizes)
        plain = history[3]
        for _ in range(len(sizes) + 1):
            plain = section(plain)
        faster += np.max(np.abs(plain - fixed)) > 1e-9
    assert faster >= 100 and refused <= 20
    # a residual that grew: no step
    ok, _, _ = secant_step((-1.0, 0.0, 0.0, -1.0), (0.0, 0.0), (1e-3, 0.0), (1e-3, 0.0),
                           (2e-3, 0.0))
    assert not ok


def test_impacts_past_a_jump_are_counted_like_the_plain_iteration_on_affine_maps():
    """impacts_past_jump with an affine map's own linear part continues the sequence from
    rest exactly: on random contractions (real and complex eigenvalues, moduli up to 0.99,
    tolerances 1e-6 to 1e-12) it returns the count of the plain iteration (period 1 at the
    first row whose step from the row before is within tol, relative: row - 1 impacts)."""
    rng = np.random.default_rng(79)
    for trial in range(300):
        m = _random_contraction(rng, trial % 2)
        m *= rng.uniform(0.5, 1.1)  # moduli up to 0.99
        if np.max(np.abs(np.linalg.eigvals(m))) >= 0.99:
            continue
        fixed = rng.normal(size=2) * rng.choice([0.1, 1.0, 10.0])
        tol = 10.0 ** rng.uniform(-12, -6)
        rows = [fixed + rng.normal(size=2)]
        n = None
        for row in range(1, 100000):
            rows.append(fixed + m @ (rows[-1] - fixed))
            if row >= 2 and np.all(np.abs(rows[-1] - rows[-2])
                                   <= tol * np.maximum(1.0, np.abs(rows[-1]))):
                n = row
                break
        if n <= 3:
            continue
        counted = impacts_past_jump(tuple((m - np.eye(2)).ravel()), 3, tuple(rows[3]),
                                    tuple(fixed), tol, 100000)
        assert counted == n - 1, (trial, counted, n - 1)


def test_a_failed_fixed_point_jump_keeps_the_secant_jacobian():
    """The transient's ``fixed_point`` accelerator (make_accelerators): where the affine
    jump fails (here: no difference between the last sections), the sequence goes on
    without a jump and keeps the last secant Jacobian, which impacts_past_jump counts the
    impacts from rest on (it was reset to zero, and a rotor-stop design whose later jump
    failed counted its transient as over at the first jump)."""
    from kernels.impact.accelerators import Acceleration, make_accelerators
    from kernels.pendulum import systems

    contact = systems.CONTACTS["rotor", "rotor_stop", ()]
    inner, first = make_accelerators(contact)[1], contact.first

    @njit
    def jump(p, data, jac, history):  # inner functions have no Python wrapper
        t, y, data = first(p, data, 0)
        a = Acceleration(jumped_at=2, secant=False, converged=False, jac=jac,
                         x_secant=(0.0, 0.0), f_secant=(0.0, 0.0), t_orbit=t, y_orbit=y,
                         first_jump=2, x_rest=(0.3, 0.4))
        after, t1, y1 = inner(a, history, 6, t, y, data, p)
        return after.jac, after.jumped_at, t1 == t and y1 == y

    fails_to_jump = module_level(jump, "fails_to_jump", globals(), dict(cache=True))
    case = np.array([2.0, 4.0, 0.0, 1.2, 0.0, 0.0, 0.0, 100.0, 100.0, 1.0])
    jac = (-0.5, 0.1, 0.2, -0.7)
    history = np.ones((8, 2))  # four equal sections: no affine map through them
    assert fails_to_jump(systems.rotor_parameters(case), systems.rotor_stop_data(case), jac,
                         history) == (jac, 2, True)
