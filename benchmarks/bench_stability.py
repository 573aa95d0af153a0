"""What the stability outputs cost: the tangent through the steady cycle, and several starts.

Run: .venv/bin/python benchmarks/bench_stability.py   (writes benchmarks/results/stability.json)

For each integrated system, the same random designs (the domain of tests/test_stability.py)
are solved by the pendulum kernel three ways, in one process, in turn (A B C A B C ...):
the default outputs; plus the multipliers and margins (the steady cycle run once more
with the variational equations: 2 + 4 or 4 + 16 components a step); plus 8 starts for the
attractor count. Reported: minimum CPU times (the kernels run in this process, one
thread) and their ratios to the default, with
DOPRI5 at a fixed rtol so that the same work is compared (auto may refine a case further
when the multiplier is asked for: its estimate then counts too).
"""

from __future__ import annotations

import json
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from kernels import rotary_pendulum as kr  # noqa: E402

MECH = kr.DECLARATION
STABILITY = ("multiplier_modulus", "multiplier_angle", "stability_margin",
             "impact_speed_min_ratio")
#: (model, tool, label): the domain of random designs; "slides" (R = 0): every impact of
#: the rotor model on the blade sticks and slides, its tangent carried through the slide
SYSTEMS = {("rotor", "rotor_stop", ""): dict(k=(0.5, 2.0), R=(0.0, 0.2), xi=(1.0, 8.0),
                                             kappa=(1.2, 2.5)),
           ("paper", "lab_window", ""): dict(k=(0.5, 2.5), R=(0.001, 0.1), xi=(2.0, 8.0),
                                             tool_window=(0.1, 0.5)),
           ("rigid", "lab_window", ""): dict(k=(0.5, 2.5), R=(0.001, 0.1),
                                             kappa=(1.05, 1.5), tool_window=(0.1, 0.5)),
           ("rotor", "lab_window", ""): dict(k=(0.5, 2.5), R=(0.001, 0.1), xi=(2.0, 8.0),
                                             kappa=(1.05, 1.5), tool_window=(0.1, 0.5)),
           ("rotor", "lab_window", "slides"): dict(k=(0.5, 2.5), R=(0.0, 0.0),
                                                   xi=(2.0, 8.0), kappa=(1.05, 1.5),
                                                   tool_window=(0.1, 0.5))}
N_DESIGNS = 30
REPEATS = 2


def parameters(model, tool, domain, rng):
    given = {name: rng.uniform(lo, hi, N_DESIGNS) for name, (lo, hi) in domain.items()}
    matrix = np.empty((len(MECH.parameters), N_DESIGNS))
    for row, p in enumerate(MECH.parameters):
        if p.name in given:
            matrix[row] = given[p.name]
        else:
            value = {"model": model, "tool": tool}.get(p.name, p.default)
            matrix[row] = np.nan if value is None else p.encode(value)
    return matrix


def main() -> None:
    rng = np.random.default_rng(2026)
    plain = MECH.default_outputs
    base = dict(integrator="dopri5", rtol=1e-9, atol=1e-9, max_impacts=300)
    methods = {"default outputs": MECH.method_record(outputs=plain, **base),
               "+ multipliers and margins": MECH.method_record(outputs=plain + STABILITY,
                                                               **base),
               "+ 8 starts": MECH.method_record(
                   outputs=plain + ("attractor_count", "basin_fraction"), starts=8, **base)}
    results = {}
    for (model, tool, label), domain in SYSTEMS.items():
        matrix = parameters(model, tool, domain, rng)
        runs = {name: (lambda m=method: kr.run(matrix, m)) for name, method in
                methods.items()}
        for fn in runs.values():
            fn()  # compile
        times = {name: [] for name in runs}
        for _ in range(REPEATS):
            for name, fn in runs.items():
                t = time.process_time()
                fn()
                times[name].append(time.process_time() - t)
        out, status, _ = kr.run(matrix, methods["+ multipliers and margins"])
        best = {name: min(t) for name, t in times.items()}
        finite = np.isfinite(out[MECH.output_index.multiplier_modulus])
        system = f"{model} on {tool}" + (f", {label}" if label else "")
        results[system] = {
            "designs": N_DESIGNS, "with a cycle": int((status == 0).sum()),
            "with a multiplier": int(finite.sum()),
            "cpu_seconds": {name: round(v, 4) for name, v in best.items()},
            "ratio to default": {name: round(v / best["default outputs"], 2)
                                 for name, v in best.items()}}
        print(f"{system}: " + ", ".join(
            f"{name} {v:.3f} s ({v / best['default outputs']:.2f}x)"
            for name, v in best.items()), flush=True)
    record = {"what": __doc__.strip().splitlines()[0], "method": base,
              "repeats": REPEATS, "machine": platform.processor() or platform.machine(),
              "cpus": os.cpu_count(), "results": results}
    path = Path(__file__).parent / "results" / "stability.json"
    path.write_text(json.dumps(record, indent=2) + "\n")
    print(f"written {path}")


if __name__ == "__main__":
    main()
