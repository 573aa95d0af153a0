"""The rotor model of the rotary-pendulum impact mechanism (dynamics.md §1.4(c), P8-P10):
a rotor of finite inertia driven by a linear motor law, carrying the pendulum; impacts on
the rotor stop at psi = 0 by the generalised Newton law of §1.3.

Units: time tau = omega1 t (omega1 the nominal rotor speed), lengths in l_cm (hinge to the
striker's centre of mass), inertias in J_c. State y = (phi1, phi1', psi, psi'); j1 = J1/J_c,
motor torque s_m (idle - phi1') with s_m in J_c omega1 and idle in omega1. The mechanism's
k = l1/l_contact and kappa = l_contact/l_p (as in the rigid model) fix the contact point:
lam = l_contact/l_cm = kappa (1 + 1/xi) and k_cm = l1/l_cm = k lam, so that a heavy rotor
with a stiff motor tends to the rigid model with the same k and kappa.
"""

import math

import numpy as np
from numba import njit

from kernels import KERNEL_OPTIONS
from kernels.extrema import golden_points, golden_shrink
from kernels.pendulum import *  # noqa: F401,F403  (ROW_*, REGIME_*)
from kernels.pendulum import (_first_crossing, accepted_step_size, classify_period,
                              initial_step, next_step, turning_time)

FLIGHT_IMPACT, FLIGHT_ESCAPE, FLIGHT_MAX_STEPS, FLIGHT_UNDERFLOW = 0, 1, 2, 3
METHOD_RK4, METHOD_DOPRI5 = 0, 1

# Dormand-Prince 5(4): nodes, stage matrix, 5th-order weights, error weights (b5 - b4)
_C = np.array([0.0, 1 / 5, 3 / 10, 4 / 5, 8 / 9, 1.0, 1.0])
_A = np.array([
    [0, 0, 0, 0, 0, 0],
    [1 / 5, 0, 0, 0, 0, 0],
    [3 / 40, 9 / 40, 0, 0, 0, 0],
    [44 / 45, -56 / 15, 32 / 9, 0, 0, 0],
    [19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729, 0, 0],
    [9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656, 0],
    [35 / 384, 0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84]])
_E = np.array([71 / 57600, 0, -71 / 16695, 71 / 1920, -17253 / 339200, 22 / 525, -1 / 40])


@njit(**KERNEL_OPTIONS)
def rotor_mass_matrix(psi, k, xi, j1):
    """(M11, M12, M22) of T = M11 phi1'^2/2 + M12 phi1' psi' + M22 psi'^2/2 (P8)."""
    c = math.cos(psi)
    return j1 + 1.0 + xi * (k * k + 1.0 + 2.0 * k * c), 1.0 + xi * (1.0 + k * c), 1.0 + xi


@njit(**KERNEL_OPTIONS)
def rotor_accelerations(w, psi, dpsi, k, xi, j1, motor_slope, idle):
    """(phi1'', psi'') from (P9)-(P10), solving the 2x2 mass-matrix system."""
    m11, m12, m22 = rotor_mass_matrix(psi, k, xi, j1)
    s = xi * k * math.sin(psi)
    rhs1 = motor_slope * (idle - w) + s * (2.0 * w * dpsi + dpsi * dpsi)
    rhs2 = -s * w * w
    det = m11 * m22 - m12 * m12
    return (m22 * rhs1 - m12 * rhs2) / det, (m11 * rhs2 - m12 * rhs1) / det


@njit(**KERNEL_OPTIONS)
def rotor_impact(w, dpsi, k, xi, j1, lam, r):
    """Generalised Newton impact at psi = 0 for the 2-DOF rotor-pendulum (dynamics.md §1.3):
    contact Jacobian J = (k + lam, lam) (contact lam l2 from A), normal speed v_n = J q',
    impulse P = -(1 + R) v_n / (J M^-1 J^T), q'+ = q'- + M^-1 J^T P.
    Returns (w+, psi'+, energy lost)."""
    m11, m12, m22 = rotor_mass_matrix(0.0, k, xi, j1)
    det = m11 * m22 - m12 * m12
    j_a, j_b = k + lam, lam
    # M^-1 J^T
    x_a = (m22 * j_a - m12 * j_b) / det
    x_b = (m11 * j_b - m12 * j_a) / det
    eff = j_a * x_a + j_b * x_b  # J M^-1 J^T
    v_n = j_a * w + j_b * dpsi
    impulse = -(1.0 + r) * v_n / eff
    return w + x_a * impulse, dpsi + x_b * impulse, (1.0 - r * r) * v_n * v_n / (2.0 * eff)


