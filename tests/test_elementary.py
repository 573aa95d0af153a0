"""The kernels' own atan2 and sine-cosine pair against libm (math.atan2, math.sin,
math.cos), in ulp."""

import math

import numpy as np
import pytest

from kernels.elementary import atan2_fast, atan_fast, jacobi_small, sincos_quadrant


def ulp_error(a, b):
    return abs(a - b) / math.ulp(abs(b)) if b != 0 else abs(a) / 5e-324


def test_atan_fast_within_2_ulp_on_random_and_edge_inputs():
    rng = np.random.default_rng(0)
    xs = np.concatenate([rng.uniform(-1, 1, 20000), 10 ** rng.uniform(-12, 12, 20000),
                         -(10 ** rng.uniform(-12, 12, 20000)),
                         [0.0, 0.66, 0.66 + 1e-16, 2.414213562373095, 2.4142135623730954,
                          1.0, -1.0, 1e308, -1e308, 5e-324]])
    worst = max(ulp_error(atan_fast(float(x)), math.atan(float(x))) for x in xs)
    assert worst <= 2.0, worst
    assert atan_fast(math.inf) == pytest.approx(math.pi / 2, rel=1e-16)


def test_atan2_fast_quadrants_and_accuracy():
    rng = np.random.default_rng(1)
    y = rng.normal(size=20000) * 10 ** rng.uniform(-6, 6, 20000)
    x = rng.normal(size=20000) * 10 ** rng.uniform(-6, 6, 20000)
    worst = max(ulp_error(atan2_fast(a, b), math.atan2(a, b)) for a, b in zip(y, x))
    assert worst <= 3.0, worst
    for a, b in [(1.0, 0.0), (-1.0, 0.0), (0.0, 1.0), (0.0, -1.0), (1.0, -1.0),
                 (-1.0, -1.0), (0.0, 0.0), (1e-300, 1.0), (1.0, 1e-300)]:
        assert atan2_fast(a, b) == pytest.approx(math.atan2(a, b), abs=4e-16)


def test_sincos_quadrant_within_1_ulp_of_libm_on_the_first_quadrant():
    """sin and cos of x in [0, pi/2] from one reduction: random points, tiny arguments, and
    the ends and the switch at pi/4 with their neighbours; a Taylor series of the wrong
    order or an unsplit pi/2 - x (x near pi/2: cos x is the small difference) fails it."""
    rng = np.random.default_rng(5)
    quarter = 0.25 * math.pi
    xs = np.concatenate([rng.uniform(0.0, 0.5 * math.pi, 40000), 10 ** rng.uniform(-300, -1, 2000),
                         0.5 * math.pi - 10 ** rng.uniform(-15, -1, 2000),
                         [0.0, 5e-324, quarter, np.nextafter(quarter, 0), np.nextafter(quarter, 4),
                          0.5 * math.pi, np.nextafter(0.5 * math.pi, 0)]])
    worst_sin = worst_cos = 0.0
    for x in xs:
        s, c = sincos_quadrant(float(x))
        worst_sin = max(worst_sin, ulp_error(s, math.sin(x)))
        worst_cos = max(worst_cos, ulp_error(c, math.cos(x)))
    assert worst_sin <= 1.0 and worst_cos <= 1.0, (worst_sin, worst_cos)
    assert all(math.isnan(v) for v in sincos_quadrant(math.nan))


def test_golden_section_finds_a_maximum_with_one_evaluation_per_step():
    from kernels.extrema import golden_points, golden_shrink
    calls = []

    def f(x):
        calls.append(x)
        return -(x - 0.3) ** 2

    a, b = -1.0, 2.0
    c, d = golden_points(a, b)
    fc, fd = f(c), f(d)
    steps = 0
    while b - a > 1e-10:
        a, b, c, d, fc, fd, left = golden_shrink(a, b, c, d, fc, fd)
        if left:
            fc = f(c)
        else:
            fd = f(d)
        steps += 1
    assert abs(0.5 * (a + b) - 0.3) < 1e-10
    assert len(calls) == steps + 2  # one new evaluation per step
    assert steps == math.ceil(math.log(1e-10 / 3.0) / math.log(0.5 * (math.sqrt(5) - 1)))


