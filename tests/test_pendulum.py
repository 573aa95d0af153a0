"""Rotary-pendulum impact mechanism ([RP]; docs/models.md §5): closed forms against the
integrators, oracles P-O1..P-O13, the separatrix (H1, H2), the affine map (H13)."""

import math

import numpy as np
import pytest
from scipy.special import ellipk as scipy_ellipk

from kernels import rotary_pendulum as kr
from kernels.pendulum import free_flight as ff
from kernels.pendulum import dispatch, models as pm
from kernels.impact.outcomes import FLIGHT_EVENT
from sweep import spec
from sweep.errors import UserError
from tests import probes
from tests.conftest import flag_words, kernel_point

XI = 4.0
# docs/models.md §5.1: the model values (A, n, max|psi''|/omega1^2) and the paper's Table 1
MODEL = {1.0: (2.15268, 0.69967, 1.2734), 1.5: (1.91174, 1.00691, 2.2122),
         2.0: (1.79862, 1.25931, 3.4131), 2.5: (1.72373, 1.48959, 4.9196)}
TABLE1 = {1.0: (2.170, 0.7004), 1.5: (1.920, 1.0109), 2.0: (1.792, 1.2566), 2.5: (1.724, 1.4948)}
# [RP] Table 2, max angular acceleration [1/s^2] at omega1 = 20..100 (OCR "2210(" = 22100)
TABLE2 = {1.0: (495, 2000, 4520, 8000, 12230), 1.5: (883, 2530, 7900, 14120, 22200),
          2.0: (1350, 5470, 12350, 22100, 33930), 2.5: (2000, 8000, 17300, 31500, 49700)}
TYPO = (1.5, 40.0)  # printed 2530, the model gives 3540: a typo for 3530
DOPRI5 = probes.METHODS["dopri5"]


def closed(k, v=None, xi=XI):
    v = 1 + k if v is None else v
    amp = ff.paper_amplitude(v, k, xi)
    return amp, ff.paper_half_period(v, k, xi, amp), ff.paper_peak_acceleration(v, k, xi, amp)


def launch(model, v, p, **settings):
    """The flight from the rotor stop launched at psi' = -v, back to the stop (refined)."""
    return probes.flight(model, "rotor_stop")(0.0, (0.0, -v), p, (0.0, p[0]),
                                              probes.settings(**settings), True)


def dimensionless(method=None, **design):
    """One design through the kernel in omega1 units (omega1 = l2 = 1)."""
    out, status, _ = kernel_point("rotary_pendulum", method, omega1=1.0, l2=1.0, **design)
    return out, status


@pytest.mark.parametrize("k", sorted(MODEL))
def test_closed_form_reproduces_the_reconstructed_model(k):
    amp, tau1, acc = closed(k)
    a_ref, n_ref, c_ref = MODEL[k]
    assert amp == pytest.approx(a_ref, abs=5e-6)
    assert math.pi / tau1 == pytest.approx(n_ref, abs=5e-6)
    assert acc == pytest.approx(c_ref, abs=5e-5)


@pytest.mark.parametrize("k", sorted(MODEL))
def test_P_O2_O3_O4_O5_closed_form_equals_dopri5_at_tight_tolerance(k):
    amp, tau1, acc = closed(k)
    fl = launch("paper", 1 + k, (k, XI), rtol=1e-12, atol=1e-14)
    assert fl.outcome == FLIGHT_EVENT and fl.event == 0
    assert abs(fl.amplitude - amp) <= 1e-9  # P-O2
    assert abs(fl.t - tau1) <= 1e-9  # P-O3
    assert fl.peak == pytest.approx(acc, rel=1e-8)  # P-O4
    assert abs(fl.y[1] - (1 + k)) <= 1e-10  # P-O5: the flight is time-reversible


def test_P_O1_first_integral_is_conserved_along_a_dopri5_orbit():
    """(psi'^2 + xi) M(psi) with ln M = ln(1 + xi X)/xi^2 - X/xi is constant on a flight."""
    k, v = 2.0, 3.0

    def invariant(psi, dpsi):
        x = k * k + 1 + 2 * k * math.cos(psi)
        return (dpsi * dpsi + XI) * math.exp(math.log1p(XI * x) / XI**2 - x / XI)

    start = invariant(0.0, -v)
    for tau in (0.3, 0.9, 1.6, 2.4):
        psi, dpsi = probes.fixed_steps("paper")(DOPRI5, (0.0, -v), (k, XI), tau / 400, 400)
        assert invariant(psi, dpsi) == pytest.approx(start, rel=1e-10)
        assert dpsi * dpsi == pytest.approx(ff.paper_u(psi, v, k, XI), rel=1e-9, abs=1e-12)


