"""Boundaries by bisection vs a uniformly refined grid, to the same accuracy.

Run: .venv/bin/python benchmarks/bench_boundaries.py   (writes benchmarks/results/boundaries.json)

For a coarse n x n grid, a uniform grid refined F times along each axis locates every
boundary to half its spacing, at F^2 times the points. `sweep boundaries` reaches (at least)
the same accuracy by bisecting only the edges where the flag changes: its cost grows with
the boundaries' length (edges x rounds), not the grid's volume. Both run the same kernel
through the same block evaluation (no file I/O on either side), in one process, and the
ratios are reported: kernel evaluations and wall time. The count a uniform grid would need
for the default tolerance 1e-8 is computed, not run.
"""

from __future__ import annotations

import json
import math
import os
import platform
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from sweep import refinement as boundaries, engine, runner, spec  # noqa: E402

CASES = {
    "crank_rocker (types a, b)": (
        'mechanism = "crank_rocker"\n[grid]\nR = {{start = 0.05, stop = 0.40, num = {n}}}\n'
        'largest_link = {{start = 1.5, stop = 30.0, num = {n}}}\ntype = ["a", "b"]\n',
        "status", ("R", "largest_link")),
    "rotary_pendulum (paper, closed form)": (
        'mechanism = "rotary_pendulum"\n[grid]\nk = {{start = 1.0, stop = 2.5, num = {n}}}\n'
        'R = {{start = 0.0, stop = 0.35, num = {n}}}\n[fixed]\nmodel = "paper"\n',
        "regime", ("k", "R")),
}
COARSE = 16
REFINE = 64  # uniform grid: (COARSE - 1) * REFINE + 1 points per axis


def uniform(text: str, workers: int) -> tuple[float, int]:
    """Wall time and points of the refined grid, evaluated in blocks as a sweep is."""
    sweep = spec.parse(text.format(n=(COARSE - 1) * REFINE + 1))
    started = time.perf_counter()
    step = 1_000_000
    for a in range(0, sweep.size, step):
        points = np.arange(a, min(sweep.size, a + step))
        boundaries.evaluate(sweep, engine.point_parameters(sweep, points), workers)
    return time.perf_counter() - started, sweep.size


def bisection(text: str, var: str, tol: float, workers: int, folder: Path):
    """Wall time of the coarse atlas plus its boundaries; evaluations of both."""
    sweep = spec.parse(text.format(n=COARSE))
    path = folder / "coarse.nc"
    started = time.perf_counter()
    runner.run_sweep(sweep, path, progress=False, force=True, history="bench")
    import xarray as xr

    with xr.open_dataset(path) as ds:
        result = boundaries.refine(ds, var, tol, workers=workers)
    return time.perf_counter() - started, sweep.size + result.attrs["kernel_evaluations"], \
        result


def main() -> None:
    workers = os.cpu_count() or 1
    rows = {}
    with tempfile.TemporaryDirectory() as tmp:
        for name, (text, var, axes) in CASES.items():
            sweep = spec.parse(text.format(n=COARSE))
            spans = {a.name: float(np.ptp(a.values)) for a in sweep.axes if a.name in axes}
            largest = {a.name: float(np.max(np.abs(a.values))) for a in sweep.axes
                       if a.name in axes}
            # the uniform grid's accuracy (half its spacing) in the measure of --tol
            half = {a: 0.5 * spans[a] / ((COARSE - 1) * REFINE) / max(1.0, largest[a])
                    for a in axes}
            tol = min(half.values())
            bisection(text, var, tol, workers, Path(tmp))  # warm-up: compile
            t_bis, n_bis, result = bisection(text, var, tol, workers, Path(tmp))
            t_uni, n_uni = uniform(text, workers)
            at_default = math.prod(spans[a] / (2e-8 * max(1.0, largest[a])) for a in axes)
            rows[name] = {
                "coarse_grid": f"{COARSE} x {COARSE}", "refined_grid":
                    f"{(COARSE - 1) * REFINE + 1} x {(COARSE - 1) * REFINE + 1}",
                "tolerance": tol, "crossings": int(result.sizes["crossing"]),
                "rounds": int(result.attrs["rounds"]),
                "evaluations_bisection": int(n_bis), "evaluations_uniform": int(n_uni),
                "evaluation_ratio": n_uni / n_bis,
                "seconds_bisection": t_bis, "seconds_uniform": t_uni,
                "wall_ratio": t_uni / t_bis,
                "uniform_points_for_tol_1e-8": at_default,
            }
            print(f"{name}: tol {tol:.2e}: bisection {n_bis:,} evaluations in {t_bis:.2f} s, "
                  f"uniform {n_uni:,} in {t_uni:.2f} s: {n_uni / n_bis:.0f}x fewer "
                  f"evaluations, {t_uni / t_bis:.1f}x less wall time "
                  f"(uniform at 1e-8 would take {at_default:.1e} points)")
    out = Path(__file__).resolve().parent / "results" / "boundaries.json"
    out.write_text(json.dumps({"machine": platform.machine(), "cores": workers,
                               "cases": rows}, indent=2))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
