"""Six-link impact mechanism ([SIX]; docs/models.md §3): oracles O10-O12, hard cases H5,
H6 (stage 2), H14, and the link-length conditions."""

import math

import numpy as np
import pytest

from kernels import fourbar as fb
from kernels import six_link as sl

EXAMPLE = dict(lambda2=1.6, lambda3=1.3, mu4=1.5, mu5=2.5, beta=0.0, delta=0.0, direction=1,
               omega1=30.0, crank_length=0.1)
LAM6 = 1 - 1.6 + 1.3
MU6 = 1 - 1.5 + 2.5
TOL = 1e-9


def run(samples=2880, profile_points=0, **kw):
    p = dict(EXAMPLE, **kw)
    params = np.array([[p.get(name, np.nan)] for name in sl.P._fields], dtype=float)
    method = sl.DECLARATION.method_record(geometry_tol=TOL, samples=samples,
                                          profile_points=profile_points)
    out, status, prof = sl.run(params, method)
    return dict(zip(sl.O._fields, out[:, 0])), int(status[0]), prof[sl.ROCKER_ANGLE, 0]


def phi5(phi1, beta=0.0, delta=0.0, sigma2=1.0):
    """The composed rocker angle phi5(phi1), continuous (the rocker swings about pi)."""
    phi3 = sl.stage1(phi1, LAM6, 1.6, 1.3, TOL)[0]
    return fb.loop_closure(phi3 + delta - beta, MU6, 1.0, 1.5, 2.5, sigma2, TOL)[1] % (2 * math.pi)


def test_O10_stage1_alternates_and_is_continuous_on_the_switched_path():
    out, status, _ = run()
    g1 = math.sqrt(LAM6 * 1.6 / 1.3)
    assert out["transfer_stage1_low"] == pytest.approx(0.239363, abs=1e-6)
    assert out["transfer_stage1_high"] == pytest.approx(6.427303, abs=1e-6)
    assert out["gamma1"] == pytest.approx(g1, rel=1e-15)
    for m in range(1, 5):  # four passages of the node
        node = 2 * math.pi * m
        below = sl.stage1(node - 1e-7, LAM6, 1.6, 1.3, TOL)[1]
        above = sl.stage1(node + 1e-7, LAM6, 1.6, 1.3, TOL)[1]
        expected = out["transfer_stage1_high"] if m % 2 else out["transfer_stage1_low"]
        assert below == pytest.approx(above, abs=1e-5)  # continuous across the node
        assert below == pytest.approx(expected, abs=1e-5)  # and alternating
        assert sl.stage1_node_value(m, LAM6, g1) == pytest.approx(expected, rel=1e-14)


def test_stage1_path_equals_first_order_continuation():
    """Independent of the alternation rule: track phi3 with a first-order predictor, taking
    at each step the nearer root of both branches."""
    h = 4.1e-3
    phi, phi3 = h / 2, sl.stage1(h / 2, LAM6, 1.6, 1.3, TOL)[0]
    sigma = 1.0
    worst = 0.0
    while phi < 4 * math.pi - h:
        u = fb.transfer_ratio(phi, LAM6, 1.0, 1.6, 1.3, sigma)
        predicted = phi3 + u * h
        phi += h
        roots = {s: fb.loop_closure(phi, LAM6, 1.0, 1.6, 1.3, s)[1] for s in (1.0, -1.0)}
        near = {s: r + 2 * math.pi * round((predicted - r) / (2 * math.pi)) for s, r in roots.items()}
        sigma = min(near, key=lambda s: abs(near[s] - predicted))
        phi3 = near[sigma]
        worst = max(worst, abs(phi3 - sl.stage1(phi, LAM6, 1.6, 1.3, TOL)[0]))
    assert worst < 1e-12


@pytest.mark.parametrize("phi1", [0.9, 2.5, 4.0, 5.0, 6.6, 8.0, 10.5, 12.0])
@pytest.mark.parametrize("beta", [0.0, 0.7])
def test_O11_composition_matches_finite_differences_of_phi5(phi1, beta):
    h = 1e-5
    f = [phi5(phi1 + k * h, beta) for k in (-1, 0, 1)]
    fd1 = (f[2] - f[0]) / (2 * h)
    fd2 = (f[2] - 2 * f[1] + f[0]) / h**2
    phi3, u31, du31 = sl.stage1(phi1, LAM6, 1.6, 1.3, TOL)
    *_, u53, _, du53 = fb.vector_kinematics(phi3 - beta, MU6, 1.0, 1.5, 2.5, 1.0, TOL)
    u51 = u31 * u53
    du51 = du31 * u53 + u31**2 * du53
    assert u51 == pytest.approx(fd1, abs=1e-6)
    assert du51 == pytest.approx(fd2, rel=1e-4, abs=1e-4)


def test_O12_equal_impacts_at_zero_phase():
    out, status, _ = run()
    assert status == sl.S.ok
    assert out["transfer_stage1_impact_1"] == pytest.approx(out["transfer_stage1_impact_2"],
                                                            abs=1e-8)
    assert out["transfer_stage1_impact_1"] == pytest.approx(1.538462, abs=1e-6)
    assert out["transfer_impact_1"] == pytest.approx(out["transfer_impact_2"], abs=1e-8)
    # mirror symmetry: the impacts sit symmetrically about the node at 2 pi
    a1, a2 = out["impact_crank_angle_1"], out["impact_crank_angle_2"]
    assert a1 + a2 == pytest.approx(4 * math.pi, abs=1e-9)


