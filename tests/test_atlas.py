"""Atlas round trip: CF attributes, flags, provenance, chunk/thread invariance, queries."""

import json

import numpy as np
import pytest
import xarray as xr

from sweep import engine, runner, spec, store
from sweep.cli import main
from sweep.errors import UserError
from sweep.selection import evaluate, select
from tests.conftest import crank_rocker_point
from tests.command_line import run_cli

SPEC = '''
mechanism = "crank_rocker"
[grid]
R = {start = 0.05, stop = 0.4, num = 13}
largest_link = {start = 1.5, stop = 20.0, num = 17, scale = "log"}
type = ["a", "b", "c"]
omega1 = [30.0, -20.0]
'''


def write(tmp_path, name, chunk=None, workers=None, text=SPEC):
    s = spec.parse(text)
    path = tmp_path / name
    runner.run_sweep(s, path, chunk=chunk, progress=False, workers=workers, history="test")
    return xr.open_dataset(path)


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    return write(tmp_path_factory.mktemp("ref"), "ref.nc", chunk=100000, workers=1)


def test_cf_attributes_and_provenance(reference):
    ds = reference
    for name in list(ds.data_vars) + list(ds.coords):
        assert "units" in ds[name].attrs and "long_name" in ds[name].attrs, name
    for name in ds.data_vars:
        if name != "status":
            assert ds[name].attrs["ancillary_variables"] == "status"
    flags = ds["status"].attrs
    meanings = flags["flag_meanings"].split()
    assert meanings[0] == "ok" and len(meanings) == len(flags["flag_values"])
    assert set(np.unique(ds["status"].values)) <= set(flags["flag_values"].tolist())
    for key in ("Conventions", "title", "mechanism", "spec", "method", "package_versions",
                "code_version", "history"):
        assert key in ds.attrs, key
    filled = json.loads(ds.attrs["spec"])
    assert filled["fixed"]["crank_length"] == 0.1 and filled["method"]["geometry_tol"] == 1e-9
    assert json.loads(ds.attrs["package_versions"])["numba"]
    assert list(ds.dims) == ["R", "largest_link", "type", "omega1"]


def test_atlas_values_equal_the_kernel_point_by_point(reference):
    sub = reference.isel(R=7, largest_link=11, type=2, omega1=1)
    out, status = crank_rocker_point(type="c", R=float(sub.R), largest_link=float(sub.largest_link),
                                     omega1=float(sub.omega1))
    meanings = reference.status.attrs["flag_meanings"].split()
    codes = list(reference.status.attrs["flag_values"])
    assert meanings[codes.index(int(sub.status))] == status
    checked = [name for name in out if name in reference.variables]  # not on request
    assert set(reference.data_vars) - {"status"} <= set(checked)
    for name in checked:
        np.testing.assert_equal(float(sub[name]), out[name])


@pytest.mark.slow
@pytest.mark.parametrize("chunk, workers", [(1, 2), (37, 1), (500, 2), (5000, 2)])
def test_bit_identical_whatever_chunk_size_and_threads(tmp_path, reference, chunk, workers):
    other = write(tmp_path, f"c{chunk}.nc", chunk=chunk, workers=workers)
    xr.testing.assert_identical(other.drop_attrs(deep=False), reference.drop_attrs(deep=False))
    for name in reference.data_vars:
        assert np.array_equal(other[name].values, reference[name].values, equal_nan=True)


def test_chunk_choice_is_balanced_and_bounded():
    assert engine.choose_chunks((1000, 1000), 10000) == (100, 100)
    assert engine.choose_chunks((3, 10**6), 131072) == (3, 43690)
    c = engine.choose_chunks((71, 240, 3), 4096)
    assert np.prod(c) <= 4096 and c[2] == 3


def test_failed_run_leaves_no_atlas_but_keeps_its_finished_blocks(tmp_path, monkeypatch,
                                                                  reference):
    """A block that fails partway: no atlas and no temporary netCDF, but the finished blocks
    stay in the store, and --resume computes only the rest, to the same bits."""
    s = spec.parse(SPEC)
    calls = []
    real = engine.run_block

    def flaky(sweep, location):
        calls.append(location)
        if len(calls) == 5:
            raise RuntimeError("disk full")
        return real(sweep, location)

    monkeypatch.setattr(engine, "run_block", flaky)
    target = tmp_path / "a.nc"
    with pytest.raises(RuntimeError):
        runner.run_sweep(s, target, chunk=50, progress=False, workers=1)
    assert not target.exists() and not list(tmp_path.glob(".a.nc.tmp*"))
    kept = list(store.partial_dir(target).glob("*.npy"))
    assert len(kept) >= 4
    monkeypatch.setattr(engine, "run_block", real)
    calls.clear()
    monkeypatch.setattr(engine, "run_block", lambda sw, loc: (calls.append(loc), real(sw, loc))[1])
    done = runner.run_sweep(s, target, chunk=50, progress=False, workers=2, resume=True,
                           history="test")
    assert done["reused"] == len(kept) and len(calls) == done["blocks"] - len(kept)
    assert not store.partial_dir(target).exists()
    ds = xr.open_dataset(target)
    for name in reference.data_vars:
        assert np.array_equal(ds[name].values, reference[name].values, equal_nan=True)