def test_P_O6_affine_impact_map_fixed_point_and_contraction():
    k, r = 2.5, 0.2
    v_star = ff.steady_state_speed(k, r)
    assert v_star == pytest.approx(5.25, rel=1e-15)
    assert 1 + k + v_star == pytest.approx(2 * (1 + k) / (1 - r), rel=1e-15)  # V*/(omega1 l2)
    count, escaped = ff.impacts_to_converge(k, r, ff.paper_critical_speed(k, XI), 1e-11)
    assert not escaped and count == math.ceil(math.log(1e-11) / math.log(r))  # ratio R
    assert count == 16 or count == 17  # docs/models.md §5.4: 17 impacts to 1e-11


@pytest.mark.parametrize("k, r_crit", [(1.0, 0.061), (1.5, 0.146), (2.0, 0.221), (2.5, 0.288)])
@pytest.mark.parametrize("integrator", ["closed_form", "dopri5"])
def test_P_O7_escape_threshold_classifies_exactly(k, r_crit, integrator):
    v_crit = ff.paper_critical_speed(k, XI)
    exact = (v_crit - (1 + k)) / (v_crit + (1 + k))
    assert exact == pytest.approx(r_crit, abs=6e-4)
    method = dict(integrator=integrator, rtol=1e-10, atol=1e-12, max_impacts=100000)
    out, status = dimensionless(method, k=k, R=exact * (1 - 1e-6))
    assert status == "ok" and out["regime"] == kr.R_["period_1"]
    out, status = dimensionless(method, k=k, R=exact * (1 + 1e-6))
    assert status == "escape" and out["regime"] == kr.R_["escape"]


def test_P_O8_rigid_pendulum_elliptic_period_and_the_separatrix():
    for m in (0.1, 0.5, 0.9, 0.999):
        assert ff.ellipk(m) == pytest.approx(scipy_ellipk(m), rel=4e-16)
    # kappa k = 2: launched with 1 + k = 2 from k = 1, m = 0.5
    amp, tau1, acc = ff.rigid_flight(2.0, 2.0)
    fl = launch("rigid", 2.0, (1.0, 2.0), rtol=1e-12, atol=1e-14)
    assert abs(fl.t - tau1) <= 1e-9 and abs(fl.amplitude - amp) <= 1e-9
    assert amp == pytest.approx(2 * math.asin(math.sqrt(0.5)), rel=1e-15)
    # H1: on the separatrix (point mass, k = 1, R = 0: v^2 = 4 kappa k) the closed form
    # decides before any integration
    assert math.isnan(ff.rigid_flight(2.0, 1.0)[0])
    out, status = dimensionless(dict(integrator="dopri5"), model="rigid", k=1.0, kappa=1.0)
    assert status == "separatrix" and out["n_steps"] == 0  # no step taken


def test_the_rigid_pendulums_closed_form_is_as_exact_as_m_up_to_the_separatrix():
    """rigid_flight (P-O8) against mpmath at 40 digits on the same double inputs, at 300
    random designs: Omega^2 from 0.1 to 30, launch speeds from 0.01 v_crit to within 1e-13
    of it. Near the separatrix the flight time is as sensitive as m = v^2/(4 Omega^2), which
    a double holds to an ulp: the error is bounded in units of eps x value + the change of
    the exact value when m moves by one ulp. Within 2 units (seen: 1.2; 1.9e-5 relative
    at 1 - m = 2e-13, all of it m's own rounding); the peak Omega^2 sin(min(A, pi/2))
    within 2 ulp."""
    import mpmath as mp

    mp.mp.dps = 40
    eps = 2.0 ** -52
    rng = np.random.default_rng(2029)
    for j in range(300):
        omega2 = 10 ** rng.uniform(-1.0, 1.5)
        v = (1.0 - 10 ** rng.uniform(-13.0, -0.01 if j % 2 else -2.0)) * 2.0 * math.sqrt(omega2)
        amplitude, tau1, peak = ff.rigid_flight(v, omega2)
        m = mp.mpf(v) ** 2 / (4 * mp.mpf(omega2))

        def exact_tau(mm):
            return 2 * mp.ellipk(mm) / mp.sqrt(mp.mpf(omega2))

        def exact_amplitude(mm):
            return 2 * mp.asin(mp.sqrt(mm))

        for value, exact in ((tau1, exact_tau), (amplitude, exact_amplitude)):
            unit = eps * exact(m) + abs(exact(m * (1 + eps)) - exact(m))
            assert abs(value - exact(m)) <= 2 * unit, (v, omega2, value)
        exact_peak = mp.mpf(omega2) * mp.sin(min(exact_amplitude(m), mp.pi / 2))
        assert peak == pytest.approx(float(exact_peak), rel=4.5e-16), (v, omega2)


