"""Forced integration of the paper model on the rotor stop against heyoka's Taylor
integrator (issue 40): steady states per CPU-second at rtol 1e-12 (and a looser one),
DOPRI5 and DOP853 of the core against heyoka, in interleaved rounds, each at its error
against the closed form.

- the core: ``integrator = "dopri5"`` or ``"dop853"`` at rtol, atol = rtol, through the
  kernel as a sweep calls it, its steady state where the section states repeat to
  10 rtol (the paper model's section map is affine: the core jumps to its fixed point
  after two flights);
- heyoka: benchmarks/heyoka_paper.py in the benchmark's own environment
  (benchmarks/.heyoka, made on first use: ``pip install heyoka numpy``; heyoka is not a
  dependency of impact-sweep), tol = rtol, its steady state where the arrival speed repeats
  to 10 rtol; the Taylor integrator is built once per round and the build is not timed.

Each side's CPU time is its own loop over the same designs (the core: this process; heyoka:
the child's process_time around its loop), in rounds A B B A. The error is the largest
relative error of the steady impact speed against the closed form (heyoka's: of the
steady arrival speed, whose closed form is one line); steps and flights are per steady
state. Both sides fly the same flights: heyoka's loop jumps to the affine map's fixed
point after two flights, as the core does.

Run: .venv/bin/python benchmarks/bench_heyoka.py   (writes benchmarks/results/heyoka.json)
"""

from __future__ import annotations

import json
import os
import platform
import subprocess
import sys
import tempfile
import time
import venv
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

from benchmarks.auto_cases import MECH, OUT, points, run  # noqa: E402

ENV = HERE / ".heyoka"
HEYOKA = "heyoka==7.13.2"
N_DESIGNS, ROUNDS, SEED = 200, 5, 40
RTOLS = (1e-14, 1e-12, 1e-10)  # 1e-14: the core at the error heyoka reaches at 1e-12
CORE = ("dopri5", "dop853")


def heyoka_python() -> Path:
    """The Python of the benchmark's own environment, with heyoka installed in it."""
    python = ENV / "bin" / "python"
    if not python.exists():
        venv.create(ENV, with_pip=True)
        subprocess.run([str(python), "-m", "pip", "install", "-q", HEYOKA, "numpy"],
                       check=True)
    return python


def steady_arrival(k, r):
    """The steady arrival speed psi' at the stop in closed form: a flight of the paper model
    returns to the stop as fast as it left it (its energy integral, [RP] P3), so the
    arrival a = R (1 + k + a) + (1 + k) of the Newton law: a = (1 + k)(1 + R)/(1 - R)."""
    return (1.0 + k) * (1.0 + r) / (1.0 - r)


def main() -> None:
    params = points("paper", N_DESIGNS, seed=SEED)
    column = {p.name: i for i, p in enumerate(MECH.parameters)}
    k, xi, r = (params[column[name]] for name in ("k", "xi", "R"))
    arrival = steady_arrival(k, r)
    closed, _ = run(params, "closed_form", tol=1e-12)
    python = heyoka_python()
    results = {}
    with tempfile.TemporaryDirectory() as tmp:
        for rtol in RTOLS:
            job = Path(tmp) / f"job_{rtol:g}.json"
            job.write_text(json.dumps({"designs": np.c_[k, xi, r].tolist(), "tol": rtol,
                                       "repeat": 10 * rtol, "max_impacts": 1000}))

            def heyoka():
                text = subprocess.run([str(python), str(HERE / "heyoka_paper.py"), str(job)],
                                      check=True, capture_output=True, text=True).stdout
                found = json.loads(text)
                error = np.abs(np.array(found["arrival"]) / arrival - 1.0)
                return found["cpu"], error, np.array(found["steps"]), np.array(found["flights"])

            def core(integrator):
                def solve():
                    start = time.process_time()
                    out, status = run(params, integrator, rtol=rtol, atol_per_rtol=1.0)
                    cpu = time.process_time() - start
                    error = np.abs(out[OUT["impact_speed"]] / closed[OUT["impact_speed"]] - 1)
                    return cpu, error, out[OUT["n_steps"]], out[OUT["n_events"]]
                return solve

            sides = {"heyoka": heyoka, **{name: core(name) for name in CORE}}
            for solve in sides.values():
                solve()  # warm-up: compile, build
            cpu = {name: [] for name in sides}
            last = {}
            for i in range(ROUNDS):
                order = list(sides) if i % 2 == 0 else list(sides)[::-1]
                for name in order:
                    last[name] = sides[name]()
                    cpu[name].append(last[name][0])
            entry = {}
            for name in sides:
                _, error, steps, flights = last[name]
                median = float(np.median(cpu[name]))
                entry[name] = {
                    "cpu_s_median": round(median, 4),
                    "steady_states_per_cpu_s": round(N_DESIGNS / median, 1),
                    "max_relative_error": float(np.max(error)),
                    "steps_per_steady_state": round(float(np.mean(steps)), 1),
                    "flights_per_steady_state": round(float(np.mean(flights)), 2),
                    "cpu_us_per_step": round(1e6 * median / float(np.sum(steps)), 3)}
            for name in CORE:
                entry[name]["over_heyoka"] = round(entry[name]["cpu_s_median"]
                                                   / entry["heyoka"]["cpu_s_median"], 2)
            results[f"{rtol:g}"] = entry
            for name, e in entry.items():
                print(f"rtol {rtol:g} {name:7s} {e['steady_states_per_cpu_s']:9.1f} steady "
                      f"states per CPU-s, error {e['max_relative_error']:.1e}, "
                      f"{e['steps_per_steady_state']:7.1f} steps and "
                      f"{e['flights_per_steady_state']:5.2f} flights per steady state"
                      + (f", {e['over_heyoka']:.2f}x heyoka's CPU" if name in CORE else ""))
    record = {"what": __doc__.strip().splitlines()[0], "designs": N_DESIGNS,
              "rounds": ROUNDS, "heyoka": HEYOKA,
              "machine": platform.processor() or platform.machine(), "cpus": os.cpu_count(),
              "results": results}
    (HERE / "results" / "heyoka.json").write_text(json.dumps(record, indent=2) + "\n")


if __name__ == "__main__":
    main()
