"""The hard cases of event-driven impact simulation (H3-H6 of docs/models.md §7.2, the located
escape, the step budget, the step-size underflow) on every model x tool: on the core (one
flight or one chatter, against a SciPy twin at rtol 1e-13, tests/pendulum_twins.py) and end
to end (a design through the kernel, by its status).

The mechanism's rotor stop sits at psi = 0, the pendulum's equilibrium, where the restoring
acceleration vanishes: a contact there is never tangential (no grazing) and a bounce never
comes back (no chatter). Those two cases are tested on the blade and on the test-defined
stop at psi_s != 0 (tests/stop_tool.py), for each model.
"""

import math

import numpy as np
import pytest

from kernels.impact.outcomes import FLIGHT_EVENT, FLIGHT_MAX_STEPS, FLIGHT_UNDERFLOW
from tests import probes
from tests.conftest import kernel_point
from scipy.optimize import brentq

from tests.pendulum_twins import (Twin, beta, chatter_reference, first_event, free_extremum,
                                  h_ratio)

MODELS = ("paper", "rigid", "rotor")
TWINS = {"paper": Twin("paper", k=2.5), "rigid": Twin("rigid", k=1.0, kappa=1.2),
         "rotor": Twin("rotor", k=1.0, kappa=1.2, j1=30.0, slope=5.0)}
ESCAPE = {"rotor_stop": 1, "lab_window": 2, "relative_stop": 1}  # the escape event's index
WINDOW = 0.3
STOP = -0.3  # the test stop's angle


def tool_data(twin, tool, lower=-2 * math.pi):
    """The flight data of a tool: (0, k), (lower face, reach, k, level, side) or (psi_s,)."""
    if tool == "rotor_stop":
        return (0.0, twin.k)
    if tool == "lab_window":
        return (lower, WINDOW, twin.k, 0.0, 1.0)
    return (STOP,)


def fly(model, tool, t, y, data, **settings):
    twin = TWINS[model]
    return probes.flight(model, tool)(t, tuple(y), twin.p, data, probes.settings(**settings),
                                      False)


ALL = [(m, t) for m in MODELS for t in ("rotor_stop", "lab_window", "relative_stop")]
OFF_EQUILIBRIUM = [(m, t) for m in MODELS for t in ("lab_window", "relative_stop")]
#: the systems a fast run (``./tasks test --fast``) covers where a test takes every system:
#: each other system costs a compile of its own flight
FAST = {("paper", "rotor_stop"), ("rigid", "lab_window")}


def slow_except_fast(systems):
    """Every (model, tool) of ``systems``, those outside FAST marked slow."""
    return [s if s in FAST else pytest.param(*s, marks=pytest.mark.slow) for s in systems]


def leaving_start(model, tool):
    """A state exactly on the tool, leaving it: on the stop at psi = 0 swinging back; on
    the blade's face (G = 0) with G' < 0; on the test stop swinging down."""
    twin = TWINS[model]
    if tool == "rotor_stop":
        return twin.state(0.0, -3.0 if model == "paper" else -1.5)
    if tool == "lab_window":
        return twin.state(0.0, -1.05 / h_ratio(0.0, twin.k))
    return twin.state(STOP, -1.0)


@pytest.mark.slow
@pytest.mark.parametrize("model, tool", ALL)
def test_located_escape(model, tool):
    """Launched fast enough to go over the top: the flight ends on the escape event, at the
    time SciPy finds psi reaching -pi."""
    twin = TWINS[model]
    start = 0.0 if tool != "relative_stop" else STOP - 0.1  # below the test stop
    y0 = twin.state(start, {"paper": -8.0, "rigid": -3.0, "rotor": -6.0}[model])
    data = tool_data(twin, tool)
    ref = first_event(twin, tool, 0.0, y0, data)
    assert ref[1] == ESCAPE[tool]
    fl = fly(model, tool, 0.0, y0, data)
    assert fl.outcome == FLIGHT_EVENT and fl.event == ESCAPE[tool]
    assert fl.t == pytest.approx(ref[0], abs=1e-10)
    assert twin.psi(fl.y) == pytest.approx(-math.pi, abs=1e-10)


