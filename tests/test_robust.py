"""Robust requirements and objectives over a band (issue 65 item 1): the reduction equals
numpy's least and greatest over the band's samples, its feasibility an independent check
of every point; the refined extremes between samples equal a dense sampling of 10^4 points
of the band; band ends off the grid are computed; a front ranks by the robust values."""

import json

import numpy as np
import pytest
import xarray as xr

import sweep
from tests.command_line import run_cli

MACHINE = {"mechanism": "impact_machine",
           "grid": {"R": {"start": 0.05, "stop": 0.4, "num": 8},
                    "flywheel_inertia": [1.0, 4.0, 16.0], "m3": [4.0, 8.0]},
           "fixed": {"type": "a", "largest_link": 2.5, "design_restitution": 0.3},
           "requirements": {"blow_energy": ">= 270", "motor_torque_peak": "<= 300"}}


@pytest.fixture(scope="module")
def machine(tmp_path_factory):
    path = tmp_path_factory.mktemp("robust") / "machine.nc"
    sweep.run(MACHINE, path)
    return path


def test_the_reduction_is_numpys_over_the_samples_and_feasibility_every_points(machine):
    ds = xr.open_dataset(machine)
    band = ds.sel(R=slice(0.05, 0.3 + 1e-12))
    result = sweep.robust(machine, {"R": (0.05, 0.3)}, refine=[])
    usable = band.status == 0
    for name in ("blow_energy", "motor_torque_peak", "speed_fluctuation"):
        values = band[name].where(usable)
        np.testing.assert_array_equal(result[f"{name}_min"].values,
                                      values.min("R").transpose(*result[f"{name}_min"].dims))
        np.testing.assert_array_equal(result[f"{name}_max"].values,
                                      values.max("R").transpose(*result[f"{name}_max"].dims))
    meets = ((band.status == 0) & (band.blow_energy >= 270) & (band.motor_torque_peak <= 300))
    everywhere = meets.all("R").transpose(*result.requirements.dims).values
    assert np.array_equal(result.requirements.values == 0, everywhere)
    assert 0 < everywhere.sum() < everywhere.size
    assert json.loads(result.attrs["robust"])["samples_in_band"] == band.sizes["R"]


def test_refined_extremes_equal_a_dense_sampling_of_the_band():
    grid = {"tilt": {"start": 0.0, "stop": 3.0, "num": 7}, "omega1": [12.0, 33.0]}
    outputs = ["force_peak_A", "balancing_moment_peak"]
    atlas = sweep.run({"mechanism": "linkage_forces", "grid": grid, "outputs": outputs})
    result = sweep.robust(atlas, {"tilt": (0.2, 2.9)}, refine=outputs)
    dense = sweep.run({"mechanism": "linkage_forces", "outputs": outputs,
                       "grid": {"tilt": {"start": 0.2, "stop": 2.9, "num": 10_000},
                                "omega1": grid["omega1"]}})
    for name in outputs:
        least, most = result[f"{name}_min"].values, result[f"{name}_max"].values
        low, high = dense[name].min("tilt").values, dense[name].max("tilt").values
        assert np.all(least <= low * (1 + 1e-12)) and np.all(most >= high * (1 - 1e-12))
        np.testing.assert_allclose(least, low, rtol=1e-4)
        np.testing.assert_allclose(most, high, rtol=1e-4)
    sampled = atlas.force_peak_A.sel(tilt=slice(0.2, 2.9)).min("tilt").values
    assert np.all(result.force_peak_A_min.values <= sampled)
    assert np.any(result.force_peak_A_min.values < sampled * 0.9)  # the samples miss it


def test_band_ends_off_the_grid_are_computed(machine):
    result = sweep.robust(machine, {"R": (0.12, 0.33)}, refine=[])
    assert json.loads(result.attrs["robust"])["ends_computed"] == [0.12, 0.33]
    at_end = sweep.run({**MACHINE, "grid": {"R": [0.33], "flywheel_inertia": [4.0],
                                            "m3": [8.0]}})
    value = float(at_end.blow_energy.values.ravel()[0])
    assert float(result.blow_energy_min.sel(flywheel_inertia=4.0, m3=8.0)) <= value
    assert value in (float(result.blow_energy_min.sel(flywheel_inertia=4.0, m3=8.0)),
                     float(result.blow_energy_max.sel(flywheel_inertia=4.0, m3=8.0))) or \
        float(result.blow_energy_max.sel(flywheel_inertia=4.0, m3=8.0)) >= value


def test_a_front_ranks_by_the_robust_values(machine, tmp_path):
    robust = sweep.robust(machine, "R", path=tmp_path / "robust.nc")
    front = sweep.pareto(tmp_path / "robust.nc", maximize="blow_energy_min",
                         minimize="motor_torque_peak_max")
    assert front.designs.sizes["design"] >= 1
    feasible = (robust.status == 0) & (robust.requirements == 0)
    assert int(feasible.sum()) == front.candidates


def test_bad_input_is_one_line_and_exit_2(machine, tmp_path, capsys):
    for over, kwargs, match in (("nope", {}, "over: 'nope' is not a grid axis"),
                                ({"R": (0.0, 0.3)}, {}, "reaches outside"),
                                ({"R": (0.3, 0.1)}, {}, "must be below"),
                                ("R", {"refine": ["nope"]}, "refine: 'nope'")):
        with pytest.raises(sweep.UserError, match=match):
            sweep.robust(machine, over, **kwargs)
    for args in (["robust", machine, "--over", "R=0.1", "-o", tmp_path / "r.nc"],
                 ["robust", machine, "--over", "nope", "-o", tmp_path / "r.nc"],
                 ["robust", machine, "--over", "R", "-o", machine]):
        code, out, err = run_cli(capsys, *args)
        assert code == 2 and err.count("\n") == 1, (args, err)
    assert not (tmp_path / "r.nc").exists()
