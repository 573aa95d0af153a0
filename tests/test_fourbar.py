"""Loop closure and transfer functions against independent methods (docs/models.md §7.1)."""

import math

import mpmath
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import fsolve

from kernels import fourbar as fb
from kernels.crank_rocker import synthesize_largest_rod

T1_L2_25 = (2.029159519725557, 1.0, 2.5, 1.470840480274443)  # (l0, l1, l2, l3), type a
GEOMETRIES = [
    T1_L2_25,
    (2.5, 1.0, 2.029159519725557, 1.470840480274443),  # T2 lambda0 = 2.5, type c
    (2.0, 1.0, 3.0, 4.0),  # Fig. 2 curve 2, type b
    (3.0, 1.0, 1.2 * 3, 2.2),  # a generic crank-rocker (scaled)
]


def residual(phi1, phi2, phi3, l0, l1, l2, l3):
    z = (l1 * np.exp(1j * phi1) + l2 * np.exp(1j * phi2) - l3 * np.exp(1j * phi3) - l0)
    return abs(z)


def wrap(a):
    return (a + math.pi) % (2 * math.pi) - math.pi


@pytest.mark.parametrize("geom", GEOMETRIES)
@pytest.mark.parametrize("sigma", [1.0, -1.0])
def test_O6_loop_residual_and_O7_positions_match_newton(geom, sigma):
    l0, l1, l2, l3 = geom
    for phi1 in np.linspace(0.05, 2 * math.pi - 0.05, 36):
        phi2, phi3 = fb.loop_closure(phi1, l0, l1, l2, l3, sigma)
        assert residual(phi1, phi2, phi3, *geom) <= 1e-13 * sum(geom)  # O6
    # O7 away from the nodes at 0 and pi: there the Jacobian is singular (H12) and a start
    # 0.05 rad off may converge to the other branch
    for phi1 in (0.4, 1.0, 1.6, 2.2, 2.7, 3.6, 4.4, 5.2, 5.9):
        phi2, phi3 = fb.loop_closure(phi1, l0, l1, l2, l3, sigma)

        def eqs(x):
            return [l1 * math.cos(phi1) + l2 * math.cos(x[0]) - l3 * math.cos(x[1]) - l0,
                    l1 * math.sin(phi1) + l2 * math.sin(x[0]) - l3 * math.sin(x[1])]

        def jac(x):
            return [[-l2 * math.sin(x[0]), l3 * math.sin(x[1])],
                    [l2 * math.cos(x[0]), -l3 * math.cos(x[1])]]

        ref = fsolve(eqs, [phi2 + 0.05, phi3 - 0.05], fprime=jac, xtol=1e-12)
        assert abs(wrap(ref[0] - phi2)) < 1e-10 and abs(wrap(ref[1] - phi3)) < 1e-10  # O7


@pytest.mark.parametrize("geom", GEOMETRIES)
@pytest.mark.parametrize("sigma", [1.0, -1.0])
def test_O8_transfer_functions_match_finite_differences(geom, sigma):
    h = 1e-5
    for phi1 in np.linspace(0.2, 2 * math.pi - 0.2, 23):
        if min(abs(phi1 - math.pi), phi1, 2 * math.pi - phi1) < 0.1:
            continue  # O8 is stated away from special positions (|dphi1| > 0.1)
        f = [fb.loop_closure(phi1 + k * h, *geom, sigma)[1] for k in (-1, 0, 1)]
        u_fd = wrap(f[2] - f[0]) / (2 * h)
        du_fd = (wrap(f[2] - f[1]) - wrap(f[1] - f[0])) / h**2
        _, _, u21, u31, du21, du31 = fb.transfer_functions(phi1, *geom, sigma)
        assert abs(u31 - u_fd) < 1e-8 * max(1.0, abs(u31))
        assert abs(du31 - du_fd) < 1e-4 * max(1.0, abs(du31))
        g = [fb.loop_closure(phi1 + k * h, *geom, sigma)[0] for k in (-1, 1)]
        assert abs(u21 - wrap(g[1] - g[0]) / (2 * h)) < 1e-8 * max(1.0, abs(u21))


