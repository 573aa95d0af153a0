"""Boundary tests of the failure maps docs/failure_map_grazing.png and
docs/failure_map_separatrix.png: on each side of the drawn boundary, the outcome the map
shows (benchmarks/failure_maps.py computes both)."""

import math

import numpy as np
import pytest

from benchmarks import failure_maps as fm
from tests.conftest import kernel_point

PHASES = np.arange(16) / 16


def window(speed):
    return 2 * speed / math.sin(fm.APEX)  # time beyond the stop, ballistic near the apex


def eps_of(speed):
    return fm.APEX - fm.approach_level(speed)


@pytest.mark.parametrize("step", [0.3, 0.1, 0.03])
def test_step_end_sign_change_misses_a_contact_shorter_than_a_step(step):
    wide = 3.0 * step * math.sin(fm.APEX) / 2  # window = 3 steps
    narrow = 0.05 * step * math.sin(fm.APEX) / 2  # window = step / 20
    assert window(wide) == pytest.approx(3 * step)
    assert all(fm.naive_found(step, wide, p) for p in PHASES)
    assert sum(fm.naive_found(step, narrow, p) for p in PHASES) <= 2


@pytest.mark.slow
@pytest.mark.parametrize("step", [0.3, 0.1, 0.03])
def test_kernel_detector_misses_only_below_the_interpolation_error(step):
    """Found in every phase when eps >= 10 step^4/384, even with a window of a hundredth
    of a step; missed in most phases when eps <= step^4/384/30 (the interpolant's error
    then exceeds how far the pendulum passes the stop)."""
    bound = step**4 / 384

    def speed_for(eps):
        return math.sqrt(2 * (math.cos(fm.APEX - eps) - math.cos(fm.APEX)))
    above, below = speed_for(10 * bound), speed_for(bound / 30)
    assert eps_of(above) == pytest.approx(10 * bound, rel=1e-6)
    assert all(fm.detector_found(step, above, p) for p in PHASES)
    if step <= 0.1:
        assert window(above) < step / 5  # the naive detector could not see these
    assert sum(fm.detector_found(step, below, p) for p in PHASES) <= len(PHASES) // 2


@pytest.mark.slow
@pytest.mark.parametrize("rtol", [1e-4, 1e-6, 1e-8])
def test_dopri5_alone_classifies_escape_right_only_above_rtol(rtol):
    assert fm.separatrix_correct("dopri5", rtol, 10 * rtol) == 2
    assert fm.separatrix_correct("dopri5", rtol, rtol / 1000) < 2


@pytest.mark.parametrize("step", [0.3, 0.1, 0.03])
def test_rk4_alone_classifies_escape_right_only_above_step4(step):
    assert fm.separatrix_correct("rk4", step, 10 * step**4) == 2
    assert fm.separatrix_correct("rk4", step, step**4 / 1e4) < 2


@pytest.mark.parametrize("delta", [1e-6, 1e-9, 1e-12])
def test_the_kernel_classifies_by_the_closed_form_where_the_integrator_cannot(delta):
    """The same launch, 2 = v_crit (1 -+ delta) with kappa = (1 +- delta)^-2, k = 1, R = 0,
    through the kernel with DOPRI5 at a loose rtol: the closed-form criterion decides."""
    method = dict(integrator="dopri5", rtol=1e-4, atol=1e-6, max_impacts=10)
    out, status, _ = kernel_point("rotary_pendulum", method, model="rigid", k=1.0,
                                  kappa=(1 + delta) ** 2, R=0.0)
    assert status == "ok"
    assert out["regime"] == 0  # period_1
    out, status, _ = kernel_point("rotary_pendulum", method, model="rigid", k=1.0,
                                  kappa=(1 - delta) ** 2, R=0.0)
    assert status == "escape" and out["regime"] == 3  # escape
