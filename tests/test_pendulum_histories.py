"""The rotary pendulum's steady cycle as time histories ([RP] Fig. 3): psi, psi' and psi'' of the paper and rigid models on the rotor stop, against a
SciPy integration (DOP853 at rtol 1e-12) of the same equation from the atlas's own steady
state, the impact that opens the cycle, in physical time; their peak against the atlas's
acceleration_peak; none where the model or tool has no such cycle."""

import json
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import sweep

PROFILES = ["time", "rotor_angle", "swing_angle", "swing_rate", "swing_acceleration"]


def equation(model, k, second, w):
    """psi'' in physical time: [RP]'s equation (P1-P2) with xi, or the rigid pendulum with
    kappa, at rotor speed w."""
    def paper(t, y):
        x = k * k + 1 + 2 * k * math.cos(y[0])
        return [y[1], -k * x / (1 + second * x) * (y[1] ** 2 + second * w * w)
                * math.sin(y[0])]

    def rigid(t, y):
        return [y[1], -second * k * w * w * math.sin(y[0])]
    return paper if model == "paper" else rigid


@pytest.mark.parametrize("model", ["paper", "rigid"])
def test_the_histories_are_the_flight_from_the_steady_impact(model):
    rng = np.random.default_rng({"paper": 1, "rigid": 2}[model])
    ks = sorted(rng.uniform(1.2, 2.6, 3).round(6).tolist())
    second = "xi" if model == "paper" else "kappa"
    value = 4.0 if model == "paper" else 2.0  # rigid: kappa > (1+k)^2/(4k) to swing back
    ds = sweep.decode(sweep.run({
        "mechanism": "rotary_pendulum", "grid": {"k": ks, "R": [0.0, 0.05]},
        "fixed": {"model": model, "omega1": float(rng.uniform(20, 80)), second: value},
        "method": {"profile_points": 64}}))
    checked = 0
    for i, k in enumerate(ds.k.values):
        for j, r in enumerate(ds.R.values):
            point = ds.isel(k=i, R=j)
            if str(point.status.values) != "ok":
                assert np.isnan(point.swing_angle.values).all()
                continue
            w = json.loads(ds.attrs["spec"])["fixed"]["omega1"]
            launch = -(1 + k) * (1 + r) / (1 - r) * w  # the closed form's v*, away from the stop
            times = point.time.values
            sol = solve_ivp(equation(model, k, value, w), (0.0, times[-1]), [0.0, launch],
                            method="DOP853", rtol=1e-12, atol=1e-14, t_eval=times)
            swing = sol.y[0]
            rate = sol.y[1]
            accel = np.array([equation(model, k, value, w)(0, y)[1] for y in sol.y.T])
            amplitude = float(point.amplitude)
            np.testing.assert_allclose(point.swing_angle.values, swing, atol=1e-8 * amplitude)
            np.testing.assert_allclose(point.swing_rate.values, rate, atol=1e-8 * abs(launch))
            peak = float(point.acceleration_peak)
            np.testing.assert_allclose(point.swing_acceleration.values, accel, atol=1e-8 * peak)
            # the sampled peak approaches the closed form's from below; the cycle closes
            sampled = np.abs(point.swing_acceleration.values).max()
            assert sampled <= peak * (1 + 1e-9) and sampled >= 0.95 * peak
            np.testing.assert_allclose(point.rotor_angle.values, w * times, rtol=1e-12)
            np.testing.assert_allclose(times[-1] + times[0],
                                       float(point.impact_interval) / w, rtol=1e-12)
            assert abs(point.swing_angle.values[-1]) < abs(launch / w) * 2 * times[0] * w
            checked += 1
    assert checked >= 4


def test_histories_on_both_tools_but_none_through_a_chatter():
    """Every steady cycle has its histories (the blade's: tests/test_pendulum_cycle_walk.py)
    but one that accumulates a chatter: its infinitely many bounces are the core's
    closed-form tail (a chatter design of tests/test_pendulum_models.py)."""
    ds = sweep.decode(sweep.run({
        "mechanism": "rotary_pendulum", "grid": {"tool": ["rotor_stop", "lab_window"]},
        "fixed": {"k": 2.0}, "method": {"profile_points": 8}}))
    stop, blade = ds.sel(tool="rotor_stop"), ds.sel(tool="lab_window")
    assert str(blade.status.values) == "ok"
    assert np.isfinite(stop.swing_angle.values).all()
    assert np.isfinite(blade.swing_angle.values).all()
    chatter = sweep.decode(sweep.run({
        "mechanism": "rotary_pendulum", "grid": {"k": [0.926]},
        "fixed": {"model": "rigid", "tool": "lab_window", "kappa": 25.32, "R": 0.363,
                  "tool_window": 1.463},
        "outputs": ["regime", "swing_angle"], "method": {"profile_points": 8}})).isel(k=0)
    assert str(chatter.status.values) == "ok" and str(chatter.regime.values) == "chatter"
    assert np.isnan(chatter.swing_angle.values).all()


def test_without_profile_points_the_atlas_has_no_histories():
    ds = sweep.run({"mechanism": "rotary_pendulum", "grid": {"k": [2.0]}})
    assert not set(PROFILES) & set(ds.data_vars)


def test_the_paper_model_redraws_fig_3_with_table_1s_openings():
    """[RP] Fig. 3 (k = 1.5, 2, 2.5 at omega1 = 40): the swing reaches Table 1's amplitudes
    (1.920, 1.792, 1.724 rad, to their printed 1 %) and closes at its rotor angles of the
    first opening (178, 143, 120 degrees, within 1 degree: the paper prints whole degrees,
    truncated); the largest |psi''| of a fine history is acceleration_peak to 1e-4."""
    ds = sweep.decode(sweep.run({
        "mechanism": "rotary_pendulum", "grid": {"k": [1.5, 2.0, 2.5]},
        "fixed": {"omega1": 40.0}, "method": {"profile_points": 2000}}))
    for i, (amplitude, opening) in enumerate(((1.920, 178), (1.792, 143), (1.724, 120))):
        point = ds.isel(k=i)
        angles = point.rotor_angle.values
        closes = math.degrees(angles[-1] + angles[0])  # the cycle's end: a cell beyond
        assert abs(closes - opening) < 1.0, (closes, opening)
        assert abs(point.swing_angle.values).max() == pytest.approx(amplitude, rel=0.01)
        assert abs(point.swing_acceleration.values).max() == pytest.approx(
            float(point.acceleration_peak), rel=1e-4)