@pytest.mark.parametrize("model, tool", slow_except_fast(ALL))
def test_H4_no_event_where_a_flight_leaves_the_tool(model, tool):
    """A flight from exactly on the tool, leaving it: no event at its start; its next event
    and time as SciPy's (the polish on exact partial steps gives them to round-off, H5)."""
    twin = TWINS[model]
    y0, data = leaving_start(model, tool), tool_data(twin, tool)
    ref = first_event(twin, tool, 0.0, y0, data)
    fl = fly(model, tool, 0.0, y0, data)
    assert fl.outcome == FLIGHT_EVENT and fl.event == ref[1] and fl.t > 0.1
    assert fl.t == pytest.approx(ref[0], abs=1e-10)


@pytest.mark.parametrize("model, tool", ALL)
def test_H5_event_time_follows_atol(model, tool):
    """The same flight at rtol 1e-12: atol on the scale of the angles (1e-14) gives the
    event time to 1e-10; a loose atol (1e-6 rad) limits it."""
    twin = TWINS[model]
    y0, data = leaving_start(model, tool), tool_data(twin, tool)
    ref = first_event(twin, tool, 0.0, y0, data)[0]
    tight = fly(model, tool, 0.0, y0, data, rtol=1e-12, atol=1e-14).t
    loose = fly(model, tool, 0.0, y0, data, rtol=1e-12, atol=1e-6).t
    assert abs(tight - ref) < 1e-10
    assert abs(loose - ref) > 3 * abs(tight - ref)


def pulled_back(model, tool):
    """(psi, normal speed's Jacobian) of a contact whose free normal acceleration presses
    into the tool, so that a slow bounce comes back: the test stop below its equilibrium;
    on the blade, the first psi of a scan where G'' > 0 at zero normal speed."""
    twin = TWINS[model]
    if tool == "relative_stop":
        return STOP, lambda t, y: (0.0, 1.0)
    k = twin.k

    def jac(t, y):
        return (1.0, h_ratio(twin.psi(y), k))
    for psi in np.linspace(-0.5 * WINDOW, 0.5 * WINDOW, 31):  # the bounce stays in reach
        y = twin.state(psi, -1.0 / h_ratio(psi, k), phi1=-beta(psi, k))
        a_phi, a_psi = twin.accelerations(y)
        slope = k * (1 - k * k) * math.sin(psi) / (k * k + 1 + 2 * k * math.cos(psi)) ** 2
        if a_phi + h_ratio(psi, k) * a_psi + slope * twin.dpsi(y) ** 2 > 1e-3:
            return psi, jac
    raise AssertionError("no pressing contact in the scan")


def on_tool(model, tool, psi, normal_speed):
    """The state on the tool at psi leaving it at ``normal_speed`` (< 0: away)."""
    twin = TWINS[model]
    if tool == "relative_stop":
        return 0.0, twin.state(psi, normal_speed)
    k = twin.k
    phi1 = -beta(psi, k)  # on the face G = 0
    w = twin.idle if not twin.driven else 1.0
    t = phi1 if twin.driven else 0.0
    return t, twin.state(psi, (normal_speed - w) / h_ratio(psi, k), phi1=phi1)


@pytest.mark.parametrize("model, tool", OFF_EQUILIBRIUM)
@pytest.mark.parametrize("speed", [1e-3, 1e-6])
def test_H4_a_bounce_shorter_than_a_step_is_seen(model, tool, speed):
    """Leaving the tool at a small normal speed, pulled back: the bounce lasts ~speed,
    far shorter than a step at 1e-6; the first step is capped by the ballistic return time
    and the contact is found where SciPy (its first step capped alike) finds it. The time
    of a bounce 1e-12 deep is known to the rounding of the angle over the speed, 2e-5 of
    it at 1e-6."""
    twin = TWINS[model]
    psi, jac = pulled_back(model, tool)
    t0, y0 = on_tool(model, tool, psi, -speed)
    data = tool_data(twin, tool)
    ref = first_event(twin, tool, t0, y0, data, first_step=1e-3 * speed)
    fl = fly(model, tool, t0, y0, data)
    assert ref[1] == 0 and fl.outcome == FLIGHT_EVENT and fl.event == 0
    duration = ref[0] - t0
    assert duration < 100 * speed
    resolution = 1e-8 + 4 * np.spacing(1.0) / (speed * duration)
    assert fl.t - t0 == pytest.approx(duration, rel=resolution)


