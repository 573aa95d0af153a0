"""Crank-rocker impact four-bars ([CR]): oracles O1-O5 and hard cases H1, H6-H10 of
docs/models.md §7.1, the corrected Tables 1-2, and the audit of the printed tables."""

import math
from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from kernels import fourbar as fb
from tests.conftest import GAMMA03, crank_rocker_point

G2 = Fraction(169, 49)  # gamma^2 at R = 0.3, exactly


def exact_rod(lam2):
    """Eq. (10) in exact rational arithmetic: (lambda0, lambda3, |u31(2 pi)|) of type a."""
    l2 = Fraction(lam2)
    lam0 = G2 * (l2 + 1) / (G2 + l2)
    lam3 = l2 * (l2 + 1) / (G2 + l2)
    return lam0, lam3, (1 + Fraction(13, 7)) / (lam0 - 1)


def exact_base(lam0):
    """Eq. (11): (lambda2, lambda3, |u31(2 pi)|) of type c."""
    l0 = Fraction(lam0)
    lam2 = G2 * (l0 + 1) / (G2 + l0)
    lam3 = l0 * (l0 + 1) / (G2 + l0)
    return lam2, lam3, (1 + Fraction(13, 7)) / (l0 + 1)


# (given, printed lambda3, printed lambda0, printed |u31(2pi)|) of [CR] Table 1 (type a)
TABLE1 = [(0.75, 0.313, 1.437, 6.532), (1.0, 0.450, 1.551, 5.190), (1.25, 0.599, 1.652, 4.385),
          (1.5, 0.758, 1.742, 3.850), (1.75, 0.926, 1.824, 3.466), (2.0, 1.100, 1.900, 3.176),
          (2.5, 1.472, 2.028, 2.778), (3.0, 1.846, 2.154, 2.488)]
# (given lambda0, printed lambda2, printed lambda3, printed |u31(2pi)|) of Table 2 (type c)
TABLE2 = [(1.75, 1.824, 0.925, 1.039), (2.0, 1.899, 1.101, 0.952), (2.25, 1.967, 1.283, 0.879),
          (2.5, 2.029, 1.471, 0.816), (2.75, 2.086, 1.664, 0.762), (3.0, 2.147, 1.868, 0.714),
          (3.25, 2.188, 2.062, 0.672), (3.5, 2.234, 2.267, 0.635)]
WRONG_CELLS = {("T1", 3.0, "lambda3"), ("T1", 3.0, "lambda0"), ("T1", 3.0, "u31"),
               ("T2", 3.0, "lambda2"), ("T2", 3.0, "lambda3")}
INFEASIBLE = {("T1", x) for x in (0.75, 1.0, 1.25, 1.5, 1.75)} | {("T2", 1.75)}


def one_sided_limits(out, omega1):
    """Numeric one-sided limits of the stable u31 at the node on the kernel's branch
    (Richardson extrapolation of first-order one-sided values, h = 1e-6)."""
    lam0, lam2, lam3 = out["lambda0"], out["lambda2"], out["lambda3"]
    sigma, phi_star = out["assembly_branch"], out["special_crank_angle"]
    u = lambda phi: fb.transfer_ratio(phi, lam0, 1.0, lam2, lam3, sigma)
    h = 1e-6
    minus = 2 * u(phi_star - h) - u(phi_star - 2 * h)
    plus = 2 * u(phi_star + h) - u(phi_star + 2 * h)
    return (minus, plus) if omega1 > 0 else (plus, minus)  # (before, after)


def hessian_roots(lam0, lam2, lam3, phi1, phi3):
    """Slopes of the two smooth curves through the node (docs/models.md §1.5), l1 = 1."""
    c13 = math.cos(phi1 - phi3)
    f11 = 2 * lam0 * math.cos(phi1) + 2 * lam3 * c13
    f13 = -2 * lam3 * c13
    f33 = -2 * lam0 * lam3 * math.cos(phi3) + 2 * lam3 * c13
    disc = math.sqrt(f13 * f13 - f11 * f33)
    return sorted(((-f13 - disc) / f33, (-f13 + disc) / f33))


