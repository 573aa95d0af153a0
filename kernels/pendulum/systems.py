"""The pendulum systems of the table (kernels/pendulum/table.py), each the integration
core's impact map specialised to it, and a block function that solves the cases of one
system.

Each system's entry points are made here from the table, module level (numba caches them
on disk), and compiled only when a sweep has a case of its system and method: a sweep of the
paper model on the rotor stop never compiles the rotor model on the blade, and one by DOPRI5
never compiles DOP853 (``entry_point``).
"""

import math
from collections import namedtuple

import numpy as np
from numba import njit

from kernels import KERNEL_OPTIONS, INLINE_OPTIONS, INNER_OPTIONS
from kernels.impact.impact_map import (ATTRACTOR_TOL, KNOWN, UNDER_WAY, known_attractor,
                                       make_impact_map, relative_distance, with_cost)
from kernels.impact.lanes import advance, layout, load, make_trial, outcome
from kernels.impact.tuples import replacer
from kernels.impact.outcomes import (NO_COST, SEQUENCE_CYCLE, SEQUENCE_MAX_STEPS, Settings,
                                     add)
from kernels.impact.runge_kutta import METHOD_DOP853, METHOD_RK4, OTHER_METHODS, low_order
from kernels.pendulum import models, tools
from kernels.pendulum.accuracy import cycle_error
from kernels.pendulum.cases import C, N_ROW, ROW
from kernels.pendulum.table import RETURNING_TOOLS, SYSTEMS, entry_name


@njit(**KERNEL_OPTIONS)
def section_repeat_tol(method, rtol):
    """The relative tolerance to which a cycle's section states must repeat: 10 rtol
    (DOPRI5, the closed-form flight), at least 1e-12, or 1e-9 at RK4's fixed step."""
    return max(10.0 * rtol, 1e-12) if method != METHOD_RK4 else 1e-9


@njit(**KERNEL_OPTIONS)
def paper_parameters(case):
    return case[C.k], case[C.xi]


@njit(**KERNEL_OPTIONS)
def rigid_parameters(case):
    return case[C.k], case[C.kappa]


@njit(**KERNEL_OPTIONS)
def rotor_parameters(case):
    """(k_cm, xi, J1/J_c, s_m, idle): the contact point follows kappa as in the rigid model,
    lambda = kappa (1 + 1/xi) = l_contact/l_cm and k_cm = k lambda, so that a heavy rotor
    with a steep motor tends to the rigid model with the same k and kappa."""
    lam = case[C.kappa] * (1.0 + 1.0 / case[C.xi])
    return (case[C.k] * lam, case[C.xi], case[C.rotor_inertia_ratio], case[C.motor_slope],
            case[C.idle_speed])


@njit(**KERNEL_OPTIONS)
def rotor_stop_data(case):
    return 0.0, case[C.k]  # the stop at psi = 0


@njit(**KERNEL_OPTIONS)
def lab_window_data(case):
    return (-tools.TWO_PI, case[C.tool_window], case[C.k], 0.0, 1.0)


#: the longest section state of a tool (the blade's: psi, the gap's rate, the rotor speed)
MAX_KEY = 3


#: a case in its lane (make_block): its index, parameters, system data and restitution;
#: the start being solved and the stage of its solve (STAGE_*), the first stage's Steady,
#: the state it ran its cycle from and the cost of the start's solve so far; the case's
#: solve from rest (start 0: its Steady and its first stage's), the cost of all its
#: starts, its distinct attractors so far, the starts that reached the one from rest, and
#: what the case reports of them
CaseState = namedtuple("CaseState", [
    "case", "p", "data", "r", "start", "stage", "first", "t", "y", "d", "cost", "steady",
    "steady_first", "case_cost", "distinct", "same", "attractors", "basin"])
case_with = replacer(CaseState)
#: the stages of a start's solve (block): the first (from the start, at the block's
#: settings), the second (on from the first one's cycle, finer), the finer solve again
#: from the start
STAGE_FIRST, STAGE_ON, STAGE_AGAIN = 1, 2, 3
#: where a lane's case is (make_block's drive): a flight just ended, a section at its next
#: contact, a section ended, the transient before its next section, the next case to take
FLOWN, CONTACT, SECTION_ENDED, TRANSIENT, NEXT_CASE = range(5)