@njit(**KERNEL_OPTIONS)
def _rhs(y, k, xi, j1, slope, idle, dy):
    """dy = y' for the state y = (phi1, phi1', psi, psi')."""
    a1, b2 = rotor_accelerations(y[1], y[2], y[3], k, xi, j1, slope, idle)
    dy[0], dy[1], dy[2], dy[3] = y[1], a1, y[3], b2


@njit(**KERNEL_OPTIONS)
def _step(method, y, f0, h, k, xi, j1, slope, idle, stages, work, y_new, f_new):
    """One RK4 or DOPRI5 step from (y, f0 = y'(y)); fills y_new, f_new and returns the
    DOPRI5 error norm's raw components in stages[6] (zero for RK4)."""
    n = y.shape[0]
    if method == METHOD_RK4:
        for i in range(n):
            work[i] = y[i] + 0.5 * h * f0[i]
        _rhs(work, k, xi, j1, slope, idle, stages[1])
        for i in range(n):
            work[i] = y[i] + 0.5 * h * stages[1, i]
        _rhs(work, k, xi, j1, slope, idle, stages[2])
        for i in range(n):
            work[i] = y[i] + h * stages[2, i]
        _rhs(work, k, xi, j1, slope, idle, stages[3])
        for i in range(n):
            y_new[i] = y[i] + h / 6.0 * (f0[i] + 2.0 * stages[1, i] + 2.0 * stages[2, i]
                                         + stages[3, i])
            stages[6, i] = 0.0
        _rhs(y_new, k, xi, j1, slope, idle, f_new)
        return
    for i in range(n):
        stages[0, i] = f0[i]
    for s in range(1, 7):
        for i in range(n):
            acc = 0.0
            for j in range(s):
                acc += _A[s, j] * stages[j, i]
            work[i] = y[i] + h * acc
        if s < 6:
            _rhs(work, k, xi, j1, slope, idle, stages[s])
        else:
            for i in range(n):
                y_new[i] = work[i]
            _rhs(y_new, k, xi, j1, slope, idle, f_new)  # first-same-as-last
    for i in range(n):
        acc = _E[6] * f_new[i]
        for j in range(6):
            acc += _E[j] * stages[j, i]
        stages[6, i] = h * acc


@njit(**KERNEL_OPTIONS)
def _error_norm(y, y_new, stages, rtol, atol):
    """RMS of the DOPRI5 error over (phi1, phi1', psi, psi') scaled by atol + rtol |y|; phi1
    grows without bound and what matters is its error per step (a lab-fixed blade sits at
    a rotor angle), so it is scaled as a variable of size 1."""
    total = (stages[6, 0] / (atol + rtol)) ** 2
    for i in range(1, 4):
        sc = atol + rtol * max(abs(y[i]), abs(y_new[i]))
        total += (stages[6, i] / sc) ** 2
    return math.sqrt(total / 4.0)


@njit(**KERNEL_OPTIONS)
def attempt(method, y, f0, h, k, xi, j1, slope, idle, rtol, atol, stages, work, y_new, f_new):
    """One step into y_new, f_new; returns the DOPRI5 error norm (> 1: reject), 0 for RK4."""
    _step(method, y, f0, h, k, xi, j1, slope, idle, stages, work, y_new, f_new)
    if method == METHOD_DOPRI5:
        return _error_norm(y, y_new, stages, rtol, atol)
    return 0.0


@njit(**KERNEL_OPTIONS)
def rotor_turning_value(method, y, f0, h, y_new, k, xi, j1, slope, idle, stages, work, part,
                        f_part):
    """psi at the turning point inside a step (psi' = 0), by Newton on exact partial steps
    from the interpolant's estimate."""
    s = turning_time(h, y[2], y[3], y_new[2], y_new[3])
    for _ in range(4):
        _step(method, y, f0, s, k, xi, j1, slope, idle, stages, work, part, f_part)
        if f_part[3] == 0.0:
            break
        s_new = min(h, max(0.0, s - part[3] / f_part[3]))
        if abs(s_new - s) <= 1e-15 * h:
            break
        s = s_new
    _step(method, y, f0, s, k, xi, j1, slope, idle, stages, work, part, f_part)
    return part[2]


