"""Spec validation and the CLI: bad input gives exit 2, one line naming the key, no files."""

import subprocess
import sys

import pytest

from sweep.cli import main

GOOD = '''
mechanism = "crank_rocker"
[grid]
R = {start = 0.1, stop = 0.3, num = 3}
largest_link = [2.5, 3.0]
'''

# (spec text, a word the one-line message must contain)
MALFORMED = [
    ('mechanism = "crank_rocker"\n[grid]\nR = {start = 0.1, stop = 0.3, num = 0}\nlargest_link = [3.0]', "grid.R.num"),
    ('mechanism = "crank_rocker"\n[grid]\nR = {start = 0.1, stop = 0.3}\nlargest_link = [3.0]', "grid.R.num"),
    ('mechanism = "crank_rocker"\n[grid]\nR = {start = 0.1, stop = 1.3, num = 4}\nlargest_link = [3.0]', "grid.R"),
    ('mechanism = "crank_rocker"\n[grid]\nR = {start = 0.1, stop = nan, num = 4}\nlargest_link = [3.0]', "grid.R"),
    ('mechanism = "crank_rocker"\n[grid]\nR = {start = 0.1, stop = inf, num = 4}\nlargest_link = [3.0]', "grid.R"),
    ('mechanism = "crank_rocker"\n[grid]\nR = {start = 0.2, stop = 0.2, num = 4}\nlargest_link = [3.0]', "grid.R"),
    ('mechanism = "crank_rocker"\n[grid]\nR = []\nlargest_link = [3.0]', "grid.R"),
    ('mechanism = "crank_rocker"\n[grid]\nR = [0.1, 0.1]\nlargest_link = [3.0]', "grid.R"),
    ('mechanism = "crank_rocker"\n[grid]\nR = ["0.1"]\nlargest_link = [3.0]', "grid.R"),
    ('mechanism = "crank_rocker"\n[grid]\nR = {start = 0.1, stop = 0.3, num = 3, scale = "cubic"}\nlargest_link = [3.0]', "grid.R.scale"),
    ('mechanism = "crank_rocker"\n[grid]\nR = {start = -0.1, stop = 0.3, num = 3, scale = "log"}\nlargest_link = [3.0]', "grid.R"),
    ('mechanism = "crank_rocker"\n[grid]\nR = {start = 0.1, stop = 0.3, num = 3, step = 1}\nlargest_link = [3.0]', "grid.R.step"),
    ('mechanism = "crank_rocker"\n[grid]\nwobble = [1.0]', "grid.wobble"),
    ('mechanism = "crank_rocker"\n[grid]\nlargest_link = [3.0]\n[fixed]\nwobble = 1.0', "fixed.wobble"),
    ('mechanism = "crank_rocker"\n[grid]\nlargest_link = [3.0]\n[fixed]\nlargest_link = 2.0', "largest_link"),
    ('mechanism = "crank_rocker"\n[grid]\nlargest_link = [3.0]\n[fixed]\nomega1 = 0.0', "fixed.omega1"),
    ('mechanism = "crank_rocker"\n[grid]\nlargest_link = [3.0]\n[fixed]\ncrank_length = -0.1', "fixed.crank_length"),
    ('mechanism = "crank_rocker"\n[grid]\nlargest_link = [3.0]\n[fixed]\nsigma = 2', "fixed.sigma"),
    ('mechanism = "crank_rocker"\n[grid]\nlargest_link = [3.0]\ntype = ["a", "d"]', "grid.type"),
    ('mechanism = "crank_rocker"\n[grid]\ntype = {start = 0, stop = 1, num = 2}\nlargest_link = [3.0]', "grid.type"),
    ('mechanism = "crank_rocker"\n[grid]\nR = [0.2, 0.3]', "largest_link"),
    ('mechanism = "crank_rocker"\n[grid]\nlargest_link = [3.0]\n[fixed]\nlambda2 = 2.0', "lambda2"),
    ('mechanism = "crank_rocker"\n[grid]\ntype = ["general"]\n[fixed]\nlambda0 = 2.0\nlambda2 = 3.0', "lambda3"),
    ('mechanism = "crank_rocker"\n[grid]\ntype = ["b"]\n[fixed]\nlambda0 = 5.0\nlargest_link = 14.0', "largest_link"),
    ('mechanism = "crank_rocker"\noutputs = ["rocker_speed"]\n[grid]\nlargest_link = [3.0]', "outputs"),
    ('mechanism = "crank_rocker"\noutputs = []\n[grid]\nlargest_link = [3.0]', "outputs"),
    ('mechanism = "crank_rocker"\n[grid]\nlargest_link = [3.0]\n[method]\ngeometry_tol = -1.0', "method.geometry_tol"),
    ('mechanism = "crank_rocker"\n[grid]\nlargest_link = [3.0]\n[method]\nrtol = 1e-9', "method.rtol"),
    ('mechanism = "crank_rocker"\n[grid]\nlargest_link = [3.0]\n[run]\nchunk = 0', "run.chunk"),
    ('mechanism = "crank_rocker"\n[grid]\nlargest_link = [3.0]\n[run]\nworkers = 0', "run.workers"),
    ('mechanism = "crank_rocker"\n[grid]\nlargest_link = [3.0]\n[run]\nscheduler = 5', "run.scheduler"),
    ('mechanism = "crank_rocker"\n[grid]\nlargest_link = [3.0]\n[chart]\nx = "R"\ny = "largest_link"\ncolor = "gamma"', "chart.x"),
    ('mechanism = "gearbox"\n[grid]\nx = [1.0]', "mechanism"),
    ('mechanism = "crank_rocker"', "grid"),
    ('mechanism = "crank_rocker"\n[grid]', "grid"),
    ('mechanism = "crank_rocker"\ncolour = "red"\n[grid]\nlargest_link = [3.0]', "colour"),
    ('mechanism = "crank_rocker"\n[grid\nlargest_link = [3.0]', "invalid TOML"),
    ('mechanism = 3\n[grid]\nlargest_link = [3.0]', "mechanism"),
    ('mechanism = "crank_rocker"\n[grid]\nlargest_link = {start = 1.0, stop = 2.0, num = 100000}\nR = {start = 0.1, stop = 0.3, num = 100000}\nomega1 = {start = 1.0, stop = 2.0, num = 100000}', "grid"),
]