CASES = [dict(type="a", largest_link=2.5), dict(type="c", largest_link=2.5),
         dict(type="b", largest_link=14.0), dict(type="b", largest_link=14.0, base_root="larger"),
         dict(type="general", lambda0=2.0, lambda2=4.0, lambda3=3.0),
         dict(type="general", lambda0=2.0, lambda2=3.0, lambda3=4.0),
         dict(type="general", lambda0=4.0, lambda2=3.0, lambda3=2.0)]


@pytest.mark.parametrize("case", CASES)
@pytest.mark.parametrize("omega1", [30.0, -12.0])
def test_O1_branch_values_equal_hessian_roots_and_one_sided_limits(case, omega1):
    out, status = crank_rocker_point(omega1=omega1, **case)
    assert status == "ok"
    mask = fb.change_point_identities(out["lambda0"], out["lambda2"], out["lambda3"], 1e-9)
    phi3_star = 0.0 if mask & fb.CHANGE_POINT_A else math.pi  # a: (0, 0); b: (0, pi); c: (pi, pi)
    roots = hessian_roots(out["lambda0"], out["lambda2"], out["lambda3"],
                          out["special_crank_angle"], phi3_star)
    closed = sorted((out["transfer_before"], out["transfer_after"]))
    assert closed == pytest.approx(roots, rel=1e-12)
    before, after = one_sided_limits(out, omega1)
    assert out["transfer_before"] == pytest.approx(before, rel=1e-7)
    assert out["transfer_after"] == pytest.approx(after, rel=1e-7)
    assert abs(out["transfer_before"]) > abs(out["transfer_after"])  # |Rk| < 1: an impact


@pytest.mark.parametrize("lams, rk", [((2.0, 4.0, 3.0), -0.240408), ((2.0, 3.0, 4.0), -0.101021),
                                      ((4.0, 3.0, 2.0), -0.420204)])
def test_O2_fig2_restitution(lams, rk):
    out, status = crank_rocker_point(type="general", lambda0=lams[0], lambda2=lams[1],
                                     lambda3=lams[2])
    assert status == "ok"
    assert out["restitution_kinematic"] == pytest.approx(rk, abs=5e-7)
    before, after = one_sided_limits(out, 30.0)
    assert after / before == pytest.approx(out["restitution_kinematic"], abs=1e-7)


@settings(max_examples=200, deadline=None)
@given(st.floats(0.01, 0.6), st.floats(1.001, 40.0), st.sampled_from(["a", "c"]))
def test_O3_property_synthesis_round_trip_types_a_c(r, scale, kind):
    gamma = (1 + r) / (1 - r)
    out, status = crank_rocker_point(type=kind, R=r, largest_link=gamma * scale)
    assert status in ("ok", "second_special_position")
    assert -out["restitution_kinematic"] == pytest.approx(r, abs=1e-12)
    lam0, lam2, lam3 = out["lambda0"], out["lambda2"], out["lambda3"]
    identity = (lam0 + lam3 - 1 - lam2) if kind == "a" else (lam0 + 1 - lam2 - lam3)
    assert abs(identity) <= 1e-12 * (1 + lam0 + lam2 + lam3)


@settings(max_examples=200, deadline=None)
@given(st.floats(0.01, 0.5), st.floats(1.0001, 30.0), st.sampled_from(["smaller", "larger"]))
def test_O3_property_synthesis_round_trip_type_b(r, scale, root):
    gamma = (1 + r) / (1 - r)
    lam3_min = (gamma + math.sqrt(gamma**2 - 1)) ** 2
    out, status = crank_rocker_point(type="b", R=r, largest_link=lam3_min * scale,
                                     base_root=root)
    assert status in ("ok", "not_assemblable")
    assert -out["restitution_kinematic"] == pytest.approx(r, abs=1e-12) or status != "ok"
    lam0, lam2, lam3 = out["lambda0"], out["lambda2"], out["lambda3"]
    assert abs(lam0 + lam2 - 1 - lam3) <= 1e-12 * (1 + lam0 + lam2 + lam3)
    assert math.sqrt(lam0 * lam2 / lam3) == pytest.approx(gamma, rel=1e-12)
    # the other way round: type b given lambda0 gives back lambda3
    back, st_back = crank_rocker_point(type="b", R=r, lambda0=lam0)
    if lam0 > gamma**2 * (1 + 1e-9):
        assert back["lambda3"] == pytest.approx(lam3, rel=1e-9)


