"""A tool fixed in the frame (dynamics.md §1.7, H11) for the constant-speed pendulum models.

Geometry, lengths in l_contact (hinge A to the striker's contact point), rotor angle tau:
the contact point C is at radius rho = sqrt(X), X = k^2 + 1 + 2k cos psi, and at the polar
angle tau + beta(psi), beta = atan2(sin psi, k + cos psi) ahead of the rotor arm. The tool is
a radial blade at lab angle 0 reaching in from the outside down to radius rho_T = sqrt(X(w)):
the striker meets it only while |psi| <= w (``tool_window``), otherwise it passes inside.

Gap function: G = tau + beta(psi) (the striker's polar angle) against the blade at G = 2 pi m;
its normal speed is rho G' with G' = 1 + h psi', h = dbeta/dpsi = (1 + k cos psi)/X > 0 for
|psi| <= pi/2. An impact is G reaching a blade face (either face) with |psi| <= w; Newton's
law G'+ = -R G'- with omega1 held by the drive gives psi'+ = (-R G'- - 1)/h (at psi = 0 this
is the paper's law (5)). After a plastic contact (R = 0, or a chatter sequence accumulated
by the Zeno guard) the striker slides along the blade while it is pressed into it: then
G = const fixes psi(tau) in closed form (tau = L - beta(psi)), until the free motion would
leave the face (release) or the striker slides off the blade's inner edge (|psi| = w).
"""

import math

import numpy as np
from numba import njit

from kernels import KERNEL_OPTIONS
from kernels.pendulum import *  # noqa: F401,F403  (ROW_*, REGIME_*)
from kernels.pendulum import (METHOD_DOPRI5, SUBSTEP_SAMPLES, _hermite, _refine_peak,
                              accepted_step_size, acceleration, attempt_step,
                              classify_period, hermite_slope, illinois, initial_step,
                              interpolated_event, next_step, track_peak, turning_value)

LAB_CONTACT, LAB_ESCAPE, LAB_NO_IMPACT, LAB_MAX_STEPS, LAB_UNDERFLOW = 0, 1, 2, 3, 4
SPEED_EPS = 1e-7  # Zeno guard: contact speeds G' below this accumulate (H6)
SLIDE_SAMPLES = 128  # release-test samples along a slide
SECTION_MIN_FLIGHT = 0.1  # impacts after a shorter flight belong to the previous episode


@njit(**KERNEL_OPTIONS)
def beta(psi, k):
    """Polar angle of the contact point ahead of the rotor arm."""
    return math.atan2(math.sin(psi), k + math.cos(psi))


@njit(**KERNEL_OPTIONS)
def h_ratio(psi, k):
    """h = dbeta/dpsi = (1 + k cos psi)/X."""
    return (1.0 + k * math.cos(psi)) / (k * k + 1.0 + 2.0 * k * math.cos(psi))


@njit(**KERNEL_OPTIONS)
def h_slope(psi, k):
    """dh/dpsi = k (1 - k^2) sin psi / X^2."""
    x = k * k + 1.0 + 2.0 * k * math.cos(psi)
    return k * (1.0 - k * k) * math.sin(psi) / (x * x)


@njit(**KERNEL_OPTIONS)
def gap_acceleration(model, psi, dpsi, k, xi, kappa):
    """G'' of the free motion: h psi'' + h' psi'^2."""
    return (h_ratio(psi, k) * acceleration(model, psi, dpsi, k, xi, kappa)
            + h_slope(psi, k) * dpsi * dpsi)


@njit(**KERNEL_OPTIONS)
def _gap_rate_on_step(s, h, y0, d0, y1, d1, k):
    p = _hermite(s, h, y0, d0, y1, d1)
    return 1.0 + h_ratio(p, k) * hermite_slope(s, h, y0, d0, y1, d1)


