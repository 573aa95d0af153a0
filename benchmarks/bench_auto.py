"""integrator = "auto" against the best single method, in wall time (the tests count
right-hand sides instead): for each model and requested tolerance, the best single method is
the fastest of closed form, DOPRI5 at the loosest rtol and RK4 at the largest step meeting
the tolerance at every design of the sweep, found in hindsight. Best of 3 runs each.

Run: .venv/bin/python benchmarks/bench_auto.py   (writes benchmarks/results/auto.json);
with --dop853 only auto by DOP853 against auto by DOPRI5 at tight tol (auto_dop853.json).
"""

from __future__ import annotations

import json
import math
import platform
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from benchmarks.auto_cases import OUT, cost, errors, one_solve, points, run  # noqa: E402
from benchmarks.timing import best_time, paired_cpu_times  # noqa: E402
from kernels.pendulum import accuracy  # noqa: E402


def candidates(tol):
    yield "closed_form", dict(integrator="closed_form")
    for atol_per_rtol in (1.0, 1e-2):
        for rtol in tol * np.geomspace(1.0, 1e-3, 13):
            yield (f"dopri5 rtol {rtol:.2g} atol {rtol * atol_per_rtol:.2g}",
                   dict(integrator="dopri5", rtol=rtol, atol_per_rtol=atol_per_rtol))
    for dt in 0.4 / 2.0 ** np.arange(10):
        yield f"rk4 dt {dt:.3g}", dict(integrator="rk4", dt=dt)


def against_one_solve(params, ref, tol):
    """auto against one DOPRI5 solve from rest at auto's finer rtol, the accuracy auto
    delivers: right-hand sides (deterministic) and CPU time (median of 41 interleaved pairs),
    and the worst errors of both against the reference."""
    one = one_solve(tol)
    out, _ = run(params, "auto", tol=tol)
    single, _ = run(params, **one)
    # runs of a few milliseconds each: with few pairs the median is the machine's noise
    t_auto, t_one = paired_cpu_times(lambda: run(params, "auto", tol=tol),
                                     lambda: run(params, **one), repeats=41)
    return {"one_solve": f"dopri5 rtol {one['rtol']:.2g}",
            "auto_over_one_evaluations": cost(out, "dopri5") / cost(single, "dopri5"),
            "auto_over_one_cpu": t_auto / t_one,
            "auto_over_one_events": float(np.sum(out[OUT["n_events"]])
                                          / np.sum(single[OUT["n_events"]])),
            "auto_error": float(np.max(errors(out, ref))),
            "one_error": float(np.max(errors(single, ref)))}


def against_one_solve_in_bulk(params, tol):
    """The same CPU ratio with ten times the designs in one call (median of 11 interleaved
    pairs): whether what auto adds per call (its rounds in Python, a second call into the
    kernel) weighs in the ratio of 60 designs."""
    one = one_solve(tol)
    t_auto, t_one = paired_cpu_times(lambda: run(params, "auto", tol=tol),
                                     lambda: run(params, **one), repeats=11)
    return {"bulk_designs": params.shape[1], "auto_over_one_cpu_bulk": t_auto / t_one}


def auto_by_method(tols=(1e-9, 1e-10, 1e-11)):
    """auto at tight tol by DOP853 against auto by DOPRI5 at its own calibrated rtol (each
    forced by AUTO_DOP853_BELOW), on the rotor model on its stop: right-hand sides, CPU
    time (median of interleaved rounds) and worst errors against DOPRI5 at rtol 1e-13, the
    measure of where auto switches. Writes results/auto_dop853.json."""
    params = np.concatenate([points("rotor", 12, seed=s) for s in range(400, 405)], axis=1)
    ref, _ = run(params, "dopri5", rtol=1e-13)
    below = accuracy.AUTO_DOP853_BELOW

    def auto_by(dop853, tol):
        accuracy.AUTO_DOP853_BELOW = 1.0 if dop853 else 0.0
        try:
            return run(params, "auto", tol=tol)
        finally:
            accuracy.AUTO_DOP853_BELOW = below

    result = {"machine": platform.node(), "designs": params.shape[1],
              "auto_dop853_below": below}
    for tol in tols:
        out, status = auto_by(True, tol)
        other, other_status = auto_by(False, tol)
        assert np.all(status == 0) and np.all(other_status == 0)
        t_dop853, t_dopri5 = paired_cpu_times(lambda: auto_by(True, tol),
                                              lambda: auto_by(False, tol))
        entry = {"dopri5_over_dop853_evaluations": cost(other, "dopri5") / cost(out, "dop853"),
                 "dopri5_over_dop853_cpu": t_dopri5 / t_dop853,
                 "dop853_error": float(np.max(errors(out, ref))),
                 "dopri5_error": float(np.max(errors(other, ref)))}
        result[f"rotor tol {tol:g}"] = entry
        print(f"rotor tol {tol:g}: auto by DOP853 {entry['dopri5_over_dop853_cpu']:.2f}x "
              f"faster in CPU, {entry['dopri5_over_dop853_evaluations']:.2f}x fewer "
              f"right-hand sides; worst errors {entry['dop853_error']:.1e} and "
              f"{entry['dopri5_error']:.1e}")
    Path(__file__).resolve().parent.joinpath("results", "auto_dop853.json").write_text(
        json.dumps(result, indent=2) + "\n")


def main():
    if "--dop853" in sys.argv[1:]:
        return auto_by_method()
    result = {"machine": platform.node()}
    for model in ("paper", "rotor"):
        params = np.concatenate([points(model, 12, seed=s) for s in range(400, 405)],
                                axis=1)
        ref, _ = run(params, "dopri5", rtol=1e-13)
        bulk = np.concatenate([points(model, 120, seed=s) for s in range(400, 405)], axis=1) \
            if model == "rotor" else None
        for tol in (1e-4, 1e-6, 1e-8):
            out, status = run(params, "auto", tol=tol)
            assert np.all(status == 0) and np.max(errors(out, ref)) <= tol
            t_auto = best_time(lambda: run(params, "auto", tol=tol), 3)
            best_name, best_t, seen = None, math.inf, set()
            for name, kw in candidates(tol):
                family = kw["integrator"] + str(kw.get("atol_per_rtol", ""))
                if family in seen or (model == "rotor" and family == "closed_form"):
                    continue
                trial, status = run(params, **kw)
                if np.all(status == 0) and np.max(errors(trial, ref)) <= tol:
                    seen.add(family)  # the loosest setting of this family that meets tol
                    t = best_time(lambda kw=kw: run(params, **kw), 3)
                    if t < best_t:
                        best_name, best_t = name, t
            result[f"{model} tol {tol:g}"] = {"auto_s": t_auto, "best": best_name,
                                               "best_s": best_t, "auto_over_best": t_auto
                                               / best_t}
            if model == "rotor":
                result[f"{model} tol {tol:g}"].update(against_one_solve(params, ref, tol))
                result[f"{model} tol {tol:g}"].update(against_one_solve_in_bulk(bulk, tol))
            print(f"{model:6s} tol {tol:g}: auto {t_auto * 1e3:7.2f} ms, best single "
                  f"{best_name} {best_t * 1e3:7.2f} ms, ratio {t_auto / best_t:.2f}")
    Path(__file__).resolve().parent.joinpath("results", "auto.json").write_text(
        json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