CYCLE_OUTPUTS = ("amplitude", "frequency_ratio", "period", "impact_speed", "impact_interval",
                 "acceleration_peak", "rotor_speed_ratio")


@pytest.mark.parametrize("method", [dict(integrator=i) for i in
                                    ("closed_form", "auto", "dopri5", "rk4")])
@pytest.mark.parametrize("design", [
    dict(model="paper", k=1.0, xi=4.0, R=0.061081403419311404),  # R = R_crit to rounding
    dict(model="rigid", k=2.0, R=0.1, kappa=1.6805555555555558)])  # kappa = kappa*
def test_on_the_separatrix_no_cycle_value_is_reported(method, design):
    """Issue 12 item 5: at the escape threshold the cycle's period is infinite; every
    integrator said period_1 / ok with NaN or finite stand-ins (the paper model's
    acceleration_peak was -omega1^2). The status says why and no cycle value is given."""
    out, status = dimensionless(method, **design)
    assert status == "separatrix" and out["regime"] == kr.R_["separatrix"]
    assert all(math.isnan(out[name]) for name in CYCLE_OUTPUTS)
    assert out["restitution_critical"] == pytest.approx(design["R"], rel=1e-12)


@pytest.mark.parametrize("side", [-1.0, 1.0])
def test_just_off_the_separatrix_the_regime_follows_the_side(side):
    """A relative 1e-9 below R_crit is a cycle with finite values; above it escapes."""
    r = 0.061081403419311404 * (1 + side * 1e-9)
    out, status = dimensionless(dict(integrator="auto"), model="paper", k=1.0, xi=4.0, R=r)
    if side < 0:
        assert status == "ok" and all(np.isfinite(out[n]) for n in CYCLE_OUTPUTS)
        assert out["acceleration_peak"] > 0
    else:
        assert status == "escape" and math.isnan(out["impact_speed"])


def test_physical_pendulum_never_returns_after_a_plastic_impact():
    """docs/models.md §5.2: kappa = xi/(1+xi) < (1+k)^2/(4k) for every k."""
    for k in (1.0, 1.5, 2.0, 2.5):
        out, status = dimensionless(model="rigid", k=k, kappa=XI / (1 + XI))
        assert status == "escape"
        assert math.isnan(out["restitution_critical"])  # no R has a periodic regime


def test_H2_near_separatrix_slowing():
    k = 2.5
    v_crit = ff.paper_critical_speed(k, XI)
    expected = {1e-2: 4.31, 1e-4: 7.37, 1e-6: 10.44}
    for delta, tau in expected.items():
        v = v_crit * (1 - delta)
        amp = ff.paper_amplitude(v, k, XI)
        assert ff.paper_half_period(v, k, XI, amp) == pytest.approx(tau, abs=0.01)


@pytest.mark.parametrize("model", ["paper", "rigid"])
def test_integrators_agree_with_the_closed_form_at_random_points(model):
    """15 random designs below the escape threshold: DOPRI5 at rtol 1e-10 through the whole
    impact sequence against the closed form, every output to 1e-7."""
    rng = np.random.default_rng(5)
    for _ in range(15):
        k = rng.uniform(1.0, 3.0)
        kappa = (1 + k) ** 2 / (4 * k) * rng.uniform(1.1, 1.6)
        crit = (ff.paper_critical_speed(k, XI) if model == "paper"
                else 2 * math.sqrt(kappa * k))
        r = rng.uniform(0, 0.9) * (crit - 1 - k) / (crit + 1 + k)
        design = dict(model=model, k=k, kappa=kappa, R=r)
        closed_form, status = dimensionless(dict(integrator="closed_form"), **design)
        assert status == "ok"
        integrated, status = dimensionless(dict(integrator="dopri5", rtol=1e-10, atol=1e-12),
                                           **design)
        assert status == "ok"
        for name in ("amplitude", "frequency_ratio", "impact_interval", "impact_speed",
                     "acceleration_peak"):
            assert integrated[name] == pytest.approx(closed_form[name], rel=1e-7), name


