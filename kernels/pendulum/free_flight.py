"""The free motion of the driven pendulums in closed form (docs/models.md §5): the paper's
first integral, amplitude, half period, peak acceleration and escape threshold (P1-P4),
the rigid pendulum's flight by the AGM elliptic integral and its exact flow by Jacobi's
elliptic functions (P5), each model's free swing past the blade, and the affine impact
map's fixed point on the rotor stop (P-O6)."""

import math

import numpy as np
from numba import njit

from kernels import INLINE_OPTIONS, INNER_OPTIONS, KERNEL_OPTIONS
from kernels.elementary import jacobi_small, sincos_quadrant
from kernels.impact.events import make_illinois

#: the half period's Gauss-Legendre panels: 20 nodes each, halving towards the turning point
_GL_X, _GL_W = np.polynomial.legendre.leggauss(20)


#: 1/(2j + 3): the series of log1p_excess
_EXCESS_SERIES = np.array([1.0 / (2 * j + 3) for j in range(18)])
assert _EXCESS_SERIES.shape[0] % 2 == 0  # log1p_excess takes the terms in pairs


@njit(**KERNEL_OPTIONS)
def log1p_excess(z):
    """z - log1p(z) for z > -1, to a few ulp: for |z| < 1/2 as 2 w^2 (1/(1 - w) - w T(w^2)),
    w = z/(2 + z), T(u) = sum u^j/(2j + 3) (from log1p(z) = 2 atanh(w)), with no difference
    of nearly equal numbers; the plain difference lost 2/|z| ulp (at z = 1e-6, 1e-10 of
    the value)."""
    if abs(z) < 0.5:
        w = z / (2.0 + z)
        u = w * w
        u2 = u * u
        # T in two interleaved Horner chains (even and odd powers of u), half the latency
        even, odd = 0.0, 0.0
        for j in range(_EXCESS_SERIES.shape[0] - 2, -1, -2):
            even = even * u2 + _EXCESS_SERIES[j]
            odd = odd * u2 + _EXCESS_SERIES[j + 1]
        return 2.0 * u * ((1.0 + 0.5 * z) - w * (even + u * odd))  # 1/(1 - w) = 1 + z/2
    return z - math.log1p(z)


# The first integral of [RP]'s equation is (psi'^2 + xi) exp(g(X)) = const with
# g(X) = ln(1 + xi X)/xi^2 - X/xi (P3), X = k^2 + 1 + 2k cos psi, decreasing and concave
# (g' = -X/(1 + xi X)). g itself is a difference of two terms of size X/xi that cancel to
# about -X^2/2 at small xi; its rises between two points are written without it.

@njit(**KERNEL_OPTIONS)
def rise_from_launch(d, x0, xi):
    """g(x0 - d) - g(x0) = d x0/q - log1p_excess(-xi d/q)/xi^2, q = 1 + xi x0: the rise
    of g from the launch point x0 = (1 + k)^2 (psi = 0) by d, increasing and concave in d."""
    q = 1.0 + xi * x0
    return d * x0 / q - log1p_excess(-xi * d / q) / (xi * xi)


@njit(**KERNEL_OPTIONS)
def rise_to_saddle(e, xs, xi):
    """g(xs) - g(xs + e) = e xs/q + log1p_excess(xi e/q)/xi^2, q = 1 + xi xs: the rise of
    g to the saddle xs = (1 - k)^2 (psi = pi) from e above it, increasing and convex in e."""
    q = 1.0 + xi * xs
    return e * xs / q + log1p_excess(xi * e / q) / (xi * xi)


@njit(**KERNEL_OPTIONS)
def paper_critical_speed(k, xi):
    """v_crit (P4): launched from psi = 0 faster than this, the pendulum goes over the top:
    v_crit^2 = xi expm1(g(xs) - g(x0)), the rise over the whole swing, x0 - xs = 4k."""
    return _speed_for_rise(rise_to_saddle(4.0 * k, (1.0 - k) ** 2, xi), xi)


