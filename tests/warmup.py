"""What the test suite compiles before its tests start (conftest.py: pytest_sessionstart),
in parallel processes, each entry point once (sweep/compile_ahead.py): the kernels the tests
run and the tests' own probes. The tests then load them from the cache, on every worker.

A job is a function here called with its arguments in a process of its own (those of one
pendulum system in one process, which compiles the parts they share once): every built-in
example, the pendulum's entry points of the fast loop (``FAST_ENTRY_POINTS``) and those the
whole suite adds (``SLOW_ENTRY_POINTS``), and the tests' probes. A warm-up is skipped where
nothing it compiles from has changed since the last one (``stamp``). After the tests, the
run says how many cached kernels the tests compiled themselves, and names those compiled
on more than one worker: each belongs here (tests/conftest.py).
``python -m tests.warmup [--slow]`` runs it alone."""

from __future__ import annotations

import hashlib
import sys
import time
from pathlib import Path

import numba

from kernels.pendulum.table import MODELS, TOOLS
from sweep.compile_ahead import (Job, cores, example_jobs, machine_full_job,
                                 on_request_jobs, run_jobs, together)

ROOT = Path(__file__).resolve().parent.parent


# ---------------------------------------------------------------- the jobs' functions

def pendulum(model, tool, method="dopri5", tangent=False, two_stage=False, starts=1):
    """A pendulum system's entry point (kernels/pendulum/systems.py), compiled on one case."""
    import numpy as np

    from kernels.impact.runge_kutta import METHOD_DOP853, METHOD_DOPRI5, METHOD_RK4
    from kernels.pendulum import systems
    from kernels.pendulum.cases import N_ROW, C
    from kernels.pendulum.table import MODELS, TOOLS, BY_CODES

    system = BY_CODES[MODELS[model], TOOLS[tool]]
    code = {"dopri5": METHOD_DOPRI5, "dop853": METHOD_DOP853, "rk4": METHOD_RK4}[method]
    cases = np.zeros((1, len(C)))
    cases[0, C.k], cases[0, C.xi], cases[0, C.kappa], cases[0, C.R] = 1.0, 4.0, 1.2, 0.1
    cases[0, C.tool_window], cases[0, C.rotor_inertia_ratio] = 0.3, 60.0
    cases[0, C.motor_slope], cases[0, C.idle_speed] = 20.0, 1.0
    rows = np.empty((1, N_ROW))
    entry = systems.entry_point(system, code, tangent, two_stage, starts)
    entry(cases, systems.settings_for(system, code, 1e-4, 1e-4, 0.05, 3, starts,
                                      8.0 if two_stage else 0.0), rows, rows.copy(),
          np.empty((1, 2)))


def flight_probe(model, tool):
    """The flight probe of a model on a tool (tests/probes.py), as the hard cases call it."""
    from tests.test_hard_cases import TWINS, fly, tool_data

    twin = TWINS[model]
    fly(model, tool, 0.0, twin.state(0.1, 0.0), tool_data(twin, tool), max_steps=50)


def system_probe(kind, model, tool):
    """A probe of one system (tests/probes.py) called as its tests call it, on a cheap case,
    in the process of the system's entry points, whose parts it shares."""
    import numpy as np

    from kernels.pendulum import systems
    from tests import probes, test_stability

    settings = probes.settings()
    design = {"k": 1.0, "xi": 4.0, "kappa": 1.2, "R": 0.05, "tool_window": 0.3}
    if kind == "section_jacobian":
        test_stability.section_jacobians(model, tool, design, transient=1)
    elif kind == "follow":
        test_stability.follow(model, design, [0.05], transient=1, steps=1)
    elif kind == "accumulation":
        (t, y, data, p, r, column, eps), _ = test_stability.contact_to_accumulate(
            np.random.default_rng(0), model)
        probes.accumulation(model)(t, y, data, p, r, settings, column, eps)
    elif kind == "chatter":  # and the impact map's contact after it
        from tests.test_hard_cases import chatter_case

        twin, data, r, _, t0, y0 = chatter_case(model, tool)
        _, _, t, y, *_ = probes.chatter(model, tool)(t0, tuple(y0), twin.p, data, r,
                                                     settings, 1)
        probes.zeno(model, tool)(t, y, data, twin.p, r, settings)
    elif kind == "impacts_from_rest":
        case = test_stability.case_of(model, tool, design)
        probes.impacts_from_rest(model, tool)(systems.PARAMETERS[model](case),
                                              systems.DATA[tool](case), 0.05, settings, 1e-9, 2)
    else:
        assert kind == "restitute", kind
        probes.restitute(model, tool)(0.0, (0.0, 1.0, 0.0, 2.2), (0.0, 2.5),
                                      (2.5, 4.0, 3.0, 0.0, 1.0), 0.3)


