"""The rotor model (P8-P10) against the lab-fixed blade (dynamics.md §1.7): the blade's
gap G = phi1 + beta(psi) now moves with the rotor's own angle, a state of the flight.

Same geometry and contact rules as kernels/pendulum_lab.py, with the 2-DOF dynamics:
- impact: generalised Newton impulse along the blade's normal, Jacobian J = (1, h(psi)) on
  q' = (phi1', psi') (G' = J q'), P = -(1 + R) G' / (J M^-1 J^T), q'+ = q'- + M^-1 J^T P;
- slide: the constraint G = const leaves one degree of freedom: q'' = M^-1 (Q + J^T lam)
  with J q'' + h' psi'^2 = 0, integrated by RK4 on (psi, psi') (phi1 = L - beta(psi),
  phi1' = -h psi') until the contact force would pull (release) or |psi| reaches the
  blade's edge.
Units as in kernels/pendulum_rotor.py (time in omega1, lengths in l_cm, inertias in J_c);
k = l1/l_contact enters beta and h, k_cm = k lam the mass matrix.
"""

import math

import numpy as np
from numba import njit

from kernels import KERNEL_OPTIONS
from kernels.pendulum import *  # noqa: F401,F403  (ROW_*, REGIME_*)
from kernels.pendulum import (SUBSTEP_SAMPLES, _hermite, accepted_step_size, classify_period,
                              hermite_slope, initial_step, next_step)
from kernels.pendulum_lab import (LAB_CONTACT, LAB_ESCAPE, LAB_MAX_STEPS, LAB_NO_IMPACT,
                                  LAB_UNDERFLOW, SECTION_MIN_FLIGHT, SPEED_EPS, beta,
                                  flight_outcome, h_ratio, h_slope)
from kernels.pendulum_rotor import (METHOD_DOPRI5, _refine_peak, _rhs, _step, attempt, keep_peak,
                                    rotor_accelerations, rotor_mass_matrix,
                                    rotor_turning_value)

SLIDE_STEP = 1e-3  # RK4 step of the slide [rotor rad]: its error (~step^4) is round-off


@njit(**KERNEL_OPTIONS)
def _gap(s, h, y, y_new, k):
    """G on the step's interpolant (phi1 with phi1' = w, psi with psi')."""
    return (_hermite(s, h, y[0], y[1], y_new[0], y_new[1])
            + beta(_hermite(s, h, y[2], y[3], y_new[2], y_new[3]), k))


@njit(**KERNEL_OPTIONS)
def _gap_rate(s, h, y, f0, y_new, f_new, k):
    """G' = phi1' + h psi' on the step's interpolants."""
    w = _hermite(s, h, y[1], f0[1], y_new[1], f_new[1])
    psi = _hermite(s, h, y[2], y[3], y_new[2], y_new[3])
    return w + h_ratio(psi, k) * hermite_slope(s, h, y[2], y[3], y_new[2], y_new[3])


@njit(**KERNEL_OPTIONS)
def _crossing(h, y, f0, y_new, f_new, k, level, upward):
    """First s in (0, h] where G crosses level in the given direction: sign samples, the
    extremum where G' changes sign between samples (H3), bisection; the step start never
    counts (H4). -1 if none."""
    n = SUBSTEP_SAMPLES + 1
    prev_s, prev = 0.0, _gap(0.0, h, y, y_new, k) - level
    prev_rate = _gap_rate(0.0, h, y, f0, y_new, f_new, k)
    for j in range(1, n + 1):
        s = h * j / n
        val = _gap(s, h, y, y_new, k) - level
        rate = _gap_rate(s, h, y, f0, y_new, f_new, k)
        if (prev_rate > 0.0 > rate) if upward else (prev_rate < 0.0 < rate):
            lo, hi = prev_s, s
            for _ in range(60):
                mid = 0.5 * (lo + hi)
                if (_gap_rate(mid, h, y, f0, y_new, f_new, k) > 0.0) == upward:
                    lo = mid
                else:
                    hi = mid
            ext = _gap(0.5 * (lo + hi), h, y, y_new, k) - level
            if (prev < 0.0 <= ext) if upward else (prev > 0.0 >= ext):
                s, val = 0.5 * (lo + hi), ext
        if (prev < 0.0 <= val) if upward else (prev > 0.0 >= val):
            lo, hi = prev_s, s
            for _ in range(60):
                mid = 0.5 * (lo + hi)
                if ((_gap(mid, h, y, y_new, k) - level < 0.0) == (prev < 0.0)):
                    lo = mid
                else:
                    hi = mid
            return hi
        prev_s, prev, prev_rate = s, val, rate
    return -1.0