@njit(**KERNEL_OPTIONS)
def _gap_crossing(t, h, y0, d0, y1, d1, k, level, upward):
    """First s in (0, h] where G crosses ``level`` in the given direction on the step's
    interpolant: sign samples, plus G's extremum where G' changes sign between samples (a
    grazing touch of the blade is not stepped over, H3), then Illinois. The step start never
    counts (H4). -1 if none."""
    n = SUBSTEP_SAMPLES + 1
    prev_s = 0.0
    prev = interpolated_event(0.0, t, h, y0, d0, y1, d1, level, k)
    prev_rate = _gap_rate_on_step(0.0, h, y0, d0, y1, d1, k)
    for j in range(1, n + 1):
        s = h * j / n
        val = interpolated_event(s, t, h, y0, d0, y1, d1, level, k)
        rate = _gap_rate_on_step(s, h, y0, d0, y1, d1, k)
        turns = (prev_rate > 0.0 > rate) if upward else (prev_rate < 0.0 < rate)
        if turns:  # G has an extremum in (prev_s, s): test it first
            lo, hi = prev_s, s
            for _ in range(60):
                mid = 0.5 * (lo + hi)
                r = _gap_rate_on_step(mid, h, y0, d0, y1, d1, k)
                if (r > 0.0) == upward:
                    lo = mid
                else:
                    hi = mid
            ext_s = 0.5 * (lo + hi)
            ext = interpolated_event(ext_s, t, h, y0, d0, y1, d1, level, k)
            if (prev < 0.0 <= ext) if upward else (prev > 0.0 >= ext):
                s, val = ext_s, ext
        crossed = (prev < 0.0 <= val) if upward else (prev > 0.0 >= val)
        if crossed:
            return illinois(prev_s, s, prev, val, t, h, y0, d0, y1, d1, level, k)
        prev_s, prev, prev_rate = s, val, rate
    return -1.0