@njit(**INLINE_OPTIONS)
def _speed_for_rise(rise, xi):
    """The launch speed at psi = 0 whose swing rises g by ``rise``: v^2 = xi expm1(rise)."""
    return math.sqrt(xi * math.expm1(rise))


@njit(**KERNEL_OPTIONS)
def paper_u(psi, v, k, xi):
    """psi'^2 as a function of psi on the flight launched from psi = 0 with speed v (P3):
    (v^2 + xi) exp(-(g(X) - g(x0))) - xi, X = x0 - 4k sin^2(psi/2)."""
    s = math.sin(0.5 * psi)
    return (v * v + xi) * math.exp(-rise_from_launch(4.0 * k * s * s, (1.0 + k) ** 2, xi)) - xi


@njit(**KERNEL_OPTIONS)
def paper_amplitude(v, k, xi):
    """Amplitude A (P-O2): where u(A) = 0, i.e. g rises by L = log1p(v^2/xi) from the
    launch point. NaN if v >= v_crit (escape).

    Solved for the distance d = x0 - X_A = 4k sin^2(A/2) from the launch point while
    A <= pi/2, else for the distance e = X_A - xs = 4k cos^2(A/2) from the saddle (the
    rise left to it is g(xs) - g(x0) - L): each the smaller of the two, so that A comes
    from an arcsine of at most sqrt(1/2) (acos of the cosine lost up to 1e-11 at moderate
    speeds, and 3x the input's own sensitivity near the separatrix). Newton on each from
    the root of its quadratic bound, on the side from which it converges monotonically
    (the rise from the launch is concave, the one to the saddle convex): 2.3 iterations on
    random designs (6.3 from the launch point, 37 for a safeguarded Newton from the middle
    of the bracket, which overshot and bisected)."""
    x0, xs = (1.0 + k) ** 2, (1.0 - k) ** 2
    full = rise_to_saddle(4.0 * k, xs, xi)
    if v >= _speed_for_rise(full, xi):  # paper_critical_speed, its rise kept
        return math.nan
    rise = math.log1p(v * v / xi)
    if rise <= rise_from_launch(2.0 * k, x0, xi):
        q = 1.0 + xi * x0
        a, b = x0 / q, 0.5 / (q * q)  # rise <= a d - b d^2: its root is left of d
        disc = a * a - 4.0 * b * rise
        d = 2.0 * rise / (a + math.sqrt(disc)) if disc > 0.0 else 0.0
        for _ in range(100):
            f = rise_from_launch(d, x0, xi) - rise
            if not f < 0.0:  # concave: Newton from the left never passes the root
                break
            x = x0 - d
            step = -f * (1.0 + xi * x) / x  # the rise's slope is X/(1 + xi X)
            d += step
            if step <= 1e-16 * d:
                break
        return 2.0 * math.asin(math.sqrt(min(d / (4.0 * k), 1.0)))
    left = full - rise
    q = 1.0 + xi * xs
    a, b = xs / q, 0.5 / (q * q)  # left >= a e + b e^2: its root is left of e
    e = 2.0 * left / (a + math.sqrt(a * a + 4.0 * b * left))
    for j in range(100):
        x = xs + e
        step = -(rise_to_saddle(e, xs, xi) - left) * (1.0 + xi * x) / x
        if j > 0 and not step < 0.0:  # convex: after one step right, only steps left
            break
        e += step
        if abs(step) <= 1e-16 * e:
            break
    return math.pi - 2.0 * math.asin(math.sqrt(min(max(e, 0.0) / (4.0 * k), 1.0)))


def _half_t(g, x, last):
    """t/2 at Gauss node x of the half period's panel t in [g, 2g], or [0, 2g] if it is the
    last (s = pi/2 - t ascends with x)."""
    return 0.5 * g * ((1.0 - x) if last else (1.5 - 0.5 * x))


_panel_half_t = njit(**INLINE_OPTIONS)(_half_t)
#: t/2 and its sine and cosine at every node of the first 40 panels, not last [0] and last
#: [1] (the panels stop after ~25 even at the separatrix flag's 64 ulp)
_PANEL_HALF_T = np.array([[[_half_t(0.25 * math.pi * 2.0 ** -j, x, last) for x in _GL_X]
                           for j in range(40)] for last in (False, True)])
