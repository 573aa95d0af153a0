"""What counting the cycle's margins in auto's error estimate costs: the stability example
(rotor model on the blade, tol 1e-6) solved with the margins asked for and without them (the
multipliers asked for in both), CPU time in interleaved rounds and the integration steps
counted by the kernel. Writes benchmarks/results/margin_estimate.json.

Run:  .venv/bin/python benchmarks/bench_margin_estimate.py [--rounds 3]
"""

import argparse
import json
import time
from pathlib import Path

import numpy as np

from sweep import engine, spec

EXAMPLE = Path(__file__).resolve().parent.parent / "sweep" / "example_specs"
RESULTS = Path(__file__).resolve().parent / "results" / "margin_estimate.json"
BASE = ("regime", "impact_speed", "impact_interval", "multiplier_modulus", "n_steps")
MARGINS = ("impact_speed_min_ratio", "edge_margin")


def solve(sweep, outputs):
    params = engine.point_parameters(sweep, np.arange(int(np.prod(sweep.shape))))
    record = sweep.method_record._replace(outputs=outputs)
    start = time.process_time()
    out, status, _ = sweep.kernel(params, record)
    return time.process_time() - start, out, status


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    text = (EXAMPLE / "rotary_pendulum_stability.toml").read_text()
    sweep = spec.parse(text.replace("starts = 8", "starts = 1"))
    steps = sweep.mechanism.output_index.n_steps
    solve(sweep, BASE)  # compile
    times = {"without": [], "with": []}
    counted = {}
    for _ in range(args.rounds):
        for name, outputs in (("without", BASE), ("with", BASE + MARGINS)):
            cpu, out, _ = solve(sweep, outputs)
            times[name].append(cpu)
            counted[name] = float(np.nansum(out[steps]))
    result = {"designs": int(np.prod(sweep.shape)), "rounds": args.rounds,
              "cpu_s_median": {k: float(np.median(v)) for k, v in times.items()},
              "steps": counted,
              "ratio_cpu": float(np.median(times["with"]) / np.median(times["without"])),
              "ratio_steps": counted["with"] / counted["without"]}
    RESULTS.write_text(json.dumps(result, indent=2) + "\n")
    print(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
