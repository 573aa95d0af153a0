"""Maxima of a quantity over a crank cycle or a flight: the one golden-section loop of the
package, and the search that brackets every local maximum of a sample.

A peak over a cycle is a maximum of a piecewise-smooth function: smooth between the places
where the model changes (a special position, an impact, a window's edge), with its largest
values often right against such a place (reactions grow like 1/dphi1 towards a node). The
search therefore works on one smooth piece at a time:

1. ``clustered_points``: the piece's ends, a uniform sample, and points approaching each end
   geometrically (a spike against an end narrower than the uniform spacing is seen);
2. the caller evaluates the quantity there (one evaluation may give several quantities);
3. ``refine_sampled_max``: every sampled local maximum is refined by golden section between
   its two neighbours, so the answer does not depend on which basin the sample favoured.

``peak_search(f)`` specialises the search to a quantity ``f(x, data)``, with ``data`` a tuple
of whatever the quantity needs. NaN values count as "no value" (a 0/0 at a node): the caller
supplies one-sided limits there as candidates of its own.
"""

import math

import numpy as np
from numba import njit

from kernels import KERNEL_OPTIONS, INNER_OPTIONS

_GOLDEN = 0.5 * (math.sqrt(5.0) - 1.0)
#: points approaching each end of a piece, by default: down to 2^-CLUSTER of the spacing
CLUSTER = 30


@njit(**KERNEL_OPTIONS)
def golden_points(a, b):
    """The two interior points (c, d) of a golden-section search for a maximum on [a, b]."""
    return b - _GOLDEN * (b - a), a + _GOLDEN * (b - a)


@njit(**KERNEL_OPTIONS)
def golden_shrink(a, b, c, d, fc, fd):
    """One golden-section step towards the maximum, keeping one of the two values. Returns
    (a, b, c, d, fc, fd, left): the caller evaluates the new point, c if left else d, and
    stores it in fc or fd. One evaluation per step; a location error e costs O(e^2) in the
    maximum's value."""
    if fc > fd:
        b, d, fd = d, c, fc
        return a, b, b - _GOLDEN * (b - a), d, fc, fd, True
    a, c, fc = c, d, fd
    return a, b, c, a + _GOLDEN * (b - a), fc, fd, False


@njit(**KERNEL_OPTIONS)
def _value(v):
    return v if v == v else -math.inf


@njit(**KERNEL_OPTIONS)
def clustered_points(a, b, n, depth=CLUSTER):
    """Increasing sample points of [a, b]: both ends, n uniform interior points (spacing
    h = (b - a)/(n + 1)), and ``depth`` points inside each end interval approaching the
    end geometrically (a + h 2^-k, k = 1 ... depth, and likewise at b), so that a spike
    against an end narrower than the uniform spacing is seen."""
    xs = np.empty(n + 2 + 2 * depth)
    h = (b - a) / (n + 1)
    m = 0
    xs[m] = a
    m += 1
    for k in range(depth, 0, -1):
        xs[m] = a + h * 0.5 ** k
        m += 1
    for j in range(1, n + 1):
        xs[m] = a + h * j
        m += 1
    for k in range(1, depth + 1):
        xs[m] = b - h * 0.5 ** k
        m += 1
    xs[m] = b
    return xs


def peak_search(f):
    """The search specialised to one quantity f(x, data) (NaN counts as -inf): returns
    numba functions (golden_max, refine_sampled_max) that call f directly.

    golden_max(data, a, b, stop): golden-section search for a maximum on [a, b] until the
    bracket is shorter than ``stop``; the largest value evaluated.
    refine_sampled_max(data, xs, values, stop): the maximum on [xs[0], xs[-1]] from the
    values at the increasing points xs: the largest sample, and golden_max between the
    neighbours of every sampled local maximum.

    f is a closure cell, frozen at compile time (numba's cache key includes it), not an
    argument: a function passed as an argument through a loop into a loop made numba refuse
    to cache the caller (tests/test_extrema.py).
    """

    @njit(**INNER_OPTIONS)
    def golden_max(data, a, b, stop):
        c, d = golden_points(a, b)
        fc, fd = _value(f(c, data)), _value(f(d, data))
        while b - a > stop:
            a, b, c, d, fc, fd, left = golden_shrink(a, b, c, d, fc, fd)
            if left:
                fc = _value(f(c, data))
            else:
                fd = _value(f(d, data))
        return max(fc, fd)

    @njit(**INNER_OPTIONS)
    def refine_sampled_max(data, xs, values, stop):
        best = -math.inf
        for j in range(xs.shape[0]):
            best = max(best, _value(values[j]))
        for j in range(1, xs.shape[0] - 1):
            v, left, right = _value(values[j]), _value(values[j - 1]), _value(values[j + 1])
            if v == -math.inf or v < left or v < right or (v == left and v == right):
                continue  # not a local maximum (a flat run needs no refinement)
            best = max(best, golden_max(data, xs[j - 1], xs[j + 1], stop))
        return best

    return golden_max, refine_sampled_max


def cell_midpoints(n, period):
    """n profile angles: the midpoints of n equal cells of one cycle [0, period) (empty for
    n = 0), the profile coordinate of every mechanism that has profiles."""
    return period * (np.arange(n) + 0.5) / n if n > 0 else np.empty(0)
