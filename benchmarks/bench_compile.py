"""First contact: the run of each built-in example with an empty numba cache (cold: numba
compiles what the sweep needs) against the same run with the cache it left (warm), as whole
processes (`sweep run EXAMPLE -q`), in turn (cold, warm, cold, warm ...). The difference is
what a new user waits for once (wall and CPU seconds); the target is at most 20 s per
example.

Run: .venv/bin/python benchmarks/bench_compile.py [--rounds N] [EXAMPLE ...]
     (writes benchmarks/results/compile.json)
     .venv/bin/python benchmarks/bench_compile.py --against DIR [--rounds N] [--label LABEL]
     [EXAMPLE ...]
     (a redesign's first run against another checkout's tree DIR, e.g. a `git worktree` of
     the commit before: cold runs of both, each followed by a warm run on the cache it
     left, interleaved, on the child processes' CPU time;
     writes benchmarks/results/compile_against[_LABEL].json, with --label LABEL)
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
SWEEP = str(Path(sys.executable).with_name("sweep"))


def timed_run(spec: Path, cache: Path, out: Path, tree: str | None = None) -> tuple:
    """(wall seconds, CPU seconds: user and system) of one ``sweep run``; with ``tree`` the
    package imported from that checkout instead of this one."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache))
    if tree:
        env["PYTHONPATH"] = tree
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    started = time.perf_counter()
    subprocess.run([SWEEP, "run", str(spec), "-o", str(out), "-q", "--force"], env=env,
                   check=True, capture_output=True, cwd=tree)
    wall = time.perf_counter() - started
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def provenance() -> dict:
    """What a record needs beside its numbers: the machine, the commit, the day, the load."""
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=HERE, text=True,
                            capture_output=True).stdout.strip()
    dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=HERE,
                           text=True, capture_output=True).stdout.strip()
    return {"machine": platform.node(), "cores": os.cpu_count(),
            "commit": commit + ("+changes" if dirty else ""),
            "date": time.strftime("%Y-%m-%d %H:%M"), "load_before": os.getloadavg()[0]}


def example_spec(name: str, folder: Path) -> Path:
    """The built-in example's spec, written into ``folder``."""
    spec = folder / "spec.toml"
    spec.write_text(subprocess.run([SWEEP, "examples", name], check=True,
                                   capture_output=True, text=True).stdout)
    return spec


def against(names: list[str], tree: str, rounds: int, label: str = "") -> None:
    """Cold first runs of this tree and of ``tree``, interleaved, in CPU seconds, each
    followed by a warm run on the cache it left (the redesign's steady cost)."""
    path = HERE.joinpath("results", "compile_against" + (f"_{label}" if label else "")
                         + ".json")
    result = {**provenance(), "against": tree, "rounds": rounds, "examples": {}}
    here = str(HERE.parent)
    print(f"{'example':26s} {'cold: this':>10s} {'other':>7s} {'ratio':>6s} "
          f"{'warm: this':>10s} {'other':>7s} {'ratio':>6s}  (CPU s)")
    for name in names:
        if not knows(tree, name):
            result.setdefault("not_in_other", []).append(name)
            print(f"{name:26s} (not an example of {tree})", flush=True)
            continue
        with tempfile.TemporaryDirectory() as tmp:
            tmp = Path(tmp)
            spec = example_spec(name, tmp)
            times = {(which, kind): [] for which in (here, tree) for kind in ("cold", "warm")}
            for r in range(rounds):
                for i, which in enumerate((here, tree) if r % 2 == 0 else (tree, here)):
                    for kind in ("cold", "warm"):
                        times[which, kind].append(timed_run(
                            spec, tmp / f"cache{r}{i}", tmp / "a.nc", which)[1])
        m = {key: statistics.median(values) for key, values in times.items()}
        this, other = m[here, "cold"], m[tree, "cold"]
        warm_this, warm_other = m[here, "warm"], m[tree, "warm"]
        result["examples"][name] = {"this_cpu_s": this, "other_cpu_s": other,
                                    "ratio": this / other, "this_warm_cpu_s": warm_this,
                                    "other_warm_cpu_s": warm_other,
                                    "warm_ratio": warm_this / warm_other,
                                    # what a first run costs over a warm one (issue 60's bar)
                                    "this_cold_minus_warm_cpu_s": this - warm_this,
                                    "other_cold_minus_warm_cpu_s": other - warm_other}
        print(f"{name:26s} {this:10.1f} {other:7.1f} {this / other:6.2f} "
              f"{warm_this:10.1f} {warm_other:7.1f} {warm_this / warm_other:6.2f}", flush=True)
        result["load_after"] = os.getloadavg()[0]
        path.write_text(json.dumps(result, indent=2))  # what is measured so far, kept
    path.write_text(json.dumps(result, indent=2))  # also where no example was measured


def knows(tree: str, name: str) -> bool:
    """Whether the checkout ``tree`` has the built-in example ``name`` (an older tree may
    not: it is left out of the comparison, not a failure after an hour of runs)."""
    return subprocess.run([SWEEP, "examples", name], env=dict(os.environ, PYTHONPATH=tree),
                          cwd=tree, capture_output=True).returncode == 0


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("examples", nargs="*")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--against", metavar="DIR",
                        help="another checkout's tree: compare cold first runs on CPU time")
    parser.add_argument("--label", default="",
                        help="with --against: names the result file (what is compared)")
    args = parser.parse_args()
    names = args.examples or subprocess.run(
        [SWEEP, "examples"], check=True, capture_output=True, text=True).stdout.split("\n")
    names = [line.split()[0] for line in names if line.strip()]
    if args.against:
        return against(names, str(Path(args.against).resolve()), args.rounds, args.label)
    path = HERE.joinpath("results", "compile.json")
    # examples measured before and not now keep their record
    result = json.loads(path.read_text()) if path.exists() else {}
    result.pop("machine", None)  # each example's record says where and when it was made
    print(f"{'example':24s} {'cold s':>8s} {'warm s':>8s} {'cold - warm':>12s} "
          f"{'CPU s: cold - warm':>19s}")
    for name in names:
        measured = provenance()
        with tempfile.TemporaryDirectory() as tmp:
            tmp = Path(tmp)
            spec = example_spec(name, tmp)
            runs = {"cold": [], "warm": [], "cold_cpu": [], "warm_cpu": []}
            for r in range(args.rounds):
                cache = tmp / f"cache{r}"
                for kind, out in (("cold", "a.nc"), ("warm", "b.nc")):
                    wall, cpu = timed_run(spec, cache, tmp / out)
                    runs[kind].append(wall)
                    runs[kind + "_cpu"].append(cpu)
        c, w = statistics.median(runs["cold"]), statistics.median(runs["warm"])
        cc, wc = statistics.median(runs["cold_cpu"]), statistics.median(runs["warm_cpu"])
        # on CPU time too: a compile is one thread's work, and a loaded machine's wall
        # time is not the run's
        result[name] = {"cold_s": c, "warm_s": w, "difference_s": c - w,
                        "cold_cpu_s": cc, "warm_cpu_s": wc, "difference_cpu_s": cc - wc,
                        "rounds": args.rounds, **measured,
                        "load_after": os.getloadavg()[0]}
        print(f"{name:24s} {c:8.1f} {w:8.1f} {c - w:12.1f} {cc - wc:19.1f}", flush=True)
    path.write_text(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
