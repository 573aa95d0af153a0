"""The Python door speaks Python (issue 62): every example in the API's docstrings runs as a
doctest, arguments are named as the caller passed them, Python's sequences are grid axes,
and the package says it is typed."""

import doctest
import math
from pathlib import Path

import numpy as np
import pytest

import sweep
from sweep import api

ROOT = Path(__file__).resolve().parent.parent


def test_every_docstring_example_of_the_api_runs_as_a_doctest(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # an example that writes a file writes it here
    for module in (api, sweep):
        result = doctest.testmod(module, optionflags=doctest.ELLIPSIS
                                 | doctest.NORMALIZE_WHITESPACE, verbose=False)
        assert result.failed == 0
    assert doctest.testmod(api).attempted >= 8  # the examples are there to be run


def test_grid_axes_take_numpy_arrays_tuples_and_ranges():
    spec = sweep.Sweep.from_dict({
        "mechanism": "crank_rocker",
        "grid": {"R": np.linspace(0.1, 0.4, 4), "largest_link": (2.0, 3.0),
                 "type": ("a", "c")},
        "fixed": {"crank_length": np.float64(0.1), "omega1": np.int64(30)}})
    assert spec.shape == (4, 2, 2)
    assert sweep.Sweep.from_dict({"mechanism": "six_link",
                                  "grid": {"mu5": range(3, 6)}}).shape == (3,)


def test_columns_take_a_string_and_errors_name_the_python_argument(tmp_path):
    atlas = sweep.run({"mechanism": "crank_rocker",
                       "grid": {"R": [0.2, 0.3], "largest_link": [3.0]}})
    assert list(sweep.query(atlas, columns="impact_speed").columns)[-1] == "impact_speed"
    assert list(sweep.query(atlas, columns="lambda2, impact_speed").columns)[-2:] == [
        "lambda2", "impact_speed"]
    with pytest.raises(sweep.UserError, match=r"^maximize: .*maximize=NAME"):
        sweep.pareto(atlas)
    with pytest.raises(sweep.UserError, match=r"^variables: "):
        sweep.profile(atlas, [])
    path = tmp_path / "a.nc"
    path.write_bytes(b"")
    with pytest.raises(sweep.UserError, match=r"^path: .* exists; pass force=True"):
        sweep.run({"mechanism": "crank_rocker", "grid": {"R": [0.2], "largest_link": [3.0]}},
                  path)


@pytest.mark.parametrize("call", [
    lambda spec: sweep.run(spec, 123),
    lambda spec: sweep.open_atlas(4.5),
    lambda spec: sweep.chart(sweep.run(spec), x="R", y="largest_link",
                             color="impact_speed", path=["x.png"]),
])
def test_a_path_argument_that_is_not_a_path_is_a_user_error(call):
    spec = {"mechanism": "crank_rocker", "grid": {"R": [0.2, 0.3], "largest_link": [3.0]}}
    with pytest.raises(sweep.UserError, match=r"^(path|atlas): the path of a file"):
        call(spec)


def test_flags_compare_by_meaning_in_plain_xarray_after_decode():
    atlas = sweep.run({"mechanism": "crank_rocker",
                       "grid": {"R": [0.2, 0.3], "largest_link": [1.5, 3.0]}})
    decoded = sweep.decode(atlas)
    ok = (decoded.status == "ok").values
    assert np.array_equal(ok, atlas.status.values == 0)
    assert decoded.status.attrs["flag_meanings"] == atlas.status.attrs["flag_meanings"]
    assert math.isfinite(float(atlas.impact_speed.where(decoded.status == "ok").max()))


def test_the_package_is_typed():
    assert (ROOT / "sweep" / "py.typed").is_file()
    import inspect
    for name in sweep.__all__:
        if name in ("Sweep", "UserError"):
            continue
        signature = inspect.signature(getattr(sweep, name))
        assert signature.return_annotation is not inspect.Signature.empty, name