def test_O4_corrected_table1_and_table2_exact():
    for lam2, *_ in TABLE1:
        out, status = crank_rocker_point(type="a", largest_link=lam2)
        lam0, lam3, u = exact_rod(lam2)
        assert out["lambda0"] == pytest.approx(float(lam0), rel=1e-12)
        assert out["lambda3"] == pytest.approx(float(lam3), rel=1e-12)
        if status == "ok":
            assert out["impact_transfer_ratio"] == pytest.approx(float(u), rel=1e-12)
    for lam0, *_ in TABLE2:
        out, status = crank_rocker_point(type="c", largest_link=lam0)
        lam2, lam3, u = exact_base(lam0)
        assert out["lambda2"] == pytest.approx(float(lam2), rel=1e-12)
        assert out["lambda3"] == pytest.approx(float(lam3), rel=1e-12)
        if status == "ok":
            assert out["impact_transfer_ratio"] == pytest.approx(float(u), rel=1e-12)
    # the spec's quoted reference (O4): T1 lambda2 = 2.5
    out, _ = crank_rocker_point(type="a", largest_link=2.5)
    assert (out["lambda3"], out["lambda0"], out["impact_transfer_ratio"]) == pytest.approx(
        (1.470840, 2.029160, 2.776190), rel=1e-6)


def test_O4_impact_ratio_matches_a_one_sided_difference_of_the_loop_closure():
    # independent of the closed form: slope of phi3(phi1) just before the node
    for lam2 in (2.0, 2.5, 3.0):
        out, _ = crank_rocker_point(type="a", largest_link=lam2)
        lam0, lam3 = out["lambda0"], out["lambda3"]
        h = 1e-7
        phi3 = [fb.loop_closure(-k * h, lam0, 1.0, lam2, lam3, -1.0)[1] for k in (1, 2, 3)]
        slope = (-3 * phi3[0] + 4 * phi3[1] - phi3[2]) / (-2 * h)  # second-order one-sided
        assert abs(slope) == pytest.approx(out["impact_transfer_ratio"], rel=1e-6)


def test_paper_tables_audit_exactly_five_printed_cells_are_wrong():
    """[CR]'s printed tables vs the exact values (3e-3 abs): the five cells of the two
    lambda = 3.0 columns are wrong, the rest are right to the printed digits; the six
    columns with largest link < gamma are not crank-rockers at all."""
    wrong = set()
    infeasible = set()
    for lam2, p3, p0, pu in TABLE1:
        lam0, lam3, u = exact_rod(lam2)
        for name, printed, exact in (("lambda3", p3, lam3), ("lambda0", p0, lam0), ("u31", pu, u)):
            if abs(printed - float(exact)) > 3e-3:
                wrong.add(("T1", lam2, name))
        if crank_rocker_point(type="a", largest_link=lam2)[1] == "not_assemblable":
            infeasible.add(("T1", lam2))
    for lam0, p2, p3, pu in TABLE2:
        lam2, lam3, u = exact_base(lam0)
        for name, printed, exact in (("lambda2", p2, lam2), ("lambda3", p3, lam3), ("u31", pu, u)):
            if abs(printed - float(exact)) > 3e-3:
                wrong.add(("T2", lam0, name))
        if crank_rocker_point(type="c", largest_link=lam0)[1] == "not_assemblable":
            infeasible.add(("T2", lam0))
    assert wrong == WRONG_CELLS
    assert infeasible == INFEASIBLE


def test_paper_table1_lambda2_3_column_was_computed_with_gamma2_3_5():
    g2 = 3.5
    lam3 = 3.0 * 4.0 / (g2 + 3.0)
    lam0 = g2 * 4.0 / (g2 + 3.0)
    u = (1 + math.sqrt(g2)) / (lam0 - 1)
    assert (lam3, lam0, u) == pytest.approx((1.846, 2.154, 2.488), abs=6e-4)
    # Table 2, lambda0 = 3: lambda3 follows from eq. (8) with the slipped lambda2 = 2.147
    assert 3.0 * 2.147 / float(G2) == pytest.approx(1.868, abs=5e-4)


