"""The table of pendulum systems (kernels/pendulum/table.py) drives the entry points, the
dispatch, the spec's rules and the docs' list; a new impact surface goes through it.

The toy surface is tests/stop_tool.py's ``mirrored_stop``: the rotor stop met from the other
side. It touches one file and a table row here, nothing in kernels/; its steady state must be
the rotor stop's (the mirror image of every flight and contact), which the closed form gives
independently (kernels/pendulum/closed_form.py)."""

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from numba import njit

from kernels.impact.outcomes import SEQUENCE_CYCLE, Settings
from kernels.impact.runge_kutta import METHOD_DOP853, METHOD_DOPRI5, METHOD_EXACT, METHOD_RK4
from kernels.cache import module_level
from kernels.pendulum import dispatch, models, systems, table, tools
from kernels.pendulum.accuracy import exact_settings
from kernels.pendulum.cases import CASE_COLUMNS, N_ROW, ROW, C
from kernels.rotary_pendulum import DECLARATION
from tests.stop_tool import mirrored_stop

#: the toy surface's row, beside the table's (a driven model: the mirror needs an odd
#: equation)
TOY = table.PendulumSystem("paper", "mirrored_stop", closed_form=False, exact_flow=False,
                           slide=False, tangent=False, affine=True)


@njit(cache=True)
def mirrored_stop_data(case):
    return 0.0, case[C.k]  # the stop at psi = 0, the rotor stop's data


def toy_entry(model: str):
    """The toy system's block for a model, built as the table's are, and a Python entry."""
    row = TOY._replace(model=model)
    block = systems.build_block(row, mirrored_stop(getattr(models, model.upper())),
                                systems.PARAMETERS[model], mirrored_stop_data,
                                returning=True)

    return module_level(block, f"toy_mirrored_stop_{model}", globals(), dict(cache=True))


def cases_of(model, k, xi, kappa, r, tool="rotor_stop"):
    values = dict(model=table.MODELS[model], k=k, xi=xi, kappa=kappa, R=r,
                  tool=table.TOOLS[tool], tool_window=0.0, rotor_inertia_ratio=0.0,
                  motor_slope=0.0, idle_speed=0.0)
    return np.array([[values[c][i] if np.ndim(values[c]) else values[c]
                      for c in CASE_COLUMNS] for i in range(len(k))])


@pytest.mark.parametrize("model", ["paper", "rigid"])
def test_a_toy_surface_through_the_table_is_the_rotor_stop_mirrored(model):
    """Random designs with a periodic regime: the toy surface's steady state equals the
    closed form of the rotor stop to 1e-8 (DOPRI5 at rtol 1e-11) and the integrated rotor
    stop to 1e-12 (mirror images: the same steps)."""
    rng = np.random.default_rng(36 + len(model))
    n = 24
    k, xi, r = rng.uniform(0.5, 3.0, n), rng.uniform(1.0, 8.0, n), rng.uniform(0.0, 0.4, n)
    # the rigid pendulum keeps a cycle where v* = (1 + k)(1 + R)/(1 - R) stays below its
    # escape speed 2 sqrt(kappa k)
    kappa = (1 + k) ** 2 / (4 * k) * ((1 + r) / (1 - r)) ** 2 * rng.uniform(1.1, 3.0, n)
    stop = cases_of(model, k, xi, kappa, r)
    method = DECLARATION.method_record(integrator="closed_form")
    closed = dispatch.solve_cases(stop, method)
    cycle = closed[:, ROW.outcome] == SEQUENCE_CYCLE
    assert cycle.sum() >= n // 3, "too few periodic designs to compare"
    settings = Settings(method=METHOD_DOPRI5, rtol=1e-11, atol=1e-13, dt=0.0,
                        max_steps=systems.MAX_STEPS, horizon=math.inf, max_impacts=1000,
                        starts=1)
    toy = np.empty((n, N_ROW))
    toy_entry(model)(stop, settings, toy, np.empty_like(toy), np.empty((1, 2)))
    builtin = dispatch.solve_system(systems.entry_point(table.BY_CODES[table.MODELS[model], 0],
                                                        METHOD_DOPRI5), stop, settings)
    values = [ROW.amplitude, ROW.interval, ROW.speed, ROW.acceleration, ROW.frequency]
    np.testing.assert_array_equal(toy[cycle, ROW.outcome], SEQUENCE_CYCLE)
    np.testing.assert_allclose(toy[np.ix_(cycle, values)], closed[np.ix_(cycle, values)],
                               rtol=1e-8)
    np.testing.assert_allclose(toy[np.ix_(cycle, values)], builtin[np.ix_(cycle, values)],
                               rtol=1e-12)
    # escapes as the rotor stop does
    np.testing.assert_array_equal(toy[~cycle, ROW.outcome], builtin[~cycle, ROW.outcome])


