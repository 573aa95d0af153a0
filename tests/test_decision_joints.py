"""The joints between decision steps (issue 62): a chain keeps the machine it was given,
fronts ignore round-off, nothing is written over an input, faults at the edges are one line
and leave nothing behind, and the machine's diagnostics see what they name."""

import errno
import json
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import sweep
from sweep import resources, runner, spec
from sweep.fronts import front, tied
from tests.command_line import run_cli
from tests.test_decisions import brute_front, random_atlas

SWEEP = str(Path(sys.executable).with_name("sweep"))


# ---------------------------------------------------------------- chains keep the machine

def crank_rocker_designs(tmp_path, rocker_inertia=True, seed=62):
    """A crank-rocker atlas of random designs (material, size, speed), as a chain's
    source."""
    rng = np.random.default_rng(seed)
    fixed = {"crank_length": 0.1}
    if rocker_inertia:
        fixed["rocker_inertia"] = float(rng.uniform(0.02, 0.08))
    document = {"mechanism": "crank_rocker",
                "grid": {"R": sorted(rng.uniform(0.15, 0.4, 3).round(4).tolist()),
                         "largest_link": sorted(rng.uniform(2.2, 3.5, 2).round(4).tolist()),
                         "omega1": sorted(rng.uniform(12.0, 24.0, 2).round(3).tolist())},
                "fixed": fixed,
                "outputs": ["lambda0", "lambda2", "lambda3", "impact_speed",
                            "transfer_before", "restitution_kinematic", "crank_length",
                            "omega1"]
                + (["blow_energy"] if rocker_inertia else [])}
    path = tmp_path / "cr.nc"
    runner.run_sweep(spec.validate(document), path, progress=False)
    return path


def test_a_chained_machine_runs_at_the_sources_speed_material_and_rocker(tmp_path):
    """crank_rocker -> impact_machine at random designs: the machine's motor is sized so
    that its steady mean crank speed is the source's omega1 (to 1e-9), the material is the
    source's R, the rocker's inertia the source's; so its blow energy is the source's
    within the speed fluctuation it reports: (1 - delta)^2 <= E/E_source <= (1 + delta)^2."""
    source = crank_rocker_designs(tmp_path)
    chained = spec.validate({"mechanism": "impact_machine",
                             "grid": {"from": {"atlas": str(source)}},
                             "fixed": {"flywheel_inertia": 2.0}})
    assert chained.notes == ()
    ds = runner.run_in_memory(chained)
    ok = ds.status.values == 0
    assert ok.sum() >= 6, sweep.decode(ds).status.values
    cr = xr.open_dataset(source).stack(p=["R", "largest_link", "omega1"])
    point = cr.isel(p=ds.source_index.values)
    np.testing.assert_allclose(ds.mean_crank_speed.values[ok], point.omega1.values[ok],
                               rtol=1e-9)
    np.testing.assert_array_equal(ds.R.values, point.R.values)
    ratio = ds.blow_energy.values[ok] / point.blow_energy.values[ok]
    delta = ds.speed_fluctuation.values[ok]
    assert np.all(ratio >= (1 - delta) ** 2 * (1 - 1e-9)), (ratio, delta)
    assert np.all(ratio <= (1 + delta) ** 2 * (1 + 1e-9)), (ratio, delta)
    assert np.all(np.abs(ratio - 1) > 1e-6)  # the machine's own speed, not the source's