def interrupted_run(tmp_path, monkeypatch):
    """A run stopped at its first block: the store exists, the atlas does not."""
    s = spec.parse(SPEC)
    target = tmp_path / "a.nc"
    with monkeypatch.context() as patch:
        patch.setattr(engine, "run_block",
                      lambda *a: (_ for _ in ()).throw(KeyboardInterrupt))
        with pytest.raises(KeyboardInterrupt):
            runner.run_sweep(s, target, chunk=50, progress=False, workers=1)
    assert store.partial_dir(target).exists() and not target.exists()
    return s, target


def test_resume_refuses_a_different_spec(tmp_path, monkeypatch):
    s, target = interrupted_run(tmp_path, monkeypatch)
    other = spec.parse(SPEC.replace("num = 13", "num = 14"))
    with pytest.raises(UserError, match="different spec"):
        runner.run_sweep(other, target, chunk=50, progress=False, resume=True)
    with pytest.raises(UserError, match="pass resume=True"):
        runner.run_sweep(s, target, chunk=50, progress=False)  # neither resume nor force


def test_in_memory_dataset_equals_the_written_atlas(tmp_path, reference):
    lazy = engine.build(spec.parse(SPEC).with_run(chunk=300)).compute()
    for name in reference.data_vars:
        assert np.array_equal(lazy[name].values, reference[name].values, equal_nan=True)


def test_query_language(reference):
    mask = evaluate(reference, 'restitution_kinematic > -0.32 and lambda2 <= 3 and '
                               'type == "a" and status == "ok"')
    rk = reference.restitution_kinematic.values
    manual = ((rk > -0.32) & (reference.lambda2.values <= 3)
              & (reference.type.values == "a")[None, None, :, None]
              & (reference.status.values == 0))
    assert mask.values.sum() > 0 and np.array_equal(mask.values, manual)
    frame = select(reference, 'R > 0.25 and R < 0.3 and status == "ok"', sort="impact_speed",
                   limit=5)
    assert len(frame) == 5 and frame["impact_speed"].is_monotonic_increasing
    assert set(frame["status"]) == {"ok"}


@pytest.mark.parametrize("expr", [
    "__import__('os').system('echo hacked')", "R.__class__", "open('x')", "R[0]",
    "lambda: 1", "[x for x in R]", "R if R else R", "status == 'exploded'", "R + ", "R > 'a'",
    "unknown > 1", "R", "(" * 200 + "R" + ")" * 200, "R > 1; import os", "R := 3",
    "True", "f'{R}'", "R > 1 and 2",
])
def test_hostile_or_wrong_queries_are_one_line_user_errors(reference, expr):
    with pytest.raises(UserError) as err:
        evaluate(reference, expr)
    assert "\n" not in str(err.value) and str(err.value).startswith("where:")


def test_query_and_chart_cli(tmp_path, reference, capsys):
    path = reference.encoding["source"]
    with pytest.raises(SystemExit) as e:
        main(["query", path, "--where", 'type == "c" and largest_link > 10', "--limit", "3",
              "--format", "csv", "--columns", "lambda0,impact_speed"])
    out = capsys.readouterr().out.strip().splitlines()
    assert e.value.code == 0 and out[0] == "R,largest_link,type,omega1,lambda0,impact_speed"
    assert len(out) == 4
    png = tmp_path / "c.png"
    with pytest.raises(SystemExit) as e:
        main(["chart", path, "--x", "R", "--y", "largest_link", "--color", "impact_speed",
              "-o", str(png)])
    assert e.value.code == 2  # two other axes of more than one value (type, omega1)
    with pytest.raises(SystemExit) as e:
        main(["chart", path, "--x", "lambda0", "--y", "lambda2", "--color", "gamma",
              "-o", str(png)])
    assert e.value.code == 2


