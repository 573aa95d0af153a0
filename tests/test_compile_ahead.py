"""Compiling ahead (sweep/compile_ahead.py): the jobs of one system run in one process, where the
parts its entry points share are compiled once (kernels/impact/impact_map.py)."""

import os
import time
from pathlib import Path

from sweep import example_specs
from sweep.compile_ahead import Job, _tasks, mechanism_jobs, run_jobs, spec_together, together


def write_pid(path, seconds=0.0):
    """A job: this process's id into ``path``, after ``seconds``."""
    time.sleep(seconds)
    Path(path).write_text(str(os.getpid()))


def test_jobs_of_one_key_are_one_task_where_the_first_of_them_comes():
    jobs = [Job("a1", "m:f", (), "a"), Job("b", "m:f"), Job("a2", "m:f", (), "a"),
            Job("c1", "m:f", (), "c"), Job("d", "m:f"), Job("c2", "m:f", (), "c"),
            Job("a3", "m:f", (), "a")]
    assert [[job.name for job in task] for task in _tasks(jobs)] == [
        ["a1", "a2", "a3"], ["b"], ["c1", "c2"], ["d"]]


def test_jobs_of_one_key_run_in_one_process(tmp_path):
    """Three processes, five jobs: the three of one key share a process id (the first
    sleeps, so that apart they would land on three), and every job reports its CPU time
    by name."""
    jobs = [Job(f"{key}{i}", "tests.test_compile_ahead:write_pid",
                (str(tmp_path / f"{key}{i}"), 0.5 if i == 1 else 0.0), key if key == "x" else "")
            for key, i in (("x", 1), ("y", 1), ("x", 2), ("y", 2), ("x", 3))]
    times = run_jobs(jobs, workers=3)
    assert sorted(times) == sorted(job.name for job in jobs)
    pid = {job.name: (tmp_path / job.name).read_text() for job in jobs}
    assert pid["x1"] == pid["x2"] == pid["x3"]


def test_a_specs_key_is_its_mechanism_and_the_values_that_compile_apart():
    """The stability example is the rotor on the blade; a pendulum spec that names neither
    model nor tool is the defaults' system, one that sweeps two models has no key (its
    groups compile side by side: runner.compile_first); a mechanism without such
    parameters is its name."""
    assert spec_together(example_specs.text("rotary_pendulum_stability")) == together(
        "rotary_pendulum", model="rotor", tool="lab_window")
    assert spec_together('mechanism = "rotary_pendulum"\n[grid]\nk = [1.0, 2.0]\n') == \
        "rotary_pendulum model=paper tool=rotor_stop"
    assert spec_together('mechanism = "rotary_pendulum"\n[grid]\nmodel = ["rigid"]\n'
                         '[fixed]\ntool = "lab_window"\n') == \
        "rotary_pendulum model=rigid tool=lab_window"
    assert spec_together('mechanism = "rotary_pendulum"\n[grid]\n'
                         'model = ["paper", "rotor"]\n') == ""
    assert spec_together(example_specs.text("crank_rocker")) == "crank_rocker"


def test_sweep_warmup_runs_each_pendulum_system_in_one_process():
    """Each system's default sweep, its examples and its loads on request share a key."""
    keyed = {}
    for job in mechanism_jobs(["rotary_pendulum"]):
        keyed.setdefault(job.together, []).append(job.name)
    assert len(keyed) == 6
    assert keyed[together("rotary_pendulum", model="rotor", tool="lab_window")] == [
        "rotary_pendulum rotor on lab_window", "example rotary_pendulum_stability",
        "rotary_pendulum loads of rotor on lab_window"]


def test_the_entry_points_of_one_system_share_the_parts_that_do_not_depend_on_them():
    """The law, a contact, a section, the cycle and the transient are made once per
    contact and options: the entry points of one system with and without auto's second
    stage or several starts compile them once in a process."""
    from kernels.impact.impact_map import make_impact_map
    from kernels.pendulum.systems import CONTACTS

    c = CONTACTS["rotor", "lab_window", ()]
    one = make_impact_map(c, False, True, True, True, ())
    other = make_impact_map(c, False, True, True, False, ())
    assert (one.section, one.contact, one.restitute) == (
        other.section, other.contact, other.restitute)
    assert one.steady is not other.steady
    plain = make_impact_map(c, False, False, True, True, ())
    assert plain.section is not one.section and plain.contact is one.contact


def test_no_module_of_the_package_is_named_as_a_function_of_its_api():
    """Importing a submodule sets it on the package: a module sweep/warmup.py replaced the
    API's ``sweep.warmup`` once imported, and ``from sweep import warmup`` in the runner got
    the function, not the module (a cold first run of a spec of two systems failed)."""
    import sweep

    modules = {path.stem for path in Path(sweep.__file__).parent.glob("*.py")}
    assert modules & set(sweep.__all__) == set()
    assert sweep.warmup.__module__ == "sweep.api"


def test_a_first_run_of_several_groups_compiles_the_others_in_their_processes(monkeypatch):
    """Where the spec's first group of entry points is not in the cache, the runner
    compiles the other groups meanwhile (compile_ahead.compile_in_parallel), then loads
    every group here."""
    import time

    from sweep import compile_ahead, engine, runner

    compiled, loaded = [], []
    monkeypatch.setattr(engine, "sample_parameters", lambda sweep: None)
    monkeypatch.setattr(engine, "compile_groups", lambda sweep, params: [[0], [1, 2], [3]])
    monkeypatch.setattr(engine, "warm_up", lambda sweep, columns=None: (
        time.sleep(runner.COMPILE_NOTICE_AFTER + 0.3), loaded.append(columns)))
    monkeypatch.setattr(compile_ahead, "compile_in_parallel",
                        lambda sweep, groups, workers: compiled.append(groups))
    runner.compile_first(None, announce=False)
    assert compiled == [[[1, 2], [3]]] and loaded == [[0], None]
