"""Explicit Runge-Kutta steps (DOPRI5 and DOP853 with their embedded errors, classical RK4) and
the step-size controller: the one place a step is taken.

``make_stepper(rhs, scales)`` specialises the step to a vector field ``rhs(y, p)`` on a tuple
state and to its error scales ``scales(y0, y1, rtol, atol)`` (one per component); the
returned ``step(method, y, f0, h, p, rtol, atol)`` gives (y1, f1, err), with f1 = rhs(y1)
(first same as last) and err the embedded error measure over the scales (DOPRI5: its RMS;
DOP853: dop853_error; > 1: reject; 0 for RK4). A partial step of length s < h from the
same start is the exact (to the method's order) state at t + s: events and peaks are
polished on those.
"""

import math

from numba import njit

from kernels import INLINE_OPTIONS, INNER_OPTIONS
from kernels.impact.tuples import error_norm, lincomb, weighted

#: METHOD_EXACT: the system's closed-form flow (``exact``), where it has one. The one rule
#: for the four: a method that is neither RK4 nor DOP853 is DOPRI5 (step, first step,
#: controller) unless the system has an exact flow and METHOD_EXACT is asked for (the
#: slides and the tangent of a closed-form flight are integrated by DOPRI5)
METHOD_RK4, METHOD_DOPRI5, METHOD_EXACT, METHOD_DOP853 = 0, 1, 2, 3
#: the methods a stepper may have beside DOPRI5 (and the exact flow): make_stepper's
#: ``methods``, all of them unless told
OTHER_METHODS = (METHOD_DOP853, METHOD_RK4)

# Dormand-Prince 5(4): nodes are implicit in the stages; weights b (5th order), and the
# error weights e = b5 - b4
A21 = 1 / 5
A31, A32 = 3 / 40, 9 / 40
A41, A42, A43 = 44 / 45, -56 / 15, 32 / 9
A51, A52, A53, A54 = 19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729
A61, A62, A63, A64, A65 = 9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656
B1, B3, B4, B5, B6 = 35 / 384, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84
E1, E3, E4, E5, E6, E7 = (71 / 57600, -71 / 16695, 71 / 1920, -17253 / 339200, 22 / 525,
                          -1 / 40)


# Dormand-Prince 8(5,3) (Hairer's DOP853): the nonzero coefficients of each stage k2..k12
# (above each row, the stages it weighs), the 8th-order weights b, and the
# error weights of the 5th- and 3rd-order embedded solutions (b - b5, b - b3); the last
# stage, k13 = rhs(y1), is the next step's first (FSAL). Checked against scipy's table in
# tests/test_impact_core.py.
# D_A2 weighs k1
D_A2 = (0.05260015195876773,)
# D_A3 weighs k1, k2
D_A3 = (0.0197250569845379, 0.0591751709536137)
# D_A4 weighs k1, k3
D_A4 = (0.02958758547680685, 0.08876275643042054)
# D_A5 weighs k1, k3, k4
D_A5 = (0.2413651341592667, -0.8845494793282861, 0.924834003261792)
# D_A6 weighs k1, k4, k5
D_A6 = (0.037037037037037035, 0.17082860872947386, 0.12546768756682242)
# D_A7 weighs k1, k4, k5, k6
D_A7 = (0.037109375, 0.17025221101954405, 0.06021653898045596, -0.017578125)
# D_A8 weighs k1, k4, k5, k6, k7
D_A8 = (0.03709200011850479, 0.17038392571223998, 0.10726203044637328, -0.015319437748624402,
        0.008273789163814023)
# D_A9 weighs k1, k4, k5, k6, k7, k8
D_A9 = (0.6241109587160757, -3.3608926294469414, -0.868219346841726, 27.59209969944671,
        20.154067550477894, -43.48988418106996)
# D_A10 weighs k1, k4, k5, k6, k7, k8, k9
D_A10 = (0.47766253643826434, -2.4881146199716677, -0.590290826836843, 21.230051448181193,
         15.279233632882423, -33.28821096898486, -0.020331201708508627)
# D_A11 weighs k1, k4, k5, k6, k7, k8, k9, k10
D_A11 = (-0.9371424300859873, 5.186372428844064, 1.0914373489967295, -8.149787010746927,
         -18.52006565999696, 22.739487099350505, 2.4936055526796523, -3.0467644718982196)
# D_A12 weighs k1, k4, k5, k6, k7, k8, k9, k10, k11
D_A12 = (2.273310147516538, -10.53449546673725, -2.0008720582248625, -17.9589318631188,
         27.94888452941996, -2.8589982771350235, -8.87285693353063, 12.360567175794303,
         0.6433927460157636)
# D_B weighs k1, k6, k7, k8, k9, k10, k11, k12
D_B = (0.054293734116568765, 4.450312892752409, 1.8915178993145003, -5.801203960010585,
       0.3111643669578199, -0.1521609496625161, 0.20136540080403034, 0.04471061572777259)
