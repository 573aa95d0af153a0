"""Paying only for the flights a result needs (issue 40): a sequence that settles nowhere is
called not periodic as soon as the budget's own verdict is certain (verdicts.
settles_nowhere), checked against the long runs it replaces; a start is captured by a
cycle another start found (attractors.captured_by) only while it contracts onto it. (A
start that stops on such a cycle, attractors.known_attractor, is checked by the attractor
counts of tests/test_edges.py and tests/test_stability.py, against the blade twin's starts
and the section map's own.)"""

import math

import numpy as np
import pytest

from kernels.impact.attractors import CAPTURE_DISTANCE, KNOWN, captured_by
from kernels.impact.verdicts import (MAX_PERIOD, classify_period, not_periodic,
                                     settles_nowhere)
from kernels.impact.outcomes import SEQUENCE_CYCLE, SEQUENCE_NOT_PERIODIC, Settings
from kernels.impact.runge_kutta import METHOD_DOPRI5, METHOD_EXACT
from kernels.pendulum import systems, table
from kernels.pendulum.accuracy import exact_settings
from kernels.pendulum.cases import CASE_COLUMNS, N_ROW, ROW
from kernels.pendulum.dispatch import solve_system

COUNTERS = [ROW.steps, ROW.rejected, ROW.events, ROW.impacts]


def spiral(rho, angle, n=1100):
    """Section states rho^j (cos j angle, 2 sin j angle): a transient spiralling into its
    fixed point (a complex multiplier) by rho a section; rho = 1: a quasi-periodic
    sequence on an ellipse."""
    return np.array([[rho ** j * math.cos(angle * j), 2 * rho ** j * math.sin(angle * j)]
                     for j in range(n)])


def henon(n=1100):
    """The Henon map (a = 1.4, b = 0.3): a chaotic sequence, steps that never shrink."""
    x = np.empty((n, 2))
    x[0] = (0.1, 0.1)
    for j in range(1, n):
        x[j] = (1 - 1.4 * x[j - 1, 0] ** 2 + x[j - 1, 1], 0.3 * x[j - 1, 0])
    return x


def to_a_three_cycle(rho, n=1100):
    """Section states on three points, the distance to them shrinking by rho a section: a
    transient converging to a period-3 cycle, whose steps between sections never shrink."""
    corners = np.array([[1.0, 0.0], [-0.5, 0.8], [-0.5, -0.8]])
    return np.array([corners[j % 3] + rho ** j * np.array([0.3, 0.1]) for j in range(n)])


def budget_verdict(history, budget, repeat_tol=1e-9):
    """What the whole budget says: the first period classified, or not_periodic's verdict
    at the budget's end (as impact_map's transient)."""
    for m in range(3, budget + 2):
        if classify_period(history, m, repeat_tol, MAX_PERIOD) > 0:
            return "cycle"
    return not_periodic(history, budget + 1)


def test_the_early_verdict_is_stricter_than_the_budgets():
    """On transients that spiral in geometrically or converge to a period-3 cycle, the early
    verdict says not periodic only where the whole budget does too, at every checkpoint
    and budget; a rotation by an irrational angle (quasi-periodic) is called once its
    Birkhoff averages agree (256 sections), before a budget of 1000; a chaotic sequence
    never (it flies its budget)."""
    golden = 2 * math.pi * (math.sqrt(5) - 1) / 2
    rhos = np.concatenate([np.linspace(0.9, 0.999, 60), 1 - np.logspace(-3, -6, 12)])
    for budget in (100, 200, 1000):
        settings = Settings(METHOD_DOPRI5, 1e-9, 1e-9, 0.0, 10 ** 6, math.inf,
                            max_impacts=budget, starts=1, verdict_from=64)
        checkpoints = [n for n in (64, 128, 256, 512) if n < budget]
        called = 0
        for rho in rhos:
            for history in (spiral(rho, golden), spiral(rho, 0.3), spiral(rho, 2.0),
                            to_a_three_cycle(rho)):
                if any(settles_nowhere(history, n, settings, 1e-9) for n in checkpoints):
                    called += 1
                    assert budget_verdict(history, budget) == SEQUENCE_NOT_PERIODIC, (
                        budget, rho)
        assert called > 0 or budget < 256
        quasi = spiral(1.0, golden)
        assert any(settles_nowhere(quasi, n, settings, 1e-9)
                   for n in checkpoints) == (budget > 256)
        assert not settles_nowhere(quasi, 300, settings, 1e-9)  # not a checkpoint
        assert not any(settles_nowhere(henon(), n, settings, 1e-9) for n in checkpoints)
        assert not any(settles_nowhere(to_a_three_cycle(0.99), n, settings, 1e-9)
                       for n in checkpoints)
        off = settings._replace(verdict_from=0)
        assert not any(settles_nowhere(quasi, n, off, 1e-9) for n in checkpoints)