@pytest.mark.parametrize("text, key", MALFORMED, ids=[str(i) for i in range(len(MALFORMED))])
def test_malformed_spec_rejected_with_one_line_and_nothing_written(tmp_path, capsys, text, key):
    spec = tmp_path / "bad.toml"
    spec.write_text(text)
    atlas = tmp_path / "bad.nc"
    with pytest.raises(SystemExit) as exit_info:
        main(["run", str(spec), "-o", str(atlas), "-q"])
    err = capsys.readouterr().err
    assert exit_info.value.code == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("sweep: error: ") and key in lines[0], lines[0]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.toml"]


def test_corpus_is_large_enough():
    assert len(MALFORMED) >= 20


@pytest.mark.parametrize("argv, key", [
    (["run", "no/such/spec.toml"], "no such file"),
    (["run", "--chunk", "0"], "--chunk"),
    (["run", "--bogus"], "--bogus"),
    (["frobnicate"], "frobnicate"),
    (["query", "missing.nc", "--where", "x > 1"], "atlas"),
    (["examples", "nope"], "nope"),
])
def test_bad_cli_arguments_exit_2_with_one_line(capsys, tmp_path, monkeypatch, argv, key):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as exit_info:
        main(argv)
    err = capsys.readouterr().err.strip().splitlines()
    assert exit_info.value.code == 2 and len(err) == 1 and key in err[0], err
    assert not list(tmp_path.glob("*.nc"))


def test_existing_atlas_is_not_overwritten_without_force(tmp_path, capsys):
    spec = tmp_path / "s.toml"
    spec.write_text(GOOD)
    atlas = tmp_path / "s.nc"
    atlas.write_text("precious")
    with pytest.raises(SystemExit) as e:
        main(["run", str(spec), "-o", str(atlas), "-q"])
    assert e.value.code == 2 and "--force" in capsys.readouterr().err
    assert atlas.read_text() == "precious"
    with pytest.raises(SystemExit) as e:
        main(["run", str(spec), "-o", str(atlas), "-q", "--force"])
    assert e.value.code == 0