def make_block(contact, jump_early, parameters, data_of, frequency, stability=False,
               methods=OTHER_METHODS, two_stage=True, several_starts=True, lanes=1):
    """The block function of a system, ``block(cases, settings, rows, first_rows, log)``:
    each case's steady state into its row (ROW), and into ``log`` the section impacts
    (rotor angle mod 2 pi, psi) of the last case. ``frequency``: whether flights end where
    they started (the rotor stop), so that pi over the flight time is the free
    oscillation's frequency coefficient. ``stability``: carry the tangent through the
    steady cycle for its multipliers. With ``settings.starts`` > 1 each case is also run
    from starts - 1 more starting states (the tool's ``first``), and the distinct
    attractors they reach are counted. With ``settings.finer_by`` > 1 each sequence that
    reaches a cycle goes on from it at rtol and atol finer_by times smaller: ``rows`` get
    that second stage's values, ``first_rows`` the first's (else the same). ``methods``:
    those the contact's flights have beside DOPRI5; without DOP853, DOP853 asked for is
    DOPRI5 (runge_kutta.low_order), its step-size control included; without RK4, RK4 is
    never asked for (entry_point). Without ``two_stage`` the
    second stage is not compiled in, and every solve is the first stage's whatever
    settings.finer_by: the solves that never take it (exact flights, a forced method) do
    not pay for its compile. Without ``several_starts`` each case runs from rest only,
    whatever settings.starts, and the search for other starts' cycles is not compiled
    in.

    ``lanes``: the cases solved at once, each in its lane; their flights take their steps
    together (kernels/impact/lanes.py), and a lane whose case is done takes the next one.
    A case's sequences, the transients and their sections, are the driver's in parts
    (impact_map.SequenceParts); its cycles, slides and tangent are solved in its lane as
    they come, one flight at a time. A case's bits do not depend on its lane or on the
    other cases."""
    high_order = METHOD_DOP853 in methods
    driver = make_impact_map(contact, jump_early, stability, several_starts, methods)
    # bound to names: numba inlines a closure's function (INLINE_OPTIONS), not a tuple's
    (begin, top, bottom, settle, section_begin, section_contact,
     section_flown) = driver.sequence
    flight_begin, flight_after = contact.flight.begin, contact.flight.after
    flight_data, first_state = contact.flight_data, contact.first
    trial = make_trial(contact.flight, lanes, methods)

    @njit(**INNER_OPTIONS)
    def finish_start(lane, cs, s, first, settings, starts, seen, pair, rows, first_rows,
                     n_cases):
        """The case after its start ``cs.start`` came to ``s`` (its first stage to
        ``first``): (cs, more), ``more`` where another start follows, else its rows are
        written."""
        more = False
        if cs.start == 0:
            cs = case_with(cs, steady=s, steady_first=first, case_cost=s.cost, attractors=1.0,
                             basin=1.0)
            # its own test, so that numba prunes the other starts for a single one
            if several_starts:
                # a case solved again finer (its estimate misses settings.accept) counts
                # its attractors only in the solve it ends in
                write_row(pair[lane, 0], first, first.cost, 1.0, 1.0, frequency)
                write_row(pair[lane, 1], s, s.cost, 1.0, 1.0, frequency)
                if cycle_error(pair[lane, 0], pair[lane, 1], settings.margins) > settings.accept:
                    cs = case_with(cs, attractors=math.nan, basin=math.nan)
                elif starts > 1:
                    remember(seen[lane], int(0), s)
                    cs = case_with(cs, distinct=int(1), same=int(1))
                    more = True
        else:
            # a start stops on a cycle another start found: the same attractor
            known = seen[lane]
            distinct, same = cs.distinct, cs.same
            remember(known, distinct, s)
            n_keys = len(s.key)
            if _same_attractor(known, int(0), distinct, n_keys):
                same += 1
            new = True
            for i in range(distinct):
                if _same_attractor(known, i, distinct, n_keys):
                    new = False
                    break
            if new:
                distinct += 1
            cs = case_with(cs, case_cost=add(cs.case_cost, s.cost), distinct=distinct,
                             same=same)
            more = cs.start + 1 < starts
            if not more:
                cs = case_with(cs, attractors=float(distinct), basin=same / starts)
        if not more:
            write_row(rows[cs.case], cs.steady, cs.case_cost, cs.attractors, cs.basin,
                      frequency)
            write_row(first_rows[cs.case], cs.steady_first, cs.steady_first.cost,
                      cs.attractors, cs.basin, frequency)
        return cs, more

    @njit(**INNER_OPTIONS)
    def next_stage(cs, steady, t, y, d, settings, known):
        """The start's solve after its stage ``cs.stage`` came to ``steady`` (its cycle run
        from (t, y, d)): (cs, done, s, first), the start's Steady and its first stage's
        where ``done``, else cs at its next stage. A regime without a cycle is the first
        stage's, unless it is undetermined (the budget ran out while the sequence still
        converged); where the second stage does not confirm the first one's cycle (its
        period and chatter), the finer solve starts again, except from rest where auto's
        next round follows (settings.accept < inf): that round starts with the same
        solve."""
        if cs.stage == STAGE_FIRST:
            first = steady
            if not two_stage:  # its own test, so that numba prunes the second stage away
                return cs, True, first, first
            cycle = first.outcome == SEQUENCE_CYCLE
            if settings.finer_by <= 1.0 or not (cycle or first.outcome == SEQUENCE_MAX_STEPS):
                return cs, True, first, first
            if several_starts:  # (pruned for a single start: no other start's cycles)
                if cycle and known_attractor(known, first.key) >= 0:
                    return cs, True, first, first  # on a cycle another start found
            cs = case_with(cs, first=first, t=t, y=y, d=d, cost=first.cost,
                             stage=STAGE_ON if cycle else STAGE_AGAIN)
            return cs, False, first, first
        if cs.stage == STAGE_ON:
            then, first = steady, cs.first
            cost = add(cs.cost, then.cost)
            if ((then.outcome == SEQUENCE_CYCLE and then.period == first.period
                 and then.chatter == first.chatter)
                    or (cs.start == 0 and settings.accept < math.inf)):
                # (from rest where auto's next solve follows, Settings.accept: its first
                # stage is the finer solve from the start below, and the two rows
                # disagree, which sends the case there, so that sequence is flown once)
                return cs, True, with_cost(then, first.impacts, cost), first
            # not the first stage's cycle where it went on from it (a slow drift taken
            # for a cycle, a chatter that settles otherwise): the finer solve from the
            # start, as the first stage ran
            return case_with(cs, cost=cost, stage=STAGE_AGAIN), False, then, first
        again = steady
        return (cs, True, with_cost(again, again.impacts, add(cs.cost, again.cost)),
                cs.first)

    @njit(**INNER_OPTIONS)
    def drive(lane, phase, fl, cases, settings, finer, tols, cases_at, transients,
              sections, flights, flying, history, seen, pair, buf, rows, first_rows, log,
              scratch, next_case):
        """Lane ``lane`` on from ``phase`` (``fl``: the flight that just ended, at FLOWN)
        until its next flight is under way (True: its state in ``flights``, its
        parameters and whether it is a finer stage's in ``flying``, its inputs in ``buf``)
        or no case is left (False)."""
        n_cases, starts = cases.shape[0], settings.starts
        no_tangent = np.empty((5, 0))
        cs, ts, ss = cases_at[lane], transients[lane], sections[lane]
        while True:
            first_stage = cs.stage == STAGE_FIRST
            now = settings if first_stage else finer
            if phase == FLOWN:
                ss = section_flown(ss, fl, cs.p, now, no_tangent, int(0))
                phase = CONTACT if ss.outcome == UNDER_WAY else SECTION_ENDED
            elif phase == CONTACT:
                ss = section_contact(ss, cs.p, cs.r, now, ts.refine, no_tangent, int(0))
                if ss.outcome != UNDER_WAY:
                    phase = SECTION_ENDED
                    continue
                st, ended, fl = flight_begin(ss.t, ss.y, cs.p, flight_data(ss.data), now,
                                            ts.refine)
                if ended:
                    phase = FLOWN
                    continue
                cases_at[lane], transients[lane], sections[lane], flights[lane] = (
                    cs, ts, ss, st)
                flying[lane] = (cs.p, not first_stage)
                load(buf, lane, lanes, st, cs.p, now)
                return True
            elif phase == SECTION_ENDED or phase == TRANSIENT:
                repeat_tol = tols[0] if first_stage else tols[1]
                known = seen[lane, :cs.distinct]
                over = False
                if phase == SECTION_ENDED:
                    ts, over, tr = bottom(ts, ss, cs.p, cs.r, now)
                if not over:
                    # the block's log takes the first stages of its last case (the others
                    # are not kept)
                    ts, over, tr = top(
                        ts, cs.p, cs.r, now, repeat_tol,
                        log if first_stage and cs.case == n_cases - 1 else scratch,
                        history[lane], known)
                if not over:
                    ss = section_begin(ts.t, ts.y, ts.data)
                    phase = CONTACT
                    continue
                steady, t, y, d = settle(tr, cs.p, cs.r, now, repeat_tol, history[lane])
                cs, done, s, first = next_stage(cs, steady, t, y, d, settings, known)
                if done:
                    cs, more = finish_start(lane, cs, s, first, settings, starts, seen, pair,
                                            rows, first_rows, n_cases)
                    if not more:
                        phase = NEXT_CASE
                        continue
                    cs = case_with(cs, start=cs.start + 1, stage=STAGE_FIRST)
                if cs.stage == STAGE_ON:  # on from the first stage's cycle
                    ts = begin(cs.p, cs.t, cs.y, cs.d)
                else:  # from the start
                    t, y, d = first_state(cs.p, cs.data, cs.start)
                    ts = begin(cs.p, t, y, d)
                phase = TRANSIENT
            else:  # NEXT_CASE
                c = next_case[0]
                if c >= n_cases:
                    cases_at[lane], transients[lane], sections[lane] = cs, ts, ss
                    return False
                next_case[0] = c + 1
                case = cases[c]
                cs = case_with(cs, case=c, p=parameters(case), data=data_of(case), r=case[C.R],
                                 start=int(0), stage=STAGE_FIRST, distinct=int(0),
                                 same=int(0))
                t, y, d = first_state(cs.p, cs.data, int(0))
                ts = begin(cs.p, t, y, d)
                phase = TRANSIENT

    @njit(**INNER_OPTIONS)
    def block(cases, settings, rows, first_rows, log):
        n_cases = cases.shape[0]
        if n_cases == 0:
            return
        method = settings.method if high_order else low_order(settings.method)
        finer_by = max(settings.finer_by, 1.0)
        finer = scaled_settings(settings, method, finer_by, 0.0)
        settings = scaled_settings(settings, method, 1.0, settings.finer_by)
        tols = (section_repeat_tol(settings.method, settings.rtol),
                section_repeat_tol(finer.method, finer.rtol))
        # each lane's case, transient, section and flight, first as the first case's
        p, data = parameters(cases[0]), data_of(cases[0])
        t, y, d = first_state(p, data, int(0))
        ts = begin(p, t, y, d)
        st, _, fl = flight_begin(t, y, p, flight_data(d), settings, bool(False))
        s = ts.speculative
        cs = CaseState(case=int(0), p=p, data=data, r=cases[0, C.R], start=int(0),
                       stage=STAGE_FIRST, first=s, t=t, y=y, d=d, cost=NO_COST, steady=s,
                       steady_first=s, case_cost=NO_COST, distinct=int(0), same=int(0),
                       attractors=1.0, basin=1.0)
        cases_at = [cs for _ in range(lanes)]
        transients = [ts for _ in range(lanes)]
        sections = [section_begin(t, y, d) for _ in range(lanes)]
        flights = [st for _ in range(lanes)]
        # each lane's flight: its parameters, and whether it is a finer stage's (its case's
        # record, read at every step, is far larger)
        flying = [(p, False) for _ in range(lanes)]
        history = np.empty((lanes, settings.max_impacts + 2, len(s.key)))
        seen = np.empty((lanes, settings.starts, KNOWN.key + MAX_KEY))
        pair = np.empty((lanes, 2, N_ROW))
        scratch = np.empty((1, 2))
        buf = np.empty(layout(y, p, st.data).size * lanes)
        for lane in range(lanes):  # a lane with no case steps the first one's start
            load(buf, lane, lanes, st, p, settings)
        next_case = np.zeros(1, np.int64)
        busy = np.zeros(lanes, np.bool_)
        for lane in range(lanes):
            busy[lane] = drive(lane, int(NEXT_CASE), fl, cases, settings, finer, tols,
                               cases_at, transients, sections, flights, flying, history,
                               seen, pair, buf, rows, first_rows, log, scratch, next_case)
        while busy.any():
            trial(buf, method, y, p, st.data)
            for lane in range(lanes):
                if not busy[lane]:
                    continue
                y1, f1, err, clear = outcome(buf, lane, lanes, y, p, st.data)
                p_lane, fine = flying[lane]
                now = flight_after(flights[lane], y1, f1, err, p_lane,
                                   finer if fine else settings, clear)
                flights[lane], ended, fl = now
                if not ended:
                    advance(buf, lane, lanes, now[0])
                    continue
                busy[lane] = drive(lane, int(FLOWN), fl, cases, settings, finer, tols,
                                   cases_at, transients, sections, flights, flying, history,
                                   seen, pair, buf, rows, first_rows, log, scratch,
                                   next_case)

    return block


