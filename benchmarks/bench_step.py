"""The integrator's step against C: nanoseconds of CPU time per design-step of the rigid
pendulum psi'' = -Omega^2 sin psi under DOPRI5 at rtol 1e-8 (the kernel's embedded error and
PI controller), 4096 designs over 20 rotor radians each, and of the kernel's integrated
flights with everything around them, in one run:

- ``numba scalar``: the kernel's own step (``kernels.impact.runge_kutta``) and controller,
  one design after another;
- ``numba, 8 lanes, <sine> and <power>``: the same step and controller (the kernel's code,
  inlined) for 8 designs at once, laid out lane-minor in one flat buffer as the C SIMD loop
  is, each lane with its own step size; with libm's sine and pow (called: the loop stays
  scalar), with the kernels' branch-free sine (``elementary.sincos_lane``), and with it
  and the branch-free power in the controller (``elementary.power_lane``), no fastmath;
- ``numba scalar, the rotor model's step``: the kernel's step of the rotor model (the
  stability example's) and its controller alone, one design after another: what of the
  integrated flights below is the step;
- ``C scalar``: the same loop in C (benchmarks/c/rigid_dopri5.c), gcc -O3 -march=native;
- ``C SIMD``: 8 designs at once, each lane with its own step size, retiring at the end of
  its interval, with glibc's vector sine (gcc -O3 -march=native -ffast-math -fopenmp-simd);
- ``integrated flight, <example>``: the blade examples' designs (rigid striker; rotor
  model, the stability example's) to their steady states by forced DOPRI5 at the same
  rtol, through the sweep's kernel: events located and polished, impacts, slides, sections
  and the peak, per step the kernel counts (accepted and rejected, its ``n_steps``).

The numba and C loops take the same steps (the counts are checked) and reach the same
states (checksums within 1e-9 of the kernel's; the lanes with libm's sine and pow give the
kernel's bits, design by design). CPU time (the C programs time their loops on
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


def kernel_loop(model: str = "rigid"):
    """``run(w2s, vs, t_end, out) -> steps``: the kernel's DOPRI5 step and controller, one
    design after another. ``rigid``: the rigid pendulum, Omega^2 = w2, launched at v (as
    the C). ``rotor``: the rotor model's step (P9-P10, its own error scales) with k = w2,
    the pendulum launched at v from a rotor turning at its idle speed (xi 0.3, rotor
    inertia 60, motor slope 20): the step the stability example's flights take."""
    from numba import njit

    from kernels import INLINE_OPTIONS
    from kernels.impact.runge_kutta import METHOD_DOPRI5, make_stepper, next_step
    from kernels.impact.tuples import relative_scales
    from kernels.pendulum.models import rigid_rhs, rotor_rhs, rotor_scales

    if model == "rotor":
        rhs, scales = rotor_rhs, rotor_scales

        @njit(**INLINE_OPTIONS)
        def start(w2, v):  # (phi1, phi1', psi, psi'), (k, xi, j1, slope, idle)
            return (0.0, 1.0, 0.0, v), (w2, 0.3, 60.0, 20.0, 1.0)
    else:
        rhs, scales = rigid_rhs, relative_scales

        @njit(**INLINE_OPTIONS)
        def start(w2, v):  # (psi, psi'), (k, kappa): Omega^2 = kappa k
            return (0.0, v), (1.0, w2)

    step = make_stepper(rhs, scales)

    @njit(error_model="numpy")  # as the kernels
    def run(w2s, vs, t_end, out):
        steps = 0
        for i in range(w2s.shape[0]):
            y, p = start(w2s[i], vs[i])
            f = rhs(y, p)
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
            out[i] = y[-2] + y[-1]
        return steps

    return run


#: the lane loops' sine and power: (label, sine, power), each "libm" or "lane" (branch-free)
LANE_VARIANTS = (("libm's sine and pow", "libm", "libm"),
                 ("branch-free sine, libm's pow", "lane", "libm"),
                 ("branch-free sine and pow", "lane", "lane"))
LANES = 8


