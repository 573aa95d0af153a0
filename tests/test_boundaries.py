"""`sweep boundaries` (issue 17): every flag boundary of an atlas bisected to a tolerance.

Oracles: the crank-rocker feasibility bounds (types a and c: the largest link equals
gamma = (1+R)/(1-R); type b: the rocker equals (gamma + sqrt(gamma^2-1))^2), the pendulum's
escape at R_crit (paper model, from its first integral, solved here with SciPy), the
balancer's resonance lines n f r = sqrt(1 +- resonance_tol) (and sqrt((1+r^2)(1 +- tol)) with
the device), and on the blade the border collisions of H11, bisected independently on the
impact interval. Plus: bit-identical across chunk sizes and thread counts, a killed run
resumes, bad input is one line with exit 2 before any compute.
"""

import json
import math

import numpy as np
import pytest
import xarray as xr
from scipy.optimize import brentq

from sweep import refinement as boundaries, cli, runner, spec
from sweep.errors import UserError
from sweep.selection import flag_names

RNG_SEED = 20261123


def atlas(tmp_path, text, name="atlas.nc"):
    path = tmp_path / name
    runner.run_sweep(spec.parse(text), path, progress=False, history="test")
    return xr.open_dataset(path)


def pairs(result):
    """The crossings' sides as sets of meanings."""
    meaning = flag_names(result["side_below"])
    return [frozenset((meaning[int(a)], meaning[int(b)])) for a, b in
            zip(result["side_below"].values, result["side_above"].values)]


def test_crank_rocker_feasibility_bounds_come_out_exact_at_random_restitutions(tmp_path):
    """Random R (not chosen points): with geometry_tol = 1e-13 the band where the kernel
    flags the double change point at gamma shrinks to round-off, and every crossing into
    `ok` sits on the closed-form bound to the requested 1e-10 (in the axis's units, times
    max(1, |x|)), along either axis."""
    rng = np.random.default_rng(RNG_SEED)
    r_values = np.sort(rng.uniform(0.02, 0.45, 7))
    text = ('mechanism = "crank_rocker"\n[grid]\nR = ' + json.dumps(r_values.tolist())
            + '\nlargest_link = {start = 1.02, stop = 40.0, num = 23, scale = "log"}\n'
            'type = ["a", "b", "c"]\n[method]\ngeometry_tol = 1e-13\n')
    ds = atlas(tmp_path, text)
    tol = 1e-10
    result = boundaries.refine(ds, "status", tol)
    assert result.sizes["crossing"] >= 3 * 7 + 10
    assert float(result["accuracy"].max()) <= tol
    t = result["type"].values.astype(str)
    axis = result["edge_axis"].values.astype(str)
    r, big = result["R"].values, result["largest_link"].values
    to_ok = np.array(["ok" in p for p in pairs(result)])
    gamma = (1 + r) / (1 - r)
    bound = np.where(t == "b", (gamma + np.sqrt(gamma ** 2 - 1)) ** 2, gamma)
    along_link = to_ok & (axis == "largest_link")
    assert along_link.sum() >= 3 * len(r_values) - 2
    err_link = np.abs(big - bound) / np.maximum(1.0, big)
    assert err_link[along_link].max() <= 1.5 * tol
    # along R: the R whose bound equals the grid's largest link
    root = np.sqrt(big)
    gamma_b = 0.5 * (root + 1 / root)  # gamma + sqrt(gamma^2 - 1) = sqrt(lambda3)
    g = np.where(t == "b", gamma_b, big)
    r_exact = (g - 1) / (g + 1)
    along_r = to_ok & (axis == "R")
    assert along_r.sum() >= 10
    assert np.abs(r - r_exact)[along_r].max() <= 1.5 * tol
    # explained by the declared cause, with its indicator at the crossing
    indicator = result["indicator"].values.astype(str)
    value = result["indicator_value"].values
    ac = to_ok & (t != "b")
    assert set(indicator[ac]) == {"gamma"}
    np.testing.assert_allclose(value[ac], gamma[ac], rtol=1e-9)
    assert set(indicator[to_ok & (t == "b")]) == {"restitution_kinematic_max"}
    np.testing.assert_allclose(value[to_ok & (t == "b")], r[to_ok & (t == "b")], rtol=1e-8)


