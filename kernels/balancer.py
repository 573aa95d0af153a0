"""Leaf-spring balancer on the driven mass of a four-bar ([BAL]; docs/models.md §6).

Model (B4)/(B9), in the crank angle theta = omega t (' = d/dtheta):
    device:    f^2 g'' + 2 eta f g' + (1 + 1/r^2) g = gamma_s + gamma(theta)/r^2
    no device: f^2 g'' + 2 eta f g' +      1/r^2  g =           gamma(theta)/r^2
gamma(theta) is the rocker's displacement from its extreme position, from the exact loop
closure. The steady state is closed form per harmonic of gamma (B6). The unbalanced-moment
"invariants" gamma - g use their own transfer functions G_i, G_zr (no cancellation, H9).

Model no more than the scene needs: the Fourier coefficients depend only on the geometry and
are computed once per geometry (``fourier_coefficients``, numpy rFFT outside numba); the
response for each (f, r, eta) is a short sum over harmonics (``response``).
"""

import math
from collections import namedtuple

import numpy as np
from numba import njit

from kernels import INLINE_OPTIONS, INNER_OPTIONS, KERNEL_OPTIONS
from kernels.block import design_block
from kernels.declaration import POSITIVE, Boundary, Mechanism, Output, Quantity
from kernels.fourbar import closure_vectors, crank_turns_fully, vector_kinematics

NEUTRAL_HALF_SWING, NEUTRAL_MEAN = 0, 1

#: the outputs in SI, from the driven inertia and the crank speed (on request)
SI_OUTPUTS = ("spring_stiffness", "shaft_stiffness", "moment_peak_free",
              "moment_peak_balanced")


