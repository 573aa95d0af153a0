"""Large atlases end to end: the wall time of a whole `sweep run` (in this process, after
a run of the same spec with 2 points per axis has filled the numba cache), the part of it
spent computing blocks, and the share outside the kernels (spec, cache load, block store,
netCDF write, summary; the imports are paid before, by the warm-up).

Run: .venv/bin/python benchmarks/bench_atlas.py [SPEC ...]
     (default: the 10^6-point rotor-model sweep and the 10^4-point blade sweep in
     benchmarks/specs/; rotary_pendulum_blade_1e5.toml and _1e6.toml are the 10^5- and
     10^6-point ones,
     impact_machine_1e4.toml the machine's; the results of the specs run replace theirs
     in benchmarks/results/atlas.json)
"""

from __future__ import annotations

import json
import os
import platform
import re
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

DEFAULT = ["rotary_pendulum_rotor_1e6.toml", "rotary_pendulum_blade_1e4.toml"]


def timed_run(spec: Path, out: Path) -> dict:
    from sweep import cli, engine, runner

    spans = {"block_s": 0.0, "compute_s": 0.0}

    def timed(function, span):
        def wrapper(*args, **kwargs):
            t = time.perf_counter()
            try:
                return function(*args, **kwargs)
            finally:
                spans[span] += time.perf_counter() - t
        return wrapper

    run_block, compute = engine.run_block, runner._compute_local
    engine.run_block = timed(run_block, "block_s")
    runner._compute_local = timed(compute, "compute_s")
    started, cpu = time.perf_counter(), time.process_time()
    try:
        cli.main(["run", str(spec), "-o", str(out), "--force", "-q"])
    except SystemExit as done:  # the CLI ends a run with its exit code
        if done.code:
            raise
    finally:
        engine.run_block, runner._compute_local = run_block, compute
    wall, cpu = time.perf_counter() - started, time.process_time() - cpu
    import netCDF4

    with netCDF4.Dataset(out) as nc:
        points = int(nc["status"].size)
        shares = steps_by_status(nc)
    return {"points": points, "wall_s": round(wall, 2), "cpu_s": round(cpu, 2),
            "compute_s": round(spans["compute_s"], 2), "block_s": round(spans["block_s"], 2),
            "outside_kernels": round(1.0 - spans["compute_s"] / wall, 3),
            "points_per_cpu_s": round(points / cpu, 1)} | shares


def steps_by_status(nc) -> dict:
    """Where an atlas's integration steps went: per status, its share of the designs and
    of the steps (n_steps), and its median steps per design; {} without n_steps."""
    import numpy as np

    if "n_steps" not in nc.variables:
        return {}
    status = np.asarray(nc["status"][:]).ravel()
    steps = np.asarray(nc["n_steps"][:], dtype=float).ravel()
    names = dict(zip(np.asarray(nc["status"].flag_values).tolist(),
                     nc["status"].flag_meanings.split()))
    total = steps.sum()
    return {"steps": total, "by_status": {
        names[int(code)]: {"designs": round(float((status == code).mean()), 4),
                           "steps": round(float(steps[status == code].sum() / total), 4),
                           "median_steps": float(np.median(steps[status == code]))}
        for code in np.unique(status)}}


def main() -> None:
    # a spec file, or the name of one in benchmarks/specs/
    specs = [Path(name) if Path(name).exists() else HERE / "specs" / name
             for name in sys.argv[1:] or DEFAULT]
    missing = [str(spec) for spec in specs if not spec.exists()]
    if missing:
        sys.exit(f"bench_atlas: no such spec: {', '.join(missing)} (a file, or a name in "
                 f"{HERE / 'specs'})")
    results = {}
    with tempfile.TemporaryDirectory() as tmp:
        for spec in specs:
            small = Path(tmp) / spec.name
            small.write_text(re.sub(r"num = \d+", "num = 2", spec.read_text()))
            timed_run(small, Path(tmp) / "small.nc")  # compiles, or loads the cache
            r = timed_run(spec, Path(tmp) / "atlas.nc")
            results[spec.name] = r
            print(f"{spec.name}: {r['wall_s']:.1f} s whole run, {r['compute_s']:.1f} s "
                  f"computing blocks ({r['block_s']:.1f} s of block work summed over "
                  f"{os.cpu_count()} threads), {100 * r['outside_kernels']:.1f} % outside",
                  flush=True)
    path = HERE / "results" / "atlas.json"
    kept = json.loads(path.read_text())["results"] if path.exists() else {}
    record = {"what": __doc__.strip().splitlines()[0], "machine": platform.processor()
              or platform.machine(), "cpus": os.cpu_count(), "results": kept | results}
    path.write_text(json.dumps(record, indent=2) + "\n")


if __name__ == "__main__":
    main()
