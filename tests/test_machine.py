"""The crank-driven impact machine (issue 38): the oracles M-O1 ... M-O15 and hard cases
MH1 ... MH10 of docs/machine.md, each with its stated tolerance, and the steady state
against an independent SciPy model (tests/machine_reference.py) at random designs.
"""

import math

import numpy as np
import pytest

import sweep
from kernels import impact_machine as M
from kernels.machine.cycle import RUNUP_REVOLUTIONS
from kernels.machine.declaration import LAW_GENERALIZED, LAW_KINEMATIC
from kernels.machine.revolution import REV_BLOW, REV_STALL
from kernels.extrema import cell_midpoints
from tests import machine_reference as ref
from tests.machine_probes import (blow_of, data, node_of, parameters, reduced_at,
                                  section_map)

LOADED = dict(load_force_x=3.0, load_force_y=-20.0, load_arm=0.14, load_moment=1.5)
#: docs/machine.md §3, M-O13: the test machine with its rocker load, J_f = 5, linear motor
M_O13 = dict(crank_speed_after_blow=28.505745131703, crank_speed_before_blow=28.647875099107,
             mean_crank_speed=30.092463748, speed_fluctuation=0.08472907,
             blow_rate=287.361861, blow_energy=422.532201, blow_loss=444.273685,
             tool_impulse=15.960254, crank_impulse=-0.711768)


def outputs(method=None, **given):
    """The kernel's outputs by name and the status meaning, for one design."""
    from kernels.status import MEANINGS

    decl = M.DECLARATION
    extra = (method or {}).pop("outputs", ())
    record = decl.method_record(outputs=decl.default_outputs + tuple(extra),
                                **(method or {}))
    out, status, prof = M.run(parameters(**given)[:, None], record)
    named = {o.name: float(out[i, 0]) for i, o in enumerate(decl.outputs)}
    profiles = {o.name: prof[i, 0] for i, o in enumerate(decl.profiles)}
    return named, MEANINGS[int(status[0])], profiles


def random_design(rng, kind=None, coupler="general"):
    """A random synthesised design: type, R, largest link, masses and inertias; the coupler
    general, massless, or lumped at its joints B and C."""
    kind = str(kind or rng.choice(["a", "b", "c"]))
    r = float(rng.uniform(0.05, 0.5))
    gamma = (1 + r) / (1 - r)
    if kind == "b":
        largest = float((gamma + math.sqrt(gamma * gamma - 1)) ** 2 * rng.uniform(1.05, 1.6))
    else:
        largest = float(gamma * rng.uniform(1.1, 3.0))
    d = dict(type=kind, largest_link=largest, R=r, m1=float(rng.uniform(0.5, 4)),
             m2=float(rng.uniform(0.5, 5)), m3=float(rng.uniform(2, 12)),
             s1=float(rng.uniform(0.2, 0.8)), s2=float(rng.uniform(0.2, 0.8)),
             s3=float(rng.uniform(0.2, 0.9)), q1=float(rng.uniform(-0.02, 0.02)),
             q2=float(rng.uniform(-0.03, 0.03)), q3=float(rng.uniform(-0.02, 0.02)),
             J1=float(rng.uniform(0.001, 0.01)), J2=float(rng.uniform(0.005, 0.03)),
             J3=float(rng.uniform(0.01, 0.05)), flywheel_inertia=float(rng.uniform(0.5, 30)),
             tilt=float(rng.uniform(-1, 1)))
    if coupler == "massless":
        d.update(m2=0.0, J2=0.0)
    elif coupler == "lumped":  # a mass at B and one at C: centroid on BC, J2 = m2 p2 (l2 - p2)
        status, m, own = data(parameters(**d))
        l2 = m.linkage.l2
        d.update(q2=0.0, J2=d["m2"] * d["s2"] * (1 - d["s2"]) * l2 * l2)
    return d


# ---------------------------------------------------------------- kinematics and inertia

