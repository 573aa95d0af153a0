"""Python handles on the machine kernel's inner functions (kernels/machine.py), for the
tests: each probe is a small jitted function around them, taking one design's parameter
vector (the rows of the declaration)."""

import math

import numpy as np
from numba import njit

from kernels import machine as M

SNAP = 1e-9


def parameters(**given):
    """One design's parameter vector: the declaration's defaults, words or numbers given by
    name replacing them."""
    return np.array([p.encode(given.get(p.name, p.default))
                     for p in M.DECLARATION.parameters])


@njit
def data(pr):
    """(status, the machine's data tuple, the crank's own inertia)."""
    return M.design_data(pr, SNAP)


@njit
def reduced_at(pr, phis):
    """(J, J', Q, u31, u21) at crank angles phis."""
    status, m, own = M.design_data(pr, SNAP)
    out = np.empty((phis.shape[0], 5))
    for i in range(phis.shape[0]):
        j, dj, q, u31 = M.reduced(phis[i], m)
        kin = M.kinematics(phis[i], m)
        out[i, 0], out[i, 1], out[i, 2], out[i, 3], out[i, 4] = j, dj, q, u31, kin[6]
    return out


@njit
def node_of(pr):
    status, m, own = M.design_data(pr, SNAP)
    return M.node(m)


@njit
def blow_of(pr, w_minus, r, law):
    """(w_plus, Pi, dE, dE_tool, dE_capture), and T- - T+ (the loss as a difference of
    kinetic energies)."""
    status, m, own = M.design_data(pr, SNAP)
    nd = M.node(m)
    result = M.blow(w_minus, r, law, nd, m)
    return result, 0.5 * nd[0] * w_minus ** 2 - 0.5 * nd[1] * result[0] ** 2


@njit
def section_map(pr, w_plus, tol):
    """One revolution from w_plus, then the blow: (end, w_minus, w_next, period, angle)."""
    status, m, own = M.design_data(pr, SNAP)
    nd = M.node(m)
    settings = M.Settings(method=M.METHOD_DOPRI5, rtol=tol, atol=tol, dt=0.0,
                          max_steps=10 ** 6, horizon=2.0 * math.pi + 1.0)
    wref = M.constant_speed_guess(nd, pr[M.P.R], int(pr[M.P.impact_law]), m)
    if not wref == wref:
        wref = m[M.M_IDLE]
    m = M.with_flywheel(m, pr[M.P.flywheel_inertia], own, 0.5 * nd[1] * wref * wref, wref)
    rev = M.revolution(w_plus, nd, m, settings)
    w_next = M.blow(rev.w_minus, pr[M.P.R], int(pr[M.P.impact_law]), nd, m)[0]
    return rev.end, rev.w_minus, w_next, rev.period, rev.angle
