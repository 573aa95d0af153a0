"""Rotary-pendulum impact mechanism (seed 004; dynamics.md §1): closed forms and a numba
integration core with event location.

Dimensionless time tau = omega1 t (' = d/dtau); psi is the pendulum angle relative to the
rotor, psi = 0 the impact position, psi < 0 in flight. Models:
    paper (P1-P2):  psi'' = -a(psi) (psi'^2 + xi) sin psi,  a = k X/(1 + xi X),
                    X = k^2 + 1 + 2 k cos psi
    rigid (P5):     psi'' = -kappa k sin psi
Impact on the rotor stop (psi = 0, the paper's case): psi'+ = -(1+k)(1+R) - R psi'-.
A flight is time-reversible, so the impact map on the pre-impact speed is affine,
v_{j+1} = (1+k)(1+R) + R v_j, with fixed point v* = (1+k)(1+R)/(1-R) (P-O6).

omega1 enters only as a time scale: every output here is dimensionless and the sweep
rescales it (A and n unchanged, T ~ 1/omega1, accelerations ~ omega1^2, speeds ~ omega1 l2).
"""

import math

import numpy as np
from numba import njit

from kernels import KERNEL_OPTIONS
from kernels.status import CODES
from kernels.extrema import golden_points, golden_shrink

MODEL_PAPER, MODEL_RIGID = 0, 1
#: meanings of the codes of the ``regime`` output (CF flag_meanings, in this order)
REGIMES = ("period_1", "period_n", "quasi_periodic", "escape", "chatter", "no_impact")
(REGIME_PERIOD_1, REGIME_PERIOD_N, REGIME_QUASI_PERIODIC, REGIME_ESCAPE, REGIME_CHATTER,
 REGIME_NO_IMPACT) = range(len(REGIMES))
#: the slots of the case row every steady-state driver fills (in omega1 units): regime,
#: amplitude, frequency ratio n, impact interval [rotor rad], striker normal speed at impact
#: [omega1 l2], impacts to converge, peak |psi''| [omega1^2], R_crit, steps, events, method
#: used, mean rotor speed [omega1], rejected steps
(ROW_REGIME, ROW_AMPLITUDE, ROW_FREQUENCY, ROW_INTERVAL, ROW_SPEED, ROW_IMPACTS, ROW_ACCEL,
 ROW_RCRIT, ROW_STEPS, ROW_EVENTS, ROW_METHOD, ROW_ROTOR_SPEED, ROW_REJECTED) = range(13)
N_ROW = 13

_GL_X, _GL_W = np.polynomial.legendre.leggauss(96)  # for the half-period quadrature


# ------------------------------------------------------------------ paper model, closed form

@njit(**KERNEL_OPTIONS)
def _g(x, xi):
    """g(X) = ln(1 + xi X)/xi^2 - X/xi: the first integral is (psi'^2 + xi) exp(-g) = const."""
    return math.log1p(xi * x) / (xi * xi) - x / xi


@njit(**KERNEL_OPTIONS)
def paper_critical_speed(k, xi):
    """v_crit (P4): launched from psi = 0 faster than this, the pendulum goes over the top."""
    return math.sqrt(xi * math.expm1(_g((k - 1.0) ** 2, xi) - _g((1.0 + k) ** 2, xi)))


@njit(**KERNEL_OPTIONS)
def paper_u(psi, v, k, xi):
    """psi'^2 as a function of psi on the flight launched from psi = 0 with speed v (P3)."""
    x0 = (1.0 + k) ** 2
    x = k * k + 1.0 + 2.0 * k * math.cos(psi)
    return (v * v + xi) * math.exp(_g(x0, xi) - _g(x, xi)) - xi


@njit(**KERNEL_OPTIONS)
def paper_amplitude(v, k, xi):
    """Amplitude A (P-O2): the root of u(A) = 0 in (0, pi), by safeguarded Newton on
    X_A = k^2 + 1 + 2k cos A. NaN if v >= v_crit (escape)."""
    if v >= paper_critical_speed(k, xi):
        return math.nan
    x0 = (1.0 + k) ** 2
    target = math.log(v * v + xi) - math.log(xi) + _g(x0, xi)  # = g(X_A), g decreasing
    lo, hi = (k - 1.0) ** 2, x0
    x = 0.5 * (lo + hi)
    for _ in range(200):
        f = _g(x, xi) - target
        if f > 0.0:
            lo = x
        else:
            hi = x
        slope = 1.0 / (xi * (1.0 + xi * x)) - 1.0 / xi
        step = x - f / slope
        x_new = step if lo < step < hi else 0.5 * (lo + hi)
        if abs(x_new - x) <= 1e-16 * x0:
            x = x_new
            break
        x = x_new
    c = (x - k * k - 1.0) / (2.0 * k)
    return math.acos(min(1.0, max(-1.0, c)))