@pytest.mark.parametrize("kind", ["a", "b", "c"])
def test_M_O1_one_sided_u31_at_both_ends_of_the_cycle_are_the_closed_forms(kind):
    """u31 at phi1* and phi1* + 2 pi from the desingularised form against (1 -+ gamma)/
    (1 - lambda0) (types a, b) or /(1 + lambda0) (c), 1e-13 relative, at random designs."""
    rng = np.random.default_rng(11)
    for _ in range(20):
        d = random_design(rng, kind)
        status, m, own = data(parameters(**d))
        lam0, lam2, lam3 = m.linkage.l0 / m.linkage.l1, m.linkage.l2 / m.linkage.l1, m.linkage.l3 / m.linkage.l1
        gamma = math.sqrt(lam0 * lam2 / lam3)
        start = m.linkage.start
        u31 = reduced_at(parameters(**d), np.array([start, start + 2 * math.pi]))[:, 3]
        den = (1 + lam0) if kind == "c" else (1 - lam0)
        kappa = -1.0 if kind == "b" else 1.0
        s = kappa * m.linkage.sigma * gamma
        assert u31[0] == pytest.approx((1 + s) / den, rel=1e-13)  # after the blow
        assert u31[1] == pytest.approx((1 - s) / den, rel=1e-13)  # before it


def test_M_O2_J_prime_is_the_derivative_of_J():
    rng = np.random.default_rng(12)
    for _ in range(15):
        d = random_design(rng)
        pr = parameters(**d)
        start = data(pr)[1].linkage.start
        phis = start + rng.uniform(0.05, 2 * math.pi - 0.05, 6)
        h = 1e-5
        at = reduced_at(pr, phis)
        fd = (reduced_at(pr, phis + h)[:, 0] - reduced_at(pr, phis - h)[:, 0]) / (2 * h)
        np.testing.assert_allclose(at[:, 1], fd, rtol=1e-8, atol=1e-8 * np.max(at[:, 0]))


def test_M_O3_the_generalised_force_is_minus_the_potentials_slope():
    """Q_g + Q_ext against -dV/dphi1 by central differences of an independent potential
    (numpy loop closure, the load fixed in the base frame), 1e-7 absolute."""
    rng = np.random.default_rng(13)
    for _ in range(10):
        d = random_design(rng, str(rng.choice(["a", "c"])))
        d.update(load_force_x=float(rng.uniform(-30, 30)), load_force_y=float(rng.uniform(-30, 30)),
                 load_arm=float(rng.uniform(0, 0.1)), load_offset=float(rng.uniform(-0.02, 0.02)),
                 load_moment=float(rng.uniform(-3, 3)))
        mc, lam0, gamma = ref.build(d, d["type"], d["largest_link"])
        pr = parameters(**d)
        phis = mc.start + rng.uniform(0.3, 2 * math.pi - 0.3, 5)
        h = 1e-5
        slope = np.array([(ref.potential(mc, x + h) - ref.potential(mc, x - h)) / (2 * h)
                          for x in phis])
        np.testing.assert_allclose(reduced_at(pr, phis)[:, 2], -slope, rtol=0, atol=1e-7)


def test_M_O4_the_kinetic_energy_lost_at_constant_speed_is_the_corrected_464_318_J():
    """(J- - J+) 30^2 / 2 of the test mechanism (J_f cancels): 464.3183037 J, 1e-8."""
    for flywheel in (0.0, 5.0, 80.0):
        jm, jp = node_of(parameters(flywheel_inertia=flywheel))[:2]
        assert 0.5 * (jm - jp) * 30.0 ** 2 == pytest.approx(464.3183037, rel=1e-8)


# ---------------------------------------------------------------- the blow

def test_M_O5_the_kinematic_law_keeps_the_crank_speed_at_every_synthesised_design():
    rng = np.random.default_rng(15)
    for _ in range(30):
        d = random_design(rng)
        w_plus = blow_of(parameters(**d), 20.0, d["R"], LAW_KINEMATIC)[0][0]
        assert w_plus == pytest.approx(20.0, rel=1e-13)


@pytest.mark.parametrize("coupler", ["massless", "lumped"])
@pytest.mark.parametrize("kind", ["a", "b", "c"])
def test_M_O6_law_G_at_Rk_equal_minus_R_without_coupler_coupling_keeps_the_speed(coupler,
                                                                              kind):
    """A coupler without mass, or with its mass lumped at B and C (M13 = 0): no speed jump
    and no capture loss, at any flywheel, 1e-13 relative (the loss relative to the kinetic
    energy before the blow); the loss as a difference of kinetic energies agrees."""
    rng = np.random.default_rng(16)
    for _ in range(10):
        d = random_design(rng, kind, coupler)
        pr = parameters(**d)
        (w_plus, impulse, loss, tool, capture), difference = blow_of(pr, 25.0, d["R"],
                                                                     LAW_GENERALIZED)
        before = 0.5 * node_of(pr)[0] * 25.0 ** 2
        assert w_plus == pytest.approx(25.0, rel=1e-13)
        assert abs(capture) <= 1e-13 * before
        assert difference == pytest.approx(tool, rel=0, abs=1e-13 * before)


