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
    (lambda0, 0))."""
    angles = pivot_angles(np.array([lam0, 0.0]), np.array([math.cos(phi1), math.sin(phi1)]),
                          lam2, lam3)
    return min(angles, key=lambda x: abs(math.remainder(x - near, 2 * math.pi)))


@pytest.mark.parametrize("path", ["impact", "free"])
@pytest.mark.parametrize("kind", ["a", "b", "c"])
def test_the_profiles_are_the_loop_closure_and_its_derivative(kind, path):
    rng = np.random.default_rng({"a": 1, "b": 2, "c": 3}[kind])
    low, high = (14.0, 30.0) if kind == "b" else (2.6, 5.0)  # b: the rocker is the largest
    spec = {"mechanism": "crank_rocker",
            "grid": {"R": list(rng.uniform(0.1, 0.4, 3)),
                     "largest_link": list(rng.uniform(low, high, 3))},
            "fixed": {"type": kind}, "method": {"profile_points": 36, "path": path}}
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
            assert abs(math.remainder(rocker_angle(phi, lam0, lam2, lam3, phi3) - phi3,
                                      2 * math.pi)) < 1e-12
            ahead = rocker_angle(phi + h, lam0, lam2, lam3, phi3)
            behind = rocker_angle(phi - h, lam0, lam2, lam3, phi3)
            slope = math.remainder(ahead - behind, 2 * math.pi) / (2 * h)
            assert float(design.transfer_ratio.values[j]) == pytest.approx(slope, abs=1e-6)


@pytest.mark.parametrize("kind", ["a", "c"])
def test_the_free_path_passes_the_node_smoothly_and_the_impact_path_reverses(kind):
    """Over the free path's two turns u31 has no jump (the smooth curve through the node),
    and the rocker turns back to where it started; on the impact path u31 jumps at the node
    from transfer_before to transfer_after."""
    runs = {}
    for path in ("impact", "free"):
        spec = {"mechanism": "crank_rocker", "grid": {"type": [kind]},
                "fixed": {"R": 0.3, "largest_link": 3.0},
                "method": {"profile_points": 2880, "path": path}}
        runs[path] = sweep.decode(sweep.run(spec)).isel(type=0)
    free, impact = runs["free"], runs["impact"]
    assert free.crank_angle.values[-1] > 3.9 * math.pi > impact.crank_angle.values[-1]
    u = free.transfer_ratio.values
    step = np.diff(free.crank_angle.values)[0]
    assert np.abs(np.diff(u)).max() < 0.05 * np.abs(u).max()
    assert np.abs(np.diff(free.rocker_angle.values)).max() <= 1.01 * np.abs(u).max() * step
    u = impact.transfer_ratio.values
    jumps = np.abs(np.diff(np.r_[u, u[0]]))
    node_jump = abs(float(impact.transfer_after) - float(impact.transfer_before))
    assert jumps.max() == pytest.approx(node_jump, rel=0.02)
