"""Rotary pendulum: steady states per second per core for each model x tool (DOPRI5 at rtol
1e-8 through the kernel's entry point, as a sweep runs it) and the flights each steady
state took, the rigid model on the blade as a sweep runs it by default (auto, tol 1e-8:
its flights in closed form), the closed form, and SciPy's
solve_ivp (DOP853 with an impact event and a restart loop, the same tolerance) on the
paper model.

With ``--against REF`` (a git revision) the same designs also run on that revision's
kernels, in a checkout of their own, the two in turn (A B A B ...), and the ratios
(this tree over REF) are printed: the throughput before and after a change, in one run.

Run: .venv/bin/python benchmarks/bench_rotary_pendulum.py [--against REF] [--closed-form]
     (writes benchmarks/results/rotary_pendulum.json; --closed-form: only the closed form,
     to rotary_pendulum_closed_form.json)
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, os.environ.get("BENCH_ROOT", str(HERE.parent)))

XI = 4.0
FLIGHTS = "flights per steady state: "  # the key's prefix for those counts
SYSTEMS = [(m, t) for t in ("rotor_stop", "lab_window") for m in ("paper", "rigid", "rotor")]
#: designs per system, and repeats of each timing (best of). The blade's family is chaotic
#: and its cost is decided by the few designs that fly the whole impact budget (quasi-periodic,
#: about 3/4 of the steps) or drift past the blade for long (no impact): a sample of 12 gave
#: the paper model 0.95x its earlier code, two samples of 120 gave 5.1x and 8.6x.
DESIGNS = {"rotor_stop": 400, "lab_window": 200}
REPEATS = {"rotor_stop": 5, "lab_window": 2}


def designs(kr, model, tool, n, seed):
    """n random designs of a model on a tool that reach a steady state at most points, as
    the kernel's parameter matrix (only public names: the same on any revision)."""
    decl = kr.DECLARATION
    rng = np.random.default_rng(seed)
    cols = {p.name: np.full(n, p.encode(p.default) if p.default is not None else math.nan)
            for p in decl.parameters}
    cols["model"][:] = decl.parameter("model").encode(model)
    cols["tool"][:] = decl.parameter("tool").encode(tool)
    if tool == "rotor_stop":
        k = rng.uniform(1.0, 2.5, n)
        cols["k"] = k
        if model == "paper":  # R below R_crit, which the closed form gives
            probe = np.array([cols[p.name] for p in decl.parameters])
            out, _, _ = kr.run(probe, decl.method_record(integrator="closed_form"))
            r_crit = out[decl.output_index.restitution_critical]
            cols["R"] = rng.uniform(0.0, 0.8, n) * r_crit
        else:  # contact outboard of the centre of percussion: the pendulum returns
            cols["kappa"] = (1 + k) ** 2 / (4 * k) * rng.uniform(1.1, 1.5, n)
            cols["R"] = rng.uniform(0.0, 0.02, n)
    else:  # the blade example's family
        cols["k"] = np.full(n, 1.0 if model != "paper" else 2.5)
        cols["kappa"] = np.full(n, 1.2)
        cols["tool_window"] = rng.uniform(0.1, 0.5, n)
        cols["R"] = np.where(rng.uniform(size=n) < 0.5, 0.0, rng.uniform(0.0, 0.01, n))
    if model == "rotor":
        cols["rotor_inertia_ratio"] = rng.uniform(20, 200, n)
        cols["motor_slope"] = rng.uniform(3, 50, n)
    return np.array([cols[p.name] for p in decl.parameters])


def steady_states_per_second(kr, params, method, repeats):
    """(steady states per second, best of ``repeats`` after a one-design warm-up that
    compiles; the outputs of the last run)."""
    kr.run(params[:, :1], method)
    best = math.inf
    for _ in range(repeats):
        t = time.perf_counter()
        out = kr.run(params, method)[0]
        best = min(best, time.perf_counter() - t)
    return params.shape[1] / best, out


def measure(repeats=5, closed_form_only=False):
    """Steady states per second of each system at DOPRI5 rtol 1e-8 (best of REPEATS, after
    a warm-up that compiles), and of the closed form (best of ``repeats``)."""
    from kernels import rotary_pendulum as kr
    decl = kr.DECLARATION
    dopri = decl.method_record(integrator="dopri5", rtol=1e-8, atol=1e-10)
    result = {}
    for i, (model, tool) in enumerate([] if closed_form_only else SYSTEMS):
        params = designs(kr, model, tool, DESIGNS[tool], seed=100 + i)
        rate, out = steady_states_per_second(kr, params, dopri, REPEATS[tool])
        result[f"{model} on {tool}"] = rate
        # flights (located impacts) per design that reaches a steady cycle
        cycle = np.isfinite(out[decl.output_index.amplitude])
        result[f"{FLIGHTS}{model} on {tool}"] = float(out[decl.output_index.n_events][cycle]
                                                      .mean())
    if not closed_form_only:
        # what a sweep runs by default (auto at tol 1e-8) on the blade with the rigid
        # model: DOPRI5 twice (and refined) before its flights had a closed form, one exact
        # solve since
        params = designs(kr, "rigid", "lab_window", DESIGNS["lab_window"], seed=104)
        result["rigid on lab_window, auto tol 1e-8"] = steady_states_per_second(
            kr, params, decl.method_record(integrator="auto", tol=1e-8),
            REPEATS["lab_window"])[0]
    params = designs(kr, "paper", "rotor_stop", 2000, seed=7)
    result["paper closed form"] = steady_states_per_second(
        kr, params, decl.method_record(integrator="closed_form"), repeats)[0]
    return result