def test_a_general_coupler_at_Rk_equal_minus_R_does_kick_the_crank():
    """The coupler couples omega1 and omega3 (M13 != 0): at Rk = -R the blow still changes
    the crank's speed and loses energy in the capture (docs/machine.md §2)."""
    rng = np.random.default_rng(17)
    kicks = []
    for _ in range(20):
        d = random_design(rng)
        (w_plus, _, loss, _, capture), _ = blow_of(parameters(**d), 25.0, d["R"],
                                                   LAW_GENERALIZED)
        kicks.append(abs(w_plus - 25.0) / 25.0)
        assert capture > 1e-12 * loss
    assert max(kicks) > 1e-3


def test_M_O7_law_G_never_gains_energy_and_its_capture_loss_is_the_carnot_loss():
    """Random designs and materials R in [0, 1] (the linkage synthesised for another R):
    T+ <= T-, dE_tool >= 0, dE_capture >= 0, 1e-13 of T-; and the loss as a difference of
    kinetic energies, T- - T+, equals dE_tool + dE_capture (the capture as the Carnot loss
    of the velocity after the tool's impulse against the departure motion), 1e-12 of T-."""
    rng = np.random.default_rng(18)
    for _ in range(200):
        d = random_design(rng)
        r = float(rng.uniform(0.0, 1.0))
        (w_plus, impulse, loss, tool, capture), difference = blow_of(
            parameters(**d), 30.0, r, LAW_GENERALIZED)
        before = 0.5 * node_of(parameters(**d))[0] * 30.0 ** 2
        assert difference >= -1e-13 * before and tool >= -1e-13 * before
        assert capture >= -1e-13 * before
        assert difference == pytest.approx(tool + capture, rel=0, abs=1e-12 * before)


def test_M_O8_the_kinematic_law_gains_energy_exactly_where_its_condition_says():
    """Massless coupler: J_A (R^2/Rk^2 - 1) > J_D3 u31-^2 (1 - R^2) <=> T+ > T-, at random
    designs and materials (both laws compared: law G never gains)."""
    rng = np.random.default_rng(19)
    gains = agree = compared = 0
    for _ in range(300):
        d = random_design(rng, coupler="massless")
        r = float(rng.uniform(0.0, 1.0))
        pr = parameters(**d)
        jm, jp, jpm, mr, u31m, u31p = node_of(pr)[:6]
        status, m, own = data(pr)
        rk = u31p / u31m
        margin = m.ja * (r * r / (rk * rk) - 1) - m.masses.jd3 * u31m ** 2 * (1 - r * r)
        w_plus, _, loss, _, _ = blow_of(pr, 30.0, r, LAW_KINEMATIC)[0]
        if abs(margin) < 1e-9 * m.ja:
            continue
        compared += 1
        gains += loss < 0
        agree += (margin > 0) == (loss < 0)
        assert blow_of(pr, 30.0, r, LAW_GENERALIZED)[0][2] >= 0.0
    assert agree == compared >= 290 and gains > 10


def test_M_O9_law_G_without_crank_inertia_is_the_kinematic_law():
    """J_A = 0 and a massless coupler: law G equals law S, and T+ = R^2 T-, 1e-13."""
    rng = np.random.default_rng(20)
    for _ in range(20):
        d = random_design(rng, coupler="massless")
        d.update(m1=0.0, J1=0.0, flywheel_inertia=0.0)
        pr = parameters(**d)
        r = float(rng.uniform(0.0, 1.0))
        g = blow_of(pr, 30.0, r, LAW_GENERALIZED)[0]
        s = blow_of(pr, 30.0, r, LAW_KINEMATIC)[0]
        jm, jp = node_of(pr)[:2]
        assert g[0] == pytest.approx(s[0], rel=1e-13)
        assert 0.5 * jp * g[0] ** 2 == pytest.approx(r * r * 0.5 * jm * 30.0 ** 2, rel=1e-13,
                                                     abs=1e-13 * jm * 900)


