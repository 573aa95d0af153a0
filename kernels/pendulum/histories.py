"""The steady cycle on the rotor stop as time histories and loads ([RP] Fig. 3, and the
reaction Q the paper's constant rotor speed rests on): psi, psi', psi'', the hinge's force on
the rotor and the drive's torque over one flight, from the impact that opens it to the next,
with their peaks, the impulse through the hinge at the impact and the drive's work.

The pendulum is a striker of mass m with its centre at l_cm = l2/lambda from the hinge A and
centroidal inertia J_c = m l_cm^2/xi, lambda = kappa (1 + 1/xi) (1 for the paper's striker,
contact at its centre; the rotor model's convention, systems.rotor_parameters). Units: m,
l2, omega1 (time omega1 t; force m l2 omega1^2, torque and work m l2^2 omega1^2, impulse
m l2 omega1).

- Hinge force on the rotor: -m a_cm (Newton's second law of the striker; the paper's
  equation is not a rigid body's, but its striker's acceleration is still m a_cm's), along
  the pendulum A -> C (positive: pulled outward) and across it (positive: towards psi).
- Drive torque: a constant-speed rotor's drive supplies dH_O/dt of the pendulum (its
  angular momentum about the rotor axis O; for the rigid model the sympy torque of P5's
  section), and at each impact the angular impulse Delta H_O; the rotor model's motor
  supplies s_m (Omega_idle - phi1').
- Impulse through the hinge at the impact: the pendulum's momentum change less the
  contact's impulse, from its angular momentum about its centre (Newton-Euler); zero at the
  centre of percussion (kappa = 1).
- Drive work per cycle against the impact's loss (1 - R^2) v_n^2/(2 J M^-1 J^T): equal in
  a steady cycle (the rotor model's energy, the constant-speed models' angular momentum
  about O return each cycle, so the drive's work is the moment of the tool's impulse), so
  their difference is the error of the history's quadrature and of the section state.

A constant-speed cycle is a flight from psi = 0 launched at the closed form's steady speed
v* (P-O6), away from the stop; the rotor model's starts from the core's pre-impact section
state (its row's section slots) through Newton's law. The flight is stepped by the classical
RK4 of the integration core with the drive's work as one more state, in equal steps of at
most H_MAX landing on each sampled phase: a fixed grid, so a history costs the same at every
design and its error is that of RK4 at H_MAX (about 1e-12 of the swing at the stiffest
cases of the tests). Peaks are the largest sample, refined by the package's golden-section
search (kernels/extrema.py) between its neighbours.
"""

import math
from collections import namedtuple

from numba import njit

from kernels import INLINE_OPTIONS, INNER_OPTIONS, KERNEL_OPTIONS
from kernels.extrema import peak_search
from kernels.impact.runge_kutta import METHOD_RK4, make_stepper
from kernels.impact.tuples import relative_scales
from kernels.pendulum.models import (MODEL_PAPER, paper_acceleration,
                                     rotor_accelerations)

#: the longest RK4 step [rotor rad]
H_MAX = 1e-3
#: the rows of a history: psi [rad], psi' [rad per unit time], psi'' [rad per unit time^2],
#: time and rotor angle since the impact, hinge force on the rotor along and across the
#: pendulum, the drive's torque
(SWING, RATE, ACCELERATION, TIME, ROTOR_ANGLE, HINGE_ALONG, HINGE_ACROSS,
 DRIVE_TORQUE) = range(8)
N_HISTORY = 8
#: a case's loads over the cycle: peak hinge force (the impact's impulse apart), peak |drive
#: torque|, drive work per cycle (the impulse's included), the impact's loss, |impulse through
#: the hinge|, the cycle's time, the rotor angle it turns, the drive's mean torque over time
(PEAK_HINGE, PEAK_TORQUE, CYCLE_WORK, IMPACT_LOSS, HINGE_IMPULSE, CYCLE_TIME, CYCLE_ANGLE,
 MEAN_TORQUE) = range(8)
N_LOADS = 8

#: the striker in m and l2 units: l1, its centre's distance from the hinge, its centroidal
#: inertia
Striker = namedtuple("Striker", ["l1", "l_cm", "j_c"])
#: one instant of a flight: psi, psi', psi'', the rotor angle, the hinge's force on the rotor
#: along and across the pendulum, the drive's torque
Sample = namedtuple("Sample", ["swing", "rate", "acceleration", "rotor_angle", "along",
                               "across", "torque"])
#: a flight walked: peak hinge force, peak |drive torque|, the drive's work, the rotor angle
Walked = namedtuple("Walked", ["hinge", "torque", "work", "angle"])


@njit(**KERNEL_OPTIONS)
def striker_geometry(k, xi, kappa):
    """The Striker of these ratios (see the module docstring)."""
    l_cm = 1.0 / (kappa * (1.0 + 1.0 / xi))
    return Striker(k, l_cm, l_cm * l_cm / xi)