_PANEL_SIN, _PANEL_COS = np.sin(_PANEL_HALF_T), np.cos(_PANEL_HALF_T)
#: the largest rise G of g from the turning point over the half period's last panel, and
#: expm1 of it: the complex zeros of u (G = 2 pi i) then lie beyond the panel (2 and 4 gave
#: tau1 to 1e-15 on random designs with 24 nodes, 8 to 1e-14; 2 costs 1 % more panels)
_PANEL_RISE = 2.0
_PANEL_RISE_EXPM1 = math.expm1(_PANEL_RISE)


@njit(**KERNEL_OPTIONS)
def paper_half_period(v, k, xi, amplitude):
    """Flight time from impact to impact, tau1 = 2 int_0^A dpsi / sqrt(u) (P-O3), with
    psi = A sin s removing the end singularity, by Gauss-Legendre on panels graded towards
    the turning point.

    u is written from the turning point, u = xi expm1(g(X_A) - g(X)) (u(A) = 0 defines
    X_A), with X_A - X = -4k sin((A + psi)/2) sin((A - psi)/2) and (A - psi)/2 =
    A sin^2(t/2), t = pi/2 - s: near the turning point the plain u(psi) = (v^2 + xi)
    e^(...) - xi is a difference of nearly equal numbers, and it cost tau1 about 1e-11 of
    its value (against mpmath at 40 digits); this form has no such difference.

    Near the separatrix (A -> pi) the integrand has a near-singularity at t = 0 of width
    w = sqrt(2 (pi - A)/A) (where psi = A sin s would reach the saddle at pi): one rule on
    [0, pi/2] converges ever slower (96 nodes were off by 6e-10 at 1e-9 of v_crit). Panels
    t in [g, 2g], g = 2^-j pi/4, each lie one length away from it, so 20 nodes per panel
    reach round-off (6e-15 on 6,000 random designs against 48; 16 gave 2e-12, 12 per outer
    panel 7e-10); the panels stop once the last, [0, 2g], is narrower than w: one or two
    panels for most flights, about 25 within 64 ulp of v_crit.

    The nodes are placed by their distance t/2 from the turning point, tabulated with its
    sine and cosine (_PANEL_HALF_T): placed by s, sin(pi/4 - s/2) lost the digits of t next
    to the saddle, and tau1 was off by up to 2e-11 within 1e-12 of v_crit (now 2e-15).
    sin((A + psi)/2) and cos(psi/2) follow from the sines and cosines of A and A/2 and the
    node's of (A - psi)/2 by the angle sums: one sine-cosine pair per node (sincos_quadrant,
    one reduction on [0, pi/2]) instead of five sines.

    A large rise L (small xi, fast launches) brings other near-singularities to the turning
    point: u = xi expm1(G) vanishes where G = 2 pi i, about where the real rise G from the
    turning point reaches 2 pi, and 24 nodes on one panel were off by 1.4e-10 at L = 55
    (xi = 0.03, k = 2.5). The last panel [0, 2g] is therefore also kept within a rise of
    _PANEL_RISE: G(2g) <= that."""
    width = math.sqrt(2.0 * max(math.pi - amplitude, 0.0) / amplitude)
    sin_a, cos_a = math.sin(amplitude), math.cos(amplitude)
    half = (math.sin(0.5 * amplitude), math.cos(0.5 * amplitude))
    u_last = xi * _PANEL_RISE_EXPM1  # u = xi expm1(G): G <= _PANEL_RISE
    total, g, j = 0.0, 0.25 * math.pi, 0
    while True:
        last = not g > width or g < 1e-300  # NaN width (no amplitude): one panel
        if last and g >= 1e-300:  # the rise at the panel's far end t = 2g, r = sin(g)
            last = not _paper_u_from_turning_point(amplitude, sin_a, cos_a, half,
                                                   math.sin(g), k, xi) > u_last
        panel = 0.0
        for i in range(_GL_X.shape[0]):
            if j < _PANEL_HALF_T.shape[1]:
                r, q = _PANEL_SIN[int(last), j, i], _PANEL_COS[int(last), j, i]
            else:
                half_t = _panel_half_t(g, _GL_X[i], last)
                r, q = math.sin(half_t), math.cos(half_t)
            u = _paper_u_from_turning_point(amplitude, sin_a, cos_a, half, r, k, xi)
            panel += _GL_W[i] * 2.0 * r * q / math.sqrt(max(u, 1e-300))  # cos s = sin t
        total += (g if last else 0.5 * g) * panel
        if last:
            break
        g, j = 0.5 * g, j + 1
    return 2.0 * amplitude * total


