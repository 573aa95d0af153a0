"""The rigid model's flights on the blade in closed form against DOPRI5: regimes and values
against DOPRI5 at rtol 1e-13, and the time of a sweep, over the requested tol. Two design
sets: the blade example's grid (306 designs, 200 impacts at most) and 200 random designs of
its family (benchmarks/auto_cases.blade_points, 1000 impacts at most). A design is
*resolved* where DOPRI5 at rtol 1e-11, 1e-12 and 1e-13 reach one regime; its values are
compared where DOPRI5 at 1e-12 and 1e-13 also agree within 1e-9. DOPRI5 at rtol 1e-9 to
1e-11 (one solve each) is the comparison at equal work. Where a run misses a resolved
design's regime, the reference is also run at 64 copies of the design with R and the
blade's reach moved by up to 1e-6 (relative): the reference is *stable* there where all
64 keep its regime, and a miss counts against the method only there. Times: one run after
a warm-up, on one thread (ratios within one run are what to read).

Run: .venv/bin/python benchmarks/bench_exact_flights.py  (writes results/exact_flights.json)
"""

from __future__ import annotations

import json
import platform
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from benchmarks.auto_cases import KERNEL, MECH, OUT, blade_points  # noqa: E402
from kernels.rotary_pendulum import P as PARAMETER  # noqa: E402
from sweep import engine, spec  # noqa: E402
from sweep.api import example_text as _example_text  # noqa: E402

VALUES = ("impact_speed", "impact_interval", "amplitude", "acceleration_peak")


def example_params():
    sweep = spec.parse(_example_text("rotary_pendulum_blade"))
    return engine.point_parameters(sweep, np.arange(sweep.size)), sweep.method["max_impacts"]


def solve(params, max_impacts, **method):
    record = MECH.method_record(max_impacts=max_impacts, **method)
    KERNEL.run(params[:, :1], record)  # compile, outside the time
    t = time.perf_counter()
    out, _, _ = KERNEL.run(params, record)
    return out, time.perf_counter() - t


def regime(out):
    return np.nan_to_num(out[OUT["regime"]], nan=-1)


def value_error(a, b):
    return np.max([np.abs(a[OUT[v]] / b[OUT[v]] - 1) for v in VALUES], axis=0)


def references(params, max_impacts):
    """DOPRI5 at rtol 1e-13, and which designs it resolves: (reference, resolved, valued)."""
    refs = {r: solve(params, max_impacts, integrator="dopri5", rtol=r, atol=r * 1e-2)[0]
            for r in (1e-11, 1e-12, 1e-13)}
    ref = refs[1e-13]
    resolved = (regime(refs[1e-11]) == regime(ref)) & (regime(refs[1e-12]) == regime(ref))
    valued = resolved & (value_error(refs[1e-12], ref) < 1e-9)
    return ref, resolved, valued


#: how far (relative) and at how many copies a missed design is moved to see whether the
#: reference's regime there is stable
PERTURBATION, COPIES = 1e-6, 64


def reference_stable(params, max_impacts, ref, i, known):
    """Whether DOPRI5 at rtol 1e-13 keeps its regime at design i at COPIES copies moved
    by up to PERTURBATION in R and the reach (``known``: the answers so far, by design)."""
    if i not in known:
        copies = np.repeat(params[:, i:i + 1], COPIES, axis=1)
        rng = np.random.default_rng(i)
        for name in ("R", "tool_window"):
            moved = 1.0 + PERTURBATION * rng.uniform(-1.0, 1.0, COPIES)
            copies[getattr(PARAMETER, name)] *= moved
        out = solve(copies, max_impacts, integrator="dopri5", rtol=1e-13, atol=1e-15)[0]
        known[i] = bool((regime(out) == regime(ref)[i]).all())
    return known[i]


def measure(params, max_impacts, method, reference, known):
    """One run against the references: seconds, designs in the reference's regime (of the
    resolved ones), the misses where the reference is stable, and the largest value error
    (where values are compared)."""
    ref, resolved, valued = reference
    out, seconds = solve(params, max_impacts, **method)
    same = regime(out) == regime(ref)
    errors = value_error(out, ref)[valued & same]
    misses = [int(i) for i in np.flatnonzero(resolved & ~same)]
    stable = [i for i in misses if reference_stable(params, max_impacts, ref, i, known)]
    return {"seconds": seconds, "regime as reference (resolved)": int((same & resolved).sum()),
            "misses": len(misses), "misses where the reference is stable": len(stable),
            "stable misses (designs)": stable,
            "values compared": int(errors.size), "largest value error": float(errors.max()),
            "steps": float(out[OUT["n_steps"]].sum())}


def closed_form(tol):
    return dict(integrator="closed_form", tol=tol)


def dopri5(rtol):
    return dict(integrator="dopri5", rtol=rtol, atol=rtol)


def study(params, max_impacts):
    reference = references(params, max_impacts)
    runs = [(f"closed form tol {tol:g}", closed_form(tol)) for tol in (1e-3, 1e-6, 1e-8, 1e-10)]
    runs += [(f"dopri5 rtol {r:g}", dopri5(r)) for r in (1e-9, 1e-10, 1e-11)]
    rows, known = {}, {}
    for name, method in runs:
        row = rows[name] = measure(params, max_impacts, method, reference, known)
        print(f"  {name:24s} {row['seconds']:6.2f} s  regime "
              f"{row['regime as reference (resolved)']:3d}/{int(reference[1].sum())} "
              f"(misses where stable: {row['misses where the reference is stable']})  values "
              f"{row['values compared']:3d}, worst {row['largest value error']:.1e}", flush=True)
    return {"designs": params.shape[1], "resolved": int(reference[1].sum()), "runs": rows}


def main():
    result = {"machine": platform.node()}
    for name, (params, max_impacts) in (("blade example", example_params()),
                                         ("random blade designs",
                                          (blade_points("rigid", 200, 7), 1000))):
        print(name)
        result[name] = study(params, max_impacts)
    Path(__file__).with_name("results").joinpath("exact_flights.json").write_text(
        json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
