"""From an atlas to a decision (issue 39): requirements as data, the inverted inputs, Pareto
fronts with their pick rules, chained sweeps, and the bad input of each, one line."""

import json
import math

import numpy as np
import pytest
import xarray as xr

import sweep
from kernels.pareto import non_dominated
from sweep import runner, spec
from sweep.fronts import front
from tests.command_line import run_cli
from tests.conftest import interrupted_after

CR_SMALL = {"mechanism": "crank_rocker",
            "grid": {"R": {"start": 0.1, "stop": 0.4, "num": 7},
                     "largest_link": {"start": 1.6, "stop": 6.0, "num": 9, "scale": "log"},
                     "type": ["a", "b", "c"]},
            "fixed": {"envelope": 0.6, "impact_speed_limit": 10.0, "rocker_inertia": 0.05},
            "outputs": ["lambda0", "lambda2", "lambda3", "impact_speed", "envelope",
                        "crank_length", "omega1", "transmission_angle_working",
                        "blow_energy", "blow_rate"]}


# ---------------------------------------------------------------- the front, exactly

def brute_front(values: np.ndarray) -> np.ndarray:
    """O(n^2): a design is on the front when no other is <= in all and < in one."""
    keep = np.ones(len(values), bool)
    for i in range(len(values)):
        no_worse = np.all(values <= values[i], axis=1)
        better = np.any(values < values[i], axis=1)
        keep[i] = not np.any(no_worse & better)
    return keep


@pytest.mark.parametrize("k", [1, 2, 3, 4, 5])
def test_the_front_kernel_is_the_brute_force_front_with_ties(k):
    rng = np.random.default_rng(39 + k)
    for trial in range(120):
        n = int(rng.integers(1, 400))
        values = (rng.integers(0, 5, (n, k)).astype(float) if trial % 2
                  else rng.normal(size=(n, k)))
        assert np.array_equal(non_dominated(values), brute_front(values)), (k, trial)


def random_atlas(rng, shape=(23, 17)):
    """An atlas in memory with statuses, requirements, NaN and ties in its outputs."""
    size = shape[0] * shape[1]
    outputs = {name: np.round(rng.normal(size=shape), 1) for name in "pqrs"}
    for values in outputs.values():
        values[rng.random(shape) < 0.05] = np.nan
    status = rng.choice(np.array([0, 0, 0, 1, 2], np.int8), size=shape)
    req = rng.choice(np.array([0, 0, 0, 1, 2, 3], np.int8), size=shape)
    data = {n: (("x", "y"), v, {"units": "m", "long_name": n}) for n, v in outputs.items()}
    data["status"] = (("x", "y"), status, {"flag_values": np.array([0, 1, 2], np.int8),
                                           "flag_meanings": "ok not_assemblable degenerate",
                                           "units": "1", "long_name": "status"})
    data["requirements"] = (("x", "y"), req, {
        "flag_values": np.arange(4, dtype=np.int8), "units": "1", "long_name": "req",
        "flag_meanings": "met no_value above_p below_q"})
    assert size == status.size
    return xr.Dataset(data, coords={"x": np.arange(shape[0], dtype=float),
                                    "y": np.linspace(0, 1, shape[1])})


@pytest.mark.parametrize("senses", [("max", "min"), ("min", "min", "max"),
                                    ("max", "max", "min", "min")])
def test_the_front_of_random_atlases_is_the_brute_force_front_of_their_feasible_designs(
        senses):
    """Statuses, failed requirements and NaN objectives leave a design out; among the
    rest, the front is exactly the brute-force one, ties kept together."""
    rng = np.random.default_rng(len(senses))
    names = "pqrs"[:len(senses)]
    for trial in range(15):
        ds = random_atlas(rng)
        maximize = [n for n, s in zip(names, senses) if s == "max"]
        minimize = [n for n, s in zip(names, senses) if s == "min"]
        where = "y > 0.2" if trial % 3 == 0 else None
        result = front(ds, maximize, minimize, where=where)
        feasible = (ds.status.values == 0) & (ds.requirements.values == 0)
        if where:
            feasible &= ds.y.values[None, :] > 0.2
        columns = [(-1 if n in maximize else 1) * ds[n].values for n in maximize + minimize]
        values = np.stack([c.ravel() for c in columns], axis=1)
        candidates = np.flatnonzero(feasible.ravel() & np.all(np.isfinite(values), axis=1))
        expected = candidates[brute_front(values[candidates])]
        assert sorted(result.designs.grid_point.values.tolist()) == expected.tolist()
        assert result.candidates == candidates.size