@njit(**KERNEL_OPTIONS)
def paper_half_period(v, k, xi, amplitude):
    """Flight time from impact to impact, tau1 = 2 int_0^A dpsi / sqrt(u) (P-O3), with
    psi = A sin s removing the end singularity, by 96-point Gauss-Legendre."""
    total = 0.0
    half = 0.25 * math.pi
    for j in range(_GL_X.shape[0]):
        s = half * (_GL_X[j] + 1.0)
        u = paper_u(amplitude * math.sin(s), v, k, xi)
        total += _GL_W[j] * amplitude * math.cos(s) / math.sqrt(max(u, 1e-300))
    return 2.0 * half * total


@njit(**KERNEL_OPTIONS)
def paper_peak_acceleration(v, k, xi, amplitude):
    """max |psi''| over the flight = max over psi in [0, A] of a (u + xi) |sin psi| (P-O4):
    a dense sample, then golden-section search around the best sample."""
    def accel(psi):
        x = k * k + 1.0 + 2.0 * k * math.cos(psi)
        a = k * x / (1.0 + xi * x)
        return a * (paper_u(psi, v, k, xi) + xi) * abs(math.sin(psi))

    n = 32
    best_j, best = 0, -1.0
    for j in range(n + 1):
        val = accel(amplitude * j / n)
        if val > best:
            best_j, best = j, val
    lo = amplitude * max(0, best_j - 1) / n
    hi = amplitude * min(n, best_j + 1) / n
    c, d = golden_points(lo, hi)
    fc, fd = accel(c), accel(d)
    while hi - lo >= 1e-14 * amplitude:
        lo, hi, c, d, fc, fd, left = golden_shrink(lo, hi, c, d, fc, fd)
        if left:
            fc = accel(c)
        else:
            fd = accel(d)
    return max(best, fc, fd)


# ------------------------------------------------------------------ rigid model, closed form

@njit(**KERNEL_OPTIONS)
def ellipk(m):
    """Complete elliptic integral K(m) = pi / (2 AGM(1, sqrt(1 - m))), m < 1 (as scipy's
    ellipk, parameter m = k^2; matches it to ~2e-16)."""
    a, b = 1.0, math.sqrt(1.0 - m)
    for _ in range(60):
        if abs(a - b) <= 1e-16 * a:
            break
        a, b = 0.5 * (a + b), math.sqrt(a * b)
    return 0.5 * math.pi / a


@njit(**KERNEL_OPTIONS)
def rigid_flight(v, omega2):
    """Rigid pendulum psi'' = -Omega^2 sin psi launched from psi = 0 with speed v:
    (amplitude, flight time tau1, peak |psi''|) for m = v^2/(4 Omega^2) < 1 (P-O8),
    NaNs at and beyond the separatrix m = 1 (the pendulum goes over the top)."""
    omega = math.sqrt(omega2)
    m = v * v / (4.0 * omega2)
    if not m < 1.0:
        return math.nan, math.nan, math.nan
    amplitude = 2.0 * math.asin(math.sqrt(m))
    tau1 = 2.0 * ellipk(m) / omega
    return amplitude, tau1, omega2 * math.sin(min(amplitude, 0.5 * math.pi))


# ------------------------------------------------------------------ the impact map

@njit(**KERNEL_OPTIONS)
def steady_state_speed(k, r):
    """Fixed point of the affine impact map: pre-impact (= launch) speed v* (P-O6)."""
    return (1.0 + k) * (1.0 + r) / (1.0 - r)


@njit(**KERNEL_OPTIONS)
def impacts_to_converge(k, r, v_crit, tol):
    """Impacts from rest (v_0 = 0) until |v_j - v*| <= tol v*, or until the launch speed
    reaches v_crit (escape): returns (count, escaped). v_j - v* = -v* R^j exactly."""
    v_star = steady_state_speed(k, r)
    v = 0.0
    for j in range(1, 100000):
        launch = (1.0 + k) * (1.0 + r) + r * v  # speed after impact j
        if launch >= v_crit:
            return j, True
        v = launch  # a reversible flight returns with the launch speed
        if abs(v - v_star) <= tol * v_star:
            return j, False
    return 100000, False


# ------------------------------------------------------------------ integration core

FLIGHT_IMPACT, FLIGHT_ESCAPE, FLIGHT_MAX_STEPS, FLIGHT_UNDERFLOW = 0, 1, 2, 3
METHOD_RK4, METHOD_DOPRI5 = 0, 1
SUBSTEP_SAMPLES = 4  # interior sign samples per step: a flight shorter than a step is seen

