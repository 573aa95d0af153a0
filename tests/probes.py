"""Python handles on the integration core, for tests and benchmarks: the core's functions
are numba closures with no Python wrapper (kernels/__init__.py), so each probe is a small
jitted function around one of them, built (and compiled) on first use.

``SYSTEMS``: every model x tool as a Contact, by (model, tool) name, with the test-defined
``relative_stop`` (tests/stop_tool.py) beside the mechanism's two tools.
"""

from functools import cache

from numba import njit

from kernels.impact.impact_map import SPEED_EPS, make_impact_map
from kernels.impact.outcomes import FLIGHT_EVENT, Settings
from kernels.impact.runge_kutta import METHOD_DOPRI5, METHOD_RK4, make_stepper
from kernels.pendulum import models, tools
from tests.stop_tool import relative_stop

MODELS = {"paper": models.PAPER, "rigid": models.RIGID, "rotor": models.ROTOR}
TOOLS = {"rotor_stop": tools.rotor_stop, "lab_window": tools.lab_window,
         "relative_stop": relative_stop}
METHODS = {"rk4": METHOD_RK4, "dopri5": METHOD_DOPRI5}


@cache
def contact(model: str, tool: str):
    """The Contact of a model on a tool."""
    return TOOLS[tool](MODELS[model])


def settings(method="dopri5", rtol=1e-12, atol=1e-14, dt=0.002, max_steps=10**6,
             horizon=1e3):
    return Settings(METHODS[method], rtol, atol, dt, max_steps, horizon)


@cache
def flight(model: str, tool: str):
    """flight(t, y, p, data, settings, refine) -> the core's Flight record."""
    fly = contact(model, tool).flight

    @njit
    def probe(t, y, p, data, s, refine):
        return fly(t, y, p, data, s, refine)

    return probe


def fixed_steps_of(rhs, scales):
    """fixed_steps(method, y, p, h, n) of a vector field: n steps of length h (no error
    control, no events), the state at n h, for orders, invariants and limits at a set
    time."""
    step = make_stepper(rhs, scales)

    @njit
    def probe(method, y, p, h, n):
        f = rhs(y, p)
        for _ in range(n):
            y, f, err = step(method, y, f, h, p, 1.0, 1.0)
        return y

    return probe


@cache
def fixed_steps(model: str):
    """fixed_steps_of a model's free motion."""
    return fixed_steps_of(MODELS[model].rhs, MODELS[model].scales)


@cache
def restitute(model: str, tool: str):
    """The impact map's Newton law restitute(t, y, data, p, r) -> (t, y)."""
    law = make_impact_map(contact(model, tool), False).restitute

    @njit
    def probe(t, y, data, p, r):
        return law(t, y, data, p, r)

    return probe


@cache
def chatter(model: str, tool: str):
    """Flights and bounces (the impact map's Newton law) from a state until a bounce would
    leave slower than the impact map's SPEED_EPS; there, the chatter's accumulation point
    by the tool's ``settle`` (the ballistic tail): (accumulated, impacts, t, y, flight
    outcome, flight event). (The impact map's contact goes on from there into a slide.)"""
    c = contact(model, tool)
    fly, restitute = c.flight, make_impact_map(c, False).restitute
    normal_speed, normal_acceleration, settle = (c.normal_speed, c.normal_acceleration,
                                                 c.settle)

    @njit
    def probe(t, y, p, data, r, s, max_impacts):
        for impacts in range(max_impacts):
            fl = fly(t, y, p, data, s, False)
            if fl.outcome != FLIGHT_EVENT or fl.event != 0:
                return False, impacts, fl.t, fl.y, fl.outcome, fl.event
            t, y, data = fl.t, fl.y, fl.data
            approach = normal_speed(t, y, data, p)
            if r * abs(approach) < SPEED_EPS:
                dt = 2.0 * r * abs(approach) / (normal_acceleration(t, y, data, p) * (1.0 - r))
                t, y = settle(t, y, data, p, dt)
                return True, impacts + 1, t, y, fl.outcome, fl.event
            t, y = restitute(t, y, data, p, r)
        return False, max_impacts, t, y, -1, -1

    return probe


@cache
def zeno(model: str, tool: str):
    """The impact map's contact from a state at a bounce slower than SPEED_EPS: (opens, t,
    y, data, accumulated, amplitude, peak, cost)."""
    hit = make_impact_map(contact(model, tool), False).contact

    @njit
    def probe(t, y, data, p, r, s):
        return hit(t, y, data, p, r, s, False)

    return probe
