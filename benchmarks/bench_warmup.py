"""What the test suite's warm-up costs from an empty compile cache (tests/warmup.py: the
whole suite's, or the fast loop's with --fast), in this tree and in another checkout's tree,
interleaved, each in a fresh cache: wall and CPU seconds (the children's), and each job's CPU
seconds as the warm-up recorded them. Tells what a change to how the warm-up compiles
(which jobs share a process, what a process compiles once) saves, on the same machine in the
same hour.

With ``--then PYTEST-ARGS``, each warm-up is followed by those tests in the same tree and
cache (on every core, a module per worker, as ``./tasks test`` runs them): what the tests
still compile themselves, and so what moving a compile into the warm-up saves in all.

Run: .venv/bin/python benchmarks/bench_warmup.py --against DIR [--fast] [--rounds N]
     [--label L] [--then PYTEST-ARGS ...]
     (writes benchmarks/results/warmup_against[_L].json)
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

from benchmarks.bench_compile import provenance  # noqa: E402


def cold_warmup(tree: str, cache: Path, fast: bool) -> dict:
    """One warm-up of ``tree`` into the empty folder ``cache``."""
    env = dict(os.environ, PYTHONPATH=tree, NUMBA_CACHE_DIR=str(cache))
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    started = time.perf_counter()
    said = subprocess.run([sys.executable, "-m", "tests.warmup"] + ([] if fast else ["--slow"]),
                          env=env, cwd=tree, check=True, capture_output=True, text=True)
    wall = time.perf_counter() - started
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    jobs = {}
    for marker in cache.glob("warmup-*"):
        for line in marker.read_text().splitlines():
            name, seconds = line.rsplit("\t", 1)
            jobs[name] = float(seconds)
    return {"wall_s": wall,
            "cpu_s": (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime),
            "said": said.stdout.strip(), "jobs_cpu_s": jobs}


def tests_after(tree: str, cache: Path, pytest_args: list[str]) -> dict:
    """The tests ``pytest_args`` of ``tree`` in the cache its warm-up filled."""
    env = dict(os.environ, PYTHONPATH=tree, NUMBA_CACHE_DIR=str(cache))
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    started = time.perf_counter()
    subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-n",
                    str(os.cpu_count() or 1), "--dist", "loadscope", "--no-loadscope-reorder",
                    *pytest_args],
                   env=env, cwd=tree, check=True, capture_output=True, text=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return {"wall_s": time.perf_counter() - started,
            "cpu_s": (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)}


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--against", metavar="DIR", required=True,
                        help="another checkout's tree (a git worktree of an older commit)")
    parser.add_argument("--fast", action="store_true", help="the fast loop's warm-up")
    parser.add_argument("--rounds", type=int, default=1)
    parser.add_argument("--label", default="")
    parser.add_argument("--then", nargs=argparse.REMAINDER, default=[],
                        help="pytest's arguments: tests run after each warm-up")
    args = parser.parse_args()
    here, other = str(HERE.parent), str(Path(args.against).resolve())
    path = HERE / "results" / ("warmup_against" + (f"_{args.label}" if args.label else "")
                               + ".json")
    result = {**provenance(), "against": other, "fast": args.fast, "rounds": args.rounds,
              "then": args.then, "runs": {"this": [], "other": []}}
    for r in range(args.rounds):
        for which in (("this", here), ("other", other))[:: 1 if r % 2 == 0 else -1]:
            with tempfile.TemporaryDirectory() as tmp:
                run = cold_warmup(which[1], Path(tmp), args.fast)
                if args.then:
                    run["tests"] = tests_after(which[1], Path(tmp), args.then)
                    run["total_wall_s"] = run["wall_s"] + run["tests"]["wall_s"]
                    run["total_cpu_s"] = run["cpu_s"] + run["tests"]["cpu_s"]
            result["runs"][which[0]].append(run)
            print(f"round {r}: {which[0]:5s} {run['wall_s']:6.0f} s wall "
                  f"{run['cpu_s']:6.0f} CPU s  ({run['said']})"
                  + (f"; then the tests {run['tests']['wall_s']:.0f} s wall "
                     f"{run['tests']['cpu_s']:.0f} CPU s" if args.then else ""), flush=True)
    for key in ("wall_s", "cpu_s") + (("total_wall_s", "total_cpu_s") if args.then else ()):
        this = statistics.median(run[key] for run in result["runs"]["this"])
        before = statistics.median(run[key] for run in result["runs"]["other"])
        result[f"median_this_{key}"], result[f"median_other_{key}"] = this, before
        result[f"ratio_this_over_other_{key}"] = this / before
    result["load_after"] = os.getloadavg()[0]
    path.write_text(json.dumps(result, indent=2))
    print(f"this/other: wall {result['ratio_this_over_other_wall_s']:.2f}, "
          f"CPU {result['ratio_this_over_other_cpu_s']:.2f}"
          + (f"; with the tests: wall {result['ratio_this_over_other_total_wall_s']:.2f}, "
             f"CPU {result['ratio_this_over_other_total_cpu_s']:.2f}" if args.then else ""))


if __name__ == "__main__":
    main()