def test_P_O13_paper_tables_within_their_bands_and_the_typo_cell():
    for k, (a_paper, n_paper) in TABLE1.items():
        amp, tau1, _ = closed(k)
        assert abs(amp / a_paper - 1) <= 0.01 and abs(math.pi / tau1 / n_paper - 1) <= 0.005
    bad = []
    for k, row in TABLE2.items():
        c = closed(k)[2]
        for w, printed in zip((20.0, 40.0, 60.0, 80.0, 100.0), row):
            if abs(c * w * w / printed - 1) > 0.05:
                bad.append((k, w))
    assert bad == [TYPO]
    assert closed(1.5)[2] * 1600 == pytest.approx(3540, abs=5)


def test_P_O12_omega1_is_a_time_scale_and_is_not_integrated_again(monkeypatch):
    calls = []
    real = dispatch.solve_cases

    def counting(cases, method, *more):
        calls.append(cases.shape[0])
        return real(cases, method, *more)

    monkeypatch.setattr(dispatch, "solve_cases", counting)
    s = spec.parse('mechanism = "rotary_pendulum"\n[grid]\nk = [1.5, 2.5]\n'
                   'omega1 = [20.0, 37.7, 100.0]\n[method]\nintegrator = "dopri5"')
    from sweep.engine import Plan, run_block
    plan = Plan(s)
    assert plan.chunk_shape[1] == 3  # omega1 whole in every block
    blocks = [plan.split(run_block(s, location)) for _, location in plan.locations()]
    out = {name: np.concatenate([b[name] for b in blocks]) for name in blocks[0]}
    assert sum(calls) == 2  # two (k) cases solved for six grid points
    amp = out["amplitude"]
    assert np.all(amp[:, 0] == amp[:, 2])
    acc = out["acceleration_peak"]
    assert acc[:, 2] / acc[:, 0] == pytest.approx(25.0, rel=1e-12)
    period = out["period"]
    assert period[:, 0] / period[:, 2] == pytest.approx(5.0, rel=1e-12)
    v = out["impact_speed"]  # corrected eq. (7): V = 2 (1+k) omega1 l2 at R = 0
    assert v[1, 0] == pytest.approx(2 * 3.5 * 20.0 * 0.04, rel=1e-12)


@pytest.mark.parametrize("text, key", [
    ('[fixed]\ntool_window = 0.3', "tool_window"),
    ('[fixed]\ntool = "lab_window"\ntool_window = 2.0', "fixed.tool_window"),
    ('[fixed]\nmotor_slope = 3.0', "motor_slope"),
    ('[fixed]\nmodel = "rotor"\n[method]\nintegrator = "closed_form"', "method.integrator"),
    ("[fixed]\nkappa = 0.9", "kappa"),
    ("[fixed]\nR = 1.0", "fixed.R"),
    ('[method]\nintegrator = "euler"', "method.integrator"),
])
def test_pendulum_spec_errors(text, key):
    with pytest.raises(UserError) as err:
        spec.parse('mechanism = "rotary_pendulum"\n[grid]\nk = [2.5]\n' + text)
    assert key in str(err.value) and "\n" not in str(err.value)


def test_regime_flags_decode_by_name_in_the_atlas(tmp_path):
    import xarray as xr

    from sweep import runner

    s = spec.parse('mechanism = "rotary_pendulum"\n[grid]\nR = [0.0, 0.35]\n[fixed]\nk = 2.5')
    runner.run_sweep(s, tmp_path / "p.nc", progress=False, history="test")
    ds = xr.open_dataset(tmp_path / "p.nc")
    decoded = list(flag_words(ds["regime"]))
    assert decoded == ["period_1", "escape"]  # R = 0.35 > R_crit(2.5) = 0.288
    status = ds["status"].attrs["flag_meanings"].split()
    codes = list(ds["status"].attrs["flag_values"])
    assert [status[codes.index(v)] for v in ds["status"].values] == ["ok", "escape"]