def test_jacobi_small_against_mpmath_across_the_separatrix():
    """sn, cn, dn(u | m) at random u and m: libration (m < 1), m within 1e-16..1 of the
    separatrix, m = 0 and 1 exactly, and over the top (m up to 30), |u| sqrt(max(1, m))
    up to 1 (the exact pendulum step's reach where no event can fire, flight.EXACT_REACH):
    within 2e-15 of mpmath at 40 digits. A wrong series coefficient or a doubling formula
    gives 1e-10 or worse."""
    import mpmath

    mpmath.mp.dps = 40
    rng = np.random.default_rng(11)
    worst = 0.0
    for i in range(600):
        m = [rng.uniform(0, 1), 1 - 10 ** rng.uniform(-16, 0), rng.uniform(1, 30), 0.0,
             1.0][i % 5]
        u = rng.uniform(-1.0, 1.0) / math.sqrt(max(1.0, m))
        got = jacobi_small(float(u), float(m))
        for value, name in zip(got, ("sn", "cn", "dn")):
            want = float(mpmath.re(mpmath.ellipfun(name, mpmath.mpf(u), m=mpmath.mpf(m))))
            worst = max(worst, abs(value - want))
    assert worst <= 2e-15, worst
    assert jacobi_small(0.3, 0.0) == pytest.approx((math.sin(0.3), math.cos(0.3), 1.0),
                                                   abs=4e-16)
    assert jacobi_small(0.3, 1.0) == pytest.approx(
        (math.tanh(0.3), 1 / math.cosh(0.3), 1 / math.cosh(0.3)), abs=4e-16)


def test_sincos_lane_within_2_ulp_of_libm_odd_and_even_exactly():
    """sin and cos of any finite argument without a call or a branch (a step in lanes):
    random points where the pendulum's angle lives and far out, tiny arguments, the
    quarter turns and their neighbours, against libm in ulp (absolute at libm's own
    zeros); sin odd and cos even bit for bit. A reduction by a one-part pi/2 (cos near
    pi/2 off by ~1e-17 absolute, hundreds of ulp) or a quarter turn in the wrong quadrant
    fails it."""
    from numba import njit

    from kernels.elementary import sincos_lane

    @njit
    def pairs(xs):
        out = np.empty((xs.shape[0], 2))
        for i in range(xs.shape[0]):
            out[i, 0], out[i, 1] = sincos_lane(xs[i])
        return out

    rng = np.random.default_rng(7)
    quarters = np.arange(-40, 41) * (0.5 * math.pi)
    xs = np.concatenate([rng.uniform(-7.0, 7.0, 40000), rng.uniform(-1e5, 1e5, 20000),
                         10 ** rng.uniform(-300, 0, 2000), quarters,
                         np.nextafter(quarters, np.inf), np.nextafter(quarters, -np.inf),
                         [0.0, -0.0, 5e-324, 0.25 * math.pi]])
    xs = np.concatenate([xs, -xs])
    got = pairs(xs)
    worst = 0.0
    for x, (s, c) in zip(xs, got):
        for value, exact in ((s, math.sin(x)), (c, math.cos(x))):
            # near a zero of sin or cos libm's value is as small as the argument's own
            # rounding; there the error is measured against the argument's ulp
            scale = max(math.ulp(abs(exact)), math.ulp(abs(x)) if abs(exact) < 1e-8 else 0.0)
            worst = max(worst, abs(value - exact) / scale)
    assert worst <= 2.0, worst
    back = pairs(-xs)
    assert np.array_equal(back[:, 0], -got[:, 0]) and np.array_equal(back[:, 1], got[:, 1])
    assert all(math.isnan(v) for x in (math.nan, math.inf) for v in pairs(np.array([x]))[0])


