"""The pendulum systems of the table (kernels/pendulum/table.py), each the integration
core's impact map specialised to it, and a block function that solves the cases of one
system.

Each system's entry points are made here from the table, as module-level functions (numba
caches them on disk), on first lookup, and compiled only when a sweep has a case of its
system and method: a sweep of the paper model on the rotor stop never makes or compiles the
rotor model on the blade, and one by DOPRI5 never compiles DOP853 (``entry_point``).
"""

import math
import threading
from collections.abc import Mapping

import numpy as np
from numba import njit

from kernels import KERNEL_OPTIONS, INLINE_OPTIONS, INNER_OPTIONS
from kernels.cache import module_level
from kernels.impact.attractors import (ATTRACTOR_TOL, KNOWN, known_attractor,
                                      relative_distance)
from kernels.impact.impact_map import make_impact_map, with_cost
from kernels.impact.outcomes import SEQUENCE_CYCLE, SEQUENCE_MAX_STEPS, Settings, add
from kernels.impact.runge_kutta import METHOD_DOP853, METHOD_RK4, OTHER_METHODS, low_order
from kernels.pendulum import blade, models, tools
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


#: the rows of a case's two stages (auto's coarser and finer solve)
FIRST_STAGE, SECOND_STAGE = range(2)
#: the longest section state of a tool (the blade's: psi, the gap's rate, the rotor speed)
MAX_KEY = 3


def make_block(contact, jump_early, parameters, data_of, frequency, stability=False,
               methods=OTHER_METHODS, two_stage=True, several_starts=True):
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
    in."""
    high_order = METHOD_DOP853 in methods
    driver = make_impact_map(contact, jump_early, stability, several_starts, two_stage,
                             methods)
    steady, settle = driver.steady, driver.settle

    # one stage: a call of steady, inlined (one function fewer to compile)
    @njit(**(INNER_OPTIONS if two_stage else INLINE_OPTIONS))
    def solve_start(p, data, r, settings, finer, tols, log, start, known, scratch):
        """(the Steady of a start, that of its first stage) (see block); ``scratch``: a
        one-row log for the second stage, whose sections stay out of ``log``. A regime
        without a cycle is the first stage's, unless it is undetermined (the budget ran
        out while the sequence still converged); where the second stage does not confirm
        the first one's cycle (its period and chatter), the finer solve starts again,
        except from rest where auto's next round follows (settings.accept < inf): that
        round starts with the same solve."""
        tol_first, tol_finer = tols
        first, t, y, d = steady(p, data, r, settings, tol_first, log, start, known)
        if not two_stage:  # its own test, so that numba prunes the second stage away
            return first, first
        cycle = first.outcome == SEQUENCE_CYCLE
        if settings.finer_by <= 1.0 or not (cycle or first.outcome == SEQUENCE_MAX_STEPS):
            return first, first
        if several_starts:  # (pruned for a single start: no other start's cycles)
            if cycle and known_attractor(known, first.key) >= 0:
                return first, first  # on a cycle another start found: its second stage ran
        cost = first.cost
        if cycle:
            then, t_then, y_then, d_then = settle(p, d, r, finer, tol_finer, scratch, t, y,
                                                  known)
            cost = add(cost, then.cost)
            if (then.outcome == SEQUENCE_CYCLE and then.period == first.period
                    and then.chatter == first.chatter):
                return with_cost(then, first.impacts, cost), first
            if start == 0 and settings.accept < math.inf:
                # auto's next solve follows (Settings.accept), its first stage the finer
                # solve from the start below: the two rows disagree, which sends the case
                # there, so that sequence is flown once
                return with_cost(then, first.impacts, cost), first
        # undetermined, or not the first stage's cycle where it went on from it (a slow
        # drift taken for a cycle, a chatter that settles otherwise): the finer solve from
        # the start, as the first stage ran
        again, t_again, y_again, d_again = steady(p, data, r, finer, tol_finer, scratch,
                                                  start, known)
        return with_cost(again, again.impacts, add(cost, again.cost)), first

    @njit(**INNER_OPTIONS)
    def block(cases, settings, rows, first_rows, log):
        method = settings.method if high_order else low_order(settings.method)
        finer_by = max(settings.finer_by, 1.0)
        finer = scaled_settings(settings, method, finer_by, 0.0)
        settings = scaled_settings(settings, method, 1.0, settings.finer_by)
        tols = (section_repeat_tol(settings.method, settings.rtol),
                section_repeat_tol(finer.method, finer.rtol))
        starts = settings.starts
        # per start: its steady state in the columns of attractors.KNOWN
        seen = np.empty((starts, KNOWN.key + MAX_KEY))
        scratch = np.empty((1, 2))
        pair = np.empty((2, N_ROW))  # the rows of the first start's two stages
        for c in range(cases.shape[0]):
            case = cases[c]
            row = rows[c]
            p, data, r = parameters(case), data_of(case), case[C.R]
            s, first = solve_start(p, data, r, settings, finer, tols, log, int(0), seen[:0],
                                   scratch)
            cost = s.cost
            attractors, basin = 1.0, 1.0
            # its own test, so that numba prunes the other starts for a single one
            if several_starts:
                # a case solved again finer (its estimate misses settings.accept) counts
                # its attractors only in the solve it ends in
                write_row(pair[FIRST_STAGE], first, first.cost, 1.0, 1.0, frequency)
                write_row(pair[SECOND_STAGE], s, s.cost, 1.0, 1.0, frequency)
                again = cycle_error(pair[FIRST_STAGE], pair[SECOND_STAGE],
                                    settings.margins) > settings.accept
                if again:
                    attractors, basin = math.nan, math.nan
                elif starts > 1:
                    n_keys = len(s.key)
                    remember(seen, int(0), s)
                    distinct, same = int(1), int(1)
                    for j in range(1, starts):
                        # a start stops on a cycle another start found: the same attractor
                        other = solve_start(p, data, r, settings, finer, tols, log, j,
                                            seen[:distinct], scratch)[0]
                        cost = add(cost, other.cost)
                        remember(seen, distinct, other)
                        if _same_attractor(seen, int(0), distinct, n_keys):
                            same += 1
                        new = True
                        for i in range(distinct):
                            if _same_attractor(seen, i, distinct, n_keys):
                                new = False
                                break
                        if new:
                            distinct += 1
                    attractors, basin = float(distinct), same / starts
            write_row(row, s, cost, attractors, basin, frequency)
            write_row(first_rows[c], first, first.cost, attractors, basin, frequency)

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
    for i in range(len(s.key)):
        row[ROW.section_0 + i] = s.key[i]


@njit(**INLINE_OPTIONS)
def remember(seen, j, s):
    """A start's Steady ``s`` into row j of ``seen`` (columns attractors.KNOWN)."""
    seen[j, KNOWN.outcome], seen[j, KNOWN.period] = s.outcome, s.period
    seen[j, KNOWN.chatter] = 1.0 if s.chatter else 0.0
    for i in range(len(s.key)):
        seen[j, KNOWN.key + i] = s.key[i]


