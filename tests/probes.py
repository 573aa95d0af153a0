"""Python handles on the integration core, for tests and benchmarks: the core's functions
are numba closures with no Python wrapper (kernels/__init__.py), so each probe is a small
jitted function around one of them, built on first use and cached on disk as the kernels
are (``cached``: the first process that calls it compiles it, the others load it).

Every model x tool is a Contact, by (model, tool) name, with the test-defined
``relative_stop`` (tests/stop_tool.py) beside the mechanism's two tools: ``contact`` with
every method in its flights (for the flight probe), ``dopri5_contact`` with DOPRI5 alone on
the mechanism's tools (for the others, which step by DOPRI5: the entry points' own contact,
so that a process that compiled those compiles the parts a probe shares with them once).
"""

from functools import cache

import numpy as np
from numba import njit

from kernels.cache import module_level
from kernels.impact.impact_map import SPEED_EPS, make_impact_map
from kernels.impact.tangent import DPSI, DW, make_tracker
from kernels.impact.outcomes import FLIGHT_EVENT, Settings
from kernels.impact.runge_kutta import METHOD_DOP853, METHOD_DOPRI5, METHOD_RK4, make_stepper
from kernels.pendulum import blade, blade_geometry, models, systems, tools
from tests.stop_tool import relative_stop

MODELS = {"paper": models.PAPER, "rigid": models.RIGID, "rotor": models.ROTOR}
TOOLS = {"rotor_stop": tools.rotor_stop, "lab_window": blade.lab_window,
         "relative_stop": relative_stop}
METHODS = {"rk4": METHOD_RK4, "dopri5": METHOD_DOPRI5, "dop853": METHOD_DOP853}


def cached(probe, *key: str):
    """The probe as a module-level function named by ``key`` (the probe's factory and its
    arguments), which numba caches on disk (kernels.cache.module_level)."""
    return module_level(probe, "_".join(("probe",) + key), globals(), dict(cache=True))


@cache
def contact(model: str, tool: str):
    """The Contact of a model on a tool."""
    return TOOLS[tool](MODELS[model])


@cache
def dopri5_contact(model: str, tool: str):
    """The Contact of a model on a mechanism's tool whose flights step by DOPRI5 alone (the
    entry points'); on the test stop, its only one."""
    if tool in systems.TOOL_CONTACTS:
        return systems.CONTACTS[model, tool, ()]
    return contact(model, tool)


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

    return cached(probe, "flight", model, tool)


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
    return cached(fixed_steps_of(MODELS[model].rhs, MODELS[model].scales), "fixed_steps",
                  model)


@cache
def restitute(model: str, tool: str):
    """The impact map's Newton law restitute(t, y, data, p, r) -> (t, y)."""
    law = make_impact_map(dopri5_contact(model, tool), False).restitute

    @njit
    def probe(t, y, data, p, r):
        return law(t, y, data, p, r)

    return cached(probe, "restitute", model, tool)


@cache
def chatter(model: str, tool: str):
    """Flights and bounces (the impact map's Newton law) from a state until a bounce would
    leave slower than the impact map's SPEED_EPS; there, the chatter's accumulation point
    by the tool's ``settle`` (the ballistic tail): (accumulated, impacts, t, y, flight
    outcome, flight event). (The impact map's contact goes on from there into a slide.)"""
    c = dopri5_contact(model, tool)
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

    return cached(probe, "chatter", model, tool)


@cache
def zeno(model: str, tool: str):
    """The impact map's contact from a state at a bounce slower than SPEED_EPS: (opens, t,
    y, data, slid, accumulated, amplitude, peak, cost)."""
    hit = make_impact_map(dopri5_contact(model, tool), False).contact

    @njit
    def probe(t, y, data, p, r, s):
        o = hit(t, y, data, p, r, s, False)
        return o[0], o[1], o[2], o[3], o[4], o[5], o[6], o[7], o[8]

    return cached(probe, "zeno", model, tool)