def rotor_energy_momentum(y, p):
    """Kinetic energy and angular momentum of the rotor model (P8): a free rotor conserves
    both."""
    k, xi, j1 = p[0], p[1], p[2]
    m11, m12, m22 = pm.mass_matrix(y[2], k, xi, j1)
    return pm.kinetic_energy(y, p), m11 * y[1] + m12 * y[3]


def test_P_O10_free_rotor_conserves_energy_and_angular_momentum():
    p = (2.0, 4.0, 3.0, 0.0, 1.0)  # k_cm, xi, j1, no motor
    y0 = (0.0, 1.0, 0.0, -3.0)  # just after a plastic impact: psi' = -(1+k) phi1'
    t0, h0 = rotor_energy_momentum(y0, p)
    for tau in (0.5, 1.3, 2.7):
        y = probes.fixed_steps("rotor")(DOPRI5, y0, p, tau / 2000, 2000)
        t, h = rotor_energy_momentum(y, p)
        assert t == pytest.approx(t0, rel=1e-9) and h == pytest.approx(h0, rel=1e-9)


def test_P_O11_generalised_impact():
    """Newton's law through the rotor's mass matrix (docs/models.md §5.3) on the rotor stop,
    J = (1 + k, 1) on (phi1', psi') with k = l1/l_contact; the mass matrix in l_cm units
    (k_cm = l1/l_cm = 2.5)."""
    k, xi, r = 2.5, 4.0, 0.3
    law = probes.restitute("rotor", "rotor_stop")
    w, dpsi = 1.0, 2.2

    def hit(j1, y=(0.0, w, 0.0, dpsi), kc=k, data=(0.0, k)):
        return law(0.0, y, data, (kc, xi, j1, 0.0, 1.0), r)[1]

    # an infinitely heavy rotor reproduces the paper's law (5)
    after = hit(1e12)
    assert after[1] == pytest.approx(w, abs=1e-9)
    assert after[3] == pytest.approx(-(1 + k) * (1 + r) * w - r * dpsi, abs=1e-9)
    # contact at the centre of percussion, l_contact = lambda l_cm with lambda = 1 + 1/xi:
    # no rotor-speed jump, any j1 (the stop's k is l1/l_contact = k_cm/lambda)
    lam = 1 + 1 / xi
    for j1 in (0.0, 0.3, 5.0):
        y = hit(j1, data=(0.0, k / lam))
        assert y[1] == pytest.approx(w, abs=1e-12)
    # Kelvin: the energy lost equals (1 - R^2) v_n^2 / (2 J M^-1 J^T); v_n+ = -R v_n-
    j1 = 2.0
    p = (k, xi, j1, 0.0, 1.0)
    before = (0.0, w, 0.0, dpsi)
    after = hit(j1)
    m11, m12, m22 = pm.mass_matrix(0.0, k, xi, j1)
    jac = np.array([1 + k, 1.0])
    m_inv_jt = np.linalg.solve([[m11, m12], [m12, m22]], jac)
    v_n = jac @ [w, dpsi]
    lost = (1 - r * r) * v_n ** 2 / (2 * jac @ m_inv_jt)
    assert pm.kinetic_energy(before, p) - pm.kinetic_energy(after, p) == pytest.approx(
        lost, rel=1e-12)
    assert jac @ [after[1], after[3]] == pytest.approx(-r * v_n, rel=1e-12)


def test_rotor_model_tends_to_the_rigid_model_with_a_stiff_motor():
    """With a steep motor law the rotor keeps its speed and psi follows psi'' = -kappa k
    sin psi, kappa = xi/(1 + xi) (docs/models.md §5.2: 1.2e-4 at j1 = 20, s_m = 1e6, tau =
    1.5)."""
    k, xi = 2.0, 4.0
    kappa = xi / (1 + xi)  # contact at the striker: k_cm = k
    rigid = probes.fixed_steps("rigid")(DOPRI5, (0.0, -3.0), (k, kappa), 1.5 / 3000, 3000)
    gaps = []
    for slope in (1e2, 1e4, 1e6):
        n = int(max(3000, 1.5 * slope))
        y = probes.fixed_steps("rotor")(DOPRI5, (0.0, 1.0, 0.0, -3.0),
                                        (k, xi, 20.0, slope, 1.0), 1.5 / n, n)
        gaps.append(abs(y[2] - rigid[0]))
    assert gaps[0] > gaps[1] > gaps[2] and gaps[2] < 1e-3


