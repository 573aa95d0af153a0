"""The integrator's step against C: nanoseconds of CPU time per design-step of the rigid
pendulum psi'' = -Omega^2 sin psi under DOPRI5 at rtol 1e-8 (the kernel's embedded error and
PI controller), 4096 designs over 20 rotor radians each, and of the kernel's integrated
flights with everything around them, in one run:

- ``numba scalar``: the kernel's own step (``kernels.impact.runge_kutta``) and controller,
  one design after another;
- ``C scalar``: the same loop in C (benchmarks/c/rigid_dopri5.c), gcc -O3 -march=native;
- ``C SIMD``: 8 designs at once, each lane with its own step size, retiring at the end of
  its interval, with glibc's vector sine (gcc -O3 -march=native -ffast-math -fopenmp-simd);
- ``integrated flight, <example>``: the blade examples' designs (rigid striker; rotor
  model, the stability example's) to their steady states by forced DOPRI5 at the same
  rtol, through the sweep's kernel: events located and polished, impacts, slides, sections
  and the peak, per step the kernel counts (accepted and rejected, its ``n_steps``).

The first three take the same steps (the counts are checked) and reach the same states (the
C checksums within 1e-9 of the kernel's). CPU time (the C programs time their loops on
their own process's CPU clock), interleaved rounds, the median of each.

Run: .venv/bin/python benchmarks/bench_step.py [--rounds N]
     (writes benchmarks/results/step.json)
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
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

N, T, RTOL, ATOL = 4096, 20.0, 1e-8, 1e-10
#: the examples whose designs the integrated flights fly
FLIGHT_EXAMPLES = ("rotary_pendulum_blade", "rotary_pendulum_stability")
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
                y1, f1, err = step(METHOD_DOPRI5, y, f, h, p, RTOL, ATOL)
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


def integrated_flights(example: str):
    """``run() -> steps``: the example's designs (its grid, regime outputs only) to their
    steady states by the sweep's kernel under DOPRI5 at RTOL, ATOL."""
    import tomllib

    from sweep import engine, spec

    path = Path(spec.__file__).parent / "example_specs" / f"{example}.toml"
    raw = tomllib.loads(path.read_text())
    raw.pop("outputs", None), raw.pop("chart", None)
    raw["method"] = {"integrator": "dopri5", "rtol": RTOL, "atol": ATOL,
                     **{k: v for k, v in raw["method"].items() if k == "max_impacts"}}
    sweep = spec.validate(raw)
    params = engine.block_parameters(sweep, [(0, n) for n in sweep.shape])

    def run():
        out = sweep.kernel(params, sweep.method_record)[0]
        return int(np.nansum(out[sweep.mechanism.output_index.n_steps]))

    return run


def build_c(tmp: Path) -> dict:
    """{build: executable} of the two C builds."""
    cc = shutil.which("gcc") or shutil.which("cc")
    if cc is None:
        raise SystemExit("bench_step: no C compiler (gcc) on this machine")
    built = {}
    for build, flags in BUILDS.items():
        built[build] = tmp / f"rigid_dopri5_{build}"
        subprocess.run([cc, *flags, "-o", str(built[build]), str(SOURCE), "-lm"], check=True)
    return built


def c_loops(built: dict) -> dict:
    """{loop: (steps, CPU ns per design-step, checksum)} of one run of each C build."""
    found = {}
    for build, exe in built.items():
        text = subprocess.run([str(exe), str(N), str(T), "1"], check=True,
                              capture_output=True, text=True).stdout
        for line in text.splitlines():
            name, steps, ns, checksum = line.split()
            if (build, name) in (("plain", "c_scalar"), ("simd", "c_simd")):
                found[name] = (int(steps), float(ns), float(checksum))
    return found


def cpu_ns_per_step(run) -> tuple[int, float]:
    """(steps, CPU ns per step) of one call of ``run() -> steps``."""
    t = time.process_time()
    steps = run()
    return steps, 1e9 * (time.process_time() - t) / steps


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    parser.add_argument("--rounds", type=int, default=5)
    rounds = parser.parse_args().rounds
    w2, v = designs()
    loop = kernel_loop()
    out = np.empty(N)
    loops = {"numba scalar": lambda: loop(w2, v, T, out)}
    for example in FLIGHT_EXAMPLES:
        loops[f"integrated flight, {example}"] = integrated_flights(example)
    for run in loops.values():
        run()  # compiles, or loads the cache
    samples = {label: [] for label in [*loops, "C scalar", "C SIMD"]}
    counts = {}
    with tempfile.TemporaryDirectory() as tmp:
        built = build_c(Path(tmp))
        for _ in range(rounds):
            for label, run in loops.items():
                counts[label], ns = cpu_ns_per_step(run)
                samples[label].append(ns)
            checksum = float(out.sum())
            for name, label in (("c_scalar", "C scalar"), ("c_simd", "C SIMD")):
                c_steps, ns, c_sum = c_loops(built)[name]
                if (c_steps != counts["numba scalar"]
                        or abs(c_sum - checksum) > 1e-9 * abs(checksum)):
                    raise SystemExit(f"bench_step: {label} took {c_steps} steps to {c_sum!r}, "
                                     f"the kernel {counts['numba scalar']} to {checksum!r}")
                counts[label] = c_steps
                samples[label].append(ns)
    results = {label: {"steps": counts[label],
                       "ns_per_design_step": round(statistics.median(ns), 1),
                       "rounds_ns": [round(x, 1) for x in ns]}
               for label, ns in samples.items()}
    base = results["C SIMD"]["ns_per_design_step"]
    for label, r in results.items():
        r["over_c_simd"] = round(r["ns_per_design_step"] / base, 2)
        print(f"{label:50s} {r['ns_per_design_step']:7.1f} ns per design-step "
              f"({r['over_c_simd']:.2f}x the SIMD C loop)")
    record = {"what": __doc__.strip().splitlines()[0], "designs": N, "rotor_radians": T,
              "rtol": RTOL, "atol": ATOL, "rounds": rounds,
              "machine": platform.processor() or platform.machine(), "cpus": os.cpu_count(),
              "results": results}
    (HERE / "results" / "step.json").write_text(json.dumps(record, indent=2) + "\n")


if __name__ == "__main__":
    main()
