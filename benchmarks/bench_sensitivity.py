"""A 6-input sensitivity study (the kinetostatics; the crank-rocker has 5 numeric inputs
that are not alternatives of one another) at 16,384 base samples (>= 10^4; a power of two keeps the
Sobol' points balanced), i.e. 131,072 designs on the kernel, after compile: the CPU
seconds of ``sweep.sensitivity`` (sampling, the kernel on every core, SALib's estimators
with their bootstrap), in rounds, for the crank-rocker and the kinetostatics.

Run: .venv/bin/python benchmarks/bench_sensitivity.py [--rounds N]
     (writes benchmarks/results/sensitivity.json)
"""

from __future__ import annotations

import argparse
import json
import platform
import statistics
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

import sweep  # noqa: E402

SAMPLES = 16_384
STUDIES = {
    "crank_rocker": ({"mechanism": "crank_rocker", "fixed": {"type": "a"},
                      "outputs": ["impact_speed", "blow_energy", "blow_rate",
                                  "transmission_angle_working"],
                      "requirements": {"transmission_angle_working": ">= 20deg"}},
                     {"R": (0.05, 0.4), "largest_link": (1.6, 6.0), "omega1": (10.0, 40.0),
                      "crank_length": (0.05, 0.15), "rocker_inertia": (0.02, 0.08)}),
    "linkage_forces": ({"mechanism": "linkage_forces", "method": {"peak_samples": 91}},
                       {"omega1": (15.0, 40.0), "tilt": (0.0, 1.0), "m1": (1.0, 3.0),
                        "m2": (2.0, 4.0), "m3": (6.0, 10.0), "l1": (0.09, 0.11)}),
}


def cpu() -> float:
    return time.process_time()


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    result = {"what": f"sweep.sensitivity of 5 (crank_rocker) or 6 inputs at {SAMPLES:,} "
                      "base samples (samples x (inputs + 2) designs), after compile: CPU "
                      "seconds of the process (every thread), medians over rounds",
              "samples": SAMPLES, "rounds": args.rounds, "studies": {}}
    for name in STUDIES:
        document, inputs = STUDIES[name]
        sweep.sensitivity(document, inputs, samples=64)  # compile
        times = []
        for _ in range(args.rounds):
            start = cpu()
            ds = sweep.sensitivity(document, inputs, samples=SAMPLES)
            times.append(cpu() - start)
        result["studies"][name] = {"inputs": list(inputs), "designs": ds.attrs["evaluations"],
                                   "cpu_s": times, "cpu_s_median": statistics.median(times)}
        print(f"{name}: {len(inputs)} inputs, {ds.attrs['evaluations']:,} designs, "
              f"{statistics.median(times):.1f} CPU s (median of {args.rounds})", flush=True)
    result.update(machine=platform.machine(), python=platform.python_version(),
                  date=time.strftime("%Y-%m-%d"))
    out = HERE / "results" / "sensitivity.json"
    out.write_text(json.dumps(result, indent=1) + "\n")
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