# ---------------------------------------------------------------- the steady state

def test_M_O13_the_test_machines_steady_state():
    """1e-8 relative, or half a unit of the last digit the spec prints."""
    out, status, _ = outputs({"tol": 1e-12}, **LOADED)
    assert status == "ok"
    for name, value in M_O13.items():
        digits = len(repr(value).split(".")[1])
        assert abs(out[name] - value) <= max(1e-8 * abs(value), 0.5 * 10.0 ** -digits), name


def test_M_O10_and_M_O11_the_steady_cycle_balances_its_energy_and_is_a_fixed_point():
    """At random designs: motor work + gravity + load = the blow's loss, 1e-9 relative; one
    more revolution from the reported cycle repeats it to 1e-11."""
    rng = np.random.default_rng(21)
    checked = 0
    for _ in range(12):
        d = random_design(rng)
        d.update(motor_law="constant", stall_torque=float(rng.uniform(300, 1500)))
        out, status, _ = outputs(**d)
        if status != "ok":
            continue
        checked += 1
        assert abs(out["energy_balance_residual"]) <= 1e-9
        w = out["crank_speed_after_blow"]
        end, w_minus, w_next, period, angle = section_map(parameters(**d), w, 1e-10)
        assert end == REV_BLOW and abs(w_next - w) <= 1e-11 * w * 10
    assert checked >= 8


def test_M_O12_the_speed_fluctuation_falls_as_one_over_the_flywheel():
    deltas = {}
    for flywheel in (10.0, 20.0, 40.0, 80.0, 160.0):
        out, status, _ = outputs(flywheel_inertia=flywheel)
        assert status == "ok"
        deltas[flywheel] = out["speed_fluctuation"]
    slope = math.log(deltas[160.0] / deltas[80.0]) / math.log(2.0)
    assert slope == pytest.approx(-1.0, abs=0.03)
    products = [deltas[j] * j for j in sorted(deltas)]
    assert all(a < b for a, b in zip(products, products[1:]))  # tends up to its limit


def test_M_O14_the_flywheel_for_a_speed_fluctuation_exact_and_classical():
    out, status, _ = outputs({"tol": 1e-12, "outputs": ("flywheel_for_delta",
                                                        "flywheel_for_delta_classical")})
    assert status == "ok"
    assert out["flywheel_for_delta"] == pytest.approx(22.8224, rel=1e-5)
    assert out["flywheel_for_delta_classical"] == pytest.approx(23.1823, rel=1e-5)
    again, _, _ = outputs({"tol": 1e-12}, flywheel_inertia=out["flywheel_for_delta"])
    assert again["speed_fluctuation"] == pytest.approx(0.02, rel=1e-8)


def test_M_O15_the_shaft_torque_is_the_linkages_balancing_moment_at_the_actual_motion():
    """motor torque - J_A eps1 along the steady cycle equals linkage_forces' virtual-work
    balancing moment of the same linkage at the same omega1 and eps1, less the crank's own
    inertia times eps1, 1e-9 relative (the kinetostatics is another kernel, by another
    route: the sum of m (a - g).dr/dphi1 + J eps u)."""
    prof_n = 24
    out, status, prof = outputs({"profile_points": prof_n})
    assert status == "ok"
    angles = cell_midpoints(prof_n, 2 * np.pi)
    st, m, own = data(parameters())
    from kernels import kinetostatics as K
    decl = K.DECLARATION
    cols = np.array([[p.encode(p.default) for p in decl.parameters]] * prof_n).T
    cols[decl.parameter_index.omega1] = prof["crank_speed"]
    cols[decl.parameter_index.epsilon1] = prof["crank_acceleration"]
    res = np.empty(K.N_RESULT)
    for j in range(prof_n):
        K.joint_forces(angles[j], cols[:, j].copy(), m.linkage.sigma, res, 1e-9)
        expected = res[K.R_MB] - own * prof["crank_acceleration"][j]
        assert prof["shaft_torque"][j] == pytest.approx(expected, rel=1e-9, abs=1e-9 * 100)