def test_the_pick_rules_against_their_definitions():
    rng = np.random.default_rng(5)
    ds = random_atlas(rng, (40, 40))
    result = front(ds, ["p"], ["q"])
    f = np.stack([-result.designs.p.values, result.designs.q.values], axis=1)
    scaled = (f - f.min(0)) / (f.max(0) - f.min(0))
    assert result.picked == int(np.argmin(np.hypot(scaled[:, 0], scaled[:, 1])))
    assert int(result.designs.picked.values.sum()) == 1
    assert result.designs.picked.values[result.picked] == 1
    lexicographic = front(ds, ["p"], ["q"], pick="lexicographic")
    order = np.lexsort((f[:, 1], f[:, 0]))  # the first objective, ties by the second
    assert lexicographic.picked == int(order[0])
    weighted = front(ds, ["p"], ["q"], pick="weighted", weights=[1.0, 3.0])
    assert weighted.picked == int(np.argmin(scaled @ np.array([1.0, 3.0])))
    # the front is ordered by its first objective, best first
    assert np.all(np.diff(result.designs.p.values) <= 0)


def test_the_front_is_a_netcdf_selection_keeping_every_attribute(tmp_path):
    atlas = sweep.run(sweep.Sweep.from_dict(CR_SMALL))
    result = sweep.pareto(atlas, maximize=["blow_rate"], minimize=["envelope", "crank_length"],
                          path=tmp_path / "front.nc", chart=tmp_path / "front.png",
                          require=["blow_energy >= 10"])
    back = xr.open_dataset(tmp_path / "front.nc")
    for name in ("blow_rate", "impact_speed", "status", "requirements", "R", "type"):
        for key, value in atlas[name].attrs.items() if name in atlas else []:
            assert np.array_equal(np.asarray(back[name].attrs[key]), np.asarray(value)), \
                (name, key)
    for key in ("spec", "code_version", "mechanism", "package_versions", "method"):
        assert back.attrs[key] == atlas.attrs[key]
    record = json.loads(back.attrs["pareto"])
    assert record["objectives"] == ["max blow_rate", "min envelope", "min crank_length"]
    assert record["requirements"] == ["blow_energy >= 10"]
    assert int(back.picked.sum()) == 1 and back.sizes["design"] == result.designs.sizes[
        "design"]
    assert (tmp_path / "front.png").stat().st_size > 10_000
    assert set(back.type.values.tolist()) <= {"a", "b", "c"}


# ---------------------------------------------------------------- requirements

