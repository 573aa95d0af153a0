"""Compiling ahead: numba compiles a kernel on its first call and keeps it in its on-disk
cache (kernels/cache.py), so a first sweep waits for the compiler and every later one
starts at once. Here the compiles are jobs run in processes of their own, as many at a time
as there are cores (a compile holds its process's interpreter: threads would not overlap),
each filling the cache that the sweeps, and the other processes, then load. The jobs of one
system (one mechanism, one value of each parameter that compiles apart) run in one process,
where the parts their entry points share are compiled once (``Job.together``).

- ``sweep warmup [MECHANISM ...]`` compiles what the built-in examples and each pendulum
  system under the default method need (``mechanism_jobs``), once per installation;
- a run whose spec needs several entry points (the pendulum's models and tools on a grid)
  compiles them side by side (``compile_in_parallel``, from ``runner.compile_first``);
- the test suite compiles what its fast loop needs before the tests start
  (tests/warmup.py).
"""

from __future__ import annotations

import concurrent.futures as cf
import importlib
import multiprocessing
import os
import sys
import time
from dataclasses import dataclass
from typing import Callable, Iterable, Sequence

from sweep.errors import UserError


@dataclass(frozen=True)
class Job:
    """One compile: ``function`` ("module:name") called with ``arguments`` in a process of
    its own; ``name`` says what it compiles. Jobs with the same ``together`` key (not
    empty: ``together``) run in one process, one after the other: numba keeps the inner
    functions of a kernel (those it does not cache on disk) in the memory of the process
    that compiled them, so the entry points of one system compile them once there."""

    name: str
    function: str
    arguments: tuple = ()
    together: str = ""


def together(mechanism: str, **values) -> str:
    """The key of the jobs that compile the same code of a mechanism, by the values of its
    parameters that run code of their own (Quantity.compiles_apart)."""
    return " ".join([mechanism] + [f"{name}={values[name]}" for name in sorted(values)])


def spec_together(text: str) -> str:
    """The ``together`` key of a spec (TOML text) whose parameters that compile apart
    each take one value (given in [fixed] or as a one-value grid, else their default);
    empty where one takes several."""
    import tomllib

    from sweep import registry

    given = tomllib.loads(text)
    mechanism = given["mechanism"]
    values = {}
    for quantity in registry.get(mechanism).declaration.parameters:
        if not quantity.compiles_apart:
            continue
        value = given.get("fixed", {}).get(quantity.name,
                                          given.get("grid", {}).get(quantity.name,
                                                                    quantity.default))
        if isinstance(value, list):
            if len(value) != 1:
                return ""
            value = value[0]
        values[quantity.name] = value
    return together(mechanism, **values)


def run_jobs_here(jobs: Sequence[Job]) -> list[tuple[str, float]]:
    """Run jobs here, one after the other: (the name, the CPU seconds) of each."""
    times = []
    for job in jobs:
        module, name = job.function.split(":")
        started = time.process_time()
        getattr(importlib.import_module(module), name)(*job.arguments)
        times.append((job.name, time.process_time() - started))
    return times


def cores() -> int:
    """The cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0)) or 1
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def run_jobs(jobs: Sequence[Job], workers: int | None = None,
             done: Callable[[str, float], None] | None = None) -> dict[str, float]:
    """Run the jobs in at most ``workers`` processes (default: the cores), the first ones
    first (put the longest first), those with one ``together`` key in one process where
    the first of them comes; ``done(name, cpu_seconds)`` after each. Returns the CPU
    seconds of each job by name. A job that fails raises its error here, after the others
    finished."""
    tasks = _tasks(jobs)
    workers = max(1, min(workers or cores(), len(tasks)))
    times: dict[str, float] = {}
    failure = None
    # spawn: a fork of a process that has numba's threads or compiler state is not safe
    with cf.ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context("spawn"),
                                initializer=_quiet_worker) as pool:
        for future in cf.as_completed([pool.submit(run_jobs_here, task) for task in tasks]):
            try:
                task_times = future.result()
            except Exception as err:  # noqa: BLE001 (reported once all have ended)
                failure = failure or err
                continue
            for name, seconds in task_times:
                times[name] = seconds
                if done is not None:
                    done(name, seconds)
    if failure is not None:
        raise failure
    return times


def _tasks(jobs: Sequence[Job]) -> list[list[Job]]:
    """The jobs as the processes' tasks: each job alone, but those of one ``together`` key
    in one task, where the first of them comes."""
    tasks: list[list[Job]] = []
    keyed: dict[str, list[Job]] = {}
    for job in jobs:
        if job.together in keyed:
            keyed[job.together].append(job)
            continue
        tasks.append([job])
        if job.together:
            keyed[job.together] = tasks[-1]
    return tasks


def _quiet_worker() -> None:
    """A compile process uses one thread: the cores are the pool's."""
    os.environ["NUMBA_NUM_THREADS"] = "1"


# ---------------------------------------------------------------- what to compile

def compile_spec(given, columns: Sequence[int] | None = None) -> None:
    """Compile what a spec (TOML text, or a Sweep) needs: its kernel on its sample points
    (engine.sample_parameters), or on the given columns of them."""
    from sweep import engine, spec

    sweep = spec.parse(given, source="warm-up") if isinstance(given, str) else given
    params = engine.sample_parameters(sweep)
    if columns is not None:
        params = params[:, list(columns)]
    with engine.numba_without_blas():
        sweep.kernel(params, sweep.method_record)