def test_dop853_or_rk4_compiled_in_or_not_dopri5_takes_the_same_steps():
    """The entry points without DOP853 and RK4 (the default's: each is compiled only for
    the blocks that ask for it) give DOPRI5's bits to the last digit, as do those with
    either, and step by DOPRI5 where DOP853 is asked for (runge_kutta.low_order); the ones
    with DOP853 do integrate by it."""
    rng = np.random.default_rng(40)
    n = 12
    k, xi, r = rng.uniform(0.5, 3.0, n), rng.uniform(1.0, 8.0, n), rng.uniform(0.0, 0.4, n)
    stop = cases_of("paper", k, xi, np.zeros(n), r)
    row = table.BY_CODES[table.MODELS["paper"], table.TOOLS["rotor_stop"]]

    def rows(method, compiled):
        settings = systems.settings_for(row, method, 1e-10, 1e-12, 0.0, 200)
        return dispatch.solve_system(systems.ENTRY_POINTS[row, False, compiled, False, False],
                                     stop, settings)

    dopri5 = rows(METHOD_DOPRI5, ())
    assert (dopri5[:, ROW.outcome] == SEQUENCE_CYCLE).sum() >= n // 2
    np.testing.assert_array_equal(rows(METHOD_DOPRI5, (METHOD_DOP853,)), dopri5)
    np.testing.assert_array_equal(rows(METHOD_DOPRI5, (METHOD_RK4,)), dopri5)
    np.testing.assert_array_equal(rows(METHOD_DOP853, ()), dopri5)
    dop853 = rows(METHOD_DOP853, (METHOD_DOP853,))
    stepped = dopri5[:, ROW.steps] > 0  # an escape decided before a flight takes none
    assert stepped.sum() >= n // 2
    assert np.all(dop853[stepped, ROW.steps] < dopri5[stepped, ROW.steps] / 2)


# the blade's fullest entry point is this test's alone: the whole suite compiles it
@pytest.mark.parametrize("model, tool", [("rotor", "rotor_stop"),
                                         pytest.param("rigid", "lab_window",
                                                      marks=pytest.mark.slow)])
def test_the_leanest_entry_point_gives_the_bits_of_the_fullest_at_one_start(model, tool):
    """An entry point without the search for other starts' cycles and without auto's second
    stage (so with the one-stage calls inlined) gives, at one start and no second stage
    asked for, every bit of the one with both compiled in: on the rotor stop (a smooth map:
    its jumps and Broyden's steps) and on the blade by the exact flights. What the lean
    entry points leave out is only what these solves never run."""
    rng = np.random.default_rng(48)
    n = 16
    k = rng.uniform(0.9, 2.5, n)
    values = dict(model=table.MODELS[model], k=k, xi=4.0,
                  kappa=(1 + k) ** 2 / (4 * k) * rng.uniform(1.1, 1.5, n),
                  R=np.where(rng.random(n) < 0.3, 0.0, rng.uniform(0.0, 0.02, n)),
                  tool=table.TOOLS[tool], tool_window=rng.uniform(0.1, 0.5, n),
                  rotor_inertia_ratio=rng.uniform(20.0, 200.0, n),
                  motor_slope=rng.uniform(5.0, 100.0, n), idle_speed=1.0)
    cases = np.ascontiguousarray(np.stack([np.broadcast_to(values[c], n)
                                           for c in CASE_COLUMNS], axis=1))
    row = table.BY_CODES[table.MODELS[model], table.TOOLS[tool]]
    method = METHOD_EXACT if tool == "lab_window" else METHOD_DOPRI5
    rtol, atol, dt = exact_settings(1e-6) if method == METHOD_EXACT else (1e-9, 1e-9, 0.0)
    settings = systems.settings_for(row, method, rtol, atol, dt, 200)
    lean = dispatch.solve_system(systems.entry_point(row, method), cases, settings)
    full = dispatch.solve_system(systems.ENTRY_POINTS[row, False, (), True, True], cases,
                                 settings)
    assert systems.entry_point(row, method) is systems.ENTRY_POINTS[row, False, (), False,
                                                                    False]
    assert (lean[:, ROW.outcome] == SEQUENCE_CYCLE).sum() >= n // 4
    np.testing.assert_array_equal(lean, full)


