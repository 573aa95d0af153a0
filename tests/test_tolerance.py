"""Tolerance analysis of a picked design (issue 65 item 3): the design rebuilt from an
atlas gives the atlas's values bit for bit; a zero tolerance reproduces it; the quantiles
equal those of an independent plain loop over the same quasi-random points, one
``sweep.run`` per sample; a change-point linkage built to a tolerance is not a change
point unless the method's geometry_tol takes the band in. Bad input is one line."""

import math

import numpy as np
import pytest
import xarray as xr
from scipy.stats import qmc

import sweep
from tests.command_line import run_cli
from tests.test_chart_text import small_example


@pytest.fixture(scope="module")
def limits(tmp_path_factory):
    path = tmp_path_factory.mktemp("tolerance") / "limits.nc"
    sweep.run(small_example("crank_rocker_limits", 10), path)
    return path


def ok_designs(path, count, seed=65):
    ds = xr.open_dataset(path)
    ok = np.flatnonzero(ds.status.values.ravel() == 0)
    return ds, np.random.default_rng(seed).choice(ok, count, replace=False)


def test_a_design_rebuilt_from_the_atlas_and_a_zero_tolerance_give_its_values(limits):
    ds, picks = ok_designs(limits, 6)
    for design in picks:
        at = dict(zip(ds.status.dims, np.unravel_index(int(design), ds.status.shape)))
        document = sweep.design_spec(limits, design=int(design))
        assert document["fixed"]["type"] == "general" or document["grid"].get("type") \
            == ["general"]
        result = sweep.tolerance(document, {"crank_length": 0.0, "omega1": "0%"},
                                 samples=8)
        for name in result.output.values:
            own = float(ds[str(name)].isel(at))
            assert float(result.nominal.sel(output=name)) == own, name
            assert np.all(result.quantiles.sel(output=name).values == own), name
        assert list(result.event.values) == ["status = ok", "meets the requirements"] or \
            list(result.event.values) == ["status = ok"]


def test_quantiles_equal_a_plain_loop_over_the_same_points(limits):
    ds, (design,) = ok_designs(limits, 1, seed=7)
    document = sweep.design_spec(limits, design=int(design))
    nominal = {**document["fixed"], **{k: v[0] for k, v in document["grid"].items()}}
    tolerances = {"crank_length": 2e-4, "rocker_inertia": "10%", "lambda2": 1e-3}
    samples, seed = 64, 11
    result = sweep.tolerance(document, tolerances, samples=samples, seed=seed,
                             method={"geometry_tol": 1e-3})
    names = list(tolerances)
    half = [2e-4, 0.1 * nominal["rocker_inertia"], 1e-3]
    points = qmc.Sobol(3, scramble=True, seed=seed).random_base2(int(math.log2(samples)))
    rows = []
    for u in points:  # one run per sample, its spec written out by hand
        fixed = dict(nominal)
        for name, h, x in zip(names, half, u):
            fixed[name] = nominal[name] - h + 2 * h * x
        key = next(iter(fixed))
        one = sweep.run({"mechanism": "crank_rocker", "grid": {key: [fixed.pop(key)]},
                         "fixed": fixed, "outputs": list(result.output.values),
                         "method": {"geometry_tol": 1e-3}})
        rows.append([float(one[str(o)].values.ravel()[0]) for o in result.output.values])
    rows = np.array(rows)
    for k, name in enumerate(result.output.values):
        column = rows[:, k]
        if np.isfinite(column).any():
            expected = np.nanquantile(column, result.probability_level.values)
            np.testing.assert_allclose(result.quantiles.sel(output=name).values, expected,
                                       rtol=1e-12, atol=0, err_msg=str(name))


def test_a_change_point_linkage_built_to_a_tolerance(limits):
    ds, picks = ok_designs(limits, 3, seed=3)
    for design in picks:
        document = sweep.design_spec(limits, design=int(design))
        loose = sweep.tolerance(document, {"lambda2": 1e-4}, samples=64)
        words = {str(e) for e in loose.event.values}
        assert "status = ok" not in words  # the exact condition does not survive
        taken_in = sweep.tolerance(document, {"lambda2": 1e-4}, samples=64,
                                   method={"geometry_tol": 1e-3})
        assert float(taken_in.probability.sel(event="status = ok")) == 1.0


def test_bad_input_is_one_line_and_writes_nothing(limits, tmp_path, capsys):
    document = sweep.design_spec(limits, design=int(ok_designs(limits, 1)[1][0]))
    for tolerances, kwargs, match in (
            ({"nope": 1e-4}, {}, "tolerances.nope: not a parameter"),
            ({"type": 1}, {}, "categorical"),
            ({"crank_length": 1.0}, {}, "outside crank_length's domain"),
            ({"crank_length": -1e-4}, {}, ">= 0"),
            ({"crank_length": "x%"}, {}, "percentage"),
            ({"crank_length": 1e-4}, {"samples": 100}, "power of two"),
            ({}, {}, "at least one")):
        with pytest.raises(sweep.UserError, match=match):
            sweep.tolerance(document, tolerances, **kwargs)
    wide = {**document, "grid": {"crank_length": [0.1, 0.2]}}
    with pytest.raises(sweep.UserError, match="one point"):
        sweep.tolerance(wide, {"omega1": 1.0})
    for args in (["tolerance", limits, "--design", "0", "--tol", "nope=1", "-o",
                  tmp_path / "t.nc"],
                 ["tolerance", limits, "--design", "99999999", "--tol", "omega1=1", "-o",
                  tmp_path / "t.nc"],
                 ["tolerance", limits, "--tol", "omega1", "-o", tmp_path / "t.nc"]):
        code, out, err = run_cli(capsys, *args)
        assert code == 2 and err.count("\n") == 1, (args, err)
    assert list(tmp_path.iterdir()) == []