@njit(**INLINE_OPTIONS)
def scaled_settings(s, method, by, finer_by):
    """Settings ``s`` by ``method`` at rtol and atol ``by`` times smaller."""
    return Settings(method=method, rtol=s.rtol / by, atol=s.atol / by, dt=s.dt,
                    max_steps=s.max_steps, horizon=s.horizon, max_impacts=s.max_impacts,
                    starts=s.starts, verdict_from=s.verdict_from, finer_by=finer_by,
                    accept=s.accept, margins=s.margins)


@njit(**INLINE_OPTIONS)
def write_row(row, s, cost, attractors, basin, frequency):
    """A case's result row (ROW) from its Steady ``s``, the cost of all its sequences and
    its attractors."""
    for j in range(row.shape[0]):
        row[j] = math.nan
    row[ROW.outcome] = s.outcome
    row[ROW.attractors], row[ROW.basin] = attractors, basin
    row[ROW.steps] = cost.steps + cost.rejected
    row[ROW.rejected] = cost.rejected
    row[ROW.events] = cost.events
    row[ROW.impacts] = s.impacts
    if s.outcome != SEQUENCE_CYCLE:
        return
    row[ROW.period] = s.period
    row[ROW.chatter] = 1.0 if s.chatter else 0.0
    row[ROW.amplitude] = s.amplitude
    row[ROW.frequency] = math.pi * s.period / s.flight_time if frequency else math.nan
    row[ROW.interval] = s.rotor_angle / s.period
    row[ROW.speed] = s.speed / s.period
    row[ROW.acceleration] = s.peak
    row[ROW.rotor_speed] = s.rotor_angle / s.elapsed
    m = s.margins
    row[ROW.speed_ratio] = m.speed_min / m.speed_max
    row[ROW.edge] = m.edge if math.isfinite(m.edge) else math.nan
    row[ROW.modulus], row[ROW.angle] = m.modulus, m.angle


