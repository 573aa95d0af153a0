"""The rotary pendulum's models: what flies between impacts (their closed forms: free_flight.py).

Time is the rotor angle at nominal speed, tau = omega1 t (' = d/dtau); psi is the pendulum's
angle relative to the rotor (psi = 0: the striker radially outward). Three models, each a
``Model`` of functions for the tools and the integration core:

- paper ([RP]'s equation, P1-P2): psi'' = -a(psi) (psi'^2 + xi) sin psi,
  a = k X/(1 + xi X), X = k^2 + 1 + 2 k cos psi; state (psi, psi'); p = (k, xi);
- rigid (the physically derived pendulum at constant rotor speed, P5):
  psi'' = -kappa k sin psi; state (psi, psi'); p = (k, kappa);
- rotor (a rotor of finite inertia with a linear motor law, P8-P10): state
  (phi1, phi1', psi, psi'), lengths in l_cm, inertias in J_c; p = (k_cm, xi, j1, s_m, idle).

The first two run at constant rotor speed ("driven": the rotor angle is the time, the rotor
absorbs every impulse); the rotor model's rotor angle and speed are states. A contact's
impulse acts along a contact Jacobian J = (J_phi1, J_psi) on (phi1', psi'); ``response``
is M^-1 J^T (driven: (0, 1), the rotor does not move).
"""

import math
from collections import namedtuple

from numba import njit

from kernels import KERNEL_OPTIONS, INLINE_OPTIONS, INNER_OPTIONS
from kernels.impact.tuples import relative_scales

MODEL_PAPER, MODEL_RIGID, MODEL_ROTOR = 0, 1, 2

#: the functions of a model (see the module docstring); ``starting_speed(p)``: the rotor's
#: speed at a start (its idle speed; a driven rotor's speed is the unit, whatever it is
#: given); where its flow is known in closed form, ``exact(y, h, p)``,
#: ``exact_length(y, p, length)`` (its step) and ``speed_bound(y, p)`` (the largest |psi'|
#: of the free motion from y)
Model = namedtuple("Model", [
    "rhs", "scales", "monitor", "accelerations", "response", "rotor_angle", "rotor_speed",
    "psi", "dpsi", "compose", "critical_speed", "shift", "driven", "jacobian",
    "response_slope", "tangent_state", "tangent_coordinates", "swing", "starting_speed",
    "exact", "exact_length", "speed_bound"], defaults=(None, None, None))


def state_slot(index):
    """A reader of one coordinate of a model's state, ``read(y) -> y[index]``."""
    @njit(**INLINE_OPTIONS)
    def read(y):
        return y[index]

    return read


# ---------------------------------------------------------------- constant rotor speed

@njit(**KERNEL_OPTIONS)
def paper_acceleration(psi, dpsi, k, xi):
    """psi'' of [RP]'s equation (P1-P2)."""
    x = k * k + 1.0 + 2.0 * k * math.cos(psi)
    return -k * x / (1.0 + xi * x) * (dpsi * dpsi + xi) * math.sin(psi)


@njit(**INLINE_OPTIONS)
def paper_rhs(y, p):
    k, xi = p
    return (y[1], paper_acceleration(y[0], y[1], k, xi))


@njit(**INLINE_OPTIONS)
def rigid_rhs(y, p):
    k, kappa = p
    return (y[1], -kappa * k * math.sin(y[0]))


@njit(**INLINE_OPTIONS)
def paper_jacobian(y, p):
    """d(rhs)/dy of the paper's equation, row-major: a' = k dX/dpsi/(1 + xi X)^2."""
    psi, dpsi = y
    k, xi = p
    s, c = math.sin(psi), math.cos(psi)
    x = k * k + 1.0 + 2.0 * k * c
    a = k * x / (1.0 + xi * x)
    da = k * (-2.0 * k * s) / ((1.0 + xi * x) * (1.0 + xi * x))
    return (0.0, 1.0, -(dpsi * dpsi + xi) * (da * s + a * c), -2.0 * a * dpsi * s)


@njit(**INLINE_OPTIONS)
def rigid_jacobian(y, p):
    k, kappa = p
    return (0.0, 1.0, -kappa * k * math.cos(y[0]), 0.0)


@njit(**INLINE_OPTIONS)
def driven_tangent_state(c):
    """A perturbation in coordinates (dt, dphi1, dphi1', dpsi, dpsi') as the model's state
    perturbation (dpsi, dpsi'); the rotor angle is the time."""
    return (c[3], c[4])


@njit(**INLINE_OPTIONS)
def driven_tangent_coordinates(dt, dy):
    """The coordinates of a perturbation dt of the time and dy of the state: the rotor
    angle moves with the time, its speed not at all."""
    return (dt, dt, 0.0, dy[0], dy[1])


@njit(**INLINE_OPTIONS)
def driven_response_slope(y, j_phi, j_psi, dj_phi, dj_psi, p):
    return 0.0, 0.0


@njit(**INLINE_OPTIONS)
def driven_monitor(t, y, f):
    return y[0], f[0], f[1]