def measure_in(root: Path, closed_form_only=False) -> dict:
    """measure() on the kernels of another checkout, in a process of its own."""
    env = dict(os.environ, BENCH_ROOT=str(root))
    out = subprocess.run([sys.executable, str(Path(__file__).resolve()), "--measure"]
                         + ["--closed-form"] * closed_form_only,
                         env=env, capture_output=True, text=True)
    if out.returncode:
        raise SystemExit(f"measuring in {root} failed:\n{out.stderr}")
    return json.loads(out.stdout.strip().splitlines()[-1])


def scipy_steady_state(k, r, rtol, max_impacts=200):
    """The straightforward SciPy route: integrate flight by flight with an event at psi = 0
    (upward), apply the impact law, restart, until the impact speed converges."""
    from scipy.integrate import solve_ivp

    def rhs(t, y):
        x = k * k + 1 + 2 * k * math.cos(y[0])
        return [y[1], -k * x / (1 + XI * x) * (y[1] ** 2 + XI) * math.sin(y[0])]

    def impact(t, y):
        return y[0]
    impact.terminal, impact.direction = True, 1

    v, tau1 = 0.0, math.nan
    for _ in range(max_impacts):
        launch = (1 + k) * (1 + r) + r * v
        # start just below the surface so the restart point is not an event (H4)
        sol = solve_ivp(rhs, (0, 100), [-1e-12, -launch], method="DOP853", events=impact,
                        rtol=rtol, atol=rtol * 1e-2)
        if not sol.t_events[0].size:
            return math.nan, math.nan
        v_new, tau1 = sol.y_events[0][0][1], sol.t_events[0][0]
        if abs(v_new - v) <= 10 * rtol * v_new or r == 0:
            return v_new, tau1
        v = v_new
    return v, tau1


def scipy_rate(n=20):
    from kernels import rotary_pendulum as kr
    params = designs(kr, "paper", "rotor_stop", n, seed=100)
    decl = kr.DECLARATION
    ks, rs = params[decl.parameter_index.k], params[decl.parameter_index.R]
    best = math.inf
    for _ in range(3):
        t = time.perf_counter()
        for k, r in zip(ks, rs):
            scipy_steady_state(k, r, 1e-8)
        best = min(best, time.perf_counter() - t)
    return n / best


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--measure", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--against", metavar="REF", help="a git revision to compare with")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--closed-form", action="store_true",
                        help="only the closed form (the paper model on the rotor stop)")
    args = parser.parse_args()
    if args.measure:
        print(json.dumps(measure(closed_form_only=args.closed_form)))
        return
    result = {"machine": platform.node()}
    if args.against:
        with tempfile.TemporaryDirectory() as tmp:
            old = Path(tmp) / "ref"
            subprocess.run(["git", "-C", str(HERE.parent), "worktree", "add", "--detach",
                            str(old), args.against], check=True, capture_output=True)
            try:
                rounds = {"this": [], args.against: []}
                for _ in range(args.rounds + 1):  # the first round compiles both: not counted
                    rounds["this"].append(measure_in(HERE.parent, args.closed_form))
                    rounds[args.against].append(measure_in(old, args.closed_form))
            finally:
                subprocess.run(["git", "-C", str(HERE.parent), "worktree", "remove", "--force",
                                str(old)], check=True)
        best = {who: {key: max(r[key] for r in runs[1:]) for key in runs[0]}
                for who, runs in rounds.items()}
        print(f"steady states per second, this tree against {args.against} "
              f"(best of {args.rounds} rounds in turn; then the flights per steady state):")
        for key in sorted(best["this"], key=lambda key: key.startswith(FLIGHTS)):
            if key.startswith(FLIGHTS):  # counts, not rates: the same every round
                best["this"][key] = rounds["this"][0][key]
                best[args.against][key] = rounds[args.against][0][key]
            ratio = best["this"][key] / best[args.against][key]
            print(f"  {key.replace(FLIGHTS, 'flights: '):24s} {best['this'][key]:10,.2f} "
                  f"{best[args.against][key]:10,.2f}   ratio {ratio:5.2f}")
            result[key] = {"this": best["this"][key], args.against: best[args.against][key],
                           "ratio": ratio}
    elif args.closed_form:
        result.update(measure(closed_form_only=True))
        print(f"  paper closed form {result['paper closed form']:12,.2f}")
    else:
        rates = measure()
        result.update(rates)
        result["scipy_dop853_paper_rtol_1e-8"] = scipy_rate()
        result["dopri5_over_scipy"] = (rates["paper on rotor_stop"]
                                       / result["scipy_dop853_paper_rtol_1e-8"])
        for key, value in result.items():
            if key != "machine":
                print(f"  {key:50s} {value:12,.2f}")
    name = "rotary_pendulum_closed_form.json" if args.closed_form else "rotary_pendulum.json"
    HERE.joinpath("results", name).write_text(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