# Dormand-Prince 5(4) tableau
_C2, _C3, _C4, _C5 = 1 / 5, 3 / 10, 4 / 5, 8 / 9
_A21 = 1 / 5
_A31, _A32 = 3 / 40, 9 / 40
_A41, _A42, _A43 = 44 / 45, -56 / 15, 32 / 9
_A51, _A52, _A53, _A54 = 19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729
_A61, _A62, _A63, _A64, _A65 = 9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656
_B1, _B3, _B4, _B5, _B6 = 35 / 384, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84
_E1, _E3, _E4, _E5, _E6, _E7 = (71 / 57600, -71 / 16695, 71 / 1920, -17253 / 339200,
                                22 / 525, -1 / 40)


@njit(**KERNEL_OPTIONS)
def acceleration(model, psi, dpsi, k, xi, kappa):
    """psi'' of the model (P1-P2 or P5)."""
    s = math.sin(psi)
    if model == MODEL_PAPER:
        x = k * k + 1.0 + 2.0 * k * math.cos(psi)
        return -k * x / (1.0 + xi * x) * (dpsi * dpsi + xi) * s
    return -kappa * k * s


@njit(**KERNEL_OPTIONS)
def _dopri_step(model, y0, y1, f0, h, k, xi, kappa):
    """One DOPRI5 step: (new psi, new psi', new f, error estimates of psi and psi')."""
    def f(a, b):
        return acceleration(model, a, b, k, xi, kappa)

    k1a, k1b = y1, f0
    p, q = y0 + h * _A21 * k1a, y1 + h * _A21 * k1b
    k2a, k2b = q, f(p, q)
    p = y0 + h * (_A31 * k1a + _A32 * k2a)
    q = y1 + h * (_A31 * k1b + _A32 * k2b)
    k3a, k3b = q, f(p, q)
    p = y0 + h * (_A41 * k1a + _A42 * k2a + _A43 * k3a)
    q = y1 + h * (_A41 * k1b + _A42 * k2b + _A43 * k3b)
    k4a, k4b = q, f(p, q)
    p = y0 + h * (_A51 * k1a + _A52 * k2a + _A53 * k3a + _A54 * k4a)
    q = y1 + h * (_A51 * k1b + _A52 * k2b + _A53 * k3b + _A54 * k4b)
    k5a, k5b = q, f(p, q)
    p = y0 + h * (_A61 * k1a + _A62 * k2a + _A63 * k3a + _A64 * k4a + _A65 * k5a)
    q = y1 + h * (_A61 * k1b + _A62 * k2b + _A63 * k3b + _A64 * k4b + _A65 * k5b)
    k6a, k6b = q, f(p, q)
    n0 = y0 + h * (_B1 * k1a + _B3 * k3a + _B4 * k4a + _B5 * k5a + _B6 * k6a)
    n1 = y1 + h * (_B1 * k1b + _B3 * k3b + _B4 * k4b + _B5 * k5b + _B6 * k6b)
    k7a, k7b = n1, f(n0, n1)  # first-same-as-last
    e0 = h * (_E1 * k1a + _E3 * k3a + _E4 * k4a + _E5 * k5a + _E6 * k6a + _E7 * k7a)
    e1 = h * (_E1 * k1b + _E3 * k3b + _E4 * k4b + _E5 * k5b + _E6 * k6b + _E7 * k7b)
    return n0, n1, k7b, e0, e1


@njit(**KERNEL_OPTIONS)
def _rk4_step(model, y0, y1, f0, h, k, xi, kappa):
    def f(a, b):
        return acceleration(model, a, b, k, xi, kappa)

    k1a, k1b = y1, f0
    k2a = y1 + 0.5 * h * k1b
    k2b = f(y0 + 0.5 * h * k1a, k2a)
    k3a = y1 + 0.5 * h * k2b
    k3b = f(y0 + 0.5 * h * k2a, k3a)
    k4a = y1 + h * k3b
    k4b = f(y0 + h * k3a, k4a)
    n0 = y0 + h / 6.0 * (k1a + 2.0 * k2a + 2.0 * k3a + k4a)
    n1 = y1 + h / 6.0 * (k1b + 2.0 * k2b + 2.0 * k3b + k4b)
    return n0, n1, f(n0, n1)


@njit(**KERNEL_OPTIONS)
def attempt_step(model, y0, y1, f0, h, k, xi, kappa, method, rtol, atol):
    """One RK4 step, or one DOPRI5 step with its error norm (RMS of the embedded error
    over atol + rtol |y| per component; > 1 means reject): (psi, psi', psi'', error)."""
    if method == METHOD_DOPRI5:
        n0, n1, fn, e0, e1 = _dopri_step(model, y0, y1, f0, h, k, xi, kappa)
        sc0 = atol + rtol * max(abs(y0), abs(n0))
        sc1 = atol + rtol * max(abs(y1), abs(n1))
        return n0, n1, fn, math.sqrt(0.5 * ((e0 / sc0) ** 2 + (e1 / sc1) ** 2))
    n0, n1, fn = _rk4_step(model, y0, y1, f0, h, k, xi, kappa)
    return n0, n1, fn, 0.0