def lane_loop(sine: str, power: str):
    """``run(w2s, vs, t_end, out) -> steps``: kernel_loop's flights 8 at a time, the
    kernel's step and step-size rule inlined into one loop over the lanes of a flat
    lane-minor buffer (field * LANES + lane), each lane accepting, rejecting and retiring
    on its own. With libm's sine and pow, the same operations per design as kernel_loop's
    (its bits); the branch-free ones differ from libm's in the last bits."""
    import math

    from numba import njit

    from kernels import INLINE_OPTIONS, elementary
    from kernels.impact import runge_kutta
    from kernels.impact.runge_kutta import METHOD_DOPRI5, make_step_size_rule, make_stepper
    from kernels.impact.tuples import relative_scales

    if sine == "lane":
        sin = njit(**INLINE_OPTIONS)(lambda x: elementary.sincos_lane(x)[0])
    else:
        sin = njit(**INLINE_OPTIONS)(lambda x: math.sin(x))

    @njit(**INLINE_OPTIONS)
    def rhs(y, p):  # the kernel's rigid_rhs with the sine chosen
        k, kappa = p
        return (y[1], -kappa * k * sin(y[0]))

    step = make_stepper(rhs, relative_scales, methods=(), inline=True)
    next_step = make_step_size_rule(
        elementary.power_lane if power == "lane" else runge_kutta.libm_power, inline=True)
    W2, Y0, Y1, ACC, T0, H, PREV, REJECTED = (field * LANES for field in range(8))

    @njit(error_model="numpy")
    def run(w2s, vs, t_end, out):
        n, steps = w2s.shape[0], 0
        buf = np.empty(8 * LANES)
        for base in range(0, n, LANES):
            for lane in range(LANES):  # a block's last lanes repeat its last design
                i = min(base + lane, n - 1)
                buf[W2 + lane], buf[Y0 + lane], buf[Y1 + lane] = w2s[i], 0.0, vs[i]
                buf[ACC + lane], buf[T0 + lane], buf[H + lane] = 0.0, 0.0, 0.01
                buf[PREV + lane], buf[REJECTED + lane] = 1.0, 0.0
            running = LANES
            while running:
                running = 0
                for lane in range(LANES):  # vectorised by LLVM: every branch a select
                    y = (buf[Y0 + lane], buf[Y1 + lane])
                    t, h, prev = buf[T0 + lane], buf[H + lane], buf[PREV + lane]
                    live = t < t_end
                    h = t_end - t if t + h > t_end else h
                    y1, f1, err = step(METHOD_DOPRI5, y, (y[1], buf[ACC + lane]), h,
                                       (1.0, buf[W2 + lane]), RTOL, ATOL)
                    accept = live and err <= 1.0
                    after_reject = buf[REJECTED + lane] != 0.0 or not accept
                    h_next = next_step(METHOD_DOPRI5, h, err, after_reject, prev)
                    buf[T0 + lane] = t + h if accept else t
                    buf[Y0 + lane] = y1[0] if accept else y[0]
                    buf[Y1 + lane] = y1[1] if accept else y[1]
                    buf[ACC + lane] = f1[1] if accept else buf[ACC + lane]
                    buf[PREV + lane] = err if accept else prev
                    buf[REJECTED + lane] = (0.0 if accept else 1.0) if live else 1.0
                    buf[H + lane] = h_next if live else buf[H + lane]
                    steps += 1 if live else 0
                    running += 1 if live and (t + h < t_end if accept else True) else 0
            for lane in range(min(LANES, n - base)):
                out[base + lane] = buf[Y0 + lane] + buf[Y1 + lane]
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
    rotor, rotor_out = kernel_loop("rotor"), np.empty(N)
    loops = {"numba scalar": lambda: loop(w2, v, T, out),
             "numba scalar, the rotor model's step": lambda: rotor(w2, v, T, rotor_out)}
    lane_outs = {}
    for label, sine, power in LANE_VARIANTS:
        lanes, lane_outs[label] = lane_loop(sine, power), np.empty(N)
        loops[f"numba, {LANES} lanes, {label}"] = (
            lambda lanes=lanes, o=lane_outs[label]: lanes(w2, v, T, o))
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
            for label, lane_out in lane_outs.items():
                key = f"numba, {LANES} lanes, {label}"
                lane_sum = float(lane_out.sum())
                if (counts[key] != counts["numba scalar"]
                        or abs(lane_sum - checksum) > 1e-9 * abs(checksum)
                        or (label == LANE_VARIANTS[0][0]
                            and not np.array_equal(lane_out, out))):
                    raise SystemExit(f"bench_step: {key} took {counts[key]} steps to "
                                     f"{lane_sum!r}, the kernel {counts['numba scalar']} "
                                     f"to {checksum!r}")
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