@njit(**KERNEL_OPTIONS)
def hinge_and_moment(geometry, w, dw, psi, dpsi, ddpsi):
    """The hinge's force on the rotor (along, across the pendulum) and dH_O/dt of the
    striker, at rotor speed w and acceleration dw."""
    l1, l_cm, j_c = geometry
    s, c = math.sin(psi), math.cos(psi)
    w2, dw2 = w + dpsi, dw + ddpsi  # the pendulum's absolute speed and acceleration
    # a_cm = l1 (dw e1' - w^2 e1) + l_cm (dw2 e2' - w2^2 e2), e' a quarter turn ahead
    a_along = l1 * (dw * s - w * w * c) - l_cm * w2 * w2
    a_across = l1 * (dw * c + w * w * s) + l_cm * dw2
    a_lateral = l1 * dw + l_cm * (dw2 * c - w2 * w2 * s)  # a_cm . e1'
    moment = j_c * dw2 + l1 * a_lateral + l_cm * a_across  # J_c phi2'' + r x a
    return -a_along, -a_across, moment


#: what an impact sends through the pendulum (m, l2, omega1 units): the impulse through the
#: hinge on the rotor (along, across the pendulum, as the hinge force), the tool's impulse
#: on the striker along the contact's normal, and the angular impulse a drive holding the
#: rotor's speed supplies
Impulses = namedtuple("Impulses", ["along", "across", "tool", "drive"])


@njit(**KERNEL_OPTIONS)
def impact_impulses(geometry, psi, dw, dpsi):
    """The Impulses of an impact at psi that changes the rotor's speed by dw and psi' by
    dpsi. The contact is at the striker's tip (l2 from the hinge), its normal across the
    radius from O to the tip (both tools: the stop at psi = 0, the blade radial), at delta
    = beta - psi from the pendulum's across direction. Newton-Euler of the striker: the
    tool's impulse P from the angular momentum about the hinge A (the hinge's impulse has
    no moment there), the hinge's from the momentum; the drive's, Delta H_O less the
    moment of P about O."""
    l1, l_cm, j_c = geometry
    s, c = math.sin(psi), math.cos(psi)
    delta = math.atan2(s, l1 + c) - psi
    spin = dw + dpsi  # the pendulum's absolute speed's change
    dv_along, dv_across = l1 * dw * s, l1 * dw * c + l_cm * spin  # Delta v_cm
    tool = (j_c * spin + l_cm * dv_across) / math.cos(delta)
    on_pendulum_along = dv_along + tool * math.sin(delta)
    on_pendulum_across = dv_across - tool * math.cos(delta)
    moment = j_c * spin + (l1 * c + l_cm) * dv_across + l1 * s * dv_along  # Delta H_O
    radius = math.sqrt(l1 * l1 + 1.0 + 2.0 * l1 * c)
    return Impulses(-on_pendulum_along, -on_pendulum_across, tool, moment - radius * tool)


#: the golden-section search stops at brackets this short [time]
PEAK_BRACKET = 1e-10


def make_walk(rhs, loads):
    """The walk of one model's flight: ``rhs(y, q)`` its vector field with the drive's power
    as the last component, ``loads(t, y, f, q) -> Sample``."""
    step = make_stepper(rhs, relative_scales, methods=(METHOD_RK4,))

    @njit(**INNER_OPTIONS)
    def at(x, data):
        """The Sample at time x, one RK4 step on from the state (y, f) at time t."""
        q, y, f, t = data
        y1, f1, err = step(METHOD_RK4, y, f, x - t, q, 0.0, 0.0)
        return loads(x, y1, f1, q)

    @njit(**INNER_OPTIONS)
    def hinge_at(x, data):
        sample = at(x, data)
        return math.hypot(sample.along, sample.across)

    @njit(**INNER_OPTIONS)
    def torque_at(x, data):
        return abs(at(x, data).torque)

    golden_hinge, golden_torque = peak_search(hinge_at)[0], peak_search(torque_at)[0]

    @njit(**INNER_OPTIONS)
    def walk(q, y, t0, duration, phases, out):
        """Steps over ``duration`` from y at time t0 (just after an impact), the history
        at ``phases`` (fractions of the duration) into out[row, phase]; the flight Walked.
        Each peak: the largest sample, refined by golden section between its two
        neighbours (the state at the left one stepped on exactly)."""
        f = rhs(y, q)
        sample = loads(t0, y, f, q)
        # per quantity: its largest sample so far, the sample before it (time and state)
        # and the time of the one after it (inf: none yet)
        t_last, y_last, f_last = t0, y, f
        q_best, q_left, q_right = math.hypot(sample.along, sample.across), (t0, y, f), t0
        m_best, m_left, m_right = abs(sample.torque), (t0, y, f), t0
        q_pending = m_pending = True
        tau = t0
        n = phases.shape[0]
        for j in range(n + 1):
            target = t0 + (duration if j == n else phases[j] * duration)
            count = max(1, math.ceil((target - tau) / H_MAX))
            h = (target - tau) / count
            for i in range(count):
                y, f, err = step(METHOD_RK4, y, f, h, q, 0.0, 0.0)
                t_now = tau + (i + 1) * h if i + 1 < count else target
                sample = loads(t_now, y, f, q)
                if not t_now > t_last:
                    continue  # a phase on the last sample: nothing new
                q_now, m_now = math.hypot(sample.along, sample.across), abs(sample.torque)
                if q_pending:
                    q_right, q_pending = t_now, False
                if m_pending:
                    m_right, m_pending = t_now, False
                if q_now > q_best:
                    q_best, q_left, q_pending = q_now, (t_last, y_last, f_last), True
                if m_now > m_best:
                    m_best, m_left, m_pending = m_now, (t_last, y_last, f_last), True
                t_last, y_last, f_last = t_now, y, f
            tau = target
            if j < n:
                out[SWING, j], out[RATE, j] = sample.swing, sample.rate
                out[ACCELERATION, j] = sample.acceleration
                out[ROTOR_ANGLE, j], out[TIME, j] = sample.rotor_angle, target
                out[HINGE_ALONG, j], out[HINGE_ACROSS, j] = sample.along, sample.across
                out[DRIVE_TORQUE, j] = sample.torque
        if q_pending:  # the largest sample is the last one
            q_right = t_last
        if m_pending:
            m_right = t_last
        t_q, y_q, f_q = q_left
        t_m, y_m, f_m = m_left
        peak_hinge = max(q_best, golden_hinge((q, y_q, f_q, t_q), t_q, q_right, PEAK_BRACKET))
        peak_torque = max(m_best, golden_torque((q, y_m, f_m, t_m), t_m, m_right,
                                                PEAK_BRACKET))
        return Walked(peak_hinge, peak_torque, y[-1], sample.rotor_angle)

    return walk