def _paper_r_crit(k, xi=4.0):
    """R_crit of the paper model from its first integral (psi'^2 + xi) M(psi) = const,
    M = exp(ln(1 + xi X)/xi^2 - X/xi), X = k^2 + 1 + 2k cos psi: the launch speed that just
    reaches psi = pi, then R_crit = (v - (1+k))/(v + (1+k)) (docs/models.md 5.4)."""
    def log_m(x):
        return np.log1p(xi * x) / xi ** 2 - x / xi

    v = math.sqrt(xi * (math.exp(log_m((k - 1) ** 2) - log_m((1 + k) ** 2)) - 1))
    return (v - (1 + k)) / (v + (1 + k))


def test_pendulum_escape_boundary_is_R_crit_of_the_paper_model(tmp_path):
    text = ('mechanism = "rotary_pendulum"\n[grid]\nk = {start = 1.0, stop = 2.5, num = 7}\n'
            'R = {start = 0.0, stop = 0.35, num = 8}\n[fixed]\nmodel = "paper"\n')
    ds = atlas(tmp_path, text)
    tol = 1e-9
    result = boundaries.refine(ds, "regime", tol)
    sides = pairs(result)
    assert set(sides) == {frozenset(("period_1", "escape"))}
    axis = result["edge_axis"].values.astype(str)
    k, r = result["k"].values, result["R"].values
    along_r = axis == "R"
    assert along_r.sum() == 7  # R_crit(k) lies inside the R grid at every k
    err = [abs(r[i] - _paper_r_crit(k[i])) for i in np.flatnonzero(along_r)]
    assert max(err) <= tol
    along_k = np.flatnonzero(axis == "k")
    assert along_k.size >= 3
    for i in along_k:
        k_exact = brentq(lambda kk: _paper_r_crit(kk) - r[i], 1.0, 2.5, xtol=1e-15)
        assert abs(k[i] - k_exact) <= tol * max(1.0, k_exact)
    np.testing.assert_allclose(result["indicator_value"].values[along_r], r[along_r],
                               atol=2 * tol)  # restitution_critical at the crossing


def test_balancer_resonance_lines(tmp_path):
    """eta = 0 and resonance_tol = 1e-3: a harmonic n is resonant where n^2 f^2 r^2 lies
    within 1e-3 of 1 (no balancer) or of 1 + r^2 (with it); the grid's f = 0.3 + 0.05 i
    falls inside several such bands, and each band's two edges come out exact."""
    res_tol, tol = 1e-3, 1e-10
    text = ('mechanism = "spring_balancer"\n[grid]\nf = {start = 0.3, stop = 2.0, num = 35}\n'
            'r = [0.5, 1.0]\n[fixed]\neta = 0.0\n[method]\nresonance_tol = 1e-3\n')
    result = boundaries.refine(atlas(tmp_path, text), "status", tol)
    sides = pairs(result)
    resonant = np.array(["resonance" in p for p in sides])
    along_f = resonant & (result["edge_axis"].values.astype(str) == "f")
    assert along_f.sum() >= 8
    f, r = result["f"].values[along_f], result["r"].values[along_f]
    candidates = []
    for scale in (1.0, 1.0 + r ** 2):  # without / with the balancer
        for sign in (-1, 1):
            target = np.sqrt(scale * (1 + sign * res_tol))
            n = np.round(target / (f * r))
            candidates.append(np.abs(f - target / (n * r)))
    err = np.min(candidates, axis=0)
    assert err.max() <= 2 * tol
    np.testing.assert_allclose(result["indicator_value"].values[along_f], res_tol, rtol=1e-6)