def test_what_the_source_lacks_is_said_and_recorded_and_what_it_fixes_is_not_overridden(
        tmp_path, capsys):
    source = crank_rocker_designs(tmp_path, rocker_inertia=False)
    document = {"mechanism": "impact_machine", "grid": {"from": {"atlas": str(source)}}}
    chained = spec.validate(document)
    assert any("rocker_inertia" in note and "J3" in note for note in chained.notes)
    atlas = tmp_path / "m.nc"
    (tmp_path / "m.toml").write_text(
        f'mechanism = "impact_machine"\n[grid]\nfrom = {{atlas = "{source}"}}\n')
    code, out, err = run_cli(capsys, "run", tmp_path / "m.toml", "-o", atlas)
    assert code == 0 and "sweep: note: grid.from: the source has no rocker_inertia" in err
    assert any("rocker_inertia" in n for n in json.loads(xr.open_dataset(atlas).attrs["notes"]))
    for table, key in (("fixed", "R"), ("fixed", "idle_speed"), ("grid", "R")):
        changed = json.loads(json.dumps(document))
        changed.setdefault(table, {})[key] = 0.25 if table == "fixed" else [0.2, 0.3]
        with pytest.raises(sweep.UserError, match=rf"{key}"):
            spec.validate(changed)
    on_purpose = json.loads(json.dumps(document))
    on_purpose["grid"]["from"]["map"] = {"R": "R * 0 + 0.25"}
    assert set(spec.validate(on_purpose).axes[0].columns["R"]) == {0.25}


def test_chained_joint_forces_carry_the_sources_rocker_and_their_cycle_work_is_its_loss(
        tmp_path):
    """crank_rocker -> linkage_forces at random designs: the rocker is the source's
    (J3 = rocker_inertia about D, no mass), the links the source has no model of are named
    in one note; with massless crank and coupler, the balancing moment's work over a
    cycle at constant omega1 is the rocker's kinetic energy lost at the impact node, which
    the source gives independently: blow_energy (1 - Rk^2), to 1e-7."""
    source = crank_rocker_designs(tmp_path)
    with xr.open_dataset(source) as cr:
        cr = cr.load()
    inertia = json.loads(cr.attrs["spec"])["fixed"]["rocker_inertia"]
    chained = spec.validate({"mechanism": "linkage_forces",
                             "grid": {"from": {"atlas": str(source)}}})
    assert len(chained.notes) == 1 and all(n in chained.notes[0] for n in
                                           ("m1 = 2", "m2 = 3", "J1", "J2", "crank_rocker"))
    massless = {"m1": 0.0, "m2": 0.0, "J1": 0.0, "J2": 0.0}
    chained = spec.validate({"mechanism": "linkage_forces",
                             "grid": {"from": {"atlas": str(source)}}, "fixed": massless})
    assert chained.notes == ()
    ds = runner.run_in_memory(chained)
    np.testing.assert_array_equal(ds.J3.values, inertia)
    np.testing.assert_array_equal(ds.m3.values, 0.0)
    point = cr.stack(p=["R", "largest_link", "omega1"]).isel(p=ds.source_index.values)
    usable = np.isin(sweep.decode(ds).status.values, ["special_position",
                                                      "second_special_position"])
    assert usable.sum() >= 6
    loss = point.blow_energy.values * (1 - point.restitution_kinematic.values ** 2)
    np.testing.assert_allclose(np.abs(ds.cycle_work.values[usable]), loss[usable],
                               rtol=1e-7)
    (tmp_path / "lacking").mkdir()
    lacking = crank_rocker_designs(tmp_path / "lacking", rocker_inertia=False)
    notes = spec.validate({"mechanism": "linkage_forces",
                           "grid": {"from": {"atlas": str(lacking)}}}).notes
    assert any("no rocker_inertia: J3, m3 keep the target's" in n for n in notes), notes
    notes = spec.validate({"mechanism": "linkage_forces", "fixed": {"J3": 0.04},
                           "grid": {"from": {"atlas": str(lacking)}}}).notes
    assert any("no rocker_inertia: m3 keeps the target's m3 = 8 kg" in n for n in notes)
    assert not any("J3" in n for n in notes), notes