def test_entry_points_and_dispatch_follow_the_table():
    """One entry point per row, method order and stages, a tangent one exactly where the
    row says the multipliers need it, each compiled function named after its row; the
    row's flags agree with what its contact and model do."""
    for row in table.SYSTEMS:
        for method, compiled in ((METHOD_DOPRI5, ()), (METHOD_EXACT, ()),
                                 (METHOD_DOP853, (METHOD_DOP853,)), (METHOD_RK4, (METHOD_RK4,))):
            for two in (False, True):
                for tangent in (False, True):
                    for starts in (1, 8):
                        entry = systems.entry_point(row, method, tangent, two, starts)
                        assert entry.py_func.__name__ == table.entry_name(
                            row, tangent and row.tangent, compiled, two, starts > 1)
                assert (((row, True, compiled, two, False) in systems.ENTRY_POINTS)
                        == row.tangent)
        contact = systems.CONTACTS[row.model, row.tool, ()]
        model = getattr(models, row.model.upper())
        assert (contact.pressed is not tools.never) == row.slide
        assert contact.smooth == (row.tool == "rotor_stop")
        assert row.affine == (contact.smooth and model.driven)
        assert row.exact_flow == (model.exact is not None and not row.closed_form)
        assert row.closed_form == (model.driven and row.tool == "rotor_stop")
    assert set(table.BY_CODES) == {(table.MODELS[s.model], table.TOOLS[s.tool])
                                   for s in table.SYSTEMS}
    assert len(table.BY_CODES) == len(table.MODELS) * len(table.TOOLS)
    decl = {q.name: q for q in DECLARATION.parameters}
    assert decl["model"].choices == table.MODELS and decl["tool"].choices == table.TOOLS


def test_a_process_makes_only_the_entry_points_it_looks_up():
    """Importing the systems makes no entry point and no contact; looking one up makes it
    and its contact, once, and nothing else; threads that look up the same one at once get
    the same function (blocks run on threads). In a fresh process: this one's tests have
    made others already."""
    code = """
import threading
from numba.core.dispatcher import Dispatcher
import gc
from kernels.pendulum import systems, table
from kernels.impact.runge_kutta import METHOD_DOPRI5
assert not systems.ENTRY_POINTS._made and not systems.CONTACTS._made
before = sum(isinstance(o, Dispatcher) for o in gc.get_objects())
row = table.BY_CODES[table.MODELS["rotor"], table.TOOLS["rotor_stop"]]
got = []
threads = [threading.Thread(target=lambda: got.append(
    systems.entry_point(row, METHOD_DOPRI5, two_stage=True))) for _ in range(4)]
for t in threads:
    t.start()
for t in threads:
    t.join()
assert len(got) == 4 and all(g is got[0] for g in got)
assert list(systems.ENTRY_POINTS._made) == [(row, False, (), True, False)]
assert list(systems.CONTACTS._made) == [("rotor", "rotor_stop", ())]
made = sum(isinstance(o, Dispatcher) for o in gc.get_objects()) - before
every = len(systems.ENTRY_POINTS)
paper = table.BY_CODES[table.MODELS["paper"], table.TOOLS["rotor_stop"]]
assert (paper, True, (), True, False) not in systems.ENTRY_POINTS  # no tangent: no key
assert (row, True, (), True, False) in systems.ENTRY_POINTS  # a key, not made
assert len(systems.ENTRY_POINTS._made) == 1
print(made, every)
"""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         cwd=Path(__file__).resolve().parent.parent)
    assert out.returncode == 0, out.stderr
    made, every = map(int, out.stdout.split())
    # one system's block, not every system's variants (each a tree of functions)
    assert 0 < made < 200 and every > 100


def test_the_rules_and_the_docs_list_come_from_the_table():
    """closed_form is refused exactly where no row of the pairs asked for has one, and the
    message names the rows that do; the docs render the table's rows."""
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "docs"))
    try:
        from hooks import pendulum_systems
    finally:
        sys.path.pop(0)
    for row in table.SYSTEMS:
        message = DECLARATION.rules({"model": {row.model}, "tool": {row.tool},
                                     "method.integrator": {"closed_form"}})
        assert (message is None) == (row.closed_form or row.exact_flow)
        if message:
            assert all(f"{s.model} on {s.tool}" in message for s in table.SYSTEMS
                       if s.closed_form or s.exact_flow)
    rendered = pendulum_systems()
    for row in table.SYSTEMS:
        assert f"| {row.model} | {row.tool} |" in rendered