@njit(**KERNEL_OPTIONS)
def gap_free_acceleration(y, k, k_cm, xi, j1, slope, idle):
    """G'' of the free motion at state y: phi1'' + h psi'' + h' psi'^2."""
    a1, b2 = rotor_accelerations(y[1], y[2], y[3], k_cm, xi, j1, slope, idle)
    return a1 + h_ratio(y[2], k) * b2 + h_slope(y[2], k) * y[3] * y[3]


@njit(**KERNEL_OPTIONS)
def blade_impact(y, r, k, k_cm, xi, j1):
    """Newton's law on the blade's normal: G'+ = -R G'-; updates y[1], y[3]."""
    m11, m12, m22 = rotor_mass_matrix(y[2], k_cm, xi, j1)
    det = m11 * m22 - m12 * m12
    hr = h_ratio(y[2], k)
    x_a = (m22 - m12 * hr) / det  # M^-1 J^T, J = (1, h)
    x_b = (m11 * hr - m12) / det
    impulse = -(1.0 + r) * (y[1] + hr * y[3]) / (x_a + hr * x_b)
    y[1] += x_a * impulse
    y[3] += x_b * impulse


@njit(**KERNEL_OPTIONS)
def _slide_accel(psi, dpsi, level, k, k_cm, xi, j1, slope, idle):
    """(psi'' on the blade, pressing side-free G''_free) with phi1 = level - beta(psi)."""
    hr = h_ratio(psi, k)
    w = -hr * dpsi
    a1, b2 = rotor_accelerations(w, psi, dpsi, k_cm, xi, j1, slope, idle)
    g2 = a1 + hr * b2 + h_slope(psi, k) * dpsi * dpsi
    m11, m12, m22 = rotor_mass_matrix(psi, k_cm, xi, j1)
    det = m11 * m22 - m12 * m12
    x_a = (m22 - m12 * hr) / det
    x_b = (m11 * hr - m12) / det
    lam = -g2 / (x_a + hr * x_b)  # the contact force keeps G'' = 0
    return b2 + x_b * lam, g2


@njit(**KERNEL_OPTIONS)
def _slide_step(psi, dpsi, s, level, k, k_cm, xi, j1, slope, idle):
    a1 = _slide_accel(psi, dpsi, level, k, k_cm, xi, j1, slope, idle)[0]
    p2, d2 = psi + 0.5 * s * dpsi, dpsi + 0.5 * s * a1
    a2 = _slide_accel(p2, d2, level, k, k_cm, xi, j1, slope, idle)[0]
    p3, d3 = psi + 0.5 * s * d2, dpsi + 0.5 * s * a2
    a3 = _slide_accel(p3, d3, level, k, k_cm, xi, j1, slope, idle)[0]
    p4, d4 = psi + s * d3, dpsi + s * a3
    a4 = _slide_accel(p4, d4, level, k, k_cm, xi, j1, slope, idle)[0]
    return (psi + s / 6.0 * (dpsi + 2.0 * d2 + 2.0 * d3 + d4),
            dpsi + s / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4))


@njit(**KERNEL_OPTIONS)
def starts_pressed(y, level, side, k, k_cm, xi, j1, slope, idle):
    """Does a contact with G' = 0 start a slide? The free G'' pressing into the face; where
    it vanishes (at psi = 0 both h' and psi'' vanish and a stiff rotor's phi1'' is
    round-off: a degenerate touch), the pressing a short way along the slide decides."""
    now = side * gap_free_acceleration(y, k, k_cm, xi, j1, slope, idle)
    if abs(now) > 1e-9:
        return now > 0.0
    dpsi = -y[1] / h_ratio(y[2], k)
    p1, d1 = _slide_step(y[2], dpsi, 1e-4, level, k, k_cm, xi, j1, slope, idle)
    return side * _slide_accel(p1, d1, level, k, k_cm, xi, j1, slope, idle)[1] > 0.0


