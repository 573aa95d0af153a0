"""The impact map: contacts and flights from the start of a sequence to its steady cycle.

``make_impact_map(contact, jump_early)`` specialises the driver to a ``Contact``
(kernels/impact/__init__.py) and returns a ``Driver`` whose ``steady(p, data, r, settings,
repeat_tol, log, start, known) -> (Steady, t, y, data)`` runs a sequence, and ``settle``
the same from a given state (auto's second stage goes on from the first one's cycle); one
factory each: the law, a contact, a section, the transient and its accelerators, the
refined cycle, the whole sequence:

1. a contact: Newton's law on the normal speed along the contact Jacobian, through the
   model's impulse response; a bounce that would leave slower than SPEED_EPS ends a chatter
   sequence at its accumulation point (the ballistic tail 2 R v/(g (1 - R)), H6, P-O14),
   where the law acts with R = 0; a plastic contact (R = 0, or such an accumulation) that
   the free motion presses into the tool then rides it (the tool's slide), else it leaves
   at zero normal speed; a contact that does not open after the law is degenerate;
   on a smooth map with R = 0 (``jump_early``: the map is then constant) the first section
   is the cycle;
2. a flight to the next contact, or escape, or the horizon (no impact);
3. a section is the contact opening an episode (after a free flight of at least the tool's
   min_flight); its state (``key``) classifies the cycle: p sections repeating the p before
   to ``tol`` (period p <= MAX_PERIOD);
4. on a smooth map (``jump_early``: an affine map of reversible flights) Aitken's
   extrapolation from the start and two sections jumps to the fixed point, checked by the
   next section; on another smooth map with a 2-D section (the rotor model on its stop)
   the transient jumps to the fixed point of the affine map through its last four
   sections (fixed_point_jump), then goes on by Broyden's quasi-Newton steps, one after
   each section, from that map's secant Jacobian (secant_step: superlinear, each step's
   error a fraction of the last), to the first step within tol; where a step fails (the
   residual grew) plain sections go on, another jump after four, three sections confirm,
   and Aitken on the last three removes the geometric tail; the cycle's residual checks
   either (H13). Flights per steady state: 12.1 plain, 9.2 with the jump alone, 7.8 with
   Broyden's steps. The impacts from rest past the first jump are counted on the map's
   linearisation (impacts_past_jump), not the sections flown;
5. the steady cycle is run once more with ``refine`` (turning points and peaks polished),
   which gives the outputs;
6. the budget ``max_impacts``: without a cycle, not periodic where the map has stopped
   contracting, else max_steps; not periodic already at a checkpoint (a power of two of
   sections) where the steps between sections have stopped shrinking by more than the
   budget's verdict allows (settles_nowhere), so that a quasi-periodic or chaotic
   sequence does not fly the whole budget;
7. with ``stability``, the refined run of the cycle also carries the tangent of the section
   map (tangent.py) for its leading multiplier, and every cycle reports its margins: the
   slowest and fastest impact, and the smallest distance of an impact from the tool's edge;
8. ``start`` picks the starting state (0: at rest, the tool's ``first``; others for the
   attractor count); a sequence that reaches a section state of a cycle in ``known``
   (those other starts found, known_attractor), or contracts onto one (captured_by),
   stops there as that cycle.
"""

import functools
import math
from collections import namedtuple

import numpy as np
from numba import njit

from kernels import INLINE_OPTIONS, INNER_OPTIONS
from kernels.impact.accelerators import (Acceleration, aitken_jump, impacts_past_jump,
                                         make_accelerators)
from kernels.impact.attractors import KNOWN, captured_by, known_attractor
from kernels.impact.verdicts import (MAX_PERIOD, classify_period, not_periodic,
                                     settles_nowhere)