def test_the_idle_speed_for_a_crank_speed_is_its_exact_root():
    """omega1 given instead of idle_speed: the steady cycle's mean speed is omega1 (to
    1e-9); a speed beyond the motor's reach says so."""
    atlas = sweep.run({"mechanism": "impact_machine",
                       "grid": {"omega1": [12.0, 20.0, 28.0, 1000.0]}})
    status = sweep.decode(atlas).status.values.tolist()
    assert status == ["ok", "ok", "ok", "unreachable_speed"]
    np.testing.assert_allclose(atlas.mean_crank_speed.values[:3], [12.0, 20.0, 28.0],
                               rtol=1e-9)
    idle = atlas.idle_speed.values[:3]
    assert np.all(np.diff(idle) > 0) and np.all(idle > [12.0, 20.0, 28.0])
    again = sweep.run({"mechanism": "impact_machine",
                       "grid": {"idle_speed": [float(v) for v in idle]}})
    np.testing.assert_allclose(again.mean_crank_speed.values, [12.0, 20.0, 28.0],
                               rtol=1e-9)


# ---------------------------------------------------------------- fronts and round-off

@pytest.mark.parametrize("trial", range(6))
def test_fronts_with_values_perturbed_in_their_last_bits_are_the_tied_front(trial):
    """Values that agree to tie_tol are ties: the front of an atlas whose objectives are
    perturbed in their last bits is the brute-force front of the tied values, and the same
    designs as without the perturbation."""
    rng = np.random.default_rng(620 + trial)
    ds = random_atlas(rng)
    noisy = ds.copy(deep=True)
    for name in "pqr":
        v = noisy[name].values
        noisy[name].values = v * (1 + rng.integers(-4, 5, v.shape) * 2.2e-16)
    plain = front(ds, ["p", "q"], ["r"])
    shaken = front(noisy, ["p", "q"], ["r"])
    # the same members (tied designs may list in another order)
    assert set(plain.designs.grid_point.values) == set(shaken.designs.grid_point.values)
    feasible = (ds.status.values.ravel() == 0) & (ds.requirements.values.ravel() == 0)
    values = np.stack([-noisy.p.values.ravel(), -noisy.q.values.ravel(),
                       noisy.r.values.ravel()], axis=1)
    candidates = np.flatnonzero(feasible & np.all(np.isfinite(values), axis=1))
    keep = brute_front(tied(values[candidates], 1e-9))
    assert set(candidates[keep]) == set(shaken.designs.grid_point.values.tolist())


def test_a_near_constant_objective_adds_no_member_and_no_cost():
    """A fixed envelope that comes out as three values in its last bits: as an objective
    it leaves the front as it is, and the front is computed on the varying objectives
    alone (the dominance check never sees it)."""
    rng = np.random.default_rng(6202)
    ds = random_atlas(rng)
    ds["s"].values = 0.6 * (1 + rng.integers(-1, 2, ds.s.shape) * 2.2e-16)
    ds["s"].values[np.isnan(ds.p.values)] = np.nan  # no value where p has none
    base = front(ds, ["p", "q"], [])
    with_envelope = front(ds, ["p", "q"], ["s"])
    assert np.array_equal(base.designs.grid_point.values,
                          with_envelope.designs.grid_point.values)
    assert json.loads(with_envelope.designs.attrs["pareto"])["tie_tol"] == 1e-9
    calls = []
    from kernels import pareto

    real = pareto.non_dominated

    def counted(values):
        calls.append(values.shape[1])
        return real(values)

    pareto.non_dominated = counted
    try:
        front(ds, ["p", "q"], ["s"])
    finally:
        pareto.non_dominated = real
    assert calls == [2]


# ---------------------------------------------------------------- nothing overwritten

def test_no_command_writes_over_one_of_its_inputs_force_or_not(tmp_path, capsys):
    small = tmp_path / "s.toml"
    small.write_text('mechanism = "crank_rocker"\noutputs = ["impact_speed", "envelope", '
                     '"blow_rate"]\n[grid]\nR = [0.2, 0.3]\nlargest_link = [2.0, 3.0]\n')
    atlas = tmp_path / "s.nc"
    assert run_cli(capsys, "run", small, "-o", atlas)[0] == 0
    size = atlas.stat().st_size
    for args in (["pareto", atlas, "--max", "blow_rate", "-o", atlas, "--force"],
                 ["boundaries", atlas, "-o", atlas, "--force"]):
        code, out, err = run_cli(capsys, *args)
        assert code == 2 and "input" in err and "--force never overwrites" in err, err
        assert atlas.stat().st_size == size
    chain = tmp_path / "c.toml"
    chain.write_text(f'mechanism = "crank_rocker"\n[grid]\nfrom = {{atlas = "{atlas}"}}\n')
    code, out, err = run_cli(capsys, "run", chain, "-o", atlas, "--force")
    assert code == 2 and "input" in err and atlas.stat().st_size == size