def fixed_steps_probe(model):
    """The fixed steps of a model's free motion (tests/probes.py)."""
    from tests import probes
    from tests.test_hard_cases import TWINS

    twin = TWINS[model]
    probes.fixed_steps(model)(probes.settings().method, twin.state(0.1, 0.0), twin.p, 0.01,
                              2)


def joint_forces():
    """kinetostatics.joint_forces on one angle, as its tests call it."""
    import numpy as np

    from kernels import kinetostatics as kt

    pr = np.array([q.encode(q.default) for q in kt.DECLARATION.parameters], dtype=float)
    kt.joint_forces(0.5, pr, float(pr[kt.P.sigma]), np.empty(kt.N_RESULT), 1e-9)


# ---------------------------------------------------------------- the lists

#: the pendulum's entry points the fast loop runs: (model, tool, method, tangent,
#: two_stage, starts), the longest compiles first
FAST_ENTRY_POINTS = (
    ("rotor", "lab_window", "dopri5", True, True, 8),
    ("rigid", "lab_window", "rk4", False, False, 1),
    ("rigid", "lab_window", "dopri5", False, False, 1),
    ("paper", "lab_window", "dopri5", False, False, 1),
    ("paper", "rotor_stop", "dopri5", False, False, 1),
    ("rigid", "rotor_stop", "rk4", False, False, 1),
    ("rotor", "rotor_stop", "dopri5", False, False, 1),
    ("rotor", "lab_window", "dopri5", False, True, 1),
    ("paper", "rotor_stop", "rk4", False, False, 1),
    ("rotor", "lab_window", "dopri5", False, False, 1),
    ("rotor", "rotor_stop", "rk4", False, False, 1),
    ("rotor", "rotor_stop", "dopri5", False, True, 8),
    ("rigid", "rotor_stop", "dopri5", False, False, 1),
    ("paper", "lab_window", "dopri5", False, True, 1),
    ("rotor", "rotor_stop", "dopri5", False, True, 1),
    # the fast tests of several starts and of a method compiled in (the tests' listing of
    # what they compiled themselves named these: tests/conftest.py)
    ("rotor", "lab_window", "dopri5", True, False, 8),
    ("rotor", "lab_window", "dopri5", False, True, 8),
    ("paper", "rotor_stop", "dopri5", False, False, 8),
    ("rigid", "rotor_stop", "dopri5", False, False, 8),
    ("paper", "rotor_stop", "dop853", False, False, 1),
)
#: those the slow tests add (the first two were the fast loop's for one fast test each: that
#: test now runs the stability example's own entry point, or is slow)
SLOW_ENTRY_POINTS = (
    ("rotor", "lab_window", "dopri5", True, True, 1),
    ("rigid", "lab_window", "dopri5", False, True, 8),
    ("rotor", "lab_window", "dop853", True, False, 1),
    ("rotor", "rotor_stop", "dop853", True, False, 1),
    ("rotor", "lab_window", "dop853", False, False, 1),
    ("rigid", "rotor_stop", "dop853", False, False, 1),
    ("rotor", "rotor_stop", "dop853", False, True, 1),
    ("rotor", "lab_window", "dopri5", True, False, 1),
    ("rotor", "rotor_stop", "dopri5", True, False, 1),
    ("rotor", "rotor_stop", "dopri5", True, True, 1),
    ("paper", "lab_window", "dopri5", True, True, 1),
    ("rigid", "lab_window", "dopri5", True, True, 1),
    ("rigid", "lab_window", "dopri5", False, False, 8),
    ("paper", "lab_window", "dop853", False, True, 1),
    ("rotor", "lab_window", "dop853", False, True, 1),
)