# D_E3 weighs k1, k6, k7, k8, k9, k10, k11, k12
D_E3 = (-0.18980075407240762, 4.450312892752409, 1.8915178993145003, -5.801203960010585,
        -0.4226823213237919, -0.1521609496625161, 0.20136540080403034, 0.02265179219836082)
# D_E5 weighs k1, k6, k7, k8, k9, k10, k11, k12
D_E5 = (0.01312004499419488, -1.2251564463762044, -0.4957589496572502, 1.6643771824549864,
        -0.35032884874997366, 0.3341791187130175, 0.08192320648511571, -0.022355307863886294)


@njit(**INNER_OPTIONS)
def _no_exact(y, h, p):
    return y


def make_stepper(rhs, scales, exact=None, methods=OTHER_METHODS, inline=False):
    """The step of the methods, specialised to rhs, the error scales and, where the system
    has one, its exact flow ``exact(y, h, p)`` (its error estimate is 0); a system without
    one takes DOPRI5's step for METHOD_EXACT (the rule at METHOD_EXACT). DOPRI5 is always
    compiled in, DOP853 and RK4 where ``methods`` has them: without DOP853 its callers step
    by DOPRI5 (``low_order``); without RK4 they never ask for it (a pendulum system's entry
    point is chosen by its method, systems.entry_point). With ``inline`` the step and its
    stages are inlined into their caller (numba's IR): a loop of steps over several
    flights laid out lane-minor is then vectorised by LLVM (benchmarks/bench_step.py), with
    the same operations as the step called."""
    options = INLINE_OPTIONS if inline else INNER_OPTIONS
    has_exact = exact is not None
    exact = exact if has_exact else _no_exact
    high_order, fixed_step = METHOD_DOP853 in methods, METHOD_RK4 in methods

    @njit(**options)
    def dopri5(y, f0, h, p):
        k1 = f0
        k2 = rhs(lincomb(y, h, (A21,), (k1,)), p)
        k3 = rhs(lincomb(y, h, (A31, A32), (k1, k2)), p)
        k4 = rhs(lincomb(y, h, (A41, A42, A43), (k1, k2, k3)), p)
        k5 = rhs(lincomb(y, h, (A51, A52, A53, A54), (k1, k2, k3, k4)), p)
        k6 = rhs(lincomb(y, h, (A61, A62, A63, A64, A65), (k1, k2, k3, k4, k5)), p)
        y1 = lincomb(y, h, (B1, B3, B4, B5, B6), (k1, k3, k4, k5, k6))
        k7 = rhs(y1, p)
        err = weighted(h, (E1, E3, E4, E5, E6, E7), (k1, k3, k4, k5, k6, k7))
        return y1, k7, err

    @njit(**options)
    def dop853(y, f0, h, p):
        k1 = f0
        k2 = rhs(lincomb(y, h, D_A2, (k1,)), p)
        k3 = rhs(lincomb(y, h, D_A3, (k1, k2)), p)
        k4 = rhs(lincomb(y, h, D_A4, (k1, k3)), p)
        k5 = rhs(lincomb(y, h, D_A5, (k1, k3, k4)), p)
        k6 = rhs(lincomb(y, h, D_A6, (k1, k4, k5)), p)
        k7 = rhs(lincomb(y, h, D_A7, (k1, k4, k5, k6)), p)
        k8 = rhs(lincomb(y, h, D_A8, (k1, k4, k5, k6, k7)), p)
        k9 = rhs(lincomb(y, h, D_A9, (k1, k4, k5, k6, k7, k8)), p)
        k10 = rhs(lincomb(y, h, D_A10, (k1, k4, k5, k6, k7, k8, k9)), p)
        k11 = rhs(lincomb(y, h, D_A11, (k1, k4, k5, k6, k7, k8, k9, k10)), p)
        k12 = rhs(lincomb(y, h, D_A12, (k1, k4, k5, k6, k7, k8, k9, k10, k11)), p)
        ks = (k1, k6, k7, k8, k9, k10, k11, k12)
        y1 = lincomb(y, h, D_B, ks)
        return y1, rhs(y1, p), weighted(h, D_E5, ks), weighted(h, D_E3, ks)

    @njit(**options)
    def rk4(y, f0, h, p):
        k2 = rhs(lincomb(y, h, (0.5,), (f0,)), p)
        k3 = rhs(lincomb(y, h, (0.5,), (k2,)), p)
        k4 = rhs(lincomb(y, h, (1.0,), (k3,)), p)
        y1 = lincomb(y, h / 6.0, (1.0, 2.0, 2.0, 1.0), (f0, k2, k3, k4))
        return y1, rhs(y1, p)

    @njit(**options)
    def step(method, y, f0, h, p, rtol, atol):
        if has_exact and method == METHOD_EXACT:
            y1 = exact(y, h, p)
            return y1, rhs(y1, p), 0.0
        if high_order:  # a separate test, so that without it numba prunes DOP853 away
            if method == METHOD_DOP853:
                y1, f1, err5, err3 = dop853(y, f0, h, p)
                scale = scales(y, y1, rtol, atol)
                return y1, f1, dop853_error(error_norm(err5, scale), error_norm(err3, scale))
        if fixed_step:  # (as DOP853: pruned away without it)
            if method == METHOD_RK4:
                y1, f1 = rk4(y, f0, h, p)
                return y1, f1, 0.0
        y1, f1, err = dopri5(y, f0, h, p)
        return y1, f1, error_norm(err, scales(y, y1, rtol, atol))

    return step