from kernels.impact.tangent import MAX_SECTION_DIMENSION, NO_TRACKER, make_tracker
from kernels.impact.runge_kutta import OTHER_METHODS
from kernels.impact.tuples import from_row
from kernels.impact.outcomes import (FLIGHT_EVENT, FLIGHT_HORIZON, FLIGHT_NONFINITE,
                                     FLIGHT_UNDERFLOW, NO_COST, SEQUENCE_CYCLE,
                                     SEQUENCE_DEGENERATE, SEQUENCE_ESCAPE, SEQUENCE_MAX_STEPS,
                                     SEQUENCE_NO_IMPACT, SEQUENCE_NONFINITE,
                                     SEQUENCE_NOT_PERIODIC, SEQUENCE_UNDERFLOW, add)

SPEED_EPS = 1e-7  # a bounce slower than this ends a chatter sequence (H6)
MAX_CONTACTS_PER_SECTION = 200  # a chatter sequence longer than this is not a cycle
IMPACTS_COUNTED = 100000  # the longest transient counted past a jump
#: the columns of the section log: the rotor angle (mod 2 pi) and psi at each section
LOG_ROTOR_ANGLE, LOG_PSI = range(2)

#: what a sequence returns: its outcome (outcomes.SEQUENCE_*), the cycle's period and
#: whether it accumulates a chatter, and over the cycle the amplitude, the free-flight time,
#: the rotor angle and time elapsed, the summed striker speed at its section contacts and
#: the peak acceleration; the sections before the cycle; the cost of the whole sequence;
#: the cycle's margins (``Margins``); the section state (key) of its cycle that has the
#: smallest first component (the same for every phase of a period-n cycle)
Steady = namedtuple("Steady", ["outcome", "period", "chatter", "amplitude", "flight_time",
                               "rotor_angle", "elapsed", "speed", "peak", "impacts", "cost",
                               "margins", "key"])
#: how far a steady cycle is from changing: the slowest and fastest striker speed of its
#: impacts, the smallest distance of an impact from the tool's edge, and the section map's
#: leading multiplier (modulus, argument; NaN unless the tangent was carried)
Margins = namedtuple("Margins", ["speed_min", "speed_max", "edge", "modulus", "angle"])
NO_MARGINS = Margins(math.nan, math.nan, math.nan, math.nan, math.nan)
#: the driver's functions: the whole sequence from a start and from a state, one section,
#: one contact, Newton's law
Driver = namedtuple("Driver", ["steady", "settle", "section", "contact", "restitute"])
#: the refined steady cycle (``cycle``): its outcome, chatter, amplitude, free-flight time,
#: rotor angle and time elapsed, summed striker speed at its sections, peak acceleration,
#: how far its section state is from repeating after the period (``residual``), its cost,
#: margins and canonical section state
Cycle = namedtuple("Cycle", ["outcome", "chatter", "amplitude", "flight_time", "rotor_angle",
                             "elapsed", "speed", "peak", "residual", "cost", "margins", "key"])
#: how the transient ended (make_transient): with a result already (``ended``: no cycle, or
#: the constant map's), or with its count of sections, the period found, the state and
#: cost there, its jumps, whether it jumped early (an affine map) and the cycle that jump's
#: refined section gave (``steady``)
Transient = namedtuple("Transient", ["ended", "steady", "count", "period", "t", "y", "data",
                                     "cost", "acceleration", "jumped"])
#: what a section returns: its outcome (SEQUENCE_CYCLE: it reached the next section), the
#: state there, whether it chattered, its amplitude, peak, free-flight time and cost, the
#: slowest and fastest striker speed at its contacts, their smallest distance from the
#: tool's edge, and whether the tangent went through it
Section = namedtuple("Section", ["outcome", "t", "y", "data", "chatter", "amplitude", "peak",
                                 "flight_time", "cost", "speed_min", "speed_max", "edge",
                                 "tangent_ok"])


@njit(**INLINE_OPTIONS)
def ended(steady, count, t, y, data, acceleration):
    """A transient that ended with its result ``steady`` already (no cycle, the constant
    map's, a known one's)."""
    return Transient(ended=bool(True), steady=steady, count=count, period=int(0), t=t, y=y,
                     data=data, cost=steady.cost, acceleration=acceleration,
                     jumped=bool(False))