@njit(**INLINE_OPTIONS)
def remember(seen, j, s):
    """A start's Steady ``s`` into row j of ``seen`` (columns impact_map.KNOWN)."""
    seen[j, KNOWN.outcome], seen[j, KNOWN.period] = s.outcome, s.period
    seen[j, KNOWN.chatter] = 1.0 if s.chatter else 0.0
    for i in range(len(s.key)):
        seen[j, KNOWN.key + i] = s.key[i]


@njit(**KERNEL_OPTIONS)
def _same_attractor(seen, a, b, n_keys):
    """Rows a and b of ``seen`` (columns impact_map.KNOWN): the same attractor? A sequence
    that ends without a cycle (escape, no impact, ...) is one attractor per outcome."""
    for i in range(KNOWN.key):
        if seen[a, i] != seen[b, i]:
            return False
    if seen[a, KNOWN.outcome] != SEQUENCE_CYCLE:
        return True
    keys = slice(KNOWN.key, KNOWN.key + n_keys)
    return not relative_distance(seen[a, keys], seen[b, keys], seen[a, keys]) > ATTRACTOR_TOL


PARAMETERS = {"paper": paper_parameters, "rigid": rigid_parameters,
               "rotor": rotor_parameters}
DATA = {"rotor_stop": rotor_stop_data, "lab_window": lab_window_data}
#: the methods compiled into a contact's flights beside DOPRI5 (and the exact flow), one
#: variant each: none, DOP853 (tight tol), RK4 (asked for)
COMPILED = ((), (METHOD_DOP853,), (METHOD_RK4,))
#: each system's contact (the core's description of it), by the table's names and COMPILED
CONTACTS = {(s.model, s.tool, methods): getattr(tools, s.tool)(
    getattr(models, s.model.upper()), methods) for s in SYSTEMS for methods in COMPILED}
