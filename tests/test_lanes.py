"""Lanes (kernels/impact/lanes.py): the rotor model's designs solved 8 at a time, their
flights' steps taken together, give every bit of the same designs solved one at a time,
whatever their order and block; the lane loop vectorises."""

import numpy as np
import pytest
from numba import njit

from kernels.impact.outcomes import SEQUENCE_CYCLE
from kernels.impact.runge_kutta import METHOD_DOPRI5
from kernels.pendulum import dispatch, systems, table
from kernels.pendulum.cases import CASE_COLUMNS, N_ROW, ROW


def rotor_cases(tool, n, seed):
    """Random rotor-model designs on ``tool``: cycles, chatter, escapes, slides."""
    rng = np.random.default_rng(seed)
    k = rng.uniform(0.9, 2.5, n)
    values = dict(model=table.MODELS["rotor"], k=k, xi=rng.uniform(1.0, 6.0, n),
                  kappa=(1 + k) ** 2 / (4 * k) * rng.uniform(1.05, 2.0, n),
                  R=np.where(rng.random(n) < 0.3, 0.0, rng.uniform(0.0, 0.5, n)),
                  tool=table.TOOLS[tool], tool_window=rng.uniform(0.1, 0.5, n),
                  rotor_inertia_ratio=rng.uniform(5.0, 200.0, n),
                  motor_slope=rng.uniform(5.0, 100.0, n), idle_speed=1.0)
    return np.ascontiguousarray(np.stack([np.broadcast_to(values[c], n)
                                          for c in CASE_COLUMNS], axis=1))


def one_lane_entry(row):
    """The row's lean block (DOPRI5, one stage, one start) with one lane: every flight
    taken alone, its step called."""
    block = systems.build_block(row, systems.CONTACTS[row.model, row.tool, ()],
                                systems.PARAMETERS[row.model], systems.DATA[row.tool],
                                two_stage=False, several_starts=False, lanes=1)

    @njit
    def entry(cases, settings, rows, first_rows, log):
        block(cases, settings, rows, first_rows, log)

    return entry


@pytest.mark.parametrize("tool", ["rotor_stop", "lab_window"])
def test_a_design_in_a_lane_has_the_bits_it_has_alone(tool):
    """Random rotor designs: the built-in block (8 lanes, systems.LANES) gives each the row
    the one-lane block gives it, bit for bit (step, step-size control, events cleared by
    the lanes' chord bound or searched, impacts, slides); the same designs reversed and
    in blocks of 3 (other lanes, other neighbours, refills at other times) too."""
    assert systems.LANES["rotor"] > 1
    row = table.BY_CODES[table.MODELS["rotor"], table.TOOLS[tool]]
    n = 40
    cases = rotor_cases(tool, n, 41 + len(tool))
    settings = systems.settings_for(row, METHOD_DOPRI5, 1e-8, 1e-8, 0.0, 300)
    entry = systems.entry_point(row, METHOD_DOPRI5)
    in_lanes = dispatch.solve_system(entry, cases, settings)
    assert (in_lanes[:, ROW.outcome] == SEQUENCE_CYCLE).sum() >= n // 4
    assert np.nansum(in_lanes[:, ROW.steps]) > 50 * n  # the lanes took steps
    alone = np.empty((n, N_ROW))
    one_lane_entry(row)(cases, settings, alone, np.empty_like(alone), np.empty((1, 2)))
    np.testing.assert_array_equal(in_lanes, alone)
    reversed_rows = dispatch.solve_system(entry, cases[::-1].copy(), settings)[::-1]
    np.testing.assert_array_equal(reversed_rows, in_lanes)
    in_threes = np.concatenate([dispatch.solve_system(entry, cases[i:i + 3], settings)
                                for i in range(0, n, 3)])
    np.testing.assert_array_equal(in_threes, in_lanes)


def test_the_lanes_step_vectorises():
    """The rotor model's step and event test over 8 lanes (lanes.make_trial) compile to
    packed arithmetic, with no call to a sine or cosine: the step in lanes is vectorised,
    not 8 scalar steps."""
    import re

    from kernels.impact.lanes import layout, make_trial

    contact = systems.CONTACTS["rotor", "lab_window", ()]
    trial = make_trial(contact.flight, 8, ())

    @njit(error_model="numpy")
    def steps(buf, y, p, data):
        trial(buf, METHOD_DOPRI5, y, p, data)

    y, p, data = (0.0, 1.0, 0.2, 0.5), (2.0, 0.5, 60.0, 20.0, 1.0), (0.3, 0.5, 1.0, 0.0, 1.0)
    buf = np.zeros(8 * layout.py_func(y, p, data).size)
    steps(buf, y, p, data)
    asm = steps.inspect_asm(steps.signatures[0])
    packed = re.findall(r"\bv?(?:mul|add|sub|div|fmadd\w*|fmsub\w*|fnmadd\w*)pd\b", asm)
    assert len(packed) > 100, f"{len(packed)} packed arithmetic instructions"
    assert not re.search(r"\bcall\w*\s+\*?%?\w*(sin|cos)", asm)
