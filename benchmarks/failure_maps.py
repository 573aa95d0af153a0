"""Where event detection fails: the outcome of one run, for the failure-map charts
(benchmarks/charts.py) and the boundary tests (tests/test_failure_maps.py).

Test problem: the rigid pendulum psi'' = -sin psi (model "rigid", kappa k = 1), launched
from psi = 0 upwards; in rotor radians.

* Grazing: the apex is A = 1 rad and a stop sits at A - eps; the pendulum reaches it with
  approach speed v = sqrt(2 (cos(A - eps) - cos A)) and stays beyond it for a window
  w ~ 2 v / sin A. A sign-change detector that looks at step ends only misses the contact
  when no step end falls in the window; ours also samples inside the step and checks the
  interpolant's extremum (H3), and misses only when the interpolation error exceeds eps.
* Separatrix: launched at 2 (1 -+ delta) the pendulum returns (-) or goes over the top (+);
  an integrator alone decides it by whether psi reaches -pi, which its error decides once
  delta is small enough (H1, H2). The kernels decide it by the closed form instead.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.special import ellipj, ellipk

from kernels.impact.outcomes import FLIGHT_EVENT
from tests import probes

APEX = 1.0  # rad


def approach_level(speed: float) -> float:
    """The stop level A - eps reached with the given approach speed."""
    return math.acos(math.cos(APEX) + 0.5 * speed * speed)


def exact_state(tau: float) -> tuple[float, float]:
    """psi, psi' of the pendulum launched from 0 upwards with apex APEX, at time tau."""
    m = math.sin(APEX / 2) ** 2
    sn, cn, dn, _ = ellipj(tau, m)
    return 2 * math.asin(math.sqrt(m) * sn), 2 * math.sqrt(m) * cn


def naive_found(step: float, speed: float, phase: float) -> bool:
    """Step-end sign change on exact states (steps at (phase + j) step): is any step end
    beyond the stop before the pendulum is back at 0?"""
    level = approach_level(speed)
    m = math.sin(APEX / 2) ** 2
    half = 2 * ellipk(m)  # time back at psi = 0
    tau = np.arange(phase * step, half, step)
    sn = ellipj(tau, m)[0]
    return bool(np.any(2 * np.arcsin(np.sqrt(m) * sn) >= level))


def detector_found(step: float, speed: float, phase: float) -> bool:
    """The kernel's event detection (RK4 with the given step, sub-step sign samples and the
    extremum check), started from the exact state at phase * step against a stop at the
    level (the test-defined stop of tests/stop_tool.py): a contact before the pendulum is
    back at 0?"""
    level = approach_level(speed)
    psi0, dpsi0 = exact_state(phase * step)
    half = 2 * ellipk(math.sin(APEX / 2) ** 2)
    steps = int(math.ceil((half - phase * step) / step)) + 1
    fl = probes.flight("rigid", "relative_stop")(
        phase * step, (psi0, dpsi0), (1.0, 1.0), (level,),
        probes.settings("rk4", dt=step, max_steps=steps), False)
    return fl.outcome == FLIGHT_EVENT and fl.event == 0


def separatrix_correct(method: str, accuracy: float, delta: float) -> int:
    """How many of the two launches 2 (1 -+ delta) an integrator alone classifies right
    (return / escape); accuracy is rtol (DOPRI5, atol = rtol/100) or the step (RK4)."""
    right = 0
    fly = probes.flight("rigid", "rotor_stop")
    for sign in (-1.0, 1.0):
        rtol = accuracy if method == "dopri5" else 1e-3
        settings = probes.settings(method, rtol=rtol, atol=rtol * 1e-2, dt=accuracy,
                                   max_steps=10**7, horizon=1e4)
        fl = fly(0.0, (0.0, -2.0 * (1.0 + sign * delta)), (1.0, 1.0), (0.0, 1.0), settings,
                 False)
        escaped = fl.outcome == FLIGHT_EVENT and fl.event == 1
        right += escaped == (sign > 0)
    return right