@njit(**KERNEL_OPTIONS)
def _hermite(s, h, y0, d0, y1, d1):
    """Cubic Hermite interpolant of psi on a step, at s in [0, h] (psi' at the ends = d)."""
    t = s / h
    t2, t3 = t * t, t * t * t
    return ((2 * t3 - 3 * t2 + 1) * y0 + (t3 - 2 * t2 + t) * h * d0
            + (-2 * t3 + 3 * t2) * y1 + (t3 - t2) * h * d1)


@njit(**KERNEL_OPTIONS)
def initial_step(method, dt, speed, rtol):
    """First step: dt for RK4; for DOPRI5 rtol^(1/5) of the time to move a radian, the
    step an order-5 method keeps at that tolerance (fewer rejections while ramping up)."""
    if method != METHOD_DOPRI5:
        return dt
    return min(0.1, max(rtol, 1e-14) ** 0.2 / max(1.0, abs(speed)))


@njit(**KERNEL_OPTIONS)
def next_step(h, err, after_reject, err_prev=1.0):
    """Step-size control of DOPRI5: the PI controller 0.9 err^-0.17 err_prev^0.04 (Hairer's
    DOPRI5 with beta = 0.04; it damps the accept/reject see-saw where the step must keep
    shrinking), within [0.2, 5]; after a rejection only 0.9 err^(-1/5) and no growth
    (Hairer-Norsett-Wanner II.4)."""
    if after_reject or err > 1.0:
        return h * min(1.0, max(0.2, 0.9 * max(err, 1e-10) ** -0.2))
    factor = 0.9 * max(err, 1e-10) ** -0.17 * max(err_prev, 1e-4) ** 0.04
    return h * min(5.0, max(0.2, factor))


@njit(**KERNEL_OPTIONS)
def track_peak(peak, best, best_t, t, h, y0, y1, f0, n0, n1, fn):
    """Keep the step ending at the largest |psi''| so far (its start, end and length, and
    its start time): where the peak is refined at the event."""
    if abs(fn) > peak:
        return abs(fn), (y0, y1, f0, n0, n1, fn, h), t
    return peak, best, best_t


@njit(**KERNEL_OPTIONS)
def accepted_step_size(method, h, dt, err, after_reject, err_prev):
    """The next step after an accepted one: (h, err_prev) from the DOPRI5 controller, or dt
    for RK4 (a first step cut short by the ballistic-return cap is the only short one)."""
    if method == METHOD_DOPRI5:
        return next_step(h, err, after_reject, err_prev), err
    return dt, err_prev


@njit(**KERNEL_OPTIONS)
def hermite_slope(s, h, y0, d0, y1, d1):
    """Derivative of the cubic Hermite interpolant at s in [0, h]."""
    t = s / h
    return ((6 * t * t - 6 * t) * y0 / h + (3 * t * t - 4 * t + 1) * d0
            + (-6 * t * t + 6 * t) * y1 / h + (3 * t * t - 2 * t) * d1)


@njit(**KERNEL_OPTIONS)
def turning_time(h, y0, d0, y1, d1):
    """Where the step's cubic interpolant turns (psi' = d0 and d1 at the ends of opposite
    signs), by bisection on its slope: a start for Newton on exact partial steps (the
    cubic's own extremum is only O(h^4) accurate, 6e-7 at rtol 1e-8 in the rotor model)."""
    lo, hi = 0.0, h
    for _ in range(55):  # 2^-55 h: below round-off
        mid = 0.5 * (lo + hi)
        if (hermite_slope(mid, h, y0, d0, y1, d1) < 0.0) == (d0 < 0.0):
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


@njit(**KERNEL_OPTIONS)
def turning_value(model, y0, y1, f0, h, n0, n1, k, xi, kappa, method):
    """psi at the turning point inside a step (psi' = 0), by Newton on exact partial steps
    from the interpolant's estimate."""
    s = turning_time(h, y0, y1, n0, n1)
    for _ in range(4):
        p0, p1, pf, _ = attempt_step(model, y0, y1, f0, s, k, xi, kappa, method, 1.0, 1.0)
        if pf == 0.0:
            break
        s_new = min(h, max(0.0, s - p1 / pf))
        if abs(s_new - s) <= 1e-15 * h:
            break
        s = s_new
    return attempt_step(model, y0, y1, f0, s, k, xi, kappa, method, 1.0, 1.0)[0]


@njit(**KERNEL_OPTIONS)
def _grazing_peak(h, y0, d0, y1, d1, upward):
    """Where the interpolant turns inside the step (psi' changes sign towards the level),
    its extremum (s, value) by ternary search; s = -1 if it does not turn (H3)."""
    if not ((d0 > 0.0 > d1) if upward else (d0 < 0.0 < d1)):
        return -1.0, 0.0
    lo, hi = 0.0, h
    for _ in range(100):
        m1 = lo + (hi - lo) / 3.0
        m2 = hi - (hi - lo) / 3.0
        f1 = _hermite(m1, h, y0, d0, y1, d1)
        f2 = _hermite(m2, h, y0, d0, y1, d1)
        if (f1 < f2) == upward:
            lo = m1
        else:
            hi = m2
    s = 0.5 * (lo + hi)
    return s, _hermite(s, h, y0, d0, y1, d1)