def blade_cases(model, n, rng):
    values = dict(model=table.MODELS[model], k=rng.uniform(0.5, 2.5, n),
                  xi=rng.uniform(2.0, 8.0, n), kappa=rng.uniform(1.05, 1.5, n),
                  R=np.where(rng.random(n) < 0.3, 0.0, rng.uniform(0.0, 0.1, n)),
                  tool=table.TOOLS["lab_window"], tool_window=rng.uniform(0.1, 0.6, n),
                  rotor_inertia_ratio=rng.uniform(20.0, 200.0, n),
                  motor_slope=rng.uniform(5.0, 100.0, n), idle_speed=1.0)
    return np.ascontiguousarray(np.stack([np.broadcast_to(values[c], n) for c in CASE_COLUMNS],
                                         axis=1))


@pytest.mark.parametrize("model, method, budget", [("rigid", METHOD_EXACT, 200),
                                                   ("rigid", METHOD_DOPRI5, 1000),
                                                   ("paper", METHOD_DOPRI5, 200),
                                                   ("rotor", METHOD_DOPRI5, 200)])
def test_the_early_verdict_agrees_with_the_long_run_on_random_blade_designs(model, method,
                                                                             budget):
    """Random designs on the blade, where sequences that settle nowhere are common (and are
    chaotic: a few end without an impact after 65-194 sections): with the early verdict
    and without it (the whole budget flown), every design ends in the same outcome with
    the same values; only a design called early costs less."""
    rng = np.random.default_rng(40 + budget + len(model) + method)
    cases = blade_cases(model, 120, rng)
    row = table.BY_CODES[table.MODELS[model], table.TOOLS["lab_window"]]
    rtol, atol, dt = exact_settings(1e-6) if method == METHOD_EXACT else (1e-9, 1e-9, 0.0)
    early, long = (solve_system(systems.entry_point(row, method), cases, Settings(
        method=method, rtol=rtol, atol=atol, dt=dt, max_steps=systems.MAX_STEPS,
        horizon=systems.CONTACTS[row.model, row.tool, ()].horizon, max_impacts=budget,
        starts=1, verdict_from=verdict)) for verdict in (systems.VERDICT_FROM, 0))
    values = [j for j in range(N_ROW) if j not in COUNTERS]
    np.testing.assert_array_equal(early[:, values], long[:, values])
    called = early[:, ROW.steps] < long[:, ROW.steps]
    assert np.all(early[called, ROW.outcome] == SEQUENCE_NOT_PERIODIC)
    assert np.all(early[~called, ROW.steps] == long[~called, ROW.steps])