@njit(**KERNEL_OPTIONS)
def rotor_slide(y, level, side, window, k, k_cm, xi, j1, slope, idle):
    """Slide along the blade face at G = level while pressed; y (phi1, w, psi, psi') is
    updated to the end. Returns (released, time taken, peak |psi''|): released = True if
    the pressing falls to zero, False if the striker slides off the blade's edge."""
    psi, dpsi = y[2], -(y[1]) / h_ratio(y[2], k)  # on the face: G' = 0
    t, peak = 0.0, 0.0
    released = False
    for _ in range(10**6):
        acc, g2 = _slide_accel(psi, dpsi, level, k, k_cm, xi, j1, slope, idle)
        peak = max(peak, abs(acc))
        p1, d1 = _slide_step(psi, dpsi, SLIDE_STEP, level, k, k_cm, xi, j1, slope, idle)
        g2_new = _slide_accel(p1, d1, level, k, k_cm, xi, j1, slope, idle)[1]
        off = abs(p1) >= window
        lets_go = side * g2_new <= 0.0
        if off or lets_go:
            lo, hi = 0.0, SLIDE_STEP  # the event on exact partial steps, by bisection
            for _ in range(60):
                mid = 0.5 * (lo + hi)
                pm, dm = _slide_step(psi, dpsi, mid, level, k, k_cm, xi, j1, slope, idle)
                gm = _slide_accel(pm, dm, level, k, k_cm, xi, j1, slope, idle)[1]
                if (abs(pm) >= window) or side * gm <= 0.0:
                    hi = mid
                else:
                    lo = mid
            pm, dm = _slide_step(psi, dpsi, hi, level, k, k_cm, xi, j1, slope, idle)
            released = abs(pm) < window * (1.0 - 1e-12)  # else it reached the edge first
            psi, dpsi, t = pm, dm, t + hi
            break
        psi, dpsi, t = p1, d1, t + SLIDE_STEP
    hr = h_ratio(psi, k)
    y[0], y[1], y[2], y[3] = level - beta(psi, k), -hr * dpsi, psi, dpsi
    return released, t, peak