def test_O8_stable_u31_equals_angle_formula():
    l0, l1, l2, l3 = T1_L2_25
    for sigma in (1.0, -1.0):
        for phi1 in np.linspace(0.3, 6.0, 50):
            phi2, phi3 = fb.loop_closure(phi1, l0, l1, l2, l3, sigma)
            angle_form = l1 * math.sin(phi1 - phi2) / (l3 * math.sin(phi3 - phi2))
            assert abs(fb.transfer_ratio(phi1, l0, l1, l2, l3, sigma) - angle_form) \
                < 1e-12 * max(1, abs(angle_form))


def test_O9_cycle_integral_of_u31():
    # crank-rocker on a fixed branch: the rocker comes back, integral 0
    l0, l1, l2, l3 = T1_L2_25
    phi = np.linspace(1e-9, 2 * math.pi - 1e-9, 4001)
    u = np.array([fb.transfer_ratio(p, l0, l1, l2, l3, -1.0) for p in phi])
    assert abs(np.trapezoid(u, phi)) < 1e-6
    l0g, l1g, l2g, l3g = 3.0, 1.0, 3.6, 2.2  # generic crank-rocker: smooth, no node
    u = np.array([fb.transfer_ratio(p, l0g, l1g, l2g, l3g, 1.0) for p in phi])
    assert abs(np.trapezoid(u, phi)) < 1e-6
    # double crank ([SIX] stage 1): link 3 turns once per crank turn, integral 2 pi
    phi = np.linspace(0.0, 2 * math.pi, 20001)[1:-1]
    u = np.array([fb.transfer_ratio(p, 0.7, 1.0, 1.6, 1.3, -1.0) for p in phi])
    assert abs(np.trapezoid(u, phi) - 2 * math.pi) < 1e-3 * 2 * math.pi * 3


def _naive_u31(phi1, lam0, lam2, lam3, sigma):
    """The papers' route: arccos positions, then the angle-ratio u31 (hard case H2)."""
    d = math.sqrt(1 + lam0**2 - 2 * lam0 * math.cos(phi1))
    theta_db = math.atan2(math.sin(phi1), math.cos(phi1) - lam0)
    psi = math.acos(max(-1.0, min(1.0, (lam3**2 + d**2 - lam2**2) / (2 * lam3 * d))))
    phi3 = theta_db + sigma * psi
    phi2 = math.atan2(lam3 * math.sin(phi3) - math.sin(phi1),
                      lam0 + lam3 * math.cos(phi3) - math.cos(phi1))
    return math.sin(phi1 - phi2) / (lam3 * math.sin(phi3 - phi2))


def _u31_mp(phi1, lam0, lam2, lam3, sigma):
    """The closed form of docs/models.md §1.4 in 60-digit arithmetic with exact (rational)
    link ratios."""
    with mpmath.workdps(60):
        p = mpmath.mpf(phi1)
        l0, l2, l3 = (mpmath.mpf(x) for x in (lam0, lam2, lam3))
        d2 = 1 + l0**2 - 2 * l0 * mpmath.cos(p)
        P = (l2 + l3)**2 - d2
        Q = d2 - (l2 - l3)**2
        return float((1 - l0 * mpmath.cos(p)) / d2
                     - sigma * l0 * mpmath.sin(p) * (d2 + l2**2 - l3**2)
                     / (d2 * mpmath.sqrt(P * Q)))