@njit(**INLINE_OPTIONS)
def on_known(cycle, key, impacts, cost):
    """The Steady of a sequence that reached the section state ``key`` of a known cycle
    (``cycle``: a row of known cycles, columns KNOWN): its outcome, period and chatter;
    its values are that cycle's, not computed again."""
    return Steady(outcome=SEQUENCE_CYCLE, period=int(cycle[KNOWN.period]),
                  chatter=cycle[KNOWN.chatter] > 0.0,
                  amplitude=0.0, flight_time=0.0, rotor_angle=0.0, elapsed=0.0, speed=0.0,
                  peak=0.0, impacts=impacts, cost=cost, margins=NO_MARGINS, key=key)


@njit(**INLINE_OPTIONS)
def no_cycle(outcome, chatter, impacts, cost, key):
    """The Steady of a sequence that ended without a cycle."""
    return Steady(outcome=outcome, period=0, chatter=chatter, amplitude=0.0, flight_time=0.0,
                  rotor_angle=0.0, elapsed=0.0, speed=0.0, peak=0.0, impacts=impacts,
                  cost=cost, margins=NO_MARGINS, key=key)


@njit(**INLINE_OPTIONS)
def of_cycle(period, c, impacts, cost):
    """The Steady of a sequence whose cycle of ``period`` sections is ``c`` (a Cycle, or a
    Steady: its values and margins)."""
    return Steady(outcome=SEQUENCE_CYCLE, period=period, chatter=c.chatter,
                  amplitude=c.amplitude, flight_time=c.flight_time,
                  rotor_angle=c.rotor_angle, elapsed=c.elapsed, speed=c.speed, peak=c.peak,
                  impacts=impacts, cost=cost, margins=c.margins, key=c.key)


@njit(**INLINE_OPTIONS)
def with_cost(s, impacts, cost):
    """The Steady ``s`` with its impacts from the start and its cost replaced (a sequence
    solved in stages: the impacts one stage counted, the cost of all)."""
    if s.outcome != SEQUENCE_CYCLE:
        return no_cycle(s.outcome, s.chatter, impacts, cost, s.key)
    return of_cycle(s.period, s, impacts, cost)


def make_impact_map(c, jump_early, stability=False, known_cycles=True, second_stage=True,
                    methods=OTHER_METHODS):
    """The driver of a Contact (see the module docstring); with ``stability`` the steady
    cycle also carries the tangent of the section map (tangent.py) for its multipliers,
    its flights with ``methods`` compiled in beside DOPRI5 (the Contact's; DOP853 never:
    make_timed_flight);
    without ``known_cycles`` a sequence never looks for the cycles of other starts (a
    single start: their search is not compiled in); without ``second_stage`` the sequence
    from a state (``settle``) is called only by ``steady`` and inlined into it. The parts
    that do not depend on the starts and the stages (the law, a contact, a section, the
    cycle, the transient, the tangent's tracker) are made once per Contact and options
    (functools.cache), so that a process making several entry points of one system
    compiles them once: numba keeps an inner function's code in its process only."""
    tracker = make_tracker(c, 2 if c.model.driven else 4, methods) if stability else NO_TRACKER
    restitute = make_restitute(c)
    contact = make_contact(c, restitute)
    section = make_section(c, contact, tracker)
    cycle = make_cycle(c, section, tracker)
    transient = make_transient(c, jump_early, section, known_cycles)
    steady, settle = make_steady(c, jump_early, transient, cycle, second_stage)
    return Driver(steady=steady, settle=settle, section=section, contact=contact,
                  restitute=restitute)