def test_the_change_point_band_edges_are_where_geometry_tol_puts_them():
    """A type c linkage (lambda0 + 1 = lambda2 + lambda3) with lambda2 moved so that the
    identity misses by a fraction f of geometry_tol x (the links' sum, l1 = 1): inside the
    band (f = 0.9) a change point with its impact, just outside (f = 1.1) not one, on
    either side: one side locks at the node, the other passes it without the switch."""
    lam0, lam3 = 4.2, 2.3
    lam2 = lam0 + 1.0 - lam3
    tol = 1e-4
    total = 1.0 + lam0 + lam2 + lam3
    statuses = {}
    for f in (-1.1, -0.9, 0.9, 1.1):
        shifted = lam2 + f * tol * total / (1.0 - f * tol)  # the sum moves with lambda2
        atlas = sweep.decode(sweep.run({
            "mechanism": "crank_rocker", "grid": {"lambda2": [shifted]},
            "fixed": {"type": "general", "lambda0": lam0, "lambda3": lam3},
            "method": {"geometry_tol": tol}, "outputs": ["impact_speed"]}))
        statuses[f] = str(atlas.status.values.ravel()[0])
    assert statuses[-0.9] == statuses[0.9] == "ok", statuses
    outside = {statuses[-1.1], statuses[1.1]}
    assert "ok" not in outside and len(outside) == 2, statuses


@pytest.mark.parametrize("defect", [1e-6, 1e-8])
def test_just_outside_the_band_the_linkage_does_what_the_guide_derives(defect):
    """docs/guide/robust.md, "Just outside the band": a type c four-bar (l1 = 1) whose
    coupler-rocker pair is longer than lambda0 + 1 by e passes the node phi1 = pi on one
    smooth branch, u31 = [1 + s gamma x / sqrt(x^2 + x_e^2)] / (1 + lambda0) with x_e =
    sqrt(2 (1 + lambda0) e / lambda0); a pair shorter by e cannot close for |x| < x_e. Checked
    on the kernels' own loop closure against that asymptotic form, to O(x_e)."""
    from kernels.fourbar import vector_kinematics

    lam0, lam3 = 4.2, 2.3
    x_e = math.sqrt(2.0 * (1.0 + lam0) * defect / lam0)
    lam2 = lam0 + 1.0 - lam3 + defect
    gamma = math.sqrt(lam0 * lam2 / lam3)
    low, high = (1.0 - gamma) / (1.0 + lam0), (1.0 + gamma) / (1.0 + lam0)
    for sigma in (1.0, -1.0):
        node = vector_kinematics(math.pi, lam0, 1.0, lam2, lam3, sigma)
        # the rocker's velocity reversal, done by the linkage over |x| ~ x_e
        assert abs(node[9]) == pytest.approx(gamma / ((1.0 + lam0) * x_e), rel=20 * x_e)
        assert node[7] == pytest.approx(1.0 / (1.0 + lam0), abs=20 * x_e)
        # far from it (|x| = 30 x_e), the exact change point's motion on the same branch:
        # the rocker reversed, as the impact reverses it, but by the links over |x| ~ x_e
        exact = lam0 + 1.0 - lam3
        sides = []
        for x in (-30.0 * x_e, 30.0 * x_e):
            u = vector_kinematics(math.pi + x, lam0, 1.0, lam2, lam3, sigma)[7]
            ref = vector_kinematics(math.pi + x, lam0, 1.0, exact, lam3, sigma)[7]
            assert u == pytest.approx(ref, abs=gamma / 900.0 + 20 * x_e), (x, u, ref)
            sides.append(u)
        assert sorted(sides) == pytest.approx([low, high], abs=0.1 * gamma)
        assert low < 0.0 < high  # the two sides' values: the rocker reverses
        for x in (0.3, 3.0):  # the tanh-like passage
            u = vector_kinematics(math.pi + x * x_e, lam0, 1.0, lam2, lam3, sigma)[7]
            shape = (1.0 + math.copysign(1.0, node[9]) * gamma * x / math.sqrt(x * x + 1.0)
                     ) / (1.0 + lam0)
            assert u == pytest.approx(shape, abs=20 * x_e)
    short = lam0 + 1.0 - lam3 - defect  # locks: the dyad cannot reach |DB| near the node
    for x, closes in ((0.9, False), (1.1, True)):
        u31 = vector_kinematics(math.pi + x * x_e, lam0, 1.0, short, lam3, 1.0)[7]
        assert math.isfinite(u31) == closes, (x, u31)
