"""Six-link throughput: grid points per second per core (2 impacts by bisection, peaks on
720 crank angles per 4 pi cycle by default, refined), and the per-angle cost.

Run: .venv/bin/python benchmarks/bench_six_link.py   (writes benchmarks/results/*.json)
"""

from __future__ import annotations

import json
import platform
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from kernels import six_link as sl  # noqa: E402

POINTS = 2000


def main():
    rng = np.random.default_rng(3)
    columns = dict(lambda2=rng.uniform(1.45, 1.7, POINTS), lambda3=np.full(POINTS, 1.3),
                   mu4=rng.uniform(1.2, 2.0, POINTS), mu5=rng.uniform(2.2, 6.0, POINTS),
                   beta=rng.uniform(-3, 3, POINTS), delta=np.zeros(POINTS),
                   direction=np.ones(POINTS), omega1=np.full(POINTS, 30.0),
                   crank_length=np.full(POINTS, 0.1))
    params = np.array([columns[name] for name in sl.P._fields])
    result = {"machine": platform.node(), "points": POINTS}
    for samples in (720, 2880):
        method = sl.DECLARATION.method_record(geometry_tol=1e-9, samples=samples)
        sl.run(params[:, :2], method)
        times = []
        for _ in range(5):
            t = time.perf_counter()
            _, status, _ = sl.run(params, method)
            times.append(time.perf_counter() - t)
        best = min(times)
        result[f"samples_{samples}"] = {"points_per_s": POINTS / best,
                                        "ok": int((status == sl.S.ok).sum())}
        print(f"six-link, 1 thread, {samples} angles per 4 pi: {POINTS / best:,.0f} points/s "
              f"({best / POINTS / samples * 1e9:.0f} ns per angle); ok {int((status == sl.S.ok).sum())}"
              f" of {POINTS}")
    out = Path(__file__).resolve().parent / "results" / "six_link.json"
    out.write_text(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