@functools.cache
def make_restitute(c):
    """Newton's law of a Contact: ``restitute(t, y, data, p, r) -> (t, y)``."""
    jacobian, response, compose = c.jacobian, c.model.response, c.model.compose
    psi_of, dpsi_of = c.model.psi, c.model.dpsi
    rotor_angle, rotor_speed = c.model.rotor_angle, c.model.rotor_speed

    @njit(**INNER_OPTIONS)
    def restitute(t, y, data, p, r):
        """Newton's law on the normal speed: v_n+ = -r v_n-, the impulse along J through
        the model's response M^-1 J^T."""
        j_phi, j_psi = jacobian(t, y, data)
        x_phi, x_psi = response(y, j_phi, j_psi, p)
        w, dpsi = rotor_speed(y), dpsi_of(y)
        impulse = -(1.0 + r) * (j_phi * w + j_psi * dpsi) / (j_phi * x_phi + j_psi * x_psi)
        return compose(t, rotor_angle(t, y), w + x_phi * impulse, psi_of(y),
                       dpsi + x_psi * impulse)

    return restitute


@functools.cache
def make_contact(c, restitute):
    """A contact of a Contact, from its approach to where it opens or its slide ends."""
    normal_speed, normal_acceleration = c.normal_speed, c.normal_acceleration
    gap_rate_after, pressed, settle, slide = c.gap_rate_after, c.pressed, c.settle, c.slide

    @njit(**INNER_OPTIONS)
    def contact(t, y, data, p, r, settings, refine):
        """A contact: (opens, t, y, data, slid, chatter, amplitude, peak, cost, t_law,
        y_law); (t_law, y_law) just after the law, where a slide starts."""
        approach = normal_speed(t, y, data, p)
        # the chatter accumulates once the bounce it would start falls below SPEED_EPS:
        # its flight would be shorter than the resolution of the event search
        zeno = r * abs(approach) < SPEED_EPS if r > 0.0 else abs(approach) < SPEED_EPS
        if zeno and r > 0.0:
            g2 = normal_acceleration(t, y, data, p)
            if g2 > 0.0:  # the chatter's accumulation point (H6)
                t, y = settle(t, y, data, p, 2.0 * r * abs(approach) / (g2 * (1.0 - r)))
        t, y = restitute(t, y, data, p, 0.0 if zeno else r)
        # a plastic contact pressed into the tool rides it (the law first: on a rotor of
        # finite inertia the impulse also changes the rotor's speed)
        if (r == 0.0 or zeno) and pressed(t, y, data, p):
            released, t1, y1, data1, amplitude, peak, cost = slide(t, y, data, p,
                                                                   settings, refine)
            return True, t1, y1, data1, True, zeno, amplitude, peak, cost, t, y
        return (gap_rate_after(t, y, data, p) < 0.0, t, y, data, False, zeno, 0.0, 0.0,
                NO_COST, t, y)

    return contact