def blade_swing(model):
    """A start at rest at psi0 whose swing back turns the striker's polar angle G = phi1 +
    beta (a maximum, G' = 0 falling) at psi = 0.15, inside the blade's reach: psi0 by
    Brent's method on the twin. Returns (t0, y0, time and G at the turn)."""
    twin, k = TWINS[model], TWINS[model].k

    def turn(psi0):
        """(time, state) of the first turn of G, or None (too little energy to turn)."""
        return free_extremum(twin, 0.0, twin.state(psi0, 0.0), lambda t, y: (
            twin.rotor_speed(y) + h_ratio(twin.psi(y), k) * twin.dpsi(y)), t_max=8.0)

    def psi_at_turn(psi0):
        found = turn(psi0)
        return -math.inf if found is None else twin.psi(found[1])

    high = 3.0
    for low in np.arange(2.98, 1.0, -0.02):  # the turn moves down the swing with the energy
        if psi_at_turn(low) < 0.15:
            break
        high = low
    psi0 = brentq(lambda a: max(psi_at_turn(a), -1.0) - 0.15, low, high, xtol=1e-12)
    t, y = turn(psi0)
    return 0.0, twin.state(psi0, 0.0), t, twin.rotor_angle(t, y) + beta(twin.psi(y), k)


@pytest.mark.parametrize("model, tool", OFF_EQUILIBRIUM)
@pytest.mark.parametrize("eps", [1e-6, 1e-8])
def test_H3_a_grazing_contact_is_found(model, tool, eps):
    """The free flight's gap has a maximum eps beyond the tool: the contact lasts
    ~sqrt(eps) (4e-4 of the rotor turn at 1e-8), far less than DOPRI5's steps at rtol 1e-9,
    and at 1e-8 passes the tool by less than the step's cubic interpolant is accurate
    (~1e-7). The extremum check finds it: the interpolant's turning time, the gap there on
    an exact partial step (so the limit is the integration's error, not the
    interpolant's). SciPy's DOP853 at rtol 1e-6 with an event steps over these (H3)."""
    twin = TWINS[model]
    if tool == "relative_stop":  # from rest below the stop: the swing's apex
        t0, y0 = 0.0, twin.state(-0.6, 0.0)
        t_apex, y_apex = free_extremum(twin, t0, y0, lambda t, y: twin.dpsi(y))
        data = (twin.psi(y_apex) - eps,)
    else:
        t0, y0, t_apex, apex = blade_swing(model)
        data = (apex - eps - 2 * math.pi, WINDOW, twin.k, 0.0, 1.0)
    fl = fly(model, tool, t0, y0, data, rtol=1e-9, atol=1e-11)
    assert fl.outcome == FLIGHT_EVENT and fl.event == 0
    assert abs(fl.t - t_apex) < 0.01  # this contact, not a later one
    assert fl.cost.steps < 300  # found inside long steps


def chatter_case(model, tool):
    """H6's chatter: (twin, flight data, r, the normal speed's Jacobian, t0, y0)."""
    twin = TWINS[model]
    data = tool_data(twin, tool)
    if tool == "relative_stop":
        if model == "rigid":
            twin = Twin("rigid", k=1.0, kappa=1.0)  # kappa k = 1
        return twin, data, 0.8, (lambda t, y: (0.0, 1.0)), 0.0, twin.state(-0.6, 0.0)
    psi, jac = pulled_back(model, tool)
    return twin, data, 0.5, jac, *on_tool(model, tool, psi, -1e-3)