def test_a_heavy_flywheels_shaft_torque_tends_to_the_kinetostatic_balancing_moment():
    """J_f -> infinity: omega1 -> omega_m, eps1 -> 0, and motor torque - J_A eps1 tends to
    linkage_forces' balancing moment at the mean speed, the gap falling like 1/J_f."""
    gaps = []
    for flywheel in (100.0, 1000.0):
        out, status, prof = outputs({"profile_points": 36}, flywheel_inertia=flywheel)
        w = out["mean_crank_speed"]
        atlas = sweep.run({"mechanism": "linkage_forces", "grid": {"omega1": [w]},
                           "method": {"profile_points": 36}})
        mb = atlas["balancing_moment"].values[0]
        gaps.append(np.max(np.abs(prof["shaft_torque"] - mb)) / np.max(np.abs(mb)))
    assert gaps[1] < 0.15 * gaps[0] and gaps[1] < 1e-2


# ---------------------------------------------------------------- hard cases

def test_MH1_a_motor_that_cannot_start_the_machine_still_runs_it():
    """Constant 5 N m < max(-Q_g) = 9.886 N m at phi1*: from rest it stalls at the node;
    running, its steady state is omega_mean = 7.932244, delta = 0.10186 (bistable)."""
    q = reduced_at(parameters(), np.array([0.0]))[0, 2]
    assert q == pytest.approx(-9.886, abs=1e-3)
    _, status, _ = outputs({"start": "rest"}, motor_law="constant", stall_torque=5.0)
    assert status == "stalls"
    out, status, _ = outputs({"tol": 1e-12}, motor_law="constant", stall_torque=5.0)
    assert status == "ok"
    assert out["mean_crank_speed"] == pytest.approx(7.932244, rel=1e-6)
    assert out["speed_fluctuation"] == pytest.approx(0.10186, rel=1e-4)


def test_MH2_a_stall_inside_the_cycle_is_located():
    """Constant 8 N m, J_f = 0.05, leaving the blow at 0.5 rad/s: omega1 -> 0 at phi1 =
    0.0126."""
    pr = parameters(motor_law="constant", stall_torque=8.0, flywheel_inertia=0.05)
    end, w_minus, w_next, period, angle = section_map(pr, 0.5, 1e-10)
    assert end == REV_STALL and angle == pytest.approx(0.0126, abs=1e-4)


def test_MH3_only_the_rocker_has_inertia():
    _, status, _ = outputs(m1=0.0, J1=0.0, flywheel_inertia=0.0, m2=0.0, J2=0.0)
    assert status == "singular_inertia"
    _, status, _ = outputs(m1=0.0, J1=0.0, flywheel_inertia=0.0)  # a coupler with mass
    assert status == "ok"


def test_MH4_a_plastic_blow_and_the_synthesis_at_R_0():
    out, status, _ = outputs(R=0.0, design_restitution=0.3)
    assert status == "ok" and out["energy_to_material"] > 0
    _, status, _ = outputs(R=0.0)  # Rk = -0: gamma = 1, lambda0 = 1, B on D
    assert status == "degenerate"


def test_MH5_a_blow_that_gives_the_material_nothing():
    out, status, _ = outputs(R=1.0, design_restitution=0.3)
    assert status == "ok" and out["energy_to_material"] == 0.0
    assert out["blow_efficiency"] == 0.0 and out["capture_loss"] == pytest.approx(
        out["blow_loss"], rel=1e-12)
    _, status, _ = outputs(R=1.0)  # Rk = -1: no linkage
    assert status == "no_real_synthesis"


def test_MH6_a_large_mismatch():
    """Rk = -0.9 against R = 0.05: law G kicks the crank and loses in the capture; law S
    nearly stops the crank at every blow (omega1+ = 0.056 omega1-)."""
    g, status, _ = outputs(largest_link=25.0, design_restitution=0.9, R=0.05)
    assert status == "ok" and g["capture_loss"] > 0.05 * g["blow_loss"]
    s, status, _ = outputs(largest_link=25.0, design_restitution=0.9, R=0.05,
                           impact_law="kinematic")
    assert s["crank_speed_after_blow"] / s["crank_speed_before_blow"] == pytest.approx(
        0.05 / 0.9, rel=1e-12)


def test_MH7_no_flywheel():
    out, status, _ = outputs(flywheel_inertia=0.0)
    assert status == "ok"
    assert out["speed_fluctuation"] == pytest.approx(0.499, abs=1e-3)
    assert out["crank_speed_jump"] == pytest.approx(-5.75, abs=1e-2)