DECLARATION = Mechanism(
    name="spring_balancer",
    title="Leaf-spring balancer on a four-bar: steady state by Fourier series",
    summary="rocker motion from the loop closure, Fourier coefficients by rFFT once per "
            "geometry, steady state per harmonic in closed form, invariants by their own "
            "transfer functions, maxima over a revolution by dense sampling and Newton "
            "refinement",
    references="A. A. Abdurakhmanov, Influence of a spring levelling mechanism on the action "
               "of a hinged four-bar mechanism (in Ukrainian, English summary); the copy "
               "received gives neither journal nor year",
    parameters=(
        Quantity("lambda0", "1", "base ratio l0/l1 (lambda0)", "λ0", default=3.0,
                 **POSITIVE, label=r"base ratio $\lambda_0$"),
        Quantity("lambda2", "1", "coupler ratio l2/l1 (lambda2)", "λ2", default=3.5,
                 **POSITIVE, label=r"coupler ratio $\lambda_2$"),
        Quantity("lambda3", "1", "rocker ratio l3/l1 (lambda3)", "λ3", default=2.5,
                 **POSITIVE, label=r"rocker ratio $\lambda_3$"),
        Quantity("sigma", "1", "assembly branch (sigma)", "σ", default=1,
                 choices={1: 1, -1: -1}, label=r"branch $\sigma$"),
        Quantity("f", "1", "speed-change coefficient f = omega/omega0", "f", default=1.0,
                 **POSITIVE, label="speed coefficient $f$"),
        Quantity("r", "1", "stiffness ratio r = omega0/p (the paper's omega0/p)", "r",
                 default=1.0, **POSITIVE, label="stiffness ratio $r$"),
        Quantity("eta", "1", "dimensionless damping eta = nu/omega0", "η", default=0.02,
                 minimum=0.0, maximum=10.0, label=r"damping $\eta$"),
        Quantity("driven_inertia", "kg m2", "moment of inertia of the driven mass on the "
                 "rocker's shaft (I_m), for the outputs in SI", "I_m", **POSITIVE,
                 label="driven inertia $I_m$"),
        Quantity("crank_speed", "rad s-1", "crank speed omega (the operating speed: omega0 = "
                 "omega/f), for the outputs in SI", "ω", **POSITIVE,
                 label=r"crank speed $\omega$"),
        Quantity("spring_neutral", "1", "neutral angle of the spring: half the swing (the "
                 "paper) or the rocker's mean angle (no static moment)",
                 default="half_swing",
                 choices={"half_swing": NEUTRAL_HALF_SWING, "mean": NEUTRAL_MEAN},
                 label="spring neutral"),
    ),
    outputs=(
        Output("swing", "rad", "rocker swing (gamma0)", "γ0", label=r"rocker swing $\gamma_0$"),
        Output("moment_invariant_peak_free", "rad", "peak unbalanced-moment invariant "
               "without the balancer (M_i,max = max |gamma - g|)", "M_i,max",
               "moment = c M_i = I_m omega0^2 M_i/r^2",
               label=r"moment invariant $M_{i,\max}$ (free)"),
        Output("moment_invariant_peak_balanced", "rad", "peak unbalanced-moment invariant "
               "with the balancer (M_zr,max)", "M_zr,max",
               label=r"moment invariant $M_{zr,\max}$ (balanced)"),
        Output("balancing_coefficient", "1", "balancing coefficient K = M_i,max / M_zr,max",
               "K", marks=((1.0, "K = 1: the balancer stops helping"),),
               label="balancing coefficient $K$"),
        Output("dynamic_coefficient_free", "1", "dynamic coefficient without the balancer "
               "(K_d)", "K_d", label="dynamic coefficient $K_d$ free"),
        Output("dynamic_coefficient_balanced", "1", "dynamic coefficient with the balancer "
               "(K_d,zr)", "K_d,zr", label="dynamic coefficient $K_d$ balanced"),
        Output("acceleration_invariant_rigid", "1", "peak rocker acceleration invariant "
               "max |d2 gamma/d theta2| (rigid shaft)", label="peak acceleration (rigid)"),
        Output("harmonics_used", "1", "harmonics of the rocker motion used",
               diagnostic=True, count=True, label="harmonics"),
        Output("truncation_error", "1", "estimated relative truncation error of the "
               "acceleration metrics", diagnostic=True, label="truncation error"),
        Output("resonance_margin", "1", "distance to the nearest resonance, min |D_n|/K",
               label="resonance margin"),
        Output("spring_stiffness", "N m rad-1", "the balancer spring's torsional stiffness "
               "c_sp = I_m omega0^2, omega0 = omega/f", "c_sp", on_request=True,
               label="spring stiffness $c_{sp}$"),
        Output("shaft_stiffness", "N m rad-1", "the driven shaft's torsional stiffness "
               "c = I_m p^2 = c_sp / r^2", "c", on_request=True, label="shaft stiffness $c$"),
        Output("moment_peak_free", "N m", "peak unbalanced moment without the balancer, "
               "c times its invariant", "M_max", on_request=True,
               label=r"peak moment $M_\max$ free"),
        Output("moment_peak_balanced", "N m", "peak unbalanced moment with the balancer, "
               "c times its invariant", "M_zr,max", on_request=True,
               label=r"peak moment $M_{zr,\max}$ balanced"),
    ),
    rules=lambda given: (
        "driven_inertia: the outputs in SI need driven_inertia and crank_speed"
        if given.get("outputs", set()) & set(SI_OUTPUTS)
        and not {"driven_inertia", "crank_speed"} <= set(given) else None),
    status=("ok", "not_assemblable", "resonance", "truncation", "nonfinite"),
    usable=("truncation",),
    method=(
        Quantity("harmonics", "1", "harmonics of the rocker motion", default="auto",
                 minimum=1, maximum=16384, integer=True, aliases={"auto": 0}),
        Quantity("tol", "1", "relative tolerance of the metrics (sets the harmonic count "
                 "when harmonics = \"auto\")", default=1e-10, minimum=1e-14, maximum=1e-2),
        Quantity("resonance_tol", "1", "flag resonance where |D_n + i E_n| < resonance_tol "
                 "K", default=1e-9, minimum=0.0, maximum=0.1),
    ),
    boundaries=tuple(
        Boundary(frozenset((side, "resonance")), "a harmonic n of the rocker motion meets a "
                 "natural frequency: n f r = 1 without the balancer, n f r = sqrt(1 + r^2) "
                 "with it (to within resonance_tol)", indicator="resonance_margin")
        for side in ("ok", "truncation")),
)
P = DECLARATION.parameter_index
O = DECLARATION.output_index
#: the outputs this kernel computes: the ones in SI after them come from run()
KERNEL_ROWS = DECLARATION.output_index.spring_stiffness
S = DECLARATION.status_codes
#: the rows of a geometry in the parameter matrix (the Fourier coefficients depend on these)
GEOMETRY_ROWS = [P.lambda0, P.lambda2, P.lambda3, P.sigma]
N_FFT_START, N_FFT_MAX = 4096, 65536
TWO_PI = 2.0 * math.pi


