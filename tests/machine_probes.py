"""Python handles on the machine kernel's inner functions (kernels/impact_machine.py and
kernels/machine/), for the tests: each probe is a small jitted function around them,
taking one design's parameter vector (the rows of the declaration)."""

import math

import numpy as np
from numba import njit

from kernels import impact_machine as M
from kernels.impact.outcomes import Settings
from kernels.impact.runge_kutta import METHOD_DOPRI5
from kernels.machine.blow import blow, node
from kernels.machine.cycle import constant_speed_guess
from kernels.machine.data import with_flywheel
from kernels.machine.dynamics import kinematics, reduced
from kernels.machine.revolution import revolution

SNAP = 1e-9


def parameters(**given):
    """One design's parameter vector: the declaration's defaults, words or numbers given by
    name replacing them."""
    return np.array([p.encode(given.get(p.name, p.default))
                     for p in M.DECLARATION.parameters])


@njit(cache=True)
def data(pr):
    """(status, the Machine record, the crank's own inertia)."""
    return M.design_data(pr, SNAP)


@njit(cache=True)
def reduced_at(pr, phis):
    """(J, J', Q, u31, u21) at crank angles phis."""
    status, m, own = M.design_data(pr, SNAP)
    out = np.empty((phis.shape[0], 5))
    for i in range(phis.shape[0]):
        j, dj, q, u31 = reduced(phis[i], m)
        c1, s1, c2, s2, c3, s3, u21, u31_, du21, du31 = kinematics(phis[i], m.linkage)
        out[i, 0], out[i, 1], out[i, 2], out[i, 3], out[i, 4] = j, dj, q, u31, u21
    return out


@njit(cache=True)
def node_of(pr):
    status, m, own = M.design_data(pr, SNAP)
    return node(m)


@njit(cache=True)
def blow_of(pr, w_minus, r, law):
    """(the Blow: w_plus, Pi, dE, dE_tool, dE_capture), and T- - T+ (the loss as a
    difference of kinetic energies)."""
    status, m, own = M.design_data(pr, SNAP)
    nd = node(m)
    result = blow(w_minus, r, law, nd, m)
    return result, (0.5 * nd.j_before * w_minus ** 2
                    - 0.5 * nd.j_after * result.w_plus ** 2)


@njit(cache=True)
def section_map(pr, w_plus, tol):
    """One revolution from w_plus, then the blow: (end, w_minus, w_next, period, angle)."""
    status, m, own = M.design_data(pr, SNAP)
    nd = node(m)
    settings = Settings(method=METHOD_DOPRI5, rtol=tol, atol=tol, dt=0.0,
                        max_steps=10 ** 6, horizon=2.0 * math.pi + 1.0)
    wref = constant_speed_guess(nd, pr[M.P.R], int(pr[M.P.impact_law]), m)
    if not wref == wref:
        wref = m.motor.idle_speed
    m = with_flywheel(m, pr[M.P.flywheel_inertia], own, 0.5 * nd.j_after * wref * wref, wref)
    rev = revolution(w_plus, nd, m, settings)
    w_next = blow(rev.w_minus, pr[M.P.R], int(pr[M.P.impact_law]), nd, m).w_plus
    return rev.end, rev.w_minus, w_next, rev.period, rev.angle
