"""The integrator's step against C: nanoseconds per design-step of the rigid pendulum
psi'' = -Omega^2 sin psi under DOPRI5 at rtol 1e-8 (the kernel's embedded error and PI
controller), 4096 designs over 20 rotor radians each, in one run:

- ``numba scalar``: the kernel's own step (``kernels.impact.runge_kutta``) and controller,
  one design after another;
- ``C scalar``: the same loop in C (benchmarks/c/rigid_dopri5.c), gcc -O3 -march=native;
- ``C SIMD``: 8 designs at once, each lane with its own step size, retiring at the end of
  its interval, with glibc's vector sine (gcc -O3 -march=native -ffast-math -fopenmp-simd).

The three take the same steps (the counts are checked) and reach the same states (the C
checksums within 1e-9 of the kernel's). Best of 5 repeats each; the C programs are
compiled here, into a temporary directory.

Run: .venv/bin/python benchmarks/bench_step.py   (writes benchmarks/results/step.json)
"""

from __future__ import annotations

import json
import math
import os
import platform
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

N, T, REPEATS = 4096, 20.0, 5
SOURCE = HERE / "c" / "rigid_dopri5.c"
BUILDS = {"plain": ["-O3", "-march=native"],
          "simd": ["-O3", "-march=native", "-ffast-math", "-fopenmp-simd"]}


def designs(n=N):
    """Omega^2 in [1, 3], launch speeds from 0.3 to 0.9 of the separatrix's (as the C)."""
    x = (np.arange(n) + 0.5) / n
    w2 = 1.0 + 2.0 * x
    return w2, (0.3 + 0.6 * np.fmod(x * 7.0, 1.0)) * 2.0 * np.sqrt(w2)


def kernel_loop():
    from numba import njit

    from kernels.impact.runge_kutta import METHOD_DOPRI5, make_stepper, next_step
    from kernels.impact.tuples import relative_scales
    from kernels.pendulum.models import rigid_rhs

    step = make_stepper(rigid_rhs, relative_scales)

    @njit(error_model="numpy")  # as the kernels
    def run(w2s, vs, t_end, out):
        steps = 0
        for i in range(w2s.shape[0]):
            p = (1.0, w2s[i])  # (k, kappa): Omega^2 = kappa k
            y, f = (0.0, vs[i]), (vs[i], 0.0)
            t, h, prev, rejected = 0.0, 0.01, 1.0, False
            while t < t_end:
                if t + h > t_end:
                    h = t_end - t
                y1, f1, err = step(METHOD_DOPRI5, y, f, h, p, 1e-8, 1e-10)
                steps += 1
                if err <= 1.0:
                    t, y, f = t + h, y1, f1
                    h = next_step(METHOD_DOPRI5, h, err, rejected, prev)
                    prev, rejected = err, False
                else:
                    h = next_step(METHOD_DOPRI5, h, err, True, prev)
                    rejected = True
            out[i] = y[0] + y[1]
        return steps

    return run


def c_loops(tmp: Path):
    """{loop: (steps, ns per design-step, checksum)} from the two C builds."""
    cc = shutil.which("gcc") or shutil.which("cc")
    if cc is None:
        raise SystemExit("bench_step: no C compiler (gcc) on this machine")
    found = {}
    for build, flags in BUILDS.items():
        exe = tmp / f"rigid_dopri5_{build}"
        subprocess.run([cc, *flags, "-o", str(exe), str(SOURCE), "-lm"], check=True)
        text = subprocess.run([str(exe), str(N), str(T), str(REPEATS)], check=True,
                              capture_output=True, text=True).stdout
        for line in text.splitlines():
            name, steps, ns, checksum = line.split()
            if (build, name) in (("plain", "c_scalar"), ("simd", "c_simd")):
                found[name] = (int(steps), float(ns), float(checksum))
    return found


def main() -> None:
    w2, v = designs()
    run = kernel_loop()
    out = np.empty(N)
    run(w2[:8], v[:8], T, out[:8])  # compile
    best = math.inf
    for _ in range(REPEATS):
        t = time.perf_counter()
        steps = run(w2, v, T, out)
        best = min(best, time.perf_counter() - t)
    numba_ns, checksum = 1e9 * best / steps, float(out.sum())
    with tempfile.TemporaryDirectory() as tmp:
        c = c_loops(Path(tmp))
    results = {"numba scalar": {"steps": steps, "ns_per_design_step": round(numba_ns, 1)}}
    for name, label in (("c_scalar", "C scalar"), ("c_simd", "C SIMD")):
        c_steps, ns, c_sum = c[name]
        if c_steps != steps or abs(c_sum - checksum) > 1e-9 * abs(checksum):
            raise SystemExit(f"bench_step: {label} took {c_steps} steps to {c_sum!r}, "
                             f"the kernel {steps} to {checksum!r}")
        results[label] = {"steps": c_steps, "ns_per_design_step": round(ns, 1)}
    base = results["C SIMD"]["ns_per_design_step"]
    for label, r in results.items():
        r["over_c_simd"] = round(r["ns_per_design_step"] / base, 2)
        print(f"{label:13s} {r['ns_per_design_step']:7.1f} ns per design-step "
              f"({r['over_c_simd']:.2f}x the SIMD C loop)")
    record = {"what": __doc__.strip().splitlines()[0], "designs": N, "rotor_radians": T,
              "machine": platform.processor() or platform.machine(), "cpus": os.cpu_count(),
              "results": results}
    (HERE / "results" / "step.json").write_text(json.dumps(record, indent=2) + "\n")


if __name__ == "__main__":
    main()