# ---------------------------------------------------------------- rocker motion (geometry)

@njit(**KERNEL_OPTIONS)
def rocker_angle(theta, l0, l1, l2, l3, sigma):
    """Absolute rocker angle beta(theta) [rad] from the loop closure (NaN if it cannot close)."""
    c1, s1, c2, s2, c3, s3, d2, root = closure_vectors(
        math.sin(0.5 * theta), math.cos(0.5 * theta), l0, l1, l2, l3, sigma, 0.0)
    return math.atan2(s3, c3)


@njit(**KERNEL_OPTIONS)
def _extreme(theta, l0, l1, l2, l3, sigma):
    """Newton on u31(theta) = 0 from theta: a rocker dead position (the swing's ends)."""
    for _ in range(30):
        c1, s1, c2, s2, c3, s3, u21, u, du21, du = vector_kinematics(theta, l0, l1, l2, l3,
                                                                       sigma, 0.0)
        step = u / du
        theta -= step
        if abs(step) < 1e-15:
            break
    return theta


@njit(**KERNEL_OPTIONS)
def rocker_samples(l0, l1, l2, l3, sigma, n):
    """gamma(theta_j) = beta - min beta at theta_j = 2 pi j / n, and the swing gamma0.

    The extremes are polished by Newton on u31 = 0, so gamma0 is exact (B-O1, docs/models.md §7.2).
    Angles are unwrapped about beta(0): a rocker swings less than pi.
    """
    beta0 = rocker_angle(0.0, l0, l1, l2, l3, sigma)
    out = np.empty(n)
    lo_j, hi_j = 0, 0
    for j in range(n):
        b = rocker_angle(TWO_PI * j / n, l0, l1, l2, l3, sigma)
        out[j] = (b - beta0 + math.pi) % TWO_PI - math.pi
        if out[j] < out[lo_j]:
            lo_j = j
        if out[j] > out[hi_j]:
            hi_j = j
    t_lo = _extreme(TWO_PI * lo_j / n, l0, l1, l2, l3, sigma)
    t_hi = _extreme(TWO_PI * hi_j / n, l0, l1, l2, l3, sigma)
    lo = (rocker_angle(t_lo, l0, l1, l2, l3, sigma) - beta0 + math.pi) % TWO_PI - math.pi
    hi = (rocker_angle(t_hi, l0, l1, l2, l3, sigma) - beta0 + math.pi) % TWO_PI - math.pi
    lo = min(lo, out[lo_j])
    hi = max(hi, out[hi_j])
    for j in range(n):
        out[j] -= lo
    return out, hi - lo


