"""Families of curves (issue 64 item 4's line chart): every curve drawn is the atlas's
slice at the nearest value of its family's axis, with a gap (NaN) where the design has no
value; a grid axis neither drawn nor held is refused, in one line."""

import numpy as np
import pytest

import sweep
from tests.command_line import run_cli


@pytest.fixture(scope="module")
def balancer():
    return sweep.run({"mechanism": "spring_balancer",
                      "grid": {"f": {"start": 0.3, "stop": 2.0, "num": 35},
                               "r": [0.5, 0.75, 1.0, 1.5], "eta": [0.02, 0.05]}})


def test_each_curve_is_the_atlas_slice_at_its_value(balancer):
    y = "moment_invariant_peak_balanced"
    fig = sweep.lines(balancer, "f", y, by="r", values=[0.55, 1.4], at={"eta": 0.05})
    curves = fig.axes[0].get_lines()
    assert len(curves) == 2
    for line, r in zip(curves, (0.5, 1.5)):
        expected = np.degrees(balancer[y].sel(r=r, eta=0.05).values)
        np.testing.assert_array_equal(line.get_xdata(), balancer.f.values)
        np.testing.assert_array_equal(line.get_ydata(), expected)
        assert f"{r:g}" in line.get_label()


def test_a_design_without_a_value_is_a_gap(tmp_path):
    atlas = sweep.run({"mechanism": "crank_rocker",
                       "grid": {"R": [0.1, 0.2, 0.3, 0.4], "largest_link": [1.3, 2.0, 4.0]}})
    fig = sweep.lines(atlas, "largest_link", "impact_speed", by="R")
    for line, r in zip(fig.axes[0].get_lines(), atlas.R.values):
        status = atlas.status.sel(R=r).values
        assert np.array_equal(np.isnan(line.get_ydata()), status != 0)


def test_bad_input_is_one_line(balancer, tmp_path, capsys):
    for kwargs, match in (({"x": "nope", "y": "swing"}, "x: 'nope'"),
                          ({"x": "f", "y": "nope"}, "y: 'nope'"),
                          ({"x": "f", "y": "swing", "by": "r"}, "at: hold eta"),
                          ({"x": "f", "y": "swing", "by": "f"}, "by: 'f'")):
        with pytest.raises(sweep.UserError, match=match):
            sweep.lines(balancer, **kwargs)
    path = tmp_path / "b.nc"
    sweep.run({"mechanism": "spring_balancer", "grid": {"f": [0.5, 1.0], "r": [1.0, 1.2]}}, path)
    code, out, err = run_cli(capsys, "lines", path, "--x", "r", "--y", "swing", "--by", "f", "-o",
                             tmp_path / "l.png")
    assert code == 0, err
    code, out, err = run_cli(capsys, "lines", path, "--x", "f", "--y", "nope", "-o",
                             tmp_path / "m.png")
    assert code == 2 and err.count("\n") == 1 and not (tmp_path / "m.png").exists()
