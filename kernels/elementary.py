"""Small elementary functions for kernels where libm is the bottleneck.

numba calls the platform libm for math.atan2 (scalar), about ten times the cost of numpy's
SIMD arctan2: in a closed-form kernel two atan2 calls took a large share of the time.
``atan2_fast`` is the classical three-interval reduction with a degree-4/5 rational
approximation on |x| <= tan(pi/8) (Moshier's Cephes scheme), accurate to ~2 ulp
(tests/test_elementary.py checks it against math.atan2 over random and special inputs).
``sincos_quadrant`` gives sin and cos of one argument in [0, pi/2] from one reduction
(the half period's quadrature needs both at every node), within an ulp of libm
(tests/test_elementary.py).

``sincos_lane`` and ``power_lane`` are written without a call or a branch, so that a loop
of them over lanes laid out lane-minor is vectorised by LLVM, which libm's sin, cos and
pow are not (numba from PyPI has no vector math library): the integrator's step and its
step-size control in lanes (benchmarks/bench_step.py).
"""

import math

import numpy as np
from numba import njit, types
from numba.extending import intrinsic, overload

from kernels import INLINE_OPTIONS, KERNEL_OPTIONS

# arctan x = x + x z P(z) / Q(z), z = x^2, on |x| <= tan(pi/8) (Moshier's Cephes coefficients;
# Q monic)
_ATAN_P = (-8.750608600031904122785e-01, -1.615753718733365076637e01,
           -7.500855792314704667340e01, -1.228866684490136173410e02,
           -6.485021904942025371773e01)
_ATAN_Q = (1.0, 2.485846490142306297962e01, 1.650270098316988542046e02,
           4.328810604912902668951e02, 4.853903996359136964868e02,
           1.945506571482613964425e02)
_TAN_3PI_8 = 2.41421356237309504880
_MOREBITS = 6.123233995736765886130e-17  # pi/2 - float(pi/2)


def horner(x, coefficients):
    """coefficients[0] x^(n-1) + ... + coefficients[n-1] by Horner's rule; in numba
    written out for the tuple's length (a loop over the coefficients kept a loop over
    lanes from vectorising)."""
    result = coefficients[0]
    for c in coefficients[1:]:
        result = result * x + c
    return result


@overload(horner, inline="always")
def _horner(x, coefficients):
    body = "coefficients[0]"
    for i in range(1, coefficients.count):
        body = f"({body}) * x + coefficients[{i}]"
    namespace = {}
    exec(f"def horner(x, coefficients):\n    return {body}\n", namespace)
    return namespace["horner"]


@njit(**KERNEL_OPTIONS)
def atan_fast(x):
    """arctan(x) for finite or infinite x, NaN for NaN."""
    sign = 1.0
    if x < 0.0:
        sign = -1.0
        x = -x
    if x > _TAN_3PI_8:
        base = 0.5 * math.pi
        extra = _MOREBITS
        x = -1.0 / x
    elif x > 0.66:
        base = 0.25 * math.pi
        extra = 0.5 * _MOREBITS
        x = (x - 1.0) / (x + 1.0)
    else:
        base = 0.0
        extra = 0.0
    z = x * x
    return sign * (base + (extra + (x + x * z * horner(z, _ATAN_P) / horner(z, _ATAN_Q))))


@njit(**KERNEL_OPTIONS)
def atan2_fast(y, x):
    """atan2(y, x) in (-pi, pi] for finite y, x (quadrants as math.atan2; atan2(0, 0) = 0)."""
    if x == 0.0:
        if y > 0.0:
            return 0.5 * math.pi
        if y < 0.0:
            return -0.5 * math.pi
        return 0.0
    a = atan_fast(y / x)
    if x < 0.0:
        return a + math.pi if y >= 0.0 else a - math.pi
    return a


# sin and cos on [-pi/4, pi/4] (Moshier's Cephes coefficients):
# sin x = x + x^3 S(x^2), cos x = 1 - x^2/2 + x^4 C(x^2)
_SIN = (1.58962301576546568060e-10, -2.50507477628578072866e-8, 2.75573136213857245213e-6,
        -1.98412698295895385996e-4, 8.33333333332211858878e-3, -1.66666666666666307295e-1)
_COS = (-1.13585365213876817300e-11, 2.08757008419747316778e-9, -2.75573141792967388112e-7,
        2.48015872888517045348e-5, -1.38888888888730564116e-3, 4.16666666666665929218e-2)
# pi/2 = _PIO2_HI + _PIO2_LO: _PIO2_HI - x is exact for x in [pi/4, pi/2] (Sterbenz), so
# pi/2 - x is rounded once (a three-part split cancelled next to pi/2: cos was 7 ulp off)
_PIO2_HI, _PIO2_LO = 1.5707963267948966, 6.123233995736766e-17