@njit(**KERNEL_OPTIONS)
def lab_flight(model, t0, psi0, dpsi0, lower, window, k, xi, kappa, method, rtol, atol, dt,
               max_steps, horizon):
    """Free flight between the blade faces at G = lower and G = lower + 2 pi, to the next
    contact (a face reached with |psi| <= window), escape (|psi| reaching pi) or the horizon.
    A face reached with |psi| > window is passed (the striker goes inside the blade).

    Returns (status, tau, psi, psi', face level, +1 for the face ahead / -1 behind,
    passes, amplitude max|psi|, peak |psi''|, steps, rejected).
    """
    nan = math.nan
    t, y0, y1 = t0, psi0, dpsi0
    f0 = acceleration(model, y0, y1, k, xi, kappa)
    h = initial_step(method, dt, dpsi0, rtol)
    g1 = 1.0 + h_ratio(y0, k) * y1
    g2 = gap_acceleration(model, y0, y1, k, xi, kappa)
    if g1 * g2 < 0.0:
        # leaving a face but pulled back to it: the first step ends before the ballistic
        # return 2|G'|/|G''|, or a short bounce falls inside the first sample interval (H4)
        h = min(h, 0.5 * abs(g1) / abs(g2))
    steps = rejected = passes = 0
    amp = abs(y0)
    peak = abs(f0)
    after_reject = False
    err_prev = 1.0
    best = (y0, y1, f0, y0, y1, f0, 0.0)  # the step ending at the largest |psi''|
    best_t = t0
    while steps + rejected < max_steps:
        if t - t0 > horizon:
            return (LAB_NO_IMPACT, t, y0, y1, nan, 0.0, passes, amp, peak, steps, rejected)
        n0, n1, fn, err = attempt_step(model, y0, y1, f0, h, k, xi, kappa, method, rtol, atol)
        if err > 1.0:
            rejected += 1
            h = next_step(h, err, True)
            after_reject = True
            if h < 1e-14 * max(1.0, t):
                return (LAB_UNDERFLOW, t, y0, y1, nan, 0.0, passes, amp, peak, steps,
                        rejected)
            continue
        steps += 1
        # escape: |psi| through pi (relative rotation), located on the interpolant
        if abs(n0) >= math.pi:
            lvl = math.pi if n0 > 0.0 else -math.pi
            lo, hi = 0.0, h
            for _ in range(100):
                mid = 0.5 * (lo + hi)
                if abs(_hermite(mid, h, y0, y1, n0, n1)) >= math.pi:
                    hi = mid
                else:
                    lo = mid
            return (LAB_ESCAPE, t + hi, lvl, n1, nan, 0.0, passes, math.pi, peak, steps,
                    rejected)
        # the blade: the earliest crossing of either face on this step
        s_up = _gap_crossing(t, h, y0, y1, n0, n1, k, lower + 2.0 * math.pi, True)
        s_dn = _gap_crossing(t, h, y0, y1, n0, n1, k, lower, False)
        if s_up >= 0.0 or s_dn >= 0.0:
            up = s_up >= 0.0 and (s_dn < 0.0 or s_up <= s_dn)
            level = lower + 2.0 * math.pi if up else lower
            s = s_up if up else s_dn
            for _ in range(4):  # Newton on exact partial steps: t + s + beta(psi(s)) = level
                p0, p1, pf, _ = attempt_step(model, y0, y1, f0, s, k, xi, kappa, method,
                                             rtol, atol)
                rate = 1.0 + h_ratio(p0, k) * p1
                if rate == 0.0:
                    break
                s_new = s - (t + s + beta(p0, k) - level) / rate
                if not (0.0 < s_new <= h) or abs(s_new - s) <= 1e-16 * max(1.0, t):
                    break
                s = s_new
            p0, p1, pf, _ = attempt_step(model, y0, y1, f0, s, k, xi, kappa, method,
                                             rtol, atol)
            if abs(p0) <= window:
                peak = max(peak, abs(pf))
                peak = _refine_peak(model, best, min(2.0 * best[6], t + s - best_t), k, xi,
                                    kappa, method, peak, rtol)
                amp = max(amp, abs(p0))
                return (LAB_CONTACT, t + s, p0, p1, level, 1.0 if up else -1.0, passes,
                        amp, peak, steps, rejected)
            # passed inside the blade: the faces move on, the step continues from here
            passes += 1
            lower = level if up else lower - 2.0 * math.pi
            t, y0, y1, f0 = t + s, p0, p1, pf  # a pass leaves the state as it is
            continue
        amp = max(amp, abs(n0))
        if (y1 < 0.0) != (n1 < 0.0):  # a turning point inside the step
            amp = max(amp, abs(turning_value(model, y0, y1, f0, h, n0, n1, k, xi, kappa,
                                             method)))
        peak, best, best_t = track_peak(peak, best, best_t, t, h, y0, y1, f0, n0, n1, fn)
        t += h
        y0, y1, f0 = n0, n1, fn
        h, err_prev = accepted_step_size(method, h, dt, err, after_reject, err_prev)
        after_reject = False
    return (LAB_MAX_STEPS, t, y0, y1, nan, 0.0, passes, amp, peak, steps, rejected)


@njit(**KERNEL_OPTIONS)
def _pressed(model, psi, side, k, xi, kappa):
    """Pressing of the free motion into the face while sliding (G' = 0, psi' = -1/h):
    side * G''_free; > 0 keeps the contact."""
    dpsi = -1.0 / h_ratio(psi, k)
    return side * gap_acceleration(model, psi, dpsi, k, xi, kappa)


@njit(**KERNEL_OPTIONS)
def _starts_pressed(model, psi, side, k, xi, kappa):
    """Does a contact with zero normal speed start a slide? The pressing at the contact, or,
    where it vanishes (at psi = 0 both h' and psi''_free vanish: a degenerate touch), just
    along the slide, where psi has fallen."""
    now = _pressed(model, psi, side, k, xi, kappa)
    if abs(now) > 1e-12:
        return now > 0.0
    return _pressed(model, psi - 1e-6, side, k, xi, kappa) > 0.0