@njit(**INLINE_OPTIONS)
def _paper_u_from_turning_point(amplitude, sin_a, cos_a, half, r, k, xi):
    """u at the node whose (A - psi)/2 = A r^2 (r = sin(t/2); see paper_half_period):
    g(X_A) - g(X) = -d X/(1 + xi X) - log1p_excess(y)/xi^2, d = X_A - X, y = xi d/(1 + xi X),
    each term free of cancellation. X = (1 - k)^2 + 4k cos^2(psi/2), cos(psi/2) = cos(A/2 -
    gap) from half = (sin, cos)(A/2): sums of positive terms, where k^2 + 1 + 2k cos psi
    cancelled next to a saddle at k ~ 1 (X ~ 0; tau1 was 1.2e-11 off)."""
    gap = amplitude * r * r  # (A - psi)/2, in [0, pi/2)
    sin_g, cos_g = sincos_quadrant(gap)
    cos_half = half[1] * cos_g + half[0] * sin_g
    x = (1.0 - k) ** 2 + 4.0 * k * cos_half * cos_half
    d = -4.0 * k * (sin_a * cos_g - cos_a * sin_g) * sin_g
    q = 1.0 / (1.0 + xi * x)
    inverse_xi2 = 1.0 / (xi * xi)  # the same at every node: hoisted out of the loop
    return xi * math.expm1(-d * x * q - log1p_excess(xi * d * q) * inverse_xi2)


@njit(**KERNEL_OPTIONS)
def _paper_flight_acceleration(psi, data):
    """|psi''| at psi on the flight launched with speed v: a (u + xi) |sin psi|."""
    v, k, xi = data
    x = k * k + 1.0 + 2.0 * k * math.cos(psi)
    return k * x / (1.0 + xi * x) * (paper_u(psi, v, k, xi) + xi) * abs(math.sin(psi))


@njit(**INLINE_OPTIONS)
def _paper_peak_slope(psi, data):
    """sin(psi) d ln|psi''|/dpsi along a flight, for 0 < psi < pi: with u + xi =
    (v^2 + xi) e^(g0 - g(X)), |psi''| = k (v^2 + xi) e^g0 X e^-g(X) sin(psi)/(1 + xi X),
    whose logarithmic slope is cot psi - 2k sin psi (1/X + (X - xi)/(1 + xi X)): the same
    for every launch speed v, smooth, and no exponential in it."""
    s = math.sin(psi)
    return _peak_slope_of_cosine(math.cos(psi), s, s, data)


@njit(**INLINE_OPTIONS)
def _peak_slope_of_cosine(c, sin_a, sin_b, data):
    """_paper_peak_slope from c = cos psi, with sin^2 psi given as the product sin_a sin_b
    (sin psi twice, or 1 - c^2 and 1 for the scan's recurrence): one formula, each caller
    keeping its own rounding."""
    k, xi = data
    x = k * k + 1.0 + 2.0 * k * c
    return c - 2.0 * k * sin_a * sin_b * (1.0 / x + (x - xi) / (1.0 + xi * x))


_peak_slope_root = make_illinois(_paper_peak_slope)

#: below this |slope| the scan's recurrence cosine (error ~1e-14) does not decide its sign
_SCAN_SIGN = 1e-10