def test_blade_border_collisions_agree_with_the_H11_bisection(tmp_path):
    """The blade's regime changes discontinuously with the reach (H11). A boundary that `sweep boundaries` labels as a jump of the outputs lies,
    to 1e-10, where the impact interval jumps when bisected independently (as the H11 test
    does, on the interval, not on the regime, from 1e-4 either side)."""
    from tests.test_pendulum_models import steady

    design = dict(model="rigid", k=1.0, kappa=1.2, tool="lab_window")
    result = boundaries.refine(atlas(tmp_path, BLADE), "regime", 1e-10)
    jumps = np.flatnonzero(result["continuity"].values == 1)  # outputs_jump
    assert jumps.size >= 1
    for i in jumps[:2]:
        x = float(result["tool_window"].values[i])
        # the grid edge may hold further jumps of the interval inside one regime: start
        # the independent bisection 1e-4 either side of the crossing
        lo, hi = x - 1e-4, x + 1e-4
        base = steady(**design, tool_window=lo)[1]["impact_interval"]
        for _ in range(34):
            mid = 0.5 * (lo + hi)
            if abs(steady(**design, tool_window=mid)[1]["impact_interval"] - base) < 1e-6:
                lo = mid
            else:
                hi = mid
        assert abs(x - 0.5 * (lo + hi)) <= 2e-10
        assert "border collision" in str(result["explanation"].values[i])


BLADE = ('mechanism = "rotary_pendulum"\n[grid]\ntool_window = '
         + json.dumps(np.linspace(0.12, 0.3, 10).tolist())
         + '\n[fixed]\nmodel = "rigid"\nk = 1.0\nkappa = 1.2\ntool = "lab_window"\n'
         'omega1 = 1.0\nl2 = 1.0\n[method]\nintegrator = "dopri5"\nrtol = 1e-11\n'
         'atol = 1e-13\n')


@pytest.mark.slow
def test_sigkill_mid_run_then_resume_gives_the_same_bits(tmp_path):
    """A real kill (no clean-up runs) after some rounds were kept: --resume finishes from
    the last kept round, to the same file as an uninterrupted run."""
    import signal
    import subprocess
    import sys
    import time

    ds = atlas(tmp_path, BLADE)
    whole = boundaries.refine(ds, "regime", 1e-10)
    target = tmp_path / "atlas.bounds.nc"
    cmd = [sys.executable, "-m", "sweep", "boundaries", str(tmp_path / "atlas.nc"),
           "--var", "regime", "--tol", "1e-10", "-q"]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    kept = boundaries.partial_dir(target) / "brackets.npz"
    deadline = time.time() + 120
    while time.time() < deadline and proc.poll() is None and not kept.exists():
        time.sleep(0.02)
    assert proc.poll() is None, "the run finished before it could be killed"
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    assert not target.exists() and kept.exists()
    again = subprocess.run(cmd + ["--resume"], capture_output=True, text=True, timeout=600)
    assert again.returncode == 0, again.stderr
    assert not boundaries.partial_dir(target).exists()
    resumed = xr.open_dataset(target)
    for name in whole.variables:
        np.testing.assert_array_equal(whole[name].values, resumed[name].values, err_msg=name)
    assert resumed.attrs["kernel_evaluations"] == whole.attrs["kernel_evaluations"]


CRANK = ('mechanism = "crank_rocker"\n[grid]\nR = {start = 0.05, stop = 0.4, num = 9}\n'
         'largest_link = {start = 1.0, stop = 30.0, num = 25, scale = "log"}\n'
         'type = ["a", "b"]\n')


def test_identical_bits_across_chunk_sizes_and_threads(tmp_path):
    ds = atlas(tmp_path, CRANK)
    first = boundaries.refine(ds, "status", 1e-9, workers=1, chunk=7)
    second = boundaries.refine(ds, "status", 1e-9, workers=2, chunk=100000)
    assert first.sizes["crossing"] > 20
    for name in first.variables:
        np.testing.assert_array_equal(first[name].values, second[name].values, err_msg=name)
    assert first.attrs["kernel_evaluations"] == second.attrs["kernel_evaluations"]