def test_P_O9_jacobi_integral_of_the_rigid_pendulum():
    """E = psi'^2/2 - kappa k cos psi is conserved between impacts (P-O9, 1e-11)."""
    k, kappa = 2.0, 0.8
    e0 = 0.5 * 2.5**2 - kappa * k
    for tau in (0.4, 1.3, 2.9):
        psi, dpsi = probes.fixed_steps("rigid")(DOPRI5, (0.0, -2.5), (k, kappa), tau / 1000,
                                                1000)
        assert 0.5 * dpsi**2 - kappa * k * math.cos(psi) == pytest.approx(e0, abs=1e-11)


def test_the_closed_form_peak_acceleration_is_exact_to_round_off():
    """max |psi''| over the flight (P-O4) against mpmath at 30 digits (a dense sample of the
    value, then the root of its numerical log-derivative next to the best sample: a
    different algorithm from the kernel's closed-form slope) at 32 random designs: k in
    (0.05, 5), xi from 0.01 to 20, launch speeds up to 1e-13 of v_crit; a quarter within
    0.1 of k = 1 (X ~ 0 next to the saddle) and a quarter with xi < 0.1. Within 2e-12 (seen:
    8e-13, where xi ~ 0.01 makes |psi''| an exponential of a difference of numbers ~ 1/xi:
    a golden-section search on the value was as far off, biased upwards by that noise)."""
    import mpmath as mp

    mp.mp.dps = 30

    def exact(v, k, xi, amplitude):
        v, k, xi, a = (mp.mpf(x) for x in (v, k, xi, amplitude))

        def g(x):
            return mp.log1p(xi * x) / xi ** 2 - x / xi

        def f(psi):
            x = k * k + 1 + 2 * k * mp.cos(psi)
            return (k * x / (1 + xi * x) * (v * v + xi) * mp.exp(g((1 + k) ** 2) - g(x))
                    * mp.sin(psi))
        points = [a * j / 64 for j in range(1, 65)]
        values = [f(p) for p in points]
        j = max(range(64), key=values.__getitem__)
        best = values[j]
        if j < 63:
            root = mp.findroot(lambda p: mp.diff(lambda q: mp.log(f(q)), p),
                               (points[j - 1], points[j + 1]), solver="anderson")
            best = max(best, f(root))
        return float(best)

    rng = np.random.default_rng(2411)
    for j in range(32):
        k, xi = rng.uniform(0.05, 5.0), 10 ** rng.uniform(-2.0, 1.3)
        if j % 4 == 1:
            k = 1.0 + rng.choice([-1.0, 1.0]) * 10 ** rng.uniform(-6.0, -1.0)
        elif j % 4 == 2:
            xi = 10 ** rng.uniform(-2.0, -1.0)
        v = (1.0 - 10 ** rng.uniform(-13.0, -0.01)) * ff.paper_critical_speed(k, xi)
        amplitude = ff.paper_amplitude(v, k, xi)
        assert ff.paper_peak_acceleration(v, k, xi, amplitude) == pytest.approx(
            exact(v, k, xi, amplitude), rel=2e-12), (k, xi, v)