@cache
def section_jacobian(model: str, tool: str):
    """The Jacobian of a steady cycle's section map two ways, through the same kernels:
    probe(p, data, r, settings, transient, eps) -> (ok, period, carried, differenced), d x d
    matrices over the section coordinates (the rotor speed unless constant, psi on the
    blade, psi'): the tangent the driver carries through the cycle's ``period`` sections
    (the first return of the section coordinates to 1e-8, at most 8) from the section
    reached after ``transient`` sections, and central differences (step eps) of the same
    sections from states moved along each coordinate (kept on the contact surface: on the
    blade the rotor angle from the face, at constant speed the time with it)."""
    c = dopri5_contact(model, tool)
    m = MODELS[model]
    section = make_impact_map(c, False, True).section
    start = make_tracker(c, 2 if m.driven else 4).start
    first, compose, rotor_angle, rotor_speed = c.first, m.compose, m.rotor_angle, m.rotor_speed
    psi_of, dpsi_of, driven = m.psi, m.dpsi, m.driven
    on_blade = tool == "lab_window"

    @njit
    def run(t, y, data, p, r, s, period, tangent, d):
        ok = True
        for _ in range(period):
            sec = section(t, y, data, p, r, s, False, tangent, d)
            if sec.outcome != 0:
                return False, t, y, data
            ok = ok and sec.tangent_ok
            t, y, data = sec.t, sec.y, sec.data
        return ok, t, y, data

    @njit
    def coordinate(row, y):
        return rotor_speed(y) if row == DW else psi_of(y) if row == DPSI else dpsi_of(y)

    @njit
    def probe(p, data, r, s, transient, eps):
        t, y, data = first(p, data, 0)
        none = np.empty((5, 0))
        ok, t, y, data = run(t, y, data, p, r, s, transient, none, 0)
        tangent = np.empty((5, 3))
        d, rows = start(t, y, data, tangent)
        period, t1, y1, data1 = 0, t, y, data
        for q in range(1, 9):
            good, t1, y1, data1 = run(t1, y1, data1, p, r, s, 1, none, 0)
            back = good
            for i in range(d):
                a, b = coordinate(rows[i], y1), coordinate(rows[i], y)
                back = back and abs(a - b) <= 1e-8 * max(1.0, abs(b))
            if back:
                period = q
                break
        if period == 0:
            return False, 0, np.zeros((d, d)), np.zeros((d, d))
        carried_ok, t1, y1, data1 = run(t, y, data, p, r, s, period, tangent, d)
        carried = np.empty((d, d))
        differenced = np.empty((d, d))
        for i in range(d):
            for j in range(d):
                carried[i, j] = tangent[rows[i], j]
        for j in range(d):
            ends = np.empty((2, d))
            for side in range(2):
                delta = eps if side == 0 else -eps
                w, psi, dpsi = rotor_speed(y), psi_of(y), dpsi_of(y)
                if rows[j] == DW:
                    w += delta
                elif rows[j] == DPSI:
                    psi += delta
                else:
                    dpsi += delta
                phi, t2 = rotor_angle(t, y), t
                if on_blade:
                    phi = data[3] - blade_geometry.beta(psi, data[2])
                    if driven:
                        t2 = phi
                t2, y2 = compose(t2, phi, w, psi, dpsi)
                good, t3, y3, data3 = run(t2, y2, data, p, r, s, period, none, 0)
                ok = ok and good
                for i in range(d):
                    ends[side, i] = coordinate(rows[i], y3)
            for i in range(d):
                differenced[i, j] = (ends[0, i] - ends[1, i]) / (2.0 * eps)
        return ok and carried_ok, period, carried, differenced

    return cached(probe, "section_jacobian", model, tool)


@cache
def leading_multiplier():
    """leading_multiplier(a, d) -> (|mu|, arg mu) of the tangent module."""
    from kernels.impact.tangent import leading_multiplier as lead

    @njit
    def probe(a, d):
        return lead(a, d)

    return cached(probe, "leading_multiplier")


