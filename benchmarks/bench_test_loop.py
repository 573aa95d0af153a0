"""How long a developer and CI wait: the README's test commands as whole processes on a
fresh clone of HEAD (its own .venv, so its own compile cache): the fast loop cold (install
and compile included) and then warm, and the whole suite cold (a second fresh clone: what CI
runs). Wall and CPU seconds (the children's), pytest's own test time, the warm-up's line,
and the load average before and after each, since a shared machine stretches wall times.

Run: .venv/bin/python benchmarks/bench_test_loop.py [--skip-full]
     (writes benchmarks/results/test_loop.json)
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import re
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent


def load() -> float:
    return os.getloadavg()[0]


def timed(command: list[str], cwd: Path) -> dict:
    """One command as a whole process: wall and CPU seconds, what pytest and the warm-up
    said of their own time, and the load average around it."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    load_before = load()
    started = time.perf_counter()
    done = subprocess.run(command, cwd=cwd, capture_output=True, text=True)
    wall = time.perf_counter() - started
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    text = done.stdout + done.stderr
    tests = re.search(r"(\d+) passed.* in ([\d.]+)s", text)
    warmup = re.search(r"warm-up: (.*)", text)
    if done.returncode != 0:
        sys.exit(f"{' '.join(command)} failed in {cwd}:\n{text[-3000:]}")
    return {"wall_s": wall,
            "cpu_s": (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime),
            "tests_passed": int(tests.group(1)) if tests else None,
            "pytest_s": float(tests.group(2)) if tests else None,
            "warmup": warmup.group(1).strip() if warmup else None,
            "load_before": load_before, "load_after": load()}


def fresh_clone(folder: Path) -> Path:
    target = folder / "clone"
    subprocess.run(["git", "clone", "-q", str(ROOT), str(target)], check=True)
    return target


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--skip-full", action="store_true",
                        help="measure the fast loop only")
    args = parser.parse_args()
    head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT,
                          capture_output=True, text=True).stdout.strip()
    results = {"machine": platform.node(), "cores": os.cpu_count(), "commit": head,
               "measured": time.strftime("%Y-%m-%d")}
    with tempfile.TemporaryDirectory() as tmp:
        clone = fresh_clone(Path(tmp))
        results["fast_cold"] = timed(["./tasks", "test", "--fast"], clone)
        results["fast_warm"] = timed(["./tasks", "test", "--fast"], clone)
        print(json.dumps(results, indent=1), flush=True)
    if not args.skip_full:
        with tempfile.TemporaryDirectory() as tmp:
            results["full_cold"] = timed(["./tasks", "test"], fresh_clone(Path(tmp)))
    path = HERE / "results" / "test_loop.json"
    path.write_text(json.dumps(results, indent=1) + "\n")
    print(json.dumps(results, indent=1))


if __name__ == "__main__":
    main()