def test_an_interrupted_run_resumes_to_the_same_crossings(tmp_path, monkeypatch):
    ds = atlas(tmp_path, CRANK)
    whole = boundaries.refine(ds, "status", 1e-9)
    target = tmp_path / "b.nc"
    real = boundaries.bisect_round
    calls = []

    def dies_after_five(*args):
        calls.append(1)
        if len(calls) > 5:
            raise KeyboardInterrupt
        return real(*args)

    monkeypatch.setattr(boundaries, "bisect_round", dies_after_five)
    with pytest.raises(KeyboardInterrupt):
        boundaries.refine(ds, "status", 1e-9, target=target)
    assert not target.exists()  # nothing half-written
    monkeypatch.setattr(boundaries, "bisect_round", real)
    with pytest.raises(UserError, match="interrupted run"):
        boundaries.refine(ds, "status", 1e-9, target=target)
    resumed = boundaries.refine(ds, "status", 1e-9, target=target, resume=True)
    assert resumed.attrs["rounds"] == whole.attrs["rounds"]
    on_disk = xr.open_dataset(target)
    for name in whole.variables:
        np.testing.assert_array_equal(whole[name].values, resumed[name].values)
        np.testing.assert_array_equal(whole[name].values, on_disk[name].values)
    assert not boundaries.partial_dir(target).exists()
    for name in on_disk.variables:  # CF: every variable says what it is
        assert {"units", "long_name"} <= set(on_disk[name].attrs), name
    assert on_disk.attrs["spec"] == ds.attrs["spec"]
    assert on_disk.attrs["source_code_version"] == ds.attrs["code_version"]


def test_bad_input_is_one_line_with_exit_2_before_any_compute(tmp_path, capsys, monkeypatch):
    ds = atlas(tmp_path, CRANK)
    path = tmp_path / "atlas.nc"
    ds.close()
    monkeypatch.setattr(boundaries, "evaluate", lambda *a: pytest.fail("computed"))
    cases = [(["--var", "regime"], "var: 'regime' is not a variable of this atlas"),
             (["--var", "impact_speed"], "var: 'impact_speed' is not a flag variable"),
             (["--tol", "0"], "tol: must be a number > 0"),
             (["--tol", "-1e-8"], "tol: must be a number > 0"),
             (["--tol", "nan"], "tol: must be a number > 0"),
             (["-o", str(path)], "is this command's input")]
    for args, message in cases:
        with pytest.raises(SystemExit) as exit_:
            cli.main(["boundaries", str(path), *args])
        err = capsys.readouterr().err
        assert exit_.value.code == 2 and err.count("\n") == 1 and message in err, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["atlas.nc"]


def test_chart_draws_the_boundaries_and_refuses_another_sweeps(tmp_path):
    from sweep.charts import boundary_segments, design_chart

    ds = atlas(tmp_path, CRANK)
    result = boundaries.refine(ds, "status", 1e-8)
    drawn = design_chart(ds, "R", "largest_link", "impact_transfer_ratio",
                         tmp_path / "c.png", boundaries=result)
    assert "status boundaries, to 1e-08" in drawn.legend
    grid_dims = list(ds["status"].dims)
    for t in ("a", "b"):
        segments = boundary_segments(result, grid_dims, ds["status"].shape, "R",
                                     "largest_link", {"type": t})
        assert len(segments) >= 8  # a line across the 9 R columns
        ends = np.array(segments).reshape(-1, 2)
        on = result.sel(crossing=result["type"].values.astype(str) == t)
        points = np.stack([on["R"].values, on["largest_link"].values], axis=1)
        # every segment joins two refined crossings
        assert all(np.any(np.all(np.isclose(points, e, rtol=0, atol=0), axis=1))
                   for e in ends)
    other = atlas(tmp_path, CRANK.replace("num = 9", "num = 8"), "other.nc")
    with pytest.raises(UserError, match="refined from another sweep"):
        design_chart(other, "R", "largest_link", "impact_transfer_ratio",
                     tmp_path / "d.png", boundaries=result)


def test_spec_chart_boundaries_is_validated():
    with pytest.raises(UserError, match="chart.boundaries: 'impact_speed' is not a flag"):
        spec.parse(CRANK + '[chart]\nx = "R"\ny = "largest_link"\ncolor = "impact_speed"\n'
                   'boundaries = "impact_speed"\n')