def test_the_peak_accelerations_scan_finds_the_roots_of_the_exact_slope():
    """The peak's scan (P-O4) steps cos psi by a recurrence; the oracle scans the same 32
    points with the slope evaluated from math.cos and math.sin in Python, brackets each + to
    - change with brentq (SciPy) and takes the largest |psi''| there and at A. 3,000 random
    designs (k in (0.05, 5), a quarter within 0.1 of k = 1, xi from 0.01 to 20, launch
    speeds up to 1e-13 of v_crit): equal to 1e-14 (seen: 7e-16; the value is stationary at
    a root). A recurrence or sign threshold that loses a change finds another maximum."""
    from scipy.optimize import brentq

    def slope(psi, k, xi):
        x = k * k + 1.0 + 2.0 * k * math.cos(psi)
        return math.cos(psi) - 2.0 * k * math.sin(psi) ** 2 * (1.0 / x + (x - xi) / (1.0 + xi * x))

    rng = np.random.default_rng(3301)
    for j in range(3000):
        k, xi = rng.uniform(0.05, 5.0), 10 ** rng.uniform(-2.0, 1.3)
        if j % 4 == 0:
            k = 1.0 + rng.choice([-1.0, 1.0]) * 10 ** rng.uniform(-6.0, -1.0)
        v = (1.0 - 10 ** rng.uniform(-13.0, -0.01)) * ff.paper_critical_speed(k, xi)
        amplitude = ff.paper_amplitude(v, k, xi)
        best = ff._paper_flight_acceleration(amplitude, (v, k, xi))
        points = [amplitude * i / 32 for i in range(33)]
        signs = [1.0] + [slope(p, k, xi) for p in points[1:]]
        for lo, hi, before, after in zip(points, points[1:], signs, signs[1:]):
            if before > 0.0 and not after > 0.0:
                psi = brentq(slope, lo, hi, args=(k, xi), xtol=1e-16) if after < 0.0 else hi
                best = max(best, ff._paper_flight_acceleration(psi, (v, k, xi)))
        assert ff.paper_peak_acceleration(v, k, xi, amplitude) == pytest.approx(
            best, rel=1e-14), (k, xi, v)


@pytest.mark.slow
def test_the_closed_form_flight_time_is_exact_to_round_off_up_to_the_separatrix():
    """tau1 (P-O3) against mpmath at 40 digits (tanh-sinh on the same integral, its panels
    halving towards the turning point) for the kernel's own amplitude A, at 120 random
    designs: k in (0.05, 5), xi from 0.01 to 20, launch speeds from 0.1 v_crit to within
    1e-13 of it (the separatrix flag is at 64 ulp), a third of them within 1e-9; a quarter
    within 1e-1 of k = 1 (the saddle on the rotor's axis, X ~ 0 next to it) and a quarter
    with xi < 0.1 (rises L of 10-100). Within 2e-14 everywhere (seen: 2e-15). Nodes placed
    by s = pi/2 - t lost the digits of t next to the saddle: within 1e-12 of v_crit they
    were off by up to 2e-11. X = k^2 + 1 + 2k cos psi cancels next to a saddle at k ~ 1
    (1.2e-11 off); panels stopping at the separatrix's width alone left large rises, whose
    integrand's complex singularities (u = 0 at G = 2 pi i) sit close to the turning
    point, to one panel (1.4e-10 off at xi = 0.03, k = 2.5). The plain
    u(psi) = (v^2 + xi) e^(g0 - g(X)) - xi cancels near the turning point: a 96-point rule
    on it was off by up to 1.5e-10 (small swings); one 96-point rule on [0, pi/2] was off by
    1e-4 at 1e-11 of v_crit, where the integrand's near-singularity is narrower than its
    nodes' spacing."""
    import mpmath as mp

    mp.mp.dps = 40

    def exact(amplitude, k, xi):
        a, k, xi = mp.mpf(amplitude), mp.mpf(k), mp.mpf(xi)

        def g(x):
            return mp.log1p(xi * x) / xi ** 2 - x / xi
        turning = k * k + 1 + 2 * k * mp.cos(a)

        def integrand(s):
            x = k * k + 1 + 2 * k * mp.cos(a * mp.sin(s))
            return a * mp.cos(s) / mp.sqrt(xi * mp.expm1(g(turning) - g(x)))
        ends = [mp.pi / 2 - mp.pi / 2 * mp.mpf(2) ** -j for j in range(24)]
        return float(2 * mp.re(mp.quad(integrand, ends + [mp.pi / 2])))

    rng = np.random.default_rng(1103)
    checked = 0
    for j in range(120):
        k, xi = rng.uniform(0.05, 5.0), 10 ** rng.uniform(-2.0, 1.3)
        if j % 4 == 1:
            k = 1.0 + rng.choice([-1.0, 1.0]) * 10 ** rng.uniform(-6.0, -1.0)
        elif j % 4 == 2:
            xi = 10 ** rng.uniform(-2.0, -1.0)
        gap = 10 ** rng.uniform(-13.0, -9.0 if j % 3 == 0 else -0.05)
        v = (1.0 - gap) * ff.paper_critical_speed(k, xi)
        amplitude = ff.paper_amplitude(v, k, xi)
        tau = exact(amplitude, k, xi)
        assert ff.paper_half_period(v, k, xi, amplitude) == pytest.approx(
            tau, rel=2e-14), (k, xi, v)
        checked += 1
    assert checked == 120