#: a flight's step budget
MAX_STEPS = 10 ** 6
#: the cases a block of each model solves at once (make_block's lanes): several where the
#: model's step vectorises (no libm call in its right-hand side), else one
LANES = {"paper": 1, "rigid": 1, "rotor": 8}
#: the first section count at which a sequence may be called not periodic before its
#: budget of impacts (impact_map.settles_nowhere)
VERDICT_FROM = 64


def build_block(system, contact, parameters, data_of, stability=False, returning=None,
                methods=OTHER_METHODS, two_stage=True, several_starts=True, lanes=None):
    """The block function of a table row (kernels/pendulum/table.py) from its contact,
    its parameters and system data of a case; ``returning``: whether its flights end
    where they started (default: its tool is one of table.RETURNING_TOOLS);
    ``methods``: those the contact's flights have beside DOPRI5; ``two_stage``: whether
    auto's second stage is compiled in; ``several_starts``: whether a case may run from
    several starts; ``lanes``: the cases solved at once (default: LANES of its model)
    (make_block)."""
    returning = system.tool in RETURNING_TOOLS if returning is None else returning
    lanes = LANES[system.model] if lanes is None else lanes
    return make_block(contact, system.affine, parameters, data_of, returning, stability,
                      methods, two_stage, several_starts, lanes)