@pytest.mark.slow
@pytest.mark.parametrize("model, tool", OFF_EQUILIBRIUM)
def test_H6_a_chatter_accumulates_where_scipy_puts_it(model, tool):
    """Bounces at R = 0.5 (0.8 on the test stop, from rest at -0.6: the Zeno example of
    docs/models.md §5.5) shrink geometrically; once a bounce would leave slower than 1e-7 the
    sequence ends at its accumulation point (the ballistic tail). SciPy, bounce by bounce,
    needs as many impacts and puts the accumulation at the same time. For the rigid model
    on the stop the accumulation time is 12.834839 (70 impacts to r v < 1e-7; 71 to v < 1e-7)."""
    twin, data, r, jac, t0, y0 = chatter_case(model, tool)
    impacts, t_inf = chatter_reference(twin, tool, jac, t0, y0, data, r)
    accumulated, n, t, y, *_ = probes.chatter(model, tool)(t0, tuple(y0), twin.p, data, r,
                                                          probes.settings(), 10000)
    assert accumulated and n == impacts
    assert t == pytest.approx(t_inf, abs=1e-7)
    # the impact map's contact there: the accumulated chatter sticks (a slide on the blade)
    opens, *_, chattered, amplitude, peak, cost = probes.zeno(model, tool)(
        t, y, data, twin.p, r, probes.settings())
    assert opens
    if tool == "relative_stop" and model == "rigid":
        assert impacts == 70 and t == pytest.approx(12.834839, abs=1e-6)


@pytest.mark.parametrize("model, tool", ALL)
def test_the_step_budget_and_the_underflow_end_a_flight(model, tool):
    twin = TWINS[model]
    y0, data = leaving_start(model, tool), tool_data(twin, tool)
    fl = fly(model, tool, 0.0, y0, data, max_steps=3)
    assert fl.outcome == FLIGHT_MAX_STEPS and fl.cost.steps + fl.cost.rejected == 3
    fl = fly(model, tool, 0.0, y0, data, rtol=1e-300, atol=1e-300)
    assert fl.outcome == FLIGHT_UNDERFLOW and fl.t < 1e-6


# ---------------------------------------------------------------- end to end

SYSTEM_POINTS = {  # a design of each model on each tool with a steady regime
    ("paper", "rotor_stop"): dict(model="paper", k=2.5, R=0.2),
    ("rigid", "rotor_stop"): dict(model="rigid", k=1.0, kappa=1.2, R=0.02),
    ("rotor", "rotor_stop"): dict(model="rotor", k=1.0, kappa=1.2, rotor_inertia_ratio=30.0,
                                  motor_slope=5.0, R=0.02),
    ("paper", "lab_window"): dict(model="paper", k=2.5, tool="lab_window", R=0.0),
    ("rigid", "lab_window"): dict(model="rigid", k=1.0, kappa=1.2, tool="lab_window", R=0.0),
    ("rotor", "lab_window"): dict(model="rotor", k=1.0, kappa=1.2, tool="lab_window",
                                  rotor_inertia_ratio=30.0, motor_slope=5.0, R=0.0),
}
SYSTEM_IDS = [f"{m}-{t}" for m, t in SYSTEM_POINTS]


def point(system, method, **change):
    design = dict(SYSTEM_POINTS[system], **change)
    out, status, _ = kernel_point("rotary_pendulum", dict(method, integrator="dopri5"),
                                  **design)
    return out, status


@pytest.mark.parametrize("system", SYSTEM_POINTS, ids=SYSTEM_IDS)
def test_end_to_end_every_system_reaches_a_steady_state(system):
    out, status = point(system, {"rtol": 1e-10, "atol": 1e-12})
    assert status == "ok" and np.isfinite(out["impact_speed"]) and out["n_events"] > 0


@pytest.mark.parametrize("system", SYSTEM_POINTS, ids=SYSTEM_IDS)
def test_end_to_end_escape(system):
    """A lively bounce: each system goes over the top and says so (the light rotor on the
    blade at R = 0.9 keeps its pendulum out of the blade's reach instead: no_impact)."""
    r = 0.5 if system == ("rotor", "lab_window") else 0.9
    out, status = point(system, {"rtol": 1e-10, "atol": 1e-12}, R=r)
    assert status == "escape" and np.isnan(out["amplitude"])


@pytest.mark.parametrize("system", SYSTEM_POINTS, ids=SYSTEM_IDS)
def test_end_to_end_impact_budget_and_underflow(system):
    """One impact allowed: no cycle can be recognised (max_steps); tolerances below
    round-off: the first flight's steps underflow."""
    out, status = point(system, {"rtol": 1e-10, "atol": 1e-12, "max_impacts": 1})
    assert status == "max_steps" and np.isnan(out["impact_speed"])
    out, status = point(system, {"rtol": 1e-300, "atol": 1e-300})
    assert status == "step_underflow" and np.isnan(out["impact_speed"])