@njit(**KERNEL_OPTIONS)
def rotor_lab_flight(y, lower, window, k, k_cm, xi, j1, slope, idle, method, rtol, atol, dt,
                     max_steps, horizon):
    """Free flight of the rotor model between the blade faces at G = lower and lower + 2 pi,
    to a contact (|psi| <= window there), escape (|psi| reaching pi) or the horizon; a face
    met with |psi| > window is passed. y is left at the event.

    Returns (status, time, face level, +1 ahead / -1 behind, passes, amplitude, peak |psi''|,
    steps, rejected).
    """
    f0, y_new, f_new = np.empty(4), np.empty(4), np.empty(4)
    stages, work = np.empty((7, 4)), np.empty(4)
    part, f_part = np.empty(4), np.empty(4)
    best_a, best_fa, best_b, best_fb = y.copy(), np.empty(4), y.copy(), np.empty(4)
    _rhs(y, k_cm, xi, j1, slope, idle, f0)
    best_h, best_t = 0.0, 0.0
    h = initial_step(method, dt, y[3], rtol)
    g1 = y[1] + h_ratio(y[2], k) * y[3]
    g2 = gap_free_acceleration(y, k, k_cm, xi, j1, slope, idle)
    if g1 * g2 < 0.0:  # pulled back to the face it leaves: see the bounce (H4)
        h = min(h, 0.5 * abs(g1) / abs(g2))
    t = 0.0
    steps = rejected = passes = 0
    amp, peak = abs(y[2]), abs(f0[3])
    after_reject = False
    err_prev = 1.0
    while steps + rejected < max_steps:
        if t > horizon:
            return LAB_NO_IMPACT, t, math.nan, 0.0, passes, amp, peak, steps, rejected
        err = attempt(method, y, f0, h, k_cm, xi, j1, slope, idle, rtol, atol, stages, work,
                      y_new, f_new)
        if err > 1.0:
            rejected += 1
            h = next_step(h, err, True)
            after_reject = True
            if h < 1e-14 * max(1.0, t):
                return LAB_UNDERFLOW, t, math.nan, 0.0, passes, amp, peak, steps, rejected
            continue
        steps += 1
        if abs(y_new[2]) >= math.pi:
            y[:] = y_new
            return LAB_ESCAPE, t + h, math.nan, 0.0, passes, math.pi, peak, steps, rejected
        s_up = _crossing(h, y, f0, y_new, f_new, k, lower + 2.0 * math.pi, True)
        s_dn = _crossing(h, y, f0, y_new, f_new, k, lower, False)
        if s_up >= 0.0 or s_dn >= 0.0:
            up = s_up >= 0.0 and (s_dn < 0.0 or s_up <= s_dn)
            level = lower + 2.0 * math.pi if up else lower
            s = s_up if up else s_dn
            for _ in range(4):  # Newton on exact partial steps: G(s) = level
                _step(method, y, f0, s, k_cm, xi, j1, slope, idle, stages, work, part, f_part)
                rate = part[1] + h_ratio(part[2], k) * part[3]
                if rate == 0.0:
                    break
                s_new = s - (part[0] + beta(part[2], k) - level) / rate
                if not (0.0 < s_new <= h) or abs(s_new - s) <= 1e-16 * max(1.0, t):
                    break
                s = s_new
            _step(method, y, f0, s, k_cm, xi, j1, slope, idle, stages, work, part, f_part)
            if abs(part[2]) <= window:
                peak = max(peak, abs(f_part[3]))
                if best_h > 0.0:
                    peak = _refine_peak(best_a, best_fa, best_b, best_fb, best_h,
                                        min(2.0 * best_h, t + s - best_t), k_cm, xi, j1,
                                        slope, idle, method, peak, stages, work, y_new, f_new)
                y[:] = part
                return (LAB_CONTACT, t + s, level, 1.0 if up else -1.0, passes,
                        max(amp, abs(part[2])), peak, steps, rejected)
            passes += 1  # inside the blade: the state goes on unchanged from here
            lower = level if up else lower - 2.0 * math.pi
            t += s
            y[:] = part
            f0[:] = f_part
            continue
        amp = max(amp, abs(y_new[2]))
        if (y[3] < 0.0) != (y_new[3] < 0.0):
            amp = max(amp, abs(rotor_turning_value(method, y, f0, h, y_new, k_cm, xi, j1,
                                                   slope, idle, stages, work, part, f_part)))
        peak, kept = keep_peak(peak, y, f0, y_new, f_new, best_a, best_fa, best_b, best_fb)
        if kept:
            best_h, best_t = h, t
        t += h
        y[:] = y_new
        f0[:] = f_new
        h, err_prev = accepted_step_size(method, h, dt, err, after_reject, err_prev)
        after_reject = False
    return LAB_MAX_STEPS, t, math.nan, 0.0, passes, amp, peak, steps, rejected