@pytest.mark.parametrize("rtol", [1e-8, 1e-9])
def test_the_early_verdict_leaves_slowly_converging_period_n_cycles_to_the_budget(rtol):
    """The stability example's designs at R = 0.075 on its wider blades (the rotor model)
    converge slowly to a period-n cycle: their section states' averages agree and their
    steps between sections do not shrink, but the states p sections apart do. They end
    period_n with the early verdict as without it."""
    windows = np.linspace(0.34, 0.5, 9)
    n = len(windows)
    values = dict(model=table.MODELS["rotor"], k=1.0, xi=4.0, kappa=1.2, R=0.075,
                  tool=table.TOOLS["lab_window"], tool_window=windows,
                  rotor_inertia_ratio=100.0, motor_slope=100.0, idle_speed=1.0)
    cases = np.ascontiguousarray(np.stack([np.broadcast_to(values[c], n)
                                           for c in CASE_COLUMNS], axis=1))
    row = table.BY_CODES[table.MODELS["rotor"], table.TOOLS["lab_window"]]
    early, long = (solve_system(systems.entry_point(row, METHOD_DOPRI5), cases, Settings(
        method=METHOD_DOPRI5, rtol=rtol, atol=rtol, dt=0.0, max_steps=systems.MAX_STEPS,
        horizon=systems.CONTACTS[row.model, row.tool, ()].horizon, max_impacts=1000,
        starts=1, verdict_from=verdict)) for verdict in (systems.VERDICT_FROM, 0))
    assert np.all(long[:, ROW.outcome] == SEQUENCE_CYCLE) and np.all(long[:, ROW.period] > 1)
    values = [j for j in range(N_ROW) if j not in COUNTERS]
    np.testing.assert_array_equal(early[:, values], long[:, values])


def known_rows(*cycles):
    """Rows of known cycles (columns attractors.KNOWN): (outcome, period, section state)."""
    rows = np.zeros((len(cycles), KNOWN.key + 2))
    for j, (outcome, period, state) in enumerate(cycles):
        rows[j, KNOWN.outcome], rows[j, KNOWN.period] = outcome, period
        rows[j, KNOWN.key:] = state
    return rows


def first_capture(history, known):
    """The first section count at which captured_by names a row, and that row (-1, -1)."""
    for count in range(1, len(history) + 1):
        row = captured_by(known, history, count)
        if row >= 0:
            return count, row
    return -1, -1


def test_a_start_is_captured_only_while_it_contracts_onto_a_known_cycle():
    """attractors.captured_by, against sequences whose limits are known: a start that
    spirals into a known fixed point (multipliers of modulus 0.5 to 0.85) is captured
    within CAPTURE_DISTANCE of it, and only then; into a known period-3 cycle, on the
    cycle's own phase; not by a cycle 5 to 50 CAPTURE_DISTANCE from its own limit (it
    stops contracting onto it while its steps vanish), not while it converges more slowly than
    CAPTURE_RATIO, and not by a row of a sequence that ended without a cycle."""
    for rho in (0.5, 0.7, 0.85):
        history = spiral(rho, 2.0)
        count, row = first_capture(history, known_rows((SEQUENCE_CYCLE, 1, (0.0, 0.0)),
                                                       (SEQUENCE_CYCLE, 1, (0.5, 0.5))))
        assert row == 0
        assert np.abs(history[count - 1]).max() <= CAPTURE_DISTANCE
        assert np.abs(history[count - 2]).max() > CAPTURE_DISTANCE * 0.5  # not late
        for offset in (5e-3, 1e-3, 5e-4):  # its limit is another, this far from the known
            other = known_rows((SEQUENCE_CYCLE, 1, (offset, 0.0)))
            assert first_capture(history, other) == (-1, -1), (rho, offset)
        ended = known_rows((SEQUENCE_NOT_PERIODIC, 0, (0.0, 0.0)))
        assert first_capture(history, ended) == (-1, -1)
    assert first_capture(spiral(0.95, 0.0), known_rows((SEQUENCE_CYCLE, 1, (0.0, 0.0))))[1] == -1
    three = to_a_three_cycle(0.6, 60)
    count, row = first_capture(three, known_rows((SEQUENCE_CYCLE, 3, (1.0, 0.0))))
    assert row == 0 and (count - 1) % 3 == 0
    assert np.abs(three[count - 1] - (1.0, 0.0)).max() <= CAPTURE_DISTANCE
    # as a fixed point, the same cycle's corner is no limit: its states never all contract
    assert first_capture(three, known_rows((SEQUENCE_CYCLE, 1, (1.0, 0.0))))[1] == -1