@njit(**KERNEL_OPTIONS)
def paper_peak_acceleration(v, k, xi, amplitude):
    """max |psi''| over the flight = max over psi in [0, A] of a (u + xi) |sin psi| (P-O4):
    at the turning point A, or where the slope (_paper_peak_slope, positive at psi = 0)
    turns negative: its sign at 32 points, and each change by Illinois to 1e-15 A. A root
    in closed form, so the peak is exact to round-off; a golden-section search on the value
    (70 evaluations with an exponential in each) cost 6.9 us of a design's 16.7 (0.8 now).

    The scan needs only cos psi (sin^2 psi = 1 - cos^2 psi), stepped by the cosines'
    three-term recurrence instead of a sine and a cosine at every point (0.6 us of a
    cycle's 3.3); where that value is within _SCAN_SIGN of 0, and at a change's bracket,
    the slope is evaluated exactly, so the signs and the roots are those of the plain scan."""
    data, slope = (v, k, xi), (k, xi)
    best = _paper_flight_acceleration(amplitude, data)
    n = 32
    cos_step = math.cos(amplitude / n)
    c_prev, c = cos_step, 1.0  # cos of the point before lo (at -step), and of lo
    lo, before = 0.0, 1.0
    for j in range(1, n + 1):
        hi = amplitude * j / n
        c_prev, c = c, 2.0 * cos_step * c - c_prev
        after = _peak_slope_of_cosine(c, 1.0 - c * c, 1.0, slope)
        if abs(after) < _SCAN_SIGN:
            after = _paper_peak_slope(hi, slope)
        if before > 0.0 and not after > 0.0:
            psi = hi
            after = _paper_peak_slope(hi, slope)
            if j > 1:
                before = _paper_peak_slope(lo, slope)
            if after < 0.0 and before > 0.0:
                psi, _ = _peak_slope_root(slope, lo, hi, before, after, 1e-15 * amplitude)
            best = max(best, _paper_flight_acceleration(psi, data))
        lo, before = hi, after
    return best


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


@njit(**INLINE_OPTIONS)
def paper_critical(p):
    k, xi = p
    return paper_critical_speed(k, xi)


@njit(**INLINE_OPTIONS)
def rigid_critical(p):
    k, kappa = p
    return 2.0 * math.sqrt(k * kappa)


@njit(**INNER_OPTIONS)
def paper_swing(y, p, window):
    """The free swing through the state y at constant rotor speed, in closed form: (tau1,
    the flight time between two passages of psi = 0; an upper bound on the time from
    psi = 0 to |psi| = window, the speed there being the least on the way: inf if the
    swing stays inside the window); tau1 NaN if the pendulum goes over the top. The speed
    at psi = 0 from the first integral: v^2 + xi = (psi'^2 + xi) e^(g(X) - g(x0))."""
    k, xi = p
    s = math.sin(0.5 * y[0])
    v2 = (y[1] * y[1] + xi) * math.exp(rise_from_launch(4.0 * k * s * s, (1.0 + k) ** 2,
                                                        xi)) - xi
    v = math.sqrt(max(v2, 0.0))
    amplitude = paper_amplitude(v, k, xi)
    if not amplitude < math.pi:
        return math.nan, math.inf
    u = paper_u(window, v, k, xi)
    return (paper_half_period(v, k, xi, amplitude),
            window / math.sqrt(u) if u > 0.0 else math.inf)


@njit(**INNER_OPTIONS)
def rigid_swing(y, p, window):
    """paper_swing of the rigid pendulum psi'' = -Omega^2 sin psi (rigid_flight, P-O8), the
    speed at psi = 0 from v^2 = psi'^2 + 4 Omega^2 sin^2(psi/2)."""
    k, kappa = p
    omega2 = k * kappa
    s, sw = math.sin(0.5 * y[0]), math.sin(0.5 * window)
    v2 = y[1] * y[1] + 4.0 * omega2 * s * s
    tau1 = rigid_flight(math.sqrt(v2), omega2)[1]
    if not tau1 < math.inf:
        return math.nan, math.inf
    u = v2 - 4.0 * omega2 * sw * sw
    return tau1, window / math.sqrt(u) if u > 0.0 else math.inf