@njit(**KERNEL_OPTIONS)
def rotor_integrate_to(w, psi, dpsi, tau_end, k, xi, j1, motor_slope, idle, dt):
    """RK4 with n = ceil(tau_end/dt) equal steps for the state (phi1', psi, psi')."""
    n = max(1, int(math.ceil(tau_end / dt - 1e-12)))
    h = tau_end / n
    y = np.array([0.0, w, psi, dpsi])
    f0, y_new, f_new = np.empty(4), np.empty(4), np.empty(4)
    stages, work = np.empty((7, 4)), np.empty(4)
    _rhs(y, k, xi, j1, motor_slope, idle, f0)
    for _ in range(n):
        _step(METHOD_RK4, y, f0, h, k, xi, j1, motor_slope, idle, stages, work, y_new, f_new)
        y[:] = y_new
        f0[:] = f_new
    return y[1], y[2], y[3]


@njit(**KERNEL_OPTIONS)
def keep_peak(peak, y, f0, y_new, f_new, best_a, best_fa, best_b, best_fb):
    """If the step ending at y_new has the largest |psi''| so far, keep its start and end
    (where to refine the peak); returns (peak, kept)."""
    if abs(f_new[3]) <= peak:
        return peak, False
    best_a[:] = y
    best_fa[:] = f0
    best_b[:] = y_new
    best_fb[:] = f_new
    return abs(f_new[3]), True


@njit(**KERNEL_OPTIONS)
def rotor_flight(y, k, xi, j1, slope, idle, method, rtol, atol, dt, max_steps, refine_peak):
    """One flight of the rotor model from y (phi1, phi1', psi = 0, psi' < 0 just after an
    impact) to the next impact (psi up through 0) or escape (psi down through -pi: the
    pendulum goes over the top relative to the rotor). Events are located on the cubic
    Hermite interpolant of psi (sign samples and an extremum check, as in the constant-speed
    core) and polished by Newton on exact partial steps; y is left at the event.

    Returns (status, flight time, amplitude max|psi|, peak |psi''|, steps, rejected).
    """
    f0, y_new, f_new = np.empty(4), np.empty(4), np.empty(4)
    stages, work = np.empty((7, 4)), np.empty(4)
    part, f_part = np.empty(4), np.empty(4)
    # the step ending at the largest |psi''|: its start and end states, length, start time
    best_a, best_fa = y.copy(), np.empty(4)
    best_b, best_fb = y.copy(), np.empty(4)
    _rhs(y, k, xi, j1, slope, idle, f0)
    best_h, best_t = 0.0, 0.0
    t = 0.0
    h = initial_step(method, dt, y[3], rtol)
    after_reject = False
    err_prev = 1.0
    steps = rejected = 0
    lowest = 0.0
    peak = abs(f0[3])
    while steps + rejected < max_steps:
        err = attempt(method, y, f0, h, k, xi, j1, slope, idle, rtol, atol, stages, work, y_new,
                      f_new)
        if err > 1.0:
            rejected += 1
            h = next_step(h, err, True)
            after_reject = True
            if h < 1e-14 * max(1.0, t):
                return FLIGHT_UNDERFLOW, t, math.nan, math.nan, steps, rejected
            continue
        steps += 1
        for event in range(2):  # escape first, then impact
            level = -math.pi if event == 0 else 0.0
            s = _first_crossing(h, y[2], y[3], y_new[2], y_new[3], level, event == 1)
            if s < 0.0:
                continue
            for _ in range(4):  # Newton on exact partial steps from the step start
                _step(method, y, f0, s, k, xi, j1, slope, idle, stages, work, part, f_part)
                if part[3] == 0.0:
                    break
                s_new = s - (part[2] - level) / part[3]
                if not (0.0 < s_new <= h) or abs(s_new - s) <= 1e-16 * max(1.0, t):
                    break
                s = s_new
            _step(method, y, f0, s, k, xi, j1, slope, idle, stages, work, part, f_part)
            lowest = min(lowest, part[2])
            peak = max(peak, abs(f_part[3]))
            if refine_peak and best_h > 0.0:
                peak = _refine_peak(best_a, best_fa, best_b, best_fb, best_h,
                                    min(2.0 * best_h, t + s - best_t), k, xi, j1, slope,
                                    idle, method, peak, stages, work, y_new, f_new)
            y[:] = part
            status = FLIGHT_ESCAPE if event == 0 else FLIGHT_IMPACT
            return status, t + s, -lowest, peak, steps, rejected
        lowest = min(lowest, y_new[2])
        if refine_peak and y[3] < 0.0 <= y_new[3]:  # the cycle's amplitude, on the interpolant
            lowest = min(lowest, rotor_turning_value(method, y, f0, h, y_new, k, xi, j1, slope,
                                                     idle, stages, work, part, f_part))
        peak, kept = keep_peak(peak, y, f0, y_new, f_new, best_a, best_fa, best_b, best_fb)
        if kept:
            best_h, best_t = h, t
        t += h
        y[:] = y_new
        f0[:] = f_new
        h, err_prev = accepted_step_size(method, h, dt, err, after_reject, err_prev)
        after_reject = False
    return FLIGHT_MAX_STEPS, t, math.nan, math.nan, steps, rejected