def test_H2_stable_form_keeps_its_digits_where_arccos_loses_them():
    # T1 lambda2 = 2 (type a), with link ratios exact in binary so that mpmath sees the
    # same mechanism: lambda0 = 1.898876..., lambda3 = 1.101123...
    lam0, lam3 = synthesize_largest_rod(2.0, 0.3)
    lam2 = lam0 + lam3 - 1.0  # the identity, in the rounded numbers the kernel sees
    naive_err, stable_err = {}, {}
    for dphi in (1e-4, 1e-6, 1e-7, 1e-8):
        ref = _u31_mp(-dphi, lam0, lam2, lam3, -1.0)
        stable = fb.transfer_ratio(-dphi, lam0, 1.0, lam2, lam3, -1.0)
        stable_err[dphi] = abs(stable - ref) / abs(ref)
        naive_err[dphi] = abs(_naive_u31(-dphi, lam0, lam2, lam3, -1.0) - ref) / abs(ref)
    assert max(stable_err.values()) <= 3e-8, stable_err
    assert naive_err[1e-6] > 1e-5 and naive_err[1e-7] > 1e-4, naive_err  # method fails


def test_H1_transfer_ratio_is_nan_exactly_at_the_node_and_finite_beside_it():
    lam0, lam3 = synthesize_largest_rod(2.0, 0.3)
    assert math.isnan(fb.transfer_ratio(0.0, lam0, 1.0, 2.0, lam3, -1.0))
    assert math.isfinite(fb.transfer_ratio(1e-9, lam0, 1.0, 2.0, lam3, -1.0))


def test_H3_H4_node_of_the_double_crank_is_exact_at_phi1_zero():
    # [SIX] formula (1) gives ~2.6e-8 (sgn(0)) or NaN (arccos(1+eps)); the truth is pi
    for sigma in (1.0, -1.0):
        phi2, phi3 = fb.loop_closure(0.0, 0.7, 1.0, 1.6, 1.3, sigma)
        assert abs(wrap(phi3 - math.pi)) < 1e-15
        assert residual(0.0, phi2, phi3, 0.7, 1.0, 1.6, 1.3) < 1e-14


def test_H9_rocker_angle_is_undefined_when_b_is_on_d():
    assert math.isnan(fb.loop_closure(0.0, 1.0, 1.0, 2.0, 2.0, 1.0)[1])
    assert not math.isnan(fb.loop_closure(1e-3, 1.0, 1.0, 2.0, 2.0, 1.0)[1])


def test_H7_table1_lambda2_075_closes_only_for_small_crank_angles():
    lam0, lam3 = synthesize_largest_rod(0.75, 0.3)
    closes = lambda phi: not math.isnan(fb.loop_closure(phi, lam0, 1.0, 0.75, lam3, -1.0)[1])
    lo, hi = 0.5, 1.5  # bisection on the edge of the closing range
    assert closes(lo) and not closes(hi)
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if closes(mid) else (lo, mid)
    assert math.degrees(lo) == pytest.approx(47.6, abs=0.05)
    assert not fb.crank_turns_fully(lam0, 1.0, 0.75, lam3, 1e-9)


def test_transmission_angle_min_over_a_turn_is_at_a_dead_centre():
    # independent: dense sampling of the loop closure vs the two dead-centre values
    for geom in ((3.0, 1.0, 3.6, 2.2), (4.0, 1.0, 3.0, 3.5), (2.5, 1.2, 2.7, 2.0)):
        phi = np.linspace(0, 2 * math.pi, 20001)
        sampled = []
        for p in phi:
            phi2, phi3 = fb.loop_closure(p, *geom, 1.0)
            mu = abs(wrap(phi3 - phi2))
            sampled.append(min(mu, math.pi - mu))
        closed = min(fb.transmission_angle(0.0, *geom, 1e-9),
                     fb.transmission_angle(math.pi, *geom, 1e-9))
        assert min(sampled) == pytest.approx(closed, abs=1e-7)


lengths = st.floats(0.2, 5.0)


