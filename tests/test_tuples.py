"""The tuple arithmetic of the integration core (kernels/impact/tuples.py): the Runge-Kutta
stages lowered as instructions in the caller give the bits of the sum written out in
Python, in the same order, at random states; a call whose tuples do not fit is refused
when it is typed."""

import functools

import numpy as np
import pytest
from numba import njit
from numba.core.errors import TypingError

from kernels.impact.tuples import lincomb, weighted


@njit(error_model="numpy")
def both(y, h, coefs, ks):
    return lincomb(y, h, coefs, ks), weighted(h, coefs, ks)


def written_out(h, coefs, ks):
    """h ((c0 k0[i] + c1 k1[i]) + ...) in Python floats, left to right."""
    n = len(ks[0])
    return [h * functools.reduce(lambda total, term: total + term,
                                 [c * k[i] for c, k in zip(coefs, ks)])
            for i in range(n)]


@pytest.mark.parametrize("n, m, integer_coefficients",
                         [(1, 1, False), (4, 7, True), (20, 12, False)])
def test_the_stages_are_the_written_sum_bit_for_bit(n, m, integer_coefficients):
    """n components, m stages (DOP853's 12 on the 20 of the variational equations), at
    30 random states each with magnitudes over 12 decades; integer coefficients are
    converted to float as numba converts them in a product."""
    rng = np.random.default_rng(n * 100 + m)
    for _ in range(30):
        y = tuple(float(v) for v in rng.standard_normal(n) * 10 ** rng.uniform(-6, 6, n))
        ks = tuple(tuple(float(v) for v in rng.standard_normal(n) * 10 ** rng.uniform(-6, 6, n))
                   for _ in range(m))
        coefs = tuple(int(c) if integer_coefficients and j % 2 else float(c)
                      for j, c in enumerate(rng.integers(-9, 10, m) if integer_coefficients
                                            else rng.standard_normal(m)))
        h = float(10 ** rng.uniform(-8, 0))
        combined, weighted_sum = both(y, h, coefs, ks)
        expected = written_out(h, coefs, ks)
        assert np.array_equal(np.array(weighted_sum), np.array(expected))
        assert np.array_equal(np.array(combined), np.array(y) + np.array(expected))
        # and the plain-Python versions, which serve callers outside numba, agree
        assert np.allclose(lincomb(y, h, coefs, ks), combined, rtol=1e-14, atol=0.0)


def test_tuples_that_do_not_fit_are_refused_when_typed():
    """A state of another length, or more coefficients than states: a typing error, not
    a value made of what fits."""
    with pytest.raises(TypingError):
        both((1.0, 2.0), 0.1, (1.0,), ((1.0, 2.0, 3.0),))
    with pytest.raises(TypingError):
        both((1.0, 2.0), 0.1, (1.0, 2.0), ((1.0, 2.0),))