@njit(**INLINE_OPTIONS)
def _sin_cos_reduced(x):
    """sin x and cos x for |x| <= pi/4: Cephes' polynomials."""
    z = x * x
    s, c = horner(z, _SIN), horner(z, _COS)
    return x + x * z * s, 1.0 - 0.5 * z + z * z * c


@njit(**KERNEL_OPTIONS)
def sincos_quadrant(x):
    """(sin x, cos x) for x in [0, pi/2], within an ulp of libm, at about half the cost of
    math.sin and math.cos (one reduction, two short polynomials in parallel): the half
    period's nodes take both at every node."""
    if x > 0.25 * math.pi:
        y = (_PIO2_HI - x) + _PIO2_LO
        s, c = _sin_cos_reduced(y)
        return c, s
    return _sin_cos_reduced(x)


# pi/2 in three parts for Cody and Waite's reduction: the first two with 27 significant
# bits, so that n times each is exact for |n| < 2^26 (Cephes' DP1..DP3, doubled)
_PIO2_A, _PIO2_B, _PIO2_C = 1.5707962512969970703125, 7.549789415861596353352e-8, \
    5.390302858158119052953e-15
_TWO_OVER_PI = 0.6366197723675814


@njit(**INLINE_OPTIONS)
def sincos_lane(x):
    """(sin x, cos x) for finite x (|x| < 1e7; NaN for NaN or inf) without a call or a
    branch: x = n pi/2 + r by Cody and Waite's reduction in three parts, |r| <= pi/4,
    sin r and cos r by _sin_cos_reduced, and the pair rotated by n quarter turns with
    selects. Odd and even exactly (reduced from |x|). Within 2 ulp of libm
    (tests/test_elementary.py)."""
    a = abs(x)
    n = np.floor(a * _TWO_OVER_PI + 0.5)  # a float (math.floor's is an int)
    r = ((a - n * _PIO2_A) - n * _PIO2_B) - n * _PIO2_C
    sr, cr = _sin_cos_reduced(r)
    quarter = n - 4.0 * np.floor(0.25 * n)  # n mod 4
    odd = (quarter == 1.0) | (quarter == 3.0)
    s = cr if odd else sr
    c = sr if odd else cr
    s = -s if quarter >= 2.0 else s
    c = -c if (quarter == 1.0) | (quarter == 2.0) else c
    return (-s if x < 0.0 else s), c


def _bitcast(source, target):
    """An intrinsic reading a ``source`` value's IEEE bits as a ``target`` (an LLVM
    bitcast: no memory, no call, so it vectorises)."""

    @intrinsic
    def bitcast(typingctx, x):
        if x != source:
            return None

        def codegen(context, builder, signature, args):
            return builder.bitcast(args[0], context.get_value_type(target))
        return target(source), codegen
    return bitcast


_float_bits = _bitcast(types.float64, types.int64)
_bits_float = _bitcast(types.int64, types.float64)


_MANTISSA = (1 << 52) - 1
_ONE_EXPONENT = 1023 << 52  # the exponent field of 1.0
_TWO_52_EXPONENT = 0x4330000000000000  # of 2^52: an integer in the mantissa is 2^52 + n
_ROUNDING = 6755399441055744.0  # 1.5 * 2^52: x + it - it rounds x to an integer
_LN2_HI, _LN2_LO = 6.93147180369123816490e-01, 1.90821492927058770002e-10  # fdlibm's
_INV_LN2 = 1.4426950408889634
#: 1/19, 1/17, ..., 1/3: 2 atanh s = 2 s (1 + z/3 + z^2/5 + ...), z = s^2
_ATANH_SERIES = tuple(1.0 / k for k in range(19, 2, -2))
#: 1/13!, 1/12!, ..., 1/2!: e^r = 1 + r + r^2 (1/2! + r/3! + ...)
_EXP_SERIES = tuple(1.0 / math.factorial(k) for k in range(13, 1, -1))


@njit(**INLINE_OPTIONS)
def _log_lane(x):
    """ln x for normal x > 0: x = m 2^e from the bits, m in [sqrt(1/2), sqrt(2)), and
    ln m = 2 atanh s, s = (m - 1)/(m + 1), |s| <= 0.172, by its series to s^19 (the
    next term is below 0.2 ulp; without the s^19 term the error reached 6.5 ulp)."""
    bits = _float_bits(x)
    m = _bits_float((bits & _MANTISSA) | _ONE_EXPONENT)
    e = _bits_float((bits >> 52) | _TWO_52_EXPONENT) - (4503599627370496.0 + 1023.0)
    high = m > 1.4142135623730951
    m = 0.5 * m if high else m
    e = e + 1.0 if high else e
    s = (m - 1.0) / (m + 1.0)
    z = s * s
    p = horner(z, _ATANH_SERIES)
    return e * _LN2_HI + (2.0 * s + (2.0 * s * z * p + e * _LN2_LO))