def _entry_jobs(entries):
    return [Job(f"{model} on {tool} by {method}" + (" tangent" if tangent else "")
                + (" two stages" if two else "") + (f" {starts} starts" if starts > 1 else ""),
                "tests.warmup:pendulum", (model, tool, method, tangent, two, starts),
                together("rotary_pendulum", model=model, tool=tool))
            for model, tool, method, tangent, two, starts in entries]


#: the probes of one system the fast tests call (beside every system's flight probe), and
#: those the slow tests add: (kind, model, tool)
FAST_PROBES = (("restitute", "rotor", "rotor_stop"),)
SLOW_PROBES = (tuple(("section_jacobian", m, t) for m in MODELS for t in TOOLS)
               + tuple(("chatter", m, t) for m in MODELS for t in ("lab_window", "relative_stop"))
               + tuple(("accumulation", m, "lab_window") for m in MODELS)
               + (("follow", "rotor", "lab_window"), ("impacts_from_rest", "rotor", "rotor_stop")))


def _system(model, tool):
    """The key of a system's jobs (the test stop's own: it is no system of the table)."""
    return together("rotary_pendulum" if tool in TOOLS else tool, model=model, tool=tool)


def _probe_jobs(slow):
    return ([Job(f"flight probe {m} on {t}", "tests.warmup:flight_probe", (m, t), _system(m, t))
             for m in MODELS for t in (*TOOLS, "relative_stop")]
            + [Job(f"{kind} probe {m} on {t}", "tests.warmup:system_probe", (kind, m, t),
                   _system(m, t)) for kind, m, t in FAST_PROBES + (SLOW_PROBES if slow else ())]
            + [Job(f"fixed steps probe {m}", "tests.warmup:fixed_steps_probe", (m,))
               for m in MODELS])


def _examples():
    from sweep import example_specs

    return example_jobs(example_specs.names())


def jobs(slow: bool) -> list[Job]:
    """The warm-up of the fast loop, or of the whole suite: the longest first."""
    selected = _entry_jobs(FAST_ENTRY_POINTS + (SLOW_ENTRY_POINTS if slow else ()))
    return (selected + [machine_full_job()] + _examples() + _probe_jobs(slow)
            + on_request_jobs(("crank_rocker", "rotary_pendulum"),
                              () if slow else ("loads of rotor on lab_window",))
            + [Job("joint forces", "tests.warmup:joint_forces")])


# ---------------------------------------------------------------- running it

#: the test files the jobs compile from (beside kernels/ and sweep/)
TEST_FILES = ("warmup.py", "probes.py", "stop_tool.py", "pendulum_twins.py",
              "test_hard_cases.py", "test_stability.py")


def stamp(selected: list[Job]) -> str:
    """A digest of everything the jobs compile from (every Python file of kernels/ and
    sweep/, TEST_FILES), numba's version and the jobs themselves."""
    digest = hashlib.sha256(numba.__version__.encode())
    paths = [p for folder in ("kernels", "sweep") for p in sorted((ROOT / folder).rglob("*.py"))]
    for path in paths + [ROOT / "tests" / name for name in TEST_FILES]:
        digest.update(str(path.relative_to(ROOT)).encode() + b"\0" + path.read_bytes())
    digest.update(repr(selected).encode())
    return digest.hexdigest()[:24]


def before_tests(slow: bool, say) -> None:
    """Compile what the tests need, unless the last warm-up compiled it from the same
    files; ``say(line)`` reports what it did."""
    from kernels.cache import cache_dir

    selected = jobs(slow)
    if not selected:
        return
    marker = cache_dir() / f"warmup-{stamp(selected)}"
    if marker.exists():
        say(f"warm-up: nothing changed since the last one ({len(selected)} compile jobs)")
        return
    started = time.perf_counter()
    times = run_jobs(selected, cores())
    say(f"warm-up: {len(times)} compile jobs in {time.perf_counter() - started:.0f} s on "
        f"{min(cores(), len(selected))} processes ({sum(times.values()):.0f} CPU s)")
    marker.parent.mkdir(parents=True, exist_ok=True)
    for old in marker.parent.glob("warmup-*"):
        old.unlink(missing_ok=True)
    marker.write_text("\n".join(f"{name}\t{seconds:.1f}" for name, seconds in times.items()))


if __name__ == "__main__":
    before_tests("--slow" in sys.argv, print)