def test_log_and_exp_lane_against_mpmath():
    """power_lane's two pieces at 120 bits: ln x within 2 ulp over 24 decades and next to
    1 (where the series carries the whole value), e^y within 1 ulp from tiny to |y| near
    700. A series one term short (6.5 and 2 ulp) or 2^k built from the wrong bits fails
    it."""
    import mpmath
    from numba import njit

    from kernels.elementary import _exp_lane, _log_lane

    @njit
    def apply(xs, log):
        out = np.empty_like(xs)
        for i in range(xs.shape[0]):
            out[i] = _log_lane(xs[i]) if log else _exp_lane(xs[i])
        return out

    mpmath.mp.prec = 120
    rng = np.random.default_rng(3)
    xs = np.concatenate([10 ** rng.uniform(-12, 12, 3000), rng.uniform(0.7, 1.45, 3000),
                         [2.2250738585072014e-308, 1.7976931348623157e308, 2.0, 0.5,
                          math.sqrt(2.0), np.nextafter(math.sqrt(2.0), 0.0)]])
    worst_log = max(float(abs(g - e)) / math.ulp(float(abs(e)))
                    for g, e in zip(apply(xs, True), (mpmath.log(float(x)) for x in xs)))
    ys = np.concatenate([rng.uniform(-30, 30, 3000), rng.uniform(-0.4, 0.4, 3000),
                         rng.uniform(-700, 700, 1000), [0.0, 1e-300, -1e-300]])
    worst_exp = max(float(abs(g - e)) / math.ulp(float(e))
                    for g, e in zip(apply(ys, False), (mpmath.exp(float(y)) for y in ys)))
    assert worst_log <= 2.0 and worst_exp <= 1.0, (worst_log, worst_exp)
    assert apply(np.array([1.0]), True)[0] == 0.0 and apply(np.array([0.0]), False)[0] == 1.0


def test_power_lane_against_mpmath_over_the_controllers_range():
    """x^a = e^(a ln x) against mpmath at 120 bits: errors from 1e-10 (the controller's
    floor) to 1e10 and over the whole normal range, at the controllers' exponents and
    others, within 2e-16 (2 + |a ln x|) relative (ln x's error, times a, is e^y's
    argument's: it grows with |y|, a bound libm's pow does not need)."""
    import mpmath
    from numba import njit

    from kernels.elementary import power_lane

    @njit
    def powers(xs, a):
        out = np.empty_like(xs)
        for i in range(xs.shape[0]):
            out[i] = power_lane(xs[i], a)
        return out

    rng = np.random.default_rng(11)
    xs = np.concatenate([10 ** rng.uniform(-10, 10, 1500), 10 ** rng.uniform(-307, 308, 300),
                         [2.2250738585072014e-308, 1.7976931348623157e308, 1.0, 2.0, 0.5,
                          1e-10, 1e-4]])
    mpmath.mp.prec = 120
    for a in (-0.2, -0.17, 0.04, -0.125, 1.0, -1.0 / 3.0, 2.0):
        for x, value in zip(xs, powers(xs, a)):
            y = a * math.log(x)
            if abs(y) < 700.0:
                exact = mpmath.mpf(float(x)) ** mpmath.mpf(a)
                assert abs(value - exact) <= 2e-16 * (2.0 + abs(y)) * exact, (x, a, value)
    assert powers(np.array([1.0]), -0.2)[0] == 1.0


def test_lane_functions_vectorise_over_lanes():
    """A loop of sincos_lane and of power_lane over the lanes of a flat buffer compiles to
    packed arithmetic and no call to sin, cos, pow, exp or log: what a step and its
    step-size control in lanes rest on (libm's do not vectorise). With libm's pow or sin
    in the loop it fails."""
    import re

    from numba import njit

    from kernels.elementary import power_lane, sincos_lane

    @njit(error_model="numpy")
    def lanes(buf):
        for lane in range(8):
            buf[8 + lane], buf[16 + lane] = sincos_lane(buf[lane])
            buf[24 + lane] = power_lane(buf[32 + lane], -0.2)

    lanes(np.ones(40))
    # the IR names what is called (the machine code calls libm through a register)
    ir = lanes.inspect_llvm(lanes.signatures[0])
    assert len(re.findall(r"<[248] x double>", ir)) > 40
    calls = re.findall(r"call [^\n]*@(?:llvm\.)?((?:sin|cos|pow|exp|log)[\w.]*)\(", ir)
    assert not calls, calls
