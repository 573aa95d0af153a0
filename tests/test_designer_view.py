"""What a designer reads: `sweep info`, design charts and angle output (issue 15).

Each test compares what is shown with an independent reading of the atlas (its spec, its
values, the declaration), so that a chart or a summary that says the wrong thing fails.
"""

import json
import re

import numpy as np
import pytest
import xarray as xr

from sweep import registry, runner, spec
from sweep.charts import design_chart
from tests.command_line import run_cli

PENDULUM = '''
mechanism = "rotary_pendulum"
[grid]
k = {start = 1.0, stop = 2.5, num = 7}
R = {start = 0.0, stop = 0.35, num = 8}
omega1 = [20.0, 60.0]
[fixed]
model = "paper"
l2 = 0.04
'''
CRANK = '''
mechanism = "crank_rocker"
[grid]
R = {start = 0.05, stop = 0.4, num = 9}
largest_link = {start = 1.5, stop = 30.0, num = 11, scale = "log"}
omega1 = [10.0, 20.0, 30.0, 40.0]
[fixed]
type = "a"
crank_length = 0.1
'''
BALANCER = '''
mechanism = "spring_balancer"
[grid]
f = {start = 0.3, stop = 2.0, num = 24}
r = {start = 0.3, stop = 2.0, num = 20}
'''


def atlas(tmp_path, text, name="a.nc", chunk=None):
    target = tmp_path / name
    runner.run_sweep(spec.parse(text), target, chunk=chunk, progress=False, history="test")
    return target




@pytest.fixture(scope="module")
def pendulum(tmp_path_factory):
    return atlas(tmp_path_factory.mktemp("p"), PENDULUM)


def test_info_says_what_a_design_was_computed_with_in_words_and_units(tmp_path, pendulum,
                                                                      capsys):
    code, out, _ = run_cli(capsys, "info", str(pendulum))
    assert code == 0
    ds = xr.open_dataset(pendulum)
    stored = json.loads(ds.attrs["spec"])
    decl = registry.get("rotary_pendulum").declaration
    # every fixed parameter that is used, with its units; the unused ones named as such
    assert re.search(r"^\s+l2\s+0\.04 m$", out, re.M)
    assert re.search(r'^\s+model\s+"paper"$', out, re.M)
    assert re.search(r"^\s+xi\s+4$", out, re.M)
    assert "tool_window (used only with tool = \"lab_window\")" in " ".join(out.split())
    for name in stored["fixed"]:
        assert re.search(rf"\b{name}\b", out), name
    # method options in words, the unused ones named, no raw JSON or escapes
    assert re.search(r'^\s+integrator\s+"auto"$', out, re.M)
    assert "not used by this method: rtol, atol, dt" in out
    assert "\\u" not in out and '{"' not in out
    # a range per variable equal to the atlas's own min and max, with units
    for name in ("impact_speed", "amplitude", "period"):
        values = ds[name].values
        lo, hi = np.nanmin(values), np.nanmax(values)
        units = decl.output(name).units
        line = next(line for line in out.splitlines() if line.startswith(f"  {name} "))
        assert f"[{units}]" in line and f"{lo:.4g} to {hi:.4g}" in line, line
        missing = int(np.isnan(values).sum())
        assert (f"no value at {missing:,} of {values.size:,}" in line) == (missing > 0)
    amplitude = ds.amplitude.values
    line = next(line for line in out.splitlines() if line.startswith("  amplitude "))
    assert (f"({np.degrees(np.nanmin(amplitude)):.4g}° to "
            f"{np.degrees(np.nanmax(amplitude)):.4g}°)") in line  # an angle also in degrees
    # grid axes with their values and units
    assert re.search(r"^\s+omega1\s+\[rad s-1\]\s+20, 60$", out, re.M)
    assert re.search(r"^\s+k\s+\[-\]\s+1 to 2\.5, 7 values, step 0\.25$", out, re.M)
    counts = {m: int((ds.regime.values == c).sum()) for c, m in
              zip(ds.regime.attrs["flag_values"], ds.regime.attrs["flag_meanings"].split())}
    for meaning, n in counts.items():
        if n:
            assert f"{meaning} {n:,}" in out


def test_info_records_the_chunk_a_run_used(tmp_path, capsys):
    path = atlas(tmp_path, CRANK, chunk=50)
    assert json.loads(xr.open_dataset(path).attrs["spec"])["run"]["chunk"] == 50
    code, out, _ = run_cli(capsys, "info", str(path))
    assert code == 0 and "run: chunk 50 points per task" in out


def test_a_flag_is_drawn_as_categories_with_its_meanings(tmp_path, pendulum):
    ds = xr.open_dataset(pendulum)
    drawn = design_chart(ds, "k", "R", "regime", tmp_path / "r.png", at={"omega1": (60.0, "")})
    codes = np.unique(ds.regime.sel(omega1=60.0).values)
    meanings = dict(zip(ds.regime.attrs["flag_values"], ds.regime.attrs["flag_meanings"].split()))
    assert not drawn.colour_bar  # categories, not a continuous scale
    present = [meanings[c].replace("_", " ") for c in codes]  # the meanings, as words
    assert [label for label in drawn.legend if not label.startswith("no ")] == present
    assert drawn.panel_titles == [""]  # omega1 taken at one value: one panel