@pytest.mark.slow
@pytest.mark.parametrize("example", ["linkage_forces", "six_link"])
def test_boundaries_need_no_profiles_their_scalars_are_the_same_without(example):
    """Boundaries evaluate without profiles (profile_points = 0) so that memory does not grow
    with the profile length; that is exact only if no scalar output or status depends on
    the profiles."""
    from importlib import resources

    from sweep import engine

    s = spec.parse(resources.files("sweep.example_specs").joinpath(f"{example}.toml").read_text())
    assert s.method_record.profile_points > 0
    params = engine.point_parameters(s, np.arange(s.size))
    with_profiles = s.kernel(params, s.method_record)
    without = s.kernel(params, s.method_record._replace(profile_points=0))
    np.testing.assert_array_equal(with_profiles[0], without[0])
    np.testing.assert_array_equal(with_profiles[1], without[1])
    assert without[2].shape[2] == 0


def test_info_reads_a_boundaries_file_in_words_and_query_sends_the_user_there(tmp_path,
                                                                               capsys):
    ds = atlas(tmp_path, CRANK)
    target = tmp_path / "atlas.bounds.nc"
    result = boundaries.refine(ds, "status", 1e-8, target=target)
    with pytest.raises(SystemExit) as exit_:
        cli.main(["info", str(target)])
    text = capsys.readouterr().out
    assert exit_.value.code == 0
    assert f"{result.sizes['crossing']:,} crossings, each to 1e-08" in text
    assert "not_assemblable / ok" in text and "gamma at the crossings" in text
    assert "no_real_synthesis / ok" in text and "restitution_kinematic_max at the" in text
    with pytest.raises(SystemExit) as exit_:
        cli.main(["query", str(target)])
    err = capsys.readouterr().err
    assert exit_.value.code == 2 and "`sweep info` describes it" in err


def test_an_edge_with_more_crossings_than_followed_is_marked_and_chunk_invariant(tmp_path):
    """On the blade at R > 0 the regime alternates faster than the grid: midpoints keep
    finding third meanings. At most MAX_PER_EDGE crossings an edge are followed, the edge is
    marked, and which ones are followed does not depend on chunk size or threads."""
    text = ('mechanism = "rotary_pendulum"\n[grid]\n'
            'tool_window = {start = 0.1, stop = 0.5, num = 9}\nR = [0.002, 0.004]\n'
            '[fixed]\nmodel = "rigid"\ntool = "lab_window"\nk = 1.0\nkappa = 1.2\n'
            'omega1 = 40.0\nl2 = 0.04\n[method]\ntol = 1e-6\nmax_impacts = 200\n')
    ds = atlas(tmp_path, text)
    first = boundaries.refine(ds, "regime", 1e-6, workers=1, chunk=3)
    second = boundaries.refine(ds, "regime", 1e-6, workers=2)
    marked = first["edge_crossings"].values == 1
    assert marked.any()
    per_edge = np.bincount(first["grid_point"].values[marked] * 4
                           + (first["edge_axis"].values[marked] == "R"))
    assert per_edge.max() <= boundaries.MAX_PER_EDGE
    for name in first.variables:
        np.testing.assert_array_equal(first[name].values, second[name].values, err_msg=name)


def test_a_scale_only_axis_is_refined_once_and_repeated_with_the_same_bits(tmp_path):
    """omega1 only rescales the pendulum: its boundaries in (k, R) are refined at the first
    omega1 and repeated. The repeated rows equal, bit for bit, those of atlases with omega1
    fixed at each value, and the evaluations are those of one value."""
    grid = ('mechanism = "rotary_pendulum"\n[grid]\nk = {start = 1.0, stop = 2.5, num = 5}\n'
            'R = {start = 0.0, stop = 0.35, num = 6}\n')
    both = boundaries.refine(atlas(tmp_path, grid + 'omega1 = [20.0, 60.0]\n'), "regime",
                             1e-9)
    assert "omega1" in both.attrs["repeated_along"]
    for value in (20.0, 60.0):
        alone = boundaries.refine(atlas(tmp_path, grid + f"[fixed]\nomega1 = {value}\n",
                                        f"at{value:g}.nc"), "regime", 1e-9)
        rows = both.sel(crossing=both["omega1"].values == value)
        assert rows.sizes["crossing"] == alone.sizes["crossing"] > 0
        for name in alone.variables:
            if name != "grid_point":  # flat indices of different grids
                np.testing.assert_array_equal(rows[name].values, alone[name].values,
                                              err_msg=name)
        assert both.attrs["kernel_evaluations"] == alone.attrs["kernel_evaluations"]