def test_a_grid_list_in_any_order_is_an_increasing_axis(tmp_path):
    """A chart's cells (pcolormesh, shading "nearest") and a refined boundary lie between
    neighbouring grid values: a list given in any order becomes an increasing axis of the
    atlas, and its chart is drawn without matplotlib's warning that the cell centres are
    not monotonic (its cells were drawn out of place)."""
    import warnings

    import xarray as xr

    spec = tmp_path / "s.toml"
    spec.write_text('mechanism = "crank_rocker"\n[grid]\nR = [0.3, 0.1, 0.2]\n'
                    'largest_link = [3.0, 2.5, 2.8]\n[chart]\nx = "R"\ny = "largest_link"\n'
                    'color = "impact_speed"\n')
    atlas = tmp_path / "s.nc"
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(SystemExit) as e:
            main(["run", str(spec), "-o", str(atlas), "-q"])
    assert e.value.code == 0 and atlas.with_suffix(".png").exists()
    with xr.open_dataset(atlas) as ds:
        assert list(ds["R"].values) == [0.1, 0.2, 0.3]
        assert list(ds["largest_link"].values) == [2.5, 2.8, 3.0]


@pytest.mark.slow
def test_console_entry_points_run_the_default_sweep(tmp_path):
    """As a user would: python -m sweep run (the built-in default) writes atlas + chart."""
    out = subprocess.run([sys.executable, "-m", "sweep", "run", "-o", "default.nc"],
                         cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr
    assert (tmp_path / "default.nc").stat().st_size > 0
    assert (tmp_path / "default.png").read_bytes()[:4] == b"\x89PNG"
    assert "atlas:" in out.stdout and "chart:" in out.stdout
    bad = subprocess.run([sys.executable, "-m", "sweep", "run", "nope.toml"], cwd=tmp_path,
                         capture_output=True, text=True)
    assert bad.returncode == 2 and len(bad.stderr.strip().splitlines()) == 1
    info = subprocess.run([sys.executable, "-m", "sweep", "info", "default.nc"], cwd=tmp_path,
                          capture_output=True, text=True)
    assert info.returncode == 0 and "status: ok" in info.stdout


def test_examples_list_and_write(tmp_path, capsys):
    with pytest.raises(SystemExit) as e:
        main(["examples"])
    assert e.value.code == 0 and "crank_rocker" in capsys.readouterr().out
    target = tmp_path / "cr.toml"
    with pytest.raises(SystemExit) as e:
        main(["examples", "crank_rocker", "-o", str(target)])
    from sweep import spec
    assert spec.load(target).mechanism.name == "crank_rocker"


@pytest.mark.parametrize("name", sorted(__import__("sweep.api", fromlist=["examples"]).examples()))
def test_every_builtin_example_parses_and_runs_on_a_corner_of_its_grid(tmp_path, name):
    """The examples users start from must not rot: each parses, and two points of its grid
    run through the whole pipeline to an atlas with units on every variable."""
    import xarray as xr

    from sweep import runner, spec
    from sweep.api import example_text as _example_text

    s = spec.parse(_example_text(name))
    for axis in s.axes:  # keep the first two values of every axis
        axis.values, axis.codes = axis.values[:2], axis.codes[:2]
    target = tmp_path / f"{name}.nc"
    runner.run_sweep(s, target, progress=False, history="example test")
    ds = xr.open_dataset(target)
    assert all(ds[v].attrs.get("units") for v in list(ds.data_vars) + list(ds.coords))
    assert ds["status"].size == 2 ** len(s.axes)


def test_crank_rocker_sweeps_its_own_link_ratios_through_the_cli(tmp_path):
    """Issue 12, item 1: this spec computed, then exited 1 ("variables {'lambda2'} are found
    in both data_vars and coords"). The output lambda2 only echoes the axis: the axis
    carries it."""
    import xarray as xr

    spec = tmp_path / "general.toml"
    spec.write_text('mechanism = "crank_rocker"\n[grid]\nlambda2 = [2.5, 3.0]\n[fixed]\n'
                    'type = "general"\nlambda0 = 2.0\nlambda3 = 1.5\n')
    with pytest.raises(SystemExit) as e:
        main(["run", str(spec), "-o", str(tmp_path / "general.nc"), "-q"])
    assert e.value.code == 0
    ds = xr.open_dataset(tmp_path / "general.nc")
    assert list(ds["lambda2"].values) == [2.5, 3.0] and "lambda2" not in ds.data_vars
    assert set(ds["lambda0"].values) == {2.0} and set(ds["lambda3"].values) == {1.5}


def on_new_terminal(monkeypatch, run) -> str:
    """What ``run()`` shows on standard error when that is a new pseudo-terminal: it
    reports a size of 0 x 0, and tqdm then printed every line empty."""
    import os
    import pty
    import select

    main_fd, terminal_fd = pty.openpty()
    terminal = os.fdopen(terminal_fd, "w")
    monkeypatch.setattr(sys, "stderr", terminal)
    run()
    terminal.flush()
    shown = b""
    while select.select([main_fd], [], [], 0.2)[0]:
        shown += os.read(main_fd, 65536)
    monkeypatch.setattr(sys, "stderr", sys.__stderr__)
    terminal.close()
    os.close(main_fd)
    return shown.decode()


def test_the_sweeps_progress_bar_shows_on_a_new_terminal(monkeypatch, tmp_path):
    """The block bar (shown after 1.5 s) on a 0 x 0 pseudo-terminal: it counts the blocks
    (it printed empty lines before the bar took its size from terminal_bar_size)."""
    import re
    import time

    from sweep import engine, runner, spec
    from sweep.api import example_text as _example_text

    s = spec.parse(_example_text("crank_rocker"))
    for axis in s.axes:
        axis.values, axis.codes = axis.values[:4], axis.codes[:4]
    run_block = engine.run_block

    def slow_block(sweep, location):
        time.sleep(0.3)
        return run_block(sweep, location)

    monkeypatch.setattr(engine, "run_block", slow_block)
    shown = on_new_terminal(monkeypatch, lambda: runner.run_sweep(
        s, tmp_path / "a.nc", chunk=4, workers=1, progress=True, history="bar test"))
    assert "sweep:" in shown and re.search(r"(\d+)/\1 \[", shown), repr(shown)


@pytest.mark.slow
def test_a_first_runs_compile_is_said_with_its_time_and_a_warm_start_says_nothing(
        monkeypatch, capsys):
    """A compile longer than runner.COMPILE_NOTICE_AFTER is announced, then how long it
    took; a warm start (the cache loads at once) prints nothing; on a terminal the wait
    shows the time so far, ticking every second (the stability example compiles for about
    a minute)."""
    import re
    import time

    from sweep import engine, runner

    # one group of entry points, compiled by the stand-in below
    monkeypatch.setattr(engine, "sample_parameters", lambda sweep: None)
    monkeypatch.setattr(engine, "compile_groups", lambda sweep, params: [None])
    monkeypatch.setattr(engine, "warm_up", lambda sweep, columns=None: time.sleep(1.2))
    runner.compile_first(None, announce=True)
    err = capsys.readouterr().err
    assert "compiling kernels (first run only" in err and re.search(r"compiled in \d+ s", err)
    runner.compile_first(None, announce=False)
    assert capsys.readouterr().err == ""
    monkeypatch.setattr(engine, "warm_up", lambda sweep, columns=None: None)
    runner.compile_first(None, announce=True)
    assert capsys.readouterr().err == ""

    # on a new terminal (0 x 0) the clock ticks
    monkeypatch.setattr(engine, "warm_up", lambda sweep, columns=None: time.sleep(2.6))
    shown = on_new_terminal(monkeypatch, lambda: runner.compile_first(None, announce=True))
    assert "compiling kernels (first run only" in shown and "00:01" in shown, shown
    assert re.search(r"compiled in \d+ s", shown)
