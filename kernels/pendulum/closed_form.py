"""The closed form of the constant-speed models on the rotor stop ([RP], P-O6): the affine
impact map's fixed point v*, its escape threshold and transient, the flight from v* and the
margins, without a flight integrated."""

import math

import numpy as np
from numba import njit

from kernels import KERNEL_OPTIONS
from kernels.impact.attractors import radical_inverse
from kernels.impact.outcomes import SEQUENCE_CYCLE, SEQUENCE_ESCAPE, SEQUENCE_SEPARATRIX
from kernels.pendulum.cases import ROW, C
from kernels.pendulum.free_flight import (impacts_to_converge, paper_amplitude,
                                          paper_critical, paper_half_period,
                                          paper_peak_acceleration, rigid_critical,
                                          rigid_flight, steady_state_speed)
from kernels.pendulum.models import MODEL_PAPER

#: a launch speed within this (relative) of the escape threshold is on the separatrix: the
#: flight's time diverges like its logarithm, beyond what any method resolves (H1, H2)
SEPARATRIX = 64 * 2.220446049250313e-16


@njit(**KERNEL_OPTIONS)
def closed_flight(model, v, p):
    """A driven flight from psi = 0 at speed v back to psi = 0, in closed form: (amplitude,
    flight time, peak |psi''|); NaNs if it does not come back."""
    if model == MODEL_PAPER:
        k, xi = p
        amplitude = paper_amplitude(v, k, xi)
        return (amplitude, paper_half_period(v, k, xi, amplitude),
                paper_peak_acceleration(v, k, xi, amplitude))
    k, kappa = p
    return rigid_flight(v, k * kappa)



@njit(**KERNEL_OPTIONS)
def driven_stop_preamble(case, tol, row):
    """What the closed form says of a driven case on the rotor stop, before any flight:
    R_crit, the impacts the affine map needs from rest to tol (or to escape), and the
    steady launch speed v*. Returns (v*, v_crit, escapes, on the separatrix)."""
    model, k, r = int(case[C.model]), case[C.k], case[C.R]
    p = (k, case[C.xi]) if model == MODEL_PAPER else (k, case[C.kappa])
    v_crit = paper_critical(p) if model == MODEL_PAPER else rigid_critical(p)
    r_crit = (v_crit - (1.0 + k)) / (v_crit + (1.0 + k))
    row[ROW.restitution_critical] = r_crit if r_crit > 0.0 else math.nan
    count, escapes = impacts_to_converge(k, r, v_crit, tol)
    row[ROW.impacts] = count
    v = steady_state_speed(k, r)
    return v, v_crit, escapes, abs(v - v_crit) <= SEPARATRIX * v_crit


@njit(**KERNEL_OPTIONS)
def closed_form_block(cases, rows):
    """Driven cases on the rotor stop in closed form: the affine impact map's fixed point
    v* (P-O6) and the flight from it (first integral, amplitude by Newton, half period by
    Gauss-Legendre; the rigid pendulum by the AGM elliptic integral)."""
    for c in range(cases.shape[0]):
        case, row = cases[c], rows[c]
        for j in range(row.shape[0]):
            row[j] = math.nan
        row[ROW.steps] = row[ROW.rejected] = row[ROW.events] = 0.0
        v, v_crit, escapes, separatrix = driven_stop_preamble(case, 1e-12, row)
        if escapes or separatrix:
            row[ROW.outcome] = SEQUENCE_SEPARATRIX if separatrix else SEQUENCE_ESCAPE
            continue
        model, k = int(case[C.model]), case[C.k]
        p = (k, case[C.xi]) if model == MODEL_PAPER else (k, case[C.kappa])
        amplitude, tau1, peak = closed_flight(model, v, p)
        row[ROW.outcome] = SEQUENCE_CYCLE
        row[ROW.period], row[ROW.chatter] = 1.0, 0.0
        row[ROW.amplitude], row[ROW.frequency] = amplitude, math.pi / tau1
        row[ROW.interval], row[ROW.speed] = tau1, 1.0 + k + v
        row[ROW.acceleration], row[ROW.rotor_speed] = peak, 1.0


def driven_stop_margins(cases, rows, starts):
    """The margins of the constant-speed models on the rotor stop in closed form: one impact
    a cycle (speed ratio 1), the affine map's multiplier R (P-O6); from start j, arriving at
    u_j = 2 (1 + k) x_j (the tool's ``first``), the first launch (1 + k)(1 + R) + R u_j
    escapes iff it reaches v_crit, else the map contracts to v* (the one attractor)."""
    cycle = rows[:, ROW.outcome] == SEQUENCE_CYCLE
    k, r = cases[:, C.k], cases[:, C.R]
    rows[:, ROW.speed_ratio] = np.where(cycle, 1.0, np.nan)
    rows[:, ROW.modulus] = np.where(cycle, r, np.nan)
    rows[:, ROW.angle] = np.where(cycle, 0.0, np.nan)
    rows[:, ROW.attractors], rows[:, ROW.basin] = 1.0, 1.0
    if starts > 1:
        r_crit = rows[:, ROW.restitution_critical]
        v_crit = (1.0 + k) * (1.0 + r_crit) / (1.0 - r_crit)
        arrival = np.array([2.0 * radical_inverse(j, 2) for j in range(1, starts)])
        launch = ((1.0 + k) * (1.0 + r))[:, None] + r[:, None] * (1.0 + k)[:, None] * arrival
        escaping = (launch >= v_crit[:, None]).sum(axis=1)
        rows[:, ROW.attractors] = np.where(cycle & (escaping > 0), 2.0, 1.0)
        rows[:, ROW.basin] = np.where(cycle, (starts - escaping) / starts, 1.0)