@njit(**KERNEL_OPTIONS)
def rotor_lab_steady(k, xi, kappa, r, window, j1, slope, idle, method, rtol, atol, dt,
                     max_impacts, horizon, regimes, out, impact_log):
    """The rotor model on the blade to its steady regime, as lab_steady does for the
    constant-speed models; the section state is (psi, G'-, phi1') at the impact opening a
    contact episode. impact_log[j] = (phi1 mod 2 pi, psi) of section impact j. Returns 0 ok,
    1 escape, 2 not converged, 3 step underflow."""
    lam = kappa * (1.0 + 1.0 / xi)
    k_cm = k * lam
    tol = max(10.0 * rtol, 1e-12) if method == METHOD_DOPRI5 else 1e-9
    history = np.empty((max_impacts + 1, 3))
    info = np.empty((max_impacts + 1, 6))  # time, phi1, speed, amplitude, peak, zeno
    y = np.array([0.0, idle, 0.0, 0.0])  # the striker at rest relative to the rotor, on
    level, side = 0.0, 1.0  # the blade's working face: the first impact at once
    t = 0.0
    steps = events = 0
    out[ROW_REJECTED] = 0.0
    n_sec = 0
    p = 0
    finished = False
    amp_since = peak_since = zeno_since = 0.0
    flight_time = 1.0
    for _ in range(200 * (max_impacts + 1)):
        gdot = y[1] + h_ratio(y[2], k) * y[3]
        if flight_time >= SECTION_MIN_FLIGHT:
            history[n_sec, 0], history[n_sec, 1], history[n_sec, 2] = y[2], gdot, y[1]
            slot = min(n_sec, impact_log.shape[0] - 1)
            impact_log[slot, 0], impact_log[slot, 1] = y[0] % (2.0 * math.pi), y[2]
            info[n_sec, 0], info[n_sec, 1] = t, y[0]
            info[n_sec, 2] = math.sqrt(k * k + 1.0 + 2.0 * k * math.cos(y[2])) * abs(gdot)
            if n_sec > 0:
                info[n_sec - 1, 3], info[n_sec - 1, 4] = amp_since, peak_since
                info[n_sec - 1, 5] = zeno_since
            amp_since = peak_since = zeno_since = 0.0
            n_sec += 1
            p = classify_period(history, n_sec, tol, 8)
            if p > 0 or n_sec > max_impacts:
                finished = True
                break
        zeno = abs(gdot) < SPEED_EPS
        if zeno and r > 0.0:  # the chatter's accumulation point (H6)
            g2 = abs(gap_free_acceleration(y, k, k_cm, xi, j1, slope, idle))
            if g2 > 0.0:
                t += 2.0 * r * abs(gdot) / (g2 * (1.0 - r))
            zeno_since = 1.0
        blade_impact(y, 0.0 if zeno else r, k, k_cm, xi, j1)
        if (r == 0.0 or zeno) and starts_pressed(y, level, side, k, k_cm, xi, j1, slope,
                                                 idle):
            released, taken, acc = rotor_slide(y, level, side, window, k, k_cm, xi, j1, slope,
                                               idle)
            t += taken
            peak_since = max(peak_since, acc)
            if not released:  # off the blade's edge: past it in the pressing direction
                level = level if side > 0.0 else level - 2.0 * math.pi
                side = 0.0
        lower = level - 2.0 * math.pi if side > 0.0 else level
        (status, taken, level, side, passes, amp, peak, n_ok,
         n_bad) = rotor_lab_flight(y, lower, window, k, k_cm, xi, j1, slope, idle, method,
                                   rtol, atol, dt, 10**6, horizon)
        steps += n_ok + n_bad
        out[ROW_REJECTED] += n_bad
        events += 1 + passes
        amp_since, peak_since = max(amp_since, amp), max(peak_since, peak)
        flight_time = taken
        t += taken
        code = flight_outcome(status, n_sec, steps, events, regimes, out)
        if code >= 0:
            return code
    out[ROW_STEPS], out[ROW_EVENTS] = steps, events
    if not finished:
        return 2
    if p == 0:
        out[ROW_REGIME], out[ROW_IMPACTS] = REGIME_QUASI_PERIODIC, max_impacts
        return 0
    first = n_sec - 1 - p
    span = angle = speed = amp = peak = zeno = 0.0
    for q in range(first, n_sec - 1):
        span += info[q + 1, 0] - info[q, 0]
        angle += info[q + 1, 1] - info[q, 1]
        speed += info[q, 2]
        amp, peak = max(amp, info[q, 3]), max(peak, info[q, 4])
        zeno = max(zeno, info[q, 5])
    out[ROW_REGIME] = (REGIME_CHATTER if zeno > 0.0 else
                       REGIME_PERIOD_1 if p == 1 else REGIME_PERIOD_N)
    out[ROW_AMPLITUDE] = amp
    out[ROW_INTERVAL] = angle / p
    out[ROW_SPEED] = speed / p
    out[ROW_IMPACTS] = n_sec - 1 - 2 * p + 1
    out[ROW_ACCEL] = peak
    out[ROW_ROTOR_SPEED] = angle / span
    return 0
