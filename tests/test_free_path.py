"""The free path through the special positions ([CR] §2, [GUIM] Fig. 4; issue 64 item 4):
with no stop, the linkage passes each node on its smooth curve and switches branch, so its
cycle is two crank turns and nothing is lost: the balancing moment's work over it is zero
at constant omega1 (the energy balance of a conservative linkage), while on the impact path
it is the blow's loss. Its reactions are the four-bar's on the branch of each turn."""

import math

import numpy as np
import pytest

import sweep
from kernels import kinetostatics as kt
from tests.test_kinetostatics import BASE, params


def forces_atlas(path, **fixed):
    spec = {"mechanism": "linkage_forces", "grid": {"tilt": [0.0, 0.7, -1.2]},
            "fixed": fixed, "method": {"profile_points": 64, "path": path}}
    return sweep.decode(sweep.run(spec))


@pytest.mark.parametrize("seed", range(3))
def test_the_free_path_loses_nothing_and_the_impact_path_loses_the_blow(seed):
    rng = np.random.default_rng(6440 + seed)
    masses = {name: float(rng.uniform(0.5, 10.0)) for name in ("m1", "m2", "m3")}
    masses |= {name: float(rng.uniform(0.001, 0.1)) for name in ("J1", "J2", "J3")}
    masses |= {"omega1": float(rng.uniform(5.0, 40.0)), "q2": float(rng.uniform(-0.05, 0.05))}
    free, impact = forces_atlas("free", **masses), forces_atlas("impact", **masses)
    assert (free.status.values == "special_position").all()
    scale = free.balancing_moment_rms.values * 4 * math.pi
    assert np.abs(free.cycle_work.values).max() <= 1e-9 * scale.max()
    assert (impact.cycle_work.values > 1e-3 * scale).all()
    assert free.crank_angle.values[-1] > 3.9 * math.pi


def test_each_turn_of_the_free_path_is_the_four_bar_on_its_branch():
    fixed = {k: v for k, v in BASE.items() if k not in ("sigma", "tilt")}
    ds = forces_atlas("free", **fixed).isel(tilt=1)
    sigma = {"plus": 1.0, "minus": -1.0}[str(ds.assembly_branch.values)]
    node = float(ds.special_crank_angle.values)
    pr = params(**dict(BASE, tilt=float(ds.tilt.values)))
    res = np.empty(kt.N_RESULT)
    turns = set()
    for j, phi in enumerate(ds.crank_angle.values):
        turn = math.floor((phi - node) / (2 * math.pi))
        turns.add(turn % 2)
        assert kt.joint_forces(phi, pr, sigma if turn % 2 == 0 else -sigma, res, 1e-9)
        for name, row in (("F21_n", kt.R_F21N), ("F34_t", kt.R_F34T),
                          ("balancing_moment", kt.R_MB)):
            assert float(ds[name].values[j]) == pytest.approx(res[row], rel=1e-12, abs=1e-9)
    assert turns == {0, 1}