def spec_job(name: str, text: str) -> Job:
    """The job that compiles what a spec (TOML text) needs, with the spec's key."""
    return Job(name, "sweep.compile_ahead:compile_spec", (text,), spec_together(text))


def example_jobs(names: Iterable[str]) -> list[Job]:
    """A job per built-in example: what its first run compiles."""
    from sweep import example_specs

    return [spec_job(f"example {name}", example_specs.text(name)) for name in names]


def pendulum_system_jobs() -> list[Job]:
    """A job per pendulum system (model x tool) under the default method: the sweep a
    designer runs first on each."""
    from kernels.pendulum.table import SYSTEMS

    return [spec_job(f"rotary_pendulum {s.model} on {s.tool}",
                     f'mechanism = "rotary_pendulum"\n[fixed]\nmodel = "{s.model}"\n'
                     f'tool = "{s.tool}"\nkappa = 1.2\n')
            for s in SYSTEMS]


def machine_full_job() -> Job:
    """The impact machine's full block (kernels/impact_machine.py: a crank speed to size
    the motor for, profiles, force peaks, flywheels for delta), which its example, asking
    none of them, does not compile: a chained machine's first run needs it."""
    return spec_job("impact_machine at a given crank speed",
                    'mechanism = "impact_machine"\n[grid]\nomega1 = [20.0]\n')


def _pendulum_loads(model: str, tool: str) -> str:
    """A pendulum spec asking for the steady cycle's loads and histories on a system where
    it has a cycle (plastic on the blade: a slide and a flight)."""
    blade = tool == "lab_window"
    return (f'mechanism = "rotary_pendulum"\noutputs = ["amplitude", "hinge_force_peak", '
            f'"swing_angle", "hinge_force"]\n[grid]\nk = [{1.0 if blade else 2.0}]\n'
            f'[fixed]\nmodel = "{model}"\ntool = "{tool}"\n'
            + ("" if model == "paper" else "kappa = 1.2\n")
            + ('tool_window = 0.3\nR = 0.0\n' if blade else "")
            + 'striker_mass = 1.0\n[method]\nprofile_points = 8\n')


#: what a mechanism compiles only where a sweep asks for it (its examples do not), by a
#: label: its profiles, the pendulum's steady-cycle loads (the constant-speed models'
#: closed-form cycle on the stop, one function for both; each integrated system's walk)
ON_REQUEST = {
    "crank_rocker": {"profiles": 'mechanism = "crank_rocker"\n[grid]\nR = [0.3]\n'
                                 'type = ["a", "b", "c"]\n[fixed]\nlargest_link = 3.0\n'
                                 '[method]\nprofile_points = 8\n'},
    "rotary_pendulum": {f"loads of {model} on {tool}": _pendulum_loads(model, tool)
                        for model, tool in (("paper", "rotor_stop"), ("rotor", "rotor_stop"),
                                            ("paper", "lab_window"), ("rigid", "lab_window"),
                                            ("rotor", "lab_window"))},
}


def on_request_jobs(mechanisms: Iterable[str], leave_out: Iterable[str] = ()) -> list[Job]:
    """A job per ON_REQUEST spec of these mechanisms, but those labelled in leave_out."""
    left = set(leave_out)
    return [spec_job(f"{name} {label}", text)
            for name in mechanisms for label, text in ON_REQUEST.get(name, {}).items()
            if label not in left]


def mechanism_jobs(mechanisms: Sequence[str] | None = None) -> list[Job]:
    """What ``sweep warmup`` compiles for these mechanisms (default: every one): each
    built-in example of them, for the rotary pendulum each system under the default
    method, for the impact machine its full block, and what each compiles only on request
    (ON_REQUEST); the longest first."""
    from sweep import example_specs, registry

    known = sorted(registry.MECHANISMS)
    chosen = list(mechanisms) if mechanisms else known
    for name in chosen:
        if name not in registry.MECHANISMS:
            raise UserError(f"mechanism: unknown mechanism {name!r}; allowed: "
                            + ", ".join(known))
    of_example = example_specs.mechanisms()
    jobs = pendulum_system_jobs() if "rotary_pendulum" in chosen else []
    pendulum_first = sorted(of_example, key=lambda n: of_example[n] != "rotary_pendulum")
    jobs += [machine_full_job()] if "impact_machine" in chosen else []
    return (jobs + example_jobs(n for n in pendulum_first if of_example[n] in chosen)
            + on_request_jobs(chosen))


def warm_up_mechanisms(mechanisms: Sequence[str] | None = None, workers: int | None = None,
                       progress: bool = False) -> dict[str, float]:
    """Fill the compile cache for these mechanisms (``mechanism_jobs``) in parallel
    processes, with a progress bar on request; the CPU seconds of each job by name."""
    jobs = mechanism_jobs(mechanisms)
    if not progress:
        return run_jobs(jobs, workers)
    from tqdm import tqdm

    with tqdm(total=len(jobs), desc="compiling", unit="job", file=sys.stderr) as bar:
        def done(name, seconds):
            bar.set_postfix_str(f"{name} ({seconds:.0f} CPU s)", refresh=False)
            bar.update()
        return run_jobs(jobs, workers, done)


def compile_in_parallel(sweep, groups: Sequence[Sequence[int]],
                        workers: int | None = None) -> None:
    """Compile each group of a sweep's sample points (columns that run entry points of
    their own) in a process of its own, so that this process then loads them all."""
    run_jobs([Job(f"group {i}", "sweep.compile_ahead:compile_spec", (sweep, tuple(g)))
              for i, g in enumerate(groups)], workers)
