"""Joint reactions over the dynamic cycle: the kinetostatics of linkage_forces (its one dyad
solver, kinetostatics.dyad_reactions) at the actual crank speed and acceleration of each
crank angle of the steady cycle, and their peaks outside a window around the node."""

import math

import numpy as np
from numba import njit

from kernels import INNER_OPTIONS
from kernels import kinetostatics as ks
from kernels.extrema import CLUSTER, clustered_points, peak_search
from kernels.machine.dynamics import crank_motion, kinematics
from kernels.machine.revolution import (ANGLE, ENERGY, LOAD_WORK, MOTOR_WORK, TIME,
                                        TORQUE_SQUARED, after_blow, timed_revolution)

#: the peaks reported: kinetostatics' peak quantities (their codes index ``peaks``)
PEAKS = (ks.PEAK_A, ks.PEAK_B, ks.PEAK_C, ks.PEAK_D)
#: golden section brackets a peak's crank angle to this [rad]
PEAK_LOCATION = 1e-9


@njit(**INNER_OPTIONS)
def _state_at(x, data):
    """The cycle's state at crank angle x (after the blow), from the nearest sample before
    it; (reached, y)."""
    q, xs, states, m, settings, lf, res = data
    k = np.searchsorted(xs, x, side="right") - 1
    k = min(max(k, 0), xs.shape[0] - 1)
    y = (states[k, ANGLE], states[k, ENERGY], states[k, TIME], states[k, MOTOR_WORK],
         states[k, TORQUE_SQUARED], states[k, LOAD_WORK])
    return timed_revolution(y[ANGLE], y, m.linkage.start + x, m, settings)


@njit(**INNER_OPTIONS)
def reactions(y, m, lf, res):
    """The joint reactions at the revolution's state y (kinetostatics' result vector in
    res), with the crank's actual speed and acceleration and the base-frame load turned
    into the rocker frame; False where they do not exist. ``lf``: the linkage_forces
    parameters of the machine's linkage (kinetostatics.P)."""
    w, eps, torque = crank_motion(y[ANGLE], y[ENERGY], m)
    c1, s1, c2, s2, c3, s3, u21, u31, du21, du31 = kinematics(y[ANGLE], m.linkage)
    ld = m.loads
    fx, fy = ld.fx, ld.fy
    lf[ks.P.omega1], lf[ks.P.epsilon1] = w, eps
    lf[ks.P.external_force_normal] = fx * c3 + fy * s3
    lf[ks.P.external_force] = -fx * s3 + fy * c3
    # the load point's offset across the rocker: the force there is the force on the axis
    # plus the couple offset n3 x F
    lf[ks.P.external_moment] = ld.moment + ld.offset * (-s3 * fy - c3 * fx)
    return ks.dyad_reactions(y[ANGLE], lf, m.linkage.sigma, res, m.linkage.snap, ld.gx,
                             ld.gy, 0.0, 0.0)


@njit(**INNER_OPTIONS)
def _dynamic_quantity(x, data):
    q, xs, states, m, settings, lf, res = data
    reached, y = _state_at(x, data)
    if not (reached and reactions(y, m, lf, res)):
        return math.nan
    return ks.peak_quantity(q, res)


_, _refine_dynamic_peak = peak_search(_dynamic_quantity)


@njit(**INNER_OPTIONS)
def dynamic_force_peaks(w_plus, nd, m, lf, settings, window, n_samples, peaks):
    """The peaks of |F14|, |F21|, |F32|, |F34| over the steady cycle from the blow's exit
    at w_plus, outside the window around the node, into peaks[q] for q in PEAKS (NaN
    where the cycle or a reaction is not reached): a clustered sample of the cycle, each
    state reached by the revolution's steps, every sampled local maximum refined by golden
    section (kernels/extrema.py)."""
    peaks[:] = math.nan
    start = m.linkage.start
    xs = clustered_points(window, 2.0 * math.pi - window, n_samples, int(CLUSTER))
    states = np.empty((xs.shape[0], 6))
    values = np.empty((ks.N_PEAKS, xs.shape[0]))
    res = np.empty(ks.N_RESULT)
    y = after_blow(w_plus, nd, m)
    for j in range(xs.shape[0]):
        reached, y = timed_revolution(y[ANGLE], y, start + xs[j], m, settings)
        if not (reached and reactions(y, m, lf, res)):
            return
        for i in range(6):
            states[j, i] = y[i]
        for q in PEAKS:
            values[q, j] = ks.peak_quantity(q, res)
    for q in PEAKS:
        peaks[q] = _refine_dynamic_peak((q, xs, states, m, settings, lf, res), xs, values[q],
                                        PEAK_LOCATION)
