"""First contact: the run of each built-in example with an empty numba cache (cold: numba
compiles what the sweep needs) against the same run with the cache it left (warm), as whole
processes (`sweep run EXAMPLE -q`), in turn (cold, warm, cold, warm ...). The difference is
what a new user waits for once; the target is at most 20 s per example.

Run: .venv/bin/python benchmarks/bench_compile.py [--rounds N] [EXAMPLE ...]
     (writes benchmarks/results/compile.json)
"""

from __future__ import annotations

import argparse
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
SWEEP = str(Path(sys.executable).with_name("sweep"))


def timed_run(spec: Path, cache: Path, out: Path) -> float:
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache))
    started = time.perf_counter()
    subprocess.run([SWEEP, "run", str(spec), "-o", str(out), "-q", "--force"], env=env,
                   check=True, capture_output=True)
    return time.perf_counter() - started


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("examples", nargs="*")
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    names = args.examples or subprocess.run(
        [SWEEP, "examples"], check=True, capture_output=True, text=True).stdout.split("\n")
    names = [line.split()[0] for line in names if line.strip()]
    path = HERE.joinpath("results", "compile.json")
    # examples measured before and not now keep their record
    result = json.loads(path.read_text()) if path.exists() else {}
    result["machine"] = platform.node()
    print(f"{'example':24s} {'cold s':>8s} {'warm s':>8s} {'cold - warm':>12s}")
    for name in names:
        with tempfile.TemporaryDirectory() as tmp:
            tmp = Path(tmp)
            spec = tmp / "spec.toml"
            spec.write_text(subprocess.run([SWEEP, "examples", name], check=True,
                                           capture_output=True, text=True).stdout)
            cold, warm = [], []
            for r in range(args.rounds):
                cache = tmp / f"cache{r}"
                cold.append(timed_run(spec, cache, tmp / "a.nc"))
                warm.append(timed_run(spec, cache, tmp / "b.nc"))
        c, w = statistics.median(cold), statistics.median(warm)
        result[name] = {"cold_s": c, "warm_s": w, "difference_s": c - w,
                        "rounds": args.rounds}
        print(f"{name:24s} {c:8.1f} {w:8.1f} {c - w:12.1f}", flush=True)
    path.write_text(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