def fourier_coefficients(l0, l1, l2, l3, sigma, tol=1e-12):
    """(a, b, gamma0) of gamma(theta) = a0 + sum a_n cos n theta + b_n sin n theta.

    a[0] = a0; n runs to N/4 so that aliasing stays below the returned tail. N doubles from
    4096 to 65536 until the top quarter of the spectrum is below tol*|c_1|; a non-smooth or
    near-toggle motion may not get there, which the response's truncation estimate reports.
    """
    n = N_FFT_START
    while True:
        gamma, gamma0 = rocker_samples(l0, l1, l2, l3, sigma, n)
        spec = np.fft.rfft(gamma) / n
        mag = np.abs(spec)
        if n >= N_FFT_MAX or mag[n // 4:].max() <= tol * max(mag[1], 1e-300):
            break
        n *= 2
    keep = n // 4
    a = 2.0 * spec.real[:keep + 1]
    b = -2.0 * spec.imag[:keep + 1]
    a[0] = spec.real[0]
    b[0] = 0.0
    # round-off floor of the samples: weighted by n^2 it would pass for 1000 harmonics of
    # signal. Only a clearly numerical floor is cut; a non-smooth motion keeps its tail.
    floor = 20.0 * np.median(mag[n // 4:])  # in units of |c_n|: mag is |c_n|/2
    if floor < 1e-12 * mag[1]:
        below = np.nonzero(np.hypot(a, b)[1:] < floor)[0]
        if below.size:  # the geometric decay meets the floor: the rest is round-off
            a[below[0] + 1:] = 0.0
            b[below[0] + 1:] = 0.0
    return a, b, gamma0


# ---------------------------------------------------------------- steady-state response

@njit(**KERNEL_OPTIONS)
def _series(theta, cr, ci, c0, m, order):
    """sum_n (cr_n cos n theta + ci_n sin n theta) differentiated `order` times, plus c0."""
    total = c0 if order == 0 else 0.0
    c, s = math.cos(theta), math.sin(theta)
    cn, sn = c, s
    for k in range(1, m + 1):
        if order == 0:
            total += cr[k] * cn + ci[k] * sn
        elif order == 1:
            total += k * (ci[k] * cn - cr[k] * sn)
        elif order == 2:
            total -= k * k * (cr[k] * cn + ci[k] * sn)
        else:
            total += k * k * k * (cr[k] * sn - ci[k] * cn)
        cn, sn = cn * c - sn * s, sn * c + cn * s  # rotate: cos/sin of (k+1) theta
    return total


@njit(**KERNEL_OPTIONS)
def _refine_peak(vals, cr, ci, c0, m, order):
    """max over theta of |d^order/dtheta^order series| from its values on a uniform grid:
    Newton on the derivative at every local maximum within 1e-3 of the largest sample."""
    n = vals.shape[0]
    top = 0.0
    for j in range(n):
        top = max(top, abs(vals[j]))
    best = top
    for j in range(n):
        v = abs(vals[j])
        if v < (1.0 - 1e-3) * top or v < abs(vals[j - 1]) or v < abs(vals[(j + 1) % n]):
            continue
        theta = TWO_PI * j / n
        for _ in range(20):  # Newton on d/dtheta of the series = 0
            d1 = _series(theta, cr, ci, c0, m, order + 1)
            d2 = _series_d2(theta, cr, ci, m, order)
            if d2 == 0.0:
                break
            step = d1 / d2
            if abs(step) > TWO_PI / n:
                break  # left the sampled lobe: keep the sample
            theta -= step
            if abs(step) < 1e-14:
                break
        best = max(best, abs(_series(theta, cr, ci, c0, m, order)))
    return best


@njit(**KERNEL_OPTIONS)
def series_peak(cr, ci, c0, m, order):
    """max over theta of |d^order/dtheta^order series| (8 m samples, then Newton)."""
    n = max(32, 8 * m)
    vals = np.empty(n)
    for j in range(n):
        vals[j] = _series(TWO_PI * j / n, cr, ci, c0, m, order)
    return _refine_peak(vals, cr, ci, c0, m, order)


@njit(**KERNEL_OPTIONS)
def _series_d2(theta, cr, ci, m, order):
    """Second derivative of the order-th derivative: order + 2 (orders 0..2 needed)."""
    if order + 2 <= 3:
        return _series(theta, cr, ci, 0.0, m, order + 2)
    total = 0.0  # fourth derivative
    c, s = math.cos(theta), math.sin(theta)
    cn, sn = c, s
    for k in range(1, m + 1):
        total += k ** 4 * (cr[k] * cn + ci[k] * sn)
        cn, sn = cn * c - sn * s, sn * c + cn * s
    return total


@njit(**KERNEL_OPTIONS)
def _gain(num_re, num_im, den_re, den_im):
    d = den_re * den_re + den_im * den_im
    return (num_re * den_re + num_im * den_im) / d, (num_im * den_re - num_re * den_im) / d


@njit(**KERNEL_OPTIONS)
def _apply(gr, gi, a, b):
    """The complex gain G = gr + i gi on a harmonic a cos + b sin (docs/models.md §6.2)."""
    return gr * a + gi * b, gr * b - gi * a


#: the series sampled over a revolution: rigid-shaft rocker acceleration, the unbalanced-moment
#: invariants without and with the balancer, the driven mass's acceleration without and with
(RIGID_ACCELERATION, INVARIANT_FREE, INVARIANT_BALANCED, MASS_ACCELERATION_FREE,
 MASS_ACCELERATION_BALANCED) = range(5)
N_SERIES = 5

#: the weighted tail may use this share of tol: the peaks of the metrics combine several
#: harmonics, and at share 1 one of 60 random points exceeded tol by 0.2 % (test_auto.py)
TAIL_SHARE = 0.5


@njit(**KERNEL_OPTIONS)
def choose_harmonics(a, b, f, r, eta, tol, forced):
    """Harmonic count and the relative truncation estimate of the acceleration metrics.

    Tail weight of harmonic n: n^2 |c_n| times the largest mass-response gain of the two
    systems, (1/r^2)/|D_n + i E_n| (resonance amplifies, H10); scale: sum n^2 |c_n|.
    """
    top = a.shape[0] - 1
    while top > 1 and a[top] == 0.0 and b[top] == 0.0:
        top -= 1  # padding and the cut round-off floor
    inv_r2 = 1.0 / (r * r)
    w = np.empty(top + 1)
    scale = 0.0
    for n in range(1, top + 1):
        c = math.sqrt(a[n] * a[n] + b[n] * b[n])
        e = 2.0 * eta * n * f
        d_no = inv_r2 - n * n * f * f
        d_dev = 1.0 + inv_r2 - n * n * f * f
        g = max(1.0, inv_r2 / math.sqrt(d_no * d_no + e * e),
                inv_r2 / math.sqrt(d_dev * d_dev + e * e))
        w[n] = n * n * c * min(g, 1e300)
        scale += n * n * c
    tail = 0.0
    m = top
    if forced > 0:
        m = min(int(forced), top)
        for n in range(m + 1, top + 1):
            tail += w[n]
        return m, tail / scale
    for n in range(top, 0, -1):
        if tail + w[n] > TAIL_SHARE * tol * scale:
            m = n
            break
        tail += w[n]
    return m, tail / scale


@njit(**KERNEL_OPTIONS)
def response(a, b, gamma0, f, r, eta, neutral, tol, res_tol, forced, out):
    """Metrics of docs/models.md §6.3 for one (f, r, eta): writes the outputs into out (rows O),
    returns the status."""
    for k in range(out.shape[0]):
        out[k] = math.nan
    out[O.swing] = gamma0
    m, trunc = choose_harmonics(a, b, f, r, eta, tol, forced)
    out[O.harmonics_used] = m
    out[O.truncation_error] = trunc
    inv_r2 = 1.0 / (r * r)
    k_no, k_dev = inv_r2, 1.0 + inv_r2
    gamma_s = 0.5 * gamma0 if neutral == NEUTRAL_HALF_SWING else a[0]
    margin = math.inf
    resonant = False
    zr = np.empty(m + 1)
    zi = np.empty(m + 1)  # rigid gamma
    ir = np.empty(m + 1)
    ii = np.empty(m + 1)  # invariant, no device
    jr = np.empty(m + 1)
    ji = np.empty(m + 1)  # invariant, device
    nr = np.empty(m + 1)
    ni = np.empty(m + 1)  # mass motion, no device
    dr = np.empty(m + 1)
    di = np.empty(m + 1)  # mass motion, device
    for n in range(1, m + 1):
        e = 2.0 * eta * n * f
        n2f2 = n * n * f * f
        d_no, d_dev = k_no - n2f2, k_dev - n2f2
        margin = min(margin, abs(d_no) / k_no, abs(d_dev) / k_dev)
        if (math.sqrt(d_no * d_no + e * e) <= res_tol * k_no
                or math.sqrt(d_dev * d_dev + e * e) <= res_tol * k_dev):
            resonant = True
            continue
        zr[n], zi[n] = a[n], b[n]
        ir[n], ii[n] = _apply(*_gain(-n2f2, e, d_no, e), a[n], b[n])  # G_i
        jr[n], ji[n] = _apply(*_gain(1.0 - n2f2, e, d_dev, e), a[n], b[n])  # G_zr
        nr[n], ni[n] = _apply(*_gain(inv_r2, 0.0, d_no, e), a[n], b[n])  # H: mass / rocker
        dr[n], di[n] = _apply(*_gain(inv_r2, 0.0, d_dev, e), a[n], b[n])
    out[O.resonance_margin] = margin
    if resonant:
        return S.resonance
    zr[0] = zi[0] = ir[0] = ii[0] = jr[0] = ji[0] = nr[0] = ni[0] = dr[0] = di[0] = 0.0
    static_dev = (a[0] - gamma_s) * r * r / (1.0 + r * r)  # a0 - C0 (docs/models.md §6.2)
    # the five series on one grid, sharing the cos/sin recurrence, then refined peaks
    ns = max(32, 8 * m)
    vals = np.zeros((N_SERIES, ns))
    for j in range(ns):
        theta = TWO_PI * j / ns
        c, s = math.cos(theta), math.sin(theta)
        cn, sn = c, s
        v0 = v1 = v2 = v3 = v4 = 0.0
        for n in range(1, m + 1):
            n2 = n * n
            v0 -= n2 * (zr[n] * cn + zi[n] * sn)
            v1 += ir[n] * cn + ii[n] * sn
            v2 += jr[n] * cn + ji[n] * sn
            v3 -= n2 * (nr[n] * cn + ni[n] * sn)
            v4 -= n2 * (dr[n] * cn + di[n] * sn)
            cn, sn = cn * c - sn * s, sn * c + cn * s
        vals[RIGID_ACCELERATION, j] = v0
        vals[INVARIANT_FREE, j], vals[INVARIANT_BALANCED, j] = v1, v2 + static_dev
        vals[MASS_ACCELERATION_FREE, j], vals[MASS_ACCELERATION_BALANCED, j] = v3, v4
    eps_rigid = _refine_peak(vals[RIGID_ACCELERATION], zr, zi, 0.0, m, int(2))
    m_free = _refine_peak(vals[INVARIANT_FREE], ir, ii, 0.0, m, int(0))
    m_dev = _refine_peak(vals[INVARIANT_BALANCED], jr, ji, static_dev, m, int(0))
    out[O.moment_invariant_peak_free], out[O.moment_invariant_peak_balanced] = m_free, m_dev
    out[O.balancing_coefficient] = m_free / m_dev
    out[O.dynamic_coefficient_free] = _refine_peak(vals[MASS_ACCELERATION_FREE], nr, ni, 0.0,
                                                   m, int(2)) / eps_rigid
    out[O.dynamic_coefficient_balanced] = _refine_peak(vals[MASS_ACCELERATION_BALANCED], dr, di,
                                                       0.0, m, int(2)) / eps_rigid
    out[O.acceleration_invariant_rigid] = eps_rigid
    for k in range(KERNEL_ROWS):
        if not math.isfinite(out[k]):
            return S.nonfinite
    if trunc > tol:
        return S.truncation
    return S.ok


@njit(**INLINE_OPTIONS)
def design(i, pr, settings, out, prof):
    """One grid point (kernels/block.py): the steady response of its geometry's Fourier
    coefficients (computed once per geometry of the block, settings.geometry_index[i])."""
    g = settings.geometry_index[i]
    if not settings.ok_geometry[g]:
        return S.not_assemblable
    n_top = settings.lengths[g]
    return response(settings.coef_a[g, :n_top], settings.coef_b[g, :n_top],
                    settings.gamma0s[g], pr[P.f], pr[P.r], pr[P.eta],
                    int(pr[P.spring_neutral]), settings.tol, settings.res_tol,
                    settings.forced, out)


#: the method's options and the block's geometries (their Fourier coefficients, lengths,
#: neutral angles, whether each is a crank-rocker, and each design's geometry), by name
Settings = namedtuple("Settings", ["tol", "res_tol", "forced", "geometry_index", "coef_a",
                                   "coef_b", "lengths", "gamma0s", "ok_geometry"])


#: the block: each design of it by ``design`` (kernels/block.py), cached on disk
balancer_block = design_block(design, "balancer_block", globals(), KERNEL_OPTIONS)


def run(params, method):
    """Entry point. Fourier coefficients once per distinct geometry in the block."""
    forced, tol, res_tol = method.harmonics, method.tol, method.resonance_tol
    n = params.shape[1]
    geometries, index = np.unique(params[GEOMETRY_ROWS].T, axis=0, return_inverse=True)
    size = 1 + N_FFT_MAX // 4
    coef_a = np.zeros((len(geometries), size))
    coef_b = np.zeros((len(geometries), size))
    gamma0s = np.full(len(geometries), np.nan)
    ok = np.zeros(len(geometries), dtype=np.bool_)
    lengths = np.full(len(geometries), 2, dtype=np.int64)
    for g, (l0, l2, l3, sigma) in enumerate(geometries):
        if not crank_turns_fully(l0, 1.0, l2, l3, 1e-12) or min(l0, l2, l3) < 1.0:
            continue  # not a crank-rocker: no periodic rocker motion to balance
        a, b, gamma0 = fourier_coefficients(l0, 1.0, l2, l3, sigma, tol=min(tol, 1e-12))
        coef_a[g, :a.shape[0]] = a
        coef_b[g, :b.shape[0]] = b
        nonzero = np.nonzero(np.hypot(a, b))[0]
        lengths[g] = max(2, int(nonzero[-1]) + 1 if nonzero.size else 2)
        if forced > 0:
            lengths[g] = max(lengths[g], min(forced + 1, a.shape[0]))
        gamma0s[g] = gamma0
        ok[g] = True
    out = np.empty((len(O), n))
    status = np.empty(n, dtype=np.int8)
    settings = Settings(tol=float(tol), res_tol=float(res_tol), forced=int(forced),
                        geometry_index=index.ravel().astype(np.int64), coef_a=coef_a,
                        coef_b=coef_b, lengths=lengths, gamma0s=gamma0s, ok_geometry=ok)
    balancer_block(np.ascontiguousarray(params), settings, out, status, np.empty((0, n, 0)))
    # in SI, only where asked for: omega0 = omega/f, c_sp = I_m omega0^2, c = c_sp / r^2,
    # a moment = c times its invariant (docs/models.md §6.3)
    si = bool(set(method.outputs) & set(SI_OUTPUTS))
    spring = (params[P.driven_inertia] * (params[P.crank_speed] / params[P.f]) ** 2
              if si else np.full(n, np.nan))
    shaft = spring / params[P.r] ** 2
    usable = np.isfinite(out[O.moment_invariant_peak_free])
    out[O.spring_stiffness] = np.where(usable, spring, np.nan)
    out[O.shaft_stiffness] = np.where(usable, shaft, np.nan)
    out[O.moment_peak_free] = shaft * out[O.moment_invariant_peak_free]
    out[O.moment_peak_balanced] = shaft * out[O.moment_invariant_peak_balanced]
    return out, status, np.empty((0, n, 0))


# ---------------------------------------------------------------- time-domain cross-check

@njit(**KERNEL_OPTIONS)
def _gamma_exact(theta, l0, l1, l2, l3, sigma, beta_min):
    b = rocker_angle(theta, l0, l1, l2, l3, sigma)
    return (b - beta_min + math.pi) % TWO_PI - math.pi


@njit(**KERNEL_OPTIONS)
def _rhs(theta, y0, y1, forcing_const, stiff, damp, f2, geo, beta_min, homogeneous):
    """(g', g'') of (B4)/(B9); the homogeneous system drops the forcing. geo: (l0, l1, l2,
    l3, 1/r^2, sigma)."""
    force = 0.0
    if not homogeneous:
        l0, l1, l2, l3, inv_r2, sigma = geo
        force = forcing_const + inv_r2 * _gamma_exact(theta, l0, l1, l2, l3, sigma, beta_min)
    return y1, (force - stiff * y0 - damp * y1) / f2


@njit(**KERNEL_OPTIONS)
def _rk4(t, a0, a1, h, const, stiff, damp, f2, geo, beta_min, hom):
    """One classical RK4 step of (B4)/(B9)."""
    k1 = _rhs(t, a0, a1, const, stiff, damp, f2, geo, beta_min, hom)
    k2 = _rhs(t + 0.5 * h, a0 + 0.5 * h * k1[0], a1 + 0.5 * h * k1[1], const, stiff, damp,
              f2, geo, beta_min, hom)
    k3 = _rhs(t + 0.5 * h, a0 + 0.5 * h * k2[0], a1 + 0.5 * h * k2[1], const, stiff, damp,
              f2, geo, beta_min, hom)
    k4 = _rhs(t + h, a0 + h * k3[0], a1 + h * k3[1], const, stiff, damp, f2, geo, beta_min,
              hom)
    return (a0 + h / 6.0 * (k1[0] + 2.0 * k2[0] + 2.0 * k3[0] + k4[0]),
            a1 + h / 6.0 * (k1[1] + 2.0 * k2[1] + 2.0 * k3[1] + k4[1]))


@njit(**KERNEL_OPTIONS)
def _setup(l0, l1, l2, l3, sigma, f, r, eta, gamma_s, device):
    gam, gamma0 = rocker_samples(l0, l1, l2, l3, sigma, 256)
    beta_min = rocker_angle(0.0, l0, l1, l2, l3, sigma) - gam[0]  # gamma = beta - beta_min
    inv_r2 = 1.0 / (r * r)
    stiff = 1.0 + inv_r2 if device else inv_r2
    const = gamma_s if device else 0.0
    return ((l0, l1, l2, l3, inv_r2, float(sigma)), beta_min, stiff, const, 2.0 * eta * f,
            np.mean(gam))


@njit(**KERNEL_OPTIONS)
def shooting(l0, l1, l2, l3, sigma, f, r, eta, gamma_s, device, steps):
    """Periodic steady state of (B4)/(B9) driven by the exact rocker motion, by shooting:
    x0 = (I - Phi)^-1 x_p(2 pi) with fixed-step RK4 over one revolution (B-O6,
    docs/models.md §7.2).

    Returns theta_j, g(theta_j), g''(theta_j) at steps + 1 points. Accurate when the step
    resolves the fastest mode sqrt(K)/f (H7); the periodic orbit of the discrete map exists
    even where time-marching would blow up, it is then just wrong.
    """
    geo, beta_min, stiff, const, damp, mean = _setup(l0, l1, l2, l3, sigma, f, r, eta,
                                                     gamma_s, device)
    f2 = f * f
    h = TWO_PI / steps
    # the particular solution from 0 and the two homogeneous solutions (the columns of Phi)
    p0, p1, u0, u1, v0, v1 = 0.0, 0.0, 1.0, 0.0, 0.0, 1.0
    for j in range(steps):
        t = j * h
        p0, p1 = _rk4(t, p0, p1, h, const, stiff, damp, f2, geo, beta_min, False)
        u0, u1 = _rk4(t, u0, u1, h, const, stiff, damp, f2, geo, beta_min, True)
        v0, v1 = _rk4(t, v0, v1, h, const, stiff, damp, f2, geo, beta_min, True)
    m00, m01, m10, m11 = 1.0 - u0, -v0, -u1, 1.0 - v1
    det = m00 * m11 - m01 * m10
    y0 = (m11 * p0 - m01 * p1) / det
    y1 = (-m10 * p0 + m00 * p1) / det
    return _record(y0, y1, steps, h, const, stiff, damp, f2, geo, beta_min)


@njit(**KERNEL_OPTIONS)
def _record(y0, y1, steps, h, const, stiff, damp, f2, geo, beta_min):
    thetas = np.empty(steps + 1)
    g = np.empty(steps + 1)
    g2 = np.empty(steps + 1)
    for j in range(steps + 1):
        t = j * h
        thetas[j] = t
        g[j] = y0
        g2[j] = _rhs(t, y0, y1, const, stiff, damp, f2, geo, beta_min, False)[1]
        if j < steps:
            y0, y1 = _rk4(t, y0, y1, h, const, stiff, damp, f2, geo, beta_min, False)
    return thetas, g, g2


@njit(**KERNEL_OPTIONS)
def march(l0, l1, l2, l3, sigma, f, r, eta, gamma_s, device, steps, revolutions):
    """Brute-force time integration (RK4, steps per revolution) from g = a0, g' = 0 over
    ``revolutions``; returns the last revolution like ``shooting``. The slow way to a steady
    state (the transient decays like exp(-eta theta/f)), kept for the hard cases H7-H8."""
    geo, beta_min, stiff, const, damp, mean = _setup(l0, l1, l2, l3, sigma, f, r, eta,
                                                     gamma_s, device)
    f2 = f * f
    h = TWO_PI / steps
    y0, y1 = mean, 0.0
    for rev in range(revolutions - 1):
        for j in range(steps):
            y0, y1 = _rk4(j * h, y0, y1, h, const, stiff, damp, f2, geo, beta_min, False)
    return _record(y0, y1, steps, h, const, stiff, damp, f2, geo, beta_min)