def test_a_planted_limit_flips_exactly_what_an_independent_evaluation_flips(tmp_path):
    """The spec's requirements, evaluated in every block, against numpy on the outputs:
    the flag, its binding limit (the most violated, relative to its limit) and the
    margin; the same whatever the chunk, and after an interrupted run resumes."""
    document = dict(CR_SMALL, requirements={"blow_energy": ">= 12",
                                            "transmission_angle_working": ">= 20deg",
                                            "blow_rate": "< 500"})
    s = spec.validate(document)
    whole = tmp_path / "whole.nc"
    runner.run_sweep(s, whole, chunk=10**6, progress=False)
    ds = xr.open_dataset(whole)
    e, mu, rate = (ds[n].values for n in ("blow_energy", "transmission_angle_working",
                                          "blow_rate"))
    slack = np.stack([(e - 12) / 12, (mu - math.radians(20)) / math.radians(20),
                      (500 - rate) / 500])
    holds = np.stack([e >= 12, mu >= math.radians(20), rate < 500])
    missing = ~np.all(np.isfinite(slack), axis=0)
    with np.errstate(invalid="ignore"):
        fails = ~holds & np.isfinite(slack)
    worst = np.where(fails, slack, np.inf)
    expected = np.where(fails.any(axis=0), 2 + np.argmin(worst, axis=0),
                        np.where(missing, 1, 0))
    assert np.array_equal(ds.requirements.values, expected)
    assert ds.requirements.attrs["flag_meanings"] == (
        "met no_value below_blow_energy below_transmission_angle_working above_blow_rate")
    assert np.allclose(ds.requirement_margin.values,
                       np.where(missing, np.nan, slack.min(axis=0)), rtol=0, atol=0,
                       equal_nan=True)
    assert 0 < (expected == 0).sum() < expected.size and (expected > 1).sum() > 0
    small = tmp_path / "small.nc"
    runner.run_sweep(s, small, chunk=7, progress=False, workers=2)
    for name in ("requirements", "requirement_margin"):
        assert np.array_equal(xr.open_dataset(small)[name].values, ds[name].values,
                              equal_nan=True)
    # an interrupted run, resumed: the same bits
    with interrupted_after(2):
        runner.run_sweep(s, tmp_path / "resumed.nc", chunk=7, progress=False, workers=1)
    runner.run_sweep(s, tmp_path / "resumed.nc", chunk=7, progress=False, workers=1,
                     resume=True)
    resumed = xr.open_dataset(tmp_path / "resumed.nc")
    for name in ds.data_vars:
        assert np.array_equal(resumed[name].values, ds[name].values, equal_nan=True), name
    # the same limits given on the command line evaluate the same flag
    again = sweep.with_requirements(ds.drop_vars(["requirements", "requirement_margin"]),
                                    ["blow_energy >= 12", "transmission_angle_working >= 20deg",
                                     "blow_rate < 500"])
    assert np.array_equal(again.requirements.values, ds.requirements.values)


def test_a_design_that_fails_is_never_ranked_above_one_that_meets_them():
    atlas = sweep.run(sweep.Sweep.from_dict(CR_SMALL))
    rows = sweep.query(atlas, 'status == "ok"', sort="blow_rate", descending=True,
                       require=["blow_energy >= 12"], columns=["blow_rate", "requirements"])
    met = (rows["requirements"] == "met").to_numpy()
    assert met.any() and not met.all()
    assert not np.any(~met[:-1] & met[1:])  # every met row before every failing one
    assert np.all(np.diff(rows["blow_rate"].to_numpy()[met]) <= 0)
    anyway = sweep.query(atlas, 'status == "ok"', sort="blow_rate", descending=True,
                         require=["blow_energy >= 12"], rank_all=True,
                         columns=["blow_rate"])
    assert np.all(np.diff(anyway["blow_rate"].to_numpy()) <= 0)


# ---------------------------------------------------------------- inverted inputs

def test_the_derived_crank_length_and_speed_put_designs_on_their_envelope_and_limit():
    """Each ok design exactly on its envelope and at the speed limit (1e-12), and the
    forward computation with the derived l1 and omega1 gives the same outputs."""
    atlas = sweep.run(sweep.Sweep.from_dict(CR_SMALL))
    ok = atlas.status.values == 0
    assert ok.sum() > 50
    assert np.allclose(atlas.envelope.values[ok], 0.6, rtol=1e-12, atol=0)
    assert np.allclose(atlas.impact_speed.values[ok], 10.0, rtol=1e-12, atol=0)
    lam = np.stack([np.ones_like(atlas.lambda0.values), atlas.lambda0.values,
                    atlas.lambda2.values, atlas.lambda3.values])
    assert np.allclose((atlas.crank_length.values * lam.max(axis=0))[ok], 0.6, rtol=1e-15,
                       atol=0)
    assert np.all(np.isnan(atlas.omega1.values[atlas.status.values == 2]))  # no linkage
    assert np.all(np.isnan(atlas.crank_length.values[atlas.status.values == 2]))
    rows = sweep.query(atlas, 'status == "ok"', columns=["crank_length", "omega1",
                                                         "impact_speed", "blow_energy"])
    for _, row in rows.sample(12, random_state=1).iterrows():
        forward = sweep.run({"mechanism": "crank_rocker",
                             "grid": {"R": [float(row.R)]},
                             "fixed": {"type": row.type, "largest_link": float(row.largest_link),
                                       "crank_length": float(row.crank_length),
                                       "omega1": float(row.omega1), "rocker_inertia": 0.05},
                             "outputs": ["impact_speed", "envelope", "blow_energy"]})
        assert float(forward.impact_speed[0]) == pytest.approx(10.0, rel=1e-12)
        assert float(forward.envelope[0]) == pytest.approx(0.6, rel=1e-12)
        assert float(forward.blow_energy[0]) == pytest.approx(row.blow_energy, rel=1e-12)


