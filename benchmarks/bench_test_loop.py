"""How long a developer and CI wait: the README's test commands as whole processes on a
fresh clone of HEAD (its own .venv, so its own compile cache): the fast loop cold (install
and compile included) and then warm, and the whole suite cold (a second fresh clone: what CI
runs). Wall and CPU seconds (the children's), pytest's own test time, the warm-up's line,
and the load average before and after each, since a shared machine stretches wall times.

Run: .venv/bin/python benchmarks/bench_test_loop.py [--skip-full]
     .venv/bin/python benchmarks/bench_test_loop.py --skip-fast
     (writes benchmarks/results/test_loop.json; with --skip-full the whole suite's last
     record stays, with --skip-fast the fast loop's, each with the commit it measured)
     .venv/bin/python benchmarks/bench_test_loop.py --against DIR [--shared-cache] [--label L]
     [--rounds N] [TEST ...]
     (the same tests, warm, in this tree and in another checkout's tree DIR (a `git
     worktree` of an older commit, its kernels in a cache of their own), interleaved, on
     the children's CPU time: tells a slower machine from a slower code; writes
     results/test_loop_against[_L].json)
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import re
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent


def load() -> float:
    return os.getloadavg()[0]


def timed(command: list[str], cwd: Path, env: dict | None = None) -> dict:
    """One command as a whole process: wall and CPU seconds, what pytest and the warm-up
    said of their own time, and the load average around it."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    load_before = load()
    started = time.perf_counter()
    done = subprocess.run(command, cwd=cwd, capture_output=True, text=True, env=env)
    wall = time.perf_counter() - started
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    text = done.stdout + done.stderr
    tests = re.search(r"(\d+) passed.* in ([\d.]+)s", text)
    warmup = re.search(r"warm-up: (.*)", text)
    compiled = re.search(r"cached kernels compiled during the tests: (\d+) \(([^)]+)\)", text)
    if done.returncode != 0:
        sys.exit(f"{' '.join(command)} failed in {cwd}:\n{text[-3000:]}")
    return {"wall_s": wall,
            "cpu_s": (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime),
            "tests_passed": int(tests.group(1)) if tests else None,
            "pytest_s": float(tests.group(2)) if tests else None,
            "warmup": warmup.group(1).strip() if warmup else None,
            # what the warm-up left to the tests: each kernel with the test that compiled it
            "compiled_during_tests": (Path(compiled.group(2)).read_text().splitlines()
                                      if compiled and Path(compiled.group(2)).is_file()
                                      else []),
            "load_before": load_before, "load_after": load(),
            # pytest's --durations report: where the tests' own time goes
            "slowest": [f"{m.group(1)} s {m.group(2)} {m.group(3)}" for m in re.finditer(
                r"^\s*([\d.]+)s (call|setup|teardown)\s+(\S+)", text, re.MULTILINE)]}


#: the slowest tests, reported by pytest with each run
DURATIONS = "--durations=25"


def fresh_clone(folder: Path) -> Path:
    target = folder / "clone"
    subprocess.run(["git", "clone", "-q", str(ROOT), str(target)], check=True)
    return target


#: tests that start many `sweep` processes, cheap to compile: the default of --against
AGAINST_TESTS = ("tests/test_hostile_inputs.py", "tests/test_spec_cli.py",
                 "tests/test_docs.py::test_the_tutorial_runs_as_written")


def against(tree: Path, tests: list[str], rounds: int, label: str,
            shared_cache: bool = False) -> None:
    """Warm runs of ``tests`` here and in ``tree``, interleaved after one run each that
    fills the caches; medians of the children's CPU seconds. With ``shared_cache`` (the
    two trees' kernels are the same code, only the tests differ) ``tree`` runs on this
    tree's compile cache, whose entries are keyed by content (kernels/cache.py), and no
    run fills it first: the warm-up (``python -m tests.warmup --slow``) has."""
    # the default modules' fast tests; tests named on the command line run whatever marks them
    marks = ["-m", "not slow"] if tuple(tests) == AGAINST_TESTS else []
    command = [sys.executable, "-m", "pytest", "-q", "--no-warmup", "-p", "no:cacheprovider",
               *marks, *tests]
    with tempfile.TemporaryDirectory() as cache:
        trees = {"this": (ROOT, None),
                 "other": (tree, dict(os.environ, PYTHONPATH=str(tree),
                                      **({} if shared_cache else {"NUMBA_CACHE_DIR": cache})))}
        for cwd, env in trees.values() if not shared_cache else ():
            timed(command, cwd, env)
        runs = {name: [] for name in trees}
        for _ in range(rounds):
            for name, (cwd, env) in trees.items():
                runs[name].append(timed(command, cwd, env))
                print(name, f"{runs[name][-1]['cpu_s']:.1f} CPU s", flush=True)
    this, other = (statistics.median(r["cpu_s"] for r in runs[n]) for n in ("this", "other"))
    results = {"machine": platform.node(), "cores": os.cpu_count(),
               "measured": time.strftime("%Y-%m-%d"), "against": str(tree),
               "tests": tests, "rounds": rounds, "shared_cache": shared_cache,
               "median_this_cpu_s": this,
               "median_other_cpu_s": other, "ratio_other_over_this": other / this,
               "runs": runs}
    path = HERE / "results" / ("test_loop_against" + (f"_{label}" if label else "") + ".json")
    path.write_text(json.dumps(results, indent=1) + "\n")
    print(f"this {this:.1f} CPU s, other {other:.1f} CPU s, other/this {other / this:.2f}")


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--skip-full", action="store_true",
                        help="measure the fast loop only")
    parser.add_argument("--skip-fast", action="store_true",
                        help="measure the whole suite only")
    parser.add_argument("--against", type=Path, help="another checkout's tree")
    parser.add_argument("--shared-cache", action="store_true",
                        help="with --against: the same kernels, this tree's compile cache")
    parser.add_argument("--label", default="")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("tests", nargs="*", default=list(AGAINST_TESTS))
    args = parser.parse_args()
    if args.against:
        against(args.against.resolve(), args.tests, args.rounds, args.label,
                args.shared_cache)
        return
    head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT,
                          capture_output=True, text=True).stdout.strip()
    results = {"machine": platform.node(), "cores": os.cpu_count(), "commit": head,
               "measured": time.strftime("%Y-%m-%d")}
    path = HERE / "results" / "test_loop.json"
    earlier = json.loads(path.read_text()) if path.exists() else {}
    if args.skip_fast:
        # the fast loop's last measurement is kept, with the commit it measured
        for name in ("fast_cold", "fast_warm"):
            if name in earlier:
                results[name] = {"commit": earlier["commit"], **earlier[name]}
    else:
        with tempfile.TemporaryDirectory() as tmp:
            clone = fresh_clone(Path(tmp))
            for name in ("fast_cold", "fast_warm"):
                results[name] = {"commit": head,
                                 **timed(["./tasks", "test", "--fast", DURATIONS], clone)}
            print(json.dumps(results, indent=1), flush=True)
    if not args.skip_full:
        with tempfile.TemporaryDirectory() as tmp:
            results["full_cold"] = {"commit": head, **timed(["./tasks", "test", DURATIONS],
                                                            fresh_clone(Path(tmp)))}
    elif "full_cold" in earlier:
        # the whole suite's last measurement is kept, with the commit it measured
        results["full_cold"] = {"commit": earlier["commit"], **earlier["full_cold"]}
    path.write_text(json.dumps(results, indent=1) + "\n")
    print(json.dumps(results, indent=1))


if __name__ == "__main__":
    main()