@njit(**KERNEL_OPTIONS)
def _same_attractor(seen, a, b, n_keys):
    """Rows a and b of ``seen`` (columns attractors.KNOWN): the same attractor? A sequence
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
#: each tool's contact factory, by the table's names
TOOL_CONTACTS = {"rotor_stop": tools.rotor_stop, "lab_window": blade.lab_window}
#: the methods compiled into a contact's flights beside DOPRI5 (and the exact flow), one
#: variant each: none, DOP853 (tight tol), RK4 (asked for)
COMPILED = ((), (METHOD_DOP853,), (METHOD_RK4,))


class Lazy(Mapping):
    """A table whose keys are known at import and whose values are made on first lookup,
    once (under a lock: blocks run on threads), by ``make(*key)``. Each value is a tree of
    numba functions; making every system's variants at import (each method, stage and
    start variant) cost a sweep process more CPU time than loading the one cached kernel
    it runs (docs/performance.md). Only what a sweep looks up is made."""

    def __init__(self, keys, make):
        self._keys = tuple(keys)
        self._known, self._make, self._made = frozenset(self._keys), make, {}
        self._lock = threading.Lock()

    def __getitem__(self, key):
        made = self._made.get(key)
        if made is None:
            if key not in self._known:
                raise KeyError(key)
            with self._lock:
                made = self._made.get(key)
                if made is None:
                    made = self._made[key] = self._make(*key)
        return made

    def __contains__(self, key):
        return key in self._known

    def __iter__(self):
        return iter(self._keys)

    def __len__(self):
        return len(self._keys)


def _contact(model, tool, methods):
    return TOOL_CONTACTS[tool](getattr(models, model.upper()), methods)


#: each system's contact (the core's description of it), by the table's names and COMPILED
CONTACTS = Lazy(((s.model, s.tool, methods) for s in SYSTEMS for methods in COMPILED),
                _contact)
#: a flight's step budget
MAX_STEPS = 10 ** 6
#: the first section count at which a sequence may be called not periodic before its
#: budget of impacts (verdicts.settles_nowhere)
VERDICT_FROM = 64


def build_block(system, contact, parameters, data_of, stability=False, returning=None,
                methods=OTHER_METHODS, two_stage=True, several_starts=True):
    """The block function of a table row (kernels/pendulum/table.py) from its contact,
    its parameters and system data of a case; ``returning``: whether its flights end
    where they started (default: its tool is one of table.RETURNING_TOOLS);
    ``methods``: those the contact's flights have beside DOPRI5; ``two_stage``: whether
    auto's second stage is compiled in; ``several_starts``: whether a case may run from
    several starts (make_block)."""
    returning = system.tool in RETURNING_TOOLS if returning is None else returning
    return make_block(contact, system.affine, parameters, data_of, returning, stability,
                      methods, two_stage, several_starts)


def _system_entry_point(system, tangent, methods, two_stage, several_starts):
    """A module-level entry point (cache.module_level), cached on disk by its name."""
    block = build_block(system, CONTACTS[system.model, system.tool, methods],
                        PARAMETERS[system.model], DATA[system.tool], stability=tangent,
                        methods=methods, two_stage=two_stage, several_starts=several_starts)
    return module_level(block, entry_name(system, tangent, methods, two_stage,
                                          several_starts), globals(), KERNEL_OPTIONS)


#: the entry points of each system (a table row) by (system, tangent, methods, two_stage,
#: several_starts): with the tangent where its multipliers need it (elsewhere they are known
#: in closed form), with DOP853 or RK4 compiled in beside DOPRI5 (COMPILED: DOP853's code
#: made the first run of every example 1.02-1.06x longer, RK4's the stability example's
#: 4 CPU s of 64), with auto's second stage (about a tenth of the blade
#: example's first run, whose exact flights never take it), and with several starts (the
#: search for other starts' cycles is compiled only where a sweep asks for attractors)
ENTRY_POINTS = Lazy(((system, tangent, methods, two, several) for system in SYSTEMS
                     for methods in COMPILED
                     for tangent in ((False, True) if system.tangent else (False,))
                     for two in (False, True) for several in (False, True)),
                    _system_entry_point)


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