@njit(**KERNEL_OPTIONS)
def _refine_peak(a, fa, b, fb, h, window, k, xi, j1, slope, idle, method, peak, stages, work,
                 part, f_part):
    """Golden-section search for max |psi''| over the two steps around the largest step-end
    value, cut at the event (``window``); each point an exact partial step from the start
    of its own step."""
    def accel_at(s):
        if s <= h:
            _step(method, a, fa, s, k, xi, j1, slope, idle, stages, work, part, f_part)
        else:
            _step(method, b, fb, s - h, k, xi, j1, slope, idle, stages, work, part, f_part)
        return abs(f_part[3])

    lo, hi = 0.0, window
    c, d = golden_points(lo, hi)
    fc, fd = accel_at(c), accel_at(d)
    while hi - lo > 1e-7 * window:
        lo, hi, c, d, fc, fd, left = golden_shrink(lo, hi, c, d, fc, fd)
        if left:
            fc = accel_at(c)
        else:
            fd = accel_at(d)
    return max(peak, fc, fd)


@njit(**KERNEL_OPTIONS)
def _aitken(x0, x1, x2):
    """Aitken's delta-squared limit of x0, x1, x2; x2 itself unless the differences shrink
    geometrically with one sign pattern (ratio in (-0.95, 0.95))."""
    d1, d2 = x1 - x0, x2 - x1
    if d1 == 0.0 or d2 == d1 or not abs(d2 / d1) < 0.95:
        return x2
    return x2 - d2 * d2 / (d2 - d1)