@settings(max_examples=300, deadline=None)
@given(lengths, lengths, lengths, lengths, st.floats(-7.0, 7.0), st.sampled_from([1.0, -1.0]))
def test_property_loop_residual_or_honest_nan(l0, l1, l2, l3, phi1, sigma):
    d2, p, q = fb.dyad_factors(phi1, l0, l1, l2, l3)
    phi2, phi3 = fb.loop_closure(phi1, l0, l1, l2, l3, sigma)
    if d2 <= fb.B_ON_D * (l0 + l1) ** 2:  # B on D: undefined (H9), not an arbitrary number
        assert math.isnan(phi3)
    elif p < 0 or q < 0:
        assert math.isnan(phi2) and math.isnan(phi3)
        # and it truly cannot close: d outside [|l2 - l3|, l2 + l3]
        d = math.sqrt(d2)
        assert d > l2 + l3 - 1e-12 or d < abs(l2 - l3) + 1e-12
    else:
        assert residual(phi1, phi2, phi3, l0, l1, l2, l3) <= 1e-13 * (l0 + l1 + l2 + l3)


def test_kernels_do_not_raise_on_division_by_zero():
    # B on D at phi1 = 0 (l0 = l1): d = 0; numba's python error model would raise here
    assert math.isnan(fb.transfer_ratio(0.0, 1.0, 1.0, 2.0, 2.0, 1.0)) or \
        not math.isfinite(fb.transfer_ratio(0.0, 1.0, 1.0, 2.0, 2.0, 1.0))
    fb.transfer_functions(0.0, 1.0, 1.0, 2.0, 2.0, 1.0)
    from kernels.crank_rocker import branch_values
    assert not math.isfinite(branch_values(fb.CHANGE_POINT_A, 1.0, 1.0, -1.0, 1.0)[0])


@pytest.mark.parametrize("geom", GEOMETRIES)
@pytest.mark.parametrize("sigma", [1.0, -1.0])
def test_vector_kinematics_equals_the_angle_route(geom, sigma):
    for phi1 in np.linspace(-3.0, 3.1, 41):
        c1, s1, c2, s2, c3, s3, u21, u31, du21, du31 = fb.vector_kinematics(phi1, *geom, sigma)
        phi2, phi3, v21, v31, dv21, dv31 = fb.transfer_functions(phi1, *geom, sigma)
        if math.isnan(phi3):
            assert math.isnan(c3)
            continue
        assert abs(c2 - math.cos(phi2)) < 1e-14 and abs(s2 - math.sin(phi2)) < 1e-14
        assert abs(c3 - math.cos(phi3)) < 1e-14 and abs(s3 - math.sin(phi3)) < 1e-14
        for a, b in ((u21, v21), (u31, v31), (du21, dv21), (du31, dv31)):
            assert a == pytest.approx(b, rel=1e-9, abs=1e-12)
        assert residual(phi1, math.atan2(s2, c2), math.atan2(s3, c3), *geom) <= 1e-13 * sum(geom)


def _track(order, turns=4, h=4.1e-3, geom=(0.7, 1.0, 1.6, 1.3)):
    """Continuation of phi3(phi1) through the node of [SIX]'s stage 1: at each step take
    the root (of both branches) nearest a predictor of the given order. Returns the fraction
    of steps on the branch of the explicit alternation rule sigma = s0 (-1)^floor(phi1/2pi)."""
    phi = h / 2
    sigma = -1.0
    phi3 = fb.loop_closure(phi, *geom, sigma)[1]
    agree = total = 0
    while phi < turns * 2 * math.pi:
        u = fb.transfer_ratio(phi, *geom, sigma)
        predicted = phi3 + (u * h if order >= 1 else 0.0)
        phi += h
        roots = {s: fb.loop_closure(phi, *geom, s)[1] for s in (1.0, -1.0)}
        sigma = min(roots, key=lambda s: abs(wrap(roots[s] - predicted)))
        phi3 = roots[sigma]
        rule = -1.0 * (-1.0) ** math.floor(phi / (2 * math.pi))
        agree += sigma == rule
        total += 1
    return agree / total


def test_H5_zeroth_order_tracking_takes_the_wrong_branch_at_the_node():
    assert _track(order=1) == 1.0  # a first-order predictor follows the smooth curve
    assert _track(order=0) < 0.6  # "nearest previous angle" bounces at the node
