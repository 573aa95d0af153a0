"""What a whole `sweep run` costs beyond importing its libraries: the import floor.

Run: .venv/bin/python benchmarks/bench_overhead.py   (writes benchmarks/results/overhead.json)

Each case is a whole process (start-up, spec, compile-cache load, kernel, atlas write with
the default compression, summary), timed from outside and run in turn with the floor,
``python -c "import numba, xarray, dask, netCDF4"`` (A B A B ...), after one warm run
that fills the numba cache. Reported: median wall times, the excess over the floor
(median of the pairwise differences) and the ratio. Cases: a 9-point crank-rocker sweep,
a 10^6-point crank-rocker sweep, a 10^6-point closed-form pendulum sweep.
"""

from __future__ import annotations

import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
SWEEP = Path(sys.executable).with_name("sweep")
FLOOR = [sys.executable, "-c", "import numba, xarray, dask, netCDF4"]
CASES = {"tiny crank-rocker (9 points)": "crank_rocker_tiny.toml",
         "crank-rocker 10^6 points": "crank_rocker_1e6.toml",
         "closed-form pendulum 10^6 points": "rotary_pendulum_1e6.toml"}
PAIRS = 5


def wall(command) -> float:
    t = time.perf_counter()
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - t


def main() -> None:
    results = {}
    with tempfile.TemporaryDirectory() as tmp:
        for name, spec in CASES.items():
            run = [str(SWEEP), "run", str(HERE / "specs" / spec), "-o",
                   str(Path(tmp) / "atlas.nc"), "--force", "-q"]
            wall(run)  # fills the numba cache: the case is a warm run
            pairs = [(wall(run), wall(FLOOR)) for _ in range(PAIRS)]
            runs, floors = [a for a, _ in pairs], [b for _, b in pairs]
            results[name] = {
                "run_s": round(statistics.median(runs), 3),
                "floor_s": round(statistics.median(floors), 3),
                "excess_s": round(statistics.median(a - b for a, b in pairs), 3),
                "ratio": round(statistics.median(a / b for a, b in pairs), 2)}
            r = results[name]
            print(f"{name}: {r['run_s']:.2f} s, floor {r['floor_s']:.2f} s, "
                  f"excess {r['excess_s']:.2f} s ({r['ratio']:.2f}x)", flush=True)
    record = {"what": __doc__.strip().splitlines()[0], "pairs": PAIRS,
              "machine": platform.processor() or platform.machine(), "cpus": os.cpu_count(),
              "results": results}
    path = HERE / "results" / "overhead.json"
    path.write_text(json.dumps(record, indent=2) + "\n")
    print(f"written {path}")


if __name__ == "__main__":
    main()
