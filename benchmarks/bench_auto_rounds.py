"""Where auto's time goes on an example: its sweep solved once through the kernel, with each
of auto's solves (its rounds: the first, then again finer where the estimate misses
tol/10) recorded: the designs it solves, the integration steps the kernel counts and its
CPU time, the steps split by the outcome each design's row ends with in that round (a
cycle, no cycle within the budget, an escape, ...), and the share of all steps by that
outcome (cycles by whether they end in the first round or a later one) and of the
solves a later round repeats (``not_reported``: their rows are replaced). Writes
benchmarks/results/auto_rounds_<example>.json.

Run: .venv/bin/python benchmarks/bench_auto_rounds.py [EXAMPLE]
     (default rotary_pendulum_stability)
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

from kernels.impact import outcomes  # noqa: E402
from kernels.pendulum import dispatch  # noqa: E402
from kernels.pendulum.cases import ROW  # noqa: E402
from sweep import engine, spec  # noqa: E402

EXAMPLES = HERE.parent / "sweep" / "example_specs"
#: the kernel's sequence outcomes by code (kernels/impact/outcomes.py)
OUTCOMES = {getattr(outcomes, name): name.removeprefix("SEQUENCE_").lower()
            for name in dir(outcomes) if name.startswith("SEQUENCE_")}


def recorded_rounds(sweep):
    """The sweep solved once, each of auto's solves recorded as (designs, steps, CPU s,
    steps and designs by outcome)."""
    rounds, solved = [], []
    solve_auto = dispatch.solve_auto

    def recording(solve, cases, tol, margins=False):
        def timed(sub, *args):
            start = time.process_time()
            fine, coarse = solve(sub, *args)
            cpu = time.process_time() - start
            steps = fine[:, ROW.steps]
            by_outcome = {}
            for code in np.unique(fine[:, ROW.outcome]):
                chosen = fine[:, ROW.outcome] == code
                by_outcome[OUTCOMES[int(code)]] = {
                    "designs": int(chosen.sum()), "steps": float(steps[chosen].sum()),
                    "million_steps": float(steps[chosen].sum()) / 1e6}
            rounds.append({"designs": int(sub.shape[0]), "steps": float(steps.sum()),
                           "million_steps": float(steps.sum()) / 1e6, "cpu_s": cpu,
                           "by_outcome": by_outcome})
            solved.append((sub.copy(), steps))
            return fine, coarse
        return solve_auto(timed, cases, tol, margins)

    dispatch.solve_auto = recording
    try:
        params = engine.point_parameters(sweep, np.arange(int(np.prod(sweep.shape))))
        sweep.kernel(params, sweep.method_record)
    finally:
        dispatch.solve_auto = solve_auto
    # the steps of the designs a round solved and the next one solves again: flown for a
    # result that is not reported
    for j in range(len(rounds) - 1):
        again = {row.tobytes() for row in solved[j + 1][0]}
        chosen = np.array([row.tobytes() in again for row in solved[j][0]])
        rounds[j]["solved_again"] = {"designs": int(chosen.sum()),
                                     "million_steps": float(solved[j][1][chosen].sum()) / 1e6}
    return rounds


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("example", nargs="?", default="rotary_pendulum_stability")
    args = parser.parse_args()
    path = EXAMPLES / f"{args.example}.toml"
    if not path.is_file():
        sys.exit(f"example: no built-in example {args.example!r}; allowed: "
                 + ", ".join(sorted(p.stem for p in EXAMPLES.glob("*.toml"))))
    sweep = spec.parse(path.read_text())
    if getattr(sweep.method_record, "integrator", None) != dispatch.INTEGRATOR_AUTO:
        sys.exit(f"example: {args.example} does not solve by auto")
    recorded_rounds(sweep)  # compile
    rounds = recorded_rounds(sweep)
    if not rounds:
        sys.exit(f"example: {args.example} takes no rounds (closed forms or exact flights)")
    total = sum(r["steps"] for r in rounds)
    share = {}  # of all steps, by the outcome a round's rows end with; cycles by round
    for j, r in enumerate(rounds):
        for name, o in r["by_outcome"].items():
            key = name if name != "cycle" else ("cycle_first_round" if j == 0
                                                else "cycle_later_rounds")
            share[key] = share.get(key, 0.0) + o["steps"] / total
    not_reported = sum(r.get("solved_again", {"million_steps": 0.0})["million_steps"]
                       for r in rounds) * 1e6
    share["not_reported"] = not_reported / total
    result = {"example": args.example, "designs": int(np.prod(sweep.shape)),
              "rounds": {str(j + 1): r for j, r in enumerate(rounds)},
              "steps": total, "cpu_s": sum(r["cpu_s"] for r in rounds),
              "share_of_steps": share}
    path = HERE / "results" / f"auto_rounds_{args.example}.json"
    path.write_text(json.dumps(result, indent=1) + "\n")
    print(json.dumps(result, indent=1))


if __name__ == "__main__":
    main()
