"""Sensitivity with failures counted (issue 65 item 2), against closed forms and a direct
count: a crank-rocker with crank length l1 ~ U(a1, b1) and crank speed omega1 ~ U(a2, b2)
independent has a blow rate of omega1 alone (S = 1 for omega1, 0 for l1) and an impact speed
c l1 omega1, a product whose indices have closed forms; the probability of a status equals
its share of a fine uniform grid of the box; a status indicator has no index on an input
it does not depend on."""

import numpy as np
import pytest

import sweep
from tests.command_line import run_cli

BASE = {"mechanism": "crank_rocker",
        "fixed": {"R": 0.3, "largest_link": 3.0, "type": "a", "rocker_inertia": 0.05},
        "outputs": ["impact_speed", "blow_rate", "blow_energy"]}


def product_indices(a1, b1, a2, b2):
    """S1 and ST of Y = X1 X2 with X1 ~ U(a1, b1), X2 ~ U(a2, b2) independent."""
    m1, m2 = (a1 + b1) / 2, (a2 + b2) / 2
    v1, v2 = (b1 - a1) ** 2 / 12, (b2 - a2) ** 2 / 12
    variance = (v1 + m1 ** 2) * (v2 + m2 ** 2) - (m1 * m2) ** 2
    first = np.array([v1 * m2 ** 2, v2 * m1 ** 2]) / variance
    total = np.array([v1 * m2 ** 2 + v1 * v2, v2 * m1 ** 2 + v1 * v2]) / variance
    return first, total


def close(value, exact, conf):
    return abs(value - exact) <= max(3 * conf, 0.02)


def test_indices_equal_the_closed_forms_of_a_product_and_of_one_input():
    rng = np.random.default_rng(65)
    a1, a2 = rng.uniform(0.04, 0.08), rng.uniform(8.0, 20.0)
    b1, b2 = a1 + rng.uniform(0.02, 0.1), a2 + rng.uniform(5.0, 30.0)
    ds = sweep.sensitivity(BASE, {"crank_length": (a1, b1), "omega1": (a2, b2)},
                           samples=4096, seed=3)
    first, total = product_indices(a1, b1, a2, b2)
    speed = ds.sel(quantity="impact_speed")
    for k in range(2):
        assert close(speed.first_order.values[k], first[k], speed.first_order_conf.values[k])
        assert close(speed.total.values[k], total[k], speed.total_conf.values[k])
    rate = ds.sel(quantity="blow_rate")
    np.testing.assert_allclose(rate.first_order.values, [0.0, 1.0], atol=0.02)
    np.testing.assert_allclose(rate.total.values, [0.0, 1.0], atol=0.02)
    assert int(speed.rows_kept) == 4096 and float(ds.probability.sel(event="status = ok")) == 1


def test_the_probability_of_a_status_is_its_share_of_a_fine_grid_and_ignores_other_inputs():
    box = {"R": (0.1, 0.4), "largest_link": (1.3, 2.6), "omega1": (10.0, 40.0)}
    fixed = {"type": "a", "crank_length": 0.1}
    document = {"mechanism": "crank_rocker", "fixed": fixed, "outputs": ["impact_speed"]}
    ds = sweep.sensitivity(document, box, samples=4096, seed=1)
    n = 300  # a uniform grid of cell midpoints: the share of the box by direct count
    grid = {name: (low + (np.arange(n) + 0.5) * (high - low) / n).tolist()
            for name, (low, high) in list(box.items())[:2]}
    atlas = sweep.decode(sweep.run({"mechanism": "crank_rocker", "grid": grid,
                                    "fixed": {**fixed, "omega1": 20.0},
                                    "outputs": ["impact_speed"]}))
    for event in ds.event.values:
        word = str(event).removeprefix("status = ")
        share = float((atlas.status == word).mean())
        p, low, high = (float(ds[v].sel(event=event)) for v in
                        ("probability", "probability_low", "probability_high"))
        assert abs(p - share) <= 1.5 * (high - low), (word, p, share)
    failing = [q for q in ds.quantity.values if str(q).startswith("P(status")]
    assert failing
    for q in failing:
        row = ds.sel(quantity=q, input="omega1")
        assert abs(float(row.total)) <= max(3 * float(row.total_conf), 0.01), q
    speed = ds.sel(quantity="impact_speed")
    assert 0 < int(speed.rows_kept) < 4096  # conditional on the designs that exist


def test_the_same_seed_gives_the_same_study_and_a_file_and_chart(tmp_path):
    inputs = {"crank_length": (0.05, 0.1), "omega1": ("norm", 30.0, 3.0)}
    one = sweep.sensitivity(BASE, inputs, samples=256, seed=7, path=tmp_path / "s.nc",
                            chart=tmp_path / "s.png")
    two = sweep.sensitivity(BASE, inputs, samples=256, seed=7)
    for name in ("first_order", "total", "probability"):
        np.testing.assert_array_equal(one[name].values, two[name].values)
    assert (tmp_path / "s.nc").is_file() and (tmp_path / "s.png").is_file()


def test_bad_input_is_one_line_and_exit_2(tmp_path, capsys):
    cases = [({"nope": (0, 1), "omega1": (10, 20)}, {}, "inputs.nope: not a parameter"),
             ({"crank_length": (-0.1, 0.1), "omega1": (10, 20)}, {},
              "inputs.crank_length: -0.1 is outside"),
             ({"R": (0.1, 0.3), "omega1": (10, 20)}, {}, "inputs.R: also in fixed"),
             ({"type": ("a", "c"), "omega1": (10, 20)}, {}, "inputs.type"),
             ({"omega1": (10, 20)}, {}, "inputs: at least two"),
             ({"crank_length": (0.1, 0.05), "omega1": (10, 20)}, {}, "must be below"),
             ({"crank_length": ("weibull", 1, 2), "omega1": (10, 20)}, {}, "unknown dist"),
             ({"crank_length": (0.05, 0.1), "omega1": (10, 20)}, {"samples": 1000},
              "power of two"),
             ({"crank_length": (0.05, 0.1), "omega1": (10, 20)}, {"samples": 2 ** 30},
              "samples"),
             ({"crank_length": (0.05, 0.1), "omega1": (10, 20)}, {"outputs": ["nope"]},
              "outputs: 'nope'")]
    for inputs, kwargs, match in cases:
        with pytest.raises(sweep.UserError, match=match):
            sweep.sensitivity(BASE, inputs, **kwargs)
    with pytest.raises(sweep.UserError, match="grid.largest_link"):
        sweep.sensitivity({**BASE, "grid": {"largest_link": [2, 3]}},
                          {"crank_length": (0.05, 0.1), "omega1": (10, 20)})
    spec = tmp_path / "s.toml"
    spec.write_text('mechanism = "crank_rocker"\n[grid]\nR = [0.1, 0.3]\n'
                    'largest_link = [2.0, 3.0]\ntype = ["a", "b"]\n')
    code, out, err = run_cli(capsys, "sensitivity", spec, "-o", tmp_path / "s.nc")
    assert code == 2 and err.count("\n") == 1 and "grid.type" in err, err
    assert not (tmp_path / "s.nc").exists()