#: a module-level entry point: numba caches a function on disk by its name and source
#: file, and a closure called from Python would be compiled again in every process
_ENTRY = ("def {name}(cases, settings, rows, first_rows, log):\n"
          "    _{name}(cases, settings, rows, first_rows, log)\n")


def _entry_point(name: str, block):
    namespace = globals()
    namespace["_" + name] = block
    exec(compile(_ENTRY.format(name=name), __file__, "exec"), namespace)
    namespace[name] = njit(**KERNEL_OPTIONS)(namespace[name])
    return namespace[name]


#: the entry points of each system (a table row) by (system, tangent, methods, two_stage,
#: several_starts): with the tangent where its multipliers need it (elsewhere they are known
#: in closed form), with DOP853 or RK4 compiled in beside DOPRI5 (COMPILED: DOP853's code
#: made the first run of every example 1.02-1.06x longer, RK4's the stability example's
#: 4 CPU s of 64), with auto's second stage (about a tenth of the blade
#: example's first run, whose exact flights never take it), and with several starts (the
#: search for other starts' cycles is compiled only where a sweep asks for attractors)
ENTRY_POINTS = {}
for _system in SYSTEMS:
    for _methods in COMPILED:
        _args = (_system, CONTACTS[_system.model, _system.tool, _methods],
                 PARAMETERS[_system.model], DATA[_system.tool])
        for _tangent in (False, True) if _system.tangent else (False,):
            for _two in (False, True):
                for _several in (False, True):
                    ENTRY_POINTS[_system, _tangent, _methods, _two, _several] = _entry_point(
                        entry_name(_system, _tangent, _methods, _two, _several),
                        build_block(*_args, stability=_tangent, methods=_methods,
                                    two_stage=_two, several_starts=_several))


def entry_point(system, method, tangent=False, two_stage=False, starts=1):
    """The entry point that solves a system (a table row) by ``method`` (a core method
    code), with the tangent for the multipliers where asked for and the system needs it,
    with auto's second stage where asked for (settings.finer_by), and for ``starts``
    starting states per case (settings.starts)."""
    return ENTRY_POINTS[system, tangent and system.tangent, compiled_beside(method),
                        bool(two_stage), starts > 1]


def compiled_beside(method):
    """The methods an entry point solving by ``method`` has beside DOPRI5 (COMPILED): the
    method itself where it is DOP853 or RK4, else none."""
    return (method,) if method in OTHER_METHODS else ()


def settings_for(system, method, rtol, atol, dt, max_impacts, starts=1, finer_by=0.0,
                 accept=math.inf, margins=False):
    """The Settings of a solve on a system (a table row), by name."""
    return Settings(method=int(method), rtol=float(rtol), atol=float(atol), dt=float(dt),
                    max_steps=MAX_STEPS,
                    horizon=float(CONTACTS[system.model, system.tool, ()].horizon),
                    max_impacts=int(max_impacts), starts=int(starts),
                    verdict_from=VERDICT_FROM, finer_by=float(finer_by),
                    accept=float(accept), margins=bool(margins))