def test_the_first_integrals_rises_are_exact_to_a_few_ulp():
    """log1p_excess(z) = z - log1p(z), the one piece of the paper model's rises (v_crit,
    the amplitude, the flight time, u along the flight), against mpmath at 50 digits: within
    4 ulp from z = -0.999 to 1e3 and down to |z| = 1e-12 (the plain difference lost 2/|z|
    ulp: 1e-10 of the value at z = 1e-6). v_crit (P4) at 300 random designs within
    4 ulp times (1 + the swing's rise L_crit): expm1 carries the rise's own rounding (up to
    L_crit ~ 350 at xi = 0.01, k = 5); the plain difference of g's terms was off by 3e-13."""
    import mpmath as mp

    mp.mp.dps = 50
    eps = 2.0 ** -52
    rng = np.random.default_rng(71)
    zs = np.concatenate([rng.uniform(-0.999, 1e3, 200),
                         rng.choice([-1.0, 1.0], 200) * 10 ** rng.uniform(-12.0, -0.1, 200)])
    for z in zs:
        exact = mp.mpf(z) - mp.log1p(mp.mpf(z))
        assert abs(ff.log1p_excess(z) - exact) <= 4 * eps * exact, z

    def g(x, xi):
        return mp.log1p(xi * x) / xi ** 2 - x / xi
    for _ in range(300):
        k, xi = rng.uniform(0.05, 5.0), 10 ** rng.uniform(-2.0, 1.3)
        full = g((mp.mpf(k) - 1) ** 2, mp.mpf(xi)) - g((mp.mpf(k) + 1) ** 2, mp.mpf(xi))
        exact = mp.sqrt(xi * mp.expm1(full))
        assert abs(ff.paper_critical_speed(k, xi) / exact - 1) <= 4 * eps * (1 + full), (k, xi)


def test_the_closed_form_amplitude_is_as_exact_as_the_rise_it_is_solved_from():
    """A (P-O2) at 200 random designs (k in (0.05, 5), a tenth within 1e-3 of k = 1 where
    the saddle sits on the rotor's axis; xi from 0.01 to 20; launch speeds from 0.1 v_crit
    to within 1e-13 of it) against mpmath's root of the first integral at 50 digits. Near
    the separatrix A is as sensitive as the rise that defines it, which a double holds to
    an ulp of the whole swing's rise: the error is bounded in units of eps A + the change
    of the exact A when the rise moves by that ulp. Within 4 units (seen: 2.2); the
    safeguarded Newton on X_A with A = acos(cos A) was off by up to 77 (1.6e-11 at
    moderate speeds, 2e-8 next to the separatrix)."""
    import mpmath as mp

    mp.mp.dps = 50
    eps = 2.0 ** -52

    def g(x, xi):
        return mp.log1p(xi * x) / xi ** 2 - x / xi

    def exact(rise, k, xi):
        x0, xs = (1 + k) ** 2, (k - 1) ** 2
        x = mp.findroot(lambda x: g(x, xi) - g(x0, xi) - rise, (xs, x0), solver="anderson")
        return mp.acos((x - k * k - 1) / (2 * k))

    rng = np.random.default_rng(11)
    for j in range(200):
        k, xi = rng.uniform(0.05, 5.0), 10 ** rng.uniform(-2.0, 1.3)
        if j % 10 == 0:
            k = 1.0 + rng.uniform(-1e-3, 1e-3)
        gap = 10 ** rng.uniform(-13.0, -9.0 if j % 3 == 0 else -0.05)
        v = (1.0 - gap) * ff.paper_critical_speed(k, xi)
        kk, xx = mp.mpf(k), mp.mpf(xi)
        rise = mp.log1p(mp.mpf(v) ** 2 / xx)
        full = g((kk - 1) ** 2, xx) - g((kk + 1) ** 2, xx)
        a = exact(rise, kk, xx)
        unit = eps * a + abs(exact(rise - eps * full, kk, xx) - a)
        assert abs(ff.paper_amplitude(v, k, xi) - a) <= 4 * unit, (k, xi, v)