@functools.cache
def make_section(c, contact, tracker):
    """One section of a Contact: its contacts and flights up to the next section."""
    _, track_flight, track_law, _ = tracker
    flight, flight_data, escapes_before = c.flight, c.flight_data, c.escapes_before
    striker_speed, edge_distance = c.striker_speed, c.edge_distance
    escape_event, min_flight = c.escape_event, c.min_flight

    @njit(**INNER_OPTIONS)
    def section(t, y, data, p, r, settings, refine, tangent, d):
        """From a section contact (before its law) to the next section contact; the first
        d columns of ``tangent`` are carried along (tangent.py)."""
        chatter = False
        amplitude = peak = flight_time = 0.0
        speed_min, speed_max, edge = math.inf, 0.0, math.inf
        tangent_ok = True
        cost = NO_COST
        for _ in range(MAX_CONTACTS_PER_SECTION):
            speed = striker_speed(t, y, data, p)
            speed_min, speed_max = min(speed_min, speed), max(speed_max, speed)
            edge = min(edge, edge_distance(t, y, data))
            t0, y0, data0 = t, y, data
            (opens, t, y, data, slid, zeno, a, pk, spent, t_law,
             y_law) = contact(t, y, data, p, r, settings, refine)
            tangent_ok = tangent_ok and track_law(tangent, d, t0, y0, data0, t_law, y_law,
                                                  t, y, data, p, r, slid, zeno, settings)
            cost = add(cost, spent)
            # a plastic contact cannot chatter: its zero-speed touch (a graze, as where a
            # slide's release meets the face again) is not a bounce sequence
            chatter = chatter or (zeno and r > 0.0)
            amplitude, peak = max(amplitude, a), max(peak, pk)
            if not opens:
                return Section(SEQUENCE_DEGENERATE, t, y, data, chatter, amplitude, peak,
                               flight_time, cost, speed_min, speed_max, edge, tangent_ok)
            if escapes_before(t, y, data, p):  # decided in closed form (H1, H2, H12)
                return Section(SEQUENCE_ESCAPE, t, y, data, chatter, amplitude, peak,
                               flight_time, cost, speed_min, speed_max, edge, tangent_ok)
            fl = flight(t, y, p, flight_data(data), settings, refine)
            cost = add(cost, fl.cost)
            amplitude, peak = max(amplitude, fl.amplitude), max(peak, fl.peak)
            if fl.outcome != FLIGHT_EVENT or fl.event == escape_event:
                outcome = (SEQUENCE_ESCAPE if fl.outcome == FLIGHT_EVENT else
                           SEQUENCE_NO_IMPACT if fl.outcome == FLIGHT_HORIZON else
                           SEQUENCE_UNDERFLOW if fl.outcome == FLIGHT_UNDERFLOW else
                           SEQUENCE_NONFINITE if fl.outcome == FLIGHT_NONFINITE else
                           SEQUENCE_MAX_STEPS)
                return Section(outcome, fl.t, fl.y, fl.data, chatter, amplitude, peak,
                               flight_time, cost, speed_min, speed_max, edge, tangent_ok)
            tangent_ok = tangent_ok and track_flight(tangent, d, t, y, fl.t, fl.y, fl.f,
                                                     fl.data, p, settings)
            duration = fl.t - t
            flight_time += duration
            t, y, data = fl.t, fl.y, fl.data
            if duration >= min_flight:
                return Section(SEQUENCE_CYCLE, t, y, data, chatter, amplitude, peak,
                               flight_time, cost, speed_min, speed_max, edge, tangent_ok)
        return Section(SEQUENCE_NOT_PERIODIC, t, y, data, chatter, amplitude, peak,
                       flight_time, cost, speed_min, speed_max, edge, tangent_ok)

    return section


@functools.cache
def make_cycle(c, section, tracker):
    """The refined steady cycle of a Contact, with its margins and, with the tangent
    (``tracker``), its leading multiplier: ``cycle(...) -> Cycle``."""
    track_start, _, _, track_multiplier = tracker
    key_of, striker_speed, rotor_angle = c.key, c.striker_speed, c.model.rotor_angle

    @njit(**INNER_OPTIONS)
    def cycle(t, y, data, p, r, settings, period):
        """The steady cycle of ``period`` sections from (t, y), with refined flights."""
        t0, phi0, key0 = t, rotor_angle(t, y), key_of(t, y, data, p)
        chatter = False
        amplitude = peak = flight_time = speed = 0.0
        speed_min, speed_max, edge = math.inf, 0.0, math.inf
        cost = NO_COST
        tangent = np.empty((5, MAX_SECTION_DIMENSION))
        d, rows = track_start(t, y, data, tangent)
        tangent_ok = True
        canonical = key0
        for _ in range(period):
            here = key_of(t, y, data, p)
            if here[0] < canonical[0]:
                canonical = here
            speed += striker_speed(t, y, data, p)
            s = section(t, y, data, p, r, settings, bool(True), tangent, d)  # see steady
            cost = add(cost, s.cost)
            chatter = chatter or s.chatter
            amplitude, peak = max(amplitude, s.amplitude), max(peak, s.peak)
            flight_time += s.flight_time
            speed_min, speed_max = min(speed_min, s.speed_min), max(speed_max, s.speed_max)
            edge, tangent_ok = min(edge, s.edge), tangent_ok and s.tangent_ok
            t, y, data = s.t, s.y, s.data
            if s.outcome != SEQUENCE_CYCLE:
                return Cycle(outcome=s.outcome, chatter=chatter, amplitude=amplitude,
                             flight_time=flight_time, rotor_angle=0.0, elapsed=0.0,
                             speed=speed, peak=peak, residual=math.inf, cost=cost,
                             margins=NO_MARGINS, key=canonical)
        key = key_of(t, y, data, p)
        residual = 0.0
        for i in range(len(key)):
            residual = max(residual, abs(key[i] - key0[i]))
        modulus = angle = math.nan
        if tangent_ok:
            modulus, angle = track_multiplier(tangent, d, rows)
        return Cycle(outcome=SEQUENCE_CYCLE, chatter=chatter, amplitude=amplitude,
                     flight_time=flight_time, rotor_angle=rotor_angle(t, y) - phi0,
                     elapsed=t - t0, speed=speed, peak=peak, residual=residual, cost=cost,
                     margins=Margins(speed_min, speed_max, edge, modulus, angle),
                     key=canonical)

    return cycle