def test_atlas_can_be_reopened_after_another_handle_closed(tmp_path):
    """Regression: categorical coords as HDF5 vlen strings made a reopen segfault
    (xarray #8289). Run in a subprocess so a crash fails the test instead of pytest."""
    import subprocess
    import sys

    path = tmp_path / "r.nc"
    write(tmp_path, "r.nc").close()
    code = (f"import xarray as xr\np = {str(path)!r}\na = xr.open_dataset(p)\n"
            "b = xr.open_dataset(p); b.status.values; b.close()\n"
            "c = xr.open_dataset(p); print(list(c.type.values), int(a.status.sum()))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr[-500:]
    assert out.stdout.startswith("['a', 'b', 'c']")


def test_resume_refuses_a_different_code_version(tmp_path, monkeypatch):
    s, target = interrupted_run(tmp_path, monkeypatch)
    monkeypatch.setattr(store, "code_version", lambda: "9.9.9+git.other")
    with pytest.raises(UserError, match="different code version"):
        runner.run_sweep(s, target, chunk=50, progress=False, resume=True)


def test_small_grids_get_several_blocks_and_time_scale_axes_stay_whole():
    """Without an explicit chunk a grid is cut into at least MIN_BLOCKS blocks, so a small
    grid of an expensive mechanism uses every core; axes a mechanism rescales instead of
    solving again (the pendulum's omega1, l2) stay whole in every block."""
    from sweep import engine, spec
    s = spec.parse('mechanism = "rotary_pendulum"\n[grid]\nk = {start = 1.0, stop = 2.5, '
                   'num = 40}\nomega1 = [20.0, 40.0, 60.0]')
    plan = engine.Plan(s)
    assert plan.n_blocks >= engine.MIN_BLOCKS and plan.chunk_shape[1] == 3
    explicit = spec.parse('mechanism = "rotary_pendulum"\n[run]\nchunk = 1000\n[grid]\n'
                          'k = {start = 1.0, stop = 2.5, num = 40}\nomega1 = [20.0, 40.0]')
    assert engine.Plan(explicit).n_blocks == 1  # a chunk the user gave is kept
    assert engine.choose_chunks((40, 3, 5), 30, whole=(1,)) == (3, 3, 3)




def test_query_sorts_best_first_and_prints_words_units_and_a_count(reference, capsys):
    """Issue 15: descending order, flags as their meanings (not 1.0 / -1.0), units under
    the header, and how many points matched."""
    path = reference.encoding["source"]
    code, out, _ = run_cli(capsys, "query", path, "--where", 'status == "ok"', "--sort",
                           "impact_speed", "--descending", "--limit", "4", "--columns",
                           "impact_speed,assembly_branch,status")
    lines = out.splitlines()
    assert code == 0 and lines[0].split() == ["R", "largest_link", "type", "omega1",
                                              "impact_speed", "assembly_branch", "status"]
    assert "[m s-1]" in lines[1] and "[rad s-1]" in lines[1]  # units under the header
    speeds = [float(line.split()[4]) for line in lines[2:6]]
    assert speeds == sorted(speeds, reverse=True)
    ok = reference.impact_speed.where(reference.status == 0)
    assert speeds[0] == pytest.approx(float(ok.max()), rel=1e-6)
    assert all(line.split()[5] in ("plus", "minus") for line in lines[2:6])
    total = int((reference.status == 0).sum())
    assert lines[-1] == f"4 of {total:,} matching points"
    code, out, _ = run_cli(capsys, "query", path, "--sort", "impact_speed", "--desc",
                           "--limit", "2", "--format", "json", "--columns", "impact_speed")
    rows = json.loads(out)
    assert code == 0 and rows[0]["impact_speed"] == float(np.nanmax(reference.impact_speed))
    assert len(out) < 400  # shortest float repr, no 1919.999999621602001


@pytest.mark.parametrize("expr, words", [
    ("type == 1", "type is text and is compared with a number"),
    ("1 < type", "type is text and is compared with a number"),
    ("os.system(1) > 0", "function 'os.system' is not allowed"),
])
def test_query_mistakes_name_what_was_wrong(reference, capsys, expr, words):
    code, out, err = run_cli(capsys, "query", reference.encoding["source"], "--where", expr)
    assert code == 2 and words in err and len(err.strip().splitlines()) == 1


def test_an_atlas_with_profiles_queries_its_scalars_and_a_profile_at_an_angle(tmp_path,
                                                                               capsys):
    """Issue 15: a linkage_forces atlas (profiles over crank_angle) made `sweep query`
    exit 1 unless --columns left every profile out."""
    s = spec.parse('mechanism = "linkage_forces"\n[grid]\nomega1 = [5.0, 20.0]\n'
                   'tilt = [0.0, 0.5]\n[method]\nprofile_points = 72\n')
    target = tmp_path / "lf.nc"
    runner.run_sweep(s, target, progress=False, history="test")
    code, out, _ = run_cli(capsys, "query", str(target), "--format", "csv")
    assert code == 0 and "F21_n" not in out.splitlines()[0]
    assert "force_peak_D" in out.splitlines()[0] and len(out.splitlines()) == 5
    code, out, _ = run_cli(capsys, "query", str(target), "--columns", "F21_n", "--at",
                           "crank_angle=90deg", "--format", "csv")
    ds = xr.open_dataset(target)
    expected = ds.F21_n.sel(crank_angle=np.radians(90), method="nearest")
    got = np.array([float(line.split(",")[-1]) for line in out.splitlines()[1:]])
    assert code == 0 and np.allclose(got, expected.values.ravel(), rtol=1e-12)
    code, _, err = run_cli(capsys, "query", str(target), "--columns", "F21_n")
    assert code == 2 and "--at crank_angle=VALUE" in err
    code, _, err = run_cli(capsys, "query", str(target), "--columns", "F21_n", "--at",
                           "crank_angle=90")
    assert code == 2 and "outside the profile's range" in err and "90deg" in err


@pytest.mark.parametrize("example", ["crank_rocker", "linkage_forces", "rotary_pendulum",
                                     "spring_balancer"])
def test_the_writers_template_defines_what_the_lazy_dataset_does(example):
    """The atlas writer defines variables from ``engine.build(lazy=False)``, a Template that
    does without xarray and dask (building a Dataset imports dask: 0.3 s of a small run);
    the lazy Dataset that Python users get must define the same atlas: names in order,
    dimensions, dtypes, shapes, attributes and encodings, profiles included."""
    from importlib import resources

    text = (resources.files("sweep.example_specs") / f"{example}.toml").read_text()
    s = spec.parse(text)
    lazy, template = engine.build(s), engine.build(s, lazy=False)
    assert list(template.coords) == list(lazy.coords)
    assert list(template.data_vars) == list(lazy.data_vars)
    assert template.sizes == dict(lazy.sizes)
    assert template.attrs.keys() == lazy.attrs.keys()
    for key, value in lazy.attrs.items():
        if key != "code_version":
            assert template.attrs[key] == value, key
    for name in list(lazy.coords) + list(lazy.data_vars):
        a, b = template[name], lazy[name]
        assert (a.dims, a.dtype, a.shape) == (b.dims, b.dtype, b.shape), name
        assert a.attrs.keys() == b.attrs.keys() and a.encoding == b.encoding, name
        for key, value in b.attrs.items():
            assert np.array_equal(np.asarray(a.attrs[key]), np.asarray(value)), (name, key)
    assert np.array_equal(template["status"].values, np.zeros(template["status"].shape))


@pytest.mark.parametrize("level", [0, 1, 6])
@pytest.mark.parametrize("text, chunk", [
    (SPEC, 37),  # 4-D grid, flags, edge blocks smaller than a chunk
    ('mechanism = "linkage_forces"\n[grid]\nomega1 = [5.0, 20.0, 30.0]\n'
     'tilt = [0.0, 0.5]\n[method]\nprofile_points = 72\n', 2)])  # profiles in the chunks
def test_chunks_written_whole_decode_to_the_values_and_name_their_filters(tmp_path, text,
                                                                          chunk, level):
    """The writer encodes each block as a whole HDF5 chunk itself (shuffle, then deflate
    by ISA-L up to level 3, zlib above; edge chunks padded) on several threads, instead of
    letting netCDF4 compress on one. netCDF-C, another HDF5 build, must read back exactly
    the values that the in-memory dataset (no writer at all) holds, and the filters and
    level the spec asked for."""
    import netCDF4

    s = spec.parse(text + f"[run]\ncompress_level = {level}\n")
    target = tmp_path / "a.nc"
    runner.run_sweep(s, target, chunk=chunk, workers=2, progress=False, history="test")
    expected = engine.build(s.with_run(chunk=chunk)).compute()
    with netCDF4.Dataset(target) as nc:
        nc.set_auto_mask(False)
        for name in expected.data_vars:
            var = nc[name]
            assert np.array_equal(var[...], expected[name].values, equal_nan=True), name
            filters = var.filters()
            assert filters["zlib"] == (level > 0) and filters["complevel"] == level, name
            assert filters["shuffle"] == (level > 0 and name != "status"), name
            assert var.chunking() != "contiguous" and var.chunking()[0] <= chunk, name