def test_H14_impacts_alternate_when_the_stages_are_out_of_phase():
    out, _, _ = run(beta=0.7)
    pair = sorted((out["transfer_stage1_impact_1"], out["transfer_stage1_impact_2"]))
    assert pair == pytest.approx([1.0739, 2.4706], abs=1e-4)
    assert out["impact_speed_1"] != pytest.approx(out["impact_speed_2"], rel=0.1)
    # only beta - delta matters
    same, _, _ = run(beta=1.0, delta=0.3)
    assert same["transfer_impact_1"] == pytest.approx(out["transfer_impact_1"], rel=1e-9)


def test_impact_values_are_the_composed_one_sided_limits():
    out, _, _ = run(beta=0.7)
    for j in (1, 2):
        phi = out[f"impact_crank_angle_{j}"]
        before = (phi5(phi - 2e-6, 0.7) - phi5(phi - 1e-6, 0.7)) / -1e-6  # one-sided slope
        assert out[f"transfer_impact_{j}"] == pytest.approx(before, rel=1e-4)
        assert out[f"impact_speed_{j}"] == pytest.approx(
            abs(out[f"transfer_impact_{j}"]) * 30.0 * 2.5 * 1.3 * 0.1, rel=1e-14)


def test_H6_stage2_uses_the_impact_branch_for_the_rotation_direction():
    out, _, _ = run()
    assert out["assembly_branch_stage2"] == 1.0  # not [SIX]'s sigma = -1 (clockwise only)
    assert -1 < out["restitution_kinematic"] < 0
    assert out["restitution_kinematic"] == pytest.approx(-0.046, abs=5e-4)
    back, _, _ = run(direction=-1)
    assert back["assembly_branch_stage2"] == -1.0
    # the paper's branch with counter-clockwise rotation would give |Rk| > 1
    g2 = math.sqrt(MU6 * 1.5 / 2.5)
    from kernels.crank_rocker import branch_values
    b, a = branch_values(fb.CHANGE_POINT_B, MU6, g2, -1.0, 1.0)
    assert abs(a / b) > 1


@pytest.mark.parametrize("beta", [0.0, 0.7])
def test_peaks_include_the_impacts_and_are_refined_to_the_exact_maximum(beta):
    """The sample only finds each maximum's basin; golden section on the exact kinematics
    refines it, so 360 samples give the peaks of 11520 to 1e-10 (without the refinement
    they differed by 1e-3 and 2e-2), and an independent search on finite differences of
    phi5 (dense sample, then scipy's bounded Brent) agrees to its own accuracy."""
    from scipy.optimize import minimize_scalar
    coarse, _, _ = run(samples=360, beta=beta)
    fine, _, _ = run(samples=11520, beta=beta)
    assert fine["transfer_peak"] >= abs(fine["transfer_impact_1"])
    assert fine["transfer_peak"] == pytest.approx(coarse["transfer_peak"], rel=1e-10)
    assert fine["transfer2_peak"] == pytest.approx(coarse["transfer2_peak"], rel=1e-10)
    h = 1e-4
    impacts = [coarse["impact_crank_angle_1"], coarse["impact_crank_angle_2"]]

    def second(phi):
        if min(abs((phi - a + 2 * math.pi) % (4 * math.pi) - 2 * math.pi)
               for a in impacts) < 3 * h:
            return 0.0  # the stencil would straddle the velocity reversal at an impact
        f = [phi5(phi + k * h, beta) for k in (-1, 0, 1)]
        return abs(f[2] - 2 * f[1] + f[0]) / h**2
    grid = 4 * math.pi * (np.arange(4000) + 0.5) / 4000
    values = [second(phi) for phi in grid]
    j = int(np.argmax(values))
    found = minimize_scalar(lambda phi: -second(phi), bounds=(grid[j - 1], grid[j + 1]),
                            method="bounded", options={"xatol": 1e-10})
    assert coarse["transfer2_peak"] == pytest.approx(-found.fun, rel=1e-6)  # FD: h^2


def test_rocker_profile_reverses_at_the_tool_twice_per_cycle():
    out, _, prof = run(profile_points=2000, beta=0.7)
    assert np.all(np.isfinite(prof)) and abs(prof.min() - math.pi) < 0.02
    direction = np.sign(np.diff(prof))
    assert np.count_nonzero(np.diff(direction) > 0) == 2  # two reversals at the tool (minima)


@pytest.mark.parametrize("bad", [dict(lambda3=1.7),  # l3 > l2: not a drag link
                                 dict(lambda3=0.9),  # l3 < l1
                                 dict(lambda2=2.5),  # l2 - l3 > l1: lambda6 < 0
                                 dict(mu4=0.8),  # l4 < l3
                                 dict(mu4=2.6)])  # l4 > l5
def test_link_length_conditions_violated_give_a_status(bad):
    out, status, _ = run(**bad)
    assert status == sl.S.not_assemblable and math.isnan(out["transfer_impact_1"])


def test_kernel_peaks_equal_finite_differences_of_phi5():
    n = 5760
    out, _, _ = run(samples=n, beta=0.7)
    impacts = [out["impact_crank_angle_1"], out["impact_crank_angle_2"]]
    h = 1e-5
    first, second = [], []
    for j in range(n):
        phi = 4 * math.pi * (j + 0.5) / n
        if min(abs(phi - a) for a in impacts) < 3 * h:
            continue  # the stencil would straddle the velocity reversal at the impact
        f = [phi5(phi + k * h, 0.7) for k in (-1, 0, 1)]
        first.append(abs(f[2] - f[0]) / (2 * h))
        second.append(abs(f[2] - 2 * f[1] + f[0]) / h**2)
    assert out["transfer2_peak"] == pytest.approx(max(second), rel=1e-4)
    assert out["transfer_peak"] >= max(first) * (1 - 1e-6)