@njit(**KERNEL_OPTIONS)
def rotor_steady(k, xi, kappa, r, j1, slope, idle, method, rtol, atol, dt, max_impacts,
                 regimes, out):
    """Impact-to-impact iteration of the rotor model to its steady regime.

    Starts with the rotor at idle speed and the pendulum at rest on the stop (the first
    impact at once, as in the constant-speed models), then alternates the generalised impact
    (§1.3) and an integrated flight. Regimes (codes ``regimes``: period_1, period_n,
    quasi_periodic, escape) from the pre-impact states (phi1', psi'-): a cycle of p impacts
    repeating to 10 rtol, relative rotation (escape), or no repetition within max_impacts
    while the differences stop shrinking (quasi-periodic). Fills ``out`` as
    ``pendulum.dimensionless`` does; returns 0 ok, 1 escape, 2 not converged, 3 step
    underflow, 4 degenerate (the pendulum does not leave the stop after an impact).
    """
    lam = kappa * (1.0 + 1.0 / xi)
    k_cm = k * lam
    tol = max(10.0 * rtol, 1e-12) if method == METHOD_DOPRI5 else 1e-9
    max_period = 8
    history = np.empty((max_impacts + 1, 2))
    y = np.empty(4)
    w, v = idle, 0.0
    steps = events = 0
    out[ROW_REJECTED] = 0.0  # rejected steps
    p = 0
    j = 0
    for j in range(max_impacts + 1):
        history[j, 0], history[j, 1] = w, v
        p = classify_period(history, j + 1, tol, max_period)
        if p > 0:
            break
        w_plus, v_plus, _ = rotor_impact(w, v, k_cm, xi, j1, lam, r)
        if not v_plus < 0.0:
            # the impact throws the rotor back and the pendulum does not leave the stop:
            # the rotor is too light for the rotor-stop idealisation
            out[ROW_IMPACTS], out[ROW_STEPS], out[ROW_EVENTS] = j + 1, steps, events
            return 4
        y[0], y[1], y[2], y[3] = 0.0, w_plus, 0.0, v_plus
        status, tau, amp, acc, n_ok, n_bad = rotor_flight(
            y, k_cm, xi, j1, slope, idle, method, rtol, atol, dt, 10**6, False)
        steps += n_ok + n_bad
        out[ROW_REJECTED] += n_bad
        events += 1
        if status == FLIGHT_ESCAPE:
            out[ROW_REGIME], out[ROW_IMPACTS] = REGIME_ESCAPE, j + 1
            out[ROW_STEPS], out[ROW_EVENTS] = steps, events
            return 1
        if status != FLIGHT_IMPACT:
            out[ROW_STEPS], out[ROW_EVENTS] = steps, events
            return 3 if status == FLIGHT_UNDERFLOW else 2
        w, v = y[1], y[3]
    if p == 0:
        # no repetition: quasi-periodic if the map has stopped contracting, else too slow
        n = max_impacts + 1
        recent = abs(history[n - 1, 1] - history[n - 2, 1])
        older = abs(history[n // 2, 1] - history[n // 2 - 1, 1]) if n >= 4 else 0.0
        out[ROW_STEPS], out[ROW_EVENTS], out[ROW_IMPACTS] = steps, events, max_impacts
        if n >= 20 and recent > 0.1 * older:
            out[ROW_REGIME] = REGIME_QUASI_PERIODIC
            return 0
        return 2
    out[ROW_REGIME] = REGIME_PERIOD_1 if p == 1 else REGIME_PERIOD_N
    out[ROW_IMPACTS] = j - 2 * p + 1
    start_w, start_v = w, v
    if p == 1 and j >= 2:
        # the iteration stops at |x_j - x_j-1| <= 10 rtol, which leaves rho/(1 - rho) times
        # that as error for a contraction rho; Aitken's delta-squared on the last three
        # iterates removes the geometric tail (H13). Checked below by the cycle's residual.
        start_w = _aitken(history[j - 2, 0], history[j - 1, 0], w)
        start_v = _aitken(history[j - 2, 1], history[j - 1, 1], v)
    last_step = max(abs(w - history[j - 1, 0]), abs(v - history[j - 1, 1]))
    for attempt in range(2):
        # the steady cycle: p flights from the repeating state, with the peak refined
        cw, cv = start_w, start_v
        amp_max = acc_max = 0.0
        rotor_angle = flight_time = speed = 0.0
        for q in range(p):
            speed += (k + 1.0) * cw + cv  # striker normal speed, omega1 l_contact units
            w_plus, v_plus, _ = rotor_impact(cw, cv, k_cm, xi, j1, lam, r)
            y[0], y[1], y[2], y[3] = 0.0, w_plus, 0.0, v_plus
            status, tau, amp, acc, n_ok, n_bad = rotor_flight(
                y, k_cm, xi, j1, slope, idle, method, rtol, atol, dt, 10**6, True)
            steps += n_ok + n_bad
            out[ROW_REJECTED] += n_bad
            events += 1
            if status != FLIGHT_IMPACT:  # the cycle did not repeat after all
                out[ROW_REGIME] = math.nan
                out[ROW_STEPS], out[ROW_EVENTS] = steps, events
                return 2
            amp_max, acc_max = max(amp_max, amp), max(acc_max, acc)
            rotor_angle += y[0]
            flight_time += tau
            cw, cv = y[1], y[3]
        residual = max(abs(cw - start_w), abs(cv - start_v))
        if residual <= last_step or (start_w == w and start_v == v):
            break
        start_w, start_v = w, v  # the extrapolation did not help (e.g. a spiralling map)
    out[ROW_AMPLITUDE] = amp_max
    out[ROW_FREQUENCY] = math.pi * p / flight_time
    out[ROW_INTERVAL] = rotor_angle / p
    out[ROW_SPEED] = speed / p
    out[ROW_ACCEL] = acc_max
    out[ROW_STEPS], out[ROW_EVENTS] = steps, events
    out[ROW_ROTOR_SPEED] = rotor_angle / flight_time
    return 0