@pytest.mark.slow
def test_a_category_keeps_its_colour_whatever_else_the_chart_holds(tmp_path, pendulum):
    """Colours ranked among the categories present gave period_1 one colour in one blade
    chart and another in the next (an undetermined cell shifted them all): a meaning's
    colour follows its place among all the flag's meanings, undetermined grey."""
    ds = xr.open_dataset(pendulum)
    colour_of = {}
    for omega1 in ds.omega1.values:
        for rows in [slice(None)] + [slice(i, i + 1) for i in range(ds.sizes["R"])]:
            sub = ds.isel(R=rows)
            drawn = design_chart(sub, "k", "R", "regime", tmp_path / "r.png",
                                 at={"omega1": (float(omega1), "")})
            for label, colour in zip(drawn.legend, drawn.legend_colours):
                assert colour_of.setdefault(label, colour) == colour, label
    assert len(set(colour_of.values())) == len(colour_of) >= 2


def test_blank_cells_name_their_status_and_usable_results_are_not_blank(tmp_path, pendulum):
    ds = xr.open_dataset(pendulum)
    drawn = design_chart(ds, "k", "R", "impact_speed", tmp_path / "v.png",
                         at={"omega1": (20.0, "")})
    sub = ds.sel(omega1=20.0)
    status = dict(zip(ds.status.attrs["flag_values"], ds.status.attrs["flag_meanings"].split()))
    blank = ~np.isfinite(sub.impact_speed.values)
    expected = {}
    for code in np.unique(sub.status.values[blank]):
        expected[status[code]] = int((sub.status.values[blank] == code).sum())
    labels = [label for label in drawn.legend if label.startswith("no value")]
    assert sorted(labels) == sorted(f"no value: {m.replace('_', ' ')} ({n:,})"
                                    for m, n in expected.items())
    # the regime exists at every status: escape is charted as a category, not blanked
    drawn = design_chart(ds, "k", "R", "regime", tmp_path / "r.png", at={"omega1": (20.0, "")})
    assert "escape" in drawn.legend and not any(s.startswith("no ") for s in drawn.legend)


def test_no_blank_caption_where_nothing_is_blank(tmp_path):
    ds = xr.open_dataset(atlas(tmp_path, BALANCER))
    assert np.isfinite(ds.balancing_coefficient.values).all()
    drawn = design_chart(ds, "f", "r", "balancing_coefficient", tmp_path / "b.png")
    assert not any(label.startswith("no ") for label in drawn.legend)
    # K = 1, where the balancer stops helping, is marked when the map crosses it
    k = ds.balancing_coefficient.values
    assert (k.min() < 1 < k.max()) == any("K = 1" in label for label in drawn.legend)
    assert any("K = 1" in label for label in drawn.legend)


def test_panels_wrap_log_axes_read_as_numbers_and_angles_in_degrees(tmp_path):
    ds = xr.open_dataset(atlas(tmp_path, CRANK))
    drawn = design_chart(ds, "largest_link", "R", "impact_speed", tmp_path / "c.png")
    assert len(drawn.panel_titles) == 4 and (drawn.rows, drawn.columns) == (2, 3)
    assert drawn.panel_titles == [rf"crank speed $\omega_1$ = {w:g} rad/s"
                                  for w in (10, 20, 30, 40)]
    assert drawn.xscale == "log"  # a log-spaced axis on x is drawn log
    assert drawn.xticks and all(re.fullmatch(r"[0-9.]+", t) for t in drawn.xticks), drawn.xticks
    lf = ('mechanism = "linkage_forces"\n[grid]\nomega1 = [5.0, 20.0]\n'
          'tilt = [0.0, 0.5, 1.0]\n[method]\nprofile_points = 8\n')
    ds = xr.open_dataset(atlas(tmp_path, lf, "lf.nc"))
    drawn = design_chart(ds, "omega1", "tilt", "force_peak_D", tmp_path / "d.png")
    assert drawn.ylabel == r"tilt $\theta$ [°]"
    ticks = [float(t.replace("−", "-")) for t in drawn.yticks]
    assert max(ticks) > 40  # 1 rad = 57.3 deg: the axis is in degrees
    drawn = design_chart(ds, "omega1", "tilt", "force_peak_D", tmp_path / "d.png",
                         degrees=False)
    assert drawn.ylabel == r"tilt $\theta$ [rad]"