@functools.cache
def make_record(c):
    """``record(t, y, data, p, history, row, log) -> key``: a section's state into row
    ``row`` of ``history``, and its rotor angle (mod 2 pi) and psi into ``log`` (its last
    row takes any beyond)."""
    key_of, rotor_angle, psi_of = c.key, c.model.rotor_angle, c.model.psi

    @njit(**INNER_OPTIONS)
    def record(t, y, data, p, history, row, log):
        key = key_of(t, y, data, p)
        for i in range(len(key)):
            history[row, i] = key[i]
        slot = min(row, log.shape[0] - 1)
        log[slot, LOG_ROTOR_ANGLE] = rotor_angle(t, y) % (2.0 * math.pi)
        log[slot, LOG_PSI] = psi_of(y)
        return key

    return record


@functools.cache
def make_transient(c, jump_early, section, known_cycles=True):
    """The transient of a Contact: ``transient(p, data, r, settings, repeat_tol, log, t, y,
    history, known) -> Transient``, sections from (t, y) until p of them repeat
    (``history`` holds their states), one is on a cycle of ``known`` (known_attractor,
    captured_by; with ``known_cycles`` only),
    or the sequence settles nowhere (settles_nowhere); accelerated where the map allows
    it: on an affine map (``jump_early``) by Aitken's jump from the start and two
    sections (aitken_jump), on another smooth map with a 2-D section by fixed-point jumps
    and Broyden's steps (make_accelerators)."""
    key_of, striker_speed, rotor_angle = c.key, c.striker_speed, c.model.rotor_angle
    smooth = c.smooth
    land, fixed_point, broyden = make_accelerators(c)
    record = make_record(c)

    @njit(**INNER_OPTIONS)
    def transient(p, data, r, settings, repeat_tol, log, t, y, history, known):
        no_tangent = np.empty((5, 0))  # the transient's sections carry no tangent
        smooth_2d = not jump_early and smooth and history.shape[1] == 2
        a = Acceleration(jumped_at=1, secant=False, converged=False, jac=(0.0, 0.0, 0.0, 0.0),
                         x_secant=(0.0, 0.0), f_secant=(0.0, 0.0), t_orbit=t, y_orbit=y,
                         first_jump=0, x_rest=(0.0, 0.0))
        # int(): a literal 0 would compile record for the literal too (kernels/__init__.py)
        count, period, cost, jumped = int(0), int(0), NO_COST, False
        speculative = no_cycle(SEQUENCE_MAX_STEPS, False, 0, NO_COST, key_of(t, y, data, p))
        while count <= settings.max_impacts:
            key = record(t, y, data, p, history, count, log)
            count += 1
            hit = -1
            if known_cycles:  # its own test, so that numba prunes it for a single start
                hit = known_attractor(known, key)
                if hit < 0:  # captured on its way: the cycle's own state stands for it
                    hit = captured_by(known, history, count)
                    if hit >= 0:
                        key = from_row(key, known[hit], int(KNOWN.key))
            period = classify_period(history, count, repeat_tol, MAX_PERIOD)
            # on a cycle found before: that attractor (its values are known); or, away from
            # the accelerators' jumps, a sequence as not periodic as its budget would find it
            if hit >= 0 or (period == 0 and not a.secant and 2 * a.jumped_at < count
                            and settles_nowhere(history, count, settings, repeat_tol)):
                return ended(on_known(known[hit], key, count, cost) if hit >= 0 else no_cycle(
                    SEQUENCE_NOT_PERIODIC, False, settings.max_impacts, cost, key),
                    count, t, y, data, a)
            # right after a transient jump, one section more: Aitken at the end needs three
            # sections of the map's own (a jumped state's section repeats it only to tol)
            if period > 0 and not (a.jumped_at > 1 and count < a.jumped_at + 2):
                break
            # an affine map of slope r = 0 is constant: its first section is the cycle
            constant = jump_early and r == 0.0
            refine = bool(constant)  # bool(): see kernels/__init__.py
            if smooth:  # its own test, so that numba prunes the jumps of a map without them
                if a.secant and count == a.jumped_at + 1:
                    a, t, y = broyden(a, history, count, t, y, data, p, repeat_tol)
                    if a.converged:
                        period = 1
                        break
                elif smooth_2d and count - a.jumped_at >= 3:
                    a, t, y = fixed_point(a, history, count, t, y, data, p)
            if jump_early and count == 3:  # the next section, refined, is to confirm it
                t, y = land(aitken_jump(history, 2), t, y, data, p, history, count - 1)
                refine = jumped = True
            speed = striker_speed(t, y, data, p)
            t_start, phi_start = t, rotor_angle(t, y)
            s = section(t, y, data, p, r, settings, refine, no_tangent, int(0))
            cost = add(cost, s.cost)
            if s.outcome != SEQUENCE_CYCLE:
                return ended(no_cycle(s.outcome, s.chatter, count, cost,
                                      key_of(t, y, data, p)), count, t, y, data, a)
            t, y, data = s.t, s.y, s.data
            if refine:
                # one impact a cycle on a smooth map: no edge, the multiplier in closed form
                speculative = Steady(
                    outcome=SEQUENCE_CYCLE, period=1, chatter=s.chatter,
                    amplitude=s.amplitude, flight_time=s.flight_time,
                    rotor_angle=rotor_angle(t, y) - phi_start, elapsed=t - t_start,
                    speed=speed, peak=s.peak, impacts=0, cost=NO_COST,
                    margins=Margins(speed, speed, math.inf, math.nan, math.nan),
                    key=key_of(t, y, data, p))
            if constant:
                return ended(Steady(
                    outcome=SEQUENCE_CYCLE, period=1, chatter=s.chatter,
                    amplitude=s.amplitude, flight_time=s.flight_time,
                    rotor_angle=speculative.rotor_angle, elapsed=speculative.elapsed,
                    speed=striker_speed(t, y, data, p), peak=s.peak, impacts=1, cost=cost,
                    margins=speculative.margins, key=speculative.key), count, t, y, data, a)
        return Transient(ended=bool(False), steady=speculative, count=count, period=period, t=t,
                         y=y, data=data, cost=cost, acceleration=a, jumped=jumped)

    return transient