@njit(**KERNEL_OPTIONS)
def interpolated_event(s, t, h, y0, d0, y1, d1, level, k):
    """The event function on a step's cubic interpolant of psi: psi - level, or, for k >= 0,
    the lab-blade gap t + s + beta(psi) - level with beta = atan2(sin psi, k + cos psi)."""
    p = _hermite(s, h, y0, d0, y1, d1)
    if k < 0.0:
        return p - level
    return t + s + math.atan2(math.sin(p), k + math.cos(p)) - level


@njit(**KERNEL_OPTIONS)
def illinois(lo, hi, flo, fhi, t, h, y0, d0, y1, d1, level, k):
    """Root of interpolated_event in [lo, hi] (values flo, fhi of opposite signs) by the
    Illinois variant of regula falsi."""
    side = 0
    mid = hi
    for _ in range(100):
        mid = hi - fhi * (hi - lo) / (fhi - flo)
        fm = interpolated_event(mid, t, h, y0, d0, y1, d1, level, k)
        if (fm < 0.0) == (flo < 0.0):
            lo, flo = mid, fm
            if side == -1:
                fhi *= 0.5
            side = -1
        else:
            hi, fhi = mid, fm
            if side == 1:
                flo *= 0.5
            side = 1
        if hi - lo <= 1e-15 * h or fm == 0.0:
            break
    return mid


@njit(**KERNEL_OPTIONS)
def classify_period(history, count, tol, max_period):
    """Smallest p <= max_period such that the last cycle of p states of an impact map
    repeats the cycle before it (within tol, relative); 0 if none. history rows 0..count-1
    are the states at successive section impacts."""
    last = count - 1
    for p in range(1, max_period + 1):
        if last - 2 * p < 0:
            return 0
        same = True
        for q in range(p):
            a, b = last - q, last - q - p
            for i in range(history.shape[1]):
                if abs(history[a, i] - history[b, i]) > tol * max(1.0, abs(history[a, i])):
                    same = False
        if same:
            return p
    return 0


@njit(**KERNEL_OPTIONS)
def _first_crossing(h, y0, d0, y1, d1, level, upward):
    """First s in (0, h] where psi crosses ``level`` in the given direction, from sign
    samples of the step interpolant (the step start itself never counts: H4), and, where
    the interpolant turns inside the step, from its extremum: a grazing contact that lasts
    less than the sample spacing is not stepped over (H3). -1 if none."""
    # the interpolant stays within 4/27 h (|d0| + |d1|) of the chord: far from the level,
    # nothing can cross (skips the samples on almost every step)
    reach = 4.0 / 27.0 * h * (abs(d0) + abs(d1))
    if (max(y0, y1) + reach < level) if upward else (min(y0, y1) - reach > level):
        return -1.0
    peak_s, peak = _grazing_peak(h, y0, d0, y1, d1, upward)
    prev_s, prev = 0.0, y0 - level
    for j in range(1, SUBSTEP_SAMPLES + 3):
        if j <= SUBSTEP_SAMPLES + 1:
            s = h * j / (SUBSTEP_SAMPLES + 1)
            val = (_hermite(s, h, y0, d0, y1, d1) if j <= SUBSTEP_SAMPLES else y1) - level
            if peak_s > prev_s and peak_s < s:
                # the extremum lies in this interval: test it first
                pv = peak - level
                if (prev < 0.0 <= pv) if upward else (prev > 0.0 >= pv):
                    s, val = peak_s, pv
        else:
            break
        crossed = (prev < 0.0 <= val) if upward else (prev > 0.0 >= val)
        if crossed:
            return illinois(prev_s, s, prev, val, 0.0, h, y0, d0, y1, d1, level, -1.0)
        prev_s, prev = s, val
    return -1.0