def test_O5_feasibility_boundaries():
    eps = 1e-6
    for kind in ("a", "c"):
        assert crank_rocker_point(type=kind, largest_link=GAMMA03 * (1 - eps))[1] \
            == "not_assemblable"
        assert crank_rocker_point(type=kind, largest_link=GAMMA03 * (1 + eps))[1] == "ok"
    lam3_min = (GAMMA03 + math.sqrt(GAMMA03**2 - 1)) ** 2
    assert lam3_min == pytest.approx(11.710525, abs=1e-6)
    assert crank_rocker_point(type="b", largest_link=lam3_min * (1 - eps))[1] \
        == "no_real_synthesis"
    assert crank_rocker_point(type="b", largest_link=lam3_min * (1 + eps))[1] == "ok"


def test_frequency_claim_ratio_of_type_a_to_type_c_impact_ratios():
    """[CR] claims 4-5x; at equal largest link L it is (1+L)(g^2+L)/(L(g^2-1))."""
    expected = {2.0: 3.34, 2.5: 3.40, 3.0: 3.51, 4: 3.80, 5: 4.14, 6: 4.50, 7: 4.88, 8: 5.26}
    for big, ratio in expected.items():
        a = crank_rocker_point(type="a", largest_link=big)[0]["impact_transfer_ratio"]
        c = crank_rocker_point(type="c", largest_link=big)[0]["impact_transfer_ratio"]
        assert a / c == pytest.approx(ratio, abs=0.006)


def test_H1_kernel_gives_one_sided_values_where_u31_is_0_over_0():
    out, status = crank_rocker_point(type="a", largest_link=2.0)
    assert status == "ok"
    assert math.isnan(fb.transfer_ratio(0.0, out["lambda0"], 1.0, 2.0, out["lambda3"], -1.0))
    assert out["transfer_before"] == pytest.approx((1 + GAMMA03) / (1 - out["lambda0"]),
                                                   rel=1e-14)


def test_H6_wrong_assembly_mode_is_flagged_with_its_true_rk():
    curve2 = dict(type="general", lambda0=2.0, lambda2=3.0, lambda3=4.0)
    out, status = crank_rocker_point(sigma=-1, omega1=30.0, raw=True, **curve2)
    assert status == "wrong_branch"
    g = math.sqrt(2.0 * 3.0 / 4.0)
    assert out["restitution_kinematic"] == pytest.approx((1 + g) / (1 - g), rel=1e-12)
    assert out["restitution_kinematic"] == pytest.approx(-9.899, abs=1e-3)
    assert crank_rocker_point(sigma="impact", omega1=30.0, **curve2)[0]["assembly_branch"] == 1
    assert crank_rocker_point(sigma="impact", omega1=-30.0, **curve2)[0]["assembly_branch"] == -1
    assert crank_rocker_point(type="a", largest_link=2.5, sigma=-1, omega1=30.0)[1] == "ok"
    assert crank_rocker_point(type="a", largest_link=2.5, sigma=1, omega1=30.0)[1] \
        == "wrong_branch"


def test_H7_infeasible_table_columns_have_no_motion_outputs():
    out, status = crank_rocker_point(type="a", largest_link=1.75)
    assert status == "not_assemblable"
    assert out["crank_turns_fully"] == 0.0
    assert math.isnan(out["restitution_kinematic"]) and math.isnan(out["impact_speed"])
    assert out["lambda0"] == pytest.approx(float(exact_rod(1.75)[0]), rel=1e-12)


def test_H8_type_b_without_real_synthesis_reports_the_reachable_limit():
    out, status = crank_rocker_point(type="b", largest_link=4.0)
    assert status == "no_real_synthesis"
    assert math.isnan(out["lambda0"]) and math.isnan(out["restitution_kinematic"])
    g_max = 5.0 / 4.0  # (1 + lambda3)/(2 sqrt(lambda3))
    assert out["restitution_kinematic_max"] == pytest.approx((g_max - 1) / (g_max + 1),
                                                             rel=1e-14)
    assert out["restitution_kinematic_max"] > 0.101021  # Fig. 2 curve 2 is reachable


