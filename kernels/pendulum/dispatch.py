"""Which method solves each case of a block: the closed form where its system has one and
the method allows it, else the integration core on its system (kernels/pendulum/
systems.py, imported, and compiled, only when a block has a case of it), by the accuracy
policy (accuracy.py). Every choice is read from the table of systems (table.py)."""

import math

import numpy as np

from kernels.impact.outcomes import SEQUENCE_CYCLE, SEQUENCE_SEPARATRIX
from kernels.impact.runge_kutta import METHOD_DOP853, METHOD_DOPRI5, METHOD_EXACT, METHOD_RK4
from kernels.pendulum.accuracy import (auto_method, closed_form_estimate, exact_settings,
                                       solve_auto)
from kernels.pendulum.cases import N_ROW, ROW, C
from kernels.pendulum.closed_form import (closed_form_block, driven_stop_margins,
                                          driven_stop_preamble)
from kernels.pendulum.table import MODELS, SYSTEMS, TOOLS

INTEGRATOR_AUTO, INTEGRATOR_CLOSED, INTEGRATOR_RK4, INTEGRATOR_DOPRI5, INTEGRATOR_DOP853 = range(5)
USED_CLOSED, USED_RK4, USED_DOPRI5, USED_DOP853 = range(4)
#: the core's method of each fixed integrator, and the method_used flag of each method
FIXED = {INTEGRATOR_RK4: METHOD_RK4, INTEGRATOR_DOPRI5: METHOD_DOPRI5,
         INTEGRATOR_DOP853: METHOD_DOP853}
USED = {METHOD_EXACT: USED_CLOSED, METHOD_RK4: USED_RK4, METHOD_DOPRI5: USED_DOPRI5,
        METHOD_DOP853: USED_DOP853}
#: outputs that need the tangent of the steady cycle, the ones that need several starts,
#: and the cycle's margins (counted in auto's error estimate where asked for)
STABILITY_OUTPUTS = ("multiplier_modulus", "multiplier_angle", "stability_margin")
ATTRACTOR_OUTPUTS = ("attractor_count", "basin_fraction")
MARGIN_OUTPUTS = ("impact_speed_min_ratio", "edge_margin")


def solve_system(entry, cases, settings, first_stage=False):
    """The rows of the cases of one system, by its entry point, at these Settings; with
    ``first_stage``, also the rows of the first stage (settings.finer_by)."""
    out, first = np.empty((2, cases.shape[0], N_ROW))
    entry(cases, settings, out, first, np.empty((1, 2)))
    return (out, first) if first_stage else out


def _closed_form(cases, starts):
    """The rows of driven cases on the rotor stop, in closed form."""
    rows = np.empty((cases.shape[0], N_ROW))
    closed_form_block(cases, rows)
    rows[:, ROW.method] = USED_CLOSED
    rows[:, ROW.error] = closed_form_estimate(rows)
    driven_stop_margins(cases, rows, starts)
    return rows


def _integrated(system, cases, method, stability, starts):
    """The rows of the cases of one system by the integration core, as ``method`` asks."""
    from kernels.pendulum import systems
    from kernels.pendulum.systems import section_repeat_tol

    def solve(sub, method_code, rtol, atol, dt, finer_by=0.0, accept=math.inf,
              margins=False):
        entry = systems.entry_point(system, method_code, stability, finer_by > 0.0, starts)
        return solve_system(entry, sub, systems.settings_for(
            system, method_code, rtol, atol, dt, method.max_impacts, starts, finer_by,
            accept, margins), first_stage=finer_by > 0.0)

    # auto keeps DOPRI5's two stages where the multipliers are asked for: the tangent is
    # integrated, and its error needs their estimate (estimated_error)
    exact = system.exact_flow and (method.integrator == INTEGRATOR_CLOSED
                                   or method.integrator == INTEGRATOR_AUTO and not stability)
    rk4 = method.integrator == INTEGRATOR_RK4
    if exact:
        code = METHOD_EXACT
        rtol, atol, dt = exact_settings(method.tol)
        out = solve(cases, code, rtol, atol, dt)
        out[:, ROW.error] = closed_form_estimate(out, section_repeat_tol(code, rtol))
    elif method.integrator == INTEGRATOR_AUTO:
        code = auto_method(method.tol)
        out = solve_auto(solve, cases, method.tol,
                         bool(set(method.outputs) & set(MARGIN_OUTPUTS)))
    else:
        code = FIXED[method.integrator]
        out = solve(cases, code, method.rtol, method.atol, method.dt)
        out[:, ROW.error] = np.nan
    out[:, ROW.method] = USED[code]
    if system.closed_form:  # integrated anyway: what the closed form says all the same
        tol = 1e-9 if rk4 else max(10.0 * method.rtol, 1e-12)
        for j in range(cases.shape[0]):
            separatrix = driven_stop_preamble(cases[j], tol, out[j])[3]
            if separatrix:
                out[j, ROW.outcome] = SEQUENCE_SEPARATRIX
        cycle = out[:, ROW.outcome] == SEQUENCE_CYCLE
        out[:, ROW.modulus] = np.where(cycle, cases[:, C.R], np.nan)  # the affine map
        out[:, ROW.angle] = np.where(cycle, 0.0, np.nan)
    return out


def solve_cases(cases, method):
    """The result row (cases.ROW) of every case, in omega1 units, for the method record
    ``method`` (the spec's, with the outputs asked for): closed form where the case's system
    has one and the method allows it, else the integration core on its system; with
    multipliers asked for, the system's block that carries the tangent, where one is
    needed; with attractor outputs, method.starts starting states per case."""
    asked = set(method.outputs)
    stability = bool(asked & set(STABILITY_OUTPUTS))
    starts = method.starts if asked & set(ATTRACTOR_OUTPUTS) else 1
    rows = np.empty((cases.shape[0], N_ROW))
    model, tool = cases[:, C.model], cases[:, C.tool]
    for system in SYSTEMS:
        chosen = (model == MODELS[system.model]) & (tool == TOOLS[system.tool])
        if not chosen.any():
            continue
        sub = np.ascontiguousarray(cases[chosen])
        if system.closed_form and method.integrator <= INTEGRATOR_CLOSED:
            rows[chosen] = _closed_form(sub, starts)
        else:
            rows[chosen] = _integrated(system, sub, method, stability, starts)
    return rows