@njit(**KERNEL_OPTIONS)
def _refine_peak(model, best, window, k, xi, kappa, method, exact, rtol):
    """Golden-section search for max |psi''| over the two steps around the largest step-end
    value (a smooth maximum lies within a step of its best sample), cut at the event
    (``window`` from the first step's start). Each point is an exact partial step from the
    start of its own step (the cubic interpolant's psi' is only third order)."""
    a0, a1, af, b0, b1, bf, h = best
    if h == 0.0 or window <= 0.0:
        return exact

    def accel_at(s):
        if s <= 0.0:
            return abs(af)
        if s <= h:
            return abs(attempt_step(model, a0, a1, af, s, k, xi, kappa, method, 1.0, 1.0)[2])
        return abs(attempt_step(model, b0, b1, bf, s - h, k, xi, kappa, method, 1.0, 1.0)[2])

    # golden section: a location error d costs about d^2 in the relative value (psi''
    # varies on the scale of a rotor radian), so stop at d = sqrt(rtol)/3: a tenth of rtol
    stop = max(1e-7 * window, 0.3 * math.sqrt(rtol))
    lo, hi = 0.0, window
    c, d = golden_points(lo, hi)
    fc, fd = accel_at(c), accel_at(d)
    while hi - lo > stop:
        lo, hi, c, d, fc, fd, left = golden_shrink(lo, hi, c, d, fc, fd)
        if left:
            fc = accel_at(c)
        else:
            fd = accel_at(d)
    return max(exact, fc, fd)


@njit(**KERNEL_OPTIONS)
def integrate_flight(model, launch, k, xi, kappa, method, rtol, atol, dt, max_steps,
                     refine_peak=True):
    """One flight from the rotor stop: psi = 0, psi' = -launch (see _flight)."""
    return _flight(model, 0.0, -launch, 0.0, k, xi, kappa, method, rtol, atol, dt, max_steps,
                   refine_peak)


@njit(**KERNEL_OPTIONS)
def _flight(model, psi0, dpsi0, level, k, xi, kappa, method, rtol, atol, dt, max_steps,
            refine_peak):
    """One flight from (psi0, dpsi0) to the next impact (psi up through ``level``) or escape
    (psi reaching -pi: the pendulum goes over the top).

    Returns (status, tau of the event, psi' there, amplitude, peak |psi''|, steps, rejected).
    The event time is found on the step interpolant and polished by secant iterations on
    exact partial steps from the step start (atol-limited event times, H5). Without
    refine_peak (transient flights) the peak and the amplitude are only the extreme values
    at step ends.
    """
    t, y0, y1 = 0.0, psi0, dpsi0
    f0 = acceleration(model, y0, y1, k, xi, kappa)
    # where to refine the peak: the step ending at the largest |psi''| (start, end, length)
    best = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    best_t = 0.0
    h = initial_step(method, dt, dpsi0, rtol)
    if f0 * dpsi0 < 0.0:
        # pushed back towards the surface: the first step must end before the ballistic
        # return 2|psi'|/|psi''|, or a short flight falls between two sign samples (H4)
        h = min(h, 0.5 * abs(dpsi0) / abs(f0))
    steps = rejected = 0
    lowest = 0.0
    peak = abs(f0)  # largest |psi''| at step ends: picks where to refine
    nan = math.nan
    after_reject = False
    err_prev = 1.0
    while steps + rejected < max_steps:
        n0, n1, fn, err = attempt_step(model, y0, y1, f0, h, k, xi, kappa, method, rtol, atol)
        if err > 1.0:
            rejected += 1
            h = next_step(h, err, True)
            after_reject = True
            if h < 1e-14 * max(1.0, t):
                return FLIGHT_UNDERFLOW, t, nan, nan, nan, steps, rejected
            continue
        steps += 1
        # events on this step: escape (psi down through -pi) first, then impact (up through 0)
        for event in range(2):
            at = -math.pi if event == 0 else level
            s = _first_crossing(h, y0, y1, n0, n1, at, event == 1)
            if s < 0.0:
                continue
            for _ in range(3):  # Newton polish with exact partial steps from the step start
                p0, p1, pf, _ = attempt_step(model, y0, y1, f0, s, k, xi, kappa, method, rtol,
                                             atol)
                if p1 == 0.0:
                    break
                s_new = s - (p0 - at) / p1
                if not (0.0 < s_new <= h) or abs(s_new - s) <= 1e-16 * max(1.0, t):
                    s = s_new if 0.0 < s_new <= h else s
                    break
                s = s_new
            p0, p1, pf, _ = attempt_step(model, y0, y1, f0, s, k, xi, kappa, method, rtol, atol)
            status = FLIGHT_ESCAPE if event == 0 else FLIGHT_IMPACT
            peak = max(peak, abs(pf))
            if refine_peak:
                peak = _refine_peak(model, best, min(2.0 * best[6], t + s - best_t), k, xi,
                                    kappa, method, peak, rtol)
            return status, t + s, p1, -lowest, peak, steps, rejected
        # the lowest point and the peak acceleration, refined on this step's interpolant
        if refine_peak and y1 < 0.0 <= n1:  # transient flights need no amplitude
            lowest = min(lowest, turning_value(model, y0, y1, f0, h, n0, n1, k, xi, kappa,
                                               method) - psi0)
        lowest = min(lowest, n0 - psi0)
        peak, best, best_t = track_peak(peak, best, best_t, t, h, y0, y1, f0, n0, n1, fn)
        t += h
        y0, y1, f0 = n0, n1, fn
        h, err_prev = accepted_step_size(method, h, dt, err, after_reject, err_prev)
        after_reject = False
    return FLIGHT_MAX_STEPS, t, nan, nan, nan, steps, rejected