@njit(**KERNEL_OPTIONS)
def slide(model, level, psi_c, side, window, k, xi, kappa):
    """Sliding along the blade face at G = level from psi_c while pressed. psi falls
    monotonically (tau = level - beta(psi) grows); sample the pressing on a grid to the
    blade's edge psi = -window, bisect its first sign change.

    Returns (released, tau, psi, psi', peak |psi''|): released = True if the striker leaves
    the face (pressing falls to 0), False if it slides off the inner edge.
    """
    peak = 0.0
    prev_psi = psi_c
    end = -window
    for j in range(1, SLIDE_SAMPLES + 1):
        p = psi_c + (end - psi_c) * j / SLIDE_SAMPLES
        hr = h_ratio(p, k)
        peak = max(peak, abs(h_slope(p, k) / (hr * hr * hr)))  # psi'' = -h'/h^3 on the face
        if _pressed(model, p, side, k, xi, kappa) <= 0.0:
            lo, hi = p, prev_psi  # pressed at hi, not at lo
            for _ in range(80):
                mid = 0.5 * (lo + hi)
                if _pressed(model, mid, side, k, xi, kappa) > 0.0:
                    hi = mid
                else:
                    lo = mid
            q = 0.5 * (lo + hi)
            return True, level - beta(q, k), q, -1.0 / h_ratio(q, k), peak
        prev_psi = p
    return False, level - beta(end, k), end, -1.0 / h_ratio(end, k), peak


@njit(**KERNEL_OPTIONS)
def _constraint_psi(level, tau, psi_guess, k):
    """psi on the face G = level at rotor angle tau (Newton on beta(psi) = level - tau)."""
    p = psi_guess
    for _ in range(50):
        step = (beta(p, k) - (level - tau)) / h_ratio(p, k)
        p -= step
        if abs(step) <= 1e-15:
            break
    return p


@njit(**KERNEL_OPTIONS)
def flight_outcome(status, n_sec, steps, events, regimes, out):
    """What a blade flight's status means for the steady-state search: -1 to go on (a
    contact), else the kernel's return code, with out filled (escape, no_impact, failure)."""
    out[ROW_STEPS], out[ROW_EVENTS] = steps, events
    if status == LAB_CONTACT:
        return -1
    if status == LAB_ESCAPE:
        out[ROW_REGIME], out[ROW_IMPACTS] = REGIME_ESCAPE, n_sec
        return 1
    if status == LAB_NO_IMPACT:
        out[ROW_REGIME], out[ROW_IMPACTS] = REGIME_NO_IMPACT, n_sec
        return 0
    return 3 if status == LAB_UNDERFLOW else 2