def test_MH8_a_blow_that_throws_the_crank_back_is_its_own_status():
    """A heavy coupler whose centroid lies far off BC couples omega1 and omega3 so strongly
    that the capture reverses a light crank: status reverses, no values."""
    out, status, _ = outputs(m1=0.01, J1=1e-5, flywheel_inertia=0.0, m2=60.0, J2=0.01,
                             q2=0.3, s2=1.5, R=0.9, design_restitution=0.1, largest_link=4)
    assert status == "reverses" and math.isnan(out["mean_crank_speed"])


def test_MH9_a_heavy_flywheel_converges_in_a_few_revolutions():
    """J_f = 2000 with a linear motor: the map's slope is near 1 (a plain iteration needs
    hundreds of revolutions); the secant needs a few, from rest after the run-up too."""
    running, status, _ = outputs(flywheel_inertia=2000.0)
    assert status == "ok" and running["revolutions"] <= 8
    rest, status, _ = outputs({"start": "rest"}, flywheel_inertia=2000.0)
    assert status == "ok" and rest["revolutions"] <= RUNUP_REVOLUTIONS + 12
    assert rest["mean_crank_speed"] == pytest.approx(running["mean_crank_speed"], rel=1e-9)


def test_MH10_nothing_is_evaluated_as_0_over_0_at_the_node():
    """Every quantity at phi1* and phi1* + 2 pi exactly is finite (the desingularised u31,
    u21 from the loop's real part, u31' by a complex step)."""
    for kind in ("a", "b", "c"):
        d = random_design(np.random.default_rng(22), kind)
        pr = parameters(**d)
        start = data(pr)[1].linkage.start
        assert np.all(np.isfinite(reduced_at(pr, np.array([start, start + 2 * math.pi]))))


# ---------------------------------------------------------------- against SciPy

@pytest.mark.slow
def test_the_steady_state_equals_an_independent_scipy_model_at_random_designs():
    """20 random designs (types a, b, c; general couplers; linear and constant motors; a
    conservative load), the kernel at its default tol against DOP853 at rtol 1e-12 in time
    on a numpy loop closure (tests/machine_reference.py): every steady-state output within
    1e-7 relative."""
    rng = np.random.default_rng(23)
    compared = 0
    names = ["mean_crank_speed", "speed_fluctuation", "crank_speed_before_blow",
             "crank_speed_after_blow", "tool_impulse", "motor_torque_rms", "motor_power_mean",
             "blow_energy", "blow_loss", "energy_to_material", "blow_rate", "cycle_period",
             "motor_torque_peak"]
    while compared < 20:
        d = random_design(rng)
        d.update(load_force_x=float(rng.uniform(-20, 20)), load_force_y=float(rng.uniform(-20, 20)),
                 load_arm=float(rng.uniform(0.0, 0.1)), load_moment=float(rng.uniform(-2, 2)))
        mc, lam0, gamma = ref.build(d, d["type"], d["largest_link"])
        m3, tm, tp = ref.node(mc, lam0, gamma, d["type"])
        c = ref.law_g(m3, tm, tp, 1.0, mc.restitution)[2]
        target = float(rng.uniform(10.0, 50.0))
        if rng.uniform() < 0.5:
            d.update(motor_law="constant", stall_torque=c * target ** 2 / (2 * math.pi))
        else:
            idle = 1.3 * target
            d.update(motor_law="linear", idle_speed=idle,
                     stall_torque=c * target ** 2 / (2 * math.pi * (1 - target / idle)))
        out, status, _ = outputs(**d)
        if status != "ok":
            continue
        expected = ref.simulate(d, d["type"], d["largest_link"])
        for name in names:
            assert out[name] == pytest.approx(expected[name], rel=1e-7), (name, d)
        assert out["crank_impulse"] == pytest.approx(expected["crank_impulse"], rel=1e-6,
                                                     abs=1e-9 * abs(expected["tool_impulse"]))
        compared += 1