# ------------------------------------------------------------------ the mechanism kernel

INTEGRATOR_AUTO, INTEGRATOR_CLOSED, INTEGRATOR_RK4, INTEGRATOR_DOPRI5 = 0, 1, 2, 3
#: what steady_state returns (kernels.status codes)
OK, ESCAPE, MAX_STEPS, STEP_UNDERFLOW = (CODES[s] for s in ("ok", "escape", "max_steps",
                                                            "step_underflow"))
USED_CLOSED, USED_RK4, USED_DOPRI5 = 0, 1, 2


@njit(**KERNEL_OPTIONS)
def _critical(model, k, xi, kappa):
    """Closed-form escape threshold on the launch speed: v_crit (P4) or 2 Omega (P-O8)."""
    if model == MODEL_PAPER:
        return paper_critical_speed(k, xi)
    return 2.0 * math.sqrt(kappa * k)


@njit(**KERNEL_OPTIONS)
def dimensionless(model, k, xi, kappa, r, integrator, rtol, atol, dt, max_impacts, out):
    """Steady state of the impact regime in omega1 units (see steady_state)."""
    return steady_state(model, k, xi, kappa, r, integrator, rtol, atol, dt, max_impacts, out)


@njit(**KERNEL_OPTIONS)
def steady_state(model, k, xi, kappa, r, integrator, rtol, atol, dt, max_impacts, out):
    """Steady state of the impact regime in omega1 units; returns the kernel status.

    out: the case row (ROW_*); ROW_SPEED holds the pre-impact psi' v* here.
    """
    for j in range(out.shape[0]):
        out[j] = math.nan
    out[ROW_REJECTED] = 0.0
    v_crit = _critical(model, k, xi, kappa)
    r_crit = (v_crit - (1.0 + k)) / (v_crit + (1.0 + k))
    out[ROW_RCRIT] = r_crit if r_crit > 0.0 else math.nan  # no periodic regime at any R: NaN
    tol = 1e-12 if integrator <= INTEGRATOR_CLOSED else max(10.0 * rtol, 1e-12)
    count, escaped = impacts_to_converge(k, r, v_crit, tol)
    if integrator <= INTEGRATOR_CLOSED:  # the closed-form path (auto picks it here)
        out[ROW_METHOD] = USED_CLOSED
        out[ROW_IMPACTS] = count
        out[ROW_STEPS] = 0.0
        out[ROW_EVENTS] = 0.0
        if escaped:
            out[ROW_REGIME] = REGIME_ESCAPE
            return ESCAPE
        v = steady_state_speed(k, r)
        if model == MODEL_PAPER:
            amp = paper_amplitude(v, k, xi)
            tau1 = paper_half_period(v, k, xi, amp)
            acc = paper_peak_acceleration(v, k, xi, amp)
        else:
            amp, tau1, acc = rigid_flight(v, kappa * k)
        out[ROW_REGIME], out[ROW_AMPLITUDE] = REGIME_PERIOD_1, amp
        out[ROW_FREQUENCY], out[ROW_INTERVAL] = math.pi / tau1, tau1
        out[ROW_SPEED], out[ROW_ACCEL] = v, acc
        return OK
    method = METHOD_RK4 if integrator == INTEGRATOR_RK4 else METHOD_DOPRI5
    out[ROW_METHOD] = USED_RK4 if method == METHOD_RK4 else USED_DOPRI5
    steps = events = 0
    speeds = np.zeros(3)  # pre-impact speeds v_0 = 0 (from rest), v_1, v_2 integrated
    v = 0.0
    final = False
    for j in range(1, int(max_impacts) + 1):
        launch = (1.0 + k) * (1.0 + r) + r * v
        if launch >= v_crit:  # closed-form criterion, not a horizon (H1, H2, H12)
            out[ROW_REGIME], out[ROW_IMPACTS] = REGIME_ESCAPE, j
            out[ROW_STEPS], out[ROW_EVENTS] = steps, events
            return ESCAPE
        status, tau1, v_new, amp, acc, n_ok, n_bad = integrate_flight(
            model, launch, k, xi, kappa, method, rtol, atol, dt, 1000000, final or r == 0.0)
        steps += n_ok + n_bad
        out[ROW_REJECTED] += n_bad
        events += 1
        if status == FLIGHT_ESCAPE:
            out[ROW_REGIME], out[ROW_IMPACTS] = REGIME_ESCAPE, j
            out[ROW_STEPS], out[ROW_EVENTS] = steps, events
            return ESCAPE
        if status != FLIGHT_IMPACT:
            out[ROW_STEPS], out[ROW_EVENTS] = steps, events
            return STEP_UNDERFLOW if status == FLIGHT_UNDERFLOW else MAX_STEPS
        converged = r == 0.0 or abs(v_new - v) <= tol * v_new
        if converged:
            if not final and r != 0.0:
                final = True  # converged on a transient flight: one more, peak refined
                v = v_new
                continue
            out[ROW_REGIME], out[ROW_AMPLITUDE] = REGIME_PERIOD_1, amp
            out[ROW_FREQUENCY], out[ROW_INTERVAL], out[ROW_SPEED] = math.pi / tau1, tau1, v_new
            out[ROW_IMPACTS], out[ROW_ACCEL] = count, acc
            out[ROW_STEPS], out[ROW_EVENTS] = steps, events
            return OK
        if j <= 2:
            speeds[j] = v_new
        if j == 2:
            # v_0 = 0 and two integrated flights fix the affine map v -> a + R v (reversible
            # flights, H13): jump to its fixed point by Aitken's delta-squared, checked by
            # the next flight instead of iterating to convergence
            d1, d2 = speeds[1] - speeds[0], speeds[2] - speeds[1]
            if d2 != d1 and abs(d1) > 0.0:
                v_new = speeds[2] - d2 * d2 / (d2 - d1)
                final = True  # the flight from the fixed point is expected to be the last
        elif final:
            final = False  # it was not: keep iterating the map
        v = v_new
    out[ROW_STEPS], out[ROW_EVENTS] = steps, events
    return MAX_STEPS


