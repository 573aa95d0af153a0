"""The steady cycle as time histories ([RP] Fig. 3): psi, psi' and psi'' over one flight of a
constant-speed model on the rotor stop, from the impact that opens it to the next.

Such a cycle is a flight from psi = 0 launched at the closed form's steady speed v* (P-O6;
kernels/pendulum/closed_form.py), away from the stop (psi' = -v*), that returns to the stop
after the impact interval tau1, both in rotor radians (time omega1 t). The flight is stepped
by the classical RK4 of the integration core, in equal steps of at most H_MAX landing on
each sampled phase: a fixed grid, so a history costs the same at every design and its error
is that of RK4 at H_MAX (about 1e-12 of the swing at the stiffest cases of the tests).
"""

import math

from numba import njit

from kernels import INNER_OPTIONS, KERNEL_OPTIONS
from kernels.impact.runge_kutta import METHOD_RK4, make_stepper
from kernels.impact.tuples import relative_scales
from kernels.pendulum.models import MODEL_PAPER, paper_rhs, rigid_rhs

#: the longest RK4 step [rotor rad]
H_MAX = 1e-3
#: the rows of a history: psi [rad], psi' [rad per rotor rad], psi'' [rad per rotor rad^2]
SWING, RATE, ACCELERATION = 0, 1, 2


def _make_walk(rhs):
    """The history of one model's flight (see the module docstring), rhs its vector field."""
    step = make_stepper(rhs, relative_scales, methods=(METHOD_RK4,))

    @njit(**INNER_OPTIONS)
    def walk(p, launch, interval, phases, out):
        y = (0.0, -launch)
        f = rhs(y, p)
        tau = 0.0
        for j in range(phases.shape[0]):
            target = phases[j] * interval
            count = max(1, math.ceil((target - tau) / H_MAX))
            h = (target - tau) / count
            for _ in range(count):
                y, f, err = step(METHOD_RK4, y, f, h, p, 0.0, 0.0)
            tau = target
            out[SWING, j], out[RATE, j], out[ACCELERATION, j] = y[0], y[1], f[1]

    return walk


_paper_walk = _make_walk(paper_rhs)
_rigid_walk = _make_walk(rigid_rhs)


@njit(**KERNEL_OPTIONS)
def steady_histories(models, ks, seconds, launches, intervals, phases, out):
    """For each case c (model code, k, its xi (paper) or kappa (rigid), launch speed v* and
    impact interval tau1, NaN where it has no such cycle): its history at ``phases``
    (fractions of tau1, increasing) into out[c, row, phase], in omega1 units; NaN where
    none."""
    for c in range(models.shape[0]):
        if not (math.isfinite(launches[c]) and math.isfinite(intervals[c])):
            out[c, :, :] = math.nan
            continue
        p = (ks[c], seconds[c])
        if models[c] == MODEL_PAPER:
            _paper_walk(p, launches[c], intervals[c], phases, out[c])
        else:
            _rigid_walk(p, launches[c], intervals[c], phases, out[c])