# ---------------------------------------------------------------- faults at the edges

def test_a_full_disk_at_start_up_is_one_line_and_leaves_no_lock(tmp_path, capsys, monkeypatch):
    small = tmp_path / "s.toml"
    small.write_text('mechanism = "crank_rocker"\n[grid]\nR = [0.2, 0.3]\n'
                     'largest_link = [2.0, 3.0]\n')
    monkeypatch.setattr(resources, "free_disk", lambda folder: 0)
    code, out, err = run_cli(capsys, "run", small, "-o", tmp_path / "s.nc")
    assert code == 2 and "of disk" in err and len(err.strip().splitlines()) == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.toml"]


def test_a_lock_that_cannot_be_written_is_one_line_and_leaves_nothing(tmp_path, capsys,
                                                                      monkeypatch):
    small = tmp_path / "s.toml"
    small.write_text('mechanism = "crank_rocker"\n[grid]\nR = [0.2, 0.3]\n'
                     'largest_link = [2.0, 3.0]\n')

    def full(write):
        def call(fd, *args):  # the disk is full for the lock file alone
            if ".s.nc.lock" in os.readlink(f"/proc/self/fd/{fd}"):
                raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
            return write(fd, *args)
        return call

    monkeypatch.setattr(os, "write", full(os.write))
    monkeypatch.setattr(os, "pwrite", full(os.pwrite))
    code, out, err = run_cli(capsys, "run", small, "-o", tmp_path / "s.nc")
    assert code == 1 and "no space left" in err and len(err.strip().splitlines()) == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.toml"]


def test_a_name_too_long_is_exit_2_with_the_designed_message(tmp_path):
    small = tmp_path / "s.toml"
    small.write_text('mechanism = "crank_rocker"\n[grid]\nR = [0.2]\nlargest_link = [2.0]\n')
    done = subprocess.run([SWEEP, "run", str(small), "-o", str(tmp_path / ("x" * 300 + ".nc"))],
                          capture_output=True, text=True)
    assert done.returncode == 2 and "the file name is" in done.stderr, done.stderr
    assert len(done.stderr.strip().splitlines()) == 1


def test_sweep_alone_prints_its_usage_and_commands():
    done = subprocess.run([SWEEP], capture_output=True, text=True)
    assert done.returncode == 0 and done.stderr == ""
    lines = done.stdout.splitlines()
    assert lines[0].startswith("Usage: sweep") and len(lines) > 10
    for command in ("run", "query", "pareto", "warmup"):
        assert any(line.split()[:1] == [command] for line in lines), command


def test_the_runs_summary_says_which_statuses_are_usable_designs(tmp_path, capsys):
    spec_file = tmp_path / "lf.toml"
    spec_file.write_text('mechanism = "linkage_forces"\n[grid]\nomega1 = [10.0, 20.0]\n')
    code, out, err = run_cli(capsys, "run", spec_file, "-o", tmp_path / "lf.nc")
    assert code == 0 and "usable designs: special_position 2" in out, out


def test_a_requirement_on_an_output_left_out_is_computed_kept_and_said(tmp_path):
    document = {"mechanism": "crank_rocker", "outputs": ["impact_speed"],
                "grid": {"R": [0.2, 0.3], "largest_link": [3.0, 6.0]},
                "fixed": {"rocker_inertia": 0.05},
                "requirements": {"blow_energy": ">= 1e-3"}}
    checked = spec.validate(document)
    assert "blow_energy" in checked.outputs and any("blow_energy" in n for n in checked.notes)
    atlas = sweep.run(checked)
    met = sweep.query(atlas, 'requirements == "met"', columns="blow_energy")
    assert len(met) and np.all(met.blow_energy >= 1e-3)


