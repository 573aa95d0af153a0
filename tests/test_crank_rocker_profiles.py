"""The crank-rocker's rocker motion over a crank turn ([CR] Fig. 2, issue 64 item 4): the
profiles of u31 and phi3 at random designs of the three types against numpy's own loop
closure (circle intersections) and central differences of it; none where the status is
not usable."""

import math

import numpy as np
import pytest

import sweep
from tests.circles import pivot_angles


def rocker_angle(phi1, lam0, lam2, lam3, near):
    """phi3 of the assembly nearer the rocker angle ``near`` (l1 = 1, A at the origin, D at
    (lambda0, 0)), in [0, 2 pi)."""
    angles = pivot_angles(np.array([lam0, 0.0]), np.array([math.cos(phi1), math.sin(phi1)]),
                          lam2, lam3)
    return min((x % (2 * math.pi) for x in angles),
               key=lambda x: abs(math.remainder(x - near, 2 * math.pi)))


@pytest.mark.parametrize("kind", ["a", "b", "c"])
def test_the_profiles_are_the_loop_closure_and_its_derivative(kind):
    rng = np.random.default_rng({"a": 1, "b": 2, "c": 3}[kind])
    low, high = (14.0, 30.0) if kind == "b" else (2.6, 5.0)  # b: the rocker is the largest
    spec = {"mechanism": "crank_rocker",
            "grid": {"R": list(rng.uniform(0.1, 0.4, 3)),
                     "largest_link": list(rng.uniform(low, high, 3))},
            "fixed": {"type": kind}, "method": {"profile_points": 36}}
    ds = sweep.decode(sweep.run(spec)).stack(design=["R", "largest_link"])
    usable = ds.status.values == "ok"
    assert usable.sum() >= 3
    assert np.isnan(ds.transfer_ratio.values[:, ~usable]).all()
    h = 1e-6
    for k in np.flatnonzero(usable):
        design = ds.isel(design=k)
        lam0, lam2, lam3 = (float(design[n]) for n in ("lambda0", "lambda2", "lambda3"))
        for j, phi in enumerate(ds.crank_angle.values):
            phi3 = float(design.rocker_angle.values[j])
            assert rocker_angle(phi, lam0, lam2, lam3, phi3) == pytest.approx(phi3,
                                                                                abs=1e-12)
            ahead = rocker_angle(phi + h, lam0, lam2, lam3, phi3)
            behind = rocker_angle(phi - h, lam0, lam2, lam3, phi3)
            slope = math.remainder(ahead - behind, 2 * math.pi) / (2 * h)
            assert float(design.transfer_ratio.values[j]) == pytest.approx(slope, abs=1e-6)