@njit(**INLINE_OPTIONS)
def rigid_exact(y, h, p):
    """The rigid pendulum's state a time h on, exact to round-off (the closed-form flight's
    step): with X = sin(psi/2), Y = psi'/(2 Omega), Z = cos(psi/2) and m = X^2 + Y^2 (the
    energy), the free motion is X = sqrt(m) sn(Omega tau | m), Y = sqrt(m) cn, Z = dn
    (m > 1: over the top), and Jacobi's addition theorem moves the three on by Omega h
    without dividing by sqrt(m) (rest, m = 0, included); psi moves by twice the angle
    from (Z, X) to (Z1, X1), which a step keeps below pi/2."""
    k, kappa = p
    omega = math.sqrt(k * kappa)
    half = 0.5 * y[0]
    x, z = math.sin(half), math.cos(half)
    v = 0.5 * y[1] / omega
    sn, cn, dn = jacobi_small(omega * h, x * x + v * v)
    inverse = 1.0 / (1.0 - x * x * sn * sn)
    x1 = (x * cn * dn + v * z * sn) * inverse
    v1 = (v * cn - x * z * sn * dn) * inverse
    z1 = (z * dn - x * v * sn * cn) * inverse
    return y[0] + 2.0 * math.atan2(x1 * z - z1 * x, z1 * z + x1 * x), 2.0 * omega * v1


@njit(**INLINE_OPTIONS)
def rigid_exact_length(y, p, length):
    """The closed-form flight's step from y: ``length`` in the pendulum's own time, 1/Omega
    at rest and 1/sqrt(Omega^2 sin^2(psi/2) + psi'^2/4) in a fast swing, and at most
    ``length`` rotor radians (the blade's faces move with the rotor)."""
    k, kappa = p
    omega2 = k * kappa
    x = math.sin(0.5 * y[0])
    rate = math.sqrt(max(omega2, omega2 * x * x + 0.25 * y[1] * y[1]))
    return length / max(1.0, rate)


@njit(**INLINE_OPTIONS)
def rigid_speed_bound(y, p):
    """The largest |psi'| of the free motion from y: 2 Omega sqrt(m), m = sin^2(psi/2) +
    (psi'/(2 Omega))^2 its constant energy (rigid_exact), reached at psi = 0."""
    k, kappa = p
    omega2 = k * kappa
    x = math.sin(0.5 * y[0])
    return math.sqrt(4.0 * omega2 * x * x + y[1] * y[1])


@njit(**KERNEL_OPTIONS)
def steady_state_speed(k, r):
    """Fixed point of the affine impact map on the rotor stop: pre-impact (= launch) speed
    v* (P-O6)."""
    return (1.0 + k) * (1.0 + r) / (1.0 - r)


@njit(**KERNEL_OPTIONS)
def impacts_to_converge(k, r, v_crit, tol):
    """Impacts from rest (v_0 = 0) until |v_j - v*| <= tol v*, or until the launch speed
    reaches v_crit (escape): returns (count, escaped). v_j - v* = -v* R^j exactly, so a
    steady speed past v_crit escapes however close to it: the launch exceeds v_crit at the
    first j with R^j <= (v* - v_crit)/v*, also where the sequence has already converged to
    tol (a steady speed within rounding of v_crit is the caller's separatrix)."""
    v_star = steady_state_speed(k, r)
    v = 0.0
    for j in range(1, 100000):
        launch = (1.0 + k) * (1.0 + r) + r * v  # speed after impact j
        if launch >= v_crit:
            return j, True
        v = launch  # a reversible flight returns with the launch speed
        if abs(v - v_star) <= tol * v_star:
            if v_star <= v_crit:
                return j, False
            gap = (v_star - v_crit) / v_star
            return max(j, int(math.ceil(math.log(gap) / math.log(r)))), True
    return 100000, False