@njit(**INLINE_OPTIONS)
def dop853_error(rms5, rms3):
    """DOP853's error measure from the RMS errors of its 5th- and 3rd-order embedded
    solutions, rms5^2 / sqrt(rms5^2 + 0.01 rms3^2) (Hairer-Norsett-Wanner II.10): it
    behaves as h^8, an error estimate of the 8th-order solution's own order, where the 5th
    order's alone would shrink the step too far at tight tolerances; 0 where both vanish."""
    denominator = rms5 * rms5 + 0.01 * rms3 * rms3
    return rms5 * rms5 / math.sqrt(denominator) if denominator > 0.0 else 0.0


@njit(**INLINE_OPTIONS)
def low_order(method):
    """The method a stepper made without DOP853 takes for ``method``: DOPRI5 for DOP853,
    so that its step-size control is the step's."""
    return METHOD_DOPRI5 if method == METHOD_DOP853 else method


@njit(**INNER_OPTIONS)
def initial_step(method, dt, speed, rtol):
    """First step: dt for RK4; for DOPRI5 rtol^(1/5) (DOP853 rtol^(1/8)) of the time to
    move a unit of the state at ``speed``, the step a method of that order keeps at that
    tolerance (fewer rejections while ramping up)."""
    if method == METHOD_RK4:
        return dt
    order = 8.0 if method == METHOD_DOP853 else 5.0
    return min(0.1, max(rtol, 1e-14) ** (1.0 / order) / max(1.0, abs(speed)))


def make_step_size_rule(power, inline=False):
    """The step-size control ``next_step(method, h, err, after_reject, err_prev) -> h``
    with err^a computed as ``power(err, a)``. DOPRI5: the PI controller 0.9 err^-0.17
    err_prev^0.04 (Hairer's DOPRI5 with beta = 0.04; it damps the accept/reject see-saw
    where the step must keep shrinking), within [0.2, 5]; after a rejection only 0.9
    err^(-1/5) and no growth (Hairer-Norsett-Wanner II.4). DOP853: 0.9 err^(-1/8) within
    [1/3, 6], no growth after a rejection (Hairer's DOP853, beta = 0). With ``inline`` it
    is inlined into its caller, for a loop over lanes (benchmarks/bench_step.py)."""

    @njit(**(INLINE_OPTIONS if inline else INNER_OPTIONS))
    def next_step(method, h, err, after_reject, err_prev):
        if method == METHOD_DOP853:
            factor = max(1.0 / 3.0, 0.9 * power(max(err, 1e-10), -0.125))
            return h * min(1.0 if after_reject or err > 1.0 else 6.0, factor)
        if after_reject or err > 1.0:
            return h * min(1.0, max(0.2, 0.9 * power(max(err, 1e-10), -0.2)))
        factor = 0.9 * power(max(err, 1e-10), -0.17) * power(max(err_prev, 1e-4), 0.04)
        return h * min(5.0, max(0.2, factor))

    return next_step


@njit(**INLINE_OPTIONS)
def libm_power(x, a):
    """x^a by the platform's pow (the kernels' step-size control)."""
    return x ** a


#: the kernels' step-size control (make_step_size_rule), err^a by libm's pow
next_step = make_step_size_rule(libm_power)


@njit(**INNER_OPTIONS)
def rejected_step_size(method, h, err, err_prev, t):
    """The step to retry after a rejection (the controller without growth), and whether it
    fell below round-off of t: the flight cannot go on (a blow-up, a discontinuity)."""
    h = next_step(method, h, err, bool(True), err_prev)
    return h, h < 1e-14 * max(1.0, abs(t))


@njit(**INNER_OPTIONS)
def accepted_step_size(method, h, dt, err, after_reject, err_prev):
    """The next step after an accepted one: (h, err_prev) from the controller, or dt for
    RK4 (a first step cut short by the ballistic-return cap is the only short one)."""
    if method != METHOD_RK4:
        return next_step(method, h, err, after_reject, err_prev), err
    return dt, err_prev


@njit(**INNER_OPTIONS)
def ballistic_cap(h, rate, acceleration):
    """The first step after a restart on a surface, leaving at ``rate`` but pulled back by
    ``acceleration``: at most half the ballistic return time 2|rate|/|acceleration|, or a
    short flight falls between two sign samples of the first step (H4)."""
    if rate * acceleration < 0.0:
        return min(h, 0.5 * abs(rate) / abs(acceleration))
    return h