def test_a_recorded_inverted_spec_runs_again_and_records_what_was_given():
    s = sweep.Sweep.from_dict(CR_SMALL)
    assert "crank_length" not in s.spec["fixed"] and "omega1" not in s.spec["fixed"]
    assert s.spec["fixed"]["envelope"] == 0.6
    assert spec.validate(s.to_dict()).spec == s.spec


def test_the_flywheel_sized_for_a_speed_fluctuation_target():
    atlas = sweep.run({"mechanism": "impact_machine", "grid": {"R": [0.3]},
                       "fixed": {"flywheel_inertia": "for_delta_target"},
                       "method": {"tol": 1e-12, "delta_target": 0.02}})
    assert float(atlas.speed_fluctuation[0]) == pytest.approx(0.02, rel=1e-8)
    assert float(atlas.flywheel_inertia[0]) == pytest.approx(22.8224, rel=1e-5)


# ---------------------------------------------------------------- chained sweeps

@pytest.fixture(scope="module")
def source(tmp_path_factory):
    folder = tmp_path_factory.mktemp("chain")
    path = folder / "cr.nc"
    runner.run_sweep(spec.validate(CR_SMALL), path, progress=False)
    return path


def test_a_chained_sweep_equals_hand_written_specs_of_the_same_designs(source, tmp_path):
    document = {"mechanism": "linkage_forces",
                "grid": {"from": {"atlas": str(source), "where": 'type == "c"',
                                  "carry": ["blow_rate"]},
                         "m2": [2.0, 3.0]},
                "method": {"peak_samples": 91}}
    chained = tmp_path / "forces.nc"
    runner.run_sweep(spec.validate(document), chained, progress=False, chunk=5)
    ds = xr.open_dataset(chained)
    cr = xr.open_dataset(source)
    picked = cr.where((cr.status == 0) & (cr.type == "c"))
    n = int(np.isfinite(picked.lambda0.values).sum())
    assert ds.sizes["design"] == n and ds.sizes["m2"] == 2
    record = json.loads(ds.attrs["source_atlas"])
    assert record["code_version"] == cr.attrs["code_version"]
    assert record["spec"] == cr.attrs["spec"] and record["mechanism"] == "crank_rocker"
    assert json.loads(ds.attrs["spec"])["grid"]["from"]["designs"] == n
    for d in range(0, n, max(1, n // 6)):
        l1 = float(ds.l1[d])
        # the source's rocker_inertia, all as J3 about D with no mass
        hand = {"mechanism": "linkage_forces", "grid": {"m2": [2.0, 3.0]},
                "fixed": {"l0": float(ds.l0[d]), "l1": l1, "l2": float(ds.l2[d]),
                          "l3": float(ds.l3[d]), "omega1": float(ds.omega1[d]),
                          "J3": CR_SMALL["fixed"]["rocker_inertia"], "m3": 0.0},
                "method": {"peak_samples": 91}}
        by_hand = sweep.run(hand)
        for name in by_hand.data_vars:
            assert np.array_equal(by_hand[name].values, ds[name].isel(design=d).values,
                                  equal_nan=True), (d, name)
        grid_point = int(ds.source_index[d])
        point = cr.stack(p=list(cr.status.dims)).isel(p=grid_point)
        assert float(ds.l2[d]) == float(point.lambda2 * point.crank_length)
        assert float(ds.source_blow_rate[d]) == float(point.blow_rate)
        assert str(ds.source_type[d].values) == "c"


def test_a_chained_machine_and_six_link_take_the_designs_they_can(source, tmp_path):
    machine = spec.validate({"mechanism": "impact_machine",
                             "grid": {"from": {"atlas": str(source),
                                               "where": 'type == "a" and R > 0.35'}}})
    ds = runner.run_in_memory(machine)
    assert set(ds.type.values.tolist()) == {"general"} and ds.sizes["design"] > 0
    assert np.all(ds.status.values == 0)
    with pytest.raises(sweep.UserError, match="type == \"b\""):
        spec.validate({"mechanism": "six_link", "grid": {"from": {"atlas": str(source)}}})
    six = spec.validate({"mechanism": "six_link",
                         "grid": {"from": {"atlas": str(source), "where": 'type == "b"'}}})
    assert any("give no crank_length, omega1" in n for n in six.notes), six.notes
    six_ds = runner.run_in_memory(six)
    assert six_ds.sizes["design"] > 0
    if "rocker_inertia" in xr.open_dataset(source).variables:
        assert "rocker_inertia" in six.designs.columns


def test_a_front_is_a_source_and_the_picked_design_its_own_chain(source, tmp_path):
    sweep.pareto(str(source), ["blow_rate"], ["envelope", "crank_length"],
                 path=tmp_path / "front.nc")
    forces = spec.validate({"mechanism": "linkage_forces",
                            "grid": {"from": {"atlas": str(tmp_path / "front.nc"),
                                              "where": 'picked == "yes"'}}})
    ds = runner.run_in_memory(forces)
    assert ds.sizes["design"] == 1
    again = spec.validate({"mechanism": "crank_rocker",
                           "grid": {"from": {"atlas": str(tmp_path / "front.nc")}},
                           "fixed": {"envelope": 0.6, "impact_speed_limit": 10.0}})
    rerun = runner.run_in_memory(again)
    front_ds = xr.open_dataset(tmp_path / "front.nc")
    assert np.array_equal(rerun.impact_speed.values, front_ds.impact_speed.values)


def test_a_source_that_changed_is_refused_on_resume(source, tmp_path):
    document = {"mechanism": "linkage_forces", "grid": {"from": {"atlas": str(source)}}}
    recorded = spec.validate(document).to_dict()
    pinned = recorded["grid"]["from"]
    assert pinned["designs"] > 0 and len(pinned["sha256"]) == 64
    assert spec.grid_shape(recorded) == (pinned["designs"],)
    changed = dict(recorded, grid={"from": dict(pinned, sha256="0" * 64)})
    with pytest.raises(sweep.UserError, match="no longer gives the designs"):
        spec.validate(changed)


# ---------------------------------------------------------------- bad input, one line

@pytest.mark.parametrize("args, field", [
    (["--max", "no_such_output", "--min", "envelope"], "'no_such_output' is not a variable"),
    (["--max", "requirements", "--require", "blow_energy >= 1"], "is a flag"),
    (["--max", "status", "--min", "envelope"], "is a flag"),
    (["--max", "blow_rate", "--min", "envelope", "--require", "blow_rate > 1e9"],
     "no design is feasible"),
    (["--max", "blow_rate", "--max", "blow_rate"], "given twice"),
    (["--max", "blow_rate", "--min", "envelope", "--pick", "weighted"], "weights"),
    (["--max", "blow_rate", "--min", "envelope", "--pick", "weighted", "--weights", "1"],
     "weights: 1 given for 2"),
    ([], "at least one objective"),
    (["--max", "blow_rate", "--where", "R >"], "where:"),
    (["--max", "blow_rate", "--require", "blow_rate <= fast"], "require"),
])
def test_bad_pareto_input_is_one_line_exit_2_nothing_written(source, tmp_path, capsys, args,
                                                            field):
    out = tmp_path / "front.nc"
    code, _, err = run_cli(capsys, "pareto", source, *args, "-o", out, "--chart",
                           tmp_path / "front.png")
    assert code == 2 and field in err, err
    assert len(err.strip().splitlines()) == 1
    assert not out.exists() and not (tmp_path / "front.png").exists()
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("source_table, field", [
    ({"atlas": "/no/such/atlas.nc"}, "grid.from.atlas: no such file"),
    ({"atlas": "SOURCE", "map": {"lengths": "lambda0"}}, "grid.from.map.lengths: not a parameter"),
    ({"atlas": "SOURCE", "map": {"l0": "lambda9 * crank_length"}}, "unknown name 'lambda9'"),
    ({"atlas": "SOURCE", "map": {"l0": "-crank_length"}}, "allowed: a number > 0"),
    ({"atlas": "SOURCE", "where": 'type == "x"'}, "grid.from.where"),
    ({"atlas": "SOURCE", "where": "R > 5"}, "no design of"),
    ({"atlas": "SOURCE", "carry": ["nothing"]}, "grid.from.carry"),
    ({"atlas": "SOURCE", "colour": "red"}, "grid.from.colour: unknown key"),
    ({"where": "R > 0"}, "grid.from.atlas: required key is missing"),
])
def test_bad_chained_input_is_one_line_exit_2_nothing_written(source, tmp_path, capsys,
                                                             source_table, field):
    table = {k: (str(source) if v == "SOURCE" else v) for k, v in source_table.items()}
    text = 'mechanism = "linkage_forces"\n[grid]\nfrom = ' + _inline(table) + "\n"
    spec_file = tmp_path / "chain.toml"
    spec_file.write_text(text)
    code, _, err = run_cli(capsys, "run", spec_file, "-o", tmp_path / "chain.nc")
    assert code == 2 and field in err, err
    assert len(err.strip().splitlines()) == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["chain.toml"]


def test_a_source_of_another_mechanism_without_a_mapping_is_refused(tmp_path, capsys):
    balancer = tmp_path / "sb.nc"
    small = {"mechanism": "spring_balancer", "grid": {"r": [0.5, 1.0]}}
    runner.run_sweep(spec.validate(small), balancer, progress=False)
    with pytest.raises(sweep.UserError, match="no declared mapping from spring_balancer to "
                                              "linkage_forces"):
        spec.validate({"mechanism": "linkage_forces",
                       "grid": {"from": {"atlas": str(balancer)}}})
    with pytest.raises(sweep.UserError, match="not a readable netCDF atlas"):
        (tmp_path / "bad.nc").write_text("not netCDF")
        spec.validate({"mechanism": "linkage_forces",
                       "grid": {"from": {"atlas": str(tmp_path / "bad.nc")}}})


def _inline(table: dict) -> str:
    def one(v):
        if isinstance(v, dict):
            return _inline(v)
        if isinstance(v, list):
            return "[" + ", ".join(one(x) for x in v) + "]"
        return json.dumps(v)

    return "{" + ", ".join(f"{k} = {one(v)}" for k, v in table.items()) + "}"


# ---------------------------------------------------------------- the paper's claim

def test_CR_claim_type_c_blows_faster_at_equal_size_and_blow_energy_under_the_speed_limit():
    """[CR]: "type c allows a 4-5x higher blow rate at equal size and blow energy under the
    speed limit". At equal envelope and at the limit, a striker of the same mass strikes
    with the same energy; the blow rates' ratio is omega1_c / omega1_a = u31_a / u31_c =
    (1 + L)(gamma^2 + L) / (L (gamma^2 - 1)) (docs/models.md), 4-5 only for L ~ 5-7 at
    R = 0.3, and strongly dependent on R."""
    atlas = sweep.run(sweep.Sweep.from_dict(dict(
        CR_SMALL, grid={"R": [0.1, 0.2, 0.3, 0.4], "largest_link": [2.0, 3.0, 5.0, 6.0, 7.0],
                        "type": ["a", "c"]})))
    ratio = atlas.blow_rate.sel(type="c") / atlas.blow_rate.sel(type="a")
    g2 = ((1 + atlas.R) / (1 - atlas.R)) ** 2
    big = atlas.largest_link
    closed = (1 + big) * (g2 + big) / (big * (g2 - 1))
    both = (atlas.status.sel(type="a") == 0) & (atlas.status.sel(type="c") == 0)
    ratio, closed = xr.align(ratio.where(both), closed.where(both))
    assert np.allclose(ratio.values, closed.transpose(*ratio.dims).values, rtol=1e-12,
                       equal_nan=True)
    assert int(both.sum()) >= 12
    at_03 = ratio.sel(R=0.3)
    assert 4.0 < float(at_03.sel(largest_link=5.0)) < 4.2
    assert 4.4 < float(at_03.sel(largest_link=6.0)) < 4.6
    assert 3.3 < float(at_03.sel(largest_link=3.0)) < 3.6
    assert float(ratio.sel(R=0.1, largest_link=3.0)) > 10  # far more at a soft material