@njit(**KERNEL_OPTIONS)
def integrate_to(model, psi0, dpsi0, tau_end, k, xi, kappa, method, rtol, atol, dt):
    """State (psi, psi', steps) at tau_end without events: RK4 with n = ceil(tau_end/dt)
    equal steps, or DOPRI5 with the step controller (the last step clipped). For
    convergence-order and work-precision measurements."""
    y0, y1 = psi0, dpsi0
    f0 = acceleration(model, y0, y1, k, xi, kappa)
    if method == METHOD_RK4:
        n = max(1, int(math.ceil(tau_end / dt - 1e-12)))
        h = tau_end / n
        for _ in range(n):
            y0, y1, f0 = _rk4_step(model, y0, y1, f0, h, k, xi, kappa)
        return y0, y1, n
    t, h, steps = 0.0, min(0.05, tau_end), 0
    while t < tau_end and steps < 10**7:
        h = min(h, tau_end - t)
        n0, n1, fn, err = attempt_step(model, y0, y1, f0, h, k, xi, kappa, METHOD_DOPRI5,
                                       rtol, atol)
        steps += 1
        if err <= 1.0:
            t += h
            y0, y1, f0 = n0, n1, fn
        h = next_step(h, err, err > 1.0)
    return y0, y1, steps


CHATTER_STUCK, CHATTER_LEAVES, CHATTER_ESCAPE, CHATTER_FAILED = 0, 1, 2, 3


@njit(**KERNEL_OPTIONS)
def chatter(model, psi_stop, r_stop, psi0, dpsi0, k, xi, kappa, method, rtol, atol, dt,
            speed_eps, max_impacts):
    """Repeated impacts on a rotor-fixed stop at psi_stop (relative restitution r_stop,
    psi'+ = -r_stop psi'-), from (psi0, dpsi0) below the stop, with the Zeno guard (H6).

    When the impact speed falls below speed_eps the flights form a geometric series: instead
    of looping forever the guard jumps to the accumulation point
    tau_inf = tau_j + 2 r v_j / (g (1 - r)) with g = psi'' at the stop, the ballistic tail
    of P-O14 (the m-th later flight takes 2 r^m v_j / g), and checks that the centrifugal torque
    presses the pendulum into the stop (it then sticks). Returns (outcome, tau_inf or the
    time of the last event, impacts, steps).
    """
    t, steps, psi, dpsi = 0.0, 0, psi0, dpsi0
    for j in range(1, max_impacts + 1):
        status, dt_flight, v_hit, amp, acc, n_ok, n_bad = _flight(
            model, psi, dpsi, psi_stop, k, xi, kappa, method, rtol, atol, dt, 1000000, False)
        steps += n_ok + n_bad
        if status == FLIGHT_ESCAPE:
            return CHATTER_ESCAPE, t + dt_flight, j - 1, steps
        if status != FLIGHT_IMPACT:
            return CHATTER_FAILED, t, j - 1, steps
        t += dt_flight
        g = acceleration(model, psi_stop, 0.0, k, xi, kappa)  # > 0: pressed into the stop
        if v_hit < speed_eps:
            if not g > 0.0:
                return CHATTER_LEAVES, t, j, steps
            return CHATTER_STUCK, t + 2.0 * r_stop * v_hit / (g * (1.0 - r_stop)), j, steps
        psi, dpsi = psi_stop, -r_stop * v_hit
    return CHATTER_FAILED, t, max_impacts, steps