@cache
def follow(model: str, tool: str):
    """Follow one steady cycle along a parameter, through the driver's sections:
    probe(p, data, rs, settings, transient, steps) -> rows (len(rs), 6) of (period, |mu|,
    arg mu, edge distance, rotor angle per section, ok): from rest at rs[0] for
    ``transient`` sections, then at each next restitution ``steps`` sections on from where
    the last left off (so the same cycle is followed, as long as it exists and is
    stable), its period (first return to 1e-9, <= 8), and the tangent through one
    period. The blade's reach is data[1]: pass it in ``data``."""
    from kernels.impact.tangent import leading_multiplier as lead

    c = dopri5_contact(model, tool)
    m = MODELS[model]
    section = make_impact_map(c, False, True).section
    start = make_tracker(c, 2 if m.driven else 4).start
    first, rotor_angle, rotor_speed, psi_of, dpsi_of = (c.first, m.rotor_angle,
                                                        m.rotor_speed, m.psi, m.dpsi)

    @njit
    def probe(p, data, rs, s, transient, steps):
        rows = np.full((rs.shape[0], 6), np.nan)
        t, y, data = first(p, data, 0)
        none = np.empty((5, 0))
        for n in range(rs.shape[0]):
            r = rs[n]
            good = True
            for _ in range(transient if n == 0 else steps):
                sec = section(t, y, data, p, r, s, False, none, 0)
                if sec.outcome != 0:
                    good = False
                    break
                t, y, data = sec.t, sec.y, sec.data
            if not good:
                return rows
            period = 0
            t1, y1, data1 = t, y, data
            for q in range(1, 9):
                sec = section(t1, y1, data1, p, r, s, False, none, 0)
                t1, y1, data1 = sec.t, sec.y, sec.data
                back = True
                for a, b in ((rotor_speed(y1), rotor_speed(y)), (psi_of(y1), psi_of(y)),
                             (dpsi_of(y1), dpsi_of(y))):
                    back = back and abs(a - b) <= 1e-9 * max(1.0, abs(b))
                if back:
                    period = q
                    break
            if period == 0:
                rows[n, 0] = 0.0
                continue
            tangent = np.empty((5, 3))
            d, where = start(t, y, data, tangent)
            edge, ok = np.inf, True
            t1, y1, data1 = t, y, data
            for _ in range(period):
                sec = section(t1, y1, data1, p, r, s, False, tangent, d)
                edge, ok = min(edge, sec.edge), ok and sec.tangent_ok
                t1, y1, data1 = sec.t, sec.y, sec.data
            a = np.empty((d, d))
            for i in range(d):
                for j in range(d):
                    a[i, j] = tangent[where[i], j]
            modulus, angle = lead(a, d)
            rows[n, 0], rows[n, 1], rows[n, 2], rows[n, 3] = period, modulus, angle, edge
            rows[n, 4] = (rotor_angle(t1, y1) - rotor_angle(t, y)) / period
            rows[n, 5] = 1.0 if ok else 0.0
        return rows

    return cached(probe, "follow", model, tool)


@cache
def accumulation(model: str):
    """The jump to a chatter's accumulation point on the blade, two ways:
    probe(t, y, data, p, r, settings, column, eps) -> (carried, differenced), 5-vectors in
    coordinates (dt, dphi1, dphi1', dpsi, dpsi') at the point: the tool's
    ``accumulation_tangent`` applied to ``column`` (a perturbation of the contact state at
    (t, y)), and central differences (step eps) of where the impact map's contact puts
    the striker just after its law (t_law, y_law) from contact states moved along it."""
    c = dopri5_contact(model, "lab_window")
    m = MODELS[model]
    hit = make_impact_map(c, False).contact
    accumulate = c.accumulation_tangent
    compose, rotor_angle, rotor_speed, psi_of, dpsi_of = (m.compose, m.rotor_angle,
                                                          m.rotor_speed, m.psi, m.dpsi)

    @njit
    def coordinates(t, y):
        return np.array([t, rotor_angle(t, y), rotor_speed(y), psi_of(y), dpsi_of(y)])

    @njit
    def probe(t, y, data, p, r, s, column, eps):
        tangent = np.zeros((5, 3))
        tangent[:, 0] = column
        accumulate(tangent, 1, t, y, data, p, r)
        ends = np.empty((2, 5))
        for side in range(2):
            delta = eps if side == 0 else -eps
            x = coordinates(t, y) + delta * column
            t2, y2 = compose(x[0], x[1], x[2], x[3], x[4])
            o = hit(t2, y2, data, p, r, s, False)
            ends[side] = coordinates(o[9], o[10])
        return tangent[:, 0].copy(), (ends[0] - ends[1]) / (2.0 * eps)

    return cached(probe, "accumulation", model)


@cache
def impacts_from_rest(model: str, tool: str):
    """probe(p, data, r, settings, tol, limit) -> (impacts, key): the section map iterated
    from rest with nothing extrapolated, until a section repeats the one before to tol
    (relative, as the driver classifies period 1): the impacts a design takes to settle,
    counted as the driver counts them, and the section state there; (-1, last key) where
    a section ends otherwise or limit sections do not settle."""
    c = dopri5_contact(model, tool)
    section = make_impact_map(c, False).section
    first, key_of = c.first, c.key

    @njit
    def probe(p, data, r, s, tol, limit):
        t, y, data = first(p, data, 0)
        none = np.empty((5, 0))
        before = key_of(t, y, data, p)
        for n in range(1, limit + 1):
            sec = section(t, y, data, p, r, s, False, none, 0)
            if sec.outcome != 0:
                return -1, before
            t, y, data = sec.t, sec.y, sec.data
            key = key_of(t, y, data, p)
            settled = n >= 2
            for i in range(len(key)):
                settled = settled and abs(key[i] - before[i]) <= tol * max(1.0, abs(key[i]))
            if settled:
                return n - 1, key
            before = key
        return -1, before

    return cached(probe, "impacts_from_rest", model, tool)