@njit(**INLINE_OPTIONS)
def _exp_lane(y):
    """e^y for |y| < 700: y = k ln 2 + r, |r| <= ln(2)/2, e^r by its Taylor series to
    r^13 (without that term the error reached 2 ulp), times 2^k built from its bits (k
    read off the rounding's mantissa)."""
    t = y * _INV_LN2 + _ROUNDING
    k = t - _ROUNDING
    r = (y - k * _LN2_HI) - k * _LN2_LO
    p = horner(r, _EXP_SERIES)
    return (1.0 + (r + r * r * p)) * _bits_float((_float_bits(t) + 1023) << 52)


@njit(**INLINE_OPTIONS)
def power_lane(x, a):
    """x^a for normal x > 0 and |a ln x| < 700 without a call or a branch (the step-size
    controller's err^-0.2 and its kind, in lanes): e^(a ln x), within 2e-16 (2 + |a ln x|)
    relative of the exact power (tests/test_elementary.py): ln x's error, times a, is
    e^y's argument's, so it grows with |y|."""
    return _exp_lane(a * _log_lane(x))


#: the Maclaurin series of sn, cn, dn serve up to this |u| sqrt(max(1, m)): the first term
#: left out is below 1e-18 of the value there
_JACOBI_SERIES_REACH = 2.0 ** -5


@njit(**KERNEL_OPTIONS)
def jacobi_small(u, m):
    """Jacobi's (sn, cn, dn)(u | m) for a parameter m >= 0 (m > 1 too: a pendulum over the
    top) and |u| sqrt(max(1, m)) up to 1, for the exact step of a pendulum: the
    Maclaurin series to u^9 at u / 2^n (n halvings bring it within _JACOBI_SERIES_REACH),
    then n doublings of sn, 1 - cn and 1 - dn, free of cancellation while cn, dn > 0 (the
    plain doubling of cn lost 6 ulp at u = 0.3 on the separatrix). Within a few ulp of
    mpmath over |u| sqrt(max(1, m)) <= 1 (tests/test_elementary.py); no special case at
    m = 1 (the separatrix), where the arithmetic-geometric mean's descent stalls."""
    reach = abs(u) * math.sqrt(max(1.0, m))
    n = 0
    while reach > _JACOBI_SERIES_REACH:
        reach *= 0.5
        u *= 0.5
        n += 1
    u2, m2 = u * u, m * m
    m3 = m2 * m
    sn = u * (1.0 - u2 / 6.0 * ((1.0 + m) - u2 / 20.0 * (
        (1.0 + 14.0 * m + m2) - u2 / 42.0 * ((1.0 + 135.0 * m + 135.0 * m2 + m3)
                                             - u2 / 72.0 * (1.0 + 1228.0 * m + 5478.0 * m2
                                                            + 1228.0 * m3 + m2 * m2)))))
    # 1 - cn and 1 - dn, small near u = 0: the doublings then subtract nothing
    a = u2 / 2.0 * (1.0 - u2 / 12.0 * ((1.0 + 4.0 * m) - u2 / 30.0 * (
        (1.0 + 44.0 * m + 16.0 * m2) - u2 / 56.0 * (1.0 + 408.0 * m + 912.0 * m2
                                                    + 64.0 * m3))))
    b = u2 / 2.0 * m * (1.0 - u2 / 12.0 * ((4.0 + m) - u2 / 30.0 * (
        (16.0 + 44.0 * m + m2) - u2 / 56.0 * (64.0 + 912.0 * m + 408.0 * m2 + m3))))
    for _ in range(n):
        s2 = sn * sn
        cn, dn = 1.0 - a, 1.0 - b
        inverse = 1.0 / (1.0 - m * s2 * s2)
        # sn(2u) = 2 sn cn dn / D, 1 - cn(2u) = 2 sn^2 dn^2 / D, 1 - dn(2u) = 2 m sn^2 cn^2
        # / D, D = 1 - m sn^4 (cn^2 = 1 - sn^2 and dn^2 = 1 - m sn^2 taken exactly)
        sn, a, b = (2.0 * sn * cn * dn * inverse, 2.0 * s2 * dn * dn * inverse,
                    2.0 * m * s2 * cn * cn * inverse)
    return sn, 1.0 - a, 1.0 - b
