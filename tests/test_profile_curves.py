"""Several designs in one profile chart (issue 64 item 4: [CR] Fig. 2's three mechanisms)
and one profile against another ([SIX] Fig. 6): each curve is the atlas's own profile of
the design it names, and bad choices are one line before anything is drawn."""

import numpy as np
import pytest

import sweep
from sweep.errors import UserError

FIG2 = ("(lambda0 == 2 and lambda2 == 4 and lambda3 == 3) or "
        "(lambda0 == 2 and lambda2 == 3 and lambda3 == 4) or "
        "(lambda0 == 4 and lambda2 == 3 and lambda3 == 2)")


@pytest.fixture(scope="module")
def fig2():
    spec = {"mechanism": "crank_rocker",
            "grid": {"lambda0": [2.0, 4.0], "lambda2": [3.0, 4.0], "lambda3": [2.0, 3.0, 4.0]},
            "fixed": {"type": "general"}, "method": {"profile_points": 90}}
    return sweep.decode(sweep.run(spec))


def test_every_matching_design_is_one_curve_of_its_own_profile(fig2, tmp_path):
    fig = sweep.profile(fig2, "transfer_ratio", FIG2, every=True, path=tmp_path / "f.png")
    lines = fig.axes[0].get_lines()
    assert len(lines) == 3
    for line in lines:
        text = line.get_label()
        lam = [float(part.split("= ")[1]) for part in text.split(", ")]
        design = fig2.sel(lambda0=lam[0], lambda2=lam[1], lambda3=lam[2])
        np.testing.assert_array_equal(line.get_ydata(), design.transfer_ratio.values)
        np.testing.assert_allclose(line.get_xdata(), np.degrees(fig2.crank_angle.values))
    # the paper's kinematic restitutions of its three mechanisms
    rk = sorted(float(fig2.restitution_kinematic.sel(lambda0=a, lambda2=b, lambda3=c))
                for a, b, c in ((2, 4, 3), (2, 3, 4), (4, 3, 2)))
    assert rk == pytest.approx([-0.420204, -0.240408, -0.101021], abs=1e-6)
    assert (tmp_path / "f.png").stat().st_size > 0


def test_each_value_of_an_axis_is_one_curve(fig2):
    fig = sweep.profile(fig2, "rocker_angle", "lambda0 == 2 and lambda2 == 4", each="lambda3")
    assert len(fig.axes[0].get_lines()) == 3
    for line, lam3 in zip(fig.axes[0].get_lines(), fig2.lambda3.values):
        y = np.degrees(fig2.rocker_angle.sel(lambda0=2.0, lambda2=4.0, lambda3=lam3).values)
        np.testing.assert_allclose(line.get_ydata(), y, equal_nan=True)


def test_one_profile_against_another():
    six = sweep.run({"mechanism": "six_link", "grid": {"beta": [0.0]},
                     "outputs": ["rocker_angle", "link3_angle"],
                     "method": {"profile_points": 60}})
    fig = sweep.profile(six, "rocker_angle", against="link3_angle")
    line = fig.axes[0].get_lines()[0]
    np.testing.assert_allclose(line.get_xdata(), np.degrees(six.link3_angle.values[0]))
    assert "against link 3 angle" in fig.get_suptitle()


@pytest.mark.parametrize("kwargs, field", [
    (dict(each="lambda9"), "each:"), (dict(against="status"), "against:"),
    (dict(every=True, where="lambda0 > 100"), "where:")])
def test_bad_choices_are_one_line(fig2, kwargs, field):
    where = kwargs.pop("where", None)
    with pytest.raises(UserError, match=field):
        sweep.profile(fig2, "transfer_ratio", where, **kwargs)