def test_chart_input_mistakes_are_one_line_errors(tmp_path, pendulum, capsys):
    png = str(tmp_path / "x.png")
    code, _, err = run_cli(capsys, "chart", str(pendulum), "--x", "k", "--y", "R", "--color",
                           "impact_speed", "--at", "nope=3", "-o", png)
    assert code == 2 and "at: 'nope' is not a grid axis" in err
    bad = PENDULUM + '[chart]\nx = "k"\ny = "R"\ncolor = "regime"\nat = {omega1 = 500.0}\n'
    with pytest.raises(Exception) as e:
        spec.parse(bad)
    assert "chart.at.omega1: 500 is outside the grid" in str(e.value)
    two = CRANK.replace('type = "a"', "").replace("[fixed]", 'type = ["a", "c"]\n[fixed]') + \
        '[chart]\nx = "R"\ny = "largest_link"\ncolor = "impact_speed"\n'
    with pytest.raises(Exception) as e:
        spec.parse(two)
    assert "take all but one at a value with chart.at" in str(e.value)


def test_query_prints_angles_in_degrees_on_request(pendulum, capsys):
    code, out, _ = run_cli(capsys, "query", str(pendulum), "--columns", "amplitude",
                           "--where", 'regime == "period_1"', "--limit", "2", "--format",
                           "csv", "--degrees")
    ds = xr.open_dataset(pendulum)
    meanings = ds.regime.attrs["flag_meanings"].split()
    period_1 = ds.regime.attrs["flag_values"][meanings.index("period_1")]
    first = ds.amplitude.where(ds.regime == period_1).stack(p=ds.status.dims).dropna("p")
    got = [float(line.split(",")[-1]) for line in out.splitlines()[1:]]
    assert code == 0 and np.allclose(got, np.degrees(first.values[:2]), rtol=1e-14)
    code, out, _ = run_cli(capsys, "query", str(pendulum), "--columns", "amplitude",
                           "--limit", "1", "--degrees")
    assert code == 0 and "[deg]" in out.splitlines()[1]


@pytest.mark.parametrize("name", ["crank_rocker", "linkage_forces", "rotary_pendulum",
                                  "rotary_pendulum_blade", "six_link", "spring_balancer",
                                  "models on the grid"])
def test_the_spec_an_atlas_records_runs_again_as_it_is(name):
    """The recorded spec lists only what the design used (a default of an unused parameter,
    such as tool_window on the rotor stop or rtol under auto, used to be recorded and made
    the recorded spec fail validation), and validating it gives the same spec back."""
    from sweep.api import example_text as _example_text

    text = (PENDULUM.replace('model = "paper"\n', "").replace(
        "[grid]", '[grid]\nmodel = ["paper", "rigid"]') if name == "models on the grid"
        else _example_text(name))
    first = spec.parse(text)
    recorded = json.loads(first.spec_json())
    again = spec.validate(recorded)
    assert again.spec == recorded
    assert again.fixed == first.fixed and again.method_record == first.method_record
    decl = first.mechanism
    for key in recorded["fixed"]:
        q = decl.parameter(key)
        for other, values in q.used_when.items():
            assert set(values) & ({recorded["fixed"][other]} if other in recorded["fixed"]
                                  else set(first.axes[[a.name for a in first.axes]
                                                      .index(other)].values.tolist())), key
    if name == "models on the grid":
        assert "rotor_inertia_ratio" not in recorded["fixed"]  # no rotor on this grid
    if recorded["method"].get("integrator") == "auto":
        assert not {"rtol", "atol", "dt"} & set(recorded["method"])


def test_a_log_colour_bar_writes_every_tick_as_the_contours_do(tmp_path):
    """Peak forces over four decades of crank speed: a log colour scale whose ticks read as
    the contour labels read (1,000,000), never 1e+06 beside 500000; each tick's text is the
    value matplotlib placed there."""
    import matplotlib.pyplot as plt

    from sweep.charts import design_figure

    lf = ('mechanism = "linkage_forces"\n[grid]\nomega1 = [10.0, 100.0, 1000.0, 3000.0]\n'
          'tilt = [0.0, 0.5]\n[method]\nprofile_points = 8\n')
    ds = xr.open_dataset(atlas(tmp_path, lf, "wide.nc"))
    assert float(ds.force_peak_D.max() / ds.force_peak_D.min()) > 1e4  # a log scale
    fig = design_figure(ds, "omega1", "tilt", "force_peak_D")
    fig.draw_without_rendering()
    bar = next(ax for ax in fig.axes if ax.get_label() == "<colorbar>")
    shown = [t for t in bar.yaxis.get_majorticklabels() + bar.yaxis.get_minorticklabels()
             if t.get_text() and bar.get_ylim()[0] <= t.get_position()[1] <= bar.get_ylim()[1]]
    texts = [t.get_text() for t in shown]
    assert any(float(t.replace(",", "")) >= 1e6 for t in texts), texts
    for t in shown:
        assert re.fullmatch(r"\d{1,3}(,\d{3})*|\d+(\.\d+)?", t.get_text()), texts
        assert float(t.get_text().replace(",", "")) == pytest.approx(t.get_position()[1],
                                                                      rel=1e-12)
    plt.close(fig)
