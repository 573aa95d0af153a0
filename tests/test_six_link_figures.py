"""The six-link's profiles for [SIX] Figs. 4 and 6 (issue 64 item 4), on request: link 3's
angle on each fixed stage-1 branch (the paper's two laws) and on the switching path, and
stage 2's transfer ratio u53; against numpy's own circle intersections and central
differences of them. Without the request, the atlas holds the rocker angle alone."""

import math

import numpy as np
import pytest

import sweep
from tests.circles import pivot_angles

FIGURES = ["rocker_angle", "link3_angle", "link3_angle_branch_plus",
           "link3_angle_branch_minus", "transfer_stage2"]


def gap(a, b):
    return abs(math.remainder(a - b, 2 * math.pi))


@pytest.fixture(scope="module")
def six():
    spec = {"mechanism": "six_link", "grid": {"beta": [0.0, 0.7]},
            "fixed": {"mu5": 3.1, "delta": 0.2}, "outputs": ["impact_speed_1", *FIGURES],
            "method": {"profile_points": 96}}
    return sweep.decode(sweep.run(spec))


def test_the_two_laws_are_the_two_assemblies_and_the_path_takes_each_for_a_turn(six):
    lam2, lam3 = 1.6, 1.3
    lam6 = 1.0 - lam2 + lam3
    for k in range(six.sizes["beta"]):
        point = six.isel(beta=k)
        for j, phi1 in enumerate(six.crank_angle.values):
            both = pivot_angles(np.array([lam6, 0.0]), np.array([math.cos(phi1),
                                                                 math.sin(phi1)]), lam2, lam3)
            plus = float(point.link3_angle_branch_plus.values[j])
            minus = float(point.link3_angle_branch_minus.values[j])
            assert sorted(min(gap(x, b) for b in both) for x in (plus, minus)) == \
                pytest.approx([0.0, 0.0], abs=1e-12)
            assert gap(plus, minus) > 1e-6  # two distinct assemblies off the nodes
            path = float(point.link3_angle.values[j])
            assert path == (plus if phi1 < 2 * math.pi else minus)
        # both laws and the path turn link 3 by 4 pi over the cycle, never backwards
        for name in ("link3_angle", "link3_angle_branch_plus", "link3_angle_branch_minus"):
            assert (np.diff(point[name].values) > 0).all(), name


def test_the_stage_2_ratio_is_the_slope_of_its_loop_closure(six):
    """u53 against a central difference of phi5(phi3) from numpy's circle intersections,
    the root followed being the one nearest the atlas's phi5."""
    lam3, mu4, mu5 = 1.3, 1.5, 3.1
    mu6 = 1.0 - mu4 + mu5
    h = 1e-6
    for k, beta in enumerate(six.beta.values):
        point = six.isel(beta=k)
        offset = 0.2 - beta
        crossings = 0
        for j in range(six.sizes["crank_angle"]):
            phi3 = float(point.link3_angle.values[j]) + offset  # in stage 2's frame
            phi5 = float(point.rocker_angle.values[j])

            def rocker(x):
                roots = pivot_angles(np.array([mu6, 0.0]), np.array([math.cos(x),
                                                                     math.sin(x)]), mu4, mu5)
                return min(roots, key=lambda r: gap(r, phi5))
            if min(gap(phi3, 0.0), gap(rocker(phi3), math.pi)) < 1e-3:
                crossings += 1  # at the impact the slope jumps
                continue
            assert gap(rocker(phi3), phi5) < 1e-12
            slope = math.remainder(rocker(phi3 + h) - rocker(phi3 - h), 2 * math.pi) / (2 * h)
            assert float(point.transfer_stage2.values[j]) == pytest.approx(slope, abs=1e-6)
        assert crossings <= 4


def test_without_the_request_the_atlas_has_the_rocker_angle_alone():
    spec = {"mechanism": "six_link", "grid": {"beta": [0.0]},
            "method": {"profile_points": 8}}
    ds = sweep.decode(sweep.run(spec))
    profiles = [n for n in ds.data_vars if "crank_angle" in ds[n].dims]
    assert profiles == ["rocker_angle"]
