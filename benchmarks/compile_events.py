"""Where a first run's compile goes, against another checkout: one cold run of an example's
kernel in each tree (a fresh process and numba cache each), with numba's compile events
recorded, and each function's own compile time (the seconds its compile took, less those
of the functions it compiled on the way), in CPU seconds, summed by the function's name.
What one tree compiles and the other does not is listed apart. A single cold run each: for
the first run's ratio, use bench_compile.py --against (interleaved rounds).

Run: .venv/bin/python benchmarks/compile_events.py --against DIR [--label LABEL] EXAMPLE
     (writes benchmarks/results/compile_events_<EXAMPLE>[_LABEL].json)
"""

from __future__ import annotations

import argparse
import collections
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent


def record(example: str, out: str) -> None:
    """In this process (its tree on sys.path): the example's kernel on its sample, cold,
    each function's own compile CPU seconds into ``out`` (JSON)."""
    from numba.core import event

    stack, own = [], collections.defaultdict(float)

    class Compiles(event.Listener):
        def on_start(self, e):
            stack.append([e.data["dispatcher"].py_func.__name__, time.process_time(), 0.0])

        def on_end(self, e):
            name, started, inner = stack.pop()
            took = time.process_time() - started
            own[name] += took - inner
            if stack:
                stack[-1][2] += took

    event.register("numba:compile", Compiles())
    from sweep import engine, spec

    path = Path.cwd() / "sweep" / "example_specs" / f"{example}.toml"
    sw = spec.parse(path.read_text(), str(path))
    sw.kernel(engine.sample_parameters(sw), sw.method_record)
    Path(out).write_text(json.dumps(own))


def cold_run(tree: str, example: str) -> dict:
    """Each function's own compile seconds of one cold run in ``tree``."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "events.json"
        env = dict(os.environ, PYTHONPATH=tree, NUMBA_CACHE_DIR=str(Path(tmp) / "cache"))
        subprocess.run([sys.executable, __file__, example, "--child", str(out)], env=env,
                       cwd=tree, check=True)
        return json.loads(out.read_text())


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("example")
    parser.add_argument("--against", metavar="DIR")
    parser.add_argument("--label", default="")
    parser.add_argument("--child", metavar="OUT", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        return record(args.example, args.child)
    if not args.against:
        parser.error("--against DIR is required")
    this = cold_run(str(HERE.parent), args.example)
    other = cold_run(str(Path(args.against).resolve()), args.example)
    result = {
        "machine": platform.node(), "against": args.against, "example": args.example,
        "this_compile_cpu_s": sum(this.values()), "other_compile_cpu_s": sum(other.values()),
        "only_this": {k: v for k, v in sorted(this.items()) if k not in other},
        "only_other": {k: v for k, v in sorted(other.items()) if k not in this},
        "both": {k: [this[k], other[k]] for k in sorted(this, key=lambda k: other.get(k, 0)
                                                     - this[k]) if k in other}}
    result["only_this_cpu_s"] = sum(result["only_this"].values())
    result["only_other_cpu_s"] = sum(result["only_other"].values())
    name = f"compile_events_{args.example}" + (f"_{args.label}" if args.label else "")
    HERE.joinpath("results", name + ".json").write_text(json.dumps(result, indent=2))
    print(json.dumps({k: v for k, v in result.items() if not isinstance(v, dict)}, indent=1))


if __name__ == "__main__":
    main()
