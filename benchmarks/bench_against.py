"""A built-in example against the code before a change: warm runs of this tree and of
another checkout's tree (DIR, e.g. a `git worktree` of the commit before), interleaved
(A B B A A B ...), each a whole `sweep run` process, timed on its CPU time (user + system of
the child), after one run of each that fills its own numba cache. Then the two atlases of
the last round, variable by variable: identical, or how many values differ; and the
integration steps each took (n_steps summed).

Run: .venv/bin/python benchmarks/bench_against.py EXAMPLE --against DIR [--rounds N]
     [--set KEY=VALUE ...] [--label WHAT]
     (writes benchmarks/results/against_EXAMPLE[_WHAT][_SETTINGS].json; EXAMPLE is a
     built-in example's name or a spec file, e.g. benchmarks/specs/*.toml)

``--set`` changes the example's spec (``method.starts=1``), for the same comparison at
another setting.
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
from pathlib import Path

import numpy as np
import xarray as xr

HERE = Path(__file__).resolve().parent
SWEEP = str(Path(sys.executable).with_name("sweep"))


def cpu_run(spec: Path, out: Path, tree: str, cache: Path) -> float:
    """CPU seconds of one ``sweep run`` of ``spec`` by the package in ``tree``."""
    env = dict(os.environ, PYTHONPATH=tree, NUMBA_CACHE_DIR=str(cache))
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run([SWEEP, "run", str(spec), "-o", str(out), "-q", "--force"], env=env,
                   check=True, capture_output=True, cwd=tree)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def with_settings(text: str, settings: list[str]) -> str:
    """The spec's text with ``section.key=value`` lines replaced (or added to section)."""
    for item in settings:
        key, value = item.split("=", 1)
        section, name = key.rsplit(".", 1)
        pattern = re.compile(rf"^{re.escape(name)}\s*=.*$", re.MULTILINE)
        head, found, rest = text.partition(f"[{section}]\n")
        if not found:
            text += f"\n[{section}]\n{name} = {value}\n"
        elif pattern.search(rest.split("\n[", 1)[0]):
            body, sep, tail = rest.partition("\n[")
            text = head + found + pattern.sub(f"{name} = {value}", body, 1) + sep + tail
        else:
            text = head + found + f"{name} = {value}\n" + rest
    return text


def differences(a: Path, b: Path) -> dict[str, str]:
    """Each variable of two atlases: "identical", or how many values differ."""
    out = {}
    with xr.open_dataset(a) as x, xr.open_dataset(b) as y:
        for name in sorted(set(x.data_vars) | set(y.data_vars)):
            if name not in x or name not in y:
                out[name] = "only in one"
                continue
            u, v = np.asarray(x[name].values), np.asarray(y[name].values)
            same = (u == v) | (np.isnan(u) & np.isnan(v)) if u.dtype.kind == "f" else u == v
            out[name] = "identical" if same.all() else f"{int((~same).sum())} differ"
    return out


def step_count(atlas: Path) -> float:
    """The integration steps an atlas took in all (its n_steps), 0 where it has none."""
    with xr.open_dataset(atlas) as x:
        return float(np.nansum(x["n_steps"].values)) if "n_steps" in x else 0.0


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("example")
    parser.add_argument("--against", required=True, metavar="DIR")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    parser.add_argument("--label", default="", help="what changed: names the result file")
    args = parser.parse_args()
    here, there = str(HERE.parent), str(Path(args.against).resolve())
    given = Path(args.example)
    text = (given.read_text() if given.suffix == ".toml" and given.is_file() else
            subprocess.run([SWEEP, "examples", args.example], check=True,
                           capture_output=True, text=True).stdout)
    args.example = given.stem
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        spec = tmp / "spec.toml"
        spec.write_text(with_settings(text, args.set))
        caches = {here: tmp / "cache_here", there: tmp / "cache_there"}
        outs = {here: tmp / "here.nc", there: tmp / "there.nc"}
        for tree in (here, there):  # fill each tree's cache
            cpu_run(spec, outs[tree], tree, caches[tree])
        times = {here: [], there: []}
        for r in range(args.rounds):
            for tree in (here, there) if r % 2 == 0 else (there, here):
                times[tree].append(cpu_run(spec, outs[tree], tree, caches[tree]))
        diff = differences(outs[here], outs[there])
        steps = {tree: step_count(outs[tree]) for tree in (here, there)}
    this, other = statistics.median(times[here]), statistics.median(times[there])
    record = {"example": args.example, "label": args.label, "set": args.set, "against": there,
              "rounds": args.rounds, "machine": platform.node(),
              "this_cpu_s": times[here], "other_cpu_s": times[there],
              "median_this_cpu_s": this, "median_other_cpu_s": other,
              "ratio_other_over_this": other / this, "steps_this": steps[here],
              "steps_other": steps[there], "variables": diff}
    if steps[here]:
        record["steps_other_over_this"] = steps[there] / steps[here]
    print(f"{args.example} {' '.join(args.set)}: this {this:.1f} CPU s, other {other:.1f} "
          f"CPU s (median of {args.rounds}): {other / this:.2f}x faster")
    for name, verdict in diff.items():
        print(f"  {name}: {verdict}")
    suffix = re.sub(r"[^\w.]+", "-", "_".join([args.label] + args.set)).strip("-_")
    name = f"against_{args.example}" + (f"_{suffix}" if suffix else "") + ".json"
    (HERE / "results" / name).write_text(json.dumps(record, indent=2) + "\n")


if __name__ == "__main__":
    main()
