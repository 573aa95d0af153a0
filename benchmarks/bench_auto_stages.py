"""Where auto's cost goes on the rotor model's stop: its first stage (DOPRI5 from rest to the
cycle) against its second (on from that cycle 8 times finer in rtol, the error estimate),
on random designs of the rotor_auto workload's family (benchmarks/specs/
rotary_pendulum_rotor_auto.toml), at the default tol. The entry point is called directly
(warm), one stage and two stages interleaved, CPU time; the steps and sections (impact
events) of each stage are counted, and the second stage's sections histogrammed.

Run: .venv/bin/python benchmarks/bench_auto_stages.py [--designs N] [--rounds N]
     (writes benchmarks/results/auto_stages.json)
"""

from __future__ import annotations

import argparse
import json
import math
import platform
import statistics
import time
from pathlib import Path

import numpy as np

from kernels.impact.runge_kutta import METHOD_DOPRI5
from kernels.pendulum import accuracy, systems
from kernels.pendulum.cases import C, N_ROW, ROW
from kernels.pendulum.table import BY_CODES, MODELS, TOOLS

HERE = Path(__file__).resolve().parent


def cases(n: int, seed: int = 0) -> np.ndarray:
    """n random rotor designs of the workload's ranges (k = 1, kappa = 1.2)."""
    rng = np.random.default_rng(seed)
    out = np.zeros((n, len(C)))
    out[:, C.model], out[:, C.k], out[:, C.xi], out[:, C.kappa] = MODELS["rotor"], 1.0, 4.0, 1.2
    out[:, C.R] = rng.uniform(0.0, 0.02, n)
    out[:, C.rotor_inertia_ratio] = rng.uniform(20.0, 200.0, n)
    out[:, C.motor_slope] = rng.uniform(3.0, 50.0, n)
    out[:, C.idle_speed] = 1.0
    return out


def solve(designs: np.ndarray, finer_by: float, rtol: float):
    """(rows, first-stage rows, CPU s) of one call of the system's entry point."""
    system = BY_CODES[MODELS["rotor"], TOOLS["rotor_stop"]]
    entry = systems.entry_point(system, METHOD_DOPRI5, False, finer_by > 0.0, 1)
    settings = systems.settings_for(system, METHOD_DOPRI5, rtol, rtol, 0.0, 1000, 1, finer_by,
                                    math.inf, False)
    rows, first = np.empty((2, designs.shape[0], N_ROW))
    started = time.process_time()
    entry(designs, settings, rows, first, np.empty((1, 2)))
    return rows, first, time.process_time() - started


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--designs", type=int, default=1500)
    parser.add_argument("--rounds", type=int, default=5)
    args = parser.parse_args()
    designs = cases(args.designs)
    tol = 1e-8
    rtol = accuracy.AUTO_COARSE * accuracy.auto_rtol(tol)
    for finer_by in (0.0, accuracy.AUTO_REFINE):  # compile, or load the cache
        solve(designs, finer_by, rtol)
    one, two = [], []
    for _ in range(args.rounds):
        one.append(solve(designs, 0.0, rtol)[2])
        rows, first, seconds = solve(designs, accuracy.AUTO_REFINE, rtol)
        two.append(seconds)
    second_steps = rows[:, ROW.steps] - first[:, ROW.steps]
    second_sections = (rows[:, ROW.events] - first[:, ROW.events]).astype(int)
    result = {
        "machine": platform.node(), "designs": args.designs, "rounds": args.rounds, "tol": tol,
        "one_stage_cpu_s": statistics.median(one), "two_stages_cpu_s": statistics.median(two),
        "second_over_first_cpu": statistics.median(two) / statistics.median(one) - 1.0,
        "first_stage_steps_per_design": float(first[:, ROW.steps].mean()),
        "second_stage_steps_per_design": float(second_steps.mean()),
        "second_over_first_steps": float(second_steps.sum() / first[:, ROW.steps].sum()),
        "first_stage_sections_per_design": float(first[:, ROW.events].mean()),
        "second_stage_sections_histogram": np.bincount(second_sections).tolist(),
    }
    HERE.joinpath("results", "auto_stages.json").write_text(json.dumps(result, indent=2))
    print(json.dumps(result, indent=1))


if __name__ == "__main__":
    main()