# ---------------------------------------------------------------- constant rotor speed

@njit(**INLINE_OPTIONS)
def _driven_loads(t, y, f, q):
    pendulum, geometry = q
    along, across, moment = hinge_and_moment(geometry, 1.0, 0.0, y[0], y[1], f[1])
    return Sample(y[0], y[1], f[1], t, along, across, moment)


@njit(**INLINE_OPTIONS)
def _paper_rhs(y, q):
    (k, xi), geometry = q
    ddpsi = paper_acceleration(y[0], y[1], k, xi)
    return (y[1], ddpsi, hinge_and_moment(geometry, 1.0, 0.0, y[0], y[1], ddpsi)[2])


@njit(**INLINE_OPTIONS)
def _rigid_rhs(y, q):
    (k, kappa), geometry = q
    ddpsi = -kappa * k * math.sin(y[0])
    return (y[1], ddpsi, hinge_and_moment(geometry, 1.0, 0.0, y[0], y[1], ddpsi)[2])


paper_walk = make_walk(_paper_rhs, _driven_loads)
rigid_walk = make_walk(_rigid_rhs, _driven_loads)


@njit(**KERNEL_OPTIONS)
def driven_cycle(model, k, second, r, geometry, launch, interval, phases, out, loads):
    """The cycle of a constant-speed model (second: its xi or kappa) launched at v* from
    the stop: its history into out[row, phase] and its loads into loads[:]."""
    q = ((k, second), geometry)
    y = (0.0, -launch, 0.0)
    if model == MODEL_PAPER:
        walked = paper_walk(q, y, 0.0, interval, phases, out)
    else:
        walked = rigid_walk(q, y, 0.0, interval, phases, out)
    l1, l_cm, j_c = geometry
    jump = -2.0 * launch  # psi' from +v* to -v*: Newton's law at the cycle's fixed point
    impulse = impact_impulses(geometry, 0.0, 0.0, jump)
    loads[PEAK_HINGE], loads[PEAK_TORQUE] = walked.hinge, walked.torque
    loads[CYCLE_WORK] = walked.work + impulse.drive
    speed = 1.0 + k + launch  # the striker's normal speed before the impact
    loads[IMPACT_LOSS] = 0.5 * (1.0 - r * r) * (j_c + l_cm * l_cm) * speed * speed
    loads[HINGE_IMPULSE] = math.hypot(impulse.along, impulse.across)
    loads[CYCLE_TIME], loads[CYCLE_ANGLE] = interval, walked.angle
    loads[MEAN_TORQUE] = loads[CYCLE_WORK] / interval


# ---------------------------------------------------------------- rotor of finite inertia

@njit(**INLINE_OPTIONS)
def _rotor_rhs(y, q):
    (k, xi, j1, slope, idle), geometry = q
    dw, ddpsi = rotor_accelerations(y[1], y[2], y[3], k, xi, j1, slope, idle)
    return (y[1], dw, y[3], ddpsi, slope * (idle - y[1]) * y[1])


@njit(**INLINE_OPTIONS)
def _rotor_loads(t, y, f, q):
    (k, xi, j1, slope, idle), geometry = q
    along, across, moment = hinge_and_moment(geometry, y[1], f[1], y[2], y[3], f[3])
    # the motor's torque is in J_c omega1^2
    return Sample(y[2], y[3], f[3], y[0], along, across,
                  geometry.j_c * slope * (idle - y[1]))


rotor_walk = make_walk(_rotor_rhs, _rotor_loads)
