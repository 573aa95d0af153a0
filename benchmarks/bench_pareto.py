"""Pareto fronts of 10^6 candidate designs: the exact front (kernels.pareto) after the atlas
is read, for 2, 3 and 4 objectives; CPU time, interleaved rounds (the machine is shared).

Run: .venv/bin/python benchmarks/bench_pareto.py   (writes benchmarks/results/pareto.json)

The atlas is a 1030 x 1030 grid in memory with the crank-rocker's kind of outputs: a status
(2 % not ok), requirements (3 % failing; 10^6 candidates left) and objectives with ties (values rounded to a
grid of 1e-4) that conflict, so that the front is not a handful of points.
"""

from __future__ import annotations

import json
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

N_SIDE = 1030
ROUNDS = 5


def atlas(seed: int = 7):
    import xarray as xr

    rng = np.random.default_rng(seed)
    shape = (N_SIDE, N_SIDE)
    u, v = rng.random(shape), rng.random(shape)
    status = np.where(rng.random(shape) < 0.02, 1, 0).astype(np.int8)
    requirements = np.where(rng.random(shape) < 0.03, 2, 0).astype(np.int8)
    outputs = {"rate": np.round(u, 4), "load": np.round(u + 0.3 * v, 4),
               "energy": np.round(1 - u * v, 4), "noise": np.round(v * v + 0.1 * u, 4)}
    data = {name: (("a", "b"), values, {"units": "1", "long_name": name})
            for name, values in outputs.items()}
    data["status"] = (("a", "b"), status, {"flag_values": np.array([0, 1], np.int8),
                                           "flag_meanings": "ok not_assemblable",
                                           "units": "1", "long_name": "status"})
    data["requirements"] = (("a", "b"), requirements, {
        "flag_values": np.array([0, 1, 2], np.int8),
        "flag_meanings": "met no_value above_load", "units": "1", "long_name": "req"})
    return xr.Dataset(data, coords={"a": np.arange(N_SIDE, dtype=float),
                                    "b": np.arange(N_SIDE, dtype=float)})


CASES = {
    "2 objectives": (["rate"], ["load"]),
    "3 objectives": (["rate"], ["load", "noise"]),
    "4 objectives": (["rate", "energy"], ["load", "noise"]),
}


def main():
    from sweep.fronts import front

    ds = atlas()
    front(ds, ["rate"], ["load"])  # compile (or load the cache) once
    cpu = {name: [] for name in CASES}
    sizes = {}
    for _ in range(ROUNDS):  # interleaved: each round runs every case once
        for name, (maximize, minimize) in CASES.items():
            t = time.process_time()
            result = front(ds, maximize, minimize)
            cpu[name].append(time.process_time() - t)
            sizes[name] = (result.candidates, result.designs.sizes["design"])
    results = {name: {"candidates": sizes[name][0], "front_designs": sizes[name][1],
                      "cpu_s_median": float(np.median(cpu[name])),
                      "cpu_s_min": float(np.min(cpu[name]))} for name in CASES}
    out = {"what": "sweep.pareto.front on a 10^6-point atlas in memory (after reading): "
                   "feasibility, the exact front, the pick and the selection; CPU seconds",
           "points": N_SIDE * N_SIDE, "rounds": ROUNDS,
           "machine": {"node": platform.node(), "cpu_count": os.cpu_count(),
                       "python": platform.python_version()},
           "results": results}
    path = Path(__file__).parent / "results" / "pareto.json"
    path.write_text(json.dumps(out, indent=2) + "\n")
    for name, r in results.items():
        print(f"{name}: {r['candidates']:,} candidates, {r['front_designs']:,} on the front, "
              f"{r['cpu_s_median']:.3f} s CPU (median of {ROUNDS})")


if __name__ == "__main__":
    main()
