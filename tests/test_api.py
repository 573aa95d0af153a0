"""The Python API as a user calls it: `import sweep`, a spec from a dict or a file, an atlas in
memory or on disk, a query into a DataFrame, a chart into a Figure; and the command line as a
thin layer over the same functions (issue 35).

Each test compares with an independent reading: the file atlas against the in-memory one
bit for bit, the DataFrame against the atlas's own arrays, the chart against the atlas.
"""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import xarray as xr

import sweep
from tests.command_line import run_cli

SPEC = {
    "mechanism": "crank_rocker",
    "grid": {"R": {"start": 0.1, "stop": 0.4, "num": 7},
             "largest_link": {"start": 2.0, "stop": 6.0, "num": 9},
             "type": ["a", "c"]},
    "fixed": {"crank_length": 0.1, "omega1": 30.0},
}
PENDULUM = {
    "mechanism": "rotary_pendulum",
    "grid": {"k": {"start": 1.0, "stop": 2.5, "num": 7}, "R": {"start": 0.0, "stop": 0.2,
                                                               "num": 6}},
    "fixed": {"model": "paper", "l2": 0.04, "omega1": 40.0},
}




@pytest.fixture(scope="module")
def memory_atlas():
    return sweep.run(sweep.Sweep.from_dict(SPEC))


