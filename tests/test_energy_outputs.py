"""Energy per blow, blow rate and outputs in SI for the mechanisms with a prescribed crank
speed (issue 38, item 2): each computed only where asked for, each against a closed form
written here, and the crank-rocker's against the impact machine's at the same speed."""

import math

import numpy as np
import pytest

import sweep


def test_the_crank_rockers_energy_per_blow_is_the_rockers_kinetic_energy_at_impact():
    """0.5 J_D3 (u31- omega1)^2 with u31- = (1 + gamma)/(1 - lambda0) of [CR] (type a,
    Rk = -R), one blow a crank turn."""
    rng = np.random.default_rng(50)
    r = sorted(rng.uniform(0.1, 0.45, 6).round(6).tolist())  # the atlas's axis increases
    atlas = sweep.run({"mechanism": "crank_rocker", "grid": {"R": r},
                       "fixed": {"largest_link": 4.0, "rocker_inertia": 0.06, "omega1": 25.0},
                       "outputs": ["blow_energy", "blow_rate"]})
    for k, rk in enumerate(r):
        g2 = ((1 + rk) / (1 - rk)) ** 2
        lam0 = g2 * 5.0 / (g2 + 4.0)
        u31 = (1 + math.sqrt(g2)) / (1 - lam0)
        assert atlas["blow_energy"].values[k] == pytest.approx(0.5 * 0.06 * (u31 * 25) ** 2,
                                                               rel=1e-13)
    np.testing.assert_allclose(atlas["blow_rate"].values, 60 * 25 / (2 * math.pi), rtol=1e-15)


def test_the_crank_rockers_energy_per_blow_is_the_machines_at_the_machines_speed():
    """The impact machine's blow_energy equals crank_rocker's at the machine's speed before
    the blow, with the rocker's inertia about D (two mechanisms, one quantity)."""
    machine = sweep.run({"mechanism": "impact_machine", "grid": {"R": [0.2, 0.3, 0.4]},
                         "outputs": ["blow_energy", "crank_speed_before_blow"]})
    s3 = 0.11 / (0.1 * 1.470840480274443)  # the default centroid, a fraction of l3
    for k, r in enumerate([0.2, 0.3, 0.4]):
        g2 = ((1 + r) / (1 - r)) ** 2
        l3 = 0.1 * 2.5 * 3.5 / (g2 + 2.5)  # type a, lambda2 = 2.5, synthesised for r
        j_d3 = 8 * 0.15 ** 2 / 12 + 0.02 + 8.0 * ((s3 * l3) ** 2 + 0.015 ** 2)
        w = float(machine["crank_speed_before_blow"].values[k])
        cr = sweep.run({"mechanism": "crank_rocker", "grid": {"R": [r]},
                        "fixed": {"largest_link": 2.5, "rocker_inertia": j_d3, "omega1": w},
                        "outputs": ["blow_energy"]})
        assert cr["blow_energy"].values[0] == pytest.approx(
            machine["blow_energy"].values[k], rel=1e-12)


def test_the_six_links_two_blows_and_their_rate():
    atlas = sweep.run({"mechanism": "six_link", "grid": {"beta": [0.0, 0.6]},
                       "fixed": {"rocker_inertia": 0.1, "omega1": 30.0},
                       "outputs": ["transfer_impact_1", "transfer_impact_2", "blow_energy_1",
                                   "blow_energy_2", "blow_rate"]})
    assert (atlas["status"].values == 0).all()  # asking for them changes no status
    for n in (1, 2):
        np.testing.assert_allclose(atlas[f"blow_energy_{n}"].values,
                                   0.5 * 0.1 * (atlas[f"transfer_impact_{n}"].values * 30) ** 2,
                                   rtol=1e-15)
    np.testing.assert_allclose(atlas["blow_rate"].values, 60 * 30 / (2 * math.pi), rtol=1e-15)


def test_the_pendulums_energy_per_blow_and_rate_at_the_closed_form():
    """Paper model on the rotor stop: V* = 2 (1 + k) omega1 l2 / (1 - R), blow energy
    m V*^2 / 2; at constant rotor speed the blows come every impact_interval of rotor angle
    (1/(2 pi) of them a turn at once a turn)."""
    r = [0.0, 0.02, 0.04]
    atlas = sweep.run({"mechanism": "rotary_pendulum", "grid": {"R": r},
                       "fixed": {"model": "paper", "k": 2.0, "xi": 4.0, "omega1": 40.0,
                                 "striker_mass": 1.5},
                       "outputs": ["impact_speed", "impact_interval", "blow_energy",
                                   "blow_rate"]})
    for k, rk in enumerate(r):
        v = 2 * 3.0 * 40.0 * 0.04 / (1 - rk)
        assert atlas["blow_energy"].values[k] == pytest.approx(0.5 * 1.5 * v * v, rel=1e-13)
        assert atlas["blow_rate"].values[k] == pytest.approx(
            60 * 40.0 / atlas["impact_interval"].values[k], rel=1e-15)


def test_the_balancers_stiffnesses_and_moments_in_si():
    atlas = sweep.run({"mechanism": "spring_balancer", "grid": {"f": [0.8, 1.25], "r": [0.5, 1.0]},
                       "fixed": {"driven_inertia": 2.0, "crank_speed": 30.0},
                       "outputs": ["moment_invariant_peak_free", "moment_invariant_peak_balanced",
                                   "spring_stiffness", "shaft_stiffness", "moment_peak_free",
                                   "moment_peak_balanced"]})
    plain = sweep.run({"mechanism": "spring_balancer", "grid": {"f": [0.8, 1.25], "r": [0.5, 1.0]}})
    np.testing.assert_array_equal(atlas["status"].values, plain["status"].values)
    f, r = np.meshgrid(atlas["f"].values, atlas["r"].values, indexing="ij")
    spring = 2.0 * (30.0 / f) ** 2
    np.testing.assert_allclose(atlas["spring_stiffness"].values, spring, rtol=1e-15)
    np.testing.assert_allclose(atlas["shaft_stiffness"].values, spring / r ** 2, rtol=1e-15)
    for kind in ("free", "balanced"):
        np.testing.assert_allclose(atlas[f"moment_peak_{kind}"].values,
                                   spring / r ** 2 * atlas[f"moment_invariant_peak_{kind}"].values,
                                   rtol=1e-15)


@pytest.mark.parametrize("mechanism, outputs, needs", [
    ("crank_rocker", ["blow_energy"], "rocker_inertia"),
    ("six_link", ["blow_energy_1"], "rocker_inertia"),
    ("rotary_pendulum", ["blow_energy"], "striker_mass"),
    ("spring_balancer", ["moment_peak_free"], "driven_inertia"),
])
def test_an_energy_output_without_its_mass_is_one_line_and_none_costs_unless_asked(
        mechanism, outputs, needs):
    grid = {"crank_rocker": {"largest_link": [3.0]}, "six_link": {"beta": [0.0]},
            "rotary_pendulum": {"R": [0.0]}, "spring_balancer": {"f": [1.0]}}[mechanism]
    with pytest.raises(sweep.UserError, match=f"^{needs}: "):
        sweep.Sweep.from_dict({"mechanism": mechanism, "grid": grid, "outputs": outputs})
    default = sweep.Sweep.from_dict({"mechanism": mechanism, "grid": grid})
    assert not set(default.outputs) & {"blow_energy", "blow_energy_1", "blow_rate",
                                       "moment_peak_free", "spring_stiffness"}
