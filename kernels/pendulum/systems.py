"""The six pendulum systems, models x tools, each the integration core's impact map
specialised to it, and a block function that solves the cases of one system.

Each block function is module level (numba caches it on disk) and compiled only when a
sweep has a case of its system: a sweep of the paper model on the rotor stop never compiles
the rotor model on the blade.
"""

import math

from numba import njit

from kernels import KERNEL_OPTIONS, INNER_OPTIONS
from kernels.impact.impact_map import make_impact_map
from kernels.impact.outcomes import SEQUENCE_CYCLE, Settings
from kernels.impact.runge_kutta import METHOD_DOPRI5
from kernels.pendulum import models, tools
from kernels.pendulum.cases import C, ROW


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
def stop_data(case):
    return 0.0, case[C.k]  # the stop at psi = 0


@njit(**KERNEL_OPTIONS)
def blade_data(case):
    return (-tools.TWO_PI, case[C.tool_window], case[C.k], 0.0, 1.0)


def make_block(contact, jump_early, parameters, data_of, frequency):
    """The block function of a system: each case's steady state into its row (ROW), and
    into ``log`` the section impacts (rotor angle mod 2 pi, psi) of the last case.
    ``frequency``: whether flights end where they started (the rotor stop), so that pi over
    the flight time is the free oscillation's frequency coefficient."""
    steady = make_impact_map(contact, jump_early).steady
    horizon = contact.horizon

    @njit(**INNER_OPTIONS)
    def block(cases, method, rtol, atol, dt, max_impacts, rows, log):
        settings = Settings(method, rtol, atol, dt, 10 ** 6, horizon)
        # section states repeat to 10 rtol (DOPRI5), or to 1e-9 at RK4's fixed step
        tol = max(10.0 * rtol, 1e-12) if method == METHOD_DOPRI5 else 1e-9
        for c in range(cases.shape[0]):
            case = cases[c]
            row = rows[c]
            for j in range(row.shape[0]):
                row[j] = math.nan
            s = steady(parameters(case), data_of(case), case[C.R], settings, max_impacts, tol,
                       log)
            row[ROW.outcome] = s.outcome
            row[ROW.steps] = s.cost.steps + s.cost.rejected
            row[ROW.rejected] = s.cost.rejected
            row[ROW.events] = s.cost.events
            row[ROW.impacts] = s.impacts
            if s.outcome != SEQUENCE_CYCLE:
                continue
            row[ROW.period] = s.period
            row[ROW.chatter] = 1.0 if s.chatter else 0.0
            row[ROW.amplitude] = s.amplitude
            row[ROW.frequency] = (math.pi * s.period / s.flight_time if frequency else
                                  math.nan)
            row[ROW.interval] = s.rotor_angle / s.period
            row[ROW.speed] = s.speed / s.period
            row[ROW.acceleration] = s.peak
            row[ROW.rotor_speed] = s.rotor_angle / s.elapsed

    return block


_paper_stop = make_block(tools.rotor_stop(models.PAPER), True, paper_parameters, stop_data,
                         True)
_rigid_stop = make_block(tools.rotor_stop(models.RIGID), True, rigid_parameters, stop_data,
                         True)
_rotor_stop = make_block(tools.rotor_stop(models.ROTOR), False, rotor_parameters, stop_data,
                         True)
_paper_blade = make_block(tools.lab_window(models.PAPER), False, paper_parameters,
                          blade_data, False)
_rigid_blade = make_block(tools.lab_window(models.RIGID), False, rigid_parameters,
                          blade_data, False)
_rotor_blade = make_block(tools.lab_window(models.ROTOR), False, rotor_parameters,
                          blade_data, False)


# module-level entry points: numba caches these on disk (a closure called from Python is
# recompiled in every process)
@njit(**KERNEL_OPTIONS)
def paper_on_stop(cases, method, rtol, atol, dt, max_impacts, rows, log):
    _paper_stop(cases, method, rtol, atol, dt, max_impacts, rows, log)


@njit(**KERNEL_OPTIONS)
def rigid_on_stop(cases, method, rtol, atol, dt, max_impacts, rows, log):
    _rigid_stop(cases, method, rtol, atol, dt, max_impacts, rows, log)


@njit(**KERNEL_OPTIONS)
def rotor_on_stop(cases, method, rtol, atol, dt, max_impacts, rows, log):
    _rotor_stop(cases, method, rtol, atol, dt, max_impacts, rows, log)


@njit(**KERNEL_OPTIONS)
def paper_on_blade(cases, method, rtol, atol, dt, max_impacts, rows, log):
    _paper_blade(cases, method, rtol, atol, dt, max_impacts, rows, log)


@njit(**KERNEL_OPTIONS)
def rigid_on_blade(cases, method, rtol, atol, dt, max_impacts, rows, log):
    _rigid_blade(cases, method, rtol, atol, dt, max_impacts, rows, log)


@njit(**KERNEL_OPTIONS)
def rotor_on_blade(cases, method, rtol, atol, dt, max_impacts, rows, log):
    _rotor_blade(cases, method, rtol, atol, dt, max_impacts, rows, log)


#: the block function of each (model, tool), by their codes
SYSTEMS = {(models.MODEL_PAPER, 0): paper_on_stop, (models.MODEL_RIGID, 0): rigid_on_stop,
           (models.MODEL_ROTOR, 0): rotor_on_stop, (models.MODEL_PAPER, 1): paper_on_blade,
           (models.MODEL_RIGID, 1): rigid_on_blade, (models.MODEL_ROTOR, 1): rotor_on_blade}