def test_import_sweep_is_light_and_lists_the_api():
    code = ("import sys, sweep; "
            "print(sorted(m for m in ('numba', 'xarray', 'dask', 'matplotlib', 'pandas') "
            "if m in sys.modules)); print(sorted(sweep.__all__))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.splitlines()
    assert out[0] == "[]"
    for name in ("Sweep", "run", "open_atlas", "query", "chart", "profile", "boundaries",
                 "info", "UserError"):
        assert name in out[1] and callable(getattr(sweep, name))
    assert sweep.Sweep.__module__ == "sweep.spec"


def test_an_atlas_in_memory_is_the_file_atlas_bit_for_bit(tmp_path, memory_atlas):
    on_disk = sweep.run(SPEC, tmp_path / "cr.nc")
    try:
        assert set(memory_atlas.variables) == set(on_disk.variables)
        for name in memory_atlas.variables:
            a, b = memory_atlas[name].values, on_disk[name].values
            if a.dtype.kind == "f":
                np.testing.assert_array_equal(a, b)
            else:
                assert (a.astype(str) == b.astype(str)).all(), name
            assert memory_atlas[name].attrs.keys() == on_disk[name].attrs.keys(), name
        for key in ("spec", "method", "mechanism", "references", "code_version"):
            assert memory_atlas.attrs[key] == on_disk.attrs[key]
    finally:
        on_disk.close()
    # written from memory by xarray, it reads back the same
    memory_atlas.to_netcdf(tmp_path / "again.nc")
    with xr.open_dataset(tmp_path / "again.nc") as again:
        np.testing.assert_array_equal(again["impact_speed"].values,
                                      memory_atlas["impact_speed"].values)


def test_a_spec_from_a_file_a_dict_and_an_example_are_one_spec(tmp_path):
    text = sweep.api.example_text("crank_rocker")
    (tmp_path / "cr.toml").write_text(text)
    from_file = sweep.Sweep.from_toml(tmp_path / "cr.toml")
    assert from_file.spec == sweep.example("crank_rocker").spec
    assert sweep.Sweep.from_dict(from_file.to_dict()).spec == from_file.spec
    assert sweep.api.as_sweep(str(tmp_path / "cr.toml")).spec == from_file.spec
    assert "crank_rocker" in sweep.examples()


@pytest.mark.parametrize("call, field", [
    (lambda: sweep.Sweep.from_dict({"mechanism": "crank_rocker", "grid": {"R": [1.5]}}),
     "grid.R"),
    (lambda: sweep.Sweep.from_dict({"mechanism": "nope", "grid": {"R": [0.3]}}), "mechanism"),
    (lambda: sweep.Sweep.from_toml("/no/such/spec.toml"), "spec"),
    (lambda: sweep.run(42), "spec"),
    (lambda: sweep.run(SPEC, resume=True), "resume"),
    (lambda: sweep.example("nope"), "name"),
    (lambda: sweep.query("/no/such.nc"), "atlas"),
    (lambda: sweep.query(xr.Dataset(), None), "atlas"),
    (lambda: sweep.parameters("nope"), "mechanism"),
])
def test_bad_input_is_one_user_error_naming_the_field(call, field):
    with pytest.raises(sweep.UserError) as err:
        call()
    message = str(err.value)
    assert message.startswith(field) and "\n" not in message


def test_a_specs_text_where_a_path_belongs_says_what_takes_text():
    """A TOML text passed to run is not looked up as a file name (which echoed the whole
    text as the missing file's name): the error says what takes text."""
    text = 'mechanism = "crank_rocker"\n[grid]\nR = [0.3]\nlargest_link = [2.5]\n'
    with pytest.raises(sweep.UserError, match=r"^spec: TOML text, not the path of a file: "
                                              r"pass sweep\.Sweep\.from_text\(text\)"):
        sweep.run(text)
    assert sweep.Sweep.from_text(text).spec == sweep.Sweep.from_dict(
        {"mechanism": "crank_rocker", "grid": {"R": [0.3], "largest_link": [2.5]}}).spec


def test_an_atlas_too_large_for_memory_asks_for_a_path(monkeypatch):
    monkeypatch.setattr(sweep.api, "IN_MEMORY_LIMIT", 1000)
    with pytest.raises(sweep.UserError, match="^path: the atlas would take"):
        sweep.run(SPEC)


def test_query_gives_a_dataframe_of_the_atlas_rows(memory_atlas):
    frame = sweep.query(memory_atlas, 'status == "ok" and type == "a"', sort="impact_speed",
                        descending=True, limit=4, columns=["lambda2", "impact_speed"])
    assert isinstance(frame, pd.DataFrame)
    assert list(frame.columns) == ["R", "largest_link", "type", "lambda2", "impact_speed"]
    ok = (memory_atlas["status"] == 0) & (memory_atlas["type"] == "a")
    speeds = np.sort(memory_atlas["impact_speed"].where(ok).values.ravel())
    speeds = speeds[np.isfinite(speeds)][::-1]
    np.testing.assert_array_equal(frame["impact_speed"].values, speeds[:4])
    assert frame.attrs["matched"] == int(ok.sum())
    words = sweep.query(memory_atlas, None, columns=["status"], limit=3)["status"]
    assert set(words) <= set(memory_atlas.status.attrs["flag_meanings"].split())


def test_chart_and_profile_give_figures_and_save_them(tmp_path, memory_atlas):
    from matplotlib.figure import Figure

    fig = sweep.chart(memory_atlas, "R", "largest_link", "impact_transfer_ratio",
                      path=tmp_path / "c.png")
    assert isinstance(fig, Figure) and (tmp_path / "c.png").stat().st_size > 10_000
    with pytest.raises(sweep.UserError, match="^path:"):
        sweep.chart(memory_atlas, "R", "largest_link", "impact_speed", path=tmp_path / "c.jpg")
    forces = sweep.run({"mechanism": "linkage_forces", "grid": {"omega1": [20.0, 30.0]},
                        "method": {"profile_points": 73}})
    fig = sweep.profile(forces, ["F21_n", "F34_n", "balancing_moment"], "omega1 == 30")
    # one panel per unit: forces in N, the moment in N m
    labels = [ax.get_ylabel() for ax in fig.axes]
    # one axis per unit, each named by the quantity it draws
    assert len(labels) == 2 and labels[0] == "force [N]" and labels[1].endswith("[N·m]")


def test_boundaries_and_info_from_python(tmp_path, memory_atlas):
    bounds = sweep.boundaries(memory_atlas, "status", 1e-6)
    assert bounds.sizes["crossing"] > 0 and bounds.attrs["tolerance"] == 1e-6
    text = sweep.info(memory_atlas)
    assert "crank_rocker" in text and "impact_speed" in text


def test_the_cli_hints_at_examples_and_its_help_shows_examples_and_exit_codes(capsys):
    code, _, err = run_cli(capsys, "run", "crank_rocker")
    assert code == 2 and "sweep examples crank_rocker -o crank_rocker.toml" in err
    assert len(err.strip().splitlines()) == 1
    for command in ("run", "query", "chart", "boundaries", "profile", "examples", "info",
                    "parameters"):
        code, out, _ = run_cli(capsys, command, "--help")
        assert code == 0 and "Examples:" in out and "Exit status: 0 success; 2 bad input" in out
    code, out, _ = run_cli(capsys, "--help")
    # each command's summary whole, not cut short with "..."
    assert "Refine a flag's boundaries (status, regime) to a tolerance." in out
    assert "..." not in out.split("Commands:")[1]


def test_counts_are_categories_and_rotor_angles_are_turns(tmp_path):
    from sweep.charts import design_chart

    cr = sweep.run({"mechanism": "crank_rocker",
                    "grid": {"R": {"start": 0.05, "stop": 0.4, "num": 8},
                             "largest_link": {"start": 1.5, "stop": 8.0, "num": 9}},
                    "fixed": {"type": "a"}})
    drawn = design_chart(cr, "R", "largest_link", "special_position_count", tmp_path / "n.png")
    values = cr["special_position_count"].values  # a count that exists at every status
    expected = sorted({str(int(v)) for v in values[np.isfinite(values)]})
    assert not drawn.colour_bar
    assert [label for label in drawn.legend if not label.startswith("no ")] == expected
    rp = sweep.run(PENDULUM)
    drawn = design_chart(rp, "k", "R", "impact_interval", tmp_path / "t.png")
    assert drawn.colour_bar
    fig = sweep.chart(rp, "k", "R", "impact_interval")
    bar = [ax for ax in fig.axes if ax.get_label() == "<colorbar>"][0]
    assert bar.get_ylabel() == r"impact interval $\tau_1$ [turn]"
    top = float(np.nanmax(rp["impact_interval"].values)) / (2 * np.pi)
    assert bar.get_ylim()[1] == pytest.approx(top, rel=1e-12)


def test_a_chart_says_which_code_drew_it_not_which_host(tmp_path, memory_atlas):
    import platform

    fig = sweep.chart(memory_atlas, "R", "largest_link", "impact_speed")
    caption = fig.get_suptitle()
    assert "impact-sweep 0.1.0" in caption and "made on" not in caption
    host = platform.node()
    assert not host or host not in caption


def test_six_link_profile_has_angles_in_one_unit(tmp_path):
    six = sweep.run({"mechanism": "six_link", "grid": {"beta": [0.0, 0.6]},
                     "method": {"profile_points": 91}})
    fig = sweep.profile(six, ["rocker_angle"], "beta == 0")
    ax = fig.axes[0]
    assert ax.get_ylabel().endswith("[°]") and "[°]" in ax.get_xlabel()
    line = ax.get_lines()[0].get_ydata()
    np.testing.assert_allclose(line, np.degrees(six["rocker_angle"].values[0]), rtol=1e-15)
    fig = sweep.profile(six, ["rocker_angle"], "beta == 0", degrees=False)
    assert fig.axes[0].get_ylabel().endswith("[rad]") and "[rad]" in fig.axes[0].get_xlabel()


def test_run_with_a_path_writes_the_chart_of_the_spec(tmp_path):
    spec = sweep.example("crank_rocker").to_dict()
    spec["grid"] = {"R": {"start": 0.1, "stop": 0.4, "num": 4},
                    "largest_link": {"start": 2.0, "stop": 6.0, "num": 5},
                    "type": ["a", "b", "c"]}
    atlas = sweep.run(spec, Path(tmp_path) / "cr.nc")
    atlas.close()
    assert (tmp_path / "cr.png").is_file() and (tmp_path / "cr.bounds.nc").is_file()
    with pytest.raises(sweep.UserError, match="^path: .* exists; pass force=True"):
        sweep.run(spec, tmp_path / "cr.nc")