def test_H9_b_on_d_at_the_node_is_degenerate():
    out, status = crank_rocker_point(type="general", lambda0=1.0, lambda2=2.0, lambda3=2.0)
    assert status == "degenerate"
    assert math.isnan(out["transfer_before"])


def test_H10_double_change_point_is_detected():
    out, status = crank_rocker_point(type="a", largest_link=13 / 7)  # lambda2 = gamma
    assert status == "second_special_position"
    assert out["special_position_count"] == 2
    out, status = crank_rocker_point(type="a", largest_link=13 / 7 * 1.01)
    assert status == "ok" and out["special_position_count"] == 1


def test_general_four_bar_without_change_point_and_double_crank():
    out, status = crank_rocker_point(type="general", lambda0=3.0, lambda2=3.6, lambda3=2.2,
                                     raw=True)  # not an impact linkage: no design values
    assert status == "no_special_position"
    assert out["crank_turns_fully"] == 1.0 and out["transmission_angle_working"] > 0.3
    out, status = crank_rocker_point(type="general", lambda0=0.7, lambda2=1.6, lambda3=1.3,
                                     raw=True)  # the kernel's value; no design value
    assert status == "no_impact"  # [SIX] stage 1: gamma < 1, link 3 keeps turning
    assert 0 < out["restitution_kinematic"] < 1


def test_transmission_angles_match_sampled_loop_closure():
    out, status = crank_rocker_point(type="a", largest_link=3.0)
    lam0, lam2, lam3 = out["lambda0"], out["lambda2"], out["lambda3"]
    phi2, phi3 = fb.loop_closure(math.pi, lam0, 1.0, lam2, lam3, -1.0)
    mu = abs((phi3 - phi2 + math.pi) % (2 * math.pi) - math.pi)
    assert out["transmission_angle_opposite"] == pytest.approx(min(mu, math.pi - mu), abs=1e-12)
    assert out["impact_speed"] == pytest.approx(
        out["impact_transfer_ratio"] * 30.0 * lam3 * 0.1, rel=1e-15)


@pytest.mark.parametrize("design", [dict(type="a", largest_link=3.0),
                                    dict(type="b", R=0.2, largest_link=12.0),
                                    dict(type="c", R=0.35, largest_link=4.0),
                                    dict(type="a", R=0.1, largest_link=25.0)])
@pytest.mark.parametrize("window_deg", [10.0, 30.0, 60.0])
def test_working_transmission_angle_is_the_sampled_minimum_outside_the_window(design,
                                                                               window_deg):
    """The smallest transmission angle over 20001 loop closures on the working stroke
    (the crank turn outside the window around the node, its edges sampled) is the
    kernel's; at the node itself it is 0 (all links collinear)."""
    from tests.conftest import kernel_point

    window = math.radians(window_deg)
    out, status, _ = kernel_point("crank_rocker", {"working_window": window}, **design)
    assert status == "ok"
    lam0, lam2, lam3 = out["lambda0"], out["lambda2"], out["lambda3"]
    node, sigma = out["special_crank_angle"], out["assembly_branch"]
    sampled = math.inf
    for phi in node + np.linspace(window, 2 * math.pi - window, 20001):
        phi2, phi3 = fb.loop_closure(phi, lam0, 1.0, lam2, lam3, sigma)
        mu = abs((phi3 - phi2 + math.pi) % (2 * math.pi) - math.pi)
        sampled = min(sampled, mu, math.pi - mu)
    assert out["transmission_angle_working"] == pytest.approx(sampled, abs=1e-12)
    assert 0 < out["transmission_angle_working"] <= out["transmission_angle_opposite"]
    phi2, phi3 = fb.loop_closure(node, lam0, 1.0, lam2, lam3, sigma)
    assert abs(math.sin(phi3 - phi2)) < 1e-6  # the window is what keeps the 0 out


def test_kernel_writes_status_for_every_point_of_a_block():
    from tests.conftest import kernel_points
    nan = math.nan
    out, status, _ = kernel_points("crank_rocker", type=["a", "b", "general"],
                                   largest_link=[2.5, 4.0, nan], lambda0=[nan, nan, 1.0],
                                   lambda2=[nan, nan, 2.0], lambda3=[nan, nan, 2.0])
    assert status == ["ok", "no_real_synthesis", "degenerate"]