def test_the_claim_of_CR_on_the_test_machine():
    """[CR]: at Rk = -R the dynamic loads on the crank and its speed unevenness are
    smallest. The test machine, synthesised for R = 0.3, over the material's R
    (docs/machine.md §4): a lumped coupler makes the crank's impulse and the capture loss
    vanish at 0.3, growing like |R - 0.3| and (R - 0.3)^2; the real coupler moves the
    impulse's minimum to R ~ 0.37 and leaves the capture's at ~0.30; with a light flywheel
    the speed fluctuation falls monotonically up to R = 0.75."""
    r = np.round(np.arange(0.20, 0.501, 0.001), 3)
    general = sweep.run({"mechanism": "impact_machine", "grid": {"R": r.tolist()},
                         "fixed": {"design_restitution": 0.3}})
    impulse, capture = np.abs(general["crank_impulse"].values), general["capture_loss"].values
    assert 0.36 <= r[np.argmin(impulse)] <= 0.38
    assert 0.29 <= r[np.argmin(capture)] <= 0.31 and capture.min() < 1e-3
    at = general.sel(R=0.3)
    jump = float(at["crank_speed_jump"] / at["crank_speed_before_blow"])
    assert jump == pytest.approx(-0.005, abs=5e-4)
    lumped = sweep.run({"mechanism": "impact_machine",
                        "grid": {"R": [0.25, 0.275, 0.3, 0.325, 0.35]},
                        "fixed": {"design_restitution": 0.3, "q2": 0.0,
                                  "J2": 3.0 * 0.48 * 0.52 * 0.25 ** 2}})
    h, c = lumped["crank_impulse"].values, lumped["capture_loss"].values
    scale = np.abs(h).max()
    assert abs(h[2]) <= 1e-12 * scale and c[2] <= 1e-12 * c.max()
    assert h[0] / h[1] == pytest.approx(2.0, rel=0.02) and h[4] / h[3] == pytest.approx(2.0, rel=0.02)
    assert c[0] / c[1] == pytest.approx(4.0, rel=0.05) and c[4] / c[3] == pytest.approx(4.0, rel=0.05)
    light = sweep.run({"mechanism": "impact_machine",
                       "grid": {"R": np.round(np.arange(0.05, 0.751, 0.01), 2).tolist()},
                       "fixed": {"design_restitution": 0.3, "flywheel_inertia": 0.5}})
    assert np.all(np.diff(light["speed_fluctuation"].values) < 0)


@pytest.mark.parametrize("document, field", [
    ({"grid": {"flywheel_inertia": [-1.0, 5.0]}}, "grid.flywheel_inertia"),
    ({"grid": {"R": [0.3]}, "fixed": {"impact_law": "kinematic"},
      "outputs": ["flywheel_for_delta"]}, "outputs"),
    ({"grid": {"R": [0.3]}, "fixed": {"type": "general", "lambda0": 2.0}}, "lambda2"),
    ({"grid": {"R": [0.3]}, "fixed": {"stall_torque": 0.0}}, "fixed.stall_torque"),
])
def test_bad_machine_input_is_one_line_before_compute(document, field):
    with pytest.raises(sweep.UserError) as err:
        sweep.Sweep.from_dict({"mechanism": "impact_machine", **document})
    assert str(err.value).startswith(field)


def test_the_lean_block_gives_the_full_blocks_values_bit_for_bit():
    """A run that asks nothing beyond the steady cycle compiles the lean block
    (kernels/impact_machine.py); asking profiles runs the full one. At random designs
    (material, flywheel, striker, speed) every output both compute is the same to the
    last bit, and the full block adds the profiles."""
    rng = np.random.default_rng(63)
    grid = {"R": sorted(rng.uniform(0.05, 0.6, 3).round(4).tolist()),
            "flywheel_inertia": sorted(rng.uniform(0.5, 40.0, 2).round(3).tolist()),
            "m3": sorted(rng.uniform(2.0, 12.0, 2).round(3).tolist())}
    fixed = {"idle_speed": round(float(rng.uniform(25.0, 60.0)), 3)}
    lean = sweep.run({"mechanism": "impact_machine", "grid": grid, "fixed": fixed})
    full = sweep.run({"mechanism": "impact_machine", "grid": grid, "fixed": fixed,
                      "method": {"profile_points": 7}})
    plain = np.zeros((len(M.P), 1))
    plain[M.P.omega1] = np.nan  # the idle speed given, not a crank speed
    asked = type("Method", (), {"outputs": ("blow_energy",)})
    assert not M.needs_full(plain, asked, np.empty(0))
    assert M.needs_full(plain, asked, np.ones(3))
    assert (lean.status.values == 0).sum() >= 6
    for name in lean.data_vars:
        assert np.array_equal(lean[name].values, full[name].values, equal_nan=True), name
    assert set(full.data_vars) - set(lean.data_vars)