def test_a_failing_limit_takes_precedence_over_no_value():
    """requirements names the limit a design fails even where another limit's output has
    no value there; no_value only where every limit with a value holds."""
    ds = xr.Dataset({"a": ("x", [1.0, np.nan, np.nan, 5.0]), "b": ("x", [np.nan, 9.0, 1.0,
                                                                          1.0]),
                     "status": ("x", np.zeros(4, np.int8),
                                {"flag_values": np.array([0], np.int8),
                                 "flag_meanings": "ok"})}, attrs={"mechanism": "toy"})
    for name in "ab":
        ds[name].attrs.update(units="m", long_name=name)
    out = sweep.decode(sweep.with_requirements(ds, ["a <= 2", "b <= 2"]))
    assert out.requirements.values.tolist() == ["no_value", "above_b", "no_value",
                                                "above_a"]


# ---------------------------------------------------------------- honest diagnostics

def test_the_energy_balance_residual_grows_with_the_integration_error():
    """(motor work - blow loss)/blow loss: gravity's and the load's work is 0 over the
    closed cycle, their integrated work is not; so the residual falls with tol."""
    design = {"mechanism": "impact_machine",
              "grid": {"R": [0.1, 0.3]},
              "fixed": {"load_force_x": 400.0, "load_arm": 0.2, "flywheel_inertia": 1.0}}
    loose = sweep.run({**design, "method": {"tol": 1e-5}}).energy_balance_residual.values
    tight = sweep.run({**design, "method": {"tol": 1e-11}}).energy_balance_residual.values
    assert np.all(np.abs(loose) > 1e-9) and np.all(np.abs(tight) < 1e-8)
    assert np.all(np.abs(loose) > 100 * np.abs(tight))


def test_a_delta_target_met_without_a_flywheel_says_so():
    atlas = sweep.decode(sweep.run({"mechanism": "impact_machine",
                                    "grid": {"R": [0.3]},
                                    "fixed": {"flywheel_inertia": "for_delta_target"},
                                    "method": {"delta_target": 0.9}}))
    assert atlas.flywheel_sizing.values.tolist() == ["not_needed"]
    assert float(atlas.flywheel_inertia[0]) == 0.0 and float(atlas.speed_fluctuation[0]) < 0.9
    sized = sweep.decode(sweep.run({"mechanism": "impact_machine", "grid": {"R": [0.3]},
                                    "fixed": {"flywheel_inertia": "for_delta_target"},
                                    "method": {"delta_target": 0.02}}))
    assert sized.flywheel_sizing.values.tolist() == ["sized"]


def test_the_kinematic_laws_energy_splits_are_nan_and_its_energy_gain_a_status():
    """Under the kinematic law the blow's loss has no split into the material's share and
    a capture (NaN), and a design where the law creates energy is gains_energy."""
    atlas = sweep.run({"mechanism": "impact_machine",
                       "grid": {"R": np.linspace(0.05, 0.6, 12)},
                       "fixed": {"impact_law": "kinematic", "design_restitution": 0.3}})
    status = sweep.decode(atlas).status.values
    ok = status == "ok"
    assert ok.any() and (status == "gains_energy").any(), status
    for name in ("energy_to_material", "capture_loss", "blow_efficiency"):
        assert np.all(np.isnan(atlas[name].values)), name
    assert np.all(atlas.blow_loss.values[ok] > 0)
    assert not (status == "no_convergence").any()
    loss_sign = []
    for r in atlas.R.values[status == "gains_energy"]:
        one = sweep.run({"mechanism": "impact_machine", "grid": {"R": [float(r)]},
                         "fixed": {"impact_law": "kinematic", "design_restitution": 0.3,
                                   "motor_law": "constant"}})
        loss_sign.append(sweep.decode(one).status.values[0])
    assert set(loss_sign) == {"gains_energy"}