@njit(**KERNEL_OPTIONS)
def lab_steady(model, k, xi, kappa, r, window, method, rtol, atol, dt, max_impacts,
               horizon, regimes, out, impact_log):
    """Impact sequence on the lab-fixed blade to the steady regime.

    Start: the striker at rest relative to the rotor at psi = 0 on the blade (the first
    impact at once, as on the rotor stop). The Poincare section is the impact opening each
    contact episode (an impact after a free flight of at least SECTION_MIN_FLIGHT rotor
    radians); its state (psi, G'-) classifies period_1 / period_n (a cycle of p section
    impacts repeating to 10 rtol), quasi_periodic (no repetition within max_impacts section
    impacts), escape, no_impact (no contact within ``horizon`` rotor radians), chatter (the
    steady cycle contains an accumulation of impacts, H6). impact_log[j] records the
    section impact's rotor angle mod 2 pi and psi (H11). Fills ``out`` as dimensionless does (plus
    the mean rotor speed 1); returns the kernel status (0 ok, 1 escape, 2 not converged, 3
    step underflow).
    """
    tol = max(10.0 * rtol, 1e-12) if method == METHOD_DOPRI5 else 1e-9
    max_period = 8
    history = np.empty((max_impacts + 1, 2))
    cycle_info = np.empty((max_impacts + 1, 6))  # tau, speed, amp, peak, zeno, events
    t, psi, dpsi = 0.0, 0.0, 0.0
    level, side = 0.0, 1.0  # on the blade's working face, arrived from behind
    gdot = 1.0  # G'- of the first impact: the striker arrives with the rotor's speed
    steps = events = 0
    out[ROW_REJECTED] = 0.0  # rejected steps
    n_sec = 0
    zeno_since = 0.0
    amp_since, peak_since = 0.0, 0.0
    flight_time = 1.0  # the first impact opens an episode
    p = 0
    finished = False
    for _ in range(200 * (max_impacts + 1)):
        if flight_time >= SECTION_MIN_FLIGHT:
            # a section impact: record, classify
            history[n_sec, 0], history[n_sec, 1] = psi, gdot
            slot = min(n_sec, impact_log.shape[0] - 1)
            impact_log[slot, 0], impact_log[slot, 1] = t % (2.0 * math.pi), psi
            cycle_info[n_sec, 0] = t
            cycle_info[n_sec, 1] = math.sqrt(k * k + 1.0 + 2.0 * k * math.cos(psi)) * abs(gdot)
            if n_sec > 0:
                cycle_info[n_sec - 1, 2] = amp_since
                cycle_info[n_sec - 1, 3] = peak_since
                cycle_info[n_sec - 1, 4] = zeno_since
            cycle_info[n_sec, 5] = events
            amp_since = peak_since = zeno_since = 0.0
            n_sec += 1
            p = classify_period(history, n_sec, tol, max_period)
            if p > 0 or n_sec > max_impacts:
                finished = True
                break
        # the contact: Newton's law, or plastic/accumulated contact and the slide
        hr = h_ratio(psi, k)
        zeno = abs(gdot) < SPEED_EPS
        if zeno and r > 0.0:
            g2 = abs(gap_acceleration(model, psi, dpsi, k, xi, kappa))
            if g2 > 0.0:  # jump to the accumulation point of the chatter (H6, P-O14)
                t += 2.0 * r * abs(gdot) / (g2 * (1.0 - r))
                psi = _constraint_psi(level, t, psi, k)
            zeno_since = 1.0
        if r == 0.0 or zeno:
            if _starts_pressed(model, psi, side, k, xi, kappa):
                released, t, psi, dpsi, acc = slide(model, level, psi, side, window, k, xi,
                                                    kappa)
                peak_since = max(peak_since, acc)
                if not released:
                    # off the blade's edge: the striker passes it in the pressing direction
                    level = level if side > 0.0 else level - 2.0 * math.pi
                    side = 0.0
            else:
                dpsi = -1.0 / hr
        else:
            dpsi = (-r * gdot - 1.0) / hr
        lower = level - 2.0 * math.pi if side > 0.0 else level
        (status, t_new, psi, dpsi, level, side, passes, amp, peak, n_ok,
         n_bad) = lab_flight(model, t, psi, dpsi, lower, window, k, xi, kappa, method, rtol,
                             atol, dt, 10**6, horizon)
        steps += n_ok + n_bad
        out[ROW_REJECTED] += n_bad
        events += 1 + passes
        amp_since, peak_since = max(amp_since, amp), max(peak_since, peak)
        flight_time = t_new - t
        t = t_new
        code = flight_outcome(status, n_sec, steps, events, regimes, out)
        if code >= 0:
            return code
        gdot = 1.0 + h_ratio(psi, k) * dpsi
    out[ROW_STEPS], out[ROW_EVENTS] = steps, events
    if not finished:
        return 2
    if p == 0:
        out[ROW_IMPACTS] = max_impacts
        out[ROW_REGIME] = REGIME_QUASI_PERIODIC
        return 0
    first = n_sec - 1 - p  # the section impact that starts the last full cycle
    cycle = t_span = speed = amp = peak = zeno = 0.0
    for q in range(first, n_sec - 1):
        t_span += cycle_info[q + 1, 0] - cycle_info[q, 0]
        speed += cycle_info[q, 1]
        amp = max(amp, cycle_info[q, 2])
        peak = max(peak, cycle_info[q, 3])
        zeno = max(zeno, cycle_info[q, 4])
    cycle = t_span / p
    out[ROW_REGIME] = (REGIME_CHATTER if zeno > 0.0 else
                       REGIME_PERIOD_1 if p == 1 else REGIME_PERIOD_N)
    out[ROW_AMPLITUDE] = amp
    out[ROW_FREQUENCY] = math.nan  # no single free frequency: flights end on the blade
    out[ROW_INTERVAL] = cycle
    out[ROW_SPEED] = speed / p
    out[ROW_IMPACTS] = n_sec - 1 - 2 * p + 1
    out[ROW_ACCEL] = peak
    out[ROW_ROTOR_SPEED] = 1.0
    return 0