def make_steady(c, jump_early, transient, cycle, second_stage=True):
    """The whole sequence of a Contact: ``steady(p, data, r, settings, repeat_tol, log,
    start, known) -> (Steady, t, y, data)`` from a starting state (see the module
    docstring), and ``settle(p, data, r, settings, repeat_tol, log, t, y, known)`` the
    same from the state (t, y, data); each also returns the state its cycle ran from."""
    first, key_of, from_key, smooth = c.first, c.key, c.from_key, c.smooth

    # one caller (steady) where no second stage goes on from a state: inlined into it, one
    # function fewer to compile
    @njit(**(INNER_OPTIONS if second_stage else INLINE_OPTIONS))
    def settle(p, data, r, settings, repeat_tol, log, t, y, known):
        """The sequence from (t, y, data) to its steady cycle, within settings.max_impacts,
        its cycle's section states repeating to ``repeat_tol``; log[j] gets (rotor angle
        mod 2 pi, psi) at section j (the last row takes any beyond). It stops at a section
        state of a cycle in ``known`` (known_attractor), and reports that cycle's outcome,
        period, chatter and this section state, without its values. Returns the Steady and
        the state on the cycle its values were run from (where the sequence ended, without
        one)."""
        history = np.empty((settings.max_impacts + 2, len(key_of(t, y, data, p))))
        tr = transient(p, data, r, settings, repeat_tol, log, t, y, history, known)
        if tr.ended:
            return tr.steady, tr.t, tr.y, tr.data
        count, period, a, cost = tr.count, tr.period, tr.acceleration, tr.cost
        t, y, data = tr.t, tr.y, tr.data
        impacts = count - 2 * period
        if smooth:  # (a map without jumps: pruned, as in the transient)
            if a.first_jump > 0 and period == 1:  # the impacts from rest, not the sections
                impacts = impacts_past_jump(a.jac, a.first_jump - 1, a.x_rest,
                                            (history[count - 1, 0], history[count - 1, 1]),
                                            repeat_tol, IMPACTS_COUNTED)
        if period == 0:
            return no_cycle(not_periodic(history, count), False, settings.max_impacts, cost,
                            key_of(t, y, data, p)), t, y, data
        if tr.jumped and period == 1 and tr.steady.outcome == SEQUENCE_CYCLE:
            return of_cycle(1, tr.steady, impacts, cost), t, y, data
        # the steady cycle from where the sequence is (on the cycle, to tol); at period 1 on
        # a smooth map from Aitken's extrapolation of the last three sections instead, kept
        # if the cycle's residual beats the last iteration's step (H13)
        last_step = 0.0
        for i in range(history.shape[1]):
            last_step = max(last_step, abs(history[count - 1, i] - history[count - 2, i]))
        t_run, y_run = t, y
        extrapolated = False
        if smooth:
            extrapolated = period == 1 and count >= 3 and not jump_early and not a.converged
            if extrapolated:
                t_run, y_run = from_key(aitken_jump(history, count - 1), t, y, data, p)
        result = cycle(t_run, y_run, data, p, r, settings, period)
        cost = add(cost, result.cost)
        if extrapolated and result.residual > last_step:
            t_run, y_run = t, y
            result = cycle(t, y, data, p, r, settings, period)
            cost = add(cost, result.cost)
        if a.converged and result.residual > repeat_tol * max(
                1.0, abs(history[count - 1, 0]), abs(history[count - 1, 1])):
            t_run, y_run = a.t_orbit, a.y_orbit
            result = cycle(a.t_orbit, a.y_orbit, data, p, r, settings, period)
            cost = add(cost, result.cost)
        if result.outcome != SEQUENCE_CYCLE:  # the cycle did not repeat after all
            return (no_cycle(SEQUENCE_MAX_STEPS, result.chatter, impacts, cost, result.key),
                    t_run, y_run, data)
        return of_cycle(period, result, impacts, cost), t_run, y_run, data

    @njit(**INNER_OPTIONS)
    def steady(p, data0, r, settings, repeat_tol, log, start, known):
        """The sequence from starting state number ``start`` (0: at rest, the tool's
        ``first``), as ``settle``."""
        t, y, data = first(p, data0, start)
        return settle(p, data, r, settings, repeat_tol, log, t, y, known)

    return steady, settle
