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