@njit(**INLINE_OPTIONS)
def driven_rotor_angle(t, y):
    return t


@njit(**INLINE_OPTIONS)
def driven_rotor_speed(y):
    return 1.0


driven_psi, driven_dpsi = state_slot(0), state_slot(1)


@njit(**INLINE_OPTIONS)
def driven_compose(t, phi1, w, psi, dpsi):
    """The state with these coordinates: the rotor angle is the time."""
    return phi1, (psi, dpsi)


@njit(**INLINE_OPTIONS)
def driven_shift(t, y, angle):
    """The same state with the rotor angle (the time) measured from another origin."""
    return t + angle, y


@njit(**INLINE_OPTIONS)
def driven_starting_speed(p):
    """A driven rotor turns at the unit speed, whatever its compose is given."""
    return 1.0


@njit(**INLINE_OPTIONS)
def driven_response(y, j_phi, j_psi, p):
    """M^-1 J^T up to scale for a rotor that does not move: the impulse changes psi' only."""
    return 0.0, 1.0


def driven_model(rhs, critical_speed, jacobian, swing, exact=None, exact_length=None,
                 speed_bound=None):
    @njit(**INLINE_OPTIONS)
    def accelerations(t, y, p):
        return 0.0, rhs(y, p)[1]

    return Model(rhs=rhs, scales=relative_scales, monitor=driven_monitor,
                 accelerations=accelerations, response=driven_response,
                 rotor_angle=driven_rotor_angle, rotor_speed=driven_rotor_speed,
                 psi=driven_psi, dpsi=driven_dpsi, compose=driven_compose,
                 critical_speed=critical_speed, shift=driven_shift, driven=True,
                 jacobian=jacobian, response_slope=driven_response_slope,
                 tangent_state=driven_tangent_state,
                 tangent_coordinates=driven_tangent_coordinates, swing=swing,
                 starting_speed=driven_starting_speed, exact=exact,
                 exact_length=exact_length, speed_bound=speed_bound)


# ---------------------------------------------------------------- rotor of finite inertia

@njit(**KERNEL_OPTIONS)
def mass_matrix(psi, k, xi, j1):
    """(M11, M12, M22) of T = M11 phi1'^2/2 + M12 phi1' psi' + M22 psi'^2/2 (P8)."""
    c = math.cos(psi)
    return j1 + 1.0 + xi * (k * k + 1.0 + 2.0 * k * c), 1.0 + xi * (1.0 + k * c), 1.0 + xi


@njit(**KERNEL_OPTIONS)
def rotor_accelerations(w, psi, dpsi, k, xi, j1, slope, idle):
    """(phi1'', psi'') from (P9)-(P10), solving the 2x2 mass-matrix system."""
    m11, m12, m22 = mass_matrix(psi, k, xi, j1)
    s = xi * k * math.sin(psi)
    rhs1 = slope * (idle - w) + s * (2.0 * w * dpsi + dpsi * dpsi)
    rhs2 = -s * w * w
    det = m11 * m22 - m12 * m12
    return (m22 * rhs1 - m12 * rhs2) / det, (m11 * rhs2 - m12 * rhs1) / det


@njit(**KERNEL_OPTIONS)
def _solve(m11, m12, m22, z1, z2):
    """M^-1 z for the symmetric 2x2 mass matrix."""
    det = m11 * m22 - m12 * m12
    return (m22 * z1 - m12 * z2) / det, (m11 * z2 - m12 * z1) / det


@njit(**INNER_OPTIONS)
def rotor_jacobian(y, p):
    """d(rhs)/dy of the rotor model, row-major over (phi1, phi1', psi, psi'): the
    accelerations a = M^-1 b differentiate as M^-1 (db - dM a)."""
    k, xi, j1, slope, idle = p
    w, psi, v = y[1], y[2], y[3]
    m11, m12, m22 = mass_matrix(psi, k, xi, j1)
    a1, b2 = rotor_accelerations(w, psi, v, k, xi, j1, slope, idle)
    sn, cs = math.sin(psi), math.cos(psi)
    s, ds = xi * k * sn, xi * k * cs
    dm11, dm12 = -2.0 * xi * k * sn, -xi * k * sn  # dM/dpsi (M22 is constant)
    aw = _solve(m11, m12, m22, -slope + 2.0 * s * v, -2.0 * s * w)
    av = _solve(m11, m12, m22, s * (2.0 * w + 2.0 * v), 0.0)
    ap = _solve(m11, m12, m22, ds * (2.0 * w * v + v * v) - dm11 * a1 - dm12 * b2,
                -ds * w * w - dm12 * a1)
    return (0.0, 1.0, 0.0, 0.0,
            0.0, aw[0], ap[0], av[0],
            0.0, 0.0, 0.0, 1.0,
            0.0, aw[1], ap[1], av[1])


@njit(**INNER_OPTIONS)
def rotor_response_slope(y, j_phi, j_psi, dj_phi, dj_psi, p):
    """d/dpsi of M^-1 J^T: M^-1 (dJ^T - dM M^-1 J^T)."""
    k, xi, j1, slope, idle = p
    m11, m12, m22 = mass_matrix(y[2], k, xi, j1)
    x_phi, x_psi = _solve(m11, m12, m22, j_phi, j_psi)
    sn = math.sin(y[2])
    dm11, dm12 = -2.0 * xi * k * sn, -xi * k * sn
    return _solve(m11, m12, m22, dj_phi - dm11 * x_phi - dm12 * x_psi,
                  dj_psi - dm12 * x_phi)


@njit(**INLINE_OPTIONS)
def rotor_tangent_state(c):
    return (c[1], c[2], c[3], c[4])


@njit(**INLINE_OPTIONS)
def rotor_tangent_coordinates(dt, dy):
    return (dt, dy[0], dy[1], dy[2], dy[3])


@njit(**INLINE_OPTIONS)
def rotor_rhs(y, p):
    k, xi, j1, slope, idle = p
    a1, b2 = rotor_accelerations(y[1], y[2], y[3], k, xi, j1, slope, idle)
    return (y[1], a1, y[3], b2)


@njit(**KERNEL_OPTIONS)
def rotor_scales(y0, y1, rtol, atol):
    """The error scales; phi1 grows without bound and what matters is its error per step
    (a lab-fixed tool sits at a rotor angle), so it is scaled as a variable of size 1."""
    return (atol + rtol, atol + rtol * max(abs(y0[1]), abs(y1[1])),
            atol + rtol * max(abs(y0[2]), abs(y1[2])),
            atol + rtol * max(abs(y0[3]), abs(y1[3])))


@njit(**INLINE_OPTIONS)
def rotor_monitor(t, y, f):
    return y[2], f[2], f[3]


@njit(**INLINE_OPTIONS)
def rotor_model_accelerations(t, y, p):
    k, xi, j1, slope, idle = p
    return rotor_accelerations(y[1], y[2], y[3], k, xi, j1, slope, idle)


@njit(**KERNEL_OPTIONS)
def rotor_response(y, j_phi, j_psi, p):
    """M^-1 J^T at the state's configuration."""
    k, xi, j1, slope, idle = p
    m11, m12, m22 = mass_matrix(y[2], k, xi, j1)
    det = m11 * m22 - m12 * m12
    return (m22 * j_phi - m12 * j_psi) / det, (m11 * j_psi - m12 * j_phi) / det


@njit(**INLINE_OPTIONS)
def rotor_rotor_angle(t, y):
    return y[0]


rotor_rotor_speed, rotor_psi, rotor_dpsi = state_slot(1), state_slot(2), state_slot(3)


@njit(**INLINE_OPTIONS)
def rotor_compose(t, phi1, w, psi, dpsi):
    return t, (phi1, w, psi, dpsi)


@njit(**INLINE_OPTIONS)
def rotor_shift(t, y, angle):
    """The same state with the rotor angle measured from another origin (the dynamics do
    not depend on it: phi1 is cyclic)."""
    return t, (y[0] + angle, y[1], y[2], y[3])


@njit(**INLINE_OPTIONS)
def no_critical_speed(p):
    return math.inf  # no closed form: escape is an event of the flight


@njit(**INLINE_OPTIONS)
def no_swing(y, p, window):
    return math.nan, math.inf  # the rotor's speed changes: no free swing repeats


@njit(**INLINE_OPTIONS)
def rotor_starting_speed(p):
    """The rotor's idle speed (its motor's speed at no load) in omega1 units."""
    k, xi, j1, slope, idle = p
    return idle


ROTOR = Model(rhs=rotor_rhs, scales=rotor_scales, monitor=rotor_monitor,
              accelerations=rotor_model_accelerations, response=rotor_response,
              rotor_angle=rotor_rotor_angle, rotor_speed=rotor_rotor_speed, psi=rotor_psi,
              dpsi=rotor_dpsi, compose=rotor_compose, critical_speed=no_critical_speed,
              shift=rotor_shift, driven=False, jacobian=rotor_jacobian,
              response_slope=rotor_response_slope, tangent_state=rotor_tangent_state,
              tangent_coordinates=rotor_tangent_coordinates, swing=no_swing,
              starting_speed=rotor_starting_speed)


@njit(**KERNEL_OPTIONS)
def kinetic_energy(y, p):
    """T of the rotor model (P8): with the angular momentum, conserved by a free rotor."""
    k, xi, j1, slope, idle = p
    m11, m12, m22 = mass_matrix(y[2], k, xi, j1)
    return 0.5 * m11 * y[1] ** 2 + m12 * y[1] * y[3] + 0.5 * m22 * y[3] ** 2


from kernels.pendulum.free_flight import (paper_critical, paper_swing, rigid_critical,  # noqa: E402
                                          rigid_exact, rigid_exact_length, rigid_speed_bound,
                                          rigid_swing)

PAPER = driven_model(paper_rhs, paper_critical, paper_jacobian, paper_swing)
RIGID = driven_model(rigid_rhs, rigid_critical, rigid_jacobian, rigid_swing, rigid_exact,
                     rigid_exact_length, rigid_speed_bound)


